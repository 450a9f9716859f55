//! Every example scene checks with zero diagnostics.

use sdfc::diagnostic::render;
use sdfc::driver::analyze;
use std::path::Path;

#[test]
fn every_example_checks_clean() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "sdf") {
            continue;
        }
        count += 1;
        let source = std::fs::read_to_string(&path).unwrap();
        let analysis = analyze(&source, Some(&dir));
        assert!(
            analysis.diagnostics.is_empty(),
            "{} has diagnostics:\n{}",
            path.display(),
            render(
                &path.display().to_string(),
                &source,
                &analysis.diagnostics,
                false
            )
        );
        assert!(
            analysis.program.render.is_some(),
            "{} has no render item",
            path.display()
        );
    }
    assert!(count >= 3, "expected at least 3 examples, found {count}");
}
