//! The command line's definition and the commands.

pub mod animate;
pub mod bake;
pub mod bench;
mod bench_params;
pub mod check;
pub mod compile;
pub mod eval;
pub mod export_web;
pub mod fit_height;
pub mod fmt;
pub mod frame;
pub mod latency;
pub mod params;
pub mod plot;
pub mod render;
pub mod render_mesh;
pub mod report;
pub mod scale;
pub mod seeds;
pub mod serve;
pub mod sweep;
pub mod view;

/// The value parser of a library type with named values ([`Choice`]): its names, each
/// with its help. (The library has no command line of its own and does not depend on
/// clap.)
pub fn choice<T: Choice + Clone>() -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(
        T::CHOICES
            .iter()
            .map(|(_, name, help)| PossibleValue::new(*name).help(*help)),
    )
    .map(|name| T::from_name(&name).expect("one of the possible values"))
}

/// The exit statuses, one meaning each (docs/commands.md, Exit status).
/// The GPU of `backend`, or the error printed and its exit status.
pub fn open_gpu(backend: sdfc::gpu::Backend) -> Result<sdfc::gpu::Gpu, std::process::ExitCode> {
    sdfc::gpu::Gpu::new(backend).map_err(|e| {
        eprintln!("error: {e}");
        std::process::ExitCode::from(exit::gpu(&e))
    })
}

pub mod exit {
    /// The scene has errors.
    pub const SCENE: u8 = 1;
    /// Usage or I/O problems: bad flags, unknown `--shape`/`--atlas`/`--entry`, unreadable
    /// or unwritable files.
    pub const USAGE: u8 = 2;
    /// An internal compiler error: naga rejected generated code.
    pub const ICE: u8 = 3;
    /// No usable GPU adapter.
    pub const GPU: u8 = 4;
    /// A resource limit: the GPU ran out of memory, or a size is over the adapter's or
    /// sdfc's limits. The message names the limit.
    pub const RESOURCE: u8 = 5;

    /// The status for a GPU failure.
    pub fn gpu(e: &sdfc::gpu::GpuError) -> u8 {
        use sdfc::gpu::GpuError;
        match e {
            GpuError::NoAdapter(_) | GpuError::Device(_) => GPU,
            GpuError::Resource(_) => RESOURCE,
            // A texture the check accepted that then failed to decode (changed since).
            GpuError::Texture(_) => SCENE,
            GpuError::Validation(_) => ICE,
        }
    }
}

static ALLOWED: std::sync::OnceLock<Vec<PathBuf>> = std::sync::OnceLock::new();

/// Records the folders `--allow-path` adds to what scenes may read (once, at start).
pub fn set_allowed_paths(dirs: Vec<PathBuf>) {
    let _ = ALLOWED.set(dirs);
}

/// The folders the scene at `path` may read: its own, and `--allow-path`'s.
pub fn access(path: &Path) -> sdfc::access::Access {
    let mut access = sdfc::access::Access::new(Some(&base_dir(path)));
    for dir in ALLOWED.get().into_iter().flatten() {
        access.allow(dir);
    }
    for (name, value) in params::set() {
        access.set_param(name, value);
    }
    access
}

use clap::{Parser, Subcommand, ValueEnum};
use sdfc::choice::Choice;
use std::io::Read as _;
use std::path::{Path, PathBuf};

/// sdfc compiles signed-distance scenes with Implicit UVs.
#[derive(Parser)]
#[command(name = "sdfc", version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    /// Also let scenes read textures below DIR (repeatable). By default a scene reads
    /// only files in its own folder and its subfolders, after following symbolic links.
    #[arg(long, global = true, value_name = "DIR")]
    pub allow_path: Vec<PathBuf>,
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
    /// The module has a full-screen render (vs_main with fs_main, one colour target, or
    /// fs_aov, with three float AOVs), compute entry points (cs_points, cs_grid,
    /// cs_atlas, cs_material, cs_bake) and an `sdf_NAME(p) -> f32` per named shape; its
    /// header comment documents the bind groups and which entry points use each, and
    /// `--manifest` writes the module's contract as JSON (schemas/manifest.v1.json).
    /// Exit status: 0 on success, 1 when
    /// the scene has errors, 2 on usage or I/O problems, 3 on an internal compiler error
    /// (the generated WGSL is saved for the bug report).
    Compile(CompileArgs),
    /// Export a scene as a static web page: index.html, the WebGPU driver sdfc.js, the
    /// WGSL, its manifest and the textures with their mip levels.
    ///
    /// Serve the folder from http://127.0.0.1 (WebGPU needs a secure context) with any
    /// static file server and open it in a WebGPU browser: the page shows what
    /// `sdfc render` shows, with orbit controls.
    ExportWeb(export_web::ExportWebArgs),
    /// Serve a scene's web page (the one export-web writes) on 127.0.0.1 and rebuild it
    /// when the scene or its textures change.
    ///
    /// The page reloads the new build keeping its camera; while the file has errors it
    /// shows their diagnostics over the last good picture. Besides the page, only files
    /// of the scene's own folder are served, with the same confinement as textures
    /// (no `..`, no hidden names, no symbolic link out). Prints `serving NAME at URL`
    /// on standard error; Ctrl-C stops. Exit status: 2 when the scene cannot be read or
    /// the address cannot be listened on (the port is in use).
    Serve(serve::ServeArgs),
    /// Render a scene headless to a PNG through wgpu (Vulkan, GL, Metal or DX12).
    ///
    /// Camera, size and light come from the scene's `render` item; the flags override
    /// them. With no `render` item (or with --shape), the camera frames the shape.
    /// A `.glb` baked by sdfc renders its mesh with its flat seamless atlas instead
    /// (views color, albedo, normal, depth, uv, level; no shadows), framed on its bounds
    /// with the default light. Exit status: 0 on success, 1 when the scene has errors,
    /// 2 on usage or I/O problems (an unreadable .glb), 3 on an internal compiler error,
    /// 4 when no GPU adapter can be used. With SDFC_PIPELINE_CACHE=DIR, wgpu's pipeline
    /// cache (Vulkan) is kept in DIR between runs.
    Render(RenderArgs),
    /// Open a live viewer: orbit (left drag), pan (middle or shift drag), zoom (wheel);
    /// F frames the shape, R resets to the scene's camera; 1-9 switch views (colour,
    /// normal, uv checker, seeds, blend, distortion, seams, status, steps); S saves a
    /// screenshot next to the scene; Esc quits.
    ///
    /// The scene and its textures are watched and reloaded on change; a version with
    /// errors prints its diagnostics and the last good one stays on screen. Seeds by
    /// mouse, each a text edit to the scene file (written atomically): ctrl-click adds
    /// a seed, dragging a seed moves it, alt-click removes it with its merges,
    /// shift-clicking two seeds merges them; ctrl-Z undoes the viewer's last edit.
    /// Exit status: 0 when closed, 1 when the scene never built (with --frames), 2 on
    /// usage or I/O problems, 4 when no window or GPU adapter can be used.
    View(view::ViewArgs),
    /// Bake a textured scene into a textured mesh with a seamless atlas (binary glTF).
    ///
    /// Meshes the shape's surface (dual contouring), makes one quadrilateral chart per
    /// quad (flat layout) or grows conforming rectangles of quads (--layout packed),
    /// samples the scene's material at every texel on the GPU (border texels are
    /// computed once and shared), filters the boundary-symmetric mip levels of the
    /// Seamless Texture Atlases paper, and writes a .glb with POSITION, NORMAL, TANGENT,
    /// TEXCOORD_0 and a PBR material. Exit status: 0 on success, 1 when the scene has
    /// errors, no material or no surface in the bounds, 2 on usage or I/O problems, 3 on
    /// an internal compiler error, 4 when no GPU adapter can be used, 5 when the atlas
    /// is over a limit.
    Bake(BakeArgs),
    /// Encode a target shape as a displacement of a base shape (§5.3): rays from the
    /// base along its normals to the target, each ray's signed length stored at the uv
    /// of Alg. 1 (the atlas on the base), resampled into a 16-bit grey PNG height map.
    ///
    /// Prints the encoding (height = offset + range · texel, texel in [0, 1]) and the
    /// `displace` call that reproduces the target, with the uv rectangle the map spans.
    /// Exit status: 0 on success, 1 when the scene has errors or the atlas covers too
    /// little of the base, 2 on usage or I/O problems (unknown shapes or atlas, an atlas
    /// not on the base, an unwritable output).
    FitHeight(FitHeightArgs),
    /// Measure frame times on the GPU and print ratios from one run: the shaded scene
    /// against a plain sphere trace of the same scene, the unrolled walk against the loop,
    /// and, when a material has a normal map, the scene against itself without them.
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
    /// Place an atlas's seeds and merges automatically: farthest-point sampling until
    /// Alg. 2 succeeds on the target share of the surface, then a merge forest of the
    /// neighbouring seeds whose walks reach each other, and the cycles that close
    /// under the obstruction limits.
    ///
    /// Prints the `seed` and `merge` statements, or with --write replaces the atlas's
    /// own in the file (formatted, written atomically). Exit status: 0 on success, 1
    /// when the scene has errors, 2 on usage or I/O problems.
    Seeds(seeds::SeedsArgs),
}

#[derive(clap::Args)]
pub struct FitHeightArgs {
    /// The scene file: it defines the base and target shapes and an atlas on the base.
    pub scene: PathBuf,
    /// The shape to encode (a `let` of the scene).
    #[arg(long)]
    pub target: String,
    /// The simple shape it is encoded over (a `let` of the scene).
    #[arg(long)]
    pub base: String,
    /// The atlas on the base (default: the only one).
    #[arg(long)]
    pub atlas: Option<String>,
    /// The height map to write (16-bit grey PNG, atomically).
    #[arg(short, long, default_value = "height.png")]
    pub output: PathBuf,
    /// Texels per side.
    #[arg(long, default_value_t = 256)]
    pub size: u32,
    /// Base samples (default: 6 per texel).
    #[arg(long)]
    pub samples: Option<usize>,
    /// The uv rectangle the map spans, U0 V0 U1 V1 (default: the samples' extent).
    #[arg(long, num_args = 4, value_names = ["U0", "V0", "U1", "V1"], allow_negative_numbers = true)]
    pub uv_rect: Option<Vec<f64>>,
}

#[derive(clap::Args)]
pub struct BenchArgs {
    /// The scene file (not with --seed-sweep or --scale, which generate their scenes).
    #[arg(required_unless_present_any = ["seed_sweep", "scale"])]
    pub scene: Option<PathBuf>,
    /// Image size, WIDTHxHEIGHT (default 1920x1080; 320x240 for --seed-sweep).
    #[arg(long, value_parser = render::parse_size)]
    pub size: Option<(u32, u32)>,
    /// The seed-count sweep (the paper's Fig. 15): frame time against an untextured
    /// render for plates with 1, 4, 16, 32 and 64 seeds, N = 10 and 20, merged or not,
    /// with and without the seed grid; and the merge-graph solve time.
    #[arg(long, conflicts_with_all = ["scene", "shape"])]
    pub seed_sweep: bool,
    /// How cost grows with the scene: generated cities of 10 to 10,000 spheres, then
    /// 1,200 spheres with 0 to 500 seeds, then scenes that are not cities (12 and 1,200
    /// small spheres scattered through a cube, most rays missing, and 4,000 with 200
    /// seeds); compile time, WGSL lines, pipeline and frame time (default size 160x120)
    /// and the language server's latency of each, and up to 1,200 spheres of city the
    /// same against the scene with its unions as code.
    #[arg(long, conflicts_with_all = ["scene", "shape", "seed_sweep"])]
    pub scale: bool,
    /// With --scale or --seed-sweep: also draw the chart, SVG or PNG by the extension,
    /// to this file (written atomically): --scale's figures against the number of
    /// primitives, log-log; the sweep's frame time ÷ constant uv against the number of
    /// seeds (the paper's Fig. 15).
    #[arg(long, value_name = "PATH", value_parser = plot::parse_path)]
    pub plot: Option<PathBuf>,
    /// The language server's didChange → publishDiagnostics latency on the scene
    /// (p50/p95 over --edits edits), instead of frame times: for edits that change a
    /// token (the whole analysis runs) and for comment edits (the back end is carried
    /// over).
    #[arg(long, requires = "scene")]
    pub lsp_latency: bool,
    /// Bake the scene's atlas (2048 wide, full mip chain, the default grid, the loop
    /// walk) and report the time of each stage instead of frame times.
    #[arg(long, requires = "scene", conflicts_with_all = ["lsp_latency", "seed_sweep", "scale"])]
    pub bake: bool,
    /// The atlas side for --bake [default: 2048].
    #[arg(long, requires = "bake")]
    pub atlas_size: Option<u32>,
    /// The atlas layout for --bake [default: flat].
    #[arg(long = "bake-layout", value_enum, requires = "bake")]
    pub bake_layout: Option<Layout>,
    /// How --bake chooses its level-0 texels (as `sdfc bake --texels`) [default: points].
    #[arg(long = "bake-texels", value_name = "fit|points", value_parser = bake::parse_texels, requires = "bake")]
    pub bake_texels: Option<sdfc::bake::pipeline::Texels>,
    /// The region --bake bakes, MIN MAX, each x,y,z (as `sdfc bake --bounds`; needed for
    /// shapes without finite bounds).
    #[arg(long = "bake-bounds", num_args = 2, value_names = ["MIN", "MAX"], value_parser = bake::parse_point, allow_hyphen_values = true, requires = "bake")]
    pub bake_bounds: Vec<[f64; 3]>,
    /// Edits measured by --lsp-latency.
    #[arg(long, default_value = "50")]
    pub edits: u32,
    /// The walk form of the sweep, `auto` the adapter's best as for `render` (the scene
    /// benchmark measures both).
    #[arg(long, value_parser = choice::<sdfc::gpu::WalkChoice>(), default_value = "auto")]
    pub walk: sdfc::gpu::WalkChoice,
    /// With --seed-sweep: the walk's gradients, `auto` as for `render` (the forward
    /// derivative). The scene benchmark measures both.
    #[arg(long, value_parser = choice::<sdfc::gpu::Gradients>(), default_value = "auto")]
    pub gradients: sdfc::gpu::Gradients,
    /// Frames per measurement (the median is reported).
    #[arg(long, default_value = "5")]
    pub frames: u32,
    /// Measure this named shape instead of the `render` item.
    #[arg(long)]
    pub shape: Option<String>,
    /// The graphics API.
    #[arg(long, value_parser = choice::<sdfc::gpu::Backend>(), default_value = "auto")]
    pub backend: sdfc::gpu::Backend,
    /// Also write the figures to this file as JSON, for tracking across commits (every
    /// bench: the scene's rows and ratios, the seed sweep, --bake and --lsp-latency).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub run_time: params::ParamArgs,
    /// The scene file, or a baked mesh (`.glb`).
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
    #[arg(long, value_parser = choice::<sdfc::gpu::ViewMode>(), default_value = "color")]
    pub view: sdfc::gpu::ViewMode,
    /// Also write a 32-bit float EXR: depth, normal, position, steps, or uv (u, v, status) (repeatable).
    #[arg(long, value_name = "NAME=FILE.exr", value_parser = render::parse_aov)]
    pub aov: Vec<(String, PathBuf)>,
    /// The graphics API.
    #[arg(long, value_parser = choice::<sdfc::gpu::Backend>(), default_value = "auto")]
    pub backend: sdfc::gpu::Backend,
    /// How the geodesic walk is emitted: unrolled to exactly N steps, or a loop; `auto`
    /// takes the adapter's best (unrolled on a GPU, a loop on a software adapter).
    #[arg(long, value_parser = choice::<sdfc::gpu::WalkChoice>(), default_value = "auto")]
    pub walk: sdfc::gpu::WalkChoice,
    /// How the walk takes the field's gradient: the forward derivative the compiler
    /// writes (one evaluation a step; `compile`'s), central differences (six), or `auto`,
    /// the forward derivative on every adapter (as fast as differences or faster on
    /// lavapipe, measured; five evaluations a step fewer on a GPU).
    #[arg(long, value_parser = choice::<sdfc::gpu::Gradients>(), default_value = "auto")]
    pub gradients: sdfc::gpu::Gradients,
    /// Trace every large union whole, not over the leaves each 8 × 8-pixel screen tile
    /// can meet (per-tile culling, exact: the baseline it is measured against; see
    /// docs/performance.md, Big scenes).
    #[arg(long)]
    pub no_tiles: bool,
    /// The multi-scale atlas pass: walk one pixel in 4 × 4 and rebuild the others'
    /// atlas samples where those agree (see docs/performance.md, "Multi-scale atlas
    /// pass"), or walk every pixel.
    #[arg(long, value_parser = choice::<sdfc::gpu::MultiScale>(), default_value = "auto")]
    pub multiscale: sdfc::gpu::MultiScale,
    /// Prune each walk's field to the union operands within its reach (exact; off by
    /// default, as it measured slower on the software adapter: see docs/performance.md).
    #[arg(long)]
    pub prune: bool,
    /// Where the atlases' seeds and merge graphs live: baked into the shader, or in the
    /// `tables` buffer (faster to compile and, for many seeds, to build and render; auto:
    /// baked up to 64 seeds; see docs/performance.md).
    #[arg(long, value_parser = choice::<sdfc::codegen::SeedData>(), default_value = "auto")]
    pub seed_data: sdfc::codegen::SeedData,
    /// Skip unions' operands by their bounding boxes where they cannot change the union
    /// (exact; costly: operands of several primitives; off by default, as the software
    /// adapter's `if` never skips work: see docs/performance.md).
    #[arg(long, value_parser = choice::<sdfc::codegen::Bounds>(), default_value = "off")]
    pub bounds: sdfc::codegen::Bounds,
    /// Whether the nearest-seed search uses the compile-time seed grid (auto: above 4 seeds).
    #[arg(long, value_parser = choice::<sdfc::codegen::SeedGridChoice>(), default_value = "auto")]
    pub seed_grid: sdfc::codegen::SeedGridChoice,
    /// The atlas of the atlas views and of `cs_atlas` (default: the first).
    #[arg(long)]
    pub atlas: Option<String>,
    /// Print compile, pipeline, frame and readback times.
    #[arg(long)]
    pub timings: bool,
    /// For a baked mesh (.glb): take the camera, light, size and background from this
    /// scene's `render` item (the scene it was baked from), to compare the two renders.
    #[arg(long, value_name = "SCENE")]
    pub camera_from: Option<PathBuf>,
    /// For a baked mesh (.glb): how to read its atlas. `atlas` (the default) is sdfc's
    /// seamless lookup; `standard` shows what any glTF viewer shows (TEXCOORD_0 over
    /// each triangle, hardware trilinear filtering on a generic mip chain).
    #[arg(long, value_parser = choice::<sdfc::gpu::MeshFilter>())]
    pub filter: Option<sdfc::gpu::MeshFilter>,
    /// Render an animation of SECONDS: one frame per step of `time` (from `--time`),
    /// one pipeline, only the parameters' block changing. The output is an animated
    /// GIF (.gif), an animated PNG (.png), or numbered frames (frame%04d.png).
    #[arg(long, value_name = "SECONDS")]
    pub animate: Option<f64>,
    /// Frames per second of `--animate`.
    #[arg(long, default_value_t = 24.0, value_name = "F")]
    pub fps: f64,
}

/// The atlas layouts `sdfc bake` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Layout {
    /// Every chart at the same resolution, all levels in one image in a mip-map
    /// pattern (the paper's §3.3).
    Flat,
    /// Charts grown over the mesh into conforming rectangles of quads, each with as
    /// many texels as its quads, packed in shelves with a lookup table (the paper's
    /// §3.4): uniform texel density and fewer chart borders.
    Packed,
}

#[derive(clap::Args)]
pub struct BakeArgs {
    #[command(flatten)]
    pub run_time: params::ParamArgs,
    /// The scene file.
    pub scene: PathBuf,
    /// The binary glTF to write (atomically).
    #[arg(short, long, default_value = "out.glb")]
    pub output: PathBuf,
    /// Bake this named shape instead of the `render` item's target.
    #[arg(long)]
    pub shape: Option<String>,
    /// The atlas width in texels, a power of two (its height is what the charts need).
    #[arg(long, default_value = "2048")]
    pub size: u32,
    /// Mesh grid: cells along the longest side of the bounds (default 48).
    #[arg(long, conflicts_with = "edge")]
    pub grid: Option<usize>,
    /// Mesh grid: the cells' edge length.
    #[arg(long)]
    pub edge: Option<f64>,
    /// Mesh quads along each chart's side: charts come from a grid M times coarser
    /// than the mesh, so there are M² times fewer charts, each with more texels (less
    /// border overhead); each chart is split into M × M quads projected onto the surface.
    /// `--grid 96 --chart-quads 2` keeps the charts and texels of the default and
    /// quarters the mesh's chord error: texels then land where the implicit render
    /// shows them in close-ups (docs/baking.md).
    #[arg(long, value_name = "M", default_value_t = sdfc::bake::pipeline::DEFAULT_CHART_QUADS)]
    pub chart_quads: usize,
    /// Pad every level-0 chart with a gutter of TEXELS texels (`--gutter=4`; 2 when
    /// the flag is given alone), filled from the charts across its sides, for engines that build
    /// their own mip chain of the image: its levels up to log2(TEXELS + 1) then average
    /// real neighbours (2 texels: level 1; 3 or 4: levels 1 and 2). Each chart's cell
    /// grows by twice the gutter, so fewer texels are left for the picture at a given
    /// --size (the robot at --size 1024: 8² texels a chart either way, 43 % of the
    /// image used with 2 texels, 85 % without).
    #[arg(long, value_name = "TEXELS", num_args = 0..=1, require_equals = true, default_value = "0", default_missing_value = "2")]
    pub gutter: u32,
    /// Mesh the cells that may hold detail finer than themselves (a part thinner than
    /// a cell, a slit, a wedge sharper than 75°) on a grid R times finer, joined to the
    /// rest without cracks. `auto` does it only where the plain mesh misses part of the
    /// surface (the report's "surface held"), at R = 2, 4 or 8, the first that parts
    /// every slit and holds the surface; 1 never does (docs/baking.md).
    #[arg(long, value_name = "auto|R", default_value = "auto", value_parser = bake::parse_refine)]
    pub refine: sdfc::bake::pipeline::Refine,
    /// How level-0 texels are chosen: `fit` sets each chart's inner texels so that a
    /// reader's bilinear filter draws the material between texels too (it shades four
    /// samples a texel: about three times the bake's time); `points` takes the material at
    /// each texel's point. Chart borders are point samples either way (docs/baking.md).
    #[arg(long, value_name = "fit|points", default_value = "points", value_parser = bake::parse_texels)]
    pub texels: sdfc::bake::pipeline::Texels,
    /// The atlas layout.
    #[arg(long, value_enum, default_value = "flat")]
    pub layout: Layout,
    /// Packed layout: the longest side of a grown chart, in chart-grid quads [default:
    /// 16].
    #[arg(long, value_name = "CELLS")]
    pub max_chart: Option<usize>,
    /// The region to bake, MIN MAX, each x,y,z (needed for shapes without finite bounds):
    /// the exported mesh is cut at its faces.
    #[arg(long, num_args = 2, value_names = ["MIN", "MAX"], value_parser = bake::parse_point, allow_hyphen_values = true)]
    pub bounds: Vec<[f64; 3]>,
    /// Also write the colour atlas's full mip chain as an uncompressed KTX2 file (each
    /// level the chart grid of that level, the paper's stacked style).
    #[arg(long, value_name = "FILE")]
    pub ktx2: Option<PathBuf>,
    /// Also write the object-space normals as a PNG in the same flat layout (the glTF
    /// holds the tangent-space map that `normalTexture` needs).
    #[arg(long, value_name = "FILE")]
    pub object_normals: Option<PathBuf>,
    /// Also write the chart table as JSON: each chart's rectangle per level and its
    /// neighbours along each side, with orientation.
    #[arg(long, value_name = "FILE")]
    pub charts: Option<PathBuf>,
    /// The graphics API.
    #[arg(long, value_parser = choice::<sdfc::gpu::Backend>(), default_value = "auto")]
    pub backend: sdfc::gpu::Backend,
    /// How the geodesic walk is emitted.
    #[arg(long, value_parser = choice::<sdfc::codegen::WalkForm>(), default_value = "loop")]
    pub walk: sdfc::codegen::WalkForm,
}

#[derive(clap::Args)]
pub struct CompileArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Output file (written atomically); standard output when left out (not for SPIR-V).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Output language.
    #[arg(long, value_parser = choice::<sdfc::codegen::Target>(), default_value = "wgsl")]
    pub target: sdfc::codegen::Target,
    /// Also write the module's manifest: entry points, render targets, bindings with the
    /// entry points that use each, the globals' layout, meaning and the scene's values,
    /// textures and tables (JSON; schemas/manifest.v1.json).
    #[arg(long, value_name = "FILE")]
    pub manifest: Option<PathBuf>,
    /// Render this named shape instead of the `render` item's target.
    #[arg(long)]
    pub shape: Option<String>,
    /// How the geodesic walk is emitted: unrolled to exactly N steps, or a loop.
    #[arg(long, value_parser = choice::<sdfc::codegen::WalkForm>(), default_value = "unrolled")]
    pub walk: sdfc::codegen::WalkForm,
    /// Whether the nearest-seed search uses the compile-time seed grid (auto: above 4 seeds).
    #[arg(long, value_parser = choice::<sdfc::codegen::SeedGridChoice>(), default_value = "auto")]
    pub seed_grid: sdfc::codegen::SeedGridChoice,
    /// Large unions (16 or more primitives under moves, turns and paints) as code, one
    /// call per primitive, instead of data in the `tables` buffer walked through a
    /// bounding-volume hierarchy (the default; see docs/performance.md, Big scenes).
    #[arg(long)]
    pub unions_as_code: bool,
    /// Prune each walk's field to the union operands within its reach (exact; off by
    /// default, as it measured slower on the software adapter: see docs/performance.md).
    #[arg(long)]
    pub prune: bool,
    /// Where the atlases' seeds and merge graphs live: baked into the shader, or in the
    /// `tables` buffer (faster to compile and, for many seeds, to build and render; auto:
    /// baked up to 64 seeds; see docs/performance.md).
    #[arg(long, value_parser = choice::<sdfc::codegen::SeedData>(), default_value = "auto")]
    pub seed_data: sdfc::codegen::SeedData,
    /// Skip unions' operands by their bounding boxes where they cannot change the union
    /// (exact; costly: operands of several primitives; off by default, as the software
    /// adapter's `if` never skips work: see docs/performance.md).
    #[arg(long, value_parser = choice::<sdfc::codegen::Bounds>(), default_value = "off")]
    pub bounds: sdfc::codegen::Bounds,
    /// The atlas of the atlas views and of `cs_atlas` (default: the first).
    #[arg(long)]
    pub atlas: Option<String>,
    /// Add the multi-scale atlas pass: the compute entry point `cs_coarse`, which the
    /// host dispatches before each frame over a buffer sized for the frame (the
    /// manifest's `coarse` says how), and render entry points that rebuild atlas
    /// samples from it where they agree. It pays on a GPU (0.69-0.98 of the frame on
    /// an NVIDIA H200), not on a software adapter. Nothing changes for a scene whose
    /// materials read no atlas.
    #[arg(long)]
    pub multiscale: bool,
    /// The entry point to translate for GLSL (one per file): vs_main, fs_main, fs_aov,
    /// cs_points, cs_grid, cs_atlas, cs_material or cs_bake (and cs_coarse with
    /// --multiscale).
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
    /// Scene files to check, or folders to check every `.sdf` file below (`-` reads
    /// standard input).
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
    #[command(flatten)]
    pub run_time: params::ParamArgs,
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
    #[arg(long, value_parser = choice::<sdfc::gpu::Backend>(), default_value = "auto")]
    pub backend: sdfc::gpu::Backend,
    /// Also report every seed's own log map, status and offset (`"seeds"`, CPU reference).
    #[arg(long)]
    pub all_seeds: bool,
    /// Search the nearest seed without the early-out of Eq. 35: every seed is walked
    /// with the full D (CPU; for testing the early-out).
    #[arg(long)]
    pub brute_force: bool,
}

/// A scene as read: its text, and the diagnostics of decoding its bytes (invalid UTF-8).
pub struct Source {
    pub text: String,
    pub decoding: Vec<sdfc::Diagnostic>,
}

/// Reads at most `limit + 1` bytes of a file (`-`: standard input), so an over-long
/// input is known to be one without reading all of it. A folder is an error.
pub fn read_bytes(path: &Path, limit: usize) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    let take = limit as u64 + 1;
    if path == Path::new("-") {
        std::io::stdin().lock().take(take).read_to_end(&mut bytes)?;
    } else {
        if std::fs::metadata(path)?.is_dir() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "it is a folder",
            ));
        }
        std::fs::File::open(path)?
            .take(take)
            .read_to_end(&mut bytes)?;
    }
    Ok(bytes)
}

/// Reads a scene file (`-`: standard input). Text over the size limit is read only up to
/// just past it, for the checker to report.
pub fn read_source(path: &Path) -> std::io::Result<Source> {
    let bytes = read_bytes(path, sdfc::syntax::MAX_SOURCE_BYTES)?;
    let (text, decoding) = sdfc::syntax::decode(&bytes);
    Ok(Source { text, decoding })
}

/// Reads a UTF-8 text file of at most `limit` bytes (the `eval` points).
pub fn read_text(path: &Path, limit: usize) -> std::io::Result<String> {
    let bytes = read_bytes(path, limit)?;
    if bytes.len() > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("it is larger than the limit of {limit} bytes"),
        ));
    }
    String::from_utf8(bytes)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e.to_string()))
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
    let Source {
        text: source,
        decoding,
    } = read_source(path).map_err(|e| {
        eprintln!("error: cannot read {name}: {e}");
        std::process::ExitCode::from(exit::USAGE)
    })?;
    let mut analysis = sdfc::driver::check_with(&source, &access(path));
    analysis.add_decoding(decoding);
    sdfc::diagnostic::cap(&mut analysis.diagnostics);
    let color = std::io::IsTerminal::is_terminal(&std::io::stderr())
        && std::env::var_os("NO_COLOR").is_none();
    eprint!(
        "{}",
        sdfc::diagnostic::render(&name, &source, &analysis.diagnostics, color)
    );
    if analysis.has_errors() {
        return Err(std::process::ExitCode::from(exit::SCENE));
    }
    if let Err(e) = params::validate(&analysis.program) {
        eprintln!("error: {e}");
        return Err(std::process::ExitCode::from(exit::USAGE));
    }
    Ok((source, analysis))
}

/// The view of a checked scene: the render item's, or framed on `--shape`.
pub fn view_for(
    analysis: &sdfc::driver::Analysis,
    shape: Option<&str>,
) -> Result<sdfc::view::View, std::process::ExitCode> {
    if analysis.scene.is_none() {
        return Err(std::process::ExitCode::from(exit::SCENE));
    }
    sdfc::view::View::of(analysis, shape).map_err(|e| {
        eprintln!("error: {e}");
        std::process::ExitCode::from(exit::USAGE)
    })
}
