//! Edits of comments and whitespace only: the back end's results carried over from
//! the last full analysis (`sdfc::incremental`, what the language server does) equal a
//! fresh analysis of the new text, for every example and UI scene.

use sdfc::driver;
use sdfc::incremental::BackEnd;
use sdfc::syntax::lexer;
use std::path::Path;

use crate::common;

/// The text with comments and line breaks added between tokens, and spaces doubled.
fn with_trivia(text: &str) -> String {
    let lexed = lexer::lex(text, &mut Vec::new());
    let mut out = String::from("// added\n");
    let mut at = 0;
    for (k, (_, span)) in lexed.tokens.iter().enumerate() {
        out.push_str(&text[at..span.start].replace(' ', "  "));
        match k % 4 {
            0 => out.push_str("/* c */ "),
            2 => out.push_str("\n  "),
            _ => {}
        }
        out.push_str(&text[span.range()]);
        at = span.end;
    }
    out.push_str(&text[at..]);
    out
}

/// WGSL with the numbers after `height_` left out.
fn unnumbered(wgsl: &str) -> String {
    let mut out = String::with_capacity(wgsl.len());
    let mut rest = wgsl;
    while let Some(k) = rest.find("height_") {
        out.push_str(&rest[..k + 7]);
        rest = rest[k + 7..].trim_start_matches(|c: char| c.is_ascii_digit());
    }
    out.push_str(rest);
    out
}

#[test]
fn carried_back_ends_equal_fresh_analyses() {
    let files = common::scene_files();
    let (mut carried_count, mut with_back_end_diagnostics) = (0, 0);
    for path in &files {
        let Ok(text) = std::fs::read_to_string(path) else {
            continue; // not UTF-8: a decoding test
        };
        let dir = path.parent();
        let old_front = driver::analyze(&text, dir);
        if old_front.has_errors() {
            continue;
        }
        let old = driver::check_all(&text, dir);
        let new_text = with_trivia(&text);
        let front = driver::analyze(&new_text, dir);
        let fresh = driver::check_all(&new_text, dir);
        let name = path.display();
        let back_end = BackEnd::of(&text, &old_front.diagnostics, &old);
        let carried = back_end
            .carry(&new_text, front)
            .unwrap_or_else(|_| panic!("{name}: not carried"));
        carried_count += 1;
        if old.diagnostics.len() > old_front.diagnostics.len() {
            with_back_end_diagnostics += 1;
        }
        assert_eq!(carried.diagnostics, fresh.diagnostics, "{name}");
        assert_eq!(carried.atlases.len(), fresh.atlases.len(), "{name}");
        assert_eq!(carried.scene.is_some(), fresh.scene.is_some(), "{name}");
        match (&carried.compiled, &fresh.compiled) {
            (Some(c), Some(f)) => {
                let (c, f) = (&c.module, &f.module);
                assert_eq!(c.source_map.len(), f.source_map.len(), "{name}");
                // The same code, but for the displacements' `height_ID` functions, named
                // by their place in the text that was compiled.
                let (cw, fw) = (unnumbered(&c.wgsl), unnumbered(&f.wgsl));
                let first = cw.lines().zip(fw.lines()).position(|(a, b)| a != b);
                assert!(
                    first.is_none() && cw.len() == fw.len(),
                    "{name}: line {first:?}: {:?} against {:?}",
                    first.and_then(|k| cw.lines().nth(k)),
                    first.and_then(|k| fw.lines().nth(k)),
                );
                for (a, b) in c.source_map.iter().zip(&f.source_map) {
                    assert_eq!((a.span, &a.what), (b.span, &b.what), "{name}");
                }
            }
            (None, None) => {}
            _ => panic!("{name}: compiled in one analysis only"),
        }
        // A change the back end reads is not carried: here a shape, which the module
        // emits even unused.
        let changed = new_text.replacen("// added\n", "let added_by_the_test = sphere(1);\n", 1);
        let front = driver::analyze(&changed, dir);
        assert!(back_end.carry(&changed, front).is_err(), "{name}");
        // An unused constant is inert: carried, and equal to a fresh analysis.
        let inert = new_text.replacen("// added\n", "let added_by_the_test = [1, 2, 3];\n", 1);
        let front = driver::analyze(&inert, dir);
        if !front.has_errors() {
            let carried = back_end
                .carry(&inert, front)
                .unwrap_or_else(|_| panic!("{name}: an unused constant was not carried"));
            let fresh = driver::check_all(&inert, dir);
            assert_eq!(carried.diagnostics, fresh.diagnostics, "{name}");
            if let (Some(c), Some(f)) = (&carried.compiled, &fresh.compiled) {
                assert_eq!(
                    unnumbered(&c.module.wgsl),
                    unnumbered(&f.module.wgsl),
                    "{name}"
                );
            }
        }
        // Carried twice: from the first text to a third with the same tokens.
        let third = format!("{new_text}\n// and another comment\n");
        let front = driver::analyze(&third, dir);
        let again = back_end
            .carry(&third, front)
            .unwrap_or_else(|_| panic!("{name}"));
        assert_eq!(
            again.diagnostics,
            driver::check_all(&third, dir).diagnostics,
            "{name}"
        );
    }
    eprintln!(
        "{carried_count} scenes carried over, {with_back_end_diagnostics} with back-end diagnostics"
    );
    assert!(carried_count >= 20 && with_back_end_diagnostics >= 5);
}

/// The parse of a document after an edit, reusing the unchanged items of the last,
/// equals a fresh parse: same tree, same diagnostics.
#[test]
fn reused_items_parse_as_fresh_ones() {
    use sdfc::syntax::{parse, parse_reusing, ItemCache};
    let files = common::scene_files();
    let mut reused = 0;
    for path in &files {
        let Ok(text) = std::fs::read_to_string(path) else {
            continue;
        };
        let name = path.display();
        let mut cache = ItemCache::default();
        let check = |cache: &mut ItemCache, text: &str| {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            let fresh = parse(text, &mut a);
            let kept = parse_reusing(text, &mut b, Some(cache));
            assert_eq!(kept.file, fresh.file, "{name}");
            assert_eq!(kept.comments, fresh.comments, "{name}");
            assert_eq!(b, a, "{name}");
        };
        check(&mut cache, &text);
        // Edits: a new item first (every later item moves); trivia everywhere; a token
        // changed in the middle; an error in the middle, then that error fixed.
        let mid = text.len() / 2;
        let mid = (mid..text.len())
            .find(|&k| text.is_char_boundary(k))
            .unwrap_or(text.len());
        let edits = [
            format!("let added_first = 2;\n{text}"),
            with_trivia(&text),
            format!("{}\n{}", &text[..mid], &text[mid..]),
            format!("{} (( {}", &text[..mid], &text[mid..]),
            text.clone(),
        ];
        let clean = {
            let mut d = Vec::new();
            let items = parse(&text, &mut d).file.items.len();
            d.is_empty().then_some(items)
        };
        for (k, edit) in edits.iter().enumerate() {
            check(&mut cache, edit);
            reused += cache.reused();
            // A new first item moves every other; each is reused, none parsed again.
            if let (0, Some(items)) = (k, clean) {
                assert_eq!(cache.reused(), items, "{name}");
            }
        }
    }
    assert!(reused > 200, "{reused} items reused");
}

/// Unused `let`s that are surface fields or load a texture are not inert: the back end
/// may read their textures (a displacement decodes every one), so an edit adding one
/// runs it again; an unused number is carried.
#[test]
fn only_unused_constants_are_inert() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let base = "let ball = sphere(1);\nrender ball;\n";
    let front = driver::analyze(base, Some(&dir));
    let full = driver::check_all(base, Some(&dir));
    let back_end = BackEnd::of(base, &front.diagnostics, &full);
    for (added, inert) in [
        ("let k = 2;", true),
        ("let v = [1, 2, 3];", true),
        ("let n = normal;", false),
        (
            "let c = image(\"textures/bricks.png\").sample([0.5, 0.5]);",
            false,
        ),
        ("let s = sphere(2);", false),
    ] {
        let text = format!("{base}{added}\n");
        let front = driver::analyze(&text, Some(&dir));
        assert!(!front.has_errors(), "{added}: {:?}", front.diagnostics);
        assert_eq!(back_end.carry(&text, front).is_ok(), inert, "{added}");
    }
}
