//! The code action "make this number a parameter": the number literal at the cursor,
//! inside a `let`, a material or the render item's target, becomes a `param` item
//! declared just above that item (named after the argument it sets), with a range
//! around its value, and the literal becomes the parameter's name. Every other byte of
//! the file stays as it was.

use super::Document;
use crate::diagnostic::Edit;
use crate::span::Span;
use crate::syntax::ast::ItemKind;
use crate::syntax::lexer::{lex, Token};

/// The action's title.
pub const TITLE: &str = "Make this number a parameter";

/// Whether `name` is taken in the document (a definition, a builtin or a keyword).
fn taken(doc: &Document, name: &str) -> bool {
    doc.analysis.program.lookup(name).is_some()
        || crate::sema::builtins::lookup(name).is_some()
        || crate::sema::builtins::CONSTANTS
            .iter()
            .any(|c| c.name == name)
        || crate::syntax::lexer::KEYWORDS.contains(&name)
}

/// The range a parameter of value `v` gets: from half to twice its size, or [-1, 1]
/// around zero (in the literal's own unit).
fn range(v: f64) -> (f64, f64) {
    if v > 0.0 {
        (v * 0.5, v * 2.0)
    } else if v < 0.0 {
        (v * 2.0, v * 0.5)
    } else {
        (-1.0, 1.0)
    }
}

fn number(x: f64, unit: &str) -> String {
    format!("{}{unit}", crate::sema::Value::Float(x).display())
}

/// The edits that turn the number under `range` into a parameter, if the cursor is on
/// one where a parameter may stand.
pub fn offered(doc: &Document, at: Span) -> Option<Vec<Edit>> {
    let lexed = lex(&doc.text, &mut Vec::new());
    let i = lexed.tokens.iter().position(|(t, s)| {
        matches!(t, Token::Number(_)) && s.start <= at.start && at.end <= s.end
    })?;
    let (Token::Number(text), span) = lexed.tokens[i] else {
        return None;
    };
    // A negative literal takes its sign along.
    let negative = i > 0
        && matches!(lexed.tokens[i - 1].0, Token::Minus)
        && !matches!(
            lexed.tokens.get(i.wrapping_sub(2)).map(|t| t.0),
            Some(Token::Number(_) | Token::Ident(_) | Token::RParen | Token::RBracket)
        );
    let literal = if negative {
        lexed.tokens[i - 1].1.to(span)
    } else {
        span
    };
    // Inside an item where a parameter may stand.
    let item = doc.analysis.parsed.file.items.iter().find(|it| {
        let inside = |s: Span| s.start <= literal.start && literal.end <= s.end;
        match &it.kind {
            ItemKind::Let { value, .. } => inside(value.span),
            ItemKind::Material { .. } => inside(it.span),
            ItemKind::Render { target, .. } => inside(target.span),
            _ => false,
        }
    })?;
    let unit = ["deg", "rad"]
        .into_iter()
        .find(|u| text.ends_with(u))
        .unwrap_or("");
    let mut value: f64 = text[..text.len() - unit.len()].parse().ok()?;
    if negative {
        value = -value;
    }
    // The name of the argument it sets (`radius: 0.5`), else `value`.
    let base = match (
        i.checked_sub(2).map(|j| lexed.tokens[j].0),
        lexed.tokens.get(i.wrapping_sub(1)),
    ) {
        (Some(Token::Ident(n)), Some((Token::Colon, _))) if !negative => n.to_string(),
        _ => String::from("value"),
    };
    let name = (1..)
        .map(|k| {
            if k == 1 {
                base.clone()
            } else {
                format!("{base}_{k}")
            }
        })
        .find(|n| !taken(doc, n))?;
    let (lo, hi) = range(value);
    let decl = format!(
        "param {name} = {} in [{}, {}];\n",
        number(value, unit),
        number(lo, unit),
        number(hi, unit)
    );
    Some(vec![
        Edit {
            span: Span::new(item.span.start, item.span.start),
            text: decl,
        },
        Edit {
            span: literal,
            text: name,
        },
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(src: &str, cursor: &str) -> Option<String> {
        let doc = Document::new(src, None);
        let at = src.find(cursor)?;
        let edits = offered(&doc, Span::new(at, at))?;
        Some(super::super::actions::apply(src, &edits))
    }

    #[test]
    fn a_number_becomes_a_parameter_and_nothing_else_moves() {
        let src = "// a comment\nlet s = sphere(radius: 0.5);  // keep\nrender s;\n";
        let out = apply(src, "0.5").unwrap();
        assert_eq!(
            out,
            "// a comment\nparam radius = 0.5 in [0.25, 1];\nlet s = sphere(radius: radius);  // keep\nrender s;\n"
        );
        let doc = Document::new(out.as_str(), None);
        assert!(!doc.analysis.has_errors(), "{:?}", doc.analysis.diagnostics);
        // Units, signs and taken names.
        let src = "let radius = 1;\nrender box(radius).rotate_y(-30deg);\n";
        let out = apply(src, "30deg").unwrap();
        assert!(
            out.contains("param value = -30deg in [-60deg, -15deg];"),
            "{out}"
        );
        assert!(out.contains("rotate_y(value)"), "{out}");
        let src = "let s = sphere(radius: 0.5);\nrender s;\n";
        let taken = src.replace("let s", "let radius = 2;\nlet s");
        let out = apply(&taken, "0.5").unwrap();
        assert!(out.contains("param radius_2 = 0.5"), "{out}");
        // Not offered in a setting, nor away from a number.
        assert!(apply("render sphere(1) { size = [64, 64]; }", "64").is_none());
        assert!(apply("render sphere(1);", "sphere").is_none());
    }
}
