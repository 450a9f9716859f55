//! Automatic seeds (`sdfc seeds`, `uv::seeds`): a seed on every face of a box,
//! determinism, the ring around a hole, `--keep`, the stretch measure. Coverage of
//! every example against an independent area-uniform measure, and stretch against the
//! hand-placed seeds, are in `seeds_coverage.rs`.

use crate::common;

use common::sdfc;

/// An atlas with no seed yet (an error for `check`) is what `sdfc seeds` is for.
#[test]
fn an_atlas_without_seeds_gets_some() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("new.sdf");
    std::fs::write(
        &path,
        "let b = sphere(1);\n\natlas skin on b {\n    steps = 16;\n}\n\nrender b;\n",
    )
    .unwrap();
    let (code, out, err) = sdfc(&["seeds", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("    seed s0 = ["), "{out}");
    let (code, _, err) = sdfc(&["seeds", path.to_str().unwrap(), "--write"]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = sdfc(&["check", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = sdfc(&["seeds", path.to_str().unwrap(), "--atlas", "nope"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no atlas `nope`"), "{err}");
}

#[test]
fn every_face_of_a_box_gets_a_seed_and_placement_is_deterministic() {
    let source = "let b = box([1, 0.6, 0.8]);\natlas skin on b { steps = 16; seed x = [0, 0, 1]; }\nrender b;\n";
    let analysis = sdfc::driver::check(source, None);
    assert!(!analysis.has_errors(), "{:?}", analysis.diagnostics);
    let def = &analysis.program.atlases[0];
    let shape = sdfc::ir::lower_shape(&def.shape).unwrap();
    let place = || {
        let samples = sdfc_samples(&shape);
        sdfc::uv::seeds::place(def, &shape, &samples, Default::default())
    };
    let placed = place();
    assert!(placed.coverage >= 0.995, "coverage {}", placed.coverage);
    for axis in [glam::DVec3::X, glam::DVec3::Y, glam::DVec3::Z] {
        for sign in [1.0, -1.0] {
            let n = axis * sign;
            let on_face = placed.seeds.iter().any(|(p, _)| {
                let g = sdfc::ir::eval::gradient(&shape, *p).normalize();
                g.dot(n) > 0.99
            });
            assert!(on_face, "no seed on the face facing {n}");
        }
    }
    // Sharp edges split the box into six islands: merges stay inside faces.
    let normal = |k: usize| sdfc::ir::eval::gradient(&shape, placed.seeds[k].0).normalize();
    for &(a, b) in &placed.merges {
        assert!(
            normal(a).dot(normal(b)) > 0.99,
            "merge {a}–{b} across an edge"
        );
    }
    assert_eq!(place(), placed, "not deterministic");
}

/// Fig. 12: on the top of a plate with a hole, placement finds a merged ring around the
/// hole: a cycle of merges among seeds of the top face that winds once around the
/// hole's axis. The plate is flat, so the cycle closes without an obstruction.
#[test]
fn the_ring_around_the_hole_is_found_and_closed() {
    let source = "let plate = box([4, 0.2, 4]) - cylinder(radius: 0.6, height: 1);\natlas top on plate { steps = 20; seed x = [1.2, 0.1, 0]; }\nrender plate;\n";
    let analysis = sdfc::driver::check(source, None);
    assert!(!analysis.has_errors(), "{:?}", analysis.diagnostics);
    let def = &analysis.program.atlases[0];
    let shape = sdfc::ir::lower_shape(&def.shape).unwrap();
    let placed = sdfc::uv::seeds::place(def, &shape, &sdfc_samples(&shape), Default::default());
    // The merges among seeds on the top face (y = 0.1).
    let top = |k: usize| (placed.seeds[k].0.y - 0.1).abs() < 1e-3;
    let edges: Vec<(usize, usize)> = placed
        .merges
        .iter()
        .copied()
        .filter(|&(a, b)| top(a) && top(b))
        .collect();
    // Remove leaves until only cycles remain (the 2-core of the merge graph).
    let mut live = edges.clone();
    loop {
        let degree =
            |k: usize, e: &[(usize, usize)]| e.iter().filter(|&&(a, b)| a == k || b == k).count();
        let before = live.len();
        let snapshot = live.clone();
        live.retain(|&(a, b)| degree(a, &snapshot) > 1 && degree(b, &snapshot) > 1);
        if live.len() == before {
            break;
        }
    }
    assert!(
        !live.is_empty(),
        "no cycle among the top face's merges {edges:?}"
    );
    // Some cycle winds around the hole's axis (y): lift each seed's angle about the
    // axis along a spanning tree of the merges (each edge sweeps less than π, as the
    // seeds are close); an edge off the tree whose own sweep disagrees with the lifted
    // angles by a turn closes a cycle that goes once around the hole.
    let angle = |k: usize| placed.seeds[k].0.z.atan2(placed.seeds[k].0.x);
    let wrap = |mut d: f64| {
        while d > std::f64::consts::PI {
            d -= std::f64::consts::TAU;
        }
        while d < -std::f64::consts::PI {
            d += std::f64::consts::TAU;
        }
        d
    };
    let mut lifted: std::collections::BTreeMap<usize, f64> = Default::default();
    let mut winds = false;
    for &(a0, _) in &live {
        if lifted.contains_key(&a0) {
            continue;
        }
        lifted.insert(a0, angle(a0));
        let mut stack = vec![a0];
        let mut tree = std::collections::BTreeSet::new();
        while let Some(at) = stack.pop() {
            for (i, &(a, b)) in live.iter().enumerate() {
                let next = match (a == at, b == at) {
                    (true, _) => b,
                    (_, true) => a,
                    _ => continue,
                };
                if tree.contains(&i) {
                    continue;
                }
                let through = lifted[&at] + wrap(angle(next) - angle(at));
                match lifted.get(&next) {
                    None => {
                        tree.insert(i);
                        lifted.insert(next, through);
                        stack.push(next);
                    }
                    Some(&there) => {
                        tree.insert(i);
                        if (through - there).abs() > std::f64::consts::PI {
                            winds = true;
                        }
                    }
                }
            }
        }
    }
    assert!(winds, "no merged cycle around the hole: {live:?}");
    // And the atlas, cycle included, checks clean.
    let text = format!(
        "let plate = box([4, 0.2, 4]) - cylinder(radius: 0.6, height: 1);\natlas top on plate {{\n    steps = 20;\n{}}}\nrender plate;\n",
        sdfc::ide::seeds::statements(&placed)
    );
    let checked = sdfc::driver::check(&text, None);
    assert!(checked.diagnostics.is_empty(), "{:?}", checked.diagnostics);
}

/// Surface samples as `sdfc seeds` makes them: drawn uniformly by area.
fn sdfc_samples(shape: &sdfc::ir::Shape) -> Vec<sdfc::uv::seeds::SurfaceSample> {
    sdfc::reference::surface::surface_samples(shape, 40).unwrap()
}

/// `--keep` ("add seeds to cover the gaps"): the robot with its legs' seeds removed
/// keeps every seed and merge it has, word for word and in place, and gains seeds
/// where the legs are uncovered; the result covers the target share and checks clean.
#[test]
fn keep_adds_seeds_to_the_gaps_and_leaves_the_seeds_there() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("textures")).unwrap();
    std::fs::copy(
        "examples/textures/bricks.png",
        dir.path().join("textures/bricks.png"),
    )
    .unwrap();
    let robot = std::fs::read_to_string("examples/robot.sdf").unwrap();
    let without: String = robot
        .lines()
        .filter(|l| !["shin_", "calf_", "hip_"].iter().any(|k| l.contains(k)))
        .map(|l| format!("{l}\n"))
        .collect();
    let path = dir.path().join("robot.sdf");
    std::fs::write(&path, &without).unwrap();
    let (code, _, err) = sdfc(&["seeds", path.to_str().unwrap(), "--keep", "--write"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("(24 kept)"), "{err}");
    let coverage: f64 = err
        .split("coverage ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    // 99.37 % measured on a draw apart from placement's: the rest lies within the
    // gradient's step of the boxes' creases, where every walk fails (see
    // seeds_coverage.rs, ROBOT_COVERAGE).
    assert!(coverage >= 99.2, "{err}");
    let written = std::fs::read_to_string(&path).unwrap();
    // Every line of the atlas block that was there is still there, in order.
    let mut rest = written.as_str();
    for line in without
        .lines()
        .filter(|l| l.trim_start().starts_with("seed ") || l.trim_start().starts_with("merge "))
    {
        let at = rest
            .find(line.trim())
            .unwrap_or_else(|| panic!("lost: {line}\n{written}"));
        rest = &rest[at..];
    }
    assert!(written.contains("seed auto0 = "), "{written}");
    let (code, out, err) = sdfc(&["check", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("0 errors, 0 warnings") || err.contains("0 errors, 0 warnings"),
        "{out}{err}"
    );
}

/// The stretch report: 1 for an isometry (a flat slab's top, one seed, up to its
/// rim), above 1 where the log map stretches (a sphere with one seed, far from it).
#[test]
fn stretch_is_one_on_a_plane_and_grows_on_a_sphere() {
    let measure = |src: &str| {
        let a = sdfc::driver::check(src, None);
        assert!(!a.has_errors(), "{:?}", a.diagnostics);
        let atlas = a.atlases[0].as_ref().unwrap();
        let samples = sdfc::reference::surface::surface_samples(&atlas.shape, 24).unwrap();
        sdfc::uv::seeds::stretch(atlas, &samples)
    };
    let (mean, p95, n) = measure(
        "let slab = box([4, 0.5, 4]);\natlas a on slab { seed o = [0, 0.25, 0] tangent [1, 0, 0]; }\nrender slab;",
    );
    assert!(n > 100, "{n}");
    // The samples by the rim count too (drawn uniformly by area, some lie 0.02 from
    // the edge): Eq. 17's first difference once reached back across the edge from a
    // point beside it, and the uv there was off (stretch up to 10, a mean of 1.05).
    assert!((p95 - 1.0).abs() < 1e-3 && mean < 1.001, "{mean} {p95}");
    let (mean, p95, _) = measure(
        "let ball = sphere(1);\natlas a on ball { max_distance = 3.2; seed o = [0, 0, 1]; }\nrender ball;",
    );
    assert!(mean > 1.1 && p95 > mean, "{mean} {p95}");
}
