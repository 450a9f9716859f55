//! Carrying the back end's results over an edit that changes only trivia.
//!
//! The back end (the atlases' geometry, lowering, code generation and naga) reads the
//! checked program, which comes from the significant tokens alone. When an edit changes
//! only comments and whitespace, the new text has the same tokens in the same order,
//! so the back end would compute the same atlases, scene and module, and the same
//! diagnostics at the same tokens. [`carry_back_end`] then reuses them, moving their
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
struct TokenMap {
    old: Vec<Span>,
    new: Vec<Span>,
    new_len: usize,
}

impl TokenMap {
    fn new(old_text: &str, new_text: &str) -> Option<TokenMap> {
        let (old, new) = (
            lexer::lex(old_text, &mut Vec::new()),
            lexer::lex(new_text, &mut Vec::new()),
        );
        if old.tokens.len() != new.tokens.len()
            || old
                .tokens
                .iter()
                .zip(&new.tokens)
                .any(|((a, sa), (b, sb))| {
                    a != b || old_text.get(sa.range()) != new_text.get(sb.range())
                })
        {
            return None;
        }
        Some(TokenMap {
            old: old.tokens.iter().map(|t| t.1).collect(),
            new: new.tokens.iter().map(|t| t.1).collect(),
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

/// The full analysis of `new_text`, from its front end's `front` and the full analysis
/// `old` of `old_text` (whose front end gave `old_front`), when the two texts have the
/// same significant tokens; None when they do not, or when `front` has errors.
pub fn carry_back_end(
    old_text: &str,
    old_front: &[Diagnostic],
    old: &Analysis,
    new_text: &str,
    mut front: Analysis,
) -> Option<Analysis> {
    if front.has_errors() {
        return None;
    }
    let map = TokenMap::new(old_text, new_text)?;
    // The back end's diagnostics: the full set less the front end's (as a multiset).
    let mut front_left: Vec<&Diagnostic> = old_front.iter().collect();
    let back: Vec<Diagnostic> = old
        .diagnostics
        .iter()
        .filter(|d| match front_left.iter().position(|f| f == d) {
            Some(k) => {
                front_left.swap_remove(k);
                false
            }
            None => true,
        })
        .map(|d| map.diagnostic(d.clone()))
        .collect();
    front.diagnostics.extend(back);
    diagnostic::sort(&mut front.diagnostics);
    front.atlases = old.atlases.clone();
    front.scene = old.scene.clone();
    front.compiled = old.compiled.as_ref().map(|c| {
        let mut module = c.module.clone();
        for region in &mut module.source_map {
            region.span = map.span(region.span);
        }
        Arc::new(Compiled {
            module,
            validated: Arc::clone(&c.validated),
        })
    });
    Some(front)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_follow_their_tokens() {
        let old = "let a = sphere(1); // x\nrender a;";
        let new = "/* c */ let  a=sphere( 1 );\n\n   render a ;";
        let map = TokenMap::new(old, new).unwrap();
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
        assert!(TokenMap::new(old, "let a = sphere(2); render a;").is_none());
        assert!(TokenMap::new(old, "let b = sphere(1); render a;").is_none());
        assert!(TokenMap::new(old, "let a = sphere(1);").is_none());
    }
}
