//! Displacement (§5.2.2, Eq. 56-58) on the f64 CPU reference: analytic oracles, the
//! step bound against a fine march, and `sdfc fit-height` reproducing a target.

use glam::DVec3;
use sdfc::driver::{check, Analysis};
use sdfc::ir::{eval, Op};
use std::path::Path;

use crate::common;
use common::Rng;

fn checked(src: &str, dir: Option<&Path>) -> Analysis {
    let a = check(src, dir);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    a
}

/// The render target with the environment of its heights (textures, atlases).
fn render_shape(a: &Analysis) -> sdfc::ir::Field<'_> {
    a.field(a.scene.as_ref().unwrap().render.as_ref().unwrap())
}

/// A folder with one grey PNG (`w` × `h`, value per texel from `f`).
fn texture_dir(name: &str, w: u32, h: u32, f: impl Fn(u32, u32) -> u8) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let img = image::GrayImage::from_fn(w, h, |x, y| image::Luma([f(x, y)]));
    img.save(dir.path().join(name)).unwrap();
    dir
}

fn random_points(n: usize, half: f64, seed: u64) -> Vec<DVec3> {
    let mut r = Rng(seed);
    (0..n)
        .map(|_| {
            DVec3::new(
                r.range(-half, half),
                r.range(-half, half),
                r.range(-half, half),
            )
        })
        .collect()
}

#[test]
fn constant_height_on_a_sphere_is_the_bigger_sphere() {
    // A constant: f − h everywhere.
    let a = checked("render sphere(0.8).displace(0.15);", None);
    let s = render_shape(&a);
    for p in random_points(2000, 2.0, 7) {
        let d = eval::distance(s, p);
        assert!((d - (p.length() - 0.95)).abs() <= 1e-4, "at {p}: {d}");
    }
    assert_eq!(s.lipschitz(), 1.0);
    // The same through an atlas and a uniform texture: Π_f, the walk and the texel
    // read all run inside the band (|f| ≤ τ·ε = 2 · 0.15), the shift outside it.
    let dir = texture_dir("flat.png", 8, 8, |_, _| 128);
    let h = 0.3 * 128.0 / 255.0;
    let a = checked(
        "let ball = sphere(0.8);\nlet flat = image(\"flat.png\");\natlas skin on ball {\n    steps = 12;\n    seed front = [0, 0, 0.8];\n}\nrender ball.displace(flat.sample(skin.uv).r, scale: 0.3);\n",
        Some(dir.path()),
    );
    let s = render_shape(&a);
    let Op::Displace { height, .. } = &s.root_node().op else {
        panic!("the root is not a displacement");
    };
    assert!((height.lo - h).abs() < 1e-12 && (height.hi - h).abs() < 1e-12);
    assert_eq!(height.slope, 0.0);
    let (mut inside_band, mut checked_points) = (0, 0);
    for p in random_points(3000, 1.6, 11) {
        if p.length() < 0.2 {
            continue; // Π_f is undefined at the centre
        }
        let d = eval::distance(s, p);
        let want = p.length() - 0.8 - h;
        assert!((d - want).abs() <= 1e-4, "at {p}: {d}, want {want}");
        checked_points += 1;
        if (p.length() - 0.8).abs() <= 2.0 * h {
            inside_band += 1;
        }
    }
    assert!(
        checked_points > 2000 && inside_band > 300,
        "{inside_band} points in the band"
    );
}

/// Bilinear sampling with repeat of a grey image at uv (texel centres at half-integers),
/// written out here independently of sdfc's sampler.
fn bilinear(img: &image::GrayImage, u: f64, v: f64) -> f64 {
    let (w, h) = img.dimensions();
    let x = u * w as f64 - 0.5;
    let y = v * h as f64 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let t = |i: f64, j: f64| {
        let i = (i as i64).rem_euclid(w as i64) as u32;
        let j = (j as i64).rem_euclid(h as i64) as u32;
        img.get_pixel(i, j).0[0] as f64 / 255.0
    };
    let top = t(x0, y0) * (1.0 - fx) + t(x0 + 1.0, y0) * fx;
    let bottom = t(x0, y0 + 1.0) * (1.0 - fx) + t(x0 + 1.0, y0 + 1.0) * fx;
    top * (1.0 - fy) + bottom * fy
}

#[test]
fn height_map_on_a_plane_is_the_graph_of_the_height() {
    // f = z; the log map of a seed at the origin with tangent x is uv = (x, y).
    let f = |x: u32, y: u32| {
        let v = 0.5 + 0.4 * ((x as f64 * 0.7).sin() * (y as f64 * 0.45).cos());
        (v * 255.0).round() as u8
    };
    let dir = texture_dir("bumps.png", 16, 16, f);
    let img = image::open(dir.path().join("bumps.png"))
        .unwrap()
        .to_luma8();
    let a = checked(
        "let ground = plane(normal: [0, 0, 1]);\nlet bumps = image(\"bumps.png\");\natlas flat on ground {\n    steps = 8;\n    max_distance = 4;\n    seed o = [0, 0, 0] tangent [1, 0, 0];\n}\nrender ground.displace(bumps.sample(flat.uv * 0.25).r, scale: 0.2);\n",
        Some(dir.path()),
    );
    let s = render_shape(&a);
    let Op::Displace { height, .. } = &s.root_node().op else {
        panic!("the root is not a displacement");
    };
    let range = height.hi - height.lo;
    assert!(range > 0.1, "range {range}");
    let mut r = Rng(3);
    let mut worst: f64 = 0.0;
    for _ in 0..300 {
        let (x, y) = (r.range(-2.5, 2.5), r.range(-2.5, 2.5));
        // The root of f_h along z, by bisection between the band's sides.
        let (mut lo, mut hi) = (-0.5, 0.5);
        assert!(eval::distance(s, DVec3::new(x, y, lo)) < 0.0);
        assert!(eval::distance(s, DVec3::new(x, y, hi)) > 0.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if eval::distance(s, DVec3::new(x, y, mid)) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let want = 0.2 * bilinear(&img, x * 0.25, y * 0.25);
        worst = worst.max((lo - want).abs() / range);
    }
    eprintln!("worst |z − h(x, y)| / range: {worst:.2e}");
    assert!(worst <= 1e-3, "worst {worst:.2e} of the height range");
}

/// A march with steps f/L from `o` along `dir`; at each step the segment to the next
/// point is sampled at 32 points: it fails if some sample is inside the displaced
/// surface (f < 0) before the march reaches the surface. Returns (hit, stepped through).
fn march(s: sdfc::ir::Field, lipschitz: f64, o: DVec3, dir: DVec3) -> (bool, bool) {
    let mut t = 0.0;
    for _ in 0..400 {
        let d = eval::distance(s, o + dir * t);
        if d < 1e-5 {
            return (true, false);
        }
        let step = d / lipschitz;
        for k in 1..=32 {
            let u = t + step * k as f64 / 32.0;
            if eval::distance(s, o + dir * u) < -1e-9 {
                return (false, true);
            }
        }
        t += step;
        if t > 8.0 {
            return (false, false);
        }
    }
    (false, false)
}

#[test]
fn sphere_tracing_with_the_bound_never_steps_through() {
    // A steep procedural height: slope 0.12 · 0.5 · 14 · √2 per unit of uv.
    let a = checked(
        "let ball = sphere(1);\natlas skin on ball {\n    steps = 10;\n    seed front = [0, 0, 1] tangent [1, 0, 0];\n}\nrender ball.displace(0.5 + 0.5 * sin(skin.uv.x * 14) * sin(skin.uv.y * 14), scale: 0.12);\n",
        None,
    );
    let s = render_shape(&a);
    let bound = s.lipschitz();
    assert!(bound > 1.5, "bound {bound}");
    let eye = DVec3::new(0.0, 0.0, 4.0);
    let mut r = Rng(5);
    let (mut hits, mut through, mut through_unit) = (0, 0, 0);
    let rays: Vec<DVec3> = (0..400)
        .map(|_| (DVec3::new(r.range(-0.9, 0.9), r.range(-0.9, 0.9), 0.0) - eye).normalize())
        .collect();
    for &dir in &rays {
        let (hit, stepped) = march(s, bound, eye, dir);
        hits += hit as usize;
        through += stepped as usize;
        // Without the displacement's bound (L = 1, the base's), steps overshoot.
        through_unit += march(s, 1.0, eye, dir).1 as usize;
    }
    eprintln!("bound {bound:.3}: {hits} hits, {through} through; L = 1: {through_unit} through");
    assert!(hits > 200, "only {hits} rays hit");
    assert_eq!(
        through, 0,
        "{through} rays stepped through the displaced surface"
    );
    assert!(
        through_unit > 0,
        "the check cannot fail here: no ray steps through even with L = 1"
    );
}

/// The head-like blob of `examples/fit_blob.sdf`, over a unit sphere with one seed.
const BLOB: &str = "let base = sphere(1);
let skull = ellipsoid([0.95, 1.12, 1.0]);
let nose = capsule(a: [0, 0.05, 0.9], b: [0, -0.18, 1.08], radius: 0.11);
let cheeks = sphere(0.34).translate([0.42, -0.28, 0.66]) | sphere(0.34).translate([-0.42, -0.28, 0.66]);
let ears = sphere(0.2).translate([0.93, 0.02, 0]) | sphere(0.2).translate([-0.93, 0.02, 0]);
let blob = smooth_union(smooth_union(skull, nose, 0.15), cheeks | ears, 0.2);
atlas skin on base {
    steps = 20;
    max_distance = 2.6;
    seed front = [0, 0, 1] tangent [1, 0, 0];
}
";

/// The root of `f` along the ray from the origin in direction `w`, between r = 0.5 and 2.
fn radial_root<'a>(s: impl Into<sdfc::ir::Field<'a>>, w: DVec3) -> f64 {
    let s = s.into();
    let (mut lo, mut hi) = (0.5, 2.0);
    assert!(eval::distance(s, w * lo) < 0.0 && eval::distance(s, w * hi) > 0.0);
    for _ in 0..60 {
        let m = 0.5 * (lo + hi);
        if eval::distance(s, w * m) > 0.0 {
            hi = m;
        } else {
            lo = m;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn fit_height_encodes_the_blob_as_a_displaced_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("fit.sdf");
    std::fs::write(&scene, format!("{BLOB}render blob;\n")).unwrap();
    let out = dir.path().join("h.png");
    let (code, stdout, stderr) = common::sdfc(&[
        "fit-height",
        scene.to_str().unwrap(),
        "--target",
        "blob",
        "--base",
        "base",
        "--size",
        "128",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    // A 16-bit grey PNG.
    let img = image::open(&out).unwrap();
    assert_eq!(img.color(), image::ColorType::L16);
    // The printed `displace` call reproduces the blob.
    let call = stdout.lines().skip(1).collect::<Vec<_>>().join("\n");
    assert!(call.contains("let fit = base.displace("), "{stdout}");
    let a = checked(&format!("{BLOB}{call}\nrender fit;\n"), Some(dir.path()));
    let fit = render_shape(&a);
    let blob = a.scene.as_ref().unwrap().shape("blob").unwrap();
    // Compare the radial distance to both surfaces over the chart's reach (geodesic
    // distance from the seed below 2.3 of the sphere's 2.6 reach), in directions from a
    // Fibonacci sphere.
    let (mut worst, mut sum, mut n) = (0.0f64, 0.0, 0);
    let count = 600;
    for k in 0..count {
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / count as f64;
        let phi = k as f64 * 2.399_963_229_728_653;
        let r = (1.0 - z * z).sqrt();
        let w = DVec3::new(r * phi.cos(), r * phi.sin(), z);
        if w.z.acos() > 2.3 {
            continue;
        }
        let e = (radial_root(fit, w) - radial_root(blob, w)).abs();
        worst = worst.max(e);
        sum += e;
        n += 1;
    }
    eprintln!(
        "fit-height: {n} directions, mean |Δr| {:.2e}, worst {worst:.2e}",
        sum / n as f64
    );
    // The range of the map is about 0.25: 8-bit texels (the renderer's texture format)
    // quantize it by 1e-3 (measured mean 4.0e-4). The worst error is at the nose's tip
    // (radius 0.11), which 128² texels over the 5.2-wide uv square (0.04 a texel)
    // resample coarsely (measured 1.1e-2).
    assert!(n > 400);
    assert!(sum / n as f64 <= 1e-3, "mean error {:.2e}", sum / n as f64);
    assert!(worst <= 2e-2, "worst error {worst:.2e}");
}

/// An atlas on a displaced shape (its walks evaluate the displaced field, whose height
/// walks the base's atlas at every evaluation): a height that reads the base atlas but
/// is the constant h makes the displaced sphere of radius R the sphere of radius R + h,
/// so the atlas on it equals the same atlas on that sphere (≤ 1e-6 in uv), and its GPU
/// walks agree with the CPU (≤ 1e-3 relative).
#[test]
fn an_atlas_on_a_displaced_shape_walks_the_displaced_surface() {
    let seeds = "steps = 10;\n    seed a = [0, 0, 1.1] tangent [1, 0, 0];\n    seed b = [1.1, 0, 0];\n    merge a b;";
    let a = checked(
        &format!(
            "let ball = sphere(1);\n\
             atlas skin on ball {{ seed s = [0, 0, 1]; }}\n\
             let bumpy = ball.displace(0.1 + 0.01 * clamp(skin.distance, 0, 0), scale: 1);\n\
             atlas outer on bumpy {{\n    {seeds}\n}}\n\
             material m {{ color = [outer.uv, 0]; }}\n\
             render bumpy.paint(m);"
        ),
        None,
    );
    let codes: Vec<&str> = a.diagnostics.iter().map(|d| d.code).collect();
    assert_eq!(codes, ["N0003"]);
    let plain = checked(
        &format!("let big = sphere(1.1);\natlas outer on big {{\n    {seeds}\n}}\nrender big;"),
        None,
    );
    // The sphere's atlas walks on forward derivatives, the displaced one (whose height
    // reads a texture-like atlas) on differences: compared like with like, the sphere's
    // on the same differences.
    let mut reference = plain.atlases[0].clone().unwrap();
    assert!(reference.params.exact_gradient);
    reference.params.exact_gradient = false;
    let (outer, reference) = (a.atlases[1].as_ref().unwrap(), &reference);
    // The height really reads the base's atlas (nested walks), and the outer atlas's
    // environment evaluates it (0.1 + 0.01 · clamp(…, 0, 0) = 0.1 everywhere).
    let height = outer
        .shape
        .nodes
        .iter()
        .find_map(|n| match &n.op {
            Op::Displace { height, .. } => Some(height.clone()),
            _ => None,
        })
        .unwrap();
    assert!(height.atlas.is_some() && !height.is_constant());
    let h = outer.heights.scalar(&height, DVec3::Z, DVec3::Z);
    assert!(h.is_some_and(|h| (h - 0.1).abs() < 1e-12), "{h:?}");
    let mut rng = Rng(12);
    let mut points = Vec::new();
    while points.len() < 60 {
        let d = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(0.0, 1.0),
        );
        if d.length() > 0.2 {
            points.push(d.normalize() * 1.1);
        }
    }
    let mut worst = 0.0f64;
    for x in &points {
        let (s, r) = (outer.sample(*x), reference.sample(*x));
        assert_eq!(s.status, r.status, "at {x}");
        worst = worst.max((s.uv - r.uv).length());
    }
    eprintln!("atlas on the displaced sphere vs on the sphere of radius 1.1: {worst:.2e}");
    assert!(worst <= 1e-6, "{worst}");
    let Some(gpu) = sdfc::gpu::gpu_for_tests() else {
        return;
    };
    let options = sdfc::codegen::Options {
        walk: sdfc::codegen::WalkForm::Loop,
        atlas: Some("outer".into()),
        ..Default::default()
    };
    let m = sdfc::driver::compile(&a, &options).unwrap().module;
    let got = sdfc::gpu::eval_atlas(&gpu, &m, &points[..20]).unwrap();
    for (x, g) in points.iter().zip(&got) {
        let c = outer.sample(*x);
        let guv = glam::DVec2::new(g.uv[0] as f64, g.uv[1] as f64);
        assert_eq!(g.status, c.status.code(), "at {x}");
        let e = (c.uv - guv).length() / c.uv.length().max(0.2);
        assert!(e <= 1e-3, "at {x}: {} vs {guv}", c.uv);
    }
}
