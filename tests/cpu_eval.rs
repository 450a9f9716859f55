//! The CPU reference against analytic signed distances.

use glam::DVec3;
use sdfc::driver::analyze;
use sdfc::ir::{self, eval};

fn shape(src: &str) -> ir::Shape {
    let a = analyze(src, None);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    let scene = ir::lower(&a.program);
    scene.render.expect("render target")
}

/// Deterministic sample points in a cube.
fn points(n: usize, half: f64) -> Vec<DVec3> {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| DVec3::new(next(), next(), next()) * half)
        .collect()
}

fn check(src: &str, oracle: impl Fn(DVec3) -> f64) {
    let s = shape(src);
    for p in points(2000, 3.0) {
        let got = eval::distance(&s, p);
        let want = oracle(p);
        assert!(
            (got - want).abs() <= 1e-9,
            "{src}: at {p}: got {got}, want {want}"
        );
    }
}

#[test]
fn sphere_matches_analytic() {
    check("render sphere(0.75).translate([0.5, -0.25, 1]);", |p| {
        (p - DVec3::new(0.5, -0.25, 1.0)).length() - 0.75
    });
}

#[test]
fn box_matches_analytic() {
    // Exact box distance: outside, the distance to the nearest point; inside, minus the distance to the nearest face.
    check("render box([2, 1, 0.5]);", |p| {
        let h = DVec3::new(1.0, 0.5, 0.25);
        let q = p.abs() - h;
        if q.max_element() > 0.0 {
            q.max(DVec3::ZERO).length()
        } else {
            q.max_element()
        }
    });
}

#[test]
fn torus_matches_analytic() {
    check("render torus(major: 1.2, minor: 0.3);", |p| {
        ((p.x * p.x + p.z * p.z).sqrt() - 1.2).hypot(p.y) - 0.3
    });
}

#[test]
fn plane_matches_analytic() {
    let n = DVec3::new(1.0, 2.0, -0.5).normalize();
    check("render plane(normal: [1, 2, -0.5], offset: 0.3);", |p| {
        p.dot(n) - 0.3
    });
}

#[test]
fn rotation_is_rigid() {
    // A rotated sphere off the axis: the centre moves by the rotation.
    let c = glam::DMat3::from_rotation_z(std::f64::consts::FRAC_PI_2) * DVec3::new(1.0, 0.0, 0.0);
    check(
        "render sphere(0.5).translate([1, 0, 0]).rotate_z(90deg);",
        |p| (p - c).length() - 0.5,
    );
}

#[test]
fn uniform_scale_scales_distance() {
    check("render sphere(1).scale(2.5);", |p| p.length() - 2.5);
}

#[test]
fn csg_of_spheres() {
    let a = |p: DVec3| (p - DVec3::new(-0.4, 0.0, 0.0)).length() - 0.7;
    let b = |p: DVec3| (p - DVec3::new(0.4, 0.0, 0.0)).length() - 0.7;
    check("let a = sphere(0.7).translate([-0.4, 0, 0]); let b = sphere(0.7).translate([0.4, 0, 0]); render a | b;", |p| a(p).min(b(p)));
    check("let a = sphere(0.7).translate([-0.4, 0, 0]); let b = sphere(0.7).translate([0.4, 0, 0]); render a & b;", |p| a(p).max(b(p)));
    check("let a = sphere(0.7).translate([-0.4, 0, 0]); let b = sphere(0.7).translate([0.4, 0, 0]); render a - b;", |p| a(p).max(-b(p)));
}

#[test]
fn gradient_is_the_unit_normal() {
    let s = shape("render sphere(1);");
    for p in points(200, 2.0) {
        if p.length() < 0.1 {
            continue;
        }
        let g = eval::gradient(&s, p);
        assert!((g - p.normalize()).length() < 1e-8, "at {p}: {g}");
    }
}

#[test]
fn projection_lands_on_the_surface() {
    let s = shape(
        "render torus(major: 1, minor: 0.25).rotate_x(30deg) | box(0.5).translate([0, 1, 0]);",
    );
    for p in points(300, 2.0) {
        if let Some(x) = eval::project(&s, p, 1e-10) {
            assert!(eval::distance(&s, x).abs() < 1e-10);
        }
    }
    let sphere = shape("render sphere(1);");
    let x = eval::project(&sphere, DVec3::new(0.0, 3.0, 4.0), 1e-12).unwrap();
    // Finite-difference gradients are good to about 1e-9, so the landing point is too.
    assert!((x - DVec3::new(0.0, 0.6, 0.8)).length() < 1e-8);
}

#[test]
fn every_primitive_is_a_distance_bound() {
    // On a ray from outside towards each primitive, stepping by d / L never crosses the surface:
    // the sign at the landing point is still non-negative (within 1e-9).
    let prims = [
        "sphere(1)",
        "box([1, 2, 0.5])",
        "round_box([1, 1, 1], 0.2)",
        "box_frame([1, 1, 1], 0.1)",
        "torus(1, 0.3)",
        "capsule([0, -1, 0], [0, 1, 0], 0.3)",
        "cylinder(0.5, 1)",
        "cone(0.5, 1)",
        "capped_cone(1, 0.5, 0.2)",
        "ellipsoid([1, 0.5, 0.3])",
        "octahedron(1)",
        "hex_prism(0.5, 1)",
        "tri_prism(0.5, 1)",
        "pyramid(1)",
        "link(0.5, 0.4, 0.1)",
        "box(1).twist(rate: 1.5)",
        "box(1).bend(rate: 0.8)",
        "box([1, 2, 1]).scale([1, 3, 0.5])",
    ];
    for prim in prims {
        let s = shape(&format!("render {prim};"));
        let l = s.lipschitz();
        for dir in points(300, 1.0) {
            if dir.length() < 1e-3 {
                continue;
            }
            let dir = dir.normalize();
            let origin = -dir * 4.0;
            let mut t = 0.0;
            for _ in 0..400 {
                let d = eval::distance(&s, origin + dir * t);
                assert!(
                    d > -1e-9,
                    "{prim}: stepped inside along {dir} at t = {t} (d = {d}, L = {l})"
                );
                if d < 1e-7 {
                    break;
                }
                t += d / l;
            }
        }
    }
}
