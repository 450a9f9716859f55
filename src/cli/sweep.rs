//! `sdfc bench --seed-sweep`: per-pixel cost against the number of seeds (the paper's
//! Fig. 15), as frame-time ratios against the same plate with its atlas answering a
//! constant uv (same shading, no walks) and against a bare sphere trace, measured in one
//! run on one adapter; and the merge-graph solve time of each merged plate.

use super::{compile, BenchArgs};
use sdfc::bench::{layout, plate, SEED_COUNTS};
use sdfc::codegen::{Options, SeedGridChoice};
use sdfc::driver;
use sdfc::gpu::{self, Gpu, MultiScale, ViewMode};
use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

/// One measured configuration.
struct Row {
    seeds: u32,
    steps: u32,
    merged: bool,
    grid: bool,
    pipeline: Duration,
    frame: Duration,
}

/// The baselines, each measured before every seed count and at the end.
#[derive(Default)]
struct Baselines {
    /// A bare sphere trace of the plate (no materials).
    plain: Vec<Duration>,
    /// The plate with its atlas a constant sample: the same material and shading.
    constant: Vec<Duration>,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Checks a generated scene; its diagnostics are printed and the sweep stops if any.
fn checked(name: &str, source: &str) -> Result<driver::Analysis, ExitCode> {
    let analysis = driver::check(source, None);
    if !analysis.diagnostics.is_empty() {
        eprint!(
            "{}",
            sdfc::diagnostic::render(name, source, &analysis.diagnostics, false)
        );
        eprintln!("error: a generated sweep scene has diagnostics (a bug in sdfc::bench::plate)");
        return Err(ExitCode::from(super::exit::SCENE));
    }
    Ok(analysis)
}

/// The median over `runs` checks of the time the frame and offset solves take.
fn solve_time(source: &str, runs: usize) -> Duration {
    let mut times: Vec<f64> = (0..runs)
        .filter_map(|_| {
            let a = driver::check(source, None);
            a.atlases.first()?.as_ref().map(|x| x.graph.solve_seconds)
        })
        .collect();
    times.sort_by(f64::total_cmp);
    Duration::from_secs_f64(times.get(times.len() / 2).copied().unwrap_or(0.0))
}

/// What every measurement of the sweep shares: the adapter, the image size and the
/// number of frames.
struct Bench<'a> {
    gpu: &'a Gpu,
    width: u32,
    height: u32,
    frames: u32,
}

impl Bench<'_> {
    /// The pipeline creation time and the median frame time of one scene.
    fn measure(
        &self,
        name: &str,
        source: &str,
        options: &Options,
    ) -> Result<(Duration, Duration), ExitCode> {
        let analysis = checked(name, source)?;
        // As `sdfc render` draws it: the colour view's pipeline alone (the renderer
        // sets the view's pipeline constants).
        let module = driver::compile(&analysis, options)
            .map_err(|e| compile::report(name, source, e))?
            .module;
        let mut view = super::view_for(&analysis, None)?;
        (view.width, view.height) = (self.width, self.height);
        let gpu_error = |e: gpu::GpuError| {
            eprintln!("error: {e}");
            ExitCode::from(super::exit::gpu(&e))
        };
        // A real build: benchmarks measure pipelines, not the cache.
        self.gpu.pipelines.clear();
        let renderer = gpu::Renderer::new(self.gpu, &module, Path::new(".")).map_err(gpu_error)?;
        let (frame, _) = renderer
            .frames(self.gpu, &view, ViewMode::Color, 1, self.frames)
            .map_err(gpu_error)?;
        Ok((frame.timings.pipeline, frame.timings.frame))
    }

    /// Both baselines' frame times, into `b`.
    fn measure_baselines(&self, b: &mut Baselines) -> Result<(), ExitCode> {
        let plain = Options {
            plain: true,
            ..Default::default()
        };
        b.plain
            .push(self.measure("plain", &plate(1, 10, false), &plain)?.1);
        let constant = Options {
            constant_uv: true,
            ..Default::default()
        };
        b.constant.push(
            self.measure("constant uv", &plate(1, 10, false), &constant)?
                .1,
        );
        Ok(())
    }
}

pub fn run(args: &BenchArgs) -> ExitCode {
    match sweep(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

fn sweep(args: &BenchArgs) -> Result<(), ExitCode> {
    let gpu = super::open_gpu(args.backend)?;
    let (width, height) = args.size.unwrap_or((320, 240));
    let bench = Bench {
        gpu: &gpu,
        width,
        height,
        frames: args.frames.max(1),
    };
    println!("seed-count sweep (Fig. 15): the 8 x 8 plate of examples/plate.sdf");
    println!("adapter:   {}", gpu.describe());
    println!(
        "size:      {width}x{height}, median of {} frames after one warm-up frame, walk {:?}, multi-scale pass {} (render's default), {}",
        bench.frames,
        args.walk.on(&gpu),
        if MultiScale::Auto.on(&gpu) { "on" } else { "off" },
        if args.gradients.differences() {
            "gradients by central differences"
        } else {
            "gradients by forward derivatives"
        }
    );
    let (rows, baselines) = measure_rows(&bench, args)?;
    println!();
    let plain = print_baseline("bare sphere trace (no materials)", baselines.plain);
    let constant = print_baseline(
        "constant uv (same material and shading, no walks)",
        baselines.constant,
    );
    print_ratios(&rows, constant, "constant uv");
    print_ratios(&rows, plain, "bare trace");
    print_speedups(&rows);
    let solves = print_solve_times();
    // A chart that cannot be written does not lose the JSON: its error comes last.
    let plotted = match &args.plot {
        Some(path) => {
            let figure = SweepPlot {
                rows: &rows,
                constant,
                adapter: gpu.describe(),
            };
            super::plot::write(path, &figure)
                .map(|()| println!("plot:      {}", path.display()))
                .map_err(|e| {
                    eprintln!("error: cannot write the plot {}: {e}", path.display());
                    ExitCode::from(super::exit::USAGE)
                })
        }
        None => Ok(()),
    };
    if let Some(path) = &args.json {
        let json = serde_json::json!({
            "bench": "seed sweep",
            "adapter": gpu.describe(),
            "size": [width, height],
            "frames": bench.frames,
            "walk": format!("{:?}", args.walk.on(&gpu)),
            "multiscale": MultiScale::Auto.on(&gpu),
            "gradients": if args.gradients.differences() { "differences" } else { "forward" },
            "constant_uv_ms": ms(constant),
            "plain_ms": ms(plain),
            "rows": rows.iter().map(|r| serde_json::json!({
                "seeds": r.seeds,
                "steps": r.steps,
                "merged": r.merged,
                "grid": r.grid,
                "pipeline_ms": ms(r.pipeline),
                "frame_ms": ms(r.frame),
                "over_constant_uv": ms(r.frame) / ms(constant),
                "over_plain": ms(r.frame) / ms(plain),
            })).collect::<Vec<_>>(),
            "solve_ms": solves.iter().map(|(seeds, t)| serde_json::json!({
                "seeds": seeds,
                "ms": ms(*t),
            })).collect::<Vec<_>>(),
        });
        super::report::write_json(path, &json)?;
    }
    plotted
}

/// Measures every configuration, printing a line for each. The untextured baseline is
/// measured before each seed count and at the end; the ratios use the median of those
/// measurements, and the spread is reported.
fn measure_rows(bench: &Bench, args: &BenchArgs) -> Result<(Vec<Row>, Baselines), ExitCode> {
    let mut baselines = Baselines::default();
    println!();
    println!(
        "{:>5} {:>3} {:>6} {:>4} {:>12} {:>10}",
        "seeds", "N", "merged", "grid", "pipeline ms", "frame ms"
    );
    let mut rows = Vec::new();
    for seeds in SEED_COUNTS {
        bench.measure_baselines(&mut baselines)?;
        for steps in [10, 20] {
            // One seed has nothing to merge with: its merged row would repeat the other.
            for merged in [false, true].into_iter().filter(|&m| !m || seeds > 1) {
                let source = plate(seeds, steps, merged);
                for grid in [false, true] {
                    let options = Options {
                        walk: args.walk.on(bench.gpu),
                        // As `sdfc render` draws it by default.
                        multiscale: MultiScale::Auto.on(bench.gpu),
                        seed_grid: if grid {
                            SeedGridChoice::On
                        } else {
                            SeedGridChoice::Off
                        },
                        differences: args.gradients.differences(),
                        ..Default::default()
                    };
                    let name = format!("plate({seeds}, {steps}, {merged})");
                    let (pipeline, frame) = bench.measure(&name, &source, &options)?;
                    println!(
                        "{seeds:>5} {steps:>3} {:>6} {:>4} {:>12.1} {:>10.2}",
                        if merged { "yes" } else { "no" },
                        if grid { "on" } else { "off" },
                        ms(pipeline),
                        ms(frame),
                    );
                    rows.push(Row {
                        seeds,
                        steps,
                        merged,
                        grid,
                        pipeline,
                        frame,
                    });
                }
            }
        }
    }
    bench.measure_baselines(&mut baselines)?;
    Ok((rows, baselines))
}

/// The row of one configuration.
fn find(rows: &[Row], seeds: u32, steps: u32, merged: bool, grid: bool) -> Option<&Row> {
    rows.iter()
        .find(|r| (r.seeds, r.steps, r.merged, r.grid) == (seeds, steps, merged, grid))
}

/// Prints a baseline's spread; returns its median.
fn print_baseline(name: &str, mut times: Vec<Duration>) -> Duration {
    times.sort();
    let base = times[times.len() / 2];
    println!(
        "{name}: median {:.2} ms of {} measurements through the run (min {:.2}, max {:.2})",
        ms(base),
        times.len(),
        ms(times[0]),
        ms(times[times.len() - 1])
    );
    base
}

fn print_ratios(rows: &[Row], base: Duration, name: &str) {
    println!();
    println!("frame time ÷ {name}:");
    println!(
        "{:>5} {:>3}   {:>14} {:>14} {:>14} {:>14}",
        "seeds", "N", "unmerged, off", "unmerged, grid", "merged, off", "merged, grid"
    );
    for seeds in SEED_COUNTS {
        for steps in [10, 20] {
            let cell = |merged: bool, grid: bool| {
                find(rows, seeds, steps, merged, grid)
                    .map(|r| format!("{:.2}", ms(r.frame) / ms(base)))
                    .unwrap_or_else(|| String::from("—"))
            };
            println!(
                "{seeds:>5} {steps:>3}   {:>14} {:>14} {:>14} {:>14}",
                cell(false, false),
                cell(false, true),
                cell(true, false),
                cell(true, true)
            );
        }
    }
}

fn print_speedups(rows: &[Row]) {
    println!();
    println!("seed grid speed-up (frame time off ÷ on):");
    for seeds in SEED_COUNTS {
        let mut cells = Vec::new();
        for steps in [10, 20] {
            for merged in [false, true] {
                let pick = |grid: bool| find(rows, seeds, steps, merged, grid);
                if let (Some(off), Some(on)) = (pick(false), pick(true)) {
                    cells.push(format!(
                        "N={steps} {}: {:.2}",
                        if merged { "merged" } else { "unmerged" },
                        ms(off.frame) / ms(on.frame)
                    ));
                }
            }
        }
        println!("{seeds:>5} seeds   {}", cells.join("   "));
    }
}

/// Prints the merge-graph solve times; returns them (seeds, median).
fn print_solve_times() -> Vec<(u32, Duration)> {
    let mut out = Vec::new();
    println!();
    println!("merge-graph solve (frames, Eq. 45/48, and offsets, Eq. 47), median of 21 checks:");
    for seeds in SEED_COUNTS.into_iter().filter(|&s| s > 1) {
        let (r, c) = layout(seeds);
        let edges = r * (c - 1) + c * (r - 1);
        let t = solve_time(&plate(seeds, 10, true), 21);
        println!(
            "{seeds:>5} seeds, {edges:>3} merges: {:.3} ms",
            t.as_secs_f64() * 1e3
        );
        out.push((seeds, t));
    }
    out
}

/// Frame time ÷ constant uv against the number of seeds (the paper's Fig. 15): a line
/// per N and merging, with the seed grid (solid) and without it (light).
struct SweepPlot<'a> {
    rows: &'a [Row],
    constant: Duration,
    adapter: String,
}

impl super::plot::Figure for SweepPlot<'_> {
    fn draw<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<(), Box<dyn std::error::Error>>
    where
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;
        let ratio = |r: &Row| ms(r.frame) / ms(self.constant);
        let top = self.rows.iter().map(ratio).fold(1.0f64, f64::max);
        let max_seeds = SEED_COUNTS.into_iter().max().unwrap_or(1) as f64;
        root.fill(&WHITE)?;
        let (title, subtitle) = root.split_vertically(48);
        title.draw(&Text::new(
            "sdfc bench --seed-sweep (Fig. 15): frame time ÷ constant uv",
            (16, 8),
            ("sans-serif", 20),
        ))?;
        title.draw(&Text::new(
            self.adapter.clone(),
            (16, 30),
            ("sans-serif", 12),
        ))?;
        let mut chart = ChartBuilder::on(&subtitle)
            .margin(16)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d((0.8..max_seeds * 1.25).log_scale(), 0.0..top * 1.1)?;
        chart
            .configure_mesh()
            .x_desc("seeds")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_desc("frame time ÷ constant uv")
            .draw()?;
        let colours = [
            ((10, false), BLUE),
            ((10, true), RED),
            ((20, false), GREEN),
            ((20, true), MAGENTA),
        ];
        for grid in [true, false] {
            for ((steps, merged), colour) in colours {
                let points: Vec<(f64, f64)> = self
                    .rows
                    .iter()
                    .filter(|r| {
                        r.steps == steps && r.grid == grid && (r.merged == merged || r.seeds == 1)
                    })
                    .map(|r| (r.seeds as f64, ratio(r)))
                    .collect();
                let style = if grid {
                    colour.stroke_width(2)
                } else {
                    colour.mix(0.35).stroke_width(1)
                };
                let label = format!(
                    "N = {steps}, {}, grid {}",
                    if merged { "merged" } else { "unmerged" },
                    if grid { "on" } else { "off" }
                );
                chart
                    .draw_series(LineSeries::new(points, style))?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], style));
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()?;
        Ok(())
    }
}
