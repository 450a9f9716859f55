//! Carrying the back end's results over an edit that changes nothing it reads.
//!
//! The back end (the atlases' geometry, lowering, code generation and naga) reads the
//! checked program, which comes from the significant tokens alone, and never looks at
//! a `let` of a plain constant that nothing uses. When an edit changes only comments,
//! whitespace and such inert `let`s, the other tokens are the same in the same order,
//! so the back end would compute the same atlases, scene and module, and the same
//! diagnostics at the same tokens. [`BackEnd::carry`] then reuses them, moving their
//! spans token by token, instead of running the back end again: the language server's
//! answer to such an edit takes the front end's milliseconds.
//!
//! What the back end read besides the text (texture files, for displacements) is not
//! read again: an edit of comments keeps what a texture gave the last full analysis.

use crate::diagnostic::{self, Diagnostic};
use crate::driver::{Analysis, Compiled};
use crate::span::Span;
use crate::syntax::lexer;
use std::sync::Arc;

/// The significant tokens' spans of two texts, when their tokens are the same.
struct TokenMap<'a> {
    old: &'a [Span],
    new: Vec<Span>,
    new_len: usize,
}

/// The spans of a text's significant tokens, but for those inside `inert` items
/// (sorted, disjoint spans).
fn token_spans(text: &str, inert: &[Span]) -> Vec<Span> {
    let mut k = 0;
    lexer::lex(text, &mut Vec::new())
        .tokens
        .iter()
        .map(|t| t.1)
        .filter(|s| {
            while k < inert.len() && inert[k].end <= s.start {
                k += 1;
            }
            !inert
                .get(k)
                .is_some_and(|i| i.start <= s.start && s.end <= i.end)
        })
        .collect()
}

/// The items of an analysed text that the back end never reads: `let`s of a constant
/// number, vector, boolean or string that nothing uses (the front end's `W0001`) and
/// that load no texture. Adding,
/// removing or changing one leaves the atlases, the scene and the module as they were.
/// Sorted by position.
fn inert_items(analysis: &Analysis) -> Vec<Span> {
    let unused: std::collections::HashSet<Span> = analysis
        .diagnostics
        .iter()
        .filter(|d| d.code == crate::codes::W_UNUSED)
        .filter_map(Diagnostic::span)
        .collect();
    use crate::sema::types::Value;
    // Every `image(…)` is a texture of the program, which the back end may decode (for
    // displacements), used or not: an item holding one is never inert.
    let reads_texture = |item: Span| {
        analysis
            .program
            .textures
            .iter()
            .any(|t| item.start <= t.span.start && t.span.end <= item.end)
    };
    let mut spans: Vec<Span> = analysis
        .program
        .defs
        .iter()
        .filter(|d| {
            d.kind == crate::sema::DefKind::Let
                && unused.contains(&d.span)
                // A folded constant: not a surface field of the same type.
                && matches!(
                    d.value,
                    Value::Float(_) | Value::Vec(_) | Value::Bool(_) | Value::Str(_)
                )
                && !reads_texture(d.item_span)
        })
        .map(|d| d.item_span)
        .collect();
    spans.sort();
    spans
}

impl<'a> TokenMap<'a> {
    /// The map from `old_text` (whose tokens are at `old`) to `new_text`. The lexer
    /// reads no context beyond a token, so tokens of the same text are the same tokens.
    fn new(
        old_text: &str,
        old: &'a [Span],
        new_text: &str,
        new_inert: &[Span],
    ) -> Option<TokenMap<'a>> {
        let new = token_spans(new_text, new_inert);
        if old.len() != new.len()
            || old
                .iter()
                .zip(&new)
                .any(|(a, b)| old_text.get(a.range()) != new_text.get(b.range()))
        {
            return None;
        }
        Some(TokenMap {
            old,
            new,
            new_len: new_text.len(),
        })
    }

    /// The new offset of an old one: the same place in the same token; in trivia, as
    /// far after the previous token as before, but not past the next token. Where one
    /// token ends as the next starts, a span's start goes with the next and its end
    /// with the previous.
    fn offset(&self, x: usize, end: bool) -> usize {
        // The last token starting at or before x (before x, for an end).
        let i = self
            .old
            .partition_point(|s| s.start < x || (!end && s.start == x));
        if i == 0 {
            return x.min(self.new.first().map_or(self.new_len, |s| s.start));
        }
        let (o, n) = (self.old[i - 1], self.new[i - 1]);
        if x <= o.end {
            return n.start + (x - o.start);
        }
        let limit = self.new.get(i).map_or(self.new_len, |s| s.start);
        (n.end + (x - o.end)).min(limit)
    }

    fn span(&self, s: Span) -> Span {
        let start = self.offset(s.start, false);
        Span::new(start, self.offset(s.end, true).max(start))
    }

    fn diagnostic(&self, mut d: Diagnostic) -> Diagnostic {
        for label in d.primary.iter_mut().chain(d.secondary.iter_mut()) {
            label.span = self.span(label.span);
        }
        for edit in d.fixes.iter_mut().flat_map(|f| f.edits.iter_mut()) {
            edit.span = self.span(edit.span);
        }
        d
    }
}

/// What the back end of a document's last full analysis gave, kept for its next text.
#[derive(Debug)]
pub struct BackEnd {
    text: String,
    tokens: Vec<Span>,
    /// The back end's diagnostics: the full set less the front end's.
    diagnostics: Vec<Diagnostic>,
    atlases: Vec<Option<crate::uv::Atlas>>,
    scene: Option<crate::ir::Scene>,
    compiled: Option<Arc<Compiled>>,
}

impl BackEnd {
    /// The back end of `full`, the full analysis of `text`, whose front end reported
    /// `front`.
    pub fn of(text: &str, front: &[Diagnostic], full: &Analysis) -> BackEnd {
        let mut front_left: Vec<&Diagnostic> = front.iter().collect();
        let diagnostics = full
            .diagnostics
            .iter()
            .filter(|d| match front_left.iter().position(|f| f == d) {
                Some(k) => {
                    front_left.swap_remove(k);
                    false
                }
                None => true,
            })
            .cloned()
            .collect();
        BackEnd {
            text: text.to_string(),
            tokens: token_spans(text, &inert_items(full)),
            diagnostics,
            atlases: full.atlases.clone(),
            scene: full.scene.clone(),
            compiled: full.compiled.clone(),
        }
    }

    /// The back end's results for `new_text`, whose front end's analysis is `front`,
    /// when it has the same significant tokens as this back end's text, but for inert
    /// items ([`inert_items`]): the same results with their spans moved.
    pub fn carried(&self, new_text: &str, front: &Analysis) -> Option<Carried> {
        let map = TokenMap::new(&self.text, &self.tokens, new_text, &inert_items(front))?;
        let diagnostics = self
            .diagnostics
            .iter()
            .map(|d| map.diagnostic(d.clone()))
            .collect();
        let compiled = self.compiled.as_ref().map(|c| {
            let mut module = c.module.clone();
            for region in &mut module.source_map {
                region.span = map.span(region.span);
            }
            Arc::new(Compiled {
                module,
                validated: Arc::clone(&c.validated),
            })
        });
        Some(Carried {
            diagnostics,
            atlases: self.atlases.clone(),
            scene: self.scene.clone(),
            compiled,
        })
    }

    /// The full analysis of `new_text` from its front end's analysis `front`, when the
    /// text has the same significant tokens as this back end's; `front` back when the
    /// tokens differ or it has errors.
    pub fn carry(&self, new_text: &str, mut front: Analysis) -> Result<Analysis, Analysis> {
        if front.has_errors() {
            return Err(front);
        }
        match self.carried(new_text, &front) {
            Some(c) => {
                c.complete(&mut front);
                Ok(front)
            }
            None => Err(front),
        }
    }
}

/// A back end's results moved to a new text ([`BackEnd::carried`]).
pub struct Carried {
    diagnostics: Vec<Diagnostic>,
    atlases: Vec<Option<crate::uv::Atlas>>,
    scene: Option<crate::ir::Scene>,
    compiled: Option<Arc<Compiled>>,
}

impl Carried {
    /// Makes `front`, the front end's analysis of the new text (without errors), the
    /// full analysis.
    pub fn complete(self, front: &mut Analysis) {
        front.diagnostics.extend(self.diagnostics);
        diagnostic::sort(&mut front.diagnostics);
        front.atlases = self.atlases;
        front.scene = self.scene;
        front.compiled = self.compiled;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_follow_their_tokens() {
        let old = "let a = sphere(1); // x\nrender a;";
        let new = "/* c */ let  a=sphere( 1 );\n\n   render a ;";
        let tokens = token_spans(old, &[]);
        let map = TokenMap::new(old, &tokens, new, &[]).unwrap();
        // `sphere` and the `1`, and the `a` of `render a`.
        let at = |s: &str, what: &str, n: usize| s.match_indices(what).nth(n).unwrap().0;
        assert_eq!(
            map.offset(at(old, "sphere", 0), false),
            at(new, "sphere", 0)
        );
        assert_eq!(map.offset(at(old, "1", 0), false), at(new, "1", 0));
        assert_eq!(map.offset(at(old, "1", 0) + 1, true), at(new, "1", 0) + 1);
        assert_eq!(map.offset(at(old, "1", 0) + 1, false), at(new, ")", 0));
        assert_eq!(
            map.offset(at(old, "render", 0) + 2, false),
            at(new, "render", 0) + 2
        );
        // In trivia: after the previous token, never past the next one.
        assert_eq!(map.offset(at(old, "//", 0), false), at(new, ";", 0) + 2);
        assert!(map.offset(at(old, "x", 0), false) <= at(new, "render", 0));
        assert_eq!(map.offset(0, false), at(new, "let", 0));
        assert_eq!(map.offset(old.len(), true), new.len());
        // An empty span at a token's start stays empty, at that token.
        let r = at(old, "render", 0);
        assert_eq!(
            map.span(Span::new(r, r)),
            Span::new(at(new, "render", 0), at(new, "render", 0))
        );
        // Another token, another name, or a token moved: no map.
        assert!(TokenMap::new(old, &tokens, "let a = sphere(2); render a;", &[]).is_none());
        assert!(TokenMap::new(old, &tokens, "let b = sphere(1); render a;", &[]).is_none());
        assert!(TokenMap::new(old, &tokens, "let a = sphere(1);", &[]).is_none());
    }
}
