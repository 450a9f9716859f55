//! `sdfc export-web SCENE -o DIR`: the scene as a static web page (`sdfc::web`).

use super::compile;
use super::exit;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct ExportWebArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The folder to write the page into (made if missing; its files are written
    /// atomically, others left alone).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The walk's form in the page's module: loop (the default here: browsers'
    /// shader compilers build the unrolled walk slowly) or unrolled.
    #[arg(long, value_parser = super::choice::<sdfc::codegen::WalkForm>(), default_value = "loop")]
    pub walk: sdfc::codegen::WalkForm,
    /// Show this named shape instead of the `render` item's target.
    #[arg(long)]
    pub shape: Option<String>,
    /// Add the multi-scale atlas pass (as `compile --multiscale`): the page walks the
    /// atlases at one pixel in 16 first and rebuilds the others where they agree. It
    /// pays on a GPU, not on a software adapter (SwiftShader).
    #[arg(long)]
    pub multiscale: bool,
}

pub fn run(args: ExportWebArgs) -> ExitCode {
    if args.output.exists() && !args.output.is_dir() {
        eprintln!("error: {} is not a folder", args.output.display());
        return ExitCode::from(exit::USAGE);
    }
    let options = sdfc::codegen::Options {
        walk: args.walk,
        multiscale: args.multiscale,
        ..Default::default()
    };
    let (_, analysis, mut compiled) =
        match compile::build(&args.scene, args.shape.as_deref(), &options) {
            Ok(x) => x,
            Err(code) => return code,
        };
    compiled.module.manifest.scene = sdfc::gpu::scene_values(&analysis, args.shape.as_deref());
    let textures = match sdfc::Textures::load(&analysis.program) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(exit::SCENE);
        }
    };
    let title = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| String::from("scene"));
    for w in sdfc::web::warnings(&compiled.module) {
        eprintln!("warning: {w}");
    }
    match sdfc::web::export(&args.output, &title, &compiled.module, &textures) {
        Ok(written) => {
            println!(
                "wrote {} files to {}: serve the folder over http://127.0.0.1 and open index.html in a WebGPU browser",
                written.len(),
                args.output.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(exit::USAGE)
        }
    }
}
