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
    child.stdin.take().unwrap().write_all(input).unwrap();
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
