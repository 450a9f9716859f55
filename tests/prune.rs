//! Per-seed pruned fields (`uv::prune`) on the CPU reference: inside a walk's guard,
//! wherever the pruned value is within the window, it equals the full field, and the
//! guarded field (what the generated code evaluates) equals it everywhere.

use glam::DVec3;
use sdfc::driver::check;
use sdfc::ir::eval;
use sdfc::uv::prune::{Pruning, GUARD, WINDOW};
use sdfc::uv::Atlas;
use std::path::Path;

use crate::common;
use common::Rng;

fn atlases(src: &str) -> Vec<Atlas> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let a = check(src, Some(&dir));
    assert!(!a.has_errors(), "{:#?}", a.diagnostics);
    a.atlases.into_iter().flatten().collect()
}

/// Checks the pruning of `atlas` at every seed and at several reaches, on points of the
/// guard ball and points near the surface inside it. Returns how many points were
/// evaluated pruned (some bit clear, inside the guard and the window).
fn check_exact(name: &str, atlas: &Atlas, pr: &Pruning, rng: &mut Rng) -> usize {
    let shape = &atlas.shape;
    let d = atlas.params.max_distance;
    let mut pruned_points = 0;
    for (j, s) in atlas.seeds.iter().enumerate() {
        let c = s.seed.p;
        for reach in [0.05, 0.15, 0.3, 0.6, 1.0].map(|t| t * d) {
            let mask = pr.mask(j, reach);
            let walk = sdfc::uv::prune::WalkMask {
                mask,
                centre: c,
                reach,
            };
            let radius = GUARD * reach + pr.eps;
            let window = WINDOW * reach + pr.eps;
            for i in 0..60 {
                let dir = DVec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                );
                let mut y = c + dir.normalize_or_zero() * radius * rng.unit().cbrt();
                // Half the points near the surface (where walks query), off it by up to
                // the window.
                if i % 2 == 0 {
                    if let Some(q) = eval::project(shape, y, 1e-10) {
                        let g = eval::gradient(shape, q).normalize_or_zero();
                        y = q + g * window * rng.range(-1.2, 1.2);
                    }
                }
                let full = eval::distance(shape, y);
                let v = pr.pruned(shape, y, mask);
                assert!(
                    v >= full - 1e-12,
                    "{name}: pruning lowered f at {y} (seed {j}, reach {reach}): {v} < {full}"
                );
                let inside = (y - c).length() <= radius;
                if inside && v.abs() < window {
                    assert!(
                        (v - full).abs() <= 1e-12,
                        "{name}: seed {j}, reach {reach}, mask {mask:#x}: pruned f = {v}, full f = {full} at {y}"
                    );
                    if mask != u32::MAX {
                        pruned_points += 1;
                    }
                }
                let guarded = pr.field(shape, y, walk);
                assert_eq!(guarded, full, "{name}: the guarded field differs at {y}");
            }
        }
    }
    pruned_points
}

#[test]
fn pruned_fields_equal_the_full_field_on_every_example() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .collect();
    names.sort();
    let mut rng = Rng(0x5eed_0f_9e0);
    let (mut pruned_atlases, mut pruned_points) = (0, 0);
    for path in names {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        for atlas in atlases(&std::fs::read_to_string(&path).unwrap()) {
            let Some(pr) = atlas.pruning() else {
                continue;
            };
            pruned_atlases += 1;
            pruned_points += check_exact(&name, &atlas, &pr, &mut rng);
        }
    }
    // The test means something: pruning applies to several examples and many points.
    assert!(pruned_atlases >= 3, "only {pruned_atlases} atlases pruned");
    assert!(pruned_points >= 500, "only {pruned_points} points pruned");
}

#[test]
fn the_robots_arm_walks_skip_the_far_parts() {
    let src =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/robot.sdf"))
            .unwrap();
    let atlas = atlases(&src).remove(0);
    let pr = atlas.pruning().expect("the robot's union is pruned");
    // The six parts, and the unions of the chain that some seed is far from (those
    // that hold the whole torso and more are no candidates).
    assert!(
        (6..=9).contains(&pr.candidates.len()),
        "{:?}",
        pr.candidates
    );
    let j = atlas
        .seed_names
        .iter()
        .position(|n| n == "arm_l_hi")
        .unwrap();
    let skipped = |reach: f64| pr.mask(j, reach).count_zeros();
    // A short walk on the left arm: the right arm, both legs and the head are far.
    let near = skipped(0.3);
    assert!(near >= 4, "a reach of 0.3 skips only {near} operands");
    // Over the whole D the walk may reach everything but the far arm.
    let far = skipped(atlas.params.max_distance);
    assert!(far < near, "{far} skipped at D, {near} at 0.3");
    // A seed on the torso's front never skips the torso (its own operand).
    let chest = atlas
        .seed_names
        .iter()
        .position(|n| n == "chest_a")
        .unwrap();
    let torso_bit = pr
        .candidates
        .iter()
        .position(|&c| {
            let b = atlas.shape[c].bounds;
            (b.min - DVec3::new(-0.6, -0.7, -0.35)).length() < 1e-9
        })
        .expect("the torso is a candidate");
    assert_ne!(pr.mask(chest, 0.05) & (1 << torso_bit), 0);
}

/// Smooth unions (whose radii widen the margins), stretched operands (Lipschitz bounds
/// above 1), a `let` used twice, nested unions and a difference on the chain's side.
#[test]
fn smooth_stretched_and_shared_operands_stay_exact() {
    let src = r#"
let bead = sphere(0.2);
let rod = capsule(a: [0, -0.5, 0], b: [0, 0.5, 0], radius: 0.12);
let egg = ellipsoid([0.3, 0.15, 0.2]).translate([1.4, 0, 0]);
let squashed = box([0.2, 0.2, 0.2]).scale([1, 0.4, 2.0]).translate([-1.3, 0.2, 0]);
let twisted = box([0.1, 0.5, 0.1]).twist(axis: [0, 1, 0], rate: 1.5).translate([0, 0, 1.3]);
let left = smooth_union(bead.translate([-0.6, 0, 0]), squashed, 0.2);
let right = smooth_union(bead.translate([0.6, 0, 0]), egg, 0.15) | rod.translate([0.6, -1.0, 0]);
let cut = box([0.3, 0.3, 0.3]).translate([0, -1.2, 0]) - bead.translate([0, -1.2, 0.3]);
let scene = left | right | twisted | cut | rod;

atlas skin on scene {
    max_distance = 2.0;
    seed a = [-0.6, 0.2, 0];
    seed b = [0.6, 0.2, 0];
    seed c = [1.4, 0.15, 0];
    seed d = [0, 0.5, 1.3];
    seed e = [0.12, 0, 0];
    seed f = [0, -1.2, -0.3];
}
"#;
    let atlas = atlases(src).remove(0);
    let pr = atlas.pruning().expect("the scene is pruned");
    let mut rng = Rng(77);
    let pruned = check_exact("synthetic", &atlas, &pr, &mut rng);
    assert!(pruned >= 300, "only {pruned} points pruned");
}

/// A stretched operand's field grows more slowly than its distance (a non-uniform scale
/// multiplies by the smallest factor): at the end of its long axis it is far below the
/// distance to its box (0.09 against 4.7 here). Its limit divides by its bound L, so
/// only short walks skip it, and along the axis, next to the seed, the pruned field
/// stays the full one.
#[test]
fn stretched_operands_are_pruned_only_as_far_as_their_stretch_allows() {
    let src = "let ball = sphere(1);
let rod = sphere(1).scale([10, 0.2, 0.2]).translate([16, 0, 0]);
let body = ball | rod;
atlas skin on body {
    max_distance = 3.5;
    seed s = [1, 0, 0];
}
render body;
";
    let atlas = atlases(src).remove(0);
    let shape = &atlas.shape;
    let c = DVec3::new(1.0, 0.0, 0.0);
    // The rod's field next to the seed, against its box's distance (5).
    let rod = eval::distance(shape, DVec3::new(1.3, 0.0, 0.0));
    assert!(rod < 0.1, "{rod}");
    let pr = atlas.pruning().expect("the rod is a candidate");
    // Short walks skip it (its bound accounts for the stretch); longer ones do not.
    assert_eq!(pr.mask(0, 0.5).count_zeros(), 1);
    assert_eq!(pr.mask(0, 3.5).count_zeros(), 0);
    for reach in [0.25, 0.5, 0.75, 1.0, 2.0, 3.5] {
        let mask = pr.mask(0, reach);
        for k in 0..=40 {
            let y = c + DVec3::new(0.01 * k as f64, 0.0, 0.0);
            let full = eval::distance(shape, y);
            let v = pr.pruned(shape, y, mask);
            if (y - c).length() <= GUARD * reach + pr.eps && v.abs() < WINDOW * reach + pr.eps {
                assert!(
                    (v - full).abs() <= 1e-12,
                    "reach {reach}, mask {mask:#x}: pruned f = {v}, full f = {full} at {y}"
                );
            }
        }
    }
}
