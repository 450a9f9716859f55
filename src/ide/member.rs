//! Completion after `receiver.`: what the checker accepts after a value of the
//! receiver's type. Fields on atlases, swizzles on vectors, and the builtins that
//! take the receiver as their first argument (shape methods on shapes, `sample` on
//! textures, math on numbers), but not the constructors (`sphere`, `orbit`, `image`).
//!
//! The receiver's type comes from the checker: the receiver's text is checked as a
//! `let` after the items before the cursor's, so it sees the same names the
//! receiver does, even when the text around the cursor does not parse.

use super::completion::{function, Completion, CompletionKind};
use super::Document;
use crate::sema::builtins::{Builtin, PTy, Ret, BUILTINS};
use crate::sema::{AtlasAttr, DefKind, Ty};
use crate::span::Span;
use crate::syntax::lexer::Token;

/// Where the tokens of the receiver ending just before `toks[dot]` start: a name, a
/// literal, a call, a vector or a parenthesised expression, with any `.field` and
/// `.method(…)` after it.
fn receiver_start(toks: &[(Token, Span)], dot: usize) -> Option<usize> {
    let mut end = dot;
    loop {
        let last = end.checked_sub(1)?;
        let start = match toks[last].0 {
            Token::Ident(_) | Token::Number(_) | Token::Str(_) | Token::True | Token::False => last,
            close @ (Token::RParen | Token::RBracket) => {
                let open = if close == Token::RParen {
                    Token::LParen
                } else {
                    Token::LBracket
                };
                let mut depth = 0usize;
                let mut j = last;
                loop {
                    let t = toks[j].0;
                    if t == close {
                        depth += 1;
                    } else if t == open {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    j = j.checked_sub(1)?;
                }
                match j.checked_sub(1).map(|k| toks[k].0) {
                    Some(Token::Ident(_)) if open == Token::LParen => j - 1,
                    _ => j,
                }
            }
            _ => return None,
        };
        match start.checked_sub(1).map(|k| toks[k].0) {
            Some(Token::Dot) => end = start - 1,
            _ => return Some(start),
        }
    }
}

/// Where the top-level item around the end of `toks` starts (0 if none does).
fn item_start(text_len: usize, toks: &[(Token, Span)]) -> usize {
    let mut depth = 0usize;
    let mut start = None;
    for (t, s) in toks {
        match t {
            t if t.starts_item() && depth == 0 => start = Some(s.start),
            Token::LBrace => depth += 1,
            Token::RBrace => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    start.unwrap_or(0).min(text_len)
}

/// The checker's type of the receiver before `toks[dot]`, a `.` (None where there is
/// no receiver or it does not check).
fn receiver_type(doc: &Document, toks: &[(Token, Span)], dot: usize) -> Option<Ty> {
    const NAME: &str = "__sdfc_receiver__";
    let first = receiver_start(toks, dot)?;
    let receiver = &doc.text[toks[first].1.start..toks[dot - 1].1.end];
    let before = &doc.text[..item_start(doc.text.len(), &toks[..first])];
    let source = format!("{before}\nlet {NAME} = {receiver};\n");
    let analysis = crate::driver::analyze(&source, None);
    let def = analysis.program.defs.last()?;
    (def.kind == DefKind::Let && def.name == NAME && def.ty != Ty::Error).then(|| def.ty.clone())
}

/// Whether `receiver.name(…)` makes sense: the builtin takes the receiver as its first
/// argument, and does not build a scene object out of plain values.
fn is_method_of(b: &Builtin, receiver: &Ty) -> bool {
    let Some(first) = b.params.first() else {
        return false;
    };
    let constructor = matches!(b.ret, Ret::Shape | Ret::Texture | Ret::Camera | Ret::Light)
        && !matches!(first.ty, PTy::Shape | PTy::Texture);
    !constructor
        && (!receiver.is_field() || b.kind.lifts_fields())
        && receiver.base().fits(first.ty)
}

/// Swizzles of a vector with `n` components: single components and the leading runs
/// (`xy`, `xyz`, `rgb` …) in both spellings.
fn swizzles(n: u8, field: bool) -> impl Iterator<Item = Completion> {
    ["xyzw", "rgba"].into_iter().flat_map(move |set| {
        let n = usize::from(n).min(4);
        let singles = (0..n).map(|i| &set[i..=i]);
        let runs = (2..=n).map(|k| &set[..k]);
        singles.chain(runs).map(move |s| {
            let ty = match s.len() {
                1 => Ty::Float,
                k => Ty::Vec(k as u8),
            };
            Completion::new(s, CompletionKind::Field).detail(ty.lift(field).to_string())
        })
    })
}

/// The atlas fields, as after `skin.`.
fn atlas_fields() -> impl Iterator<Item = Completion> {
    AtlasAttr::ALL.iter().map(|(_, name, ty, text)| {
        Completion::new(*name, CompletionKind::Field)
            .detail(format!("field<{ty}>"))
            .doc(*text)
    })
}

/// Completions after the `.` that ends `toks`: the receiver's fields, then its methods.
pub(super) fn members(doc: &Document, toks: &[(Token, Span)]) -> Vec<Completion> {
    let Some(ty) = toks
        .len()
        .checked_sub(1)
        .and_then(|dot| receiver_type(doc, toks, dot))
    else {
        return Vec::new();
    };
    let mut out: Vec<Completion> = match &ty {
        Ty::Atlas => atlas_fields().collect(),
        Ty::Vec(n) => swizzles(*n, false).collect(),
        Ty::Field(t) => match **t {
            Ty::Vec(n) => swizzles(n, true).collect(),
            _ => Vec::new(),
        },
        _ => Vec::new(),
    };
    out.extend(
        BUILTINS
            .iter()
            .filter(|b| is_method_of(b, &ty))
            .map(function),
    );
    out
}
