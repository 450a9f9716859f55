//! `sdfc eval`: signed distances, gradients and surface projections at points.

use super::exit;
use super::{load, read_text, EvalArgs};
use glam::DVec3;
use sdfc::driver;
use sdfc::ir::eval;
use std::io::Write;
use std::process::ExitCode;

/// Parses `[[x, y, z], …]`.
/// The most points one `eval` takes.
pub const MAX_POINTS: usize = 1_000_000;
/// The largest points file, in bytes.
pub const MAX_POINTS_BYTES: usize = 128 << 20;

pub fn parse_points(text: &str) -> Result<Vec<DVec3>, String> {
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| format!("the points are not valid JSON: {e}"))?;
    let list = value
        .as_array()
        .ok_or("the points must be a JSON array of [x, y, z] arrays")?;
    if list.len() > MAX_POINTS {
        return Err(format!(
            "{} points; the limit is {MAX_POINTS} per run",
            list.len()
        ));
    }
    list.iter()
        .enumerate()
        .map(|(i, p)| {
            let c = p
                .as_array()
                .filter(|c| c.len() == 3)
                .ok_or_else(|| format!("point {i} is not an [x, y, z] array"))?;
            let f = |k: usize| {
                c[k].as_f64()
                    .ok_or_else(|| format!("point {i} has a component that is not a number"))
            };
            Ok(DVec3::new(f(0)?, f(1)?, f(2)?))
        })
        .collect()
}

/// One output line, fields in the documented order.
#[derive(serde::Serialize)]
struct Line {
    point: [f64; 3],
    distance: f64,
    gradient: [f64; 3],
    surface: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    atlas: Option<AtlasLine>,
}

/// The atlas at the point's projection onto the atlas's surface.
#[derive(serde::Serialize)]
struct AtlasLine {
    name: String,
    status: &'static str,
    uv: [f64; 2],
    seed: Option<String>,
    geodesic_distance: Option<f64>,
    /// The chosen seed's normalized blend weight (1 away from merged frontiers).
    weight: f64,
    /// With --all-seeds: every seed's own log map (Alg. 1, full D), no offset.
    #[serde(skip_serializing_if = "Option::is_none")]
    seeds: Option<Vec<SeedLine>>,
}

#[derive(serde::Serialize)]
struct SeedLine {
    name: String,
    status: &'static str,
    uv: [f64; 2],
    geodesic_distance: Option<f64>,
    offset: [f64; 2],
}

/// An error already reported on stderr, with the exit status it calls for.
type Failed = ExitCode;

/// Prints a usage or I/O error and gives its exit status.
fn fail(message: impl std::fmt::Display, code: u8) -> Failed {
    eprintln!("error: {message}");
    ExitCode::from(code)
}

pub fn run(args: EvalArgs) -> ExitCode {
    args.run_time.install();
    match eval(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

/// The steps of `sdfc eval`: load, pick the shape and the atlas, read the points,
/// evaluate on the CPU (and with `--gpu`, on the GPU), print one line per point.
fn eval(args: &EvalArgs) -> Result<(), Failed> {
    let (source, analysis) = load(&args.scene)?;
    let Some(scene) = &analysis.scene else {
        return Err(ExitCode::from(exit::SCENE));
    };
    let shape =
        driver::pick_shape(scene, args.shape.as_deref()).map_err(|e| fail(e, exit::USAGE))?;
    let points = read_text(&args.points, MAX_POINTS_BYTES)
        .map_err(|e| format!("cannot read {}: {e}", args.points.display()))
        .and_then(|t| parse_points(&t))
        .map_err(|e| fail(e, exit::USAGE))?;
    // The atlas as the check prepared it (projected seeds, solved merge graph).
    let atlas = driver::pick_atlas(&analysis.program, args.atlas.as_deref())
        .map_err(|e| fail(e, exit::USAGE))?
        .and_then(|def| analysis.atlas(&def.name));
    // Atlas queries happen at each point's projection onto the atlas's own surface.
    let atlas_points: Vec<Option<DVec3>> = match atlas {
        Some(a) => points
            .iter()
            .map(|p| eval::project(a.field(), *p, 1e-6 * sdfc::uv::atlas::scale(&a.shape)))
            .collect(),
        None => Vec::new(),
    };
    let mut results = eval::query_all(analysis.field(shape), &points);
    let mut atlas_results = match atlas {
        Some(a) => cpu_atlas_lines(a, &atlas_points, args),
        None => Vec::new(),
    };
    if args.gpu {
        let module = compile(args, &analysis, &source)?;
        let gpu = sdfc::gpu::Gpu::new(args.backend).map_err(|e| {
            let code = exit::gpu(&e);
            fail(e, code)
        })?;
        gpu_distances(&gpu, &module, &analysis.program, &points, &mut results)?;
        if let Some(a) = atlas {
            gpu_atlas_lines(&gpu, &module, a, &atlas_points, args, &mut atlas_results)?;
        }
    }
    print_lines(results, atlas.is_some().then_some(atlas_results))
}

/// The atlas lines of the CPU reference, `None` where a point has no projection.
fn cpu_atlas_lines(
    a: &sdfc::uv::Atlas,
    atlas_points: &[Option<DVec3>],
    args: &EvalArgs,
) -> Vec<Option<AtlasLine>> {
    let search = sdfc::uv::Search {
        brute_force: args.brute_force,
    };
    atlas_points
        .iter()
        .map(|x| {
            let x = (*x)?;
            let s = a.sample_with(x, search);
            let seed = s.seed.map(|i| i as i32).unwrap_or(-1);
            let mut line = atlas_line(a, s.status, s.uv.to_array(), seed, s.distance, s.weight);
            if args.all_seeds {
                line.seeds = Some(seed_lines(a, x));
            }
            Some(line)
        })
        .collect()
}

/// The scene's module for `--gpu`, with the shape and atlas asked for.
fn compile(
    args: &EvalArgs,
    analysis: &driver::Analysis,
    source: &str,
) -> Result<sdfc::codegen::Module, Failed> {
    let options = sdfc::codegen::Options {
        atlas: args.atlas.clone(),
        ..Default::default()
    };
    let name = args.scene.display().to_string();
    driver::compile_shape(analysis, args.shape.as_deref(), &options)
        .map(|c| c.module)
        .map_err(|e| super::compile::report(&name, source, e))
}

/// Replaces the CPU distances and gradients with the GPU's.
fn gpu_distances(
    gpu: &sdfc::gpu::Gpu,
    module: &sdfc::codegen::Module,
    program: &sdfc::sema::Program,
    points: &[DVec3],
    results: &mut [eval::Query],
) -> Result<(), Failed> {
    let values = if module.manifest.textures.is_empty() {
        sdfc::gpu::eval_points(gpu, module, points)
    } else {
        // A displacement's height samples textures in the field itself.
        let textures = sdfc::ir::texture::Textures::load(program).map_err(|e| fail(e, 2))?;
        sdfc::gpu::eval_points_textured(gpu, module, &textures, points)
    }
    .map_err(|e| {
        let code = exit::gpu(&e);
        fail(e, code)
    })?;
    for (q, v) in results.iter_mut().zip(values) {
        q.distance = v[0] as f64;
        q.gradient = DVec3::new(v[1] as f64, v[2] as f64, v[3] as f64);
    }
    Ok(())
}

/// Replaces the CPU atlas lines with the GPU's, at the same projections.
fn gpu_atlas_lines(
    gpu: &sdfc::gpu::Gpu,
    module: &sdfc::codegen::Module,
    a: &sdfc::uv::Atlas,
    atlas_points: &[Option<DVec3>],
    args: &EvalArgs,
    atlas_results: &mut [Option<AtlasLine>],
) -> Result<(), Failed> {
    let on_surface: Vec<DVec3> = atlas_points
        .iter()
        .map(|x| x.unwrap_or(DVec3::ZERO))
        .collect();
    let values = sdfc::gpu::eval_atlas(gpu, module, &on_surface).map_err(|e| {
        let code = exit::gpu(&e);
        fail(e, code)
    })?;
    for ((slot, v), x) in atlas_results.iter_mut().zip(values).zip(atlas_points) {
        let Some(x) = x else {
            continue;
        };
        let mut line = atlas_line(
            a,
            sdfc::uv::Status::from_code(v.status),
            [v.uv[0] as f64, v.uv[1] as f64],
            v.seed,
            v.distance as f64,
            v.weight as f64,
        );
        if args.all_seeds {
            line.seeds = Some(seed_lines(a, *x));
        }
        *slot = Some(line);
    }
    Ok(())
}

/// Prints one JSON line per point; with an atlas, a point without a projection gets
/// the status `no_surface`.
fn print_lines(
    results: Vec<eval::Query>,
    atlas_results: Option<Vec<Option<AtlasLine>>>,
) -> Result<(), Failed> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let has_atlas = atlas_results.is_some();
    let mut atlas_results = atlas_results.unwrap_or_default().into_iter();
    for q in results {
        let atlas = has_atlas.then(|| {
            atlas_results.next().flatten().unwrap_or_else(|| AtlasLine {
                name: String::new(),
                status: "no_surface",
                uv: [0.0; 2],
                seed: None,
                geodesic_distance: None,
                weight: 0.0,
                seeds: None,
            })
        });
        let line = Line {
            point: q.point.to_array(),
            distance: q.distance,
            gradient: q.gradient.to_array(),
            surface: q.surface.map(|s| s.to_array()),
            atlas,
        };
        let text = serde_json::to_string(&line).unwrap_or_default();
        writeln!(out, "{text}").map_err(|_| ExitCode::from(exit::USAGE))?;
    }
    Ok(())
}

fn atlas_line(
    a: &sdfc::uv::Atlas,
    status: sdfc::uv::Status,
    uv: [f64; 2],
    seed: i32,
    distance: f64,
    weight: f64,
) -> AtlasLine {
    let ok = status == sdfc::uv::Status::Ok;
    AtlasLine {
        name: a.name.clone(),
        status: status.name(),
        uv,
        seed: usize::try_from(seed)
            .ok()
            .and_then(|i| a.seed_names.get(i).cloned()),
        geodesic_distance: ok.then_some(distance),
        weight,
        seeds: None,
    }
}

/// Every seed's log map at x (CPU reference, f64).
fn seed_lines(a: &sdfc::uv::Atlas, x: DVec3) -> Vec<SeedLine> {
    a.all_seeds(x)
        .iter()
        .zip(&a.seeds)
        .zip(&a.seed_names)
        .map(|((m, s), name)| SeedLine {
            name: name.clone(),
            status: m.status.name(),
            uv: m.uv.to_array(),
            geodesic_distance: (m.status == sdfc::uv::Status::Ok).then_some(m.distance),
            offset: s.offset.to_array(),
        })
        .collect()
}
