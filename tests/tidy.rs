//! Tidy: the rooms of `src/` use only their own layer and the layers below, as the
//! table of ARCHITECTURE.md says (read from it: one truth), apart from the arrows back
//! up that ARCHITECTURE.md lists as still to remove; inside each room the modules
//! import each other without a cycle; and no function runs over 150 lines but the flat
//! tables ARCHITECTURE.md lists.

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

// ---- No circles inside a room ------------------------------------------------------
//
// The rule (ARCHITECTURE.md, "Rules that go with the table"): inside a room (a folder of
// `src/`), the modules' imports form no cycle. A module is a file (`a/mod.rs` is `a`);
// module M imports module T when M's code names a path `super::…` or `crate::…` that
// leads into T: to an item of T, or to T itself. Paths through an item that a module
// re-exports (`pub use x::Y`, or the parent's private `use`, which children see) lead
// on to where the item is defined. `self::…` paths, and any path from a module into its
// own children (a parent using or re-exporting what it declares), are not edges: a
// parent is the hall of its children. A child using its parent's own items is one.

/// A module, as its names below `src/`: `bake/export/gltf.rs` is `["bake", "export",
/// "gltf"]`, `bake/mod.rs` is `["bake"]`.
type Module = Vec<String>;

/// Where an import is written: file (below `src/`) and line.
type Place = (String, usize);

/// The module a file below `src/` is.
fn module_of(rel: &str) -> Module {
    let mut m: Module = rel
        .trim_end_matches(".rs")
        .split('/')
        .map(String::from)
        .collect();
    if m.last().is_some_and(|l| l == "mod") {
        m.pop();
    }
    m
}

/// A file's code without its comments, and without everything from its first
/// `#[cfg(test)]` on (unit tests come last and may reach anywhere). Lines keep their
/// numbers.
fn code(text: &str) -> String {
    let mut out = String::new();
    let mut block = 0usize;
    for line in text.lines() {
        if block == 0 && line.trim_start().starts_with("#[cfg(test)]") {
            break;
        }
        let mut rest = line;
        while !rest.is_empty() {
            if block > 0 {
                match (rest.find("/*"), rest.find("*/")) {
                    (Some(o), Some(c)) if o < c => (block, rest) = (block + 1, &rest[o + 2..]),
                    (_, Some(c)) => (block, rest) = (block - 1, &rest[c + 2..]),
                    _ => rest = "",
                }
            } else {
                match (rest.find("//"), rest.find("/*")) {
                    (Some(l), b) if b.is_none_or(|b| l < b) => {
                        out.push_str(&rest[..l]);
                        rest = "";
                    }
                    (_, Some(b)) => {
                        out.push_str(&rest[..b]);
                        (block, rest) = (1, &rest[b + 2..]);
                    }
                    _ => {
                        out.push_str(rest);
                        rest = "";
                    }
                }
            }
        }
        out.push('\n');
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths of the use tree (or plain path) at the start of `s`, each with the name it
/// binds: `a::{b, c::d as e}` is `[a, b]` (b) and `[a, c, d]` (e); a path in an
/// expression ends where the path does (`a::f(x)` is `[a, f]`). Also the length read.
fn use_tree(s: &str) -> (Vec<(Vec<String>, String)>, usize) {
    fn skip_ws(s: &str, i: usize) -> usize {
        i + (s[i..].len() - s[i..].trim_start().len())
    }
    fn tree(
        s: &str,
        mut i: usize,
        prefix: &[String],
        out: &mut Vec<(Vec<String>, String)>,
    ) -> usize {
        let mut path = prefix.to_vec();
        loop {
            i = skip_ws(s, i);
            if s[i..].starts_with('{') {
                i += 1;
                loop {
                    i = skip_ws(s, i);
                    if s[i..].starts_with(',') {
                        i += 1;
                        continue;
                    }
                    if s[i..].is_empty() || s[i..].starts_with('}') {
                        return (i + 1).min(s.len());
                    }
                    let before = i;
                    i = tree(s, i, &path, out);
                    if i == before {
                        // Not a use tree after all: skip a character.
                        i += s[i..].chars().next().map_or(1, char::len_utf8);
                    }
                }
            }
            let len = if s[i..].starts_with('*') {
                1
            } else {
                s[i..].find(|c: char| !is_ident(c)).unwrap_or(s.len() - i)
            };
            if len == 0 {
                return i;
            }
            path.push(s[i..i + len].to_string());
            i += len;
            let j = skip_ws(s, i);
            if s[j..].starts_with("::") {
                i = j + 2;
                continue;
            }
            let mut name = path.last().cloned().unwrap_or_default();
            if name == "self" && path.len() > 1 {
                name = path[path.len() - 2].clone();
            }
            if let Some(alias) = s[j..].strip_prefix("as ") {
                let a = alias.trim_start();
                let len = a.find(|c: char| !is_ident(c)).unwrap_or(a.len());
                name = a[..len].to_string();
                i = s.len() - a.len() + len;
            }
            out.push((path, name));
            return i;
        }
    }
    let mut out = Vec::new();
    let n = tree(s, 0, &[], &mut out);
    (out, n)
}

/// Each module's names brought in by its `use` items (at the start of a line, so at
/// the module's top level): name → path.
fn imports(code: &str) -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    for line_start in std::iter::once(0).chain(code.match_indices('\n').map(|(i, _)| i + 1)) {
        let line = &code[line_start..];
        let rest = ["use ", "pub use ", "pub(crate) use ", "pub(super) use "]
            .iter()
            .find_map(|p| line.strip_prefix(p));
        if let Some(rest) = rest {
            for (path, name) in use_tree(rest).0 {
                if name != "*" {
                    out.insert(name, path);
                }
            }
        }
    }
    out
}

struct Modules {
    /// Each module's code.
    code: BTreeMap<Module, String>,
    /// Each module's top-level imports.
    imports: BTreeMap<Module, BTreeMap<String, Vec<String>>>,
}

impl Modules {
    /// `files`: (path below `src/`, text).
    fn new(files: &[(String, String)]) -> Modules {
        let code: BTreeMap<Module, String> = files
            .iter()
            .map(|(rel, text)| (module_of(rel), code(text)))
            .collect();
        let imports = code.iter().map(|(m, c)| (m.clone(), imports(c))).collect();
        Modules { code, imports }
    }

    /// The module a path written in module `from` leads into: the last module on the
    /// way, following re-exports; None when it leaves the crate's modules.
    fn resolve(&self, from: &[String], path: &[String], depth: usize) -> Option<Module> {
        let mut cur: Module = from.to_vec();
        for (k, seg) in path.iter().enumerate() {
            match seg.as_str() {
                "crate" => cur.clear(),
                "super" => {
                    cur.pop()?;
                }
                "self" => {}
                name => {
                    let mut child = cur.clone();
                    child.push(name.to_string());
                    if self.code.contains_key(&child) {
                        cur = child;
                        continue;
                    }
                    let through = self.imports.get(&cur).and_then(|i| i.get(name));
                    return match through {
                        Some(p) if depth < 8 => {
                            let onward: Vec<String> =
                                p.iter().chain(&path[k + 1..]).cloned().collect();
                            self.resolve(&cur, &onward, depth + 1)
                        }
                        // A path that starts with another crate's name (`std::…`).
                        None if k == 0 => None,
                        _ => Some(cur),
                    };
                }
            }
        }
        Some(cur)
    }

    /// The import graph inside the rooms: module → module it imports → where (the
    /// first place).
    fn graph(&self, files: &[(String, String)]) -> BTreeMap<Module, BTreeMap<Module, Place>> {
        let mut graph: BTreeMap<Module, BTreeMap<Module, Place>> = BTreeMap::new();
        for (rel, _) in files {
            let m = module_of(rel);
            let code = &self.code[&m];
            let mut i = 0;
            while i < code.len() {
                let rest = &code[i..];
                let starts = (rest.starts_with("super::") || rest.starts_with("crate::"))
                    && !code[..i].ends_with(is_ident);
                if !starts {
                    i += rest.chars().next().map_or(1, char::len_utf8);
                    continue;
                }
                let (paths, len) = use_tree(rest);
                let line = code[..i].matches('\n').count() + 1;
                for (path, _) in paths {
                    let Some(to) = self.resolve(&m, &path, 0) else {
                        continue;
                    };
                    // Same room; not the module itself nor one of its own children.
                    if to.first() == m.first() && !to.starts_with(&m) {
                        graph
                            .entry(m.clone())
                            .or_default()
                            .entry(to)
                            .or_insert_with(|| (rel.clone(), line));
                    }
                }
                i += len.max(1);
            }
        }
        graph
    }
}

/// Every cycle a depth-first walk of `graph` closes, each as its modules in order
/// with the place of each import (the last back to the first).
fn cycles(graph: &BTreeMap<Module, BTreeMap<Module, Place>>) -> Vec<Vec<(Module, Place)>> {
    fn walk(
        m: &Module,
        graph: &BTreeMap<Module, BTreeMap<Module, Place>>,
        stack: &mut Vec<Module>,
        done: &mut BTreeSet<Module>,
        out: &mut Vec<Vec<(Module, Place)>>,
    ) {
        stack.push(m.clone());
        for to in graph.get(m).into_iter().flat_map(|t| t.keys()) {
            if let Some(k) = stack.iter().position(|s| s == to) {
                let ring = &stack[k..];
                let places = ring
                    .iter()
                    .enumerate()
                    .map(|(i, a)| (a.clone(), graph[a][&ring[(i + 1) % ring.len()]].clone()))
                    .collect();
                out.push(places);
            } else if !done.contains(to) {
                walk(to, graph, stack, done, out);
            }
        }
        stack.pop();
        done.insert(m.clone());
    }
    let (mut out, mut done) = (Vec::new(), BTreeSet::new());
    for m in graph.keys() {
        if !done.contains(m) {
            walk(m, graph, &mut Vec::new(), &mut done, &mut out);
        }
    }
    out
}

fn show_cycle(cycle: &[(Module, Place)]) -> String {
    let names: Vec<String> = cycle
        .iter()
        .map(|(m, _)| m.join("::"))
        .chain(cycle.first().map(|(m, _)| m.join("::")))
        .collect();
    let places: Vec<String> = cycle
        .iter()
        .map(|(_, (f, l))| format!("src/{f}:{l}"))
        .collect();
    format!("{} ({})", names.join(" → "), places.join(", "))
}

/// Every file in a folder of `src/`: (path below `src/`, text).
fn room_files() -> Vec<(String, String)> {
    let src = root().join("src");
    let mut paths = Vec::new();
    rust_files(&src, &mut paths);
    paths.sort();
    paths
        .iter()
        .filter_map(|p| {
            let rel = p
                .strip_prefix(&src)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            rel.contains('/')
                .then(|| (rel, std::fs::read_to_string(p).unwrap()))
        })
        .collect()
}

#[test]
fn no_room_imports_in_a_circle() {
    let files = room_files();
    assert!(files.len() > 100, "the rooms lost their files");
    let graph = Modules::new(&files).graph(&files);
    assert!(
        graph.values().map(BTreeMap::len).sum::<usize>() > 100,
        "the import graph lost its edges: {graph:?}"
    );
    let found: Vec<String> = cycles(&graph).iter().map(|c| show_cycle(c)).collect();
    assert!(
        found.is_empty(),
        "modules of a room that import each other in a circle (ARCHITECTURE.md: move the \
         shared piece into a module of its own, or to the module that owns it):\n{}",
        found.join("\n")
    );
}

#[test]
fn the_circle_checker_follows_re_exports_and_spares_parents() {
    let files: Vec<(String, String)> = [
        // The parent re-exports and uses its children: no edge.
        ("r/mod.rs", "mod a;\nmod b;\nmod c;\npub use a::A;\nfn f() { a::g(); c::h(); }\n"),
        // a → b (a grouped, multi-line use tree).
        ("r/a.rs", "use super::{\n    b::B,\n    c,\n};\npub struct A;\n"),
        // b → a, through the parent's re-export of `A`.
        ("r/b.rs", "use crate::r::A;\npub struct B;\n"),
        // c → the parent's own item: an edge to r, but r's edges to its children are none.
        (
            "r/c.rs",
            "// super::b in a comment\nfn h() { super::f(); }\n#[cfg(test)]\nmod tests { use super::super::a; }\n",
        ),
    ]
    .map(|(p, t)| (p.to_string(), t.to_string()))
    .into();
    let graph = Modules::new(&files).graph(&files);
    let m = |s: &str| module_of(s);
    assert_eq!(
        graph[&m("r/a.rs")].keys().collect::<Vec<_>>(),
        [&m("r/b.rs"), &m("r/c.rs")]
    );
    assert_eq!(
        graph[&m("r/b.rs")].keys().collect::<Vec<_>>(),
        [&m("r/a.rs")]
    );
    assert_eq!(
        graph[&m("r/c.rs")].keys().collect::<Vec<_>>(),
        [&m("r/mod.rs")]
    );
    assert!(!graph.contains_key(&m("r/mod.rs")));
    let found: Vec<String> = cycles(&graph).iter().map(|c| show_cycle(c)).collect();
    assert_eq!(found, ["r::a → r::b → r::a (src/r/a.rs:1, src/r/b.rs:1)"]);
}

// ---- Short functions ---------------------------------------------------------------

/// The most lines a function of `src/` may span (from its `fn` line to its closing
/// brace) unless ARCHITECTURE.md lists it under "Flat tables".
const MAX_FN_LINES: usize = 150;

/// A file's lines with comments, string and character literals blanked (their
/// characters become spaces; lines keep their numbers), so that braces and `fn`s in them
/// do not count.
fn blank_literals(text: &str) -> Vec<String> {
    #[derive(PartialEq)]
    enum In {
        Code,
        Block(usize),
        Str,
        Raw(usize),
    }
    let mut state = In::Code;
    let mut lines = Vec::new();
    for line in text.lines() {
        let c: Vec<char> = line.chars().collect();
        let mut out = String::new();
        let mut i = 0;
        while i < c.len() {
            let next = c.get(i + 1).copied();
            match state {
                In::Block(depth) => {
                    if c[i] == '*' && next == Some('/') {
                        state = if depth == 1 {
                            In::Code
                        } else {
                            In::Block(depth - 1)
                        };
                        i += 1;
                    } else if c[i] == '/' && next == Some('*') {
                        state = In::Block(depth + 1);
                        i += 1;
                    }
                }
                In::Str => {
                    if c[i] == '\\' {
                        i += 1;
                    } else if c[i] == '"' {
                        state = In::Code;
                    }
                }
                In::Raw(hashes) => {
                    if c[i] == '"' && c[i + 1..].iter().take_while(|&&h| h == '#').count() >= hashes
                    {
                        state = In::Code;
                        i += hashes;
                    }
                }
                In::Code => {
                    let word_before = i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_');
                    if c[i] == '/' && next == Some('/') {
                        break;
                    } else if c[i] == '/' && next == Some('*') {
                        state = In::Block(1);
                        i += 1;
                    } else if c[i] == '"' {
                        state = In::Str;
                    } else if (c[i] == 'r' || (c[i] == 'b' && next == Some('r'))) && !word_before {
                        // r"…", r#"…"#, br"…"
                        let from = if c[i] == 'b' { i + 2 } else { i + 1 };
                        let hashes = c[from.min(c.len())..]
                            .iter()
                            .take_while(|&&h| h == '#')
                            .count();
                        if c.get(from + hashes) == Some(&'"') {
                            state = In::Raw(hashes);
                            i = from + hashes;
                        } else {
                            out.push(c[i]);
                        }
                    } else if c[i] == '\'' {
                        // A character literal ('x', '\n', '\u{7f}'), not a lifetime.
                        let len = if next == Some('\\') {
                            let escaped = c.get(i + 3..).unwrap_or_default();
                            escaped.iter().position(|&q| q == '\'').map(|p| p + 4)
                        } else {
                            (c.get(i + 2) == Some(&'\'')).then_some(3)
                        };
                        match len {
                            Some(len) => i += len - 1,
                            None => out.push(c[i]),
                        }
                    } else {
                        out.push(c[i]);
                    }
                }
            }
            // Keep columns: one character out for each read (blanks for literals).
            while out.chars().count() <= i {
                out.push(' ');
            }
            i += 1;
        }
        lines.push(out);
    }
    lines
}

/// Every function with a body: (name, first line, lines spanned), lines numbered from 1.
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let lines = blank_literals(text);
    let mut out = Vec::new();
    for (n, line) in lines.iter().enumerate() {
        let mut from = 0;
        while let Some(k) = line[from..].find("fn ") {
            let at = from + k;
            from = at + 3;
            if line[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let rest = line[at + 3..].trim_start();
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if name.is_empty() {
                continue;
            }
            if let Some(end) = body_end(&lines, n, at) {
                out.push((name, n + 1, end - n + 1));
            }
        }
    }
    out
}

/// The line of the brace that closes the body of the `fn` at `lines[line][col..]`;
/// None for a declaration without a body.
fn body_end(lines: &[String], line: usize, col: usize) -> Option<usize> {
    let (mut depth, mut body) = (0i64, false);
    for (n, text) in lines.iter().enumerate().skip(line) {
        let text = if n == line { &text[col..] } else { &text[..] };
        for c in text.chars() {
            match c {
                '(' | '[' if !body => depth += 1,
                ')' | ']' if !body => depth -= 1,
                ';' if !body && depth == 0 => return None,
                '{' if !body && depth == 0 => {
                    body = true;
                    depth = 1;
                }
                '{' if body => depth += 1,
                '}' if body => {
                    depth -= 1;
                    if depth == 0 {
                        return Some(n);
                    }
                }
                _ => {}
            }
        }
    }
    None
}

/// ARCHITECTURE.md's "Flat tables": lines "- `PATH::NAME`: why" under that heading,
/// PATH below `src/`: (PATH, NAME) → why.
fn flat_tables(doc: &str) -> BTreeMap<(String, String), String> {
    let section = format!("\n{doc}");
    let section = section
        .split("\n## ")
        .find(|s| s.starts_with("Flat tables"))
        .expect("ARCHITECTURE.md has a \"## Flat tables\" section");
    section
        .lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("- `")?;
            let (item, why) = rest.split_once("`:")?;
            let (path, name) = item.rsplit_once("::")?;
            Some(((path.to_string(), name.to_string()), why.trim().to_string()))
        })
        .collect()
}

#[test]
fn no_function_runs_long() {
    let doc = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let tables = flat_tables(&doc);
    for ((path, name), why) in &tables {
        assert!(
            !why.is_empty(),
            "Flat tables: `{path}::{name}` needs a reason"
        );
    }
    let src = root().join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut long = Vec::new();
    let mut seen = BTreeSet::new();
    let mut count = 0;
    for path in &files {
        let rel = path
            .strip_prefix(&src)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(path).unwrap();
        for (name, line, len) in functions(&text) {
            count += 1;
            if len <= MAX_FN_LINES {
                continue;
            }
            let key = (rel.clone(), name.clone());
            if tables.contains_key(&key) {
                seen.insert(key);
            } else {
                long.push(format!("src/{rel}:{line}: `{name}` is {len} lines"));
            }
        }
    }
    assert!(
        count > 1000,
        "the function count fell to {count}: the scan broke"
    );
    assert!(
        long.is_empty(),
        "functions over {MAX_FN_LINES} lines (split them, or list a flat table under \
         ARCHITECTURE.md's \"Flat tables\"):\n{}",
        long.join("\n")
    );
    let gone: Vec<_> = tables.keys().filter(|k| !seen.contains(*k)).collect();
    assert!(
        gone.is_empty(),
        "these flat tables are gone or no longer long: remove them from ARCHITECTURE.md: {gone:?}"
    );
}

#[test]
fn the_length_checker_skips_literals_and_declarations() {
    let text = r##"trait T {
    fn declared(&self) -> [u8; 4];
}
fn outer(x: [u8; 2]) -> impl Fn(f64) -> f64 {
    let s = "} fn fake() {";
    let r = r#"}}"#;
    let c = '}';
    let l: &'static str = "\"}";
    /* } fn in_comment() { */
    // }
    fn inner() {}
    move |y| y
}
"##;
    let found = functions(text);
    assert_eq!(
        found,
        [("outer".to_string(), 4, 10), ("inner".to_string(), 11, 1)]
    );
    let doc = "## Flat tables\n\nText.\n\n- `ir/eval.rs::prim`: one arm a primitive\n\n## Next\n- `a.rs::b`: not here\n";
    let tables = flat_tables(doc);
    assert_eq!(tables.len(), 1);
    assert_eq!(
        tables[&("ir/eval.rs".to_string(), "prim".to_string())],
        "one arm a primitive"
    );
}

// ---- Features: the library builds without the CLI, the viewer and the language server.
// The library builds without the command line, the viewer and the language server
// (`cargo build --no-default-features --lib`): each optional dependency of
// Cargo.toml is used only in the rooms its feature gates. Checked statically here, on
// every `cargo test`, so the suite need not build the crate twice; the build itself
// is `cargo check --no-default-features --lib` (CONTRIBUTING.md).
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
        ("serve", vec!["src/web/serve"], deps("serve")),
    ]
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
            // implies `viewer`, `lsp` and `serve`).
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
                // A dependency two features share (`notify`: the viewer's and the
                // server's watching) may be used in the rooms of either.
                let shared = all.iter().any(|(_, rooms, deps)| {
                    deps.contains(dep) && rooms.iter().any(|r| path.starts_with(r))
                });
                if !shared && names(&text, dep) {
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
    let web = std::fs::read_to_string("src/web/mod.rs").unwrap();
    assert!(
        web.contains("#[cfg(feature = \"serve\")]\npub mod serve;"),
        "src/web/mod.rs does not gate `serve` on `serve`"
    );
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
