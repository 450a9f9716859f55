//! `sdfc bench`: frame-time ratios measured in one run on one adapter.

use super::{compile, BenchArgs};
use sdfc::codegen::{Bounds, Options, SeedData, WalkForm};
use sdfc::gpu::{self, ViewMode};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// One bench row: pipeline creation, median frame, SDF evaluations per pixel.
#[derive(Debug, Clone, Copy)]
struct Row {
    pipeline: Duration,
    frame: Duration,
    evals_mean: f64,
    evals_p95: f64,
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

pub fn run(args: BenchArgs) -> ExitCode {
    let sweep = args.seed_sweep || args.scene.is_none();
    if args.plot.is_some() && !args.scale && (!sweep || args.lsp_latency || args.bake) {
        eprintln!("error: --plot draws the charts of --scale and --seed-sweep only");
        return ExitCode::from(super::exit::USAGE);
    }
    // The chart's font, before minutes of measuring.
    if let (Some(path), Err(e)) = (
        &args.plot,
        args.plot.as_ref().map_or(Ok(()), |_| super::plot::font()),
    ) {
        eprintln!("error: cannot draw the plot {}: {e}", path.display());
        return ExitCode::from(super::exit::USAGE);
    }
    if args.scale {
        return super::scale::run(&args);
    }
    let scene = match &args.scene {
        Some(s) if args.lsp_latency => {
            return super::latency::run(s, args.edits, args.json.as_deref())
        }
        Some(s) if args.bake => return super::bake::bench(s, &args),
        Some(s) if !args.seed_sweep => s.clone(),
        _ => return super::sweep::run(&args),
    };
    let t = Instant::now();
    let base = Options {
        shape: args.shape.clone(),
        ..Default::default()
    };
    let (source, analysis, unrolled) = match compile::build(&scene, &base) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let compile_time = t.elapsed();
    let name = scene.display().to_string();
    // The other forms from the same analysis: the geometry and lowering ran once.
    let variant = |options: Options| {
        sdfc::driver::compile(&analysis, &options)
            .map(|c| c.module)
            .map_err(|e| compile::report(&name, &source, e))
    };
    let rolled = match variant(Options {
        walk: WalkForm::Loop,
        ..base.clone()
    }) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let plain = match variant(Options {
        plain: true,
        ..base.clone()
    }) {
        Ok(x) => x,
        Err(code) => return code,
    };
    // Every atlas a constant sample: the same shading, shadows and texture reads
    // without the walks (what the atlases cost).
    let constant = match variant(Options {
        walk: WalkForm::Loop,
        constant_uv: true,
        ..base.clone()
    }) {
        Ok(x) => x,
        Err(code) => return code,
    };
    // Without the warm start of Alg. 2's search, to measure what it saves.
    let cold = match variant(Options {
        walk: WalkForm::Loop,
        cold: true,
        ..base.clone()
    }) {
        Ok(x) => x,
        Err(code) => return code,
    };
    // The walks pruned per seed (uv::prune, opt-in), measured against the default loop.
    let pruned = if analysis
        .atlases
        .iter()
        .flatten()
        .any(|a| a.pruning().is_some())
    {
        match variant(Options {
            walk: WalkForm::Loop,
            prune: true,
            ..base.clone()
        }) {
            Ok(m) => Some(m),
            Err(code) => return code,
        }
    } else {
        None
    };
    // The seeds and merge graphs in the tables buffer against baked in, whichever the
    // default picks for the scene's largest atlas, measured against the default loop.
    let most_seeds = analysis
        .atlases
        .iter()
        .flatten()
        .map(|a| a.seeds.len())
        .max();
    let other_seed_data = most_seeds.map(|n| {
        if SeedData::Auto.in_buffer(n) {
            SeedData::Baked
        } else {
            SeedData::Buffer
        }
    });
    let other_form = match other_seed_data {
        Some(seed_data) => match variant(Options {
            walk: WalkForm::Loop,
            seed_data,
            ..base.clone()
        }) {
            Ok(m) => Some(m),
            Err(code) => return code,
        },
        None => None,
    };
    // Unions' operands skipped by their boxes (ir::guard, opt-in): the costly ones, and
    // every one, against none (the default), where the forms differ.
    let mut bounded = Vec::new();
    for (plain, bounds) in [
        (true, Bounds::Costly),
        (false, Bounds::Costly),
        (false, Bounds::All),
    ] {
        match variant(Options {
            walk: WalkForm::Loop,
            plain,
            bounds,
            ..base.clone()
        }) {
            Ok(m) => bounded.push(m),
            Err(code) => return code,
        }
    }
    if bounded[1].wgsl == rolled.wgsl && bounded[2].wgsl == rolled.wgsl {
        bounded.clear();
    }
    // A displaced render target: the same scene with every displacement replaced by its
    // base (the plain textured render), to measure what displacement costs.
    let target = analysis.program.render.as_ref().map(|r| &r.target);
    let undisplaced =
        match target.filter(|t| args.shape.is_none() && sdfc::sema::displaced(t).is_some()) {
            Some(t) => {
                let mut scene = analysis.scene.clone().unwrap_or_default();
                scene.render = sdfc::ir::lower_shape(&sdfc::sema::undisplaced(t));
                let options = Options {
                    walk: WalkForm::Loop,
                    ..base.clone()
                };
                let Some(shape) = scene.render.as_ref() else {
                    eprintln!("error: the undisplaced scene has no render target");
                    return ExitCode::from(super::exit::ICE);
                };
                let target = sdfc::codegen::Rendered { shape, name: None };
                match sdfc::codegen::generate(
                    &analysis.program,
                    &scene,
                    &analysis.atlases,
                    target,
                    &options,
                ) {
                    Ok(m) => Some(m),
                    Err(d) => {
                        eprintln!("error: cannot compile the undisplaced scene: {d:?}");
                        return ExitCode::from(super::exit::ICE);
                    }
                }
            }
            None => None,
        };
    let unrolled = unrolled.module;
    // The same scene with every material's `normal` back to the surface normal: the
    // plain textured render that normal maps are measured against.
    let flat = sdfc::sema::MaterialAttrs::default().normal;
    let normal_maps = analysis
        .program
        .materials
        .iter()
        .any(|m| m.attrs.normal != flat);
    let mut unmapped = Vec::new();
    if normal_maps {
        let mut without = analysis.clone();
        for m in &mut without.program.materials {
            m.attrs.normal = flat.clone();
        }
        for walk in [WalkForm::Unrolled, WalkForm::Loop] {
            let options = Options {
                walk,
                ..base.clone()
            };
            match sdfc::driver::compile(&without, &options) {
                Ok(c) => unmapped.push(c.module),
                Err(e) => return compile::report(&name, &source, e),
            }
        }
    }
    // Every atlas refined (`refine = 1`, `2`), loop walk: what the log map's Newton
    // corrections cost against the scene as written.
    let mut refined = Vec::new();
    if analysis
        .atlases
        .iter()
        .flatten()
        .any(|a| a.params.refine == 0)
    {
        for k in [1, 2] {
            let mut with = analysis.clone();
            for a in with.atlases.iter_mut().flatten() {
                a.params.refine = k;
            }
            let options = Options {
                walk: WalkForm::Loop,
                ..base.clone()
            };
            match sdfc::driver::compile(&with, &options) {
                Ok(c) => refined.push(c.module),
                Err(e) => return compile::report(&name, &source, e),
            }
        }
    }
    let mut view = match super::view_for(&analysis, args.shape.as_deref()) {
        Ok(v) => v,
        Err(code) => return code,
    };
    (view.width, view.height) = args.size.unwrap_or((1920, 1080));
    let gpu = match super::open_gpu(args.backend) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let dir = super::base_dir(&scene);
    let measure = |module: &sdfc::codegen::Module,
                   mode: ViewMode|
     -> Result<(Row, gpu::Renderer), gpu::GpuError> {
        // One pipeline per module, built (not found in the device's cache); a warm-up
        // frame, then the measured ones; then one frame of the evals view for the
        // evaluations per pixel.
        gpu.pipelines.clear();
        let renderer = gpu::Renderer::new(&gpu, module, &dir)?;
        let (_, frames) = renderer.frames(&gpu, &view, mode, 1, args.frames.max(1))?;
        let (evals, _) = renderer.frames(&gpu, &view, ViewMode::Evals, 0, 1)?;
        let (evals_mean, evals_p95, _) = gpu::eval_stats(&evals);
        let row = Row {
            pipeline: renderer.pipeline_time,
            frame: median(frames),
            evals_mean,
            evals_p95,
        };
        Ok((row, renderer))
    };
    // Two pipelines' frames alternated one by one, so that a load that drifts during
    // the run (a shared machine, a software adapter) weighs on both alike: the
    // ratio of their medians.
    let paired = |a: &gpu::Renderer, b: &gpu::Renderer| -> Result<f64, gpu::GpuError> {
        let (mut ta, mut tb) = (Vec::new(), Vec::new());
        for _ in 0..args.frames.max(1) {
            ta.extend(a.frames(&gpu, &view, ViewMode::Color, 0, 1)?.1);
            tb.extend(b.frames(&gpu, &view, ViewMode::Color, 0, 1)?.1);
        }
        Ok(median(ta).as_secs_f64() / median(tb).as_secs_f64())
    };
    let mut rows = vec![
        ("plain sphere trace (no materials)", &plain, ViewMode::Color),
        ("shaded, unrolled walk", &unrolled, ViewMode::Color),
        ("shaded, loop walk", &rolled, ViewMode::Color),
        ("shaded, loop walk, cold start", &cold, ViewMode::Color),
        ("shaded, constant uv (no walks)", &constant, ViewMode::Color),
    ];
    let mut pruned_row = None;
    if let Some(m) = &pruned {
        pruned_row = Some(rows.len());
        rows.push(("shaded, loop walk, pruned", m, ViewMode::Color));
    }
    let mut other_form_row = None;
    if let Some(m) = &other_form {
        other_form_row = Some(rows.len());
        rows.push((
            if other_seed_data == Some(SeedData::Buffer) {
                "shaded, loop walk, seeds in buffer"
            } else {
                "shaded, loop walk, seeds baked in"
            },
            m,
            ViewMode::Color,
        ));
    }
    let mut bounded_rows = None;
    if let [plain_costly, costly, all] = &bounded[..] {
        bounded_rows = Some((rows.len(), rows.len() + 1, rows.len() + 2));
        rows.push(("plain, node bounds (costly)", plain_costly, ViewMode::Color));
        rows.push(("shaded, loop walk, node bounds", costly, ViewMode::Color));
        rows.push(("shaded, loop walk, all bounded", all, ViewMode::Color));
    }
    let mut undisplaced_row = None;
    if let Some(m) = &undisplaced {
        undisplaced_row = Some(rows.len());
        rows.push(("textured, undisplaced, loop walk", m, ViewMode::Color));
    }
    let mut unmapped_rows = None;
    if let [unrolled, rolled] = &unmapped[..] {
        unmapped_rows = Some((rows.len(), rows.len() + 1));
        rows.push((
            "shaded, no normal maps, unrolled",
            unrolled,
            ViewMode::Color,
        ));
        rows.push(("shaded, no normal maps, loop", rolled, ViewMode::Color));
    }
    let mut refined_rows = None;
    if let [one, two] = &refined[..] {
        refined_rows = Some((rows.len(), rows.len() + 1));
        rows.push(("shaded, loop walk, refine = 1", one, ViewMode::Color));
        rows.push(("shaded, loop walk, refine = 2", two, ViewMode::Color));
    }
    let mut results = Vec::new();
    let mut renderers = Vec::new();
    for (name, module, mode) in rows {
        match measure(module, mode) {
            Ok((r, renderer)) => {
                results.push((name, r));
                renderers.push(renderer);
            }
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(super::exit::gpu(&e));
            }
        }
    }
    // The loop walk's pipeline built, then asked for again: the in-process cache
    // (gpu::cache) that a viewer reload with unchanged WGSL hits.
    gpu.pipelines.clear();
    let again = gpu::Renderer::new(&gpu, &rolled, &dir)
        .and_then(|built| Ok((built, gpu::Renderer::new(&gpu, &rolled, &dir)?)));
    let (built, again) = match again {
        Ok((a, b)) => (a.pipeline_time, b.pipeline_time),
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(super::exit::gpu(&e));
        }
    };
    // The comparisons whose frames are alternated one by one (with, without): the warm
    // start against none; the scene against its constant-uv twin (row 4), unrolled and
    // loop, which is what the atlases cost with everything else equal; refined against
    // the scene's own; normal maps against none.
    let mut pairs = vec![
        ("warm ÷ cold start, loop", 2, 3),
        ("textured ÷ constant uv, unrolled", 1, 4),
        ("textured ÷ constant uv, loop", 2, 4),
    ];
    if let Some(k) = other_form_row {
        pairs.push(if other_seed_data == Some(SeedData::Buffer) {
            ("seeds in buffer ÷ baked, loop", k, 2)
        } else {
            ("seeds baked ÷ in buffer, loop", k, 2)
        });
    }
    if let Some(k) = pruned_row {
        pairs.push(("pruned ÷ unpruned walks, loop", k, 2));
    }
    if let Some((plain_costly, costly, all)) = bounded_rows {
        pairs.push(("node bounds ÷ none, plain", plain_costly, 0));
        pairs.push(("node bounds ÷ none, loop", costly, 2));
        pairs.push(("all bounded ÷ none, loop", all, 2));
    }
    if let Some((one, two)) = refined_rows {
        pairs.push(("refine = 1 ÷ 0, loop", one, 2));
        pairs.push(("refine = 2 ÷ 0, loop", two, 2));
    }
    if let Some((no_unrolled, no_loop)) = unmapped_rows {
        pairs.push(("normal maps ÷ none, unrolled", 1, no_unrolled));
        pairs.push(("normal maps ÷ none, loop", 2, no_loop));
    }
    let mut alternated = Vec::new();
    for (label, with, without) in pairs {
        match paired(&renderers[with], &renderers[without]) {
            Ok(r) => alternated.push((label, r, "frames alternated")),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(super::exit::gpu(&e));
            }
        }
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    println!("scene:     {}", scene.display());
    println!("adapter:   {}", gpu.describe());
    println!(
        "size:      {}x{}, median of {} frames",
        view.width,
        view.height,
        args.frames.max(1)
    );
    println!(
        "compile:   {:.2} ms (parse → validated WGSL)",
        ms(compile_time)
    );
    for (name, r) in &results {
        println!(
            "{name:34} pipeline {:9.2} ms   frame {:9.2} ms   evals/px {:7.1} (p95 {:.0})",
            ms(r.pipeline),
            ms(r.frame),
            r.evals_mean,
            r.evals_p95
        );
    }
    println!(
        "{:34} pipeline {:9.2} ms   (built again: {:.2} ms)",
        "loop walk, same WGSL again (cache)",
        ms(again),
        ms(built)
    );
    let (plain, unrolled_r, loop_r) = (results[0].1, results[1].1, results[2].1);
    // (label, value, how it was measured)
    let mut ratios: Vec<(&str, f64, &str)> = vec![
        (
            "shaded ÷ plain, unrolled",
            ms(unrolled_r.frame) / ms(plain.frame),
            "",
        ),
        (
            "shaded ÷ plain, loop",
            ms(loop_r.frame) / ms(plain.frame),
            "",
        ),
        (
            "unrolled ÷ loop, frame",
            ms(unrolled_r.frame) / ms(loop_r.frame),
            "",
        ),
        (
            "unrolled ÷ loop, pipeline",
            ms(unrolled_r.pipeline) / ms(loop_r.pipeline),
            "",
        ),
    ];
    if let Some((_, undisplaced)) = undisplaced_row.map(|k| results[k]) {
        // Displacements and shell maps alike are replaced by their base.
        ratios.push((
            "displaced ÷ undisplaced, loop",
            ms(loop_r.frame) / ms(undisplaced.frame),
            "",
        ));
    }
    ratios.extend(alternated);
    if let Some(r) = analysis
        .scene
        .as_ref()
        .and_then(|scene| sdfc::driver::pick_shape(scene, args.shape.as_deref()).ok())
        .and_then(cpu_bounds_ratio)
    {
        ratios.push(("CPU reference, node bounds ÷ none", r, "f64, alternated"));
    }
    for (label, value, how) in &ratios {
        let how = if how.is_empty() {
            String::new()
        } else {
            format!(" ({how})")
        };
        println!("ratio {:34} {value:.2}{how}", format!("{label}:"));
    }
    if let Some(path) = &args.json {
        let json = serde_json::json!({
            "scene": scene.display().to_string(),
            "adapter": gpu.describe(),
            "size": [view.width, view.height],
            "frames": args.frames.max(1),
            "compile_ms": ms(compile_time),
            "pipeline_cached_ms": ms(again),
            "pipeline_rebuilt_ms": ms(built),
            "rows": results.iter().map(|(name, r)| serde_json::json!({
                "name": name,
                "pipeline_ms": ms(r.pipeline),
                "frame_ms": ms(r.frame),
                "evals_per_pixel_mean": r.evals_mean,
                "evals_per_pixel_p95": r.evals_p95,
            })).collect::<Vec<_>>(),
            "ratios": ratios.iter().map(|(label, value, how)| serde_json::json!({
                "name": label,
                "value": value,
                "measured": if how.is_empty() { "one after the other" } else { how },
            })).collect::<Vec<_>>(),
        });
        if let Err(code) = super::report::write_json(path, &json) {
            return code;
        }
    }
    ExitCode::SUCCESS
}

/// The CPU reference with its unions' guards (`ir::guard`, always on) against every
/// operand evaluated: 100,000 points of the shape's framing box, five rounds alternated,
/// the ratio of the medians. None when no union is guarded.
fn cpu_bounds_ratio(shape: &sdfc::ir::Shape) -> Option<f64> {
    use glam::DVec3;
    use sdfc::ir::{eval, NodeId};
    (0..shape.nodes.len()).find(|&i| shape.guard(NodeId::new(i)).is_some())?;
    let b = shape.framing_bounds();
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut unit = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let points: Vec<DVec3> = (0..100_000)
        .map(|_| b.min + (b.max - b.min) * DVec3::new(unit(), unit(), unit()))
        .collect();
    let time = |f: &dyn Fn(DVec3) -> f64| {
        let t = Instant::now();
        let sum: f64 = points.iter().map(|p| f(*p)).sum();
        std::hint::black_box(sum);
        t.elapsed()
    };
    let (mut guarded, mut full) = (Vec::new(), Vec::new());
    for _ in 0..5 {
        guarded.push(time(&|p| eval::eval_blend(shape, p).0));
        full.push(time(&|p| eval::eval_unguarded(shape, p).0));
    }
    Some(median(guarded).as_secs_f64() / median(full).as_secs_f64())
}
