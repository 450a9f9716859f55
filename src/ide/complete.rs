//! Completion and signature help. Both read the tokens before the cursor, so
//! they work on the half-written text an editor sends, whatever the parser
//! made of it; names come from the checked program, signatures from the
//! builtins table. After `receiver.`, the members of the receiver's type come
//! from [`super::member`].

pub use super::completion::{Completion, CompletionKind};

use super::completion::function;
use super::Document;
use crate::sema::builtins::{
    self, Builtin, SettingSpec, ATLAS_SETTINGS, BUILTINS, CONSTANTS, MATERIAL_SETTINGS,
    RENDER_SETTINGS,
};
use crate::sema::DefKind;
use crate::span::Span;
use crate::syntax::lexer::{lex, Token};

type Toks<'a> = Vec<(Token<'a>, Span)>;

/// The tokens before the cursor, without the name being typed at it; `None`
/// inside a comment or a string.
fn tokens_before(text: &str, offset: usize) -> Option<Toks<'_>> {
    let lexed = lex(text, &mut Vec::new());
    for c in &lexed.comments {
        let s = c.span;
        let closed = c.block && s.len() >= 4 && text[s.range()].ends_with("*/");
        let inside = if !c.block {
            s.start < offset && offset <= s.end
        } else if closed {
            s.start < offset && offset < s.end
        } else {
            s.start < offset
        };
        if inside {
            return None;
        }
    }
    let mut out: Toks = Vec::new();
    for (t, s) in lexed.tokens {
        if s.end > offset {
            if matches!(t, Token::Str(_) | Token::UnterminatedStr(_)) && s.start < offset {
                return None;
            }
            break;
        }
        out.push((t, s));
    }
    if let Some((Token::Ident(_), s)) = out.last() {
        if s.end == offset {
            out.pop();
        }
    }
    if let Some((Token::UnterminatedStr(_), s)) = out.last() {
        if s.end == offset {
            return None;
        }
    }
    Some(out)
}

/// The innermost block around the cursor: its item keyword and (for atlases) its name.
fn block<'a>(toks: &[(Token<'a>, Span)]) -> Option<(Token<'a>, Option<&'a str>)> {
    let mut depth = 0usize;
    let mut item: Option<(Token, Option<&str>)> = None;
    for (i, (t, _)) in toks.iter().enumerate() {
        match t {
            t if t.starts_item() && depth == 0 => {
                let name = match toks.get(i + 1) {
                    Some((Token::Ident(n), _)) => Some(*n),
                    _ => None,
                };
                item = Some((*t, name));
            }
            Token::LBrace => depth += 1,
            Token::RBrace => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    if depth > 0 {
        item
    } else {
        None
    }
}

/// The call whose argument list holds the cursor.
pub(crate) struct Call {
    pub builtin: &'static Builtin,
    /// `receiver.f(…)`: the receiver is the first parameter.
    pub method: bool,
    /// Arguments before the cursor's: (name if named).
    pub before: Vec<Option<String>>,
    /// The name of the cursor's argument, when it is named (`name: …`).
    pub named: Option<String>,
    /// The cursor is where an argument starts (after `(` or `,`).
    pub at_start: bool,
}

impl Call {
    /// Which parameters the arguments before the cursor's give: the receiver and the
    /// positional arguments the first ones, named arguments their own.
    pub fn given(&self) -> Vec<bool> {
        let positional =
            self.before.iter().take_while(|a| a.is_none()).count() + usize::from(self.method);
        self.builtin
            .params
            .iter()
            .enumerate()
            .map(|(i, p)| i < positional || self.before.iter().flatten().any(|n| n == p.name))
            .collect()
    }

    /// The parameter the cursor's argument binds to: the one it names, or else the
    /// first one not given yet (the next position after positional arguments; after
    /// named ones, the parameter the user is most likely about to name).
    pub fn active_parameter(&self) -> Option<usize> {
        if let Some(n) = &self.named {
            return self.builtin.param(n).map(|(i, _)| i);
        }
        self.given().iter().position(|g| !g)
    }
}

/// The argument's name: `name :` at the start of the tokens of one argument.
fn arg_name<'a>(arg: &[(Token<'a>, Span)]) -> Option<&'a str> {
    match arg {
        [(Token::Ident(n), _), (Token::Colon, _), ..] => Some(n),
        _ => None,
    }
}

pub(crate) fn call_at(toks: &[(Token, Span)]) -> Option<Call> {
    let mut depth = 0usize;
    // Where the cursor's argument and each later-found argument start.
    let mut commas: Vec<usize> = Vec::new();
    let mut i = toks.len();
    while i > 0 {
        i -= 1;
        match toks[i].0 {
            Token::RParen | Token::RBracket => depth += 1,
            Token::LBracket if depth == 0 => commas.clear(),
            Token::LParen if depth == 0 => {
                let method = i >= 2 && toks[i - 2].0 == Token::Dot;
                let Some((Token::Ident(name), _)) = i.checked_sub(1).map(|j| toks[j]) else {
                    commas.clear();
                    continue;
                };
                let builtin = builtins::lookup(name)?;
                let mut bounds: Vec<usize> = std::iter::once(i)
                    .chain(commas.iter().rev().copied())
                    .collect();
                bounds.push(toks.len());
                let args: Vec<&[(Token, Span)]> = bounds
                    .windows(2)
                    .map(|w| &toks[w[0] + 1..w[1].max(w[0] + 1)])
                    .collect();
                let (current, before) = args.split_last()?;
                return Some(Call {
                    builtin,
                    method,
                    before: before
                        .iter()
                        .map(|a| arg_name(a).map(String::from))
                        .collect(),
                    named: arg_name(current).map(String::from),
                    at_start: current.is_empty(),
                });
            }
            Token::LParen | Token::LBracket => depth -= 1,
            Token::Comma if depth == 0 => commas.push(i),
            Token::Semi | Token::LBrace | Token::RBrace => return None,
            t if t.starts_item() => return None,
            _ => {}
        }
    }
    None
}

fn settings(specs: &[SettingSpec]) -> impl Iterator<Item = Completion> + '_ {
    specs.iter().map(|s| {
        Completion::new(s.name, CompletionKind::Setting)
            .detail(s.describe())
            .doc(s.doc)
            .insert(format!("{} = ", s.name))
    })
}

/// Completions at a byte offset.
pub fn completions(doc: &Document, offset: usize) -> Vec<Completion> {
    let Some(toks) = tokens_before(&doc.text, offset) else {
        return Vec::new();
    };
    let program = &doc.analysis.program;
    let last = toks.last().map(|t| t.0);
    let block = block(&toks);

    // After `.`: what the receiver's type has.
    if last == Some(Token::Dot) {
        return super::member::members(doc, &toks);
    }
    // Where a name is being defined, there is nothing to offer.
    if matches!(
        last,
        Some(Token::Let | Token::Param | Token::Atlas | Token::Material | Token::Seed)
    ) {
        return Vec::new();
    }
    if let (Some(Token::Ident(_)), Some(Token::Atlas)) =
        (last, toks.len().checked_sub(2).map(|i| toks[i].0))
    {
        return vec![Completion::new("on", CompletionKind::Keyword)];
    }
    // At the start of a statement.
    if matches!(
        last,
        None | Some(Token::Semi | Token::LBrace | Token::RBrace)
    ) {
        return match block {
            None => ["let", "atlas", "material", "render"]
                .into_iter()
                .map(|k| Completion::new(k, CompletionKind::Keyword))
                .collect(),
            Some((Token::Atlas, _)) => ["seed", "merge"]
                .into_iter()
                .map(|k| Completion::new(k, CompletionKind::Keyword))
                .chain(settings(ATLAS_SETTINGS))
                .collect(),
            Some((Token::Material, _)) => settings(MATERIAL_SETTINGS).collect(),
            Some((Token::Render, _)) => settings(RENDER_SETTINGS).collect(),
            Some(_) => Vec::new(),
        };
    }
    // `merge a b …`: the seeds of the atlas.
    if let Some((Token::Atlas, Some(atlas))) = block {
        let stmt = toks
            .iter()
            .rposition(|(t, _)| matches!(t, Token::Semi | Token::LBrace))
            .map_or(0, |i| i + 1);
        if toks.get(stmt).map(|t| t.0) == Some(Token::Merge) {
            return program
                .atlases
                .iter()
                .filter(|a| a.name == atlas)
                .flat_map(|a| &a.seeds)
                .map(|s| Completion::new(s.name.clone(), CompletionKind::Seed))
                .collect();
        }
    }
    // An expression.
    let mut out = Vec::new();
    if let Some(call) = call_at(&toks) {
        if call.at_start {
            for (p, given) in call.builtin.params.iter().zip(call.given()) {
                if !given {
                    out.push(
                        Completion::new(format!("{}:", p.name), CompletionKind::Parameter)
                            .detail(p.describe())
                            .insert(format!("{}: ", p.name)),
                    );
                }
            }
        }
    }
    for d in &program.defs {
        if d.item_span.end > offset {
            continue;
        }
        let kind = match d.kind {
            DefKind::Let | DefKind::Param => CompletionKind::Variable,
            DefKind::Atlas => CompletionKind::Atlas,
            DefKind::Material => CompletionKind::Material,
            DefKind::Seed { .. } => continue,
        };
        out.push(Completion::new(d.name.clone(), kind).detail(d.ty.to_string()));
    }
    out.extend(
        CONSTANTS
            .iter()
            .map(|c| Completion::new(c.name, CompletionKind::Constant).doc(c.doc)),
    );
    out.extend(BUILTINS.iter().map(function));
    out.extend(["true", "false"].map(|k| Completion::new(k, CompletionKind::Keyword)));
    out
}

/// Signature help for the call around the cursor.
#[derive(Debug, Clone, PartialEq)]
pub struct SignatureHelp {
    /// The builtin's signature, as in [`Builtin::signature`].
    pub label: String,
    /// Each parameter's byte range in `label`.
    pub parameters: Vec<(usize, usize)>,
    pub active_parameter: Option<usize>,
    pub documentation: String,
}

/// Signature help at a byte offset.
pub fn signature_help(doc: &Document, offset: usize) -> Option<SignatureHelp> {
    let toks = tokens_before(&doc.text, offset)?;
    let call = call_at(&toks)?;
    let b = call.builtin;
    let mut label = format!("{}(", b.name);
    let mut parameters = Vec::new();
    for (i, p) in b.params.iter().enumerate() {
        if i > 0 {
            label.push_str(", ");
        }
        let start = label.len();
        label.push_str(&p.describe());
        parameters.push((start, label.len()));
    }
    let sig = b.signature();
    label.push_str(&sig[sig.rfind(')').unwrap_or(sig.len())..]);
    Some(SignatureHelp {
        label,
        parameters,
        active_parameter: call.active_parameter(),
        documentation: format!("{} — {}", b.kind.title(), b.doc),
    })
}
