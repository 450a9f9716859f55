//! The documentation: the book in `docs/` (an mdBook) and the files beside it.
//!
//! - `docs/SUMMARY.md` names every chapter under `docs/`, and every chapter it names
//!   exists;
//! - every relative link and image in README.md, CONTRIBUTING.md, ARCHITECTURE.md and
//!   the book points at a file that exists, every `#anchor` into a Markdown file at one
//!   of its headings (GitHub's and mdBook's slugs), and no chapter links out of the book;
//! - nothing there or in `src/` points outside the repository: the papers are cited by
//!   title, and what the project needs from its notes is in `docs/papers.md`;
//! - the README's scene is one of the examples, verbatim, so it keeps compiling;
//! - `mdbook build` builds the book with no warning, when mdbook is installed (on PATH
//!   or at `$SDFC_MDBOOK`); with `SDFC_REQUIRE_TOOLS=1` (as in CI) a missing mdbook
//!   fails instead of skipping.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn docs() -> PathBuf {
    root().join("docs")
}

/// `path` relative to the repository, for messages.
fn rel(path: &Path) -> String {
    path.strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string()
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// Every file below `dir` whose name ends with `suffix` (all files for ""), sorted.
fn files_below(dir: &Path, suffix: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.to_string_lossy().ends_with(suffix) {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The Markdown files whose links are checked: the three at the root and the book.
fn documents() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = ["README.md", "CONTRIBUTING.md", "ARCHITECTURE.md"]
        .iter()
        .map(|name| root().join(name))
        .collect();
    out.extend(files_below(&docs(), ".md"));
    out
}

fn is_fence(line: &str) -> bool {
    let t = line.trim_start();
    t.starts_with("```") || t.starts_with("~~~")
}

/// The text outside fenced code blocks, line by line.
fn prose_lines(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut in_fence = false;
    for line in text.lines() {
        if is_fence(line) {
            in_fence = !in_fence;
        } else if !in_fence {
            out.push(line);
        }
    }
    out
}

/// `text` without its inline code spans: a run of n backticks up to the next run of
/// exactly n backticks is removed (a run with no partner is kept as it is).
fn strip_code_spans(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let mut n = 0;
        while i + n < chars.len() && chars[i + n] == '`' {
            n += 1;
        }
        // Look for the closing run of exactly n backticks.
        let mut j = i + n;
        let mut close = None;
        while j < chars.len() {
            if chars[j] == '`' {
                let mut m = 0;
                while j + m < chars.len() && chars[j + m] == '`' {
                    m += 1;
                }
                if m == n {
                    close = Some(j + m);
                    break;
                }
                j += m;
            } else {
                j += 1;
            }
        }
        match close {
            Some(end) => i = end,
            None => {
                for _ in 0..n {
                    out.push('`');
                }
                i += n;
            }
        }
    }
    out
}

/// The targets of the inline links and images of a Markdown text, `[text](target)` and
/// `![alt](target)`, outside code blocks and code spans.
fn link_targets(text: &str) -> Vec<String> {
    let prose = strip_code_spans(&prose_lines(text).join("\n"));
    let mut out = Vec::new();
    let mut rest = prose.as_str();
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        let Some(j) = after.find(')') else { break };
        out.push(after[..j].trim().to_string());
        rest = &after[j + 1..];
    }
    out
}

/// A heading's anchor as GitHub and mdBook make it: lowercase; letters, digits, `-`
/// and `_` kept; each whitespace character a `-`; everything else dropped.
fn slug(heading: &str) -> String {
    let mut out = String::new();
    for c in heading.trim().to_lowercase().chars() {
        if c.is_alphanumeric() || c == '-' || c == '_' {
            out.push(c);
        } else if c.is_whitespace() {
            out.push('-');
        }
    }
    out
}

/// The anchors of a Markdown file's ATX headings (`# …` to `###### …`), a repeated one
/// numbered `-1`, `-2`, … as both renderers do.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in prose_lines(text) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if hashes == 0 || hashes > 6 {
            continue;
        }
        let rest = &line[hashes..];
        if !rest.starts_with(' ') {
            continue;
        }
        // A code span keeps its text in the anchor; its backticks go like any punctuation.
        let base = slug(rest.trim().trim_end_matches('#'));
        let mut id = base.clone();
        let mut n = 0;
        while out.contains(&id) {
            n += 1;
            id = format!("{base}-{n}");
        }
        out.insert(id);
    }
    out
}

#[test]
fn summary_names_every_chapter() {
    let summary_path = docs().join("SUMMARY.md");
    let summary = read(&summary_path);
    let named: Vec<PathBuf> = link_targets(&summary)
        .iter()
        .map(|t| docs().join(t))
        .collect();
    assert!(
        named.len() >= 10,
        "docs/SUMMARY.md names only {} chapters",
        named.len()
    );
    for chapter in &named {
        assert!(
            chapter.is_file(),
            "docs/SUMMARY.md names {}, which does not exist",
            rel(chapter)
        );
    }
    let named: BTreeSet<PathBuf> = named.iter().map(|p| p.canonicalize().unwrap()).collect();
    for file in files_below(&docs(), ".md") {
        if file == summary_path {
            continue;
        }
        assert!(
            named.contains(&file.canonicalize().unwrap()),
            "{} is not named in docs/SUMMARY.md, so the book leaves it out",
            rel(&file)
        );
    }
}

#[test]
fn relative_links_resolve() {
    let docs_dir = docs().canonicalize().unwrap();
    let mut failures = Vec::new();
    for doc in documents() {
        let text = read(&doc);
        let in_book = doc.starts_with(docs());
        for target in link_targets(&text) {
            if target.starts_with("http://")
                || target.starts_with("https://")
                || target.starts_with("mailto:")
            {
                continue;
            }
            let (path, fragment) = match target.split_once('#') {
                Some((p, f)) => (p, f),
                None => (target.as_str(), ""),
            };
            let file = if path.is_empty() {
                doc.clone()
            } else {
                doc.parent().unwrap().join(path)
            };
            if !file.exists() {
                failures.push(format!("{}: `{target}`: no such file", rel(&doc)));
                continue;
            }
            if in_book && !file.canonicalize().unwrap().starts_with(&docs_dir) {
                failures.push(format!(
                    "{}: `{target}` leaves the book, so the built book cannot follow it \
                     (name the file in code instead)",
                    rel(&doc)
                ));
            }
            if !fragment.is_empty() && file.extension().is_some_and(|e| e == "md") {
                let known = anchors(&read(&file));
                if !known.contains(fragment) {
                    failures.push(format!(
                        "{}: `{target}`: {} has no heading with the anchor `{fragment}`",
                        rel(&doc),
                        rel(&file)
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "broken links:\n{}",
        failures.join("\n")
    );
}

#[test]
fn nothing_points_outside_the_repository() {
    // Spelled in pieces, so that this file does not match itself if it is ever scanned.
    let patterns = [
        format!("..{}shared", '/'),
        format!("shared{}papers", '/'),
        format!("shared{}notes", '/'),
    ];
    let mut files: Vec<PathBuf> = ["README.md", "CONTRIBUTING.md", "ARCHITECTURE.md"]
        .iter()
        .map(|name| root().join(name))
        .collect();
    files.extend(files_below(&docs(), ".md"));
    files.extend(files_below(&docs(), ".toml"));
    files.extend(files_below(&root().join("src"), ""));
    let mut failures = Vec::new();
    for file in files {
        let bytes = std::fs::read(&file).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        for (n, line) in text.lines().enumerate() {
            if patterns.iter().any(|p| line.contains(p.as_str())) {
                failures.push(format!("{}:{}: {}", rel(&file), n + 1, line.trim()));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "these point outside the repository, where a clone has nothing; cite the paper by \
         title, or point at docs/papers.md:\n{}",
        failures.join("\n")
    );
}

#[test]
fn readme_scene_is_an_example() {
    let readme = read(&root().join("README.md"));
    let mut scene = None;
    let mut lines = readme.lines();
    while let Some(line) = lines.next() {
        if line.trim() == "```sdf" {
            let mut text = String::new();
            for l in lines.by_ref() {
                if is_fence(l) {
                    break;
                }
                text.push_str(l);
                text.push('\n');
            }
            scene = Some(text);
            break;
        }
    }
    let scene = scene.expect("README.md has no ```sdf block: its first screen shows a scene");
    let examples = files_below(&root().join("examples"), ".sdf");
    let same = examples
        .iter()
        .find(|e| read(e).replace("\r\n", "\n") == scene);
    assert!(
        same.is_some(),
        "the README's scene is not any of examples/*.sdf verbatim; copy it from the example \
         (or add it as one), so that the tests check it:\n{scene}"
    );
}

/// The mdbook binary: `$SDFC_MDBOOK`, else `mdbook` on PATH.
fn mdbook() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("SDFC_MDBOOK") {
        let p = PathBuf::from(p);
        assert!(p.is_file(), "SDFC_MDBOOK={} is not a file", p.display());
        return Some(p);
    }
    let name = format!("mdbook{}", std::env::consts::EXE_SUFFIX);
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(&name))
        .find(|p| p.is_file())
}

#[test]
fn book_builds_without_warnings() {
    let Some(mdbook) = mdbook() else {
        if std::env::var("SDFC_REQUIRE_TOOLS").as_deref() == Ok("1") {
            panic!(
                "SDFC_REQUIRE_TOOLS=1 but mdbook is not installed (cargo install mdbook \
                 --version 0.5.4 --locked, or set SDFC_MDBOOK)"
            );
        }
        eprintln!(
            "SKIPPED: the book's build: mdbook is not on PATH or at $SDFC_MDBOOK \
             (cargo install mdbook --version 0.5.4 --locked)"
        );
        return;
    };
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    let out_dir = std::env::temp_dir().join(format!("sdfc-book-{}-{nanos}", std::process::id()));
    let output = Command::new(&mdbook)
        .arg("build")
        .arg(docs())
        .arg("-d")
        .arg(&out_dir)
        .current_dir(root())
        // The default log level shows warnings; a level set for other work must not hide them.
        .env_remove("MDBOOK_LOG")
        .env_remove("RUST_LOG")
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", mdbook.display()));
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let built = out_dir.join("index.html").is_file();
    let gallery = out_dir.join("gallery/capsule.png").is_file();
    let _ = std::fs::remove_dir_all(&out_dir);
    assert!(output.status.success(), "mdbook build failed:\n{log}");
    let complaints: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("WARN") || l.contains("ERROR"))
        .collect();
    assert!(
        complaints.is_empty(),
        "mdbook build warned:\n{}",
        complaints.join("\n")
    );
    assert!(built, "mdbook wrote no index.html:\n{log}");
    assert!(
        gallery,
        "the built book has no gallery/capsule.png: the chapters' pictures would be missing"
    );
}
