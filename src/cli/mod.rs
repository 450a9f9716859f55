//! The command line's definition and the commands.

pub mod bench;
pub mod check;
pub mod compile;
pub mod eval;
pub mod fmt;
pub mod latency;
pub mod render;
pub mod sweep;

use clap::{Parser, Subcommand, ValueEnum};
use std::io::Read;
use std::path::{Path, PathBuf};

/// sdfc compiles signed-distance scenes with Implicit UVs.
#[derive(Parser)]
#[command(name = "sdfc", version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Check scene files and print every diagnostic.
    ///
    /// Exit status: 0 when there are no errors (warnings allowed), 1 when any file has
    /// errors, 2 on usage or I/O problems.
    Check(CheckArgs),
    /// Evaluate a shape's signed distance at points (CPU reference in f64).
    ///
    /// Reads a JSON array of points `[[x, y, z], …]` and prints one JSON object per point, in
    /// order: `{"point", "distance", "gradient", "surface"}`, where `surface` is the point
    /// projected onto the zero set (null when the projection does not converge). When the
    /// scene has atlases, `"atlas": {"name", "status", "uv", "seed", "geodesic_distance",
    /// "weight"}` gives the Implicit UVs at that projection: Alg. 2's blended uv, the
    /// geodesic-nearest seed and its blend weight; `--all-seeds` adds `"seeds"`, each seed's
    /// own log map.
    Eval(EvalArgs),
    /// Compile a scene to one standalone shader module, validated by naga.
    ///
    /// The module has a full-screen render entry point pair (vs_main, fs_main), compute
    /// entry points (cs_points, cs_grid) and an `sdf_NAME(p) -> f32` per named shape;
    /// its header comment documents the bind groups. Exit status: 0 on success, 1 when
    /// the scene has errors, 2 on usage or I/O problems, 3 on an internal compiler error
    /// (the generated WGSL is saved for the bug report).
    Compile(CompileArgs),
    /// Render a scene headless to a PNG through wgpu (Vulkan, GL, Metal or DX12).
    ///
    /// Camera, size and light come from the scene's `render` item; the flags override
    /// them. With no `render` item (or with --shape), the camera frames the shape.
    /// Exit status: 0 on success, 1 when the scene has errors, 2 on usage or I/O
    /// problems, 3 on an internal compiler error, 4 when no GPU adapter can be used.
    Render(RenderArgs),
    /// Measure frame times on the GPU and print ratios from one run: the shaded scene
    /// against a plain sphere trace of the same scene, and the unrolled walk against the loop.
    Bench(BenchArgs),
    /// Run the language server on standard input and output (LSP, full-document sync):
    /// diagnostics, hover, go to definition, find references, document symbols,
    /// formatting, semantic tokens, rename, completion and signature help.
    Lsp,
    /// Format scene files in place: canonical spacing, 4-space indentation, one
    /// statement per line; comments are kept.
    ///
    /// A file with syntax errors is left unchanged and its errors are printed.
    /// Exit status: 0 on success, 1 when a file has syntax errors or (with --check)
    /// would change, 2 on I/O problems.
    Fmt(fmt::FmtArgs),
}

#[derive(clap::Args)]
pub struct BenchArgs {
    /// The scene file (not with --seed-sweep, which generates its scenes).
    #[arg(required_unless_present = "seed_sweep")]
    pub scene: Option<PathBuf>,
    /// Image size, WIDTHxHEIGHT (default 1920x1080; 320x240 for --seed-sweep).
    #[arg(long, value_parser = render::parse_size)]
    pub size: Option<(u32, u32)>,
    /// The seed-count sweep (the paper's Fig. 15): frame time against an untextured
    /// render for plates with 1, 4, 16, 32 and 64 seeds, N = 10 and 20, merged or not,
    /// with and without the seed grid; and the merge-graph solve time.
    #[arg(long, conflicts_with_all = ["scene", "shape"])]
    pub seed_sweep: bool,
    /// The language server's didChange → publishDiagnostics latency on the scene
    /// (p50/p95 over --edits edits), instead of frame times.
    #[arg(long, requires = "scene")]
    pub lsp_latency: bool,
    /// Edits measured by --lsp-latency.
    #[arg(long, default_value = "50")]
    pub edits: u32,
    /// The walk form of the sweep (the scene benchmark measures both).
    #[arg(long, value_enum, default_value = "unrolled")]
    pub walk: sdfc::codegen::WalkForm,
    /// Frames per measurement (the median is reported).
    #[arg(long, default_value = "5")]
    pub frames: u32,
    /// Measure this named shape instead of the `render` item.
    #[arg(long)]
    pub shape: Option<String>,
    /// The graphics API.
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: sdfc::gpu::Backend,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The PNG to write (atomically).
    #[arg(short, long, default_value = "out.png")]
    pub output: PathBuf,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, value_parser = render::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Render this named shape, framed automatically, instead of the `render` item.
    #[arg(long)]
    pub shape: Option<String>,
    /// What to show.
    #[arg(long, value_enum, default_value = "color")]
    pub view: sdfc::gpu::ViewMode,
    /// Also write a 32-bit float EXR: depth, normal, position, steps, or uv (u, v, status) (repeatable).
    #[arg(long, value_name = "NAME=FILE.exr", value_parser = render::parse_aov)]
    pub aov: Vec<(String, PathBuf)>,
    /// The graphics API.
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: sdfc::gpu::Backend,
    /// How the geodesic walk is emitted: unrolled to exactly N steps, or a loop.
    #[arg(long, value_enum, default_value = "unrolled")]
    pub walk: sdfc::codegen::WalkForm,
    /// Whether the nearest-seed search uses the compile-time seed grid (auto: above 4 seeds).
    #[arg(long, value_enum, default_value = "auto")]
    pub seed_grid: sdfc::codegen::SeedGridChoice,
    /// The atlas of the atlas views and of `cs_atlas` (default: the first).
    #[arg(long)]
    pub atlas: Option<String>,
    /// Print compile, pipeline, frame and readback times.
    #[arg(long)]
    pub timings: bool,
}

#[derive(clap::Args)]
pub struct CompileArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Output file (written atomically); standard output when left out (not for SPIR-V).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Output language.
    #[arg(long, value_enum, default_value = "wgsl")]
    pub target: sdfc::codegen::Target,
    /// Also write a JSON description of the entry points and bindings.
    #[arg(long, value_name = "FILE")]
    pub manifest: Option<PathBuf>,
    /// Render this named shape instead of the `render` item's target.
    #[arg(long)]
    pub shape: Option<String>,
    /// How the geodesic walk is emitted: unrolled to exactly N steps, or a loop.
    #[arg(long, value_enum, default_value = "unrolled")]
    pub walk: sdfc::codegen::WalkForm,
    /// Whether the nearest-seed search uses the compile-time seed grid (auto: above 4 seeds).
    #[arg(long, value_enum, default_value = "auto")]
    pub seed_grid: sdfc::codegen::SeedGridChoice,
    /// The atlas of the atlas views and of `cs_atlas` (default: the first).
    #[arg(long)]
    pub atlas: Option<String>,
    /// The entry point to translate for GLSL (one per file).
    #[arg(long, default_value = "fs_main")]
    pub entry: String,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum Format {
    /// Rendered diagnostics with source excerpts.
    Human,
    /// One JSON object per diagnostic, one per line.
    Json,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum Color {
    Auto,
    Always,
    Never,
}

#[derive(clap::Args)]
pub struct CheckArgs {
    /// Scene files to check (`-` reads standard input).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Output format.
    #[arg(long, value_enum, default_value = "human")]
    pub format: Format,
    /// When to colour human output.
    #[arg(long, value_enum, default_value = "auto")]
    pub color: Color,
}

#[derive(clap::Args)]
pub struct EvalArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The shape to evaluate (a `let` name); default: the render target, or the only shape.
    #[arg(long)]
    pub shape: Option<String>,
    /// A JSON file of points `[[x, y, z], …]`; `-` reads standard input.
    #[arg(long, default_value = "-")]
    pub points: PathBuf,
    /// Evaluate on the GPU through the generated compute shader (f32) instead of the
    /// CPU reference (f64); `surface` is then the CPU projection of the point.
    #[arg(long)]
    pub gpu: bool,
    /// The atlas to evaluate at each point's projection (optional when the scene has one).
    #[arg(long)]
    pub atlas: Option<String>,
    /// The graphics API for --gpu.
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: sdfc::gpu::Backend,
    /// Also report every seed's own log map, status and offset (`"seeds"`, CPU reference).
    #[arg(long)]
    pub all_seeds: bool,
    /// Search the nearest seed without the early-out of Eq. 35: every seed is walked
    /// with the full D (CPU; for testing the early-out).
    #[arg(long)]
    pub brute_force: bool,
}

pub fn read_source(path: &Path) -> std::io::Result<String> {
    if path == Path::new("-") {
        let mut s = String::new();
        std::io::stdin().read_to_string(&mut s)?;
        Ok(s)
    } else {
        std::fs::read_to_string(path)
    }
}

/// The folder texture paths are relative to.
pub fn base_dir(path: &Path) -> PathBuf {
    if path == Path::new("-") {
        return std::env::current_dir().unwrap_or_else(|_| PathBuf::from("."));
    }
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Reads and checks a scene for the commands that need a valid one: prints its
/// diagnostics, and gives the exit code to return when it cannot be used.
pub fn load(path: &Path) -> Result<(String, sdfc::driver::Analysis), std::process::ExitCode> {
    let name = path.display().to_string();
    let source = read_source(path).map_err(|e| {
        eprintln!("error: cannot read {name}: {e}");
        std::process::ExitCode::from(2)
    })?;
    let analysis = sdfc::driver::check(&source, Some(&base_dir(path)));
    let color = std::io::IsTerminal::is_terminal(&std::io::stderr())
        && std::env::var_os("NO_COLOR").is_none();
    eprint!(
        "{}",
        sdfc::diagnostic::render(&name, &source, &analysis.diagnostics, color)
    );
    if analysis.has_errors() {
        return Err(std::process::ExitCode::from(1));
    }
    Ok((source, analysis))
}

/// The view of a checked scene: the render item's, or framed on `--shape`.
pub fn view_for(
    analysis: &sdfc::driver::Analysis,
    shape: Option<&str>,
) -> Result<sdfc::view::View, std::process::ExitCode> {
    let Some(scene) = &analysis.scene else {
        return Err(std::process::ExitCode::from(1));
    };
    let target = sdfc::driver::pick_shape(scene, shape).map_err(|e| {
        eprintln!("error: {e}");
        std::process::ExitCode::from(compile::USAGE_EXIT)
    })?;
    let render_item = if shape.is_some() {
        None
    } else {
        analysis.program.render.as_ref()
    };
    Ok(sdfc::view::View::new(render_item, target))
}
