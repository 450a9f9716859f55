//! Big scenes: large unions become data with a bounding-volume hierarchy
//! (`ir::group`, `codegen::group`). The CPU reference against brute-force unions, the
//! GPU against the CPU, the same picture as the union written as code, and the growth
//! of compile time and WGSL with the number of primitives.

use glam::DVec3;
use sdfc::bench::{city, city_centre};
use sdfc::codegen::{self, Options};
use sdfc::driver;
use sdfc::gpu::{self, gpu_for_tests, ViewMode};
use sdfc::ir::eval;
use sdfc::view::View;
use std::time::{Duration, Instant};

use crate::common;
use common::Rng;

fn analysis(src: &str) -> driver::Analysis {
    let a = driver::check(src, None);
    assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
    a
}

fn shape_named(a: &driver::Analysis, name: &str) -> sdfc::ir::Shape {
    let scene = a.scene.as_ref().unwrap();
    scene
        .shapes
        .iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no shape {name}"))
        .shape
        .clone()
}

fn random_points(rng: &mut Rng, lo: DVec3, hi: DVec3, n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|_| lo + (hi - lo) * DVec3::new(rng.unit(), rng.unit(), rng.unit()))
        .collect()
}

#[test]
fn the_city_is_one_group_and_equals_the_brute_force_union() {
    let n = 1200;
    let a = analysis(&city(n, 0));
    let shape = shape_named(&a, "city");
    let root = shape.root();
    let g = shape.group(root).expect("the city's union is a group");
    assert_eq!((g.leaves.len(), g.others.len()), (n, 0));
    assert_eq!(g.tree.len(), 2 * n - 1);
    let mut rng = Rng(7);
    let side = (n as f64).sqrt().ceil();
    let h = DVec3::new(side / 2.0 + 1.0, 1.5, side / 2.0 + 1.0);
    for p in random_points(&mut rng, -h, h, 2000) {
        let brute = (0..n)
            .map(|i| (p - DVec3::from(city_centre(i, n))).length() - 0.4)
            .fold(f64::INFINITY, f64::min);
        let d = eval::distance(&shape, p);
        assert!((d - brute).abs() < 1e-12, "at {p}: {d} vs {brute}");
    }
}

/// Forty primitives of eight kinds, rotated, moved and painted: each a named shape of
/// its own (a single leaf, no group), and their union (a group).
fn mixed() -> String {
    mixed_turned(true)
}

/// [`mixed`], with a third of the primitives rotated (`turned`) or none.
fn mixed_turned(turned: bool) -> String {
    let prims = [
        "sphere(0.3)",
        "box([0.5, 0.3, 0.4])",
        "round_box([0.5, 0.3, 0.4], 0.05)",
        "torus(major: 0.3, minor: 0.1)",
        "capsule(a: [0, -0.2, 0], b: [0.1, 0.3, 0], radius: 0.1)",
        "cylinder(radius: 0.2, height: 0.5)",
        "octahedron(0.3)",
        "ellipsoid([0.3, 0.2, 0.25])",
    ];
    let mut s = String::from("material red { color = [0.8, 0.1, 0.1]; }\n");
    let mut names = Vec::new();
    for i in 0..40 {
        let prim = prims[i % prims.len()];
        let (x, z) = ((i % 8) as f64 * 0.9 - 3.15, (i / 8) as f64 * 0.9 - 1.8);
        let rot = if turned && i % 3 == 0 {
            format!(".rotate(axis: [0, 1, 0.5], angle: {}deg)", 17 * i)
        } else {
            String::new()
        };
        let paint = if i % 4 == 0 { ".paint(red)" } else { "" };
        let _ = std::fmt::Write::write_fmt(
            &mut s,
            format_args!("let p{i} = {prim}{rot}.translate([{x}, 0.1, {z}]){paint};\n"),
        );
        names.push(format!("p{i}"));
    }
    s + &format!("let all = {};\nrender all;\n", names.join(" | "))
}

#[test]
fn mixed_kinds_rotations_and_paints_equal_their_leaves_one_by_one() {
    let a = analysis(&mixed());
    let all = shape_named(&a, "all");
    let g = all.group(all.root()).expect("a group");
    assert_eq!(g.leaves.len(), 40);
    assert!(g.kinds().len() >= 7);
    let leaves: Vec<_> = (0..40).map(|i| shape_named(&a, &format!("p{i}"))).collect();
    let mut rng = Rng(11);
    let h = DVec3::new(4.5, 1.0, 2.5);
    for p in random_points(&mut rng, -h, h, 3000) {
        // The first leaf of least distance: a hard union's material.
        let (mut best, mut material) = (f64::INFINITY, 0);
        for l in &leaves {
            let (d, m) = eval::eval(l, p);
            if d < best {
                (best, material) = (d, m);
            }
        }
        let (d, m) = eval::eval(&all, p);
        assert!((d - best).abs() < 1e-9, "at {p}: {d} vs {best}");
        assert_eq!(m, material, "material at {p}");
    }
}

fn compile(a: &driver::Analysis) -> codegen::Module {
    let options = Options {
        walk: codegen::WalkForm::Loop,
        ..Default::default()
    };
    driver::compile(a, &options).unwrap().module
}

#[test]
fn the_gpu_walks_the_same_hierarchy_as_the_cpu() {
    let Some(gpu) = gpu_for_tests() else { return };
    // Turned leaves read a matrix; unturned ones of several kinds only the head; a
    // city's spheres (one kind, unturned) neither (codegen::group::walker).
    for src in [mixed_turned(true), mixed_turned(false), city(100, 0)] {
        let a = analysis(&src);
        let module = compile(&a);
        let target = a.scene.as_ref().unwrap().render.clone().unwrap();
        let mut rng = Rng(5);
        let b = target.root_node().bounds;
        let points = random_points(&mut rng, b.min - 0.5, b.max + 0.5, 4000);
        let got = gpu::eval_points(&gpu, &module, &points).unwrap();
        for (p, v) in points.iter().zip(&got) {
            let cpu = eval::distance(&target, *p);
            assert!(
                (cpu - v[0] as f64).abs() < 2e-5 * (1.0 + cpu.abs()),
                "at {p}: CPU {cpu} vs GPU {}",
                v[0]
            );
        }
    }
}

#[test]
fn the_picture_is_the_union_written_as_code() {
    let Some(gpu) = gpu_for_tests() else { return };
    // The same 40 spheres: a hard union (a group, as data) and a chain of smooth unions
    // with k = 1e-6 (code, as before groups; it differs by at most k / 4).
    let n = 40;
    let spheres: Vec<String> = (0..n)
        .map(|i| {
            let [x, y, z] = city_centre(i, n);
            format!("sphere(0.4).translate([{x}, {y}, {z}])")
        })
        .collect();
    let hard = format!("let s = {};\n", spheres.join(" | "));
    let smooth = format!(
        "let s = {};\n",
        spheres[1..]
            .iter()
            .fold(spheres[0].clone(), |acc, s| format!(
                "smooth_union({acc}, {s}, 0.000001)"
            ))
    );
    let tail = "render s {\n    camera = orbit(target: [0, 0, 0], distance: 11, yaw: 30deg, pitch: 45deg);\n    size = [96, 72];\n}\n";
    let picture = |src: String| {
        let a = analysis(&src);
        let module = compile(&a);
        let shape = a.scene.as_ref().unwrap().render.clone().unwrap();
        let v = View::new(a.program.render.as_ref(), &shape);
        let frame = gpu::render(
            &gpu,
            &module,
            &v,
            ViewMode::Color,
            std::path::Path::new("."),
        );
        (module, frame.unwrap())
    };
    let (grouped, a) = picture(hard + tail);
    let (coded, b) = picture(smooth + tail);
    assert!(grouped.wgsl.contains("group_walk_"));
    assert!(!coded.wgsl.contains("group_walk_1("));
    let differ = a
        .color
        .chunks(4)
        .zip(b.color.chunks(4))
        .filter(|(x, y)| x.iter().zip(y.iter()).any(|(u, v)| u.abs_diff(*v) > 2))
        .count();
    // Silhouette pixels may flip where a ray grazes a sphere.
    assert!(differ * 200 <= a.color.len() / 4, "{differ} pixels differ");
}

/// The fastest of three compiles (check, codegen and naga) and the WGSL's line count.
fn cost(n: usize) -> (Duration, usize) {
    let src = city(n, 0);
    let mut best = Duration::MAX;
    let mut lines = 0;
    for _ in 0..3 {
        let t = Instant::now();
        let a = driver::check(&src, None);
        let m = compile(&a);
        best = best.min(t.elapsed());
        lines = m.wgsl.lines().count();
    }
    (best, lines)
}

#[test]
fn ten_times_the_primitives_cost_at_most_fifteen_times_the_compile() {
    let (t1, l1) = cost(100);
    let (t2, l2) = cost(1000);
    eprintln!("100 spheres: {t1:?}, {l1} lines; 1,000 spheres: {t2:?}, {l2} lines");
    assert!(l2 <= 15 * l1, "{l1} → {l2} WGSL lines");
    assert!(
        t2 <= t1 * 15,
        "compile {t1:?} → {t2:?} for 10× the primitives"
    );
}

#[test]
fn an_edit_that_leaves_an_atlas_as_it_was_does_not_redo_its_geometry() {
    use sdfc::uv::diagnose::PREPARE_STATS;
    use std::sync::atomic::Ordering::Relaxed;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let src = std::fs::read_to_string(dir.join("robot.sdf")).unwrap();
    let first = driver::check(&src, Some(&dir));
    let (hits, misses) = (
        PREPARE_STATS[0].load(Relaxed),
        PREPARE_STATS[1].load(Relaxed),
    );
    // A comment and another definition: the atlas's inputs are the same.
    let edited = format!("// a comment\nlet spare = sphere(2);\n{src}");
    let second = driver::check(&edited, Some(&dir));
    assert!(PREPARE_STATS[0].load(Relaxed) > hits);
    assert_eq!(PREPARE_STATS[1].load(Relaxed), misses);
    assert_eq!(first.atlases, second.atlases);
    // The diagnostics still point into the edited text (the unused `spare`).
    assert!(second
        .diagnostics
        .iter()
        .any(|d| d.code == sdfc::codes::W_UNUSED));
    // A moved seed is prepared afresh.
    let moved = src.replacen(
        "seed chest_a = [-0.3, 0.35, 0.35]",
        "seed chest_a = [-0.31, 0.35, 0.35]",
        1,
    );
    assert_ne!(moved, src);
    driver::check(&moved, Some(&dir));
    assert!(PREPARE_STATS[1].load(Relaxed) > misses);
}

/// `sdfc bench --scale`'s scenes that are not cities: every generated scene checks
/// with no diagnostic, its spheres lie in the cube with their stated radii, the same
/// index gives the same sphere whatever `n`, and the language-server scene has about
/// 4,400 lines.
#[test]
fn scattered_scenes_are_valid_and_stable() {
    use sdfc::bench::{scattered, scattered_sphere, SCATTERED, SCATTERED_SIDE};
    for (n, seeds) in SCATTERED {
        let src = scattered(n, seeds);
        assert_eq!(src, scattered(n, seeds), "deterministic");
        let a = driver::check(&src, None);
        assert!(
            a.diagnostics.is_empty(),
            "scattered({n}, {seeds}): {:?}",
            a.diagnostics.first()
        );
        let shape = shape_named(&a, "cloud");
        if n >= 16 {
            let g = shape.group(shape.root()).expect("one group");
            assert_eq!(g.leaves.len(), n);
        }
        // The CPU field is the union of the stated spheres.
        let mut rng = Rng(n as u64 + 3);
        let h = DVec3::splat(SCATTERED_SIDE / 2.0 + 0.5);
        for p in random_points(&mut rng, -h, h, 300) {
            let brute = (0..n)
                .map(|i| {
                    let (c, r) = scattered_sphere(i);
                    (p - DVec3::from(c)).length() - r
                })
                .fold(f64::INFINITY, f64::min);
            assert!((eval::distance(&shape, p) - brute).abs() < 1e-9);
        }
        if seeds > 0 {
            let lines = src.lines().count();
            assert_eq!(lines, 4428, "the language server's scene");
            assert!(a.atlases.iter().all(|x| x.is_some()), "the atlas prepares");
        }
    }
    for i in 0..5000 {
        let (c, r) = scattered_sphere(i);
        assert!(c.iter().all(|x| x.abs() <= SCATTERED_SIDE / 2.0));
        assert!((0.05..=0.15).contains(&r));
    }
    // The same spheres on every machine: the first three, pinned (worked out by hand
    // from the generator's SplitMix64 constants), and the scene's text for them.
    assert_eq!(scattered_sphere(0), ([4.686, 0.966, 0.226], 0.056));
    assert_eq!(scattered_sphere(1), ([3.686, 3.872, 3.139], 0.149));
    assert_eq!(scattered_sphere(2), ([-2.301, 4.927, 2.77], 0.089));
    let small = scattered(12, 0);
    assert_eq!(
        small.lines().nth(2),
        Some("    sphere(0.056).translate([4.686, 0.966, 0.226]) |")
    );
    // A bigger scene starts with the smaller scene's spheres, in order.
    let spheres = |text: &str| -> Vec<String> {
        text.lines()
            .filter(|l| l.trim_start().starts_with("sphere("))
            .map(|l| l.trim().trim_end_matches([';', '|']).trim().to_string())
            .collect()
    };
    let (few, many) = (spheres(&small), spheres(&scattered(1200, 0)));
    assert_eq!(few.len(), 12);
    assert_eq!(few[..], many[..12]);
    // Seeds never share a sphere, even one seed per sphere, and stay within an atlas's
    // limit.
    let text = scattered(300, 300);
    let seeds: std::collections::HashSet<&str> = text
        .lines()
        .filter_map(|l| {
            l.trim()
                .strip_prefix("seed s")?
                .split_once(" = ")
                .map(|x| x.1)
        })
        .collect();
    assert_eq!(seeds.len(), 300, "distinct seed positions");
    assert!(driver::check(&text, None)
        .diagnostics
        .iter()
        .all(|d| d.severity != sdfc::diagnostic::Severity::Error));
    assert_eq!(
        scattered(1100, 1100).matches("    seed s").count(),
        sdfc::sema::MAX_SEEDS
    );
}
