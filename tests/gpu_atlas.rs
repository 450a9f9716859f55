//! Implicit UVs part 2 on the GPU (the software adapter in CI): Alg. 2's blended uv
//! from the generated shader against the f64 CPU reference on every example, the seed
//! grid against the plain scan, and the debug views.
//!
//! These modules use the rolled walk (`WalkForm::Loop`): on the software adapter the
//! unrolled form takes tens of seconds per pipeline, and tests/gpu.rs already checks
//! that the unrolled and rolled walks agree to 1e-5.

use glam::{DVec2, DVec3};
use sdfc::codegen::{self, Options, SeedGridChoice};
use sdfc::driver::check;
use sdfc::gpu::{self, gpu_for_tests, ViewMode};
use sdfc::ir::eval;
use sdfc::uv::{Atlas, Status};
use sdfc::view::View;
use std::path::{Path, PathBuf};

use crate::common;
use common::Rng;

fn examples() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .collect();
    v.sort();
    v
}

/// Points on the atlas's surface; where the render uses the atlas's shape warped or
/// moved (a rest pose, §5.1), on the render target's surface, where the atlas views
/// query it.
fn surface_points(a: &Atlas, target: &sdfc::ir::Shape, n: usize, seed: u64) -> Vec<DVec3> {
    let shape = if a.rest.is_identity() {
        &a.shape
    } else {
        target
    };
    let b = shape.framing_bounds();
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    for _ in 0..n * 4 {
        let r = DVec3::new(rng.unit(), rng.unit(), rng.unit());
        if let Some(x) = eval::project(shape, b.min + (b.max - b.min) * r, 1e-7) {
            out.push(x);
            if out.len() == n {
                break;
            }
        }
    }
    out
}

#[test]
fn gpu_blended_uv_agrees_with_the_cpu_on_every_example() {
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut atlases_checked = 0;
    for path in examples() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let src = std::fs::read_to_string(&path).unwrap();
        let analysis = check(&src, Some(&dir));
        assert!(!analysis.has_errors());
        for (k, def) in analysis.program.atlases.iter().enumerate() {
            let atlas = analysis.atlases[k].as_ref().unwrap();
            let target = analysis.scene.as_ref().unwrap().render.clone().unwrap();
            let points = surface_points(atlas, &target, 600, 17 + k as u64);
            let scale = sdfc::uv::atlas::scale(&atlas.shape);
            let mut results = Vec::new();
            // The grid (for more than 4 seeds, as by default) with pruned walks, and the
            // plain scan with whole ones and the seeds read from the tables buffer
            // (--seed-data buffer) instead of baked in.
            let choices: &[SeedGridChoice] = if atlas.seeds.len() > 4 {
                &[SeedGridChoice::On, SeedGridChoice::Off]
            } else {
                &[SeedGridChoice::Off]
            };
            for &grid in choices {
                let options = Options {
                    atlas: Some(def.name.clone()),
                    seed_grid: grid,
                    walk: codegen::WalkForm::Loop,
                    // The first variant with the walks pruned per seed (uv::prune,
                    // opt-in), checked against the CPU and the unpruned plain scan.
                    prune: grid == choices[0],
                    seed_data: if choices.len() > 1 && grid != choices[0] {
                        codegen::SeedData::Buffer
                    } else {
                        codegen::SeedData::Baked
                    },
                    ..Default::default()
                };
                let module = sdfc::driver::compile(&analysis, &options).unwrap().module;
                results.push(gpu::eval_atlas(&gpu, &module, &points).unwrap());
            }
            let (mut compared, mut worst, mut creased) = (0usize, 0.0f64, 0usize);
            for (i, x) in points.iter().enumerate() {
                let (g, plain) = (&results[0][i], &results.last().unwrap()[i]);
                assert_eq!(
                    (g.status, g.seed),
                    (plain.status, plain.seed),
                    "{name}: the grid search and the plain scan differ at {x}"
                );
                // The views' query: at the rest point (capsule.sdf renders its atlas's
                // shape twisted), not moved onto the surface.
                let cpu = atlas.sample_at_with(*x, false);
                // A point on a crease (a box's edge, where projection lands) has no
                // normal: the walk starts from a one-sided gradient, which the shader's
                // f32 and the reference's f64 may take from different sides.
                if on_crease(atlas, *x, scale) {
                    creased += 1;
                    continue;
                }
                if cpu.status != Status::Ok
                    || g.status != 0
                    || cpu.seed.map(|s| s as i32) != Some(g.seed)
                {
                    continue;
                }
                compared += 1;
                // Every variant's uv against the CPU's.
                for r in &results {
                    let g = &r[i];
                    let gpu_uv = DVec2::new(g.uv[0] as f64, g.uv[1] as f64);
                    // Relative to the uv's size, floored at a tenth of the shape's size.
                    let err = (cpu.uv - gpu_uv).length() / cpu.uv.length().max(0.1 * scale);
                    worst = worst.max(err);
                    assert!(
                        err <= 1e-3,
                        "{name} `{}`: at {x}: CPU {} vs GPU {gpu_uv} (relative {err:.2e})",
                        def.name,
                        cpu.uv
                    );
                    assert!((cpu.weight - g.weight as f64).abs() < 1e-2);
                }
            }
            let ok = points
                .iter()
                .filter(|x| {
                    atlas.sample_at_with(**x, false).status == Status::Ok
                        && !on_crease(atlas, **x, scale)
                })
                .count();
            eprintln!(
                "{name} `{}`: {compared} of {ok} ok points off creases compared ({creased} on creases), max relative |uv_GPU − uv_CPU| = {worst:.2e}",
                def.name
            );
            // Points on a frontier may pick the other seed in f32.
            assert!(
                compared as f64 >= 0.98 * ok as f64,
                "{name}: only {compared} of {ok}"
            );
            atlases_checked += 1;
        }
    }
    assert!(atlases_checked >= 8, "{atlases_checked}");
}

struct Picture {
    color: Vec<u8>,
}

impl Picture {
    fn pixels(&self) -> impl Iterator<Item = [u8; 3]> + '_ {
        self.color.chunks(4).map(|c| [c[0], c[1], c[2]])
    }
    fn count(&self, f: impl Fn([u8; 3]) -> bool) -> usize {
        self.pixels().filter(|p| f(*p)).count()
    }
}

fn view(gpu: &gpu::Gpu, example: &str, mode: ViewMode) -> Picture {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let src = std::fs::read_to_string(dir.join(example)).unwrap();
    let a = check(&src, Some(&dir));
    let options = Options {
        walk: codegen::WalkForm::Loop,
        ..Default::default()
    };
    let module = sdfc::driver::compile(&a, &options).unwrap().module;
    let shape = a.scene.as_ref().unwrap().render.clone().unwrap();
    let mut v = View::new(a.program.render.as_ref(), &shape);
    (v.width, v.height) = (120, 120);
    let frame = gpu::render(gpu, &module, &v, mode, &dir).unwrap();
    Picture { color: frame.color }
}

#[test]
fn seams_show_only_between_unmerged_seeds() {
    let Some(gpu) = gpu_for_tests() else { return };
    // The seam colour, linear (0.95, 0.1, 0.1), is about (250, 89, 89) in sRGB.
    let red = |p: [u8; 3]| p[0] > 200 && p[1] < 120 && p[2] < 120;
    // The plate's four seeds are merged in a ring: no seam on it.
    let plate = view(&gpu, "plate_hole.sdf", ViewMode::Seams);
    assert_eq!(plate.count(red), 0, "a seam on the fully merged plate");
    // The robot has unmerged neighbours (each arm's back seed, the faces of boxes).
    let robot = view(&gpu, "robot.sdf", ViewMode::Seams);
    let seams = robot.count(red);
    assert!(seams > 20, "only {seams} seam pixels on the robot");
}

#[test]
fn seeds_blend_and_distortion_views() {
    let Some(gpu) = gpu_for_tests() else { return };
    // Voronoi cells: the plate with a hole shows its four seeds' colours.
    let seeds = view(&gpu, "plate_hole.sdf", ViewMode::Seeds);
    let mut colours: Vec<[u8; 3]> = seeds.pixels().collect();
    colours.sort();
    colours.dedup();
    assert!(colours.len() > 4);
    // Blend weights: the bands between merged seeds glow (red to yellow); cells are dark.
    let blend = view(&gpu, "plate_hole.sdf", ViewMode::Blend);
    let bright = blend.count(|p| p[0] > 150 && p[2] < 120);
    assert!(bright > 100, "only {bright} pixels in blend bands");
    // Distortion on the flat plate is (nearly) zero everywhere on the textured top face,
    // and clearly above zero on the curved blob.
    let flat = view(&gpu, "plate.sdf", ViewMode::Distortion);
    let hot = |p: [u8; 3]| p[0] > 120;
    let flat_hot = flat.count(hot);
    let blob = view(&gpu, "blob.sdf", ViewMode::Distortion);
    let blob_hot = blob.count(hot);
    assert!(
        flat_hot * 5 < blob_hot.max(1),
        "plate {flat_hot} vs blob {blob_hot} distorted pixels"
    );
}

/// Whether `x` lies on a crease of the atlas's field (within 1e-9 of its scale): its
/// one-sided differences along some axis disagree by more than curvature explains.
fn on_crease(atlas: &sdfc::uv::Atlas, x: glam::DVec3, scale: f64) -> bool {
    let f = |q: glam::DVec3| sdfc::ir::eval::distance(atlas.field(), q);
    let h = 1e-9 * scale;
    [glam::DVec3::X, glam::DVec3::Y, glam::DVec3::Z]
        .into_iter()
        .any(|e| ((f(x + e * h) - f(x)) - (f(x) - f(x - e * h))).abs() > 0.05 * h)
}
