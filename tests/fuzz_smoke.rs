//! A smoke pass of every fuzz target (`fuzz/fuzz_targets/targets.rs`) over its seed
//! corpus, the examples and the UI cases, plus a few byte-level mutations of each, on
//! stable in every `cargo test`: the targets keep compiling and their properties hold
//! on the seeds. The long runs use cargo-fuzz on nightly (CONTRIBUTING.md).

#[path = "../fuzz/fuzz_targets/targets.rs"]
mod targets;

use std::path::{Path, PathBuf};

use crate::common;

fn corpus() -> Vec<Vec<u8>> {
    let files = common::scene_files();
    let mut out = Vec::new();
    for (i, f) in files.iter().enumerate() {
        let bytes = std::fs::read(f).unwrap();
        // The seed, and one cut and one flipped byte (deterministic).
        let cut = bytes.len() * (i % 7 + 1) / 8;
        let mut flipped = bytes.clone();
        if !flipped.is_empty() {
            let k = (i * 31) % flipped.len();
            flipped[k] ^= 0x20;
        }
        out.push(bytes[..cut].to_vec());
        out.push(flipped);
        out.push(bytes);
    }
    out
}

fn ui() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui")
}

#[test]
fn parse_and_format_targets_hold_on_the_corpus() {
    for input in corpus() {
        targets::parse(&input);
        targets::format(&input);
    }
}

#[test]
fn check_targets_hold_on_the_corpus() {
    for input in corpus() {
        targets::check(&input, &ui());
        targets::check_all(&input, &ui());
    }
}

#[test]
fn lsp_target_holds_on_the_examples() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    for name in ["sphere.sdf", "capsule.sdf"] {
        let mut doc = b"#".to_vec();
        doc.extend(std::fs::read(root.join(name)).unwrap());
        targets::lsp(&doc);
    }
    // Raw framing: a request, a malformed message and an oversized claim.
    let body = r#"{"jsonrpc":"2.0","id":7,"method":"textDocument/hover","params":{"textDocument":{"uri":"file:///x.sdf"},"position":{"line":0,"character":0}}}"#;
    let framed = format!(
        "Content-Length: {}\r\n\r\n{body}Content-Length: 5\r\n\r\n{{nopeContent-Length: 99999999999\r\n\r\n",
        body.len()
    );
    targets::lsp(framed.as_bytes());
}

/// The `seeds_write` target on every scene of the corpus (textures from its own
/// folder) and the cut and flipped copies of the examples: placing seeds takes tens of
/// milliseconds per atlas on the target's coarse grid, so the examples' copies are
/// enough mutations here (the UI scenes mostly have errors, and are skipped).
#[test]
fn seeds_write_target_holds_on_the_corpus() {
    let files = common::scene_files();
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut checked = 0;
    for f in &files {
        let bytes = std::fs::read(f).unwrap();
        checked += targets::seeds_write(&bytes, f.parent().unwrap());
    }
    assert!(checked >= 20, "only {checked} edits checked");
    for (i, input) in corpus().iter().enumerate() {
        // Every third entry is a seed (checked above).
        if i % 3 != 2 {
            let mut doc = b"#".to_vec();
            doc.extend(input);
            targets::seeds_write(&doc, &examples);
        }
    }
}
