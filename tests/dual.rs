//! Forward derivatives (`codegen::dual`, `shaders/dual.wgsl`): the gradient and value
//! the generated walk reads (`atlas_K_grad_value`) against fourth-order differences of
//! the f64 field, on every primitive, operation and warp, and on random scenes. Points
//! on the surface and off it; points within reach of a crease (where the f64 gradient
//! at two difference steps disagrees) have no gradient to compare and are left out.
//! GPU tests skip loudly without an adapter unless SDFC_REQUIRE_GPU=1.

use glam::DVec3;
use sdfc::gpu::{compute, gpu_for_tests, Gpu};
use sdfc::ir::eval;
use sdfc::uv::geodesic::exact_gradient;

/// The primitives differentiated by central differences of the primitive alone
/// (`ir::prim::Kind::gradient` is None): their points are compared farther from creases
/// than the difference's step (1e-3 of the primitive's size).
const DIFFERENCED: &[&str] = &[
    "box_frame",
    "cone",
    "capped_cone",
    "octahedron",
    "hex_prism",
    "pyramid",
];

/// One shape per primitive kind, operation and warp.
const CASES: &[(&str, &str)] = &[
    ("sphere", "sphere(0.7)"),
    ("box", "box([1.2, 0.8, 0.6])"),
    ("round_box", "round_box([1.2, 0.8, 0.6], 0.15)"),
    ("box_frame", "box_frame([1.2, 0.9, 0.8], 0.12)"),
    ("torus", "torus(major: 0.6, minor: 0.2)"),
    (
        "capsule",
        "capsule(a: [0, -0.5, 0.1], b: [0.2, 0.5, 0], radius: 0.3)",
    ),
    ("cylinder", "cylinder(radius: 0.5, height: 1.2)"),
    ("cone", "cone(radius: 0.5, height: 1.0)"),
    (
        "capped_cone",
        "capped_cone(height: 1, bottom: 0.45, top: 0.2)",
    ),
    (
        "plane",
        "plane(normal: [0.3, 1, 0.2], offset: -0.1) & sphere(1.5)",
    ),
    ("ellipsoid", "ellipsoid([0.7, 0.4, 0.5])"),
    ("octahedron", "octahedron(0.7)"),
    ("hex_prism", "hex_prism(radius: 0.5, height: 0.8)"),
    ("tri_prism", "tri_prism(radius: 0.6, height: 0.8)"),
    ("pyramid", "pyramid(1)"),
    ("link", "link(length: 0.25, major: 0.3, minor: 0.1)"),
    (
        "union",
        "sphere(0.5) | box([0.8, 0.4, 0.4]).translate([0.4, 0, 0])",
    ),
    ("intersection", "sphere(0.7) & box([1.0, 0.8, 1.0])"),
    ("difference", "box([1, 1, 1]) - sphere(0.65)"),
    (
        "smooth_union",
        "smooth_union(sphere(0.5), box([0.8, 0.4, 0.4]).translate([0.5, 0, 0]), 0.2)",
    ),
    (
        "smooth_intersection",
        "smooth_intersection(sphere(0.7), box([1.0, 0.8, 1.0]), 0.15)",
    ),
    (
        "smooth_difference",
        "smooth_difference(box([1, 1, 1]), sphere(0.65), 0.1)",
    ),
    (
        "translate",
        "torus(major: 0.5, minor: 0.2).translate([0.3, -0.2, 0.1])",
    ),
    (
        "rotate",
        "box([1.2, 0.5, 0.4]).rotate(axis: [1, 2, 0.5], angle: 40deg)",
    ),
    (
        "rotate_x",
        "cylinder(radius: 0.3, height: 1.5).rotate_x(60deg)",
    ),
    ("scale", "torus(major: 0.5, minor: 0.2).scale(1.5)"),
    ("scale3", "sphere(0.5).scale([1.5, 0.6, 1])"),
    (
        "twist",
        "box([0.5, 1.6, 0.3]).twist(axis: [0, 1, 0], rate: 1.2)",
    ),
    (
        "twist_axis",
        "box([1.6, 0.4, 0.4]).twist(axis: [1, 0.3, 0], rate: 0.8)",
    ),
    (
        "bend",
        "box([2, 0.3, 0.5]).bend(axis: [1, 0, 0], rate: 0.6)",
    ),
    (
        "repeat",
        "sphere(0.15).repeat([0.6, 10, 0.6]) & box([1.4, 0.6, 1.4])",
    ),
    (
        "mirror",
        "sphere(0.35).translate([0.5, 0.1, 0]).mirror(normal: [1, 0, 0])",
    ),
    (
        "elongate",
        "torus(major: 0.3, minor: 0.1).elongate([0.4, 0.1, 0])",
    ),
    ("round", "box([0.6, 0.6, 0.6]).round(0.1)"),
    (
        "shell",
        "sphere(0.6).shell(0.1) - box([2, 0.5, 2]).translate([0, 0.6, 0])",
    ),
    (
        "paint",
        "sphere(0.6).paint(dull) | box([0.4, 0.4, 0.4]).translate([0.6, 0, 0])",
    ),
    // Run-time parameters (`PARAMS`): the shader reads them from the parameters' block.
    (
        "rotate_param",
        "box([1.2, 0.5, 0.4]).rotate(axis: [1, 2, 0.5], angle: turn)",
    ),
    (
        "twist_param",
        "box([0.5, 1.6, 0.3]).twist(axis: [0, 1, 0], rate: turn)",
    ),
    (
        "scale_param",
        "torus(major: 0.5, minor: 0.2).scale(0.5 + turn)",
    ),
    (
        "translate_param",
        "torus(major: 0.5, minor: 0.2).translate([turn, 0, 0])",
    ),
    ("round_param", "box([0.6, 0.6, 0.6]).round(0.1 * turn)"),
    (
        "smooth_param",
        "smooth_union(sphere(0.5), box([0.8, 0.4, 0.4]).translate([0.5, 0, 0]), 0.2 * turn)",
    ),
];

/// The run-time parameters the `_param` cases read (every scene declares them).
const PARAMS: &str = "param turn = 0.7 in [0.1, 1.5];\n";

/// A scene of `expr` with an atlas on it, one seed at `seed`.
fn scene(expr: &str, seed: Option<DVec3>) -> String {
    let atlas = match seed {
        Some(s) => format!(
            "atlas a on s {{\n    steps = 4;\n    max_distance = 1.0;\n    seed one = [{}, {}, {}];\n}}\nmaterial m {{\n    color = [a.uv.x, a.uv.y, 0.5];\n}}\n",
            s.x, s.y, s.z
        ),
        None => String::from("material m {\n    color = [0.5, 0.5, 0.5];\n}\n"),
    };
    format!(
        "{PARAMS}material dull {{\n    color = [0.2, 0.2, 0.2];\n}}\nlet s = {expr};\n{atlas}render s.paint(m) {{\n    camera = orbit(distance: 4);\n}}\n"
    )
}

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
    fn unit(&mut self) -> DVec3 {
        DVec3::new(self.next(), self.next(), self.next()) * 2.0 - DVec3::ONE
    }
}

/// The largest gradient and value errors of the shader's derivative against the f64
/// field at points on and near the surface of `expr`, and how many points were
/// compared. Fails the test where the scene does not compile or has no forward
/// derivative.
fn compare(gpu: &Gpu, name: &str, expr: &str, rng: &mut Rng) -> (f64, f64, usize) {
    // At least the f64 reference's own stencil (2e-4 of the scale, twice).
    let reach = if DIFFERENCED.contains(&name) {
        5e-3
    } else {
        1e-3
    };
    // The surface first, for the seed and the points.
    let plain = sdfc::driver::check(&scene(expr, None), None);
    assert!(!plain.has_errors(), "{name}: {:?}", plain.diagnostics);
    let shape = sdfc::driver::pick_shape(plain.scene.as_ref().unwrap(), None).unwrap();
    let field = plain.field(shape);
    let mut points = Vec::new();
    while points.len() < 400 {
        let Some(q) = eval::project(field, rng.unit() * 1.2, 1e-9) else {
            continue;
        };
        if q.length() > 3.0 {
            continue;
        }
        // On the surface, and off it by up to a tenth of the scale either way.
        let off = if points.len() % 2 == 0 {
            DVec3::ZERO
        } else {
            rng.unit() * 0.1
        };
        points.push(q + off);
    }
    let analysis = sdfc::driver::check(&scene(expr, Some(points[0])), None);
    assert!(!analysis.has_errors(), "{name}: {:?}", analysis.diagnostics);
    let options = sdfc::codegen::Options {
        walk: sdfc::codegen::WalkForm::Loop,
        ..Default::default()
    };
    let module = match sdfc::driver::compile(&analysis, &options) {
        Ok(c) => c.module,
        Err(e) => panic!("{name}: {e:?}"),
    };
    assert!(
        module.wgsl.contains("fn atlas_0_dual("),
        "{name}: no forward derivative"
    );
    let got = compute::eval_atlas_gradients(gpu, &module, 0, 1e-3, &points).unwrap();
    let f = |x: DVec3| eval::distance(field, x);
    let (mut worst_g, mut worst_f, mut compared) = (0.0f64, 0.0f64, 0);
    for (x, g) in points.iter().zip(&got) {
        // Within `reach` of a crease the gradient jumps: one-sided differences that far
        // disagree by far more than the curvature explains.
        let one_sided = |e: DVec3| {
            let (ahead, behind) = (f(*x + e * reach) - f(*x), f(*x) - f(*x - e * reach));
            (ahead - behind).abs() / reach
        };
        if [DVec3::X, DVec3::Y, DVec3::Z]
            .into_iter()
            .any(|e| one_sided(e) > 0.05)
        {
            continue;
        }
        // Fourth-order differences of step 1e-6: far below f32, and small enough that
        // a seam where the second derivative jumps (a smooth minimum's band, a box's
        // outside corner region) costs under 1e-6.
        let want = exact_gradient(&f, *x, 1e-2);
        compared += 1;
        let have = DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64);
        if (have - want).length() > worst_g && std::env::var("DUAL_DEBUG").is_ok() {
            eprintln!(
                "  {name}: at {x:.5} shader {have:.5} f64 {want:.5} f {:.6}",
                f(*x)
            );
        }
        worst_g = worst_g.max((have - want).length());
        worst_f = worst_f.max((g[3] as f64 - f(*x)).abs());
    }
    (worst_g, worst_f, compared)
}

#[test]
fn forward_derivatives_match_the_f64_field_on_every_primitive_operation_and_warp() {
    let Some(gpu) = gpu_for_tests() else { return };
    let mut rng = Rng(7);
    let mut failures = Vec::new();
    for (name, expr) in CASES {
        let (g, f, n) = compare(&gpu, name, expr, &mut rng);
        eprintln!("{name}: {n} points, gradient error {g:.2e}, value error {f:.2e}");
        // Differences of the primitive alone (step 1e-3 of its size, in f32) err by
        // about the step over the distance to a seam where the curvature jumps.
        let tolerance = if DIFFERENCED.contains(name) {
            5e-3
        } else {
            1e-4
        };
        if n < 100 || g > tolerance || f > 2e-5 {
            failures.push(format!(
                "{name}: {n} points, gradient {g:.2e}, value {f:.2e}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Random trees of primitives, operations and warps.
fn random_shape(rng: &mut Rng, depth: u32) -> String {
    let pick = |rng: &mut Rng, n: usize| ((rng.next() * n as f64) as usize).min(n - 1);
    if depth == 0 {
        let c = rng.unit() * 0.4;
        let leaf = match pick(rng, 6) {
            0 => format!("sphere({:.3})", 0.3 + 0.3 * rng.next()),
            1 => format!(
                "box([{:.3}, {:.3}, {:.3}])",
                0.4 + rng.next(),
                0.4 + rng.next(),
                0.4 + rng.next()
            ),
            2 => format!(
                "torus(major: {:.3}, minor: {:.3})",
                0.4 + 0.2 * rng.next(),
                0.1 + 0.1 * rng.next()
            ),
            3 => format!(
                "cylinder(radius: {:.3}, height: {:.3})",
                0.2 + 0.3 * rng.next(),
                0.5 + rng.next()
            ),
            4 => format!(
                "capsule(a: [0, -0.4, 0], b: [0.1, 0.4, 0.2], radius: {:.3})",
                0.15 + 0.2 * rng.next()
            ),
            _ => format!(
                "ellipsoid([{:.3}, {:.3}, {:.3}])",
                0.3 + 0.3 * rng.next(),
                0.3 + 0.3 * rng.next(),
                0.3 + 0.3 * rng.next()
            ),
        };
        return format!("{leaf}.translate([{:.3}, {:.3}, {:.3}])", c.x, c.y, c.z);
    }
    let a = random_shape(rng, depth - 1);
    match pick(rng, 8) {
        0 => format!(
            "smooth_union({a}, {}, {:.3})",
            random_shape(rng, depth - 1),
            0.05 + 0.2 * rng.next()
        ),
        1 => format!("({a} | {})", random_shape(rng, depth - 1)),
        2 => format!(
            "smooth_difference({a}, {}, {:.3})",
            random_shape(rng, depth - 1),
            0.05 + 0.1 * rng.next()
        ),
        3 => format!(
            "{a}.twist(axis: [0, 1, 0], rate: {:.3})",
            0.2 + 0.8 * rng.next()
        ),
        4 => format!(
            "{a}.bend(axis: [1, 0, 0], rate: {:.3})",
            0.2 + 0.5 * rng.next()
        ),
        5 => format!(
            "{a}.rotate(axis: [{:.3}, 1, {:.3}], angle: {:.1}deg)",
            rng.next(),
            rng.next(),
            90.0 * rng.next()
        ),
        6 => format!("{a}.round({:.3})", 0.02 + 0.05 * rng.next()),
        _ => format!("{a}.scale({:.3})", 0.8 + 0.4 * rng.next()),
    }
}

#[test]
fn forward_derivatives_match_the_f64_field_on_random_scenes() {
    let Some(gpu) = gpu_for_tests() else { return };
    let mut rng = Rng(2026);
    let mut failures = Vec::new();
    for i in 0..12 {
        let expr = random_shape(&mut rng, 3);
        let (g, f, n) = compare(&gpu, &format!("random {i}"), &expr, &mut rng);
        eprintln!("random {i}: {n} points, gradient error {g:.2e}, value error {f:.2e}: {expr}");
        if n < 100 || g > 1e-4 || f > 2e-5 {
            failures.push(format!(
                "random {i} ({expr}): {n} points, gradient {g:.2e}, value {f:.2e}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
