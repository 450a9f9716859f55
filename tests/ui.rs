//! UI tests: every `tests/ui/*.sdf` is checked and its rendered diagnostics are
//! snapshotted together with the source. Each case names the codes it is about.

use sdfc::codes;
use sdfc::diagnostic::render;

use std::collections::BTreeSet;
use std::path::Path;

fn cases() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .collect();
    files.sort();
    files
}

#[test]
fn ui_snapshots() {
    // Relative, so that paths in messages do not depend on where the repository lives
    // (cargo runs integration tests in the package root).
    let dir = Path::new("tests/ui");
    let mut seen_codes = BTreeSet::new();
    let files = cases();
    assert!(
        files.len() >= 40,
        "expected at least 40 UI cases, found {}",
        files.len()
    );
    for path in &files {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let source = std::fs::read_to_string(path).unwrap();
        let analysis = sdfc::driver::check(&source, Some(dir));
        assert!(
            !analysis.diagnostics.is_empty(),
            "{name}: a UI case must produce at least one diagnostic"
        );
        for d in &analysis.diagnostics {
            seen_codes.insert(d.code);
        }
        // A case lists the codes it expects on its first line: `// expect: E0100 E0101`.
        let expected: BTreeSet<&str> = source
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("// expect:"))
            .map(|l| l.split_whitespace().collect())
            .unwrap_or_default();
        let actual: BTreeSet<&str> = analysis.diagnostics.iter().map(|d| d.code).collect();
        assert_eq!(
            expected, actual,
            "{name}: the codes in its `// expect:` line differ from those reported"
        );
        let rendered = render(
            &format!("{name}.sdf"),
            &source,
            &analysis.diagnostics,
            false,
        );
        let snapshot = format!("{source}\n──── diagnostics ────\n{rendered}");
        insta::with_settings!({ snapshot_path => "ui/snapshots", prepend_module_to_snapshot => false, omit_expression => true }, {
            insta::assert_snapshot!(name, snapshot);
        });
    }
    // E0400 and E0900 come from code generation, after checking; tests/codegen.rs covers
    // them, and tests/hardening3.rs E0118 (a module too large once inlined). E0005 (invalid UTF-8), E0006 (a file over 8 MiB) and N0002 (over 1000
    // diagnostics) cannot be UI files; tests/safety.rs covers them. Every other code, the
    // geometric ones (E0401 on, notes) included, needs a case.
    let missing: Vec<&str> = codes::ALL
        .iter()
        .map(|(c, _)| *c)
        .filter(|c| !["E0400", "E0900", "E0118", "E0005", "E0006", "N0002"].contains(c))
        .filter(|c| !seen_codes.contains(c))
        .collect();
    assert!(
        missing.is_empty(),
        "diagnostic codes with no UI case: {missing:?}"
    );
}
