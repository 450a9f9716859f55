//! The `sdfc` command line.

use clap::{Parser, Subcommand, ValueEnum};
use sdfc::diagnostic;
use sdfc::driver::analyze;
use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// sdfc compiles signed-distance scenes with Implicit UVs.
#[derive(Parser)]
#[command(name = "sdfc", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Check scene files and print every diagnostic.
    ///
    /// Exit status: 0 when there are no errors (warnings allowed), 1 when any file has
    /// errors, 2 on usage or I/O problems.
    Check(CheckArgs),
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
enum Format {
    /// Rendered diagnostics with source excerpts.
    Human,
    /// One JSON object per diagnostic, one per line.
    Json,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
enum Color {
    Auto,
    Always,
    Never,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// Scene files to check (`-` reads standard input).
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    /// Output format.
    #[arg(long, value_enum, default_value = "human")]
    format: Format,
    /// When to colour human output.
    #[arg(long, value_enum, default_value = "auto")]
    color: Color,
}

fn read_source(path: &Path) -> std::io::Result<String> {
    if path == Path::new("-") {
        let mut s = String::new();
        std::io::stdin().read_to_string(&mut s)?;
        Ok(s)
    } else {
        std::fs::read_to_string(path)
    }
}

fn check(args: CheckArgs) -> ExitCode {
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
        let base_dir = if path == Path::new("-") {
            std::env::current_dir().ok()
        } else {
            Some(path.parent().map(Path::to_path_buf).unwrap_or_default())
        };
        let base_dir = base_dir.map(|d| {
            if d.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                d
            }
        });
        let analysis = analyze(&source, base_dir.as_deref());
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

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return match e.kind() {
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion => {
                    ExitCode::SUCCESS
                }
                _ => ExitCode::from(2),
            };
        }
    };
    match cli.command {
        Command::Check(args) => check(args),
    }
}
