//! `sdfc render`: a scene → PNG (and float EXR AOVs), headless, through wgpu.

use super::frame::write_frame;
use super::{compile, RenderArgs};
use sdfc::gpu::{self, ViewMode};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, found {s:?}"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!("size {s:?} must be between 1x1 and 16384x16384"));
    }
    Ok((w, h))
}

/// Parses `NAME=FILE.exr`.
pub fn parse_aov(s: &str) -> Result<(String, PathBuf), String> {
    let (name, file) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=FILE.exr, found {s:?}"))?;
    if !["depth", "normal", "position", "steps", "uv"].contains(&name) {
        return Err(format!(
            "unknown AOV {name:?}: choose depth, normal, position, steps or uv"
        ));
    }
    Ok((name.to_string(), PathBuf::from(file)))
}

pub fn run(args: RenderArgs) -> ExitCode {
    args.run_time.install();
    if is_glb(&args.scene) {
        return super::render_mesh::run(args);
    }
    if args.camera_from.is_some() {
        eprintln!(
            "error: --camera-from is for rendering a baked mesh (.glb); a scene has its own camera"
        );
        return ExitCode::from(super::exit::USAGE);
    }
    if args.filter.is_some() {
        eprintln!("error: --filter is for rendering a baked mesh (.glb): a scene has no atlas image to filter");
        return ExitCode::from(super::exit::USAGE);
    }
    if !args.view.for_scene() {
        eprintln!(
            "error: a scene has no {} view (it is a baked mesh's: render a .glb)",
            format!("{:?}", args.view).to_ascii_lowercase()
        );
        return ExitCode::from(super::exit::USAGE);
    }
    let compile_start = Instant::now();
    let mut options = sdfc::codegen::Options {
        walk: args.walk.first(),
        seed_grid: args.seed_grid,
        atlas: args.atlas.clone(),
        plain: false,
        cold: false,
        constant_uv: false,
        unions_as_code: false,
        prune: args.prune,
        seed_data: args.seed_data,
        bounds: args.bounds,
        differences: args.gradients.differences(),
        tiles: !args.no_tiles,
        multiscale: args.multiscale.first(),
    };
    let (source, analysis, mut compiled) =
        match compile::build(&args.scene, args.shape.as_deref(), &options) {
            Ok(x) => x,
            Err(code) => return code,
        };
    let mut compile_time = compile_start.elapsed();
    let mut view = match super::view_for(&analysis, args.shape.as_deref()) {
        Ok(v) => v,
        Err(code) => return code,
    };
    view.atlas_aov = args.aov.iter().any(|(n, _)| n == "uv");
    if let Some((w, h)) = args.size {
        view.width = w;
        view.height = h;
    }
    let gpu = match super::open_gpu(args.backend) {
        Ok(g) => g,
        Err(code) => return code,
    };
    // `--walk auto` on a GPU: the checked scene generated again with the unrolled walk
    // (code generation and naga's validation, no parse or atlas preparation), where it
    // has an atlas to walk; the loop stays where the unrolled module is too large.
    let walks = !analysis.program.atlases.is_empty();
    if walks
        && (args.walk.on(&gpu) != options.walk || args.multiscale.on(&gpu) != options.multiscale)
    {
        let again = Instant::now();
        let unrolled = sdfc::codegen::Options {
            walk: args.walk.on(&gpu),
            multiscale: args.multiscale.on(&gpu),
            ..options.clone()
        };
        match sdfc::driver::compile_shape(&analysis, args.shape.as_deref(), &unrolled) {
            Ok(c) => (compiled, options) = (c, unrolled),
            Err(sdfc::driver::CompileError::Scene(d))
                if d.iter().all(|d| d.code == sdfc::codes::E_INLINED_SIZE) =>
            {
                eprintln!(
                    "note: the unrolled walk is too large here (E0118); the loop walk is used"
                );
            }
            Err(e) => return compile::report(&args.scene.display().to_string(), &source, e),
        }
        compile_time += again.elapsed();
    }
    let module = &compiled.module;
    if args.view == ViewMode::Walked && module.coarse_slots == 0 {
        eprintln!(
            "note: the multi-scale atlas pass is off here (--multiscale {}), so the walked view shows no rebuilt pixel: every atlas sample walks; --multiscale on runs it",
            args.multiscale
        );
    }
    if let Some(seconds) = args.animate {
        if !args.aov.is_empty() || args.timings {
            eprintln!("error: --animate writes colour frames only (no --aov, no --timings)");
            return ExitCode::from(super::exit::USAGE);
        }
        return super::animate::run(&args, &gpu, module, &view, seconds);
    }
    let frame = match gpu::render(
        &gpu,
        module,
        &view,
        args.view,
        &super::base_dir(&args.scene),
    ) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(super::exit::gpu(&e));
        }
    };
    // Whether any atlas walks on its forward derivative: not where none of their
    // fields has one (a displacement, a shell map or a group: ir::dual::supported).
    let forward = !options.differences
        && analysis
            .atlases
            .iter()
            .flatten()
            .any(|a| a.params.exact_gradient);
    let timings = args.timings.then(|| {
        let mut t = format!(
            "adapter:   {}\ncompile:   {:.2} ms (parse → validated WGSL{})\n",
            gpu.describe(),
            compile_time.as_secs_f64() * 1e3,
            if walks {
                format!(
                    "; {} walk, {}",
                    options.walk,
                    if forward {
                        "forward derivatives"
                    } else {
                        "differences"
                    }
                )
            } else {
                String::new()
            }
        );
        t.push_str(&view_stats(args.view, &frame));
        t
    });
    write_frame(&args, &frame, timings)
}

/// The `--timings` lines of the views that count something per pixel (walked, evals).
fn view_stats(view: ViewMode, frame: &gpu::Frame) -> String {
    let mut out = String::new();
    if view == ViewMode::Walked {
        let (walked, rebuilt) = gpu::walked_stats(frame);
        out.push_str(&format!(
        "walked:    {walked} pixels walked an atlas sample, {rebuilt} rebuilt every one ({:.1} % of the pixels that read one walked)\n",
        100.0 * walked as f64 / (walked + rebuilt).max(1) as f64
        ));
    }
    if view == ViewMode::Evals {
        let (mean, p95, max) = gpu::eval_stats(frame);
        out.push_str(&format!(
            "evals:     {mean:.1} per pixel (mean), {p95:.0} (95th percentile), {max:.0} (max)\n"
        ));
    }
    out
}

/// Whether a path names a baked mesh (`.glb`, any case).
pub fn is_glb(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"))
}
