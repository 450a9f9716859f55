//! `sdfc view`: the live viewer ([`sdfc::viewer`]) from the command line.

use super::{choice, exit};
use sdfc::viewer::window::ViewError;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct ViewArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Show this named shape, framed automatically, instead of the `render` item.
    #[arg(long)]
    pub shape: Option<String>,
    /// The graphics API.
    #[arg(long, value_parser = choice::<sdfc::gpu::Backend>(), default_value = "auto")]
    pub backend: sdfc::gpu::Backend,
    /// The window's size, WIDTHxHEIGHT (default: the `render` item's size).
    #[arg(long, value_parser = super::render::parse_size)]
    pub size: Option<(u32, u32)>,
    /// How the geodesic walk is emitted. The viewer rebuilds its pipeline on every
    /// change, so it takes the loop, which builds several times faster on software
    /// adapters; `unrolled` shows what `sdfc render` draws by default.
    #[arg(long, value_parser = choice::<sdfc::codegen::WalkForm>(), default_value = "loop")]
    pub walk: sdfc::codegen::WalkForm,
    /// The multi-scale atlas pass, as for `render` (`auto`: on a GPU, not on a software
    /// adapter).
    #[arg(long, value_parser = choice::<sdfc::gpu::MultiScale>(), default_value = "auto")]
    pub multiscale: sdfc::gpu::MultiScale,
    /// The view at start (the number keys switch: colour, normal, checker, seeds,
    /// blend, distortion, seams, status, steps).
    #[arg(long, value_parser = choice::<sdfc::gpu::ViewMode>(), default_value = "color")]
    pub view: sdfc::gpu::ViewMode,
    /// For tests and scripts: draw this many frames, save --screenshot and quit.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=10000))]
    pub frames: Option<u32>,
    /// Where --frames saves the last frame (PNG, written atomically).
    #[arg(long, value_name = "FILE", requires = "frames")]
    pub screenshot: Option<PathBuf>,
    /// With --frames: turn the camera by this many degrees a frame, as a drag would,
    /// to measure the frame times while the camera moves (printed at the end).
    #[arg(long, value_name = "DEGREES", requires = "frames")]
    pub spin: Option<f64>,
}

pub fn run(args: ViewArgs) -> ExitCode {
    if !sdfc::viewer::VIEWS.iter().any(|(m, _)| *m == args.view) {
        let names: Vec<&str> = sdfc::viewer::VIEWS.iter().map(|(_, n)| *n).collect();
        eprintln!(
            "error: the viewer has no {} view; it has {}",
            format!("{:?}", args.view).to_ascii_lowercase(),
            names.join(", ")
        );
        return ExitCode::from(exit::USAGE);
    }
    if let Err(e) = std::fs::metadata(&args.scene).and_then(|m| {
        if m.is_file() {
            Ok(())
        } else {
            Err(std::io::Error::other("not a file"))
        }
    }) {
        eprintln!("error: cannot read {}: {e}", args.scene.display());
        return ExitCode::from(exit::USAGE);
    }
    let options = sdfc::viewer::Options {
        access: super::access(&args.scene),
        scene: args.scene,
        shape: args.shape,
        backend: args.backend,
        size: args.size,
        walk: args.walk,
        multiscale: args.multiscale,
        mode: args.view,
        frames: args.frames,
        screenshot: args.screenshot,
        spin: args.spin,
    };
    match sdfc::viewer::run(options) {
        Ok(()) => ExitCode::SUCCESS,
        Err(ViewError::Scene) => ExitCode::from(exit::SCENE),
        Err(ViewError::Gpu(e)) => {
            eprintln!("error: {e}");
            ExitCode::from(exit::gpu(&e))
        }
        Err(e @ ViewError::Display(_)) => {
            eprintln!("error: {e}");
            ExitCode::from(exit::GPU)
        }
        Err(e @ ViewError::Io(_)) => {
            eprintln!("error: {e}");
            ExitCode::from(exit::USAGE)
        }
    }
}
