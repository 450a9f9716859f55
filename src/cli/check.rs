//! `sdfc check`.

use super::{base_dir, read_source, CheckArgs, Color, Format};
use sdfc::diagnostic;

use std::io::{IsTerminal, Write};
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
    for path in &args.files {
        let name = path.display().to_string();
        let source = match read_source(path) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: cannot read {name}: {e}");
                io_failed = true;
                continue;
            }
        };
        let analysis = sdfc::driver::check_all(&source, Some(&base_dir(path)));
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
                for d in &analysis.diagnostics {
                    let _ = writeln!(out, "{}", diagnostic::to_json(&name, &source, d));
                }
            }
            Format::Human => {
                let text = diagnostic::render(&name, &source, &analysis.diagnostics, color);
                eprint!("{text}");
            }
        }
    }
    if args.format == Format::Human {
        summary(args.files.len(), errors, warnings);
    }
    if io_failed {
        ExitCode::from(2)
    } else if any_errors {
        ExitCode::from(1)
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
