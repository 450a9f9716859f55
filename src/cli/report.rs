//! The benchmarks' `--json` reports, shared by `sdfc bench`'s frame, seed-sweep,
//! scale, latency and bake measurements.

use std::process::ExitCode;

/// Writes a bench's `--json` report atomically.
pub fn write_json(path: &std::path::Path, json: &serde_json::Value) -> Result<(), ExitCode> {
    let text = serde_json::to_string_pretty(json).unwrap_or_default() + "\n";
    if let Err(e) = sdfc::fsutil::write_output(path, text.as_bytes()) {
        eprintln!("error: cannot write {}: {e}", path.display());
        return Err(ExitCode::from(super::exit::USAGE));
    }
    eprintln!("wrote {}", path.display());
    Ok(())
}
