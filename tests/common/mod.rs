//! Running the `sdfc` binary from integration tests.
#![allow(dead_code)]

use std::io::Write;
use std::process::{Command, Stdio};

/// Runs `sdfc` in the package root; (exit code, stdout, stderr).
pub fn sdfc(args: &[&str]) -> (i32, String, String) {
    sdfc_with_input(args, b"")
}

/// Runs `sdfc` in the package root with `input` on standard input.
pub fn sdfc_with_input(args: &[&str], input: &[u8]) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The child may exit before reading all of its input (a usage error): not a failure.
    let _ = child.stdin.take().unwrap().write_all(input);
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A small deterministic generator (xorshift) for test points.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// The Khronos glTF-Validator's report on one file.
pub struct GltfReport {
    pub errors: u64,
    pub warnings: u64,
    pub infos: u64,
    pub hints: u64,
    /// Each issue: `code`, `message`, `severity` (0 error … 3 hint), `pointer`/`offset`.
    pub messages: Vec<serde_json::Value>,
    /// The whole report, as the validator printed it.
    pub json: String,
}

/// Runs the Khronos glTF-Validator (`tools/gltf-validator`, installed there by
/// `npm ci`) on the glTF or GLB file at `path`. When Node or the validator is missing
/// this fails the test if `SDFC_REQUIRE_TOOLS=1` (as in CI) and otherwise says so on
/// stderr and returns `None`, for the caller to skip its check.
pub fn gltf_validate(path: &std::path::Path) -> Option<GltfReport> {
    let tool = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/gltf-validator");
    let installed = tool
        .join("node_modules/gltf-validator/package.json")
        .is_file();
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !installed || !node {
        let missing = if node {
            "the glTF-Validator (run `npm ci` in tools/gltf-validator)"
        } else {
            "node"
        };
        if std::env::var("SDFC_REQUIRE_TOOLS").as_deref() == Ok("1") {
            panic!("SDFC_REQUIRE_TOOLS=1 but {missing} is not installed");
        }
        eprintln!(
            "SKIPPED: glTF validation of {}: {missing} is not installed",
            path.display()
        );
        return None;
    }
    let out = Command::new("node")
        .arg(tool.join("validate.mjs"))
        .arg(path)
        .output()
        .unwrap();
    let json = String::from_utf8_lossy(&out.stdout).into_owned();
    // Exit status 0: clean, 1: errors or warnings (both print a report), 2: no report.
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "the glTF-Validator failed on {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    let issues = &report["issues"];
    let count = |key: &str| issues[key].as_u64().unwrap();
    Some(GltfReport {
        errors: count("numErrors"),
        warnings: count("numWarnings"),
        infos: count("numInfos"),
        hints: count("numHints"),
        messages: issues["messages"].as_array().cloned().unwrap_or_default(),
        json,
    })
}
