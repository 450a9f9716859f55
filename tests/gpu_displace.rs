//! Displacement on the GPU against the f64 CPU reference, on the displaced-sphere
//! example: distances (`cs_points` with the height's texture bound), the base's uv at
//! the projections (`cs_atlas`), colours (`cs_material`), and a render without holes
//! against a conservative CPU trace. Skips loudly without an adapter (fails with
//! SDFC_REQUIRE_GPU=1). Loop walks and few points/pixels: lavapipe is slow here.

use glam::DVec3;
use sdfc::codegen::{Options, WalkForm};
use sdfc::driver::{check, Analysis};
use sdfc::gpu::{self, gpu_for_tests, ViewMode};
use sdfc::ir::{eval, Op};
use sdfc::reference::material::{MaterialEval, Textures};
use sdfc::view::{trace_cpu, View};
use std::path::Path;

use crate::common;
use common::Rng;

fn example() -> Analysis {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let src = std::fs::read_to_string(dir.join("displaced_sphere.sdf")).unwrap();
    let a = check(&src, Some(&dir));
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    a
}

/// The render target with the environment of its heights (textures, atlases).
fn shape(a: &Analysis) -> sdfc::ir::Field<'_> {
    a.field(a.scene.as_ref().unwrap().render.as_ref().unwrap())
}

fn module(a: &Analysis) -> sdfc::codegen::Module {
    let options = Options {
        walk: WalkForm::Loop,
        ..Default::default()
    };
    sdfc::driver::compile(a, &options).unwrap().module
}

/// Points on the displaced surface in the chart's reach (the front), by projection.
fn surface_points(s: sdfc::ir::Field, n: usize) -> Vec<DVec3> {
    let mut r = Rng(17);
    let mut out = Vec::new();
    while out.len() < n {
        let v = DVec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(0.3, 1.0));
        let p = v.normalize() * 1.05;
        if let Some(x) = eval::project(s, p, 1e-10) {
            out.push(x);
        }
    }
    out
}

#[test]
fn displaced_sphere_gpu_agrees_with_the_cpu_reference() {
    let Some(gpu) = gpu_for_tests() else { return };
    let a = example();
    let s = shape(&a);
    let m = module(&a);
    let textures = Textures::load(&a.program).unwrap();
    let b = s.framing_bounds();
    let scale = (b.max - b.min).max_element();

    // Distances at points in and around the band.
    let mut r = Rng(3);
    let points: Vec<DVec3> = (0..400)
        .map(|_| {
            let w = DVec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(0.2, 1.0));
            w.normalize() * r.range(0.95, 1.2)
        })
        .collect();
    let gpu_d = gpu::eval_points_textured(&gpu, &m, &textures, &points).unwrap();
    let worst = points
        .iter()
        .zip(&gpu_d)
        .map(|(p, g)| (eval::distance(s, *p) - g[0] as f64).abs())
        .fold(0.0, f64::max);
    eprintln!("distance: worst |GPU − CPU| = {worst:.2e} (scale {scale:.2})");
    assert!(
        worst <= 1e-3 * scale,
        "worst distance difference {worst:.2e}"
    );

    // The base's uv at the projections of displaced surface points.
    assert!(s.nodes.iter().any(|n| matches!(n.op, Op::Displace { .. })));
    let on = surface_points(s, 200);
    let atlas = a.atlas("skin").unwrap();
    let base: Vec<DVec3> = on.iter().map(|&x| atlas.onto(x)).collect();
    let gpu_uv = gpu::eval_atlas(&gpu, &m, &base).unwrap();
    let (mut worst_uv, mut compared) = (0.0f64, 0);
    for (x, g) in base.iter().zip(&gpu_uv) {
        let c = atlas.sample(*x);
        if c.status.code() != 0 || g.status != 0 {
            continue;
        }
        let e = (c.uv - glam::DVec2::new(g.uv[0] as f64, g.uv[1] as f64)).length();
        worst_uv = worst_uv.max(e / c.uv.length().max(1.0));
        compared += 1;
    }
    eprintln!("uv: worst relative |GPU − CPU| = {worst_uv:.2e} over {compared} points");
    assert!(compared > 150);
    assert!(worst_uv <= 1e-3, "worst uv difference {worst_uv:.2e}");

    // Colours at the displaced surface (the material reads the base's atlas at the
    // point projected onto the base).
    let cpu = MaterialEval::new(&a.program, &a.atlases, textures.clone()).unwrap();
    let samples: Vec<(DVec3, DVec3, f64)> = on
        .iter()
        .map(|&x| (x, eval::gradient(s, x).normalize(), 1e-3))
        .collect();
    let gpu_m = gpu::eval_materials(&gpu, &m, &textures, &samples).unwrap();
    let mut worst_c = 0.0f64;
    for ((x, n, f), g) in samples.iter().zip(&gpu_m) {
        let c = cpu.eval(1, *x, *n, *f).color;
        for k in 0..3 {
            worst_c = worst_c.max((c[k] - g.color[k] as f64).abs());
        }
    }
    eprintln!("colour: worst |GPU − CPU| = {:.2}/255", worst_c * 255.0);
    assert!(
        worst_c <= 2.0 / 255.0,
        "worst colour difference {:.2}/255",
        worst_c * 255.0
    );
}

#[test]
fn displaced_sphere_renders_without_holes() {
    let Some(gpu) = gpu_for_tests() else { return };
    let a = example();
    let s = shape(&a).clone();
    let m = module(&a);
    let mut view = View::new(a.program.render.as_ref(), &s);
    view.width = 40;
    view.height = 40;
    let frame = gpu::render(
        &gpu,
        &m,
        &view,
        ViewMode::Color,
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples")
            .as_path(),
    )
    .unwrap();
    let (mut covered, mut holes, mut agree) = (0, 0, 0);
    for y in 0..view.height {
        for x in 0..view.width {
            let dir = view.camera.ray(
                x as f64 + 0.5,
                y as f64 + 0.5,
                view.width as f64,
                view.height as f64,
            );
            // Conservative reference: half steps, four times as many.
            let Some(hit) = trace_cpu(&s, &view, dir, 0.5, view.max_steps * 4) else {
                continue;
            };
            covered += 1;
            let gpu_t = frame.position[(y * view.width + x) as usize][3];
            if gpu_t < 0.0 {
                holes += 1;
            } else if (hit.t - gpu_t as f64).abs() <= 1e-3 * view.scale {
                agree += 1;
            }
        }
    }
    eprintln!("{covered} covered pixels: {holes} holes, {agree} at the CPU's depth");
    assert!(covered > 400, "only {covered} pixels covered");
    assert!(holes as f64 <= 0.01 * covered as f64, "{holes} holes");
    assert!(
        agree as f64 >= 0.97 * covered as f64,
        "{agree} of {covered} depths agree"
    );
}

/// The warm start of Alg. 2's search (the previous query's nearest seed walked first)
/// changes no result: on examples/displaced_column.sdf (four seeds, so the search has
/// seeds to skip), `cs_points` evaluates the field and its gradient (7 field
/// evaluations, each a walk inside the band, in one invocation: the hint is live) with
/// and without it, at points in the band. Equal within f32 noise (1e-6 of the size).
#[test]
fn warm_start_gives_the_same_field() {
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let src = std::fs::read_to_string(dir.join("displaced_column.sdf")).unwrap();
    let a = check(&src, Some(&dir));
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    let textures = Textures::load(&a.program).unwrap();
    let compile = |cold: bool| {
        let options = Options {
            walk: WalkForm::Loop,
            cold,
            ..Default::default()
        };
        sdfc::driver::compile(&a, &options).unwrap().module
    };
    let (warm, cold) = (compile(false), compile(true));
    assert!(warm.wgsl.contains("const ATLAS_0_WARM: bool = true;"));
    assert!(cold.wgsl.contains("const ATLAS_0_WARM: bool = false;"));
    let mut r = Rng(5);
    let points: Vec<DVec3> = (0..300)
        .map(|_| {
            let a = r.range(0.0, std::f64::consts::TAU);
            let rad = r.range(0.46, 0.52);
            DVec3::new(rad * a.cos(), r.range(-1.0, 1.0), rad * a.sin())
        })
        .collect();
    let w = gpu::eval_points_textured(&gpu, &warm, &textures, &points).unwrap();
    let c = gpu::eval_points_textured(&gpu, &cold, &textures, &points).unwrap();
    let worst = w
        .iter()
        .zip(&c)
        .flat_map(|(a, b)| (0..4).map(move |i| (a[i] - b[i]).abs()))
        .fold(0.0f32, f32::max);
    eprintln!("warm start: worst |warm − cold| over distance and gradient = {worst:.2e}");
    assert!(worst <= 2.6e-6, "{worst}");
}
