//! Code actions, inlay hints, merge hover and naga errors mapped to scene spans.

use sdfc::codes;
use sdfc::ide::actions::{self, InlayKind};
use sdfc::ide::Document;
use sdfc::Span;

fn whole(doc: &Document) -> Span {
    Span::new(0, doc.text.len())
}

#[test]
fn did_you_mean_fixes_apply_and_clear_the_errors() {
    // A misspelled function, name, parameter, setting and field: each error offers one
    // fix, and applying every fix leaves a file with no errors.
    let text = "let radius = 0.5;
let ball = spher(radis).translate(offst: [0, 1, 0]);
atlas skin on ball { step = 12; seed a = [0, 1.5, 0]; }
material m { color = [skin.uvv, 0]; }
render ball.paint(m);
";
    let doc = Document::new(text, None);
    let acts = actions::code_actions(&doc, whole(&doc));
    let titles: Vec<&str> = acts.iter().map(|a| a.title.as_str()).collect();
    assert_eq!(
        titles,
        [
            "replace with `sphere`",
            "replace with `radius`",
            "replace with `offset`",
            "replace with `steps`",
            "replace with `uv`"
        ],
        "{:#?}",
        doc.analysis.diagnostics
    );
    assert!(acts.iter().all(|a| a.preferred && a.edits.len() == 1));
    // Each fix replaces exactly the misspelled word its diagnostic points at.
    for a in &acts {
        assert_eq!(Some(a.edits[0].span), a.diagnostic.span());
    }
    let edits: Vec<_> = acts.iter().flat_map(|a| a.edits.clone()).collect();
    let fixed = actions::apply(text, &edits);
    let after = Document::new(fixed.clone(), None);
    assert!(
        !after.analysis.has_errors(),
        "{fixed}\n{:#?}",
        after.analysis.diagnostics
    );
    // Asking at one diagnostic's position gives only its fix.
    let at = text.find("radis").unwrap();
    let one = actions::code_actions(&doc, Span::new(at + 2, at + 2));
    assert_eq!(one.len(), 1);
    assert_eq!(one[0].title, "replace with `radius`");
}

#[test]
fn snap_seed_to_surface_rewrites_the_position() {
    // The seed is 0.2 above the unit sphere: N0001 carries a fix that writes the
    // projected position, after which the note is gone and the seed lies on the sphere.
    let text = "let ball = sphere(1);
atlas skin on ball {
    seed top = [0.3, 1.1, 0.2];
}
render ball;
";
    let doc = Document::new(text, None);
    let acts = actions::code_actions(&doc, whole(&doc));
    assert_eq!(acts.len(), 1, "{:#?}", doc.analysis.diagnostics);
    assert_eq!(acts[0].title, "snap seed to surface");
    assert_eq!(acts[0].diagnostic.code, codes::N_SEED_MOVED);
    assert_eq!(
        &text[acts[0].edits[0].span.range()],
        "[0.3, 1.1, 0.2]",
        "the edit replaces the written position"
    );
    let fixed = actions::apply(text, &acts[0].edits);
    let after = Document::new(fixed.clone(), None);
    assert!(
        after.analysis.diagnostics.is_empty(),
        "{fixed}\n{:#?}",
        after.analysis.diagnostics
    );
    let seed = &after.analysis.program.atlases[0].seeds[0].position;
    let r = (seed[0] * seed[0] + seed[1] * seed[1] + seed[2] * seed[2]).sqrt();
    assert!((r - 1.0).abs() < 1e-3, "|p| = {r}");
}

#[test]
fn snap_seed_to_surface_is_offered_anywhere_on_the_seed() {
    let text = "let ball = sphere(1);
atlas skin on ball {
    seed top = [0.3, 1.1, 0.2] tangent [1, 0, 0];
    steps = 12;
}
render ball;
";
    let doc = Document::new(text, None);
    let titles = |needle: &str| -> Vec<String> {
        let at = text.find(needle).unwrap();
        actions::code_actions(&doc, Span::new(at, at))
            .into_iter()
            .map(|a| a.title)
            .collect()
    };
    // On the keyword, the name, the `=`, the tangent and the `;`: the seed's fix.
    for needle in [
        "seed top",
        "top =",
        "= [0.3",
        "tangent",
        "[1, 0, 0]",
        ";\n    steps",
    ] {
        assert_eq!(titles(needle), ["snap seed to surface"], "at {needle:?}");
    }
    // Not on the next statement, nor on the atlas line.
    assert!(titles("steps").is_empty());
    assert!(titles("atlas").is_empty());
}

#[test]
fn inlay_hints_show_folded_values_and_merge_lengths() {
    // Seeds on the plane y = 0 (top of a thin box) one unit apart: d_M = 1 exactly.
    let text = "let half = 4 / 2;
let size = [2 * half, 0.2, 2 * half];
let thin = 0.2;
let plate = box([size.x, thin, size.z]);
atlas tiles on plate {
    seed a = [0, 0.1, 0];
    seed b = [1, 0.1, 0];
    seed c = [1, 0.1, 1.5];
    merge a b c;
}
render plate;
";
    let doc = Document::new(text, None);
    assert!(
        doc.analysis.diagnostics.is_empty(),
        "{:#?}",
        doc.analysis.diagnostics
    );
    let hints = actions::inlay_hints(&doc, whole(&doc));
    let shown: Vec<(String, InlayKind)> = hints
        .iter()
        .map(|h| {
            let line = text[..h.offset].lines().last().unwrap_or("");
            (format!("{line}⟨{}⟩", h.label), h.kind)
        })
        .collect();
    assert_eq!(
        shown,
        [
            ("let half = 4 / 2⟨= 2⟩".to_string(), InlayKind::Value),
            (
                "let size = [2 * half, 0.2, 2 * half]⟨= [4, 0.2, 4]⟩".to_string(),
                InlayKind::Value
            ),
            ("    merge a⟨─ 1.000 ─⟩".to_string(), InlayKind::Merge),
            ("    merge a b⟨─ 1.500 ─⟩".to_string(), InlayKind::Merge),
        ]
    );
    // Only the hints inside the asked range.
    let line = text.find("let size").unwrap();
    let some = actions::inlay_hints(&doc, Span::new(line, line + 40));
    assert_eq!(some.len(), 1);
}

#[test]
fn hover_on_a_merge_statement_gives_each_edge() {
    let text = "let plate = box([8, 0.2, 8]);
atlas tiles on plate {
    seed a = [0, 0.1, 0];
    seed b = [1, 0.1, 0];
    seed c = [1, 0.1, 2];
    merge a b c;
}
render plate;
";
    let doc = Document::new(text, None);
    let at = text.find("merge").unwrap() + 2;
    let h = sdfc::ide::hover(&doc, at).expect("a hover on `merge`");
    assert_eq!(&text[h.span.range()], "merge a b c;");
    assert!(
        h.markdown.contains("`a` – `b`: geodesic length 1.0000"),
        "{}",
        h.markdown
    );
    assert!(
        h.markdown.contains("`b` – `c`: geodesic length 2.0000"),
        "{}",
        h.markdown
    );
    assert!(
        h.markdown.contains("transport turns 0.0°"),
        "{}",
        h.markdown
    );
}
