//! `sdfc eval`: signed distances, gradients and surface projections at points.

use super::{load, read_source, EvalArgs};
use glam::DVec3;
use sdfc::ir::{self, eval};
use std::io::Write;
use std::process::ExitCode;

/// Picks the shape: the named one, else the render target, else the only shape.
pub fn pick_shape(scene: &ir::Scene, name: Option<&str>) -> Result<ir::Shape, String> {
    let names = || {
        scene
            .shapes
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match name {
        Some(n) => scene
            .shape(n)
            .cloned()
            .ok_or_else(|| format!("the scene has no shape `{n}`; its shapes are: {}", names())),
        None => match (&scene.render, scene.shapes.as_slice()) {
            (Some(r), _) => Ok(r.clone()),
            (None, [only]) => Ok(only.shape.clone()),
            (None, []) => Err(String::from("the scene has no shape")),
            (None, _) => Err(format!(
                "the scene has no render item; choose a shape with --shape: {}",
                names()
            )),
        },
    }
}

/// Parses `[[x, y, z], …]`.
pub fn parse_points(text: &str) -> Result<Vec<DVec3>, String> {
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| format!("the points are not valid JSON: {e}"))?;
    let list = value
        .as_array()
        .ok_or("the points must be a JSON array of [x, y, z] arrays")?;
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
}

pub fn run(args: EvalArgs) -> ExitCode {
    let (_, analysis) = match load(&args.scene) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let scene = ir::lower(&analysis.program);
    let shape = match pick_shape(&scene, args.shape.as_deref()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let points = match read_source(&args.points)
        .map_err(|e| format!("cannot read {}: {e}", args.points.display()))
        .and_then(|t| parse_points(&t))
    {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let mut results = eval::query_all(&shape, &points);
    if args.gpu {
        let module = match super::compile::build(&args.scene, args.shape.as_deref()) {
            Ok((m, _)) => m,
            Err(code) => return code,
        };
        let gpu = match sdfc::gpu::Gpu::new(args.backend) {
            Ok(g) => g,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(super::render::GPU_EXIT);
            }
        };
        match sdfc::gpu::eval_points(&gpu, &module.wgsl, &points) {
            Ok(values) => {
                for (q, v) in results.iter_mut().zip(values) {
                    q.distance = v[0] as f64;
                    q.gradient = DVec3::new(v[1] as f64, v[2] as f64, v[3] as f64);
                }
            }
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(super::render::GPU_EXIT);
            }
        }
    }
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    for q in results {
        let line = Line {
            point: q.point.to_array(),
            distance: q.distance,
            gradient: q.gradient.to_array(),
            surface: q.surface.map(|s| s.to_array()),
        };
        let text = serde_json::to_string(&line).unwrap_or_default();
        if writeln!(out, "{text}").is_err() {
            return ExitCode::from(2);
        }
    }
    ExitCode::SUCCESS
}
