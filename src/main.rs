//! The `sdfc` command line.

mod cli;

use clap::Parser;
use cli::{Cli, Command};
use std::process::ExitCode;

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
    cli::set_allowed_paths(cli.allow_path);
    match cli.command {
        Command::Check(args) => cli::check::run(args),
        Command::Eval(args) => cli::eval::run(args),
        Command::Compile(args) => cli::compile::run(args),
        Command::ExportWeb(args) => cli::export_web::run(args),
        Command::Serve(args) => cli::serve::run(args),
        Command::Render(args) => cli::render::run(args),
        Command::View(args) => cli::view::run(args),
        Command::Bake(args) => cli::bake::run(args),
        Command::Bench(args) => cli::bench::run(args),
        Command::FitHeight(args) => cli::fit_height::run(args),
        Command::Fmt(args) => cli::fmt::run(args),
        Command::Seeds(args) => cli::seeds::run(args),
        Command::Lsp => match sdfc::lsp::run_stdio() {
            Ok(sdfc::lsp::Ended::Clean) => ExitCode::SUCCESS,
            // `exit` without `shutdown`: 1, as the specification asks.
            Ok(sdfc::lsp::Ended::WithoutShutdown) => ExitCode::from(1),
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
    }
}
