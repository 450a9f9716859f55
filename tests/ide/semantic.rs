//! Semantic tokens.

use super::SCENE;
use sdfc::ide::semantic::{semantic_tokens, TokenKind};
use sdfc::ide::Document;

/// `text kind [declaration] [builtin]`, one token per line.
fn listing(text: &str) -> String {
    let doc = Document::new(text, None);
    semantic_tokens(&doc)
        .iter()
        .map(|t| {
            let mut line = format!("{:<16} {:?}", &text[t.span.range()], t.kind);
            if t.declaration {
                line.push_str(" declaration");
            }
            if t.builtin {
                line.push_str(" builtin");
            }
            line
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn every_kind_of_token() {
    let text = format!("// the scene\n{SCENE}let s = sphere(radius: /* r */ 2) - ball;\n");
    insta::with_settings!({ snapshot_path => "../snapshots", prepend_module_to_snapshot => false, omit_expression => true }, {
        insta::assert_snapshot!("semantic_tokens", listing(&text));
    });
}

#[test]
fn names_are_classified_by_what_they_name() {
    let doc = Document::new(SCENE, None);
    let tokens = semantic_tokens(&doc);
    let kind_of = |needle: &str, n: usize| {
        let start = SCENE.match_indices(needle).nth(n).unwrap().0;
        tokens
            .iter()
            .find(|t| t.span.start == start)
            .map(|t| (t.kind, t.declaration, t.builtin))
    };
    assert_eq!(
        kind_of("radius", 0),
        Some((TokenKind::Variable, true, false))
    );
    assert_eq!(
        kind_of("radius", 1),
        Some((TokenKind::Variable, false, false))
    );
    assert_eq!(
        kind_of("sphere", 0),
        Some((TokenKind::Function, false, true))
    );
    assert_eq!(
        kind_of("translate", 0),
        Some((TokenKind::Function, false, true))
    );
    assert_eq!(kind_of("skin", 0), Some((TokenKind::Atlas, true, false)));
    assert_eq!(kind_of("skin", 1), Some((TokenKind::Atlas, false, false)));
    assert_eq!(kind_of("front", 1), Some((TokenKind::Seed, false, false)));
    assert_eq!(
        kind_of("steps", 0),
        Some((TokenKind::Property, false, false))
    );
    assert_eq!(kind_of("uv", 0), Some((TokenKind::Property, false, false)));
    assert_eq!(kind_of("pi", 0), Some((TokenKind::Variable, false, true)));
    assert_eq!(kind_of("m ", 0), Some((TokenKind::Material, true, false)));
    assert_eq!(
        kind_of("tangent", 0),
        Some((TokenKind::Keyword, false, false))
    );
    assert_eq!(kind_of("0.5", 0), Some((TokenKind::Number, false, false)));
    // Sorted and disjoint.
    assert!(tokens.windows(2).all(|w| w[0].span.end <= w[1].span.start));
}
