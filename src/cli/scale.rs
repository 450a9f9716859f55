//! `sdfc bench --scale`: how cost grows with the scene. Generated cities
//! (`sdfc::bench::city`) of 10 to 10,000 spheres, then 1,200 spheres with 0 to 500
//! seeds; for each: compile time (source → validated WGSL), WGSL lines, pipeline time,
//! frame time and the language server's didChange → diagnostics latency, and up to
//! 1,200 spheres the same scene with its unions as code (no groups), measured in one
//! run on one adapter, with a log-log plot (`--plot`, SVG or PNG). Then scenes that are
//! not cities (`sdfc::bench::scattered`): 12 and 1,200 small spheres scattered through
//! a cube, where most rays miss, and 4,000 with 200 seeds for the language server.

use super::BenchArgs;
use sdfc::bench::{city, scattered, SCALE_COUNTS, SCATTERED};
use sdfc::codegen::{Options, WalkForm};
use sdfc::driver;
use sdfc::gpu::{Gpu, Renderer, ViewMode};
use sdfc::view::View;
use std::path::Path;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// The seed counts of the second series, on [`SEEDED_PRIMITIVES`] spheres (the scene of
/// the issue that asked for this bench: 1,200 spheres, 200 seeds), up to the 500 it
/// asked for (an atlas holds at most 1,024 seeds, E0117).
pub const SEED_COUNTS: [usize; 6] = [0, 1, 10, 100, 200, 500];
pub const SEEDED_PRIMITIVES: usize = 1200;

/// The largest scene also measured with its unions as code (the baseline).
pub const MAX_AS_CODE: usize = 1200;

/// One measured scene.
struct Row {
    primitives: usize,
    seeds: usize,
    lines: usize,
    compile: Duration,
    pipeline: Duration,
    frame: Duration,
    /// The language server's front-end stage (parse, names, types), p95.
    lsp_front_p95: Duration,
    /// Its full analysis.
    lsp_p50: Duration,
    lsp_p95: Duration,
    /// The same scene with its unions as code: WGSL lines, pipeline, frame.
    as_code: Option<(usize, Duration, Duration)>,
    /// The frame without per-tile culling (`--no-tiles`), where the scene has groups
    /// it applies to.
    untiled: Option<Duration>,
}

/// Which generator a row's scene comes from.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    City,
    Scattered,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

pub fn run(args: &BenchArgs) -> ExitCode {
    match scale(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

fn scale(args: &BenchArgs) -> Result<(), ExitCode> {
    let gpu = super::open_gpu(args.backend)?;
    let (width, height) = args.size.unwrap_or((160, 120));
    println!("scale: sdfc::bench::city(N, seeds), N spheres in unions of 20, a checker material");
    println!("adapter:   {}", gpu.describe());
    println!(
        "size:      {width}x{height}, median of {} frames after one warm-up frame, the loop walk; compile: median of 3; LSP: p50/p95 of {} edits",
        args.frames.max(1),
        args.edits.clamp(1, 20)
    );
    println!(
        "{:>7} {:>6} {:>8} {:>11} {:>11} {:>11} {:>9} {:>9} {:>9} | {:>8} {:>11} {:>11} {:>8}",
        "prims",
        "seeds",
        "lines",
        "compile ms",
        "pipeline ms",
        "frame ms",
        "LSP 1 p95",
        "LSP p50",
        "LSP p95",
        "lines",
        "pipeline ms",
        "frame ms",
        "speedup"
    );
    println!("{:>102}", "unions as code (no groups):");
    println!("(LSP 1: the front end's diagnostics, published first; LSP: the full set, ms)");
    println!(
        "(frame: with per-tile culling; \"no tiles\": the same module without it, and the speedup)"
    );
    let mut rows = Vec::new();
    let configs = SCALE_COUNTS
        .iter()
        .map(|&n| (n, 0))
        .chain(SEED_COUNTS.iter().map(|&s| (SEEDED_PRIMITIVES, s)));
    let configs: Vec<(usize, usize)> = configs.collect();
    for (n, seeds) in configs {
        let row = measure(&gpu, args, (Kind::City, n, seeds), (width, height))?;
        print_row(&row);
        rows.push(row);
    }
    let growth = |f: &dyn Fn(&Row) -> f64| {
        let r: Vec<&Row> = rows
            .iter()
            .filter(|r| r.seeds == 0 && SCALE_COUNTS.contains(&r.primitives))
            .collect();
        r.windows(2)
            .map(|w| format!("{:.2}", f(w[1]) / f(w[0])))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!("\ngrowth per 10x primitives (10→100, 100→1,000, 1,000→10,000):");
    println!("  compile  {}", growth(&|r| ms(r.compile)));
    println!("  lines    {}", growth(&|r| r.lines as f64));
    println!("  pipeline {}", growth(&|r| ms(r.pipeline)));
    println!("  frame    {}", growth(&|r| ms(r.frame)));
    println!("\nscattered: sdfc::bench::scattered(N, seeds), N spheres through a 10-unit cube, no ground (most rays miss)");
    let mut spread = Vec::new();
    for (n, seeds) in SCATTERED {
        let row = measure(&gpu, args, (Kind::Scattered, n, seeds), (width, height))?;
        print_row(&row);
        spread.push(row);
    }
    // The frame ratio of the first two scenes (few and many spheres, no seeds): from the
    // rows (one after the other), and from their frames alternated one by one.
    let mut alternated = None;
    if let [few, many, ..] = &spread[..] {
        let pair = paired(
            &gpu,
            args,
            [few.primitives, many.primitives],
            (width, height),
        )?;
        println!(
            "  frame, {} ÷ {} scattered spheres: {:.1}x (the rows); {:.1}x (frames alternated: {:.2} ÷ {:.2} ms)",
            many.primitives,
            few.primitives,
            ms(many.frame) / ms(few.frame),
            ms(pair[1]) / ms(pair[0]),
            ms(pair[1]),
            ms(pair[0]),
        );
        alternated = Some(ms(pair[1]) / ms(pair[0]));
    }
    // A chart that cannot be written does not lose the JSON: its error comes last.
    let plotted = match &args.plot {
        Some(path) => plot(path, &rows).map(|()| println!("plot:      {}", path.display())),
        None => Ok(()),
    };
    if let Some(path) = &args.json {
        let json = serde_json::json!({
            "bench": "scale",
            "adapter": gpu.describe(),
            "size": [width, height],
            "scattered": spread.iter().map(row_json).collect::<Vec<_>>(),
            "scattered_ratio_alternated": alternated,
            "rows": rows.iter().map(row_json).collect::<Vec<_>>(),
        });
        super::report::write_json(path, &json)?;
    }
    plotted
}

/// The view of a generated scene's render block, at `width` × `height`.
fn view_of(analysis: &driver::Analysis, (width, height): (u32, u32)) -> View {
    let shape = analysis
        .scene
        .as_ref()
        .and_then(|s| s.render.clone())
        .unwrap_or_default();
    let mut view = View::new(analysis.program.render.as_ref(), &shape);
    (view.width, view.height) = (width, height);
    view
}

/// The median frames of `scattered(n, 0)` for the two counts, built again and drawn
/// alternately one frame at a time (`args.frames` each, after one warm-up frame), so
/// that a drift of the machine, or a process's mode (a software adapter's frame of a
/// millisecond falls in two modes from run to run), weighs on both alike.
fn paired(
    gpu: &Gpu,
    args: &BenchArgs,
    counts: [usize; 2],
    (width, height): (u32, u32),
) -> Result<[Duration; 2], ExitCode> {
    let options = Options {
        walk: WalkForm::Loop,
        tiles: true,
        ..Default::default()
    };
    let fail = |e: sdfc::gpu::GpuError| {
        eprintln!("error: scattered spheres, frames alternated: {e}");
        ExitCode::from(super::exit::gpu(&e))
    };
    let mut built = Vec::new();
    for n in counts {
        let (source, name) = (scattered(n, 0), format!("scattered({n}, 0)"));
        let analysis = driver::check(&source, None);
        let module = driver::compile(&analysis, &options)
            .map_err(|e| super::compile::report(&name, &source, e))?
            .module;
        let renderer = Renderer::new(gpu, &module, Path::new(".")).map_err(fail)?;
        built.push((renderer, view_of(&analysis, (width, height))));
    }
    let mut times = [Vec::new(), Vec::new()];
    for round in 0..=args.frames.max(1) {
        for (k, (renderer, view)) in built.iter().enumerate() {
            let (_, t) = renderer
                .frames(gpu, view, ViewMode::Color, 0, 1)
                .map_err(fail)?;
            // The first round warms both up.
            if round > 0 {
                times[k].extend(t);
            }
        }
    }
    let [a, b] = times;
    Ok([median(a), median(b)])
}

/// A row's JSON, in both series (`as_code` is null where the baseline was not built).
fn row_json(r: &Row) -> serde_json::Value {
    serde_json::json!({
        "primitives": r.primitives,
        "seeds": r.seeds,
        "wgsl_lines": r.lines,
        "compile_ms": ms(r.compile),
        "pipeline_ms": ms(r.pipeline),
        "frame_ms": ms(r.frame),
        "lsp_front_p95_ms": ms(r.lsp_front_p95),
        "lsp_p50_ms": ms(r.lsp_p50),
        "lsp_p95_ms": ms(r.lsp_p95),
        "untiled_frame_ms": r.untiled.map(ms),
        "as_code": r.as_code.map(|(lines, pipeline, frame)| serde_json::json!({
            "wgsl_lines": lines,
            "pipeline_ms": ms(pipeline),
            "frame_ms": ms(frame),
        })),
    })
}

fn print_row(row: &Row) {
    let code = row
        .as_code
        .map_or(String::new(), |(lines, pipeline, frame)| {
            format!(
                " | {lines:>8} {:>11.1} {:>11.1} {:>7.1}x",
                ms(pipeline),
                ms(frame),
                ms(frame) / ms(row.frame)
            )
        });
    let untiled = row.untiled.map_or(String::new(), |u| {
        format!(
            " | no tiles {:.1} ms ({:.1}x)",
            ms(u),
            ms(u) / ms(row.frame)
        )
    });
    println!(
        "{:>7} {:>6} {:>8} {:>11.1} {:>11.1} {:>11.1} {:>9.1} {:>9.1} {:>9.1}{code}{untiled}",
        row.primitives,
        row.seeds,
        row.lines,
        ms(row.compile),
        ms(row.pipeline),
        ms(row.frame),
        ms(row.lsp_front_p95),
        ms(row.lsp_p50),
        ms(row.lsp_p95)
    );
}

fn measure(
    gpu: &Gpu,
    args: &BenchArgs,
    (kind, n, seeds): (Kind, usize, usize),
    (width, height): (u32, u32),
) -> Result<Row, ExitCode> {
    let (source, name) = match kind {
        Kind::City => (city(n, seeds), format!("city({n}, {seeds})")),
        Kind::Scattered => (scattered(n, seeds), format!("scattered({n}, {seeds})")),
    };
    let options = Options {
        walk: WalkForm::Loop,
        tiles: true,
        ..Default::default()
    };
    let mut compiles = Vec::new();
    let mut built = None;
    for _ in 0..3 {
        let t = Instant::now();
        let analysis = driver::check(&source, None);
        if !analysis.diagnostics.is_empty() {
            eprint!(
                "{}",
                sdfc::diagnostic::render(&name, &source, &analysis.diagnostics, false)
            );
            eprintln!("error: a generated scale scene has diagnostics (a bug in sdfc::bench)");
            return Err(ExitCode::from(super::exit::SCENE));
        }
        let module = driver::compile(&analysis, &options)
            .map_err(|e| super::compile::report(&name, &source, e))?
            .module;
        compiles.push(t.elapsed());
        built = Some((analysis, module));
    }
    let (analysis, module) = built.expect("three compiles");
    let fail = |e: sdfc::gpu::GpuError| {
        eprintln!("error: {name}: {e}");
        ExitCode::from(super::exit::gpu(&e))
    };
    // A real build: benchmarks measure pipelines, not the cache.
    gpu.pipelines.clear();
    let renderer = Renderer::new(gpu, &module, Path::new(".")).map_err(fail)?;
    let view = view_of(&analysis, (width, height));
    let (_, frames) = renderer
        .frames(gpu, &view, ViewMode::Color, 1, args.frames.max(1))
        .map_err(fail)?;
    // A baseline: the same scene with other options (the one compile is not timed), a
    // real pipeline build: its WGSL lines, pipeline time and median frame.
    let baseline = |edit: &dyn Fn(&mut Options)| -> Result<(usize, Duration, Duration), ExitCode> {
        let mut other = options.clone();
        edit(&mut other);
        let module = driver::compile(&analysis, &other)
            .map_err(|e| super::compile::report(&name, &source, e))?
            .module;
        gpu.pipelines.clear();
        let r = Renderer::new(gpu, &module, Path::new(".")).map_err(fail)?;
        let (_, frames) = r
            .frames(gpu, &view, ViewMode::Color, 1, args.frames.max(1))
            .map_err(fail)?;
        Ok((module.wgsl.lines().count(), r.pipeline_time, median(frames)))
    };
    // Its unions as code.
    let as_code = if kind == Kind::City && n <= MAX_AS_CODE && seeds == 0 {
        Some(baseline(&|o| o.unions_as_code = true)?)
    } else {
        None
    };
    // Without per-tile culling.
    let untiled = if module.tiling.is_some() {
        Some(baseline(&|o| o.tiles = false)?.2)
    } else {
        None
    };
    // The language server on the same text, in process (`--lsp-latency`'s loop).
    let stem = match kind {
        Kind::City => "city",
        Kind::Scattered => "scattered",
    };
    let file = std::env::temp_dir().join(format!("sdfc-scale-{stem}-{n}-{seeds}.sdf"));
    let (lsp, _) = super::latency::measure(
        &file,
        &source,
        args.edits.clamp(1, 20),
        super::latency::Edit::Token,
    )
    .map_err(|e| {
        eprintln!("error: the language server failed: {e}");
        ExitCode::from(super::exit::SCENE)
    })?;
    let front = super::latency::quantiles(lsp.front);
    let full = super::latency::quantiles(lsp.full);
    Ok(Row {
        primitives: n,
        seeds,
        lines: module.wgsl.lines().count(),
        compile: median(compiles),
        untiled,
        pipeline: renderer.pipeline_time,
        frame: median(frames),
        lsp_front_p95: front[2],
        lsp_p50: full[1],
        lsp_p95: full[2],
        as_code,
    })
}

/// The scale figures against the number of primitives, log-log.
struct ScalePlot<'a>(&'a [Row]);

impl super::plot::Figure for ScalePlot<'_> {
    fn draw<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<(), Box<dyn std::error::Error>>
    where
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;
        let series: Vec<&Row> = self
            .0
            .iter()
            .filter(|r| r.seeds == 0 && SCALE_COUNTS.contains(&r.primitives))
            .collect();
        type Line = (&'static str, RGBColor, fn(&Row) -> f64);
        let lines: [Line; 4] = [
            ("compile", RED, |r| ms(r.compile)),
            ("pipeline", BLUE, |r| ms(r.pipeline)),
            ("frame", GREEN, |r| ms(r.frame)),
            ("LSP p95", MAGENTA, |r| ms(r.lsp_p95)),
        ];
        let (lo, hi) = series
            .iter()
            .flat_map(|r| lines.iter().map(move |(_, _, f)| f(r)))
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        root.fill(&WHITE)?;
        let x_max = series.last().map_or(10.0, |r| r.primitives as f64);
        let mut chart = ChartBuilder::on(root)
            .caption("sdfc bench --scale", ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (5.0..x_max * 2.0).log_scale(),
                ((lo / 2.0).max(1e-3)..(hi * 2.0).max(1.0)).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc("primitives")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_desc("milliseconds")
            .draw()?;
        for (label, colour, f) in lines {
            chart
                .draw_series(LineSeries::new(
                    series.iter().map(|r| (r.primitives as f64, f(r))),
                    colour.stroke_width(2),
                ))?
                .label(label)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], colour));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()?;
        Ok(())
    }
}

fn plot(path: &Path, rows: &[Row]) -> Result<(), ExitCode> {
    super::plot::write(path, &ScalePlot(rows)).map_err(|e| {
        eprintln!("error: cannot write the plot {}: {e}", path.display());
        ExitCode::from(super::exit::USAGE)
    })
}
