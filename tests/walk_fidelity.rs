//! Walk fidelity (#16): no false sharp features on smooth shapes, accuracy that does not
//! depend on the rest of the scene. Geodesic distances come from Dijkstra on a fine
//! parameter grid (16-neighbour stencil, chord edge lengths), which overestimates the
//! exact distance by at most a few per cent.

use glam::DVec3;
use sdfc::driver::analyze;
use sdfc::ir;
use sdfc::uv::{Atlas, Status};
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::f64::consts::PI;

use crate::common;
use common::Rng;

fn atlas(src: &str) -> Atlas {
    let a = analyze(src, None);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    let def = &a.program.atlases[0];
    let shape = ir::lower_shape(&def.shape).unwrap();
    Atlas::prepare(def, &shape).unwrap()
}

/// A surface sampled on a (nu × nv) parameter grid; u is periodic, v is periodic when
/// `v_periodic`.
struct Grid {
    nu: usize,
    nv: usize,
    v_periodic: bool,
    points: Vec<DVec3>,
}

#[derive(PartialEq)]
struct Item(f64, usize);
impl Eq for Item {}
impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0)
    }
}

impl Grid {
    fn new(nu: usize, nv: usize, v_periodic: bool, p: impl Fn(f64, f64) -> DVec3) -> Grid {
        let mut points = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                let u = i as f64 / nu as f64;
                let v = if v_periodic {
                    j as f64 / nv as f64
                } else {
                    j as f64 / (nv - 1) as f64
                };
                points.push(p(u, v));
            }
        }
        Grid {
            nu,
            nv,
            v_periodic,
            points,
        }
    }

    fn neighbour(&self, k: usize, di: i64, dj: i64) -> Option<usize> {
        let (i, j) = ((k % self.nu) as i64, (k / self.nu) as i64);
        let i = (i + di).rem_euclid(self.nu as i64);
        let mut j = j + dj;
        if self.v_periodic {
            j = j.rem_euclid(self.nv as i64);
        } else if j < 0 || j >= self.nv as i64 {
            return None;
        }
        Some(j as usize * self.nu + i as usize)
    }

    /// Geodesic distances from vertex `src`.
    fn distances(&self, src: usize) -> Vec<f64> {
        const STENCIL: [(i64, i64); 16] = [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (1, -1),
            (-1, 1),
            (-1, -1),
            (2, 1),
            (2, -1),
            (-2, 1),
            (-2, -1),
            (1, 2),
            (1, -2),
            (-1, 2),
            (-1, -2),
        ];
        let mut d = vec![f64::INFINITY; self.points.len()];
        let mut heap = BinaryHeap::new();
        d[src] = 0.0;
        heap.push(Item(0.0, src));
        while let Some(Item(dk, k)) = heap.pop() {
            if dk > d[k] {
                continue;
            }
            for &(di, dj) in &STENCIL {
                if let Some(m) = self.neighbour(k, di, dj) {
                    let nd = dk + (self.points[m] - self.points[k]).length();
                    if nd < d[m] {
                        d[m] = nd;
                        heap.push(Item(nd, m));
                    }
                }
            }
        }
        d
    }
}

/// Walk statuses of up to `n` random grid vertices with geodesic distance in [lo, hi).
fn shares(
    a: &Atlas,
    g: &Grid,
    d: &[f64],
    lo: f64,
    hi: f64,
    n: usize,
) -> (usize, usize, Vec<Status>) {
    let mut idx: Vec<usize> = (0..d.len()).filter(|&k| d[k] >= lo && d[k] < hi).collect();
    let mut rng = Rng(17);
    for k in (1..idx.len()).rev() {
        let m = (rng.unit() * (k + 1) as f64) as usize;
        idx.swap(k, m.min(k));
    }
    idx.truncate(n);
    let mut fails = Vec::new();
    for &k in &idx {
        let m = a.walk(g.points[k], 0, 10.0);
        if m.status != Status::Ok {
            fails.push(m.status);
        }
    }
    (idx.len() - fails.len(), idx.len(), fails)
}

fn torus_grid() -> Grid {
    Grid::new(720, 360, true, |u, v| {
        let (t, p) = (u * 2.0 * PI, v * 2.0 * PI);
        let rr = 1.0 + 0.35 * p.cos();
        DVec3::new(rr * t.cos(), 0.35 * p.sin(), rr * t.sin())
    })
}

fn ellipsoid_grid() -> Grid {
    // The polar axis along x, so that the seed at the z pole is a regular vertex.
    Grid::new(720, 361, false, |u, v| {
        let (s, t) = (u * 2.0 * PI, v * PI);
        DVec3::new(1.5 * t.cos(), t.sin() * s.cos(), 0.6 * t.sin() * s.sin())
    })
}

/// The share of walks ending `ok` among up to 400 grid vertices within geodesic
/// distance `radius` of the seed at vertex `src`.
fn ok_share(a: &Atlas, g: &Grid, src: usize, radius: f64) -> f64 {
    let d = g.distances(src);
    let (ok, n, _) = shares(a, g, &d, 0.0, radius, 400);
    assert!(n >= 300, "{n} points");
    ok as f64 / n as f64
}

fn torus() -> (Atlas, Grid) {
    let a = atlas("let t = torus(1, 0.35);\natlas a on t { max_distance = 10; seed s = [1.35, 0, 0] tangent [0, 1, 0]; }\nrender t;");
    (a, torus_grid())
}

fn ellipsoid() -> (Atlas, Grid, usize) {
    let a = atlas("let e = ellipsoid([1.5, 1, 0.6]);\natlas a on e { max_distance = 10; seed s = [0, 0, 0.6] tangent [1, 0, 0]; }\nrender e;");
    (a, ellipsoid_grid(), 180 * 720 + 180)
}

#[test]
fn smooth_shapes_have_no_false_sharp_features() {
    // The region: within 0.8·π·(smallest radius of curvature) of the seed, at
    // the default N = 20: the torus's tube (0.35), the ellipsoid's tips (0.6²/1.5).
    let (a, g) = torus();
    let share = ok_share(&a, &g, 0, 0.8 * PI * 0.35);
    assert!(share >= 0.99, "torus: {share}");
    // Farther: half way round the tube and beyond (the paper's walk failed 60 % here).
    let share = ok_share(&a, &g, 0, 1.6);
    assert!(share >= 0.99, "torus to 1.6: {share}");
    let (a, g, src) = ellipsoid();
    let share = ok_share(&a, &g, src, 0.8 * PI * 0.24);
    assert!(share >= 0.99, "ellipsoid: {share}");
    // Up to the tips' tight curvature (the paper's walk failed 17 % in [1, 1.6)).
    let share = ok_share(&a, &g, src, 1.6);
    assert!(share >= 0.99, "ellipsoid to 1.6: {share}");
}

/// The status of the walk from `x` to the atlas's only seed.
fn status(src: &str, x: [f64; 3]) -> Status {
    atlas(src).walk(DVec3::from_array(x), 0, 10.0).status
}

#[test]
fn true_creases_are_still_caught() {
    // The robot's torso: a box edge (90°), from the side face to the front's seed.
    let torso = "let torso = box([1.2, 1.4, 0.7]);\natlas a on torso { seed s = [0, 0.35, 0.35]; }\nrender torso;";
    for x in [[0.6, 0.3, 0.1], [0.6, -0.2, -0.2], [0.3, 0.7, -0.1]] {
        assert_eq!(status(torso, x), Status::SharpFeature, "torso at {x:?}");
    }
    // A plate's hole rim (90°): from the hole's wall to a seed on the top face.
    let plate = "let plate = difference(box([4, 0.4, 4]), cylinder(0.5, 1));\natlas a on plate { seed s = [1, 0.2, 0.3]; }\nrender plate;";
    for x in [[0.5, 0.0, 0.0], [0.0, 0.1, 0.5], [0.35355, -0.1, 0.35355]] {
        assert_eq!(status(plate, x), Status::SharpFeature, "plate at {x:?}");
    }
    // A concave 90° CSG edge: an L of two boxes, from the upright's face to the floor.
    let ell = "let l = union(box([2, 0.4, 2]), box([0.4, 2, 2]).translate([-0.8, 0.8, 0]));\natlas a on l { seed s = [0.5, 0.2, 0]; }\nrender l;";
    for x in [[-0.6, 1.0, 0.0], [-0.6, 0.5, 0.4], [-0.6, 1.5, -0.3]] {
        assert_eq!(status(ell, x), Status::SharpFeature, "L at {x:?}");
    }
    // A shallow ridge (20°, below the 3·θ0 cap): flat on both sides, so no curvature
    // excuses the turn.
    let ridge = "let r = intersection(plane(normal: [0.17365, 0.98481, 0]), plane(normal: [-0.17365, 0.98481, 0]));\natlas a on r { seed s = [1, -0.17633, 0.2]; }\nrender r;";
    for x in [
        [-1.0, -0.17633, 0.0],
        [-0.3, -0.0529, -0.5],
        [-2.0, -0.35265, 1.0],
    ] {
        assert_eq!(status(ridge, x), Status::SharpFeature, "ridge at {x:?}");
    }
    // The same ridge rounded over a radius far above the step: smooth, so it passes.
    let round = "let r = smooth_intersection(plane(normal: [0.17365, 0.98481, 0]), plane(normal: [-0.17365, 0.98481, 0]), 2);\natlas a on r { seed s = [1, 0, 0.2]; }\nrender r;";
    let a = atlas(round);
    let x = sdfc::ir::eval::project(&a.shape, DVec3::new(-1.0, 0.0, 0.0), 1e-10).unwrap();
    assert_eq!(a.walk(x, 0, 10.0).status, Status::Ok, "rounded ridge");
}

/// The seed's and points' atlas on a radius 0.5 cylinder of `height`, in `scene` (a
/// shape expression around `cyl`).
fn cylinder_atlas(height: f64, scene: &str) -> Atlas {
    atlas(&format!(
        "let cyl = cylinder(0.5, {height});\nlet scene = {scene};\natlas a on scene {{ max_distance = 10; seed s = [0.5, 0, 0] tangent [0, 1, 0]; }}\nrender scene;"
    ))
}

/// Points on the radius 0.5 cylinder around the seed at (0.5, 0, 0): angle φ and
/// height y, with the exact log map (the unrolling: (y, 0.5·φ) in the frame e1 = y).
fn cylinder_points() -> Vec<(DVec3, [f64; 2])> {
    let mut out = Vec::new();
    for i in 0..9 {
        for j in 0..5 {
            let phi = -1.2 + 0.3 * i as f64;
            let y = -0.5 + 0.25 * j as f64;
            out.push((
                DVec3::new(0.5 * phi.cos(), y, 0.5 * phi.sin()),
                [y, 0.5 * phi],
            ));
        }
    }
    out
}

#[test]
fn accuracy_does_not_depend_on_the_rest_of_the_scene() {
    // The same cylinder alone and beside a large box far away: the walks are the same.
    let alone = cylinder_atlas(1.5, "cyl");
    let beside = cylinder_atlas(1.5, "union(cyl, box(40).translate([100, 0, 0]))");
    assert!(beside.params.h_gradient > 50.0 * alone.params.h_gradient);
    for (x, _) in cylinder_points() {
        let (a, b) = (alone.walk(x, 0, 10.0), beside.walk(x, 0, 10.0));
        assert_eq!(a.status, Status::Ok, "at {x}");
        assert!(
            (a.uv - b.uv).length() < 1e-6,
            "at {x}: {} vs {}",
            a.uv,
            b.uv
        );
    }
    // A taller cylinder: the circumferential distance error does not grow with it.
    let error = |a: &Atlas| {
        cylinder_points()
            .iter()
            .filter(|(x, _)| x.y == 0.0 && x.x < 0.49)
            .map(|&(x, [_, arc])| (a.walk(x, 0, 10.0).distance - arc.abs()).abs())
            .fold(0.0, f64::max)
    };
    let (short, tall) = (error(&alone), error(&cylinder_atlas(24.0, "cyl")));
    eprintln!("circumferential distance error: height 1.5 {short:.2e}, height 24 {tall:.2e}");
    assert!(tall < 1e-3 && short < 1e-3, "{short} {tall}");
    assert!((tall - short).abs() < 1e-6, "{short} {tall}");
}

/// RMS over `points` of |uv − exact| / |exact| (the walk from each point to seed 0).
fn rms_uv_error(a: &Atlas, points: &[(DVec3, DVec3)]) -> f64 {
    let s = a.seeds[0].seed;
    let mut sum = 0.0;
    for &(x, exact) in points {
        let m = a.walk(x, 0, 10.0);
        assert_eq!(m.status, Status::Ok, "at {x}");
        let want = glam::DVec2::new(exact.dot(s.e1), exact.dot(s.e2));
        sum += ((m.uv - want).length() / want.length()).powi(2);
    }
    (sum / points.len() as f64).sqrt()
}

/// The radius 0.5 cylinder (height 4) and a seed on it, with `refine`; random points
/// within 0.8·π·R and their exact log maps (the unrolling) as tangent vectors at the seed.
fn cylinder_case(refine: u32) -> (Atlas, Vec<(DVec3, DVec3)>) {
    let a = atlas(&format!("let c = cylinder(0.5, 4);\natlas a on c {{ max_distance = 10; refine = {refine}; seed s = [0.5, 0, 0] tangent [0, 1, 1]; }}\nrender c;"));
    let mut rng = Rng(41);
    let mut points = Vec::new();
    while points.len() < 200 {
        let (y, phi) = (rng.range(-1.2, 1.2), rng.range(-2.5, 2.5));
        let d = (y * y + 0.25 * phi * phi).sqrt();
        if d > 0.8 * PI * 0.5 || d < 0.05 {
            continue;
        }
        let x = DVec3::new(0.5 * phi.cos(), y, 0.5 * phi.sin());
        points.push((x, DVec3::new(0.0, y, 0.5 * phi)));
    }
    (a, points)
}

/// A cone (base radius 0.5 at y = 0, apex at y = 2) with a seed at y = 0.8 (radius
/// 0.3), and random points within 0.8·π·0.3 with their exact log maps: the cone unrolls
/// to a sector of radius ℓ = √(0.5² + 2²), a point at height y and angle φ to
/// ρ = (2 − y)/2·ℓ, ψ = φ·0.5/ℓ.
fn cone_case(refine: u32) -> (Atlas, Vec<(DVec3, DVec3)>) {
    let a = atlas(&format!("let c = cone(0.5, 2);\natlas a on c {{ max_distance = 10; refine = {refine}; seed s = [0.3, 0.8, 0] tangent [0, 0, 1]; }}\nrender c;"));
    let l = (0.25f64 + 4.0).sqrt();
    let unroll = |y: f64, phi: f64| {
        let (rho, psi) = ((2.0 - y) / 2.0 * l, phi * 0.5 / l);
        glam::DVec2::new(rho * psi.cos(), rho * psi.sin())
    };
    let on = |y: f64, phi: f64| {
        let r = 0.5 * (2.0 - y) / 2.0;
        DVec3::new(r * phi.cos(), y, r * phi.sin())
    };
    let p = unroll(0.8, 0.0);
    // The generator away from the apex and the circumferential direction at the seed.
    let g = (on(0.8, 0.0) - DVec3::new(0.0, 2.0, 0.0)).normalize();
    let c = DVec3::Z;
    let mut rng = Rng(43);
    let mut points = Vec::new();
    while points.len() < 200 {
        let (y, phi) = (rng.range(0.2, 1.8), rng.range(-3.0, 3.0));
        let d = unroll(y, phi) - p;
        if d.length() > 0.8 * PI * 0.3 || d.length() < 0.05 {
            continue;
        }
        points.push((on(y, phi), g * d.x + c * d.y));
    }
    (a, points)
}

#[test]
fn refinement_reaches_the_exact_log_map_on_developable_shapes() {
    for (name, case) in [
        (
            "cylinder",
            cylinder_case as fn(u32) -> (Atlas, Vec<(DVec3, DVec3)>),
        ),
        ("cone", cone_case),
    ] {
        let errors: Vec<f64> = (0..=2)
            .map(|k| {
                let (a, points) = case(k);
                rms_uv_error(&a, &points)
            })
            .collect();
        eprintln!(
            "{name}: RMS uv error / distance, refine = 0, 1, 2: {:.2e} {:.2e} {:.2e}",
            errors[0], errors[1], errors[2]
        );
        assert!(errors[2] <= 1e-3, "{name}: {errors:?}");
        assert!(errors[0] > 10.0 * errors[2], "{name}: {errors:?}");
    }
}

#[test]
fn refinement_keeps_the_sphere_exact() {
    // The exact log map on a unit sphere (notes): distance by the angle, direction along
    // the great circle. With refinement the uv's direction matches it to 1e-4 rad.
    let mut worst = [0.0f64; 2];
    for (k, refine) in [0, 2].into_iter().enumerate() {
        let a = atlas(&format!("let b = sphere(1);\natlas a on b {{ max_distance = 10; refine = {refine}; seed s = [0.36, 0.48, 0.8] tangent [1, 0, 0]; }}\nrender b;"));
        let s = a.seeds[0].seed;
        let mut rng = Rng(47);
        for _ in 0..200 {
            let (phi, rho) = (rng.range(0.0, 2.0 * PI), rng.range(0.05, 0.45 * PI));
            let dir = s.e1 * phi.cos() + s.e2 * phi.sin();
            let x = s.p * rho.cos() + dir * rho.sin();
            let m = a.walk(x, 0, 10.0);
            assert_eq!(m.status, Status::Ok, "at {x}");
            let want = glam::DVec2::new(phi.cos(), phi.sin()) * rho;
            let angle =
                m.uv.normalize()
                    .dot(want.normalize())
                    .clamp(-1.0, 1.0)
                    .acos();
            worst[k] = worst[k].max(angle);
            assert!(
                (m.distance - rho).abs() < 2e-3 * rho,
                "{} vs {rho}",
                m.distance
            );
        }
    }
    eprintln!(
        "sphere: worst uv direction error {:.1e} rad (refine = 0), {:.1e} (refine = 2)",
        worst[0], worst[1]
    );
    assert!(worst[1] <= 1e-4, "{worst:?}");
}
