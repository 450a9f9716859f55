//! `sdfc serve SCENE`: the scene's web page served on loopback and rebuilt on change
//! ([`sdfc::web::serve`]).

use super::{choice, exit};
use sdfc::web::serve::{self, ServeError};
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct ServeArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The port to listen on (0: any free port; the address is printed).
    #[arg(long, default_value = "8000")]
    pub port: u16,
    /// The address to listen on. The default is loopback; another address lets other
    /// machines read the page and the scene's folder.
    #[arg(long, default_value_t = IpAddr::V4(Ipv4Addr::LOCALHOST))]
    pub host: IpAddr,
    /// Show this named shape instead of the `render` item's target.
    #[arg(long)]
    pub shape: Option<String>,
    /// The walk's form in the page's module (loop by default, as for export-web).
    #[arg(long, value_parser = choice::<sdfc::codegen::WalkForm>(), default_value = "loop")]
    pub walk: sdfc::codegen::WalkForm,
    /// Add the multi-scale atlas pass to the page's module (as `export-web
    /// --multiscale`).
    #[arg(long)]
    pub multiscale: bool,
}

pub fn run(args: ServeArgs) -> ExitCode {
    let is_file = std::fs::metadata(&args.scene).map(|m| m.is_file());
    if !matches!(is_file, Ok(true)) {
        let why = match is_file {
            Err(e) => e.to_string(),
            Ok(_) => String::from("it is not a file"),
        };
        eprintln!("error: cannot read {}: {why}", args.scene.display());
        return ExitCode::from(exit::USAGE);
    }
    let options = serve::Options {
        source: serve::site::Source {
            access: super::access(&args.scene),
            scene: args.scene,
            shape: args.shape,
            options: sdfc::codegen::Options {
                walk: args.walk,
                multiscale: args.multiscale,
                ..Default::default()
            },
        },
        addr: SocketAddr::new(args.host, args.port),
    };
    match serve::run(options) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e @ (ServeError::Bind(..) | ServeError::Scene(_))) => {
            eprintln!("error: {e}");
            ExitCode::from(exit::USAGE)
        }
    }
}
