//! Rename and prepare-rename.

use super::{at, cursor};
use sdfc::ide::rename::{prepare_rename, rename};

/// The text with every span replaced by `new`.
fn apply(text: &str, spans: &[sdfc::Span], new: &str) -> String {
    let mut out = text.to_string();
    for s in spans.iter().rev() {
        out.replace_range(s.range(), new);
    }
    out
}

#[test]
fn renames_lets_atlases_materials_and_seeds() {
    let (doc, offset) = at(&cursor("ball", 2));
    let (span, name) = prepare_rename(&doc, offset + 1).unwrap();
    assert_eq!((&doc.text[span.range()], name.as_str()), ("ball", "ball"));
    let spans = rename(&doc, offset + 1, "orb").unwrap();
    assert_eq!(spans.len(), 3);
    let renamed = apply(&doc.text, &spans, "orb");
    assert!(renamed.contains("let orb = sphere(radius)"), "{renamed}");
    assert!(renamed.contains("atlas skin on orb {"), "{renamed}");
    assert!(renamed.contains("render orb.paint(m);"), "{renamed}");
    assert!(!renamed.contains("ball"));
    assert!(sdfc::driver::analyze(&renamed, None).diagnostics.is_empty());

    // A seed, from its use in a merge.
    let (doc, offset) = at(&cursor("front", 1));
    let spans = rename(&doc, offset, "bottom").unwrap();
    let renamed = apply(&doc.text, &spans, "bottom");
    assert!(renamed.contains("seed bottom = [0, 1, 0.5]"), "{renamed}");
    assert!(renamed.contains("merge bottom top;"), "{renamed}");

    // An atlas, with its fields, and a material.
    let (doc, offset) = at(&cursor("skin", 0));
    let renamed = apply(&doc.text, &rename(&doc, offset, "hide").unwrap(), "hide");
    assert!(
        renamed.contains("atlas hide on ball") && renamed.contains("[hide.uv, 0]"),
        "{renamed}"
    );
    let (doc, offset) = at(&cursor("m)", 0));
    let renamed = apply(
        &doc.text,
        &rename(&doc, offset, "paint_1").unwrap(),
        "paint_1",
    );
    assert!(
        renamed.contains("material paint_1 {") && renamed.contains(".paint(paint_1)"),
        "{renamed}"
    );
}

#[test]
fn refuses_builtins_keywords_and_bad_names() {
    let err = |needle: &str, n: usize, new: &str| {
        let (doc, offset) = at(&cursor(needle, n));
        rename(&doc, offset + 1, new).unwrap_err().0
    };
    assert_eq!(
        err("sphere", 0, "ball2"),
        "`sphere` is a builtin function and cannot be renamed"
    );
    assert_eq!(err("pi", 0, "p"), "`pi` is a builtin and cannot be renamed");
    assert_eq!(
        err("tangent", 0, "t"),
        "`tangent` is a keyword and cannot be renamed"
    );
    assert_eq!(
        err("steps", 0, "n"),
        "`steps` is not a name defined in this scene"
    );
    assert_eq!(err("ball", 0, "let"), "`let` is a keyword");
    assert_eq!(err("ball", 0, "2ball"), "`2ball` is not a valid name");
    assert_eq!(err("ball", 0, "my ball"), "`my ball` is not a valid name");
    assert_eq!(err("ball", 0, "torus"), "`torus` is the name of a builtin");
    assert_eq!(
        err("ball", 0, "radius"),
        "`radius` is already defined in this scene"
    );
    assert_eq!(
        err("ball", 0, "skin"),
        "`skin` is already defined in this scene"
    );
    assert_eq!(
        err("front", 0, "top"),
        "`top` is already defined in this scene"
    );
    // A seed may share a name with an item.
    let (doc, offset) = at(&cursor("front", 0));
    assert!(rename(&doc, offset, "ball").is_ok());
    let (doc, offset) = at(&cursor("sphere", 0));
    assert!(prepare_rename(&doc, offset).is_err());
}
