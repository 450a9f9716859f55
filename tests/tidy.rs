//! Tidy: the rooms of `src/` use only their own layer and the layers below, as the
//! table of ARCHITECTURE.md says (read from it: one truth), apart from the arrows back
//! up that ARCHITECTURE.md lists as still to remove.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The layer of each room, from ARCHITECTURE.md's table (`| N | `a` `b` | … |`).
fn layers(doc: &str) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    for line in doc.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let (Some(n), Some(rooms)) = (cells.get(1), cells.get(2)) else {
            continue;
        };
        let Ok(n) = n.parse::<usize>() else { continue };
        for room in rooms.split('`').skip(1).step_by(2) {
            out.insert(room.to_string(), n);
        }
    }
    out
}

/// The arrows back up ARCHITECTURE.md still allows: lines "- `a` → `b`: …".
fn allowed(doc: &str) -> BTreeSet<(String, String)> {
    doc.lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("- `")?;
            let (from, rest) = rest.split_once("` → `")?;
            let (to, _) = rest.split_once('`')?;
            Some((from.to_string(), to.to_string()))
        })
        .collect()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every `crate::ROOM` path of a file outside comments and `#[cfg(test)]` modules:
/// (line number, room).
fn crate_paths(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            // Unit tests come last in a file and may reach up.
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        let code = t.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            let before = rest[..i].chars().last();
            rest = &rest[i + "crate::".len()..];
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let room: String = rest
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || *c == '_')
                .collect();
            out.push((n + 1, room));
        }
    }
    out
}

#[test]
fn no_arrow_runs_back_up() {
    let doc = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let layer = layers(&doc);
    assert!(layer.len() >= 20, "the layer table lost rows: {layer:?}");
    let allowed = allowed(&doc);
    let src = root().join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut unknown_rooms = BTreeSet::new();
    let mut found: BTreeSet<(String, String)> = BTreeSet::new();
    let mut new_arrows = Vec::new();
    for path in &files {
        let rel = path.strip_prefix(&src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let room = first.trim_end_matches(".rs").to_string();
        if ["main", "lib", "cli"].contains(&room.as_str()) {
            continue;
        }
        let Some(&mine) = layer.get(&room) else {
            unknown_rooms.insert(room);
            continue;
        };
        let text = std::fs::read_to_string(path).unwrap();
        for (line, target) in crate_paths(&text) {
            let Some(&theirs) = layer.get(&target) else {
                unknown_rooms.insert(target);
                continue;
            };
            if theirs <= mine {
                continue;
            }
            let arrow = (room.clone(), target.clone());
            if allowed.contains(&arrow) {
                found.insert(arrow);
            } else {
                new_arrows.push(format!(
                    "src/{}:{line}: `{room}` (layer {mine}) uses `crate::{target}` (layer {theirs})",
                    rel.display()
                ));
            }
        }
    }
    assert!(
        unknown_rooms.is_empty(),
        "rooms missing from ARCHITECTURE.md's table: {unknown_rooms:?}"
    );
    assert!(
        new_arrows.is_empty(),
        "imports that run back up the layers of ARCHITECTURE.md:\n{}",
        new_arrows.join("\n")
    );
    let gone: Vec<_> = allowed.difference(&found).collect();
    assert!(
        gone.is_empty(),
        "these arrows back up are gone: remove them from ARCHITECTURE.md's list: {gone:?}"
    );
}

#[test]
fn the_checker_sees_an_arrow_and_skips_comments_and_tests() {
    let text = "use crate::span::Span;\n// crate::bake in a comment\nfn f() { crate::gpu::x(); } // crate::lsp\nlet s = \"notcrate::ir\";\n#[cfg(test)]\nmod tests { use crate::lsp; }\n";
    let rooms: Vec<String> = crate_paths(text).into_iter().map(|(_, r)| r).collect();
    assert_eq!(rooms, ["span", "gpu"]);
    let doc = "| 0 | `span` `id` | x |\n| 3 | `gpu` | y |\n- `ir` → `uv`: why\n";
    assert_eq!(layers(doc)["gpu"], 3);
    assert_eq!(layers(doc)["id"], 0);
    assert!(allowed(doc).contains(&("ir".to_string(), "uv".to_string())));
}
