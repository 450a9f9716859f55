//! Textured CSG (§5.1): each operand of a union keeps its own material and atlas. Away
//! from a smooth union's blend band, each operand's own material and uv apply exactly;
//! inside it, the materials mix with the distance blend's weight (the polynomial
//! smin's). The CPU reference against analytic distances, then the GPU's
//! `scene_surface` against the CPU on examples/textured_csg.sdf. GPU tests skip loudly
//! without an adapter (fail with SDFC_REQUIRE_GPU=1).

use glam::DVec3;
use sdfc::codegen::{Options, WalkForm};
use sdfc::driver::{check, Analysis};
use sdfc::gpu::{self, gpu_for_tests};
use sdfc::ir::eval;
use sdfc::reference::material::{MaterialEval, MaterialValue};
use std::path::Path;

use crate::common;
use common::Rng;

fn example() -> String {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    std::fs::read_to_string(dir.join("textured_csg.sdf")).unwrap()
}

fn analyze(src: &str) -> Analysis {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let a = check(src, Some(&dir));
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    a
}

const K: f64 = 0.35;
const SOFT: DVec3 = DVec3::new(1.1, 0.0, 0.0);

/// The ball's and the slab's own distances at a point of the soft copy (the ball's is
/// exact; the slab's from the IR of a slab alone).
fn operand_distances(slab: &sdfc::ir::Shape, p: DVec3) -> (f64, f64) {
    let q = p - SOFT;
    (q.length() - 0.7, eval::distance(slab, q))
}

fn slab() -> sdfc::ir::Shape {
    let a = analyze(
        "let s = round_box([1.6, 0.5, 1.2], radius: 0.06).translate([0, -0.45, 0]);\nrender s;",
    );
    a.scene.as_ref().unwrap().render.clone().unwrap()
}

/// The blend's weight is the smin's, clamp(0.5 − 0.5 (d_slab − d_ball) / k, 0, 1) for
/// the slab; beyond the band (|d_ball − d_slab| ≥ k) a single material applies, and
/// the surface's material there is that operand's own material with its own atlas's
/// uv, exactly.
#[test]
fn each_operand_keeps_its_material_away_from_the_band_and_blends_inside() {
    let src = example();
    let a = analyze(&src);
    let target = a.scene.as_ref().unwrap().render.clone().unwrap();
    assert!(target.blends_materials());
    let m = MaterialEval::load(&a.program, &a.atlases).unwrap();
    let slab = slab();
    let (brick, tile) = (1u32, 2u32);
    let (mut outside, mut inside) = (0, 0);
    for (x, n) in common::surface_points(&target, 600, 7, |_| true) {
        let (_, bl) = eval::eval_blend(&target, x);
        let got = m.eval_surface(&target, x, n, 1e-3);
        if x.x < 0.0 {
            // The hard copy: the nearer operand's material alone.
            assert_eq!(bl.t, 0.0);
            assert_eq!(got, m.eval(bl.a, x, n, 1e-3));
            continue;
        }
        let (db, ds) = operand_distances(&slab, x);
        let t = (0.5 - 0.5 * (ds - db) / K).clamp(0.0, 1.0);
        if (db - ds).abs() >= K {
            outside += 1;
            let own = if db < ds { brick } else { tile };
            assert_eq!((bl.a, bl.t), (own, 0.0), "at {x}");
            assert_eq!(got, m.eval(own, x, n, 1e-3), "at {x}");
        } else if t > 1e-6 && t < 1.0 - 1e-6 {
            inside += 1;
            assert_eq!((bl.a, bl.b), (brick, tile), "at {x}");
            assert!((bl.t - t).abs() < 1e-9, "at {x}: {} vs {t}", bl.t);
            let (ma, mb) = (m.eval(brick, x, n, 1e-3), m.eval(tile, x, n, 1e-3));
            assert!((got.color - ma.color.lerp(mb.color, t)).length() < 1e-9);
            assert!(
                (got.roughness - (ma.roughness + (mb.roughness - ma.roughness) * t)).abs() < 1e-9
            );
        }
    }
    eprintln!("{outside} points beyond the band, {inside} inside it");
    assert!(outside > 100 && inside > 10, "{outside} {inside}");
}

/// Distances are untouched by the materials: scene_blend's distance is scene_map's.
#[test]
fn blend_distance_equals_the_plain_distance() {
    let a = analyze(&example());
    let target = a.scene.as_ref().unwrap().render.clone().unwrap();
    let mut rng = Rng(2);
    for _ in 0..500 {
        let p = DVec3::new(
            rng.range(-3.0, 3.0),
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
        );
        assert_eq!(eval::eval_blend(&target, p).0, eval::distance(&target, p));
    }
}

fn module(a: &Analysis) -> sdfc::codegen::Module {
    let options = Options {
        walk: WalkForm::Loop,
        ..Default::default()
    };
    sdfc::driver::compile(a, &options).unwrap().module
}

fn close(a: &MaterialValue, g: &gpu::MaterialSample, tol: f64) -> bool {
    let c = DVec3::from_array(g.color.map(|x| x as f64));
    (a.color - c).abs().max_element() <= tol
        && (a.roughness - g.roughness as f64).abs() <= tol
        && (a.metallic - g.metallic as f64).abs() <= tol
}

/// The GPU's `scene_surface` against `MaterialEval::eval_surface`:
/// - with the materials replaced by constant colours, the colour is the blend weight
///   itself;
/// - on the textured example, the textures' colours mixed.
///
/// Colour, roughness and metallic within 2/255 wherever the CPU's colour is continuous
/// (unchanged by 1e-4 moves: away from the hard union's switch between materials, the
/// checker's edges and the frontiers of unmerged seeds).
#[test]
fn gpu_textured_csg_agrees_with_the_cpu() {
    let Some(gpu) = gpu_for_tests() else { return };
    let src = example();
    let probe = src
        .replace(
            "color = bricks.sample(skin.uv * 1.5).rgb;",
            "color = [1, 0, 0];",
        )
        .replace(
            "color = mix([0.15, 0.3, 0.55], [0.85, 0.85, 0.8], checker(tiles.uv, 4));",
            "color = [0, 0, 1];",
        );
    assert_ne!(probe, src);
    for (name, src) in [("weights", probe.as_str()), ("textured", src.as_str())] {
        let a = analyze(src);
        let target = a.scene.as_ref().unwrap().render.clone().unwrap();
        let m = MaterialEval::load(&a.program, &a.atlases).unwrap();
        let points = common::surface_points(&target, 300, 13, |_| true);
        // Half a level-0 texel (1.5 repeats of the 128-texel bricks per unit of uv).
        let footprint = 0.5 / (1.5 * 128.0);
        let samples: Vec<(DVec3, DVec3, f64)> =
            points.iter().map(|&(x, n)| (x, n, footprint)).collect();
        let got = gpu::eval_materials(&gpu, &module(&a), m.textures(), &samples).unwrap();
        let (mut compared, mut worst) = (0, 0.0f64);
        for ((x, n), g) in points.iter().zip(&got) {
            let cpu = m.eval_surface(&target, *x, *n, footprint);
            {
                let moved = [DVec3::X, DVec3::Y, DVec3::Z].iter().any(|e| {
                    let c = m.eval_surface(&target, *x + *e * 1e-4, *n, footprint);
                    (c.color - cpu.color).abs().max_element() > 1.0 / 255.0
                });
                if moved {
                    continue;
                }
            }
            compared += 1;
            let c = DVec3::from_array(g.color.map(|x| x as f64));
            worst = worst.max((cpu.color - c).abs().max_element());
            assert!(
                close(&cpu, g, 2.0 / 255.0),
                "{name} at {x}: {cpu:?} vs {g:?}"
            );
        }
        eprintln!("{name}: {compared}/300 compared, worst colour {:.4}", worst);
        assert!(compared >= 250, "{name}: {compared}");
    }
}
