//! The baked mesh against the zero set it stands for, on every example: creases and
//! rims without fins, spikes or teeth (the share of triangles whose face normal turns
//! more than 45° from the field's gradient at their centroid), and the Hausdorff
//! distance between the mesh and the zero set, both ways, under half a cell.
//!
//! Where a cell holds detail finer than itself, the bake refines it (`--refine auto`);
//! one example still does not meet the goal at the test's atlas size (issue 40): it is
//! named in [`FINER_THAN_A_CELL`] with its reasons and held to
//! today's figures, so that they cannot get worse unseen; every other example meets
//! the goal, and `capsule.sdf`, whose drilled rim had teeth, is held to a tenth of a
//! cell ([`HELD_TIGHTER`]). A drilled rim is also measured against its analytic
//! crease at several grid origins. Today's figures are in docs/baking.md ("The mesh against the zero set");
//! `--nocapture` prints them.

use crate::common;

use glam::DVec3;
use sdfc::bake::coverage::to_triangle;
use sdfc::bake::pipeline::{self, Options, Quiet};
use sdfc::gpu::gpu_for_tests;
use sdfc::ir::eval;

/// What the test measures of one baked mesh.
struct Quality {
    /// Triangles with an area.
    triangles: usize,
    /// Triangles whose normal is more than 45° off the gradient at their centroid.
    turned: usize,
    /// The largest distance from a point of the mesh to the zero set, and from a point
    /// of the zero set to the mesh.
    mesh_to_surface: f64,
    surface_to_mesh: f64,
    cell: f64,
}

/// The distance from `q` to the zero set, from above: the nearer of the surface point
/// Newton's projection reaches and, when that is over a quarter of `reach` and over
/// `known` (the largest distance found so far: a point under it cannot change the
/// maximum), the nearest sign change along 26 directions (the cube's faces, edges and
/// corners) and the gradient's, within `reach`. Newton's projection alone overshoots where the
/// gradient is short (inside a smooth blend, |∇f| < 1): waving_robot's arm joint has
/// mesh points 0.07 cells from the surface whose projection lands 0.9 cells away.
fn to_zero_set(field: sdfc::ir::Field, q: DVec3, reach: f64, known: f64) -> f64 {
    let f0 = eval::distance(field, q);
    if f0 == 0.0 {
        return 0.0;
    }
    let mut best = eval::project(field, q, 1e-9).map_or(f64::INFINITY, |on| (on - q).length());
    if best <= 0.25 * reach || best <= known {
        return best;
    }
    let mut directions = vec![eval::gradient(field, q).normalize_or_zero() * -f0.signum()];
    for x in -1..=1 {
        for y in -1..=1 {
            for z in -1..=1 {
                if (x, y, z) != (0, 0, 0) {
                    directions.push(DVec3::new(x as f64, y as f64, z as f64).normalize());
                }
            }
        }
    }
    const STEPS: usize = 32;
    for d in directions.into_iter().filter(|d| *d != DVec3::ZERO) {
        let mut lo = 0.0;
        for k in 1..=STEPS {
            let t = reach * k as f64 / STEPS as f64;
            if t >= best {
                break;
            }
            if (eval::distance(field, q + d * t) < 0.0) != (f0 < 0.0) {
                // A sign change in (lo, t]: bisect it.
                let mut hi = t;
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    if (eval::distance(field, q + d * mid) < 0.0) != (f0 < 0.0) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                best = best.min(hi);
                break;
            }
            lo = t;
        }
    }
    best
}

fn measure(path: &std::path::Path, gpu: &sdfc::gpu::Gpu, size: u32) -> Option<Quality> {
    let text = std::fs::read_to_string(path).unwrap();
    let base = path.parent().unwrap();
    let analysis = sdfc::driver::check(&text, Some(base));
    if analysis.has_errors() {
        return None;
    }
    let scene = analysis.scene.as_ref()?;
    let shape = sdfc::driver::pick_shape(scene, None).ok()?;
    if !pipeline::has_material(shape) {
        return None;
    }
    let options = sdfc::codegen::Options {
        walk: sdfc::codegen::WalkForm::Loop,
        ..Default::default()
    };
    let module = sdfc::driver::compile(&analysis, &options).ok()?.module;
    let bake = Options {
        size,
        ..Options::default()
    };
    // The field with its heights (displacements, shell maps), as `sdfc bake` meshes it.
    let field = analysis.field(shape);
    let baked = pipeline::bake(gpu, &module, base, field, &bake, &Quiet).ok()?;
    let m = &baked.mesh;
    let p = |i: u32| DVec3::from_array(m.positions[i as usize].map(f64::from));
    let tris: Vec<[DVec3; 3]> = m
        .indices
        .chunks_exact(3)
        .map(|t| [p(t[0]), p(t[1]), p(t[2])])
        .collect();
    let cell = baked.quads.cell;
    // In chunks on every core: each chunk's turned triangles and its largest distance.
    use rayon::prelude::*;
    let (turned, mesh_to_surface) = tris
        .par_chunks(256)
        .map(|chunk| {
            let mut turned = 0;
            let mut far = 0.0f64;
            for [a, b, c] in chunk {
                let centroid = (*a + *b + *c) / 3.0;
                let n = (*b - *a).cross(*c - *a).normalize_or_zero();
                let g = eval::gradient(field, centroid).normalize_or_zero();
                if n != DVec3::ZERO && g != DVec3::ZERO && n.dot(g) < 45f64.to_radians().cos() {
                    turned += 1;
                }
                for q in [centroid, (*a + *b) * 0.5, (*b + *c) * 0.5, (*c + *a) * 0.5] {
                    far = far.max(to_zero_set(field, q, 2.0 * cell, far));
                }
            }
            (turned, far)
        })
        .reduce(|| (0, 0.0), |x, y| (x.0 + y.0, x.1.max(y.1)));
    // Surface points against the mesh, through a coarse bucket grid of triangles.
    let near = sdfc::bake::coverage::Nearby::new(tris.clone(), cell, DVec3::ZERO);
    let mut surface_to_mesh = 0.0f64;
    // Area-uniform samples of the surface (the sampler of `sdfc bake`'s coverage line):
    // random points of the box projected onto the surface miss slits and grooves.
    let samples = sdfc::reference::surface::surface_samples(field, 24).unwrap();
    for x in samples.iter().map(|s| s.p) {
        let best = near.distance(x);
        // Nothing within two buckets is farther than 2 cells: say so.
        surface_to_mesh = surface_to_mesh.max(best.min(4.0 * cell));
    }
    Some(Quality {
        // Triangles the mesher's joined vertices left without area have no face
        // normal to turn: they are not counted either way.
        triangles: tris
            .iter()
            .filter(|[a, b, c]| (*b - *a).cross(*c - *a) != DVec3::ZERO)
            .count(),
        turned,
        mesh_to_surface,
        surface_to_mesh,
        cell,
    })
}

/// The examples whose detail is finer than a cell of the default grid (48 along the
/// longest side), which the bake's mesh does not hold: (name, why, and today's turned
/// share, mesh → surface and surface → mesh in cells, each with a little room, as
/// ceilings). (displaced_sphere and fit_blob were here too until the test baked their
/// fields with their heights, as `sdfc bake` does; warps and waving_robot until the
/// mesher refined the cells that hold such detail: they meet the goal.)
const FINER_THAN_A_CELL: [(&str, &str, f64, f64, f64); 1] = [(
    "shell_arrows.sdf",
    "arrows of a shell map finer than a cell, without bound at the log map's cut locus: refined even twice they need 38,347 charts, which do not fit the test's 256² atlas, so the bake keeps the plain grid's mesh (at 2048 it refines 4 times and holds 99.3 % of the surface)",
    0.125,
    0.75,
    1.95,
)];

/// Examples baked larger than the test's 256² atlas, so that their refined mesh's
/// charts fit and the bake keeps it: (name, atlas side, why).
const BAKED_LARGER: [(&str, u32, &str); 1] = [(
    "warps.sdf",
    1024,
    "a 0.05-thick shell and 0.15 spheres, thinner than a cell: refined 8 times, 67,406 charts",
)];

/// Examples held tighter than the goal where the issue saw a defect: (name, why, mesh →
/// surface and surface → mesh ceilings in cells).
const HELD_TIGHTER: [(&str, &str, f64, f64); 1] = [(
    "capsule.sdf",
    "the drilled rim, where the red team saw teeth: 0.120 / 0.135 cells with the QEF's minimizer clamped to the cell, 0.068 / 0.046 minimized within it",
    0.1,
    0.1,
)];

#[test]
fn baked_meshes_follow_creases_and_stay_within_half_a_cell_of_the_surface() {
    let Some(gpu) = gpu_for_tests() else { return };
    let mut measured = 0;
    let mut failures = Vec::new();
    let mut excepted = Vec::new();
    let mut tight = Vec::new();
    let examples = common::scene_files()
        .into_iter()
        .filter(|p| p.parent().is_some_and(|d| d.ends_with("examples")));
    for path in examples {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let size = BAKED_LARGER
            .iter()
            .find(|e| e.0 == name)
            .map_or(256, |e| e.1);
        let Some(q) = measure(&path, &gpu, size) else {
            continue;
        };
        measured += 1;
        let share = q.turned as f64 / q.triangles as f64;
        eprintln!(
            "{name}: {} triangles, {} turned over 45° ({:.3} %), mesh → surface {:.3} cells, surface → mesh {:.3} cells",
            q.triangles,
            q.turned,
            100.0 * share,
            q.mesh_to_surface / q.cell,
            q.surface_to_mesh / q.cell
        );
        let (to, from) = (q.mesh_to_surface / q.cell, q.surface_to_mesh / q.cell);
        let limits = match FINER_THAN_A_CELL.iter().find(|e| e.0 == name) {
            Some(&(_, _, turned, to, from)) => {
                excepted.push(name.clone());
                (turned, to, from)
            }
            None => match HELD_TIGHTER.iter().find(|e| e.0 == name) {
                Some(&(_, _, to, from)) => {
                    tight.push(name.clone());
                    (0.001, to, from)
                }
                None => (0.001, 0.5, 0.5),
            },
        };
        // (An exception is never held tighter than the goal.)
        let goal = |limit: f64| {
            if excepted.contains(&name) {
                limit.max(0.5)
            } else {
                limit
            }
        };
        if share >= limits.0.max(0.001) || to >= goal(limits.1) || from >= goal(limits.2) {
            failures.push(format!(
                "{name}: {:.3} % turned, {to:.3} / {from:.3} cells",
                100.0 * share
            ));
        }
    }
    assert!(measured >= 16, "only {measured} examples baked");
    assert_eq!(
        excepted.len(),
        FINER_THAN_A_CELL.len(),
        "an exception was not measured (renamed?): {excepted:?}"
    );
    assert_eq!(
        tight.len(),
        HELD_TIGHTER.len(),
        "an example held tighter was not measured (renamed?): {tight:?}"
    );
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A drilled rim against its analytic crease: a capsule (radius 0.5 along y) drilled
/// through by a cylinder (radius 0.2 along z), twisted about y as `capsule.sdf` is,
/// meshed at the default grid's cell from several grid origins. The rim is the curve
/// (0.2 cos θ, 0.2 sin θ, ±√(0.25 − 0.04 cos² θ)), twisted, where the hole's wall meets
/// the body at 66° to 90°. A mesh whose vertices there leave the crease cuts across it
/// in teeth (issue 40: the drilled capsule's rim in Blender). Returns the farthest rim
/// point from the mesh, in cells, for each origin.
fn rim_distances(twist: f64, head: bool, refine: usize) -> Vec<(f64, f64)> {
    use sdfc::bake::mesh::{adaptive_contour, Grid};
    let text = format!(
        "let body = capsule(a: [0, -1, 0], b: [0, 1, 0], radius: 0.5);\n\
         let hole = cylinder(radius: 0.2, height: 4).rotate_x(90deg);\n\
         material m {{ color = [1, 1, 1]; }}\n\
         let head = sphere(0.6).translate([0, 1.2, 0]);\n\
         render ({}).twist(axis: [0, 1, 0], rate: {twist}).paint(m) {{ }}\n",
        if head {
            "smooth_union(body, head, 0.15) - hole"
        } else {
            "body - hole"
        }
    );
    let analysis = sdfc::driver::check(&text, None);
    assert!(!analysis.has_errors(), "{:?}", analysis.diagnostics);
    let scene = analysis.scene.as_ref().unwrap();
    let shape = sdfc::driver::pick_shape(scene, None).unwrap();
    let field = analysis.field(shape);
    let bounds = shape.root_node().bounds;
    let base = Grid::over(bounds, 48);
    let mut out = Vec::new();
    for k in 0..6 {
        // Origins a sixth of a cell apart along a direction on no grid plane.
        let shift = DVec3::new(1.0, 0.7, 0.3) * (k as f64 / 6.0) * base.cell;
        let grid = Grid {
            origin: base.origin - shift,
            dims: base.dims.map(|d| d + 1),
            ..base
        };
        let tolerance = 1e-5 * (bounds.max - bounds.min).max_element();
        let mesh = adaptive_contour(field, &grid, tolerance, refine).mesh;
        let tris = mesh.triangles();
        // The nearest triangle through buckets (exact within two cells), and over all
        // triangles where none is that near.
        let near = sdfc::bake::coverage::Nearby::new(tris.clone(), grid.cell, DVec3::ZERO);
        let nearest = |p: DVec3| match near.distance(p) {
            d if d <= 2.0 * grid.cell => d,
            _ => tris
                .iter()
                .map(|[a, b, c]| to_triangle(p, *a, *b, *c))
                .fold(f64::INFINITY, f64::min),
        };
        let mut worst = 0.0f64;
        let mut rim_points = Vec::new();
        for i in 0..720 {
            let theta = i as f64 * std::f64::consts::PI / 360.0;
            let (x, y) = (0.2 * theta.cos(), 0.2 * theta.sin());
            for side in [-1.0, 1.0] {
                let flat = DVec3::new(x, y, side * (0.25 - x * x).sqrt());
                let rim = glam::DQuat::from_rotation_y(twist * y).mul_vec3(flat);
                rim_points.push(rim);
                // On the zero set: both the body and the hole are 0 there.
                assert!(eval::distance(field, rim).abs() < 1e-9, "{rim}");
                worst = worst.max(nearest(rim));
            }
        }
        // The mesh near the rim (triangles within a cell of it) against the zero set.
        let mut off = 0.0f64;
        let (lo, hi) = rim_points
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), r| {
                (lo.min(*r), hi.max(*r))
            });
        for [a, b, c] in &tris {
            let centroid = (*a + *b + *c) / 3.0;
            // (Outside the rim's box grown by a cell, no rim point is within a cell.)
            let outside =
                centroid.cmplt(lo - grid.cell).any() || centroid.cmpgt(hi + grid.cell).any();
            if outside
                || rim_points
                    .iter()
                    .all(|r| (*r - centroid).length() > grid.cell)
            {
                continue;
            }
            for q in [centroid, (*a + *b) * 0.5, (*b + *c) * 0.5, (*c + *a) * 0.5] {
                off = off.max(to_zero_set(field, q, 2.0 * grid.cell, off));
            }
        }
        out.push((worst / grid.cell, off / grid.cell));
    }
    out
}

/// The rim at every grid origin stays within the goal's half cell both ways. Where the
/// hole's wall meets the body at 66°, a wedge of solid thinner than a cell can pass
/// between the grid's corners, and the cells beside it see one plane each: the mesh
/// then cuts the rim by up to 0.43 cells (two of the six origins), with the QEF
/// minimized within the cell or clamped to it alike. Measured (rim → mesh, mesh near
/// the rim → surface, in cells, worst origin): untwisted 0.422 / 0.295, twisted
/// 0.426 / 0.291, `capsule.sdf`'s shape 0.355 / 0.268. At `capsule.sdf`'s own grid
/// (the first origin of its shape) the clamped QEF's teeth stood 0.120 cells off the
/// surface near the rim; minimized within the cell, 0.068: held under 0.09. Refined 4
/// times (`bake --refine 4`; `auto` refines only where surface is missed), the cells
/// beside the wedge see both planes: the worst origin is 0.103 / 0.065 cells (held
/// under 0.15 / 0.1).
#[test]
fn a_drilled_rim_follows_its_crease() {
    for (twist, head) in [(0.0, false), (0.4, false), (0.4, true)] {
        let d = rim_distances(twist, head, 1);
        eprintln!(
            "twist {twist}, head {head}: by grid origin, (rim → mesh, mesh near the rim → surface): {d:.3?} cells"
        );
        // Refined (`--refine 4`), the cells that hold the wedge see both its planes.
        let refined = rim_distances(twist, head, 4);
        eprintln!("  refined 4 times: {refined:.3?} cells");
        for (k, &(rim, off)) in refined.iter().enumerate() {
            assert!(
                rim < 0.15 && off < 0.1,
                "refined, twist {twist}, head {head}, origin {k}: {rim:.3} / {off:.3} cells"
            );
        }
        for (k, &(rim, off)) in d.iter().enumerate() {
            assert!(
                rim < 0.5 && off < 0.5,
                "twist {twist}, head {head}, origin {k}: the rim lies {rim:.3} cells from the mesh, the mesh near it {off:.3} cells from the surface"
            );
        }
        if head {
            assert!(
                d[0].1 < 0.09,
                "at capsule.sdf's own grid the mesh near the rim lies {:.3} cells off the surface: teeth",
                d[0].1
            );
        }
    }
}

/// `sdfc bake`'s coverage line (`bake::coverage`): the share of the surface, by area,
/// farther than half a cell from the mesh. A thin shell and small spheres (warps.sdf)
/// fall between the grid's corners at the default grid, and less of them at a finer
/// one; the robot's surface is all held.
#[test]
fn coverage_finds_what_the_mesh_misses() {
    use sdfc::bake::coverage::coverage;
    use sdfc::bake::mesh::{dual_contour, Grid};
    let at = |name: &str, cells: usize| {
        common::with_example(name, |field, shape| {
            let bounds = shape.root_node().bounds;
            let mesh = dual_contour(field, &Grid::over(bounds, cells), 1e-5);
            coverage(field, &mesh, bounds)
        })
    };
    let robot = at("robot.sdf", 48);
    assert!(robot.samples > 1000, "{robot:?}");
    assert_eq!(robot.missed, 0.0, "{robot:?}");
    assert!(robot.farthest < 0.2, "{robot:?}");
    let (coarse, fine) = (at("warps.sdf", 48), at("warps.sdf", 96));
    eprintln!("warps: grid 48 {coarse:?}, grid 96 {fine:?}");
    assert!(coarse.missed > 0.05 && coarse.farthest >= 1.0, "{coarse:?}");
    assert!(
        fine.missed > 0.0 && fine.missed < 0.5 * coarse.missed,
        "{fine:?}"
    );
}

/// `--bounds` cut out of a surface (`QuadMesh::retain_reaching`): the quads kept are
/// those whose corners' box, grown by the margin, meets the bounds; every vertex left is
/// used and in its place; the surface inside is all held (the box's edge is not
/// "missed"); and of a surface just outside the box, what the margin keeps has no
/// triangle reaching into it (`bake::clip::reaches`: the bake then finds nothing).
#[test]
fn a_region_cut_out_of_a_surface_keeps_what_reaches_into_it() {
    use sdfc::bake::clip::reaches;
    use sdfc::bake::coverage::coverage;
    use sdfc::bake::mesh::{dual_contour, Grid};
    use sdfc::ir::Aabb;
    common::with_example("sphere.sdf", |field, shape| {
        let own = shape.root_node().bounds;
        let cut = Aabb {
            min: DVec3::new(0.3, own.min.y, own.min.z),
            max: own.max,
        };
        let grid = Grid::over(cut, 24);
        let margin = 0.5 * grid.cell;
        let whole = dual_contour(field, &grid, 1e-5);
        let mut mesh = whole.clone();
        mesh.retain_reaching(cut, margin);
        assert!(!mesh.quads.is_empty() && mesh.quads.len() < whole.quads.len());
        let mut used = vec![false; mesh.vertices.len()];
        for q in &mesh.quads {
            for &i in q {
                used[i as usize] = true;
            }
        }
        assert!(used.iter().all(|&u| u), "unused vertices were kept");
        // Renumbered, not moved: every vertex (with its normal) is one of the whole
        // mesh's, and the quads kept are the whole mesh's within the margin of the box
        // (the box's other faces lie past the sphere).
        for (v, n) in mesh.vertices.iter().zip(&mesh.normals) {
            let k = whole
                .vertices
                .iter()
                .position(|w| w == v)
                .expect("a vertex");
            assert_eq!(whole.normals[k], *n);
        }
        let reaching = whole
            .quads
            .iter()
            .filter(|q| {
                q.iter()
                    .map(|&i| whole.vertices[i as usize].x)
                    .fold(f64::MIN, f64::max)
                    + margin
                    >= cut.min.x
            })
            .count();
        assert_eq!(mesh.quads.len(), reaching);
        let lowest = mesh.vertices.iter().map(|v| v.x).fold(f64::MAX, f64::min);
        assert!(
            lowest > cut.min.x - 2.0 * grid.cell && lowest < cut.min.x,
            "the kept quads end at x = {lowest}, the box at {} (cells of {})",
            cut.min.x,
            grid.cell
        );
        let held = coverage(field, &mesh, cut);
        assert!(held.samples > 100, "{held:?}");
        assert_eq!(held.missed, 0.0, "{held:?}");
        // Boxes that cut the sphere across several faces at once, at every angle to
        // the surface: what lies inside is all held there too.
        for (lo, hi) in [
            (DVec3::new(-0.37, -0.21, 0.13), own.max),
            (own.min, DVec3::new(0.41, 0.29, -0.17)),
            (DVec3::new(-0.6, -2.0, -0.55), DVec3::new(0.63, 0.07, 2.0)),
        ] {
            let cut = Aabb { min: lo, max: hi };
            let grid = Grid::over(cut, 24);
            let mut mesh = dual_contour(field, &grid, 1e-5);
            mesh.retain_reaching(cut, 0.5 * grid.cell);
            let held = coverage(field, &mesh, cut);
            assert!(held.samples > 100, "{cut:?}: {held:?}");
            assert_eq!(held.missed, 0.0, "{cut:?}: {held:?}");
        }
        // A box starting a twentieth of a cell past the sphere's surface (x = 1).
        let outside = Aabb {
            min: DVec3::new(1.0 + 0.05 * grid.cell, own.min.y, own.min.z),
            max: own.max + DVec3::ONE,
        };
        let grid = Grid::over(outside, 24);
        let margin = 0.5 * grid.cell;
        let mut mesh = dual_contour(field, &grid, 1e-5);
        assert!(
            !mesh.quads.is_empty(),
            "the grid's margin reaches the sphere"
        );
        mesh.retain_reaching(outside, margin);
        assert!(!reaches(mesh.triangles(), outside, 1e-3 * grid.cell));
        // Half a cell farther, the margin keeps nothing either.
        let farther = Aabb {
            min: outside.min + DVec3::new(0.5 * grid.cell, 0.0, 0.0),
            max: outside.max,
        };
        mesh.retain_reaching(farther, margin);
        assert!(mesh.quads.is_empty() && mesh.vertices.is_empty());
    });
}
