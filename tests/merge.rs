//! Implicit UVs part 2 on the CPU reference: the merge graph (frames, offsets,
//! obstructions), Alg. 2's blend and search, against the oracles of the notes.

use glam::{DVec2, DVec3};
use sdfc::codes;
use sdfc::driver::check;
use sdfc::ir::eval;
use sdfc::uv::{Atlas, Search, Status};
use std::path::Path;

use crate::common;
use common::Rng;

/// The first atlas of a scene that checks with no diagnostics at all.
fn clean_atlas(src: &str) -> Atlas {
    let a = check(
        src,
        Some(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("examples")
                .as_path(),
        ),
    );
    assert!(a.diagnostics.is_empty(), "{:#?}", a.diagnostics);
    a.atlases[0].clone().expect("the atlas prepares")
}

/// The file names of every example scene, sorted.
fn example_names() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .map(|p| p.file_name().unwrap().to_string_lossy().to_string())
        .collect();
    names.sort();
    names
}

fn example(name: &str) -> (String, Vec<Atlas>) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let src = std::fs::read_to_string(dir.join(name)).unwrap();
    let a = check(&src, Some(&dir));
    assert!(!a.has_errors(), "{name}: {:#?}", a.diagnostics);
    (src, a.atlases.into_iter().map(|a| a.unwrap()).collect())
}

/// A 3 x 3 grid of seeds on the plane y = 0, merged with grid neighbours, each seed
/// with a different written tangent.
const PLANE_GRID: &str = "let ground = plane(normal: [0, 1, 0], offset: 0);
atlas flat on ground {
    max_distance = 4;
    seed a = [-1, 0, -1] tangent [1, 0, 0.3];
    seed b = [0, 0, -1] tangent [0, 0, 1];
    seed c = [1, 0, -1] tangent [-1, 0, 1];
    seed d = [-1, 0, 0] tangent [0.2, 0, 1];
    seed e = [0, 0, 0] tangent [1, 0, -1];
    seed f = [1, 0, 0] tangent [0, 0, -1];
    seed g = [-1, 0, 1] tangent [1, 0, 1];
    seed h = [0, 0, 1] tangent [-1, 0, 0];
    seed i = [1, 0, 1] tangent [0.5, 0, 1];
    merge a b c f i h g d a;
    merge b e h;
    merge d e f;
}
render ground;";

#[test]
fn plane_frames_and_offsets_are_exact() {
    let a = clean_atlas(PLANE_GRID);
    let root = a.seeds[0].seed;
    // The first seed keeps its written tangent; every other frame equals it.
    assert!((root.e1 - DVec3::new(1.0, 0.0, 0.3).normalize()).length() < 1e-9);
    for s in &a.seeds {
        assert!((s.seed.e1 - root.e1).length() < 1e-6, "{:?}", s.seed.e1);
        assert!((s.seed.e2 - root.e2).length() < 1e-6);
        // u_i = Log_{p_0}(p_i) on a plane.
        let d = s.seed.p - root.p;
        let want = DVec2::new(d.dot(root.e1), d.dot(root.e2));
        assert!((s.offset - want).length() < 1e-6, "{} vs {want}", s.offset);
    }
    assert!(
        a.graph.cycles.len() == 4,
        "a 3 x 3 grid graph has 4 independent cycles"
    );
    for c in &a.graph.cycles {
        assert!(c.holonomy.abs() < 1e-6 && c.residual < 1e-6 && !c.is_obstruction());
    }
    // σ defaults to the shortest edge over 3.
    assert!((a.sigma - 1.0 / 3.0).abs() < 1e-6);
}

#[test]
fn merged_plane_atlas_is_an_isometry() {
    let a = clean_atlas(PLANE_GRID);
    let mut rng = Rng(11);
    let mut pairs = 0;
    for _ in 0..2000 {
        let p = DVec3::new(rng.range(-1.6, 1.6), 0.0, rng.range(-1.6, 1.6));
        let q = DVec3::new(rng.range(-1.6, 1.6), 0.0, rng.range(-1.6, 1.6));
        let (sp, sq) = (a.sample(p), a.sample(q));
        assert_eq!((sp.status, sq.status), (Status::Ok, Status::Ok));
        let (du, dx) = ((sp.uv - sq.uv).length(), (p - q).length());
        if dx > 1e-3 {
            pairs += 1;
            assert!(
                (du - dx).abs() <= 1e-4 * dx,
                "|uv(a) − uv(b)| = {du}, |a − b| = {dx} at {p}, {q}"
            );
        }
    }
    assert!(pairs > 1900);
}

#[test]
fn blend_weight_follows_eq_40() {
    use sdfc::uv::atlas::{blend_weight, frontier_distance};
    assert_eq!(blend_weight(-0.5, 0.2), 1.0);
    assert_eq!(blend_weight(0.5, 0.2), 0.0);
    assert!((blend_weight(0.0, 0.2) - 0.5).abs() < 1e-12);
    // ω(t) = 3t² − 2t³ at t = 1/2 − d/(2σ) = 0.75.
    assert!((blend_weight(-0.1, 0.2) - (3.0 * 0.5625 - 2.0 * 0.421875)).abs() < 1e-12);
    // Eq. 39 on a plane is the exact signed distance to the bisector.
    let (pi, pj, x) = (
        DVec3::ZERO,
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.7, 0.0, 3.0),
    );
    let f = frontier_distance((x - pi).length(), (x - pj).length(), 2.0);
    assert!((f - (0.7 - 1.0)).abs() < 1e-12);
}

/// Along a path, the uv must not jump by more than twice the sample spacing between
/// samples whose seeds are the same or merged.
fn assert_continuous(a: &Atlas, path: &[DVec3], what: &str) -> usize {
    let mut crossings = 0;
    for w in path.windows(2) {
        let (s0, s1) = (a.sample(w[0]), a.sample(w[1]));
        if s0.status != Status::Ok || s1.status != Status::Ok {
            continue;
        }
        let (i, j) = (s0.seed.unwrap(), s1.seed.unwrap());
        if i != j {
            if !a.merged(i, j) {
                continue;
            }
            crossings += 1;
        }
        let step = (w[1] - w[0]).length();
        let jump = (s1.uv - s0.uv).length();
        assert!(
            jump <= 2.0 * step,
            "{what}: uv jumps by {jump} over {step} between {} and {} (seeds {i} and {j})",
            w[0],
            w[1]
        );
    }
    crossings
}

/// Points along the segment from p to q, each projected onto the surface.
fn surface_path(a: &Atlas, p: DVec3, q: DVec3, n: usize) -> Vec<DVec3> {
    (0..=n)
        .filter_map(|k| {
            let t = k as f64 / n as f64;
            eval::project(&a.shape, p.lerp(q, t), 1e-10)
        })
        .collect()
}

#[test]
fn uv_is_continuous_across_every_merged_frontier_of_every_example() {
    let mut frontiers = 0;
    for name in example_names() {
        let (_, atlases) = example(&name);
        for a in &atlases {
            for e in &a.graph.edges {
                // The segment between two merged seeds, projected, crosses their frontier.
                let (p, q) = (a.seeds[e.a].seed.p, a.seeds[e.b].seed.p);
                let path = surface_path(a, p, q, 400);
                let crossed = assert_continuous(a, &path, &format!("{name}: {}", a.name));
                assert!(
                    crossed > 0,
                    "{name}: the path from seed {} to {} crosses their frontier",
                    e.a,
                    e.b
                );
                frontiers += 1;
            }
        }
    }
    assert!(frontiers >= 100, "{frontiers} merged frontiers checked");
}

#[test]
fn early_out_and_grid_search_equal_brute_force_on_every_example() {
    let mut rng = Rng(2024);
    let mut checked = 0;
    for name in example_names() {
        let (_, atlases) = example(&name);
        for a in &atlases {
            let grid = a.seed_grid();
            let b = a.shape.framing_bounds();
            let mut here = 0;
            for _ in 0..300 {
                let r = DVec3::new(rng.unit(), rng.unit(), rng.unit());
                let Some(x) = eval::project(&a.shape, b.min + (b.max - b.min) * r, 1e-10) else {
                    continue;
                };
                let slow = a.nearest(x, true);
                let fast = a.nearest(x, false);
                let gridded = a.nearest_in_grid(x, &grid);
                assert_eq!(fast.seed, slow.seed, "{name}: early-out at {x}");
                assert_eq!(gridded.seed, slow.seed, "{name}: grid at {x}");
                assert_eq!((fast.status, gridded.status), (slow.status, slow.status));
                if slow.status == Status::Ok {
                    // The blended sample does not depend on the search either.
                    let (u0, u1) = (
                        a.sample_with(x, Search { brute_force: true }).uv,
                        a.sample(x).uv,
                    );
                    assert!((u0 - u1).length() < 1e-9);
                }
                here += 1;
            }
            assert!(here > 100, "{name}: only {here} surface points");
            checked += here;
        }
    }
    assert!(checked > 1500);
}

#[test]
fn four_merged_seeds_cover_a_plate_with_a_hole_where_one_cannot() {
    let (src, atlases) = example("plate_hole.sdf");
    let four = &atlases[0];
    // The same plate with only the first seed.
    let one_src = src
        .lines()
        .filter(|l| {
            !(l.contains("seed north")
                || l.contains("seed west")
                || l.contains("seed south")
                || l.contains("merge"))
        })
        .collect::<Vec<_>>()
        .join("\n");
    let one = clean_atlas(&one_src);
    assert_eq!(one.seeds.len(), 1);
    let mut rng = Rng(12);
    let (mut top, mut one_failed) = (Vec::new(), 0);
    while top.len() < 600 {
        let x = DVec3::new(rng.range(-1.9, 1.9), 0.1, rng.range(-1.9, 1.9));
        if x.x * x.x + x.z * x.z < 0.7 * 0.7 {
            continue;
        }
        let s = four.sample(x);
        assert_eq!(s.status, Status::Ok, "four seeds cover {x}");
        if one.sample(x).status != Status::Ok {
            one_failed += 1;
        }
        top.push((x, s.uv));
    }
    assert!(
        one_failed > 60,
        "one seed alone fails on {one_failed} of 600 points"
    );
    // The ring of merges is flat, so the chart is one isometry over the whole top face.
    for w in top.chunks(2) {
        let (du, dx) = ((w[0].1 - w[1].1).length(), (w[0].0 - w[1].0).length());
        assert!((du - dx).abs() <= 1e-4 * dx, "{du} vs {dx}");
    }
    assert!(four.graph.cycles.len() == 1 && !four.graph.cycles[0].is_obstruction());
}

#[test]
fn seeds_merged_around_a_cylinder_are_an_obstruction_along_it_not() {
    let around = check(
        "let tube = cylinder(radius: 0.5, height: 3);
atlas skin on tube {
    seed a = [0.5, 0, 0] tangent [0, 1, 0];
    seed b = [0, 0, 0.5];
    seed c = [-0.5, 0, 0];
    seed d = [0, 0, -0.5];
    merge a b c d a;
}
render tube;",
        None,
    );
    let codes: Vec<&str> = around.diagnostics.iter().map(|d| d.code).collect();
    assert_eq!(codes, [codes::W_OBSTRUCTION]);
    let cycle = &around.atlases[0].as_ref().unwrap().graph.cycles[0];
    // The cylinder is flat: no holonomy, but the offsets miss by the whole circumference.
    assert!(
        cycle.holonomy.abs().to_degrees() < 1.0,
        "{}",
        cycle.holonomy
    );
    assert!(cycle.closure > 0.9, "{}", cycle.closure);
    let along = check(
        "let tube = cylinder(radius: 0.5, height: 3);
atlas skin on tube {
    seed a = [0.5, -1, 0] tangent [0, 1, 0];
    seed b = [0.5, 0, 0];
    seed c = [0.5, 1, 0];
    merge a b c;
}
render tube;",
        None,
    );
    assert!(along.diagnostics.is_empty(), "{:#?}", along.diagnostics);
    // Along the axis the merged chart is exact: the cylinder develops onto the plane.
    let a = along.atlases[0].as_ref().unwrap();
    // The notes: only the axial and circumferential lines through a seed are exact.
    for y in [-1.2, -0.5, 0.3, 0.9] {
        let s = a.sample(DVec3::new(0.5, y, 0.0));
        assert_eq!(s.status, Status::Ok);
        // u along the axis (the tangent [0, 1, 0]) is y + 1 from seed a; v is 0.
        assert!(
            (s.uv - DVec2::new(y + 1.0, 0.0)).length() < 1e-3,
            "{} at y = {y}",
            s.uv
        );
    }
    for (seed_y, ang) in [(-1.0, -0.6f64), (0.0, 0.4), (1.0, 0.7)] {
        let s = a.sample(DVec3::new(0.5 * ang.cos(), seed_y, 0.5 * ang.sin()));
        // Around the circumference: u is the seed's offset, |v| the arc length.
        assert!((s.uv.x - (seed_y + 1.0)).abs() < 1e-3, "{}", s.uv);
        assert!((s.uv.y.abs() - 0.5 * ang.abs()).abs() < 1e-3, "{}", s.uv);
    }
}

#[test]
fn frames_and_offsets_solve_for_seventy_two_seeds() {
    // A 12 x 6 grid on a plane, all merged with neighbours: the solve recovers one frame.
    // Both systems (213 and 71 unknowns) take the sparse factor; PLANE_GRID's the dense.
    let mut src = String::from("let ground = plane(normal: [0, 1, 0], offset: 0);\natlas flat on ground {\n    max_distance = 3;\n");
    for r in 0..6 {
        for c in 0..12 {
            let t = [(c as f64).cos(), 0.0, (r as f64 + 0.3).sin()];
            src += &format!(
                "    seed s{r}_{c} = [{}, 0, {}] tangent [{}, 0, {}];\n",
                c as f64 * 0.5,
                r as f64 * 0.5,
                t[0],
                t[2]
            );
        }
    }
    for r in 0..6 {
        src += &format!(
            "    merge {};\n",
            (0..12)
                .map(|c| format!("s{r}_{c}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    for c in 0..12 {
        src += &format!(
            "    merge {};\n",
            (0..6)
                .map(|r| format!("s{r}_{c}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    src += "}\nrender ground;";
    let a = clean_atlas(&src);
    assert_eq!(a.seeds.len(), 72);
    assert_eq!(a.graph.edges.len(), 6 * 11 + 12 * 5);
    let root = a.seeds[0].seed;
    for s in &a.seeds {
        assert!((s.seed.e1 - root.e1).length() < 1e-6);
        let d = s.seed.p - root.p;
        assert!((s.offset - DVec2::new(d.dot(root.e1), d.dot(root.e2))).length() < 1e-6);
    }
    eprintln!(
        "frame and offset solves for 72 seeds: {:.3} ms",
        a.graph.solve_seconds * 1e3
    );
}

/// The seed-count sweep's plates (`sdfc bench --seed-sweep`): every one compiles with no
/// diagnostics, reaches every sampled point of the top face, and when merged is one
/// isometric chart (the sweep measures working atlases, not failing walks).
#[test]
fn seed_sweep_plates_cover_the_top_face() {
    for seeds in sdfc::bench::SEED_COUNTS {
        for merged in [false, true] {
            let a = clean_atlas(&sdfc::bench::plate(seeds, 10, merged));
            assert_eq!(a.seeds.len(), seeds as usize);
            let want_edges = if merged {
                let (r, c) = sdfc::bench::layout(seeds);
                (r * (c - 1) + c * (r - 1)) as usize
            } else {
                0
            };
            assert_eq!(a.graph.edges.len(), want_edges, "{seeds} seeds");
            let mut rng = Rng(seeds as u64 + 100);
            // Away from the rim, where a long step of the 1-seed walk can meet the edge.
            let h = sdfc::bench::HALF - 0.3;
            let pts: Vec<DVec3> = (0..60)
                .map(|_| DVec3::new(rng.range(-h, h), 0.1, rng.range(-h, h)))
                .collect();
            let samples: Vec<_> = pts.iter().map(|&p| a.sample(p)).collect();
            for (p, s) in pts.iter().zip(&samples) {
                assert_eq!(
                    s.status,
                    Status::Ok,
                    "{seeds} seeds, merged {merged}, at {p}"
                );
            }
            if merged {
                for (i, j) in (0..pts.len()).zip(1..pts.len()) {
                    let (du, dx) = (
                        (samples[i].uv - samples[j].uv).length(),
                        (pts[i] - pts[j]).length(),
                    );
                    assert!((du - dx).abs() <= 1e-3 * dx, "{seeds} seeds: {du} vs {dx}");
                }
            }
        }
    }
}
