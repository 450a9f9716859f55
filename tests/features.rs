//! The library builds without the command line, the viewer and the language server
//! (`cargo build --no-default-features --lib`): each optional dependency of
//! Cargo.toml is used only in the rooms its feature gates. Checked statically here, on
//! every `cargo test`, so the suite need not build the crate twice; the build itself
//! is `cargo check --no-default-features --lib` (CONTRIBUTING.md).

use std::path::Path;

/// The rooms of `src/` each feature gates, and the features' optional dependencies as
/// Rust names (Cargo.toml's `dep:` entries, with `-` as `_`).
fn gated() -> Vec<(&'static str, Vec<&'static str>, Vec<String>)> {
    let manifest = std::fs::read_to_string("Cargo.toml").unwrap();
    let deps = |feature: &str| -> Vec<String> {
        let line = manifest
            .lines()
            .find(|l| l.starts_with(&format!("{feature} = [")))
            .unwrap_or_else(|| panic!("Cargo.toml has no feature `{feature}`"));
        line.split('"')
            .filter_map(|w| w.strip_prefix("dep:"))
            .map(|d| d.replace('-', "_"))
            .collect()
    };
    vec![
        ("cli", vec!["src/cli", "src/main.rs"], deps("cli")),
        ("viewer", vec!["src/viewer"], deps("viewer")),
        ("lsp", vec!["src/lsp"], deps("lsp")),
    ]
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Whether `text` names crate `dep` as a path (`dep::…`, `use dep`, `dep!`).
fn names(text: &str, dep: &str) -> bool {
    text.match_indices(dep).any(|(i, _)| {
        let before = text[..i].chars().next_back();
        let after = &text[i + dep.len()..];
        let boundary = before.is_none_or(|c| !(c.is_alphanumeric() || c == '_' || c == ':'));
        boundary && (after.starts_with("::") || after.starts_with(';') || after.starts_with(" as"))
    })
}

#[test]
fn optional_dependencies_stay_in_their_rooms() {
    let mut files = Vec::new();
    rust_files(Path::new("src"), &mut files);
    let mut wrong = Vec::new();
    let all = gated();
    for (feature, rooms, deps) in &all {
        assert!(!deps.is_empty(), "feature `{feature}` lists no dependency");
        for f in &files {
            let path = f.to_string_lossy().replace('\\', "/");
            // A room gated by a feature that implies this one may use it too (`cli`
            // implies `viewer` and `lsp`).
            let inside = rooms.iter().any(|r| path.starts_with(r))
                || (*feature != "cli"
                    && ["src/cli", "src/main.rs"]
                        .iter()
                        .any(|r| path.starts_with(r)));
            if inside {
                continue;
            }
            let text = std::fs::read_to_string(f).unwrap();
            for dep in deps {
                if names(&text, dep) {
                    wrong.push(format!("{path} uses `{dep}` (feature `{feature}`)"));
                }
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "optional dependencies outside their rooms:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_gated_modules_are_behind_their_features() {
    let lib = std::fs::read_to_string("src/lib.rs").unwrap();
    for (feature, module) in [("lsp", "lsp"), ("viewer", "viewer")] {
        let gate = format!("#[cfg(feature = \"{feature}\")]\npub mod {module};");
        assert!(
            lib.contains(&gate),
            "src/lib.rs does not gate `{module}` on `{feature}`"
        );
    }
    let manifest = std::fs::read_to_string("Cargo.toml").unwrap();
    assert!(
        manifest.contains("default = [\"cli\"]"),
        "the CLI is not a default feature"
    );
    assert!(
        manifest.contains("required-features = [\"cli\"]"),
        "the binary does not require the `cli` feature"
    );
}

#[test]
fn the_check_sees_a_use() {
    // The matcher itself: a path, a `use` and an alias count; a longer name does not.
    assert!(names("use winit::event;", "winit"));
    assert!(names("let x = clap::Parser;", "clap"));
    assert!(names("extern crate libc;\nuse libc;", "libc"));
    assert!(!names("fn my_winit_thing() {}", "winit"));
    assert!(!names("// urls and url_like", "url"));
}
