//! `sdfc bench`: frame-time ratios measured in one run on one adapter.

use super::{compile, BenchArgs};
use sdfc::codegen::{Bounds, Module, Options, SeedData, WalkForm};
use sdfc::driver::Analysis;
use sdfc::gpu::{self, Gpu, GpuError, Renderer, ViewMode};
use sdfc::view::View;
use std::path::Path;
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
    if let Err(code) = check_plot(&args).and_then(|()| check_outputs(&args)) {
        return code;
    }
    // (clap's `requires` does not hold where --bake conflicts with a flag given.)
    let bake_flags = [
        ("--atlas-size", args.atlas_size.is_some()),
        ("--bake-layout", args.bake_layout.is_some()),
        ("--bake-texels", args.bake_texels.is_some()),
        ("--bake-bounds", !args.bake_bounds.is_empty()),
    ];
    if let (false, Some((flag, _))) = (args.bake, bake_flags.iter().find(|f| f.1)) {
        eprintln!("error: {flag} is an option of --bake, which bakes the scene: it needs --bake");
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
    match frame_bench(&args, &scene) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

/// The outputs (`--json`, `--plot`) checked before minutes of measuring: each can be
/// written, neither names the other nor the scene.
fn check_outputs(args: &BenchArgs) -> Result<(), ExitCode> {
    let outputs: Vec<(&str, &std::path::Path)> = [("--json", &args.json), ("--plot", &args.plot)]
        .into_iter()
        .filter_map(|(flag, p)| Some((flag, p.as_deref()?)))
        .collect();
    let inputs: Vec<(&str, &std::path::Path)> =
        args.scene.iter().map(|s| ("scene", s.as_path())).collect();
    let refused = sdfc::fsutil::distinct_outputs(&outputs, &inputs)
        .err()
        .or_else(|| {
            outputs.iter().find_map(|(_, p)| {
                sdfc::fsutil::check_writable(p)
                    .err()
                    .map(|e| format!("cannot write {}: {e}", p.display()))
            })
        });
    match refused {
        Some(e) => {
            eprintln!("error: {e}");
            Err(ExitCode::from(super::exit::USAGE))
        }
        None => Ok(()),
    }
}

/// `--plot` only with the benchmarks that draw charts, and its font found before
/// minutes of measuring.
fn check_plot(args: &BenchArgs) -> Result<(), ExitCode> {
    let sweep = args.seed_sweep || args.scene.is_none();
    if args.plot.is_some() && !args.scale && (!sweep || args.lsp_latency || args.bake) {
        eprintln!("error: --plot draws the charts of --scale and --seed-sweep only");
        return Err(ExitCode::from(super::exit::USAGE));
    }
    // The chart's font, before minutes of measuring.
    if let (Some(path), Err(e)) = (
        &args.plot,
        args.plot.as_ref().map_or(Ok(()), |_| super::plot::font()),
    ) {
        eprintln!("error: cannot draw the plot {}: {e}", path.display());
        return Err(ExitCode::from(super::exit::USAGE));
    }
    Ok(())
}

/// The frame benchmark of one scene: every form of it measured on the GPU, the rows
/// and their ratios printed (and written as JSON with `--json`).
fn frame_bench(args: &BenchArgs, scene: &Path) -> Result<(), ExitCode> {
    let t = Instant::now();
    // As `sdfc render` draws it: large unions traced per screen tile.
    let base = Options {
        tiles: true,
        ..Default::default()
    };
    let (source, analysis, unrolled) = compile::build(scene, args.shape.as_deref(), &base)?;
    let compile_time = t.elapsed();
    let name = scene.display().to_string();
    let from = Source {
        analysis: &analysis,
        shape: args.shape.as_deref(),
        name: &name,
        text: &source,
        base: &base,
    };
    let moving = super::bench_params::recompute_times(&unrolled.module);
    let moving = super::bench_params::line(&unrolled.module, &moving);
    let forms = Forms::compile(&from, args, unrolled.module)?;
    let mut view = super::view_for(&analysis, args.shape.as_deref())?;
    (view.width, view.height) = args.size.unwrap_or((1920, 1080));
    let gpu = super::open_gpu(args.backend)?;
    let dir = super::base_dir(scene);
    let rig = Rig {
        gpu: &gpu,
        view: &view,
        dir: &dir,
        frames: args.frames.max(1),
    };
    let rows = Rows::new(&forms);
    let (results, renderers) = rig.measure_rows(&rows.list).map_err(gpu_failed)?;
    let (built, again) = rig.cached(&forms.rolled).map_err(gpu_failed)?;
    let mut alternated = Vec::new();
    for (label, with, without) in rows.pairs(forms.other_seed_data()) {
        let r = rig
            .paired(&renderers[with], &renderers[without])
            .map_err(gpu_failed)?;
        alternated.push((label, r, "frames alternated"));
    }
    // renderers[2]: the loop walk's row.
    let small = rig.small_frames(&renderers[2]).map_err(gpu_failed)?;
    alternated.push((
        "per pixel, a quarter the side ÷ full size, loop",
        small,
        "a fixed cost a frame raises it",
    ));
    let report = Report {
        scene: name,
        adapter: gpu.describe(),
        size: [view.width, view.height],
        frames: rig.frames,
        compile_time,
        results,
        built,
        again,
    };
    report.print_rows();
    if let Some(line) = moving {
        println!("{line}");
    }
    let ratios = report.ratios(rows.undisplaced, alternated, &analysis, args);
    print_ratios(&ratios);
    if let Some(path) = &args.json {
        super::report::write_json(path, &report.json(&ratios))?;
    }
    Ok(())
}

/// A GPU failure printed, as its exit status.
fn gpu_failed(e: GpuError) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(super::exit::gpu(&e))
}

/// What the forms of a scene are compiled from: its analysis, its name and text (for
/// the error reports) and the options as given.
struct Source<'a> {
    analysis: &'a Analysis,
    /// The `let` shape measured instead of the render item's target (`--shape`).
    shape: Option<&'a str>,
    name: &'a str,
    text: &'a str,
    base: &'a Options,
}

impl Source<'_> {
    /// The scene with other options, from the same analysis: the geometry and the
    /// lowering ran once.
    fn variant(&self, options: Options) -> Result<Module, ExitCode> {
        self.compile(self.analysis, options)
    }

    /// A loop walk with `edit` made to the options as given.
    fn looped(&self, edit: impl FnOnce(&mut Options)) -> Result<Module, ExitCode> {
        let mut options = Options {
            walk: WalkForm::Loop,
            ..self.base.clone()
        };
        edit(&mut options);
        self.variant(options)
    }

    /// `analysis` (this scene's, changed) compiled with `options`.
    fn compile(&self, analysis: &Analysis, options: Options) -> Result<Module, ExitCode> {
        sdfc::driver::compile_shape(analysis, self.shape, &options)
            .map(|c| c.module)
            .map_err(|e| compile::report(self.name, self.text, e))
    }
}

/// The forms of the scene that the bench measures against each other.
struct Forms {
    plain: Module,
    unrolled: Module,
    rolled: Module,
    cold: Module,
    constant: Module,
    pruned: Option<Module>,
    /// The seeds where the default does not put them, and that form.
    other_form: Option<(SeedData, Module)>,
    /// Plain with the costly bounds, loop with the costly bounds, loop with all.
    bounded: Vec<Module>,
    undisplaced: Option<Module>,
    /// Without normal maps: unrolled, loop.
    unmapped: Vec<Module>,
    /// `refine = 1`, `2`.
    refined: Vec<Module>,
    /// The walks on central differences where the compiler differentiates forward.
    differenced: Option<Module>,
    /// The loop walk with the multi-scale atlas pass, where materials read an atlas.
    multiscaled: Option<Module>,
}

impl Forms {
    fn compile(from: &Source, args: &BenchArgs, unrolled: Module) -> Result<Forms, ExitCode> {
        let rolled = from.looped(|_| {})?;
        let plain = from.variant(Options {
            plain: true,
            ..from.base.clone()
        })?;
        // Every atlas a constant sample: the same shading, shadows and texture reads
        // without the walks (what the atlases cost).
        let constant = from.looped(|o| o.constant_uv = true)?;
        // Without the warm start of Alg. 2's search, to measure what it saves.
        let cold = from.looped(|o| o.cold = true)?;
        let pruned = pruned_form(from)?;
        let other_form = other_seed_form(from)?;
        let bounded = bounded_forms(from, &rolled)?;
        let undisplaced = undisplaced_form(from, args)?;
        let unmapped = unmapped_forms(from)?;
        let refined = refined_forms(from)?;
        let differenced = differenced_form(from)?;
        // The multi-scale atlas pass (`render --multiscale on`), where it has one.
        let multiscaled =
            Some(from.looped(|o| o.multiscale = true)?).filter(|m| m.coarse_slots > 0);
        Ok(Forms {
            plain,
            unrolled,
            rolled,
            cold,
            constant,
            pruned,
            other_form,
            bounded,
            undisplaced,
            unmapped,
            refined,
            differenced,
            multiscaled,
        })
    }

    fn other_seed_data(&self) -> Option<SeedData> {
        self.other_form.as_ref().map(|(data, _)| *data)
    }
}

/// The loop walk on central differences of the whole field (`Options::differences`),
/// measured against forward derivatives (the default); None when no atlas has them.
fn differenced_form(from: &Source) -> Result<Option<Module>, ExitCode> {
    let exact = from
        .analysis
        .atlases
        .iter()
        .flatten()
        .any(|a| a.params.exact_gradient);
    if !exact {
        return Ok(None);
    }
    from.looped(|o| o.differences = true).map(Some)
}

/// The walks pruned per seed (uv::prune, opt-in), measured against the default loop;
/// None when no atlas prunes.
fn pruned_form(from: &Source) -> Result<Option<Module>, ExitCode> {
    let atlases = || from.analysis.atlases.iter().flatten();
    if !atlases().any(|a| a.pruning().is_some()) {
        return Ok(None);
    }
    from.looped(|o| o.prune = true).map(Some)
}

/// The seeds and merge graphs in the tables buffer against baked in, whichever the
/// default picks for the scene's largest atlas, measured against the default loop;
/// None without atlases.
fn other_seed_form(from: &Source) -> Result<Option<(SeedData, Module)>, ExitCode> {
    let most_seeds = from
        .analysis
        .atlases
        .iter()
        .flatten()
        .map(|a| a.seeds.len())
        .max();
    let Some(n) = most_seeds else {
        return Ok(None);
    };
    let seed_data = if SeedData::Auto.in_buffer(n) {
        SeedData::Baked
    } else {
        SeedData::Buffer
    };
    let module = from.looped(|o| o.seed_data = seed_data)?;
    Ok(Some((seed_data, module)))
}

/// Unions' operands skipped by their boxes (ir::guard, opt-in): the costly ones, and
/// every one, against none (the default), where the forms differ from `rolled`.
fn bounded_forms(from: &Source, rolled: &Module) -> Result<Vec<Module>, ExitCode> {
    let mut bounded = Vec::new();
    for (plain, bounds) in [
        (true, Bounds::Costly),
        (false, Bounds::Costly),
        (false, Bounds::All),
    ] {
        bounded.push(from.looped(|o| {
            o.plain = plain;
            o.bounds = bounds;
        })?);
    }
    if bounded[1].wgsl == rolled.wgsl && bounded[2].wgsl == rolled.wgsl {
        bounded.clear();
    }
    Ok(bounded)
}

/// A displaced render target: the same scene with every displacement replaced by its
/// base (the plain textured render), to measure what displacement costs.
fn undisplaced_form(from: &Source, args: &BenchArgs) -> Result<Option<Module>, ExitCode> {
    let analysis = from.analysis;
    let target = analysis.program.render.as_ref().map(|r| &r.target);
    let Some(t) = target.filter(|t| args.shape.is_none() && sdfc::sema::displaced(t).is_some())
    else {
        return Ok(None);
    };
    let mut scene = analysis.scene.clone().unwrap_or_default();
    scene.render = sdfc::ir::lower_shape(&sdfc::sema::undisplaced(t));
    let options = Options {
        walk: WalkForm::Loop,
        ..from.base.clone()
    };
    let Some(shape) = scene.render.as_ref() else {
        eprintln!("error: the undisplaced scene has no render target");
        return Err(ExitCode::from(super::exit::ICE));
    };
    let target = sdfc::codegen::Rendered { shape, name: None };
    match sdfc::codegen::generate(
        &analysis.program,
        &scene,
        &analysis.atlases,
        target,
        &options,
    ) {
        Ok(m) => Ok(Some(m)),
        Err(d) => {
            eprintln!("error: cannot compile the undisplaced scene: {d:?}");
            Err(ExitCode::from(super::exit::ICE))
        }
    }
}

/// The same scene with every material's `normal` back to the surface normal, unrolled
/// and loop: the plain textured render that normal maps are measured against. Empty
/// without normal maps.
fn unmapped_forms(from: &Source) -> Result<Vec<Module>, ExitCode> {
    let flat = sdfc::sema::MaterialAttrs::default().normal;
    let program = &from.analysis.program;
    if !program.materials.iter().any(|m| m.attrs.normal != flat) {
        return Ok(Vec::new());
    }
    let mut without = from.analysis.clone();
    for m in &mut without.program.materials {
        m.attrs.normal = flat.clone();
    }
    let mut unmapped = Vec::new();
    for walk in [WalkForm::Unrolled, WalkForm::Loop] {
        let options = Options {
            walk,
            ..from.base.clone()
        };
        unmapped.push(from.compile(&without, options)?);
    }
    Ok(unmapped)
}

/// Every atlas refined (`refine = 1`, `2`), loop walk: what the log map's Newton
/// corrections cost against the scene as written. Empty when every atlas refines.
fn refined_forms(from: &Source) -> Result<Vec<Module>, ExitCode> {
    let atlases = || from.analysis.atlases.iter().flatten();
    if !atlases().any(|a| a.params.refine == 0) {
        return Ok(Vec::new());
    }
    let mut refined = Vec::new();
    for k in [1, 2] {
        let mut with = from.analysis.clone();
        for a in with.atlases.iter_mut().flatten() {
            a.params.refine = k;
        }
        let options = Options {
            walk: WalkForm::Loop,
            ..from.base.clone()
        };
        refined.push(from.compile(&with, options)?);
    }
    Ok(refined)
}

/// The rows measured, in order (the first five always: plain, unrolled, loop, cold
/// start, constant uv), and where the optional ones are.
struct Rows<'a> {
    list: Vec<(&'static str, &'a Module, ViewMode)>,
    pruned: Option<usize>,
    other_form: Option<usize>,
    bounded: Option<(usize, usize, usize)>,
    undisplaced: Option<usize>,
    unmapped: Option<(usize, usize)>,
    refined: Option<(usize, usize)>,
    differenced: Option<usize>,
    multiscaled: Option<usize>,
}

impl<'a> Rows<'a> {
    fn new(forms: &'a Forms) -> Rows<'a> {
        let mut list = vec![
            (
                "plain sphere trace (no materials)",
                &forms.plain,
                ViewMode::Color,
            ),
            ("shaded, unrolled walk", &forms.unrolled, ViewMode::Color),
            ("shaded, loop walk", &forms.rolled, ViewMode::Color),
            (
                "shaded, loop walk, cold start",
                &forms.cold,
                ViewMode::Color,
            ),
            (
                "shaded, constant uv (no walks)",
                &forms.constant,
                ViewMode::Color,
            ),
        ];
        let mut push = |rows: &[(&'static str, &'a Module)]| {
            let first = list.len();
            list.extend(rows.iter().map(|&(name, m)| (name, m, ViewMode::Color)));
            first
        };
        let pruned = forms
            .pruned
            .as_ref()
            .map(|m| push(&[("shaded, loop walk, pruned", m)]));
        let other_form = forms.other_form.as_ref().map(|(data, m)| {
            let name = if *data == SeedData::Buffer {
                "shaded, loop walk, seeds in buffer"
            } else {
                "shaded, loop walk, seeds baked in"
            };
            push(&[(name, m)])
        });
        let bounded = match &forms.bounded[..] {
            [plain_costly, costly, all] => {
                let k = push(&[
                    ("plain, node bounds (costly)", plain_costly),
                    ("shaded, loop walk, node bounds", costly),
                    ("shaded, loop walk, all bounded", all),
                ]);
                Some((k, k + 1, k + 2))
            }
            _ => None,
        };
        let undisplaced = forms
            .undisplaced
            .as_ref()
            .map(|m| push(&[("textured, undisplaced, loop walk", m)]));
        let unmapped = match &forms.unmapped[..] {
            [unrolled, rolled] => {
                let k = push(&[
                    ("shaded, no normal maps, unrolled", unrolled),
                    ("shaded, no normal maps, loop", rolled),
                ]);
                Some((k, k + 1))
            }
            _ => None,
        };
        let differenced = forms
            .differenced
            .as_ref()
            .map(|m| push(&[("shaded, loop walk, differences", m)]));
        let multiscaled = forms
            .multiscaled
            .as_ref()
            .map(|m| push(&[("shaded, loop walk, multi-scale pass", m)]));
        let refined = match &forms.refined[..] {
            [one, two] => {
                let k = push(&[
                    ("shaded, loop walk, refine = 1", one),
                    ("shaded, loop walk, refine = 2", two),
                ]);
                Some((k, k + 1))
            }
            _ => None,
        };
        Rows {
            list,
            pruned,
            other_form,
            bounded,
            undisplaced,
            unmapped,
            refined,
            differenced,
            multiscaled,
        }
    }

    /// The comparisons whose frames are alternated one by one (label, with, without):
    /// the warm start against none; the scene against its constant-uv twin (row 4),
    /// unrolled and loop, which is what the atlases cost with everything else equal;
    /// refined against the scene's own; normal maps against none.
    fn pairs(&self, other_seed_data: Option<SeedData>) -> Vec<(&'static str, usize, usize)> {
        let mut pairs = vec![
            ("warm ÷ cold start, loop", 2, 3),
            ("textured ÷ constant uv, unrolled", 1, 4),
            ("textured ÷ constant uv, loop", 2, 4),
        ];
        if let Some(k) = self.other_form {
            pairs.push(if other_seed_data == Some(SeedData::Buffer) {
                ("seeds in buffer ÷ baked, loop", k, 2)
            } else {
                ("seeds baked ÷ in buffer, loop", k, 2)
            });
        }
        if let Some(k) = self.pruned {
            pairs.push(("pruned ÷ unpruned walks, loop", k, 2));
        }
        if let Some(k) = self.differenced {
            pairs.push(("differences ÷ forward derivatives, loop", k, 2));
        }
        if let Some(k) = self.multiscaled {
            pairs.push(("multi-scale pass ÷ per-pixel walk, loop", k, 2));
            pairs.push(("textured ÷ constant uv, loop, multi-scale pass", k, 4));
        }
        if let Some((plain_costly, costly, all)) = self.bounded {
            pairs.push(("node bounds ÷ none, plain", plain_costly, 0));
            pairs.push(("node bounds ÷ none, loop", costly, 2));
            pairs.push(("all bounded ÷ none, loop", all, 2));
        }
        if let Some((one, two)) = self.refined {
            pairs.push(("refine = 1 ÷ 0, loop", one, 2));
            pairs.push(("refine = 2 ÷ 0, loop", two, 2));
        }
        if let Some((no_unrolled, no_loop)) = self.unmapped {
            pairs.push(("normal maps ÷ none, unrolled", 1, no_unrolled));
            pairs.push(("normal maps ÷ none, loop", 2, no_loop));
        }
        pairs
    }
}

/// Where the frames are measured: the adapter, the view, the scene's folder (for its
/// textures) and the frames per measurement.
struct Rig<'a> {
    gpu: &'a Gpu,
    view: &'a View,
    dir: &'a Path,
    frames: u32,
}

impl Rig<'_> {
    /// One pipeline per module, built (not found in the device's cache); a warm-up
    /// frame, then the measured ones; then one frame of the evals view for the
    /// evaluations per pixel.
    fn measure(&self, module: &Module, mode: ViewMode) -> Result<(Row, Renderer), GpuError> {
        let (gpu, view) = (self.gpu, self.view);
        gpu.pipelines.clear();
        let renderer = Renderer::new(gpu, module, self.dir)?;
        let (_, frames) = renderer.frames(gpu, view, mode, 1, self.frames)?;
        let (evals, _) = renderer.frames(gpu, view, ViewMode::Evals, 0, 1)?;
        let (evals_mean, evals_p95, _) = gpu::eval_stats(&evals);
        let row = Row {
            pipeline: renderer.pipeline_time,
            frame: median(frames),
            evals_mean,
            evals_p95,
        };
        Ok((row, renderer))
    }

    /// Every row measured, in order, with the renderers for the alternated pairs.
    fn measure_rows(
        &self,
        rows: &[(&'static str, &Module, ViewMode)],
    ) -> Result<Measured, GpuError> {
        let mut results = Vec::new();
        let mut renderers = Vec::new();
        for &(name, module, mode) in rows {
            let (r, renderer) = self.measure(module, mode)?;
            // As it goes, on standard error: a run cut short (a device lent for
            // minutes) keeps the rows it measured; the table follows on stdout.
            eprintln!(
                "measured: {name}: pipeline {:.2} ms, frame {:.2} ms",
                ms(r.pipeline),
                ms(r.frame)
            );
            results.push((name, r));
            renderers.push(renderer);
        }
        Ok((results, renderers))
    }

    /// The loop walk's pipeline built, then asked for again: the in-process cache
    /// (gpu::cache) that a viewer reload with unchanged WGSL hits. (built, again).
    fn cached(&self, rolled: &Module) -> Result<(Duration, Duration), GpuError> {
        let gpu = self.gpu;
        gpu.pipelines.clear();
        let built = Renderer::new(gpu, rolled, self.dir)?;
        let again = Renderer::new(gpu, rolled, self.dir)?;
        Ok((built.pipeline_time, again.pipeline_time))
    }

    /// A frame's cost per pixel at a quarter of the view's side against the full view,
    /// frames alternated: low when a frame's cost is its pixels' (2.3 for the sphere
    /// at 270×270 on lavapipe, whose 64-pixel tiles and threads fill worse at 67×67),
    /// higher when every frame pays a fixed cost (lavapipe's compile at every draw,
    /// 10-60 ms a frame at any size: with it the sphere's loop frame cost 4.3× as much
    /// a pixel at 135×135 as at 540×540; docs/performance.md).
    fn small_frames(&self, renderer: &Renderer) -> Result<f64, GpuError> {
        let (gpu, view) = (self.gpu, self.view);
        let mut small = view.clone();
        (small.width, small.height) = ((view.width / 4).max(1), (view.height / 4).max(1));
        let (mut full, mut quarter) = (Vec::new(), Vec::new());
        for _ in 0..self.frames {
            full.extend(renderer.frames(gpu, view, ViewMode::Color, 0, 1)?.1);
            quarter.extend(renderer.frames(gpu, &small, ViewMode::Color, 0, 1)?.1);
        }
        let pixels = |v: &View| f64::from(v.width) * f64::from(v.height);
        let per_pixel = |times: Vec<Duration>, v: &View| median(times).as_secs_f64() / pixels(v);
        Ok(per_pixel(quarter, &small) / per_pixel(full, view))
    }

    /// Two pipelines' frames alternated one by one, so that a load that drifts during
    /// the run (a shared machine, a software adapter) weighs on both alike: the ratio
    /// of their medians.
    fn paired(&self, a: &Renderer, b: &Renderer) -> Result<f64, GpuError> {
        let (gpu, view) = (self.gpu, self.view);
        let (mut ta, mut tb) = (Vec::new(), Vec::new());
        for _ in 0..self.frames {
            ta.extend(a.frames(gpu, view, ViewMode::Color, 0, 1)?.1);
            tb.extend(b.frames(gpu, view, ViewMode::Color, 0, 1)?.1);
        }
        Ok(median(ta).as_secs_f64() / median(tb).as_secs_f64())
    }
}

/// The rows' results by name, and their renderers.
type Measured = (Vec<(&'static str, Row)>, Vec<Renderer>);

/// A ratio: label, value, how it was measured ("" for one after the other).
type Ratio = (&'static str, f64, &'static str);

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// What the frame benchmark measured.
struct Report {
    scene: String,
    adapter: String,
    size: [u32; 2],
    frames: u32,
    compile_time: Duration,
    results: Vec<(&'static str, Row)>,
    /// The loop walk's pipeline built, and found in the cache.
    built: Duration,
    again: Duration,
}

impl Report {
    fn print_rows(&self) {
        println!("scene:     {}", self.scene);
        println!("adapter:   {}", self.adapter);
        println!(
            "size:      {}x{}, median of {} frames",
            self.size[0], self.size[1], self.frames
        );
        println!(
            "compile:   {:.2} ms (parse → validated WGSL)",
            ms(self.compile_time)
        );
        for (name, r) in &self.results {
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
            ms(self.again),
            ms(self.built)
        );
    }

    /// The ratios: shaded against plain and unrolled against loop from the rows, the
    /// displaced against the undisplaced row, the alternated pairs, and the CPU
    /// reference's bounds.
    fn ratios(
        &self,
        undisplaced_row: Option<usize>,
        alternated: Vec<Ratio>,
        analysis: &Analysis,
        args: &BenchArgs,
    ) -> Vec<Ratio> {
        let results = &self.results;
        let (plain, unrolled_r, loop_r) = (results[0].1, results[1].1, results[2].1);
        let mut ratios: Vec<Ratio> = vec![
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
        ratios
    }

    /// The `--json` report.
    fn json(&self, ratios: &[Ratio]) -> serde_json::Value {
        serde_json::json!({
            "scene": self.scene,
            "adapter": self.adapter,
            "size": self.size,
            "frames": self.frames,
            "compile_ms": ms(self.compile_time),
            "pipeline_cached_ms": ms(self.again),
            "pipeline_rebuilt_ms": ms(self.built),
            "rows": self.results.iter().map(|(name, r)| serde_json::json!({
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
        })
    }
}

fn print_ratios(ratios: &[Ratio]) {
    for (label, value, how) in ratios {
        let how = if how.is_empty() {
            String::new()
        } else {
            format!(" ({how})")
        };
        println!("ratio {:34} {value:.2}{how}", format!("{label}:"));
    }
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
