//! Every example scene checks with zero diagnostics.

use sdfc::diagnostic::render;
use sdfc::driver::check as analyze;
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

/// Between them, the examples use every primitive, CSG operation and warp.
#[test]
fn examples_cover_every_shape_builtin() {
    use sdfc::sema::builtins::{Kind, BUILTINS};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut used = std::collections::BTreeSet::new();
    fn walk(v: &sdfc::sema::Value, used: &mut std::collections::BTreeSet<&'static str>) {
        if let sdfc::sema::Value::Shape(n) = v {
            used.insert(n.builtin.name());
            for a in &n.args {
                walk(a, used);
            }
        }
    }
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "sdf") {
            let analysis = analyze(&std::fs::read_to_string(&path).unwrap(), Some(&dir));
            for def in &analysis.program.defs {
                walk(&def.value, &mut used);
            }
            if let Some(r) = &analysis.program.render {
                walk(&r.target, &mut used);
            }
        }
    }
    let missing: Vec<&str> = BUILTINS
        .iter()
        .filter(|b| matches!(b.kind, Kind::Primitive | Kind::Csg | Kind::Warp))
        .map(|b| b.name)
        .filter(|n| !used.contains(n))
        .collect();
    assert!(missing.is_empty(), "no example uses {missing:?}");
}
