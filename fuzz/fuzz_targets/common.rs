//! Shared by the targets: the text of the input, and the span check.
#![allow(dead_code)]

use std::path::PathBuf;

/// The input as text, the way `sdfc check` reads a file: invalid UTF-8 is replaced.
pub fn text(data: &[u8]) -> String {
    sdfc::syntax::decode(data).0
}

/// The folder texture paths are relative to: tests/ui (it has `textures/bricks.png`).
pub fn base_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/ui")
}

/// Every span of every diagnostic lies inside the text, on character boundaries.
pub fn assert_spans(text: &str, diags: &[sdfc::Diagnostic]) {
    for d in diags {
        let spans = d
            .primary
            .iter()
            .chain(&d.secondary)
            .map(|l| l.span)
            .chain(d.fixes.iter().flat_map(|f| f.edits.iter().map(|e| e.span)));
        for s in spans {
            assert!(
                s.start <= s.end
                    && s.end <= text.len()
                    && text.is_char_boundary(s.start)
                    && text.is_char_boundary(s.end),
                "{}: span {}..{} outside the text of {} bytes",
                d.code,
                s.start,
                s.end,
                text.len()
            );
        }
    }
    // Rendering the diagnostics must not panic either.
    let _ = sdfc::diagnostic::render("fuzz.sdf", text, diags, false);
}
