//! `sdfc check`.

use super::{access, exit, read_source, CheckArgs, Color, Format, Source};
use sdfc::diagnostic;

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

pub fn run(args: CheckArgs) -> ExitCode {
    let color = match args.color {
        Color::Always => true,
        Color::Never => false,
        Color::Auto => std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
    };
    let mut any_errors = false;
    let (mut errors, mut warnings) = (0usize, 0usize);
    let mut io_failed = false;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut files = Vec::new();
    for path in &args.files {
        if let Err(e) = expand(path, &mut files) {
            eprintln!("error: cannot read {}: {e}", path.display());
            io_failed = true;
        }
    }
    for path in &files {
        let name = path.display().to_string();
        let Source {
            text: source,
            decoding,
        } = match read_source(path) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: cannot read {name}: {e}");
                io_failed = true;
                continue;
            }
        };
        let mut analysis = sdfc::driver::check_all_with(&source, &access(path));
        analysis.add_decoding(decoding);
        diagnostic::cap(&mut analysis.diagnostics);
        any_errors |= analysis.has_errors();
        errors += analysis
            .diagnostics
            .iter()
            .filter(|d| d.severity == sdfc::Severity::Error)
            .count();
        warnings += analysis
            .diagnostics
            .iter()
            .filter(|d| d.severity == sdfc::Severity::Warning)
            .count();
        match args.format {
            Format::Json => {
                for line in diagnostic::to_json_all(&name, &source, &analysis.diagnostics) {
                    let _ = writeln!(out, "{line}");
                }
            }
            Format::Human => {
                let text = diagnostic::render(&name, &source, &analysis.diagnostics, color);
                eprint!("{text}");
            }
        }
    }
    if args.format == Format::Human && !files.is_empty() {
        summary(files.len(), errors, warnings);
    }
    if io_failed {
        ExitCode::from(exit::USAGE)
    } else if any_errors {
        ExitCode::from(exit::SCENE)
    } else {
        ExitCode::SUCCESS
    }
}

fn summary(files: usize, errors: usize, warnings: usize) {
    let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    eprintln!(
        "checked {}: {}, {}",
        plural(files, "file"),
        plural(errors, "error"),
        plural(warnings, "warning")
    );
}

/// A file as it is; a folder as the `.sdf` files below it (sorted, hidden entries and
/// symbolic links to folders skipped). A folder with none is an error.
fn expand(path: &Path, files: &mut Vec<PathBuf>) -> std::io::Result<()> {
    if path == Path::new("-") || !std::fs::metadata(path)?.is_dir() {
        files.push(path.to_path_buf());
        return Ok(());
    }
    let before = files.len();
    let mut pending = vec![path.to_path_buf()];
    while let Some(dir) = pending.pop() {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(&dir)?
            .flatten()
            .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
            .map(|e| e.path())
            .collect();
        entries.sort();
        for entry in entries.into_iter().rev() {
            let meta = std::fs::symlink_metadata(&entry)?;
            if meta.is_dir() {
                pending.push(entry);
            } else if entry.extension().is_some_and(|e| e == "sdf") {
                files.push(entry);
            }
        }
    }
    files[before..].sort();
    if files.len() == before {
        return Err(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "the folder has no .sdf files",
        ));
    }
    Ok(())
}
