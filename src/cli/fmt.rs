//! `sdfc fmt`: the formatter of [`sdfc::ide::format`], on files.

use super::read_source;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct FmtArgs {
    /// Scene files to format in place (`-` formats standard input to standard output).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Change nothing: list the files that would change, and exit 1 if there are any.
    #[arg(long)]
    pub check: bool,
}

pub fn run(args: FmtArgs) -> ExitCode {
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let (mut io_failed, mut errors, mut unformatted) = (false, false, 0usize);
    for path in &args.files {
        let name = path.display().to_string();
        let source = match read_source(path) {
            Ok(s) if !s.decoding.is_empty() => {
                eprint!(
                    "{}",
                    sdfc::diagnostic::render(&name, &s.text, &s.decoding, color)
                );
                eprintln!("error: {name} is not UTF-8 text; it was not formatted");
                errors = true;
                continue;
            }
            Ok(s) => s.text,
            Err(e) => {
                eprintln!("error: cannot read {name}: {e}");
                io_failed = true;
                continue;
            }
        };
        let formatted = match sdfc::ide::format::format(&source) {
            Ok(f) => f,
            Err(diags) => {
                eprint!(
                    "{}",
                    sdfc::diagnostic::render(&name, &source, &diags, color)
                );
                eprintln!("error: {name} has syntax errors; it was not formatted");
                errors = true;
                continue;
            }
        };
        let stdin = path.as_os_str() == "-";
        if args.check {
            if formatted != source {
                println!("{name}");
                unformatted += 1;
            }
        } else if stdin {
            let _ = std::io::stdout().write_all(formatted.as_bytes());
        } else if formatted != source {
            if let Err(e) = sdfc::fsutil::write_output(path, formatted.as_bytes()) {
                eprintln!("error: cannot write {name}: {e}");
                io_failed = true;
            }
        }
    }
    if unformatted > 0 {
        let s = if unformatted == 1 { "" } else { "s" };
        eprintln!("{unformatted} file{s} would be reformatted (run `sdfc fmt` without --check)");
    }
    if io_failed {
        ExitCode::from(super::exit::USAGE)
    } else if errors || unformatted > 0 {
        ExitCode::from(super::exit::SCENE)
    } else {
        ExitCode::SUCCESS
    }
}
