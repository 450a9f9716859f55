//! Automatic seeds against an independent, area-uniform measure of the surface
//! (issue 42): for every example with an atlas (its seeds removed) and for shapes built
//! here with thin slits, a groove, a cup with a handle and a knot-like blend of tori,
//! `sdfc seeds --write` leaves a file that checks with no diagnostic, whose atlas covers
//! at least 99.5 % of the surface by area under Alg. 2, measured here on points drawn
//! uniformly by area (not on the placement's samples), agrees with the coverage it
//! reports to 0.3 %, and stretches no more than the hand-placed atlas (mean and 95th
//! percentile), where the example has one.
//!
//! The measure: points drawn uniformly in the thin shell |f| < ε around the zero set
//! (cells that the field's Lipschitz bound says cannot reach the shell are skipped,
//! the rest sampled evenly), weighted by |∇f| (the shell is 2ε/|∇f| thick, so that
//! weight makes the density proportional to area), then projected onto the surface.

use crate::common;

use common::{sdfc, Rng};
use glam::DVec3;
use sdfc::ir::{eval, Shape};
use sdfc::uv::seeds::SurfaceSample;

/// Samples of the independent measure per atlas (a failing share of 0.5 % is then
/// measured to ±0.13 %, one standard error).
const SAMPLES: usize = 3000;

/// The slack on stretch comparisons: the 95th percentile of stretch on flat faces is
/// 1.000 up to the finite differences that measure it.
const STRETCH_SLACK: f64 = 0.005;

/// `n` points of the zero set of `shape`, uniform by area, as weighted samples.
fn area_uniform(shape: &Shape, n: usize, seed: u64) -> Vec<SurfaceSample> {
    let b = shape.root_node().bounds;
    assert!(b.is_finite(), "no finite bounds");
    let cells = 48usize;
    let h = (b.max - b.min).max_element() / cells as f64;
    let dims = ((b.max - b.min) / h).ceil().as_uvec3() + glam::UVec3::splat(2);
    let origin = b.min - DVec3::splat(h);
    let eps = h / 256.0;
    let lip = shape.lipschitz().max(1.0);
    let reach = lip * h * 3f64.sqrt() * 0.5 + eps;
    let mut candidates = Vec::new();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let lo = origin + DVec3::new(x as f64, y as f64, z as f64) * h;
                if eval::distance(shape, lo + DVec3::splat(0.5 * h)).abs() <= reach {
                    candidates.push(lo);
                }
            }
        }
    }
    assert!(!candidates.is_empty(), "no cell reaches the surface");
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    let mut rounds = 0;
    // Whole rounds over every candidate cell keep the draw uniform over them.
    while out.len() < n {
        rounds += 1;
        assert!(rounds < 100_000, "the shell has almost no volume");
        for lo in &candidates {
            let x = *lo + DVec3::new(rng.unit(), rng.unit(), rng.unit()) * h;
            if eval::distance(shape, x).abs() >= eps {
                continue;
            }
            let w = eval::gradient(shape, x).length();
            let Some(p) = eval::project(shape, x, 1e-9) else {
                continue;
            };
            let g = eval::gradient(shape, p);
            if g.length() < 1e-6 {
                continue;
            }
            out.push(SurfaceSample {
                p,
                n: g.normalize(),
                area: w,
                smooth: 1.0,
            });
        }
    }
    out
}

/// The share of `samples` (by weight) where Alg. 2 succeeds.
fn coverage(atlas: &sdfc::uv::Atlas, samples: &[SurfaceSample]) -> f64 {
    use rayon::prelude::*;
    let ok: f64 = samples
        .par_iter()
        .filter(|s| atlas.sample(s.p).status == sdfc::uv::logmap::Status::Ok)
        .map(|s| s.area)
        .sum();
    ok / samples.iter().map(|s| s.area).sum::<f64>()
}

struct Measured {
    coverage: f64,
    /// The local stretch at each sample (None where it is not measured).
    stretch: Vec<Option<f64>>,
}

/// Mean and 95th percentile of `values`.
fn summary(mut values: Vec<f64>) -> (f64, f64) {
    if values.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    values.sort_by(f64::total_cmp);
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    (
        mean,
        values[((values.len() as f64 * 0.95) as usize).min(values.len() - 1)],
    )
}

/// Coverage and stretch of each atlas of the scene `text`, on `samples` (one set per
/// atlas; drawn here when not given).
fn measure(
    text: &str,
    base: &std::path::Path,
    samples: Option<&[Vec<SurfaceSample>]>,
) -> (Vec<Measured>, Vec<Vec<SurfaceSample>>) {
    let analysis = sdfc::driver::check(text, Some(base));
    let mut out = Vec::new();
    let mut drawn = Vec::new();
    for (k, atlas) in analysis.atlases.iter().enumerate() {
        let atlas = atlas.as_ref().expect("a prepared atlas");
        let set = match samples {
            Some(s) => s[k].clone(),
            None => area_uniform(&atlas.shape, SAMPLES, 7 + k as u64),
        };
        use rayon::prelude::*;
        let stretch = set
            .par_iter()
            .map(|s| sdfc::uv::seeds::local_stretch(atlas, s))
            .collect();
        out.push(Measured {
            coverage: coverage(atlas, &set),
            stretch,
        });
        drawn.push(set);
    }
    (out, drawn)
}

/// Runs `sdfc seeds --write` on `path`; returns the coverage it reports and its stderr.
fn place(path: &std::path::Path, extra: &[&str]) -> (f64, String) {
    let mut args = vec!["seeds", path.to_str().unwrap(), "--write"];
    args.extend_from_slice(extra);
    let (code, _, err) = sdfc(&args);
    assert_eq!(code, 0, "{}: {err}", path.display());
    let reported: f64 = err
        .split("coverage ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no coverage in {err}"));
    (reported / 100.0, err)
}

/// The scene with every atlas's seed and merge lines removed.
fn without_seeds(text: &str) -> String {
    text.lines()
        .filter(|l| {
            let t = l.trim_start();
            !(t.starts_with("seed ") || t.starts_with("merge "))
        })
        .map(|l| format!("{l}\n"))
        .collect()
}

/// The file checks with no diagnostic and is formatted.
fn check_clean(path: &std::path::Path) {
    let (code, out, err) = sdfc(&["fmt", "--check", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{}: {out}{err}", path.display());
    let (code, out, err) = sdfc(&["check", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{}: {out}{err}", path.display());
    assert!(
        err.contains("0 errors, 0 warnings") || out.contains("0 errors, 0 warnings"),
        "{}: {out}{err}",
        path.display()
    );
}

fn examples_with_atlases() -> Vec<String> {
    let mut out: Vec<String> = std::fs::read_dir("examples")
        .unwrap()
        .filter_map(|e| {
            let p = e.unwrap().path();
            let name = p.file_name()?.to_str()?.to_string();
            let text = std::fs::read_to_string(&p).ok()?;
            (name.ends_with(".sdf") && text.contains("\natlas ")).then_some(name)
        })
        .collect();
    out.sort();
    out
}

/// The scene with every atlas's seeds placed by `sdfc seeds --write` (with `args`),
/// checked clean; returns the coverage each placement reported and the time it took.
fn place_all(path: &std::path::Path, names: &[String], args: &[&str]) -> (Vec<f64>, Vec<f64>) {
    let mut reported = Vec::new();
    let mut took = Vec::new();
    for name in names {
        let mut all = vec!["--atlas", name.as_str()];
        all.extend_from_slice(args);
        let started = std::time::Instant::now();
        reported.push(place(path, &all).0);
        took.push(started.elapsed().as_secs_f64());
    }
    check_clean(path);
    (reported, took)
}

/// Mean and 95th percentile of stretch over the samples where every atlas in `all`
/// measures it.
fn stretch_where_all(which: &Measured, all: &[&Measured]) -> (f64, f64) {
    summary(
        (0..which.stretch.len())
            .filter(|&k| all.iter().all(|m| m.stretch[k].is_some()))
            .filter_map(|k| which.stretch[k])
            .collect(),
    )
}

fn copy_textures(dir: &std::path::Path) {
    std::fs::create_dir_all(dir.join("textures")).unwrap();
    for entry in std::fs::read_dir("examples/textures").unwrap() {
        let p = entry.unwrap().path();
        std::fs::copy(&p, dir.join("textures").join(p.file_name().unwrap())).unwrap();
    }
}

/// Every example's atlases, their seeds removed, placed again with the stretch target
/// set to the hand-placed atlas's 95th percentile where that is below the default (and
/// at least 1.05): coverage by the
/// independent measure, the reported coverage, no diagnostic, and stretch at most the
/// hand-placed atlas's (mean and 95th percentile) where both are measured. Examples
/// whose atlases are the same (shape and settings) are placed once.
#[test]
fn automatic_seeds_cover_every_example_by_area_and_stretch_no_more_than_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    let root = std::fs::canonicalize("examples").unwrap();
    copy_textures(dir.path());
    let mut failures = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for example in examples_with_atlases() {
        let original = std::fs::read_to_string(root.join(&example)).unwrap();
        let analysis = sdfc::driver::check(&original, Some(&root));
        let key = format!(
            "{:?}",
            analysis
                .atlases
                .iter()
                .map(|a| a.as_ref().map(|a| (&a.shape, a.params)))
                .collect::<Vec<_>>()
        );
        if !seen.insert(key) {
            eprintln!("{example}: its atlases are an earlier example's");
            continue;
        }
        let names: Vec<String> = analysis
            .program
            .atlases
            .iter()
            .map(|a| a.name.clone())
            .collect();
        let (hand, samples) = measure(&original, &root, None);
        let path = dir.path().join(&example);
        std::fs::write(&path, without_seeds(&original)).unwrap();
        let targets: Vec<String> = hand
            .iter()
            .map(|h| {
                let p95 = summary(h.stretch.iter().flatten().copied().collect()).1;
                // (No hand-placed sample measured: the default.)
                let p95 = if p95.is_nan() {
                    sdfc::uv::seeds::DEFAULT_MAX_STRETCH
                } else {
                    p95
                };
                format!(
                    "{:.3}",
                    p95.clamp(1.05, sdfc::uv::seeds::DEFAULT_MAX_STRETCH)
                )
            })
            .collect();
        let mut reported = Vec::new();
        let mut took = Vec::new();
        for (name, target) in names.iter().zip(&targets) {
            let started = std::time::Instant::now();
            // (At most 128 seeds, for CI's time, but on the 8 × 8 plate, whose thin
            // sides need about 200 at its D, and on csg.sdf, whose 3 × 3 floor held
            // to 1.05 needs 256: at 128 its top's edges take the nearest of the many
            // seeds down its 0.2-high sides, across the fillet, and stretch by 1.011
            // on average where the hand-placed atlas's one seed on top gives 1.001.)
            let most = if example == "plate.sdf" || example == "csg.sdf" {
                "256"
            } else {
                "128"
            };
            let args = [
                "--atlas",
                name,
                "--max-stretch",
                target,
                "--max-seeds",
                most,
            ];
            reported.push(place(&path, &args).0);
            took.push(started.elapsed().as_secs_f64());
        }
        let written = std::fs::read_to_string(&path).unwrap();
        // The comments outside the seed lines stay.
        let comments = |t: &str| {
            t.lines()
                .filter(|l| l.trim_start().starts_with("//"))
                .count()
        };
        assert_eq!(
            comments(&written),
            comments(&without_seeds(&original)),
            "{example}"
        );
        let (auto, _) = measure(&written, dir.path(), Some(&samples));
        let program = sdfc::driver::check(&written, Some(dir.path())).program;
        for (k, name) in names.iter().enumerate() {
            let def = &program.atlases[k];
            let (h, a) = (&hand[k], &auto[k]);
            let (hs, as_) = (stretch_where_all(h, &[h, a]), stretch_where_all(a, &[h, a]));
            let whole = stretch_where_all(a, &[a]);
            eprintln!(
                "{example} {name}: by hand {:.2} %, stretch {:.3} / {:.3}; automatic (--max-stretch {}) {} seeds, {} merges, {:.2} % (reported {:.2} %), stretch {:.3} / {:.3} there, {:.3} / {:.3} everywhere, {:.1} s",
                100.0 * h.coverage, hs.0, hs.1, targets[k], def.seeds.len(), def.merges.len(),
                100.0 * a.coverage, 100.0 * reported[k], as_.0, as_.1, whole.0, whole.1, took[k],
            );
            let id = format!("{example} {name}");
            if a.coverage < 0.995
                || (a.coverage - reported[k]).abs() > 0.003
                || as_.0 > hs.0 + STRETCH_SLACK
                || as_.1 > hs.1 + STRETCH_SLACK
            {
                failures.push(id);
            }
        }
        check_clean(&path);
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// Shapes no example has: two boxes 0.05 apart, a box with a 0.03-wide groove, a
/// shelled cup with a torus handle, and three tori blended into a knot-like loop.
/// With the default stretch target: coverage by the independent measure, the
/// reported coverage, no diagnostic, and the 95th percentile of stretch at the target.
#[test]
fn automatic_seeds_cover_slits_grooves_handles_and_blends() {
    let shapes = [
        ("slit", "box([1, 0.6, 0.8]).translate([0, 0.325, 0]) | box([1, 0.6, 0.8]).translate([0, -0.325, 0])", "steps = 12; max_distance = 1.5;"),
        ("groove", "box([1.2, 0.5, 0.8]) - box([0.03, 0.4, 1]).translate([0, 0.25, 0])", "steps = 12; max_distance = 1.5;"),
        ("cup", "smooth_union(cylinder(radius: 0.5, height: 1).shell(0.04) - box([2, 1, 2]).translate([0, 0.9, 0]), torus(major: 0.3, minor: 0.06).rotate_x(90deg).translate([0.6, 0, 0]), 0.05)", "steps = 12; max_distance = 1.2;"),
        ("knot", "smooth_union(smooth_union(torus(major: 0.6, minor: 0.12), torus(major: 0.6, minor: 0.12).rotate_x(60deg).translate([0.3, 0, 0]), 0.1), torus(major: 0.6, minor: 0.12).rotate_z(60deg).translate([0, 0.3, 0]), 0.1)", "steps = 12; max_distance = 1.2;"),
    ];
    let dir = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for (name, shape, settings) in shapes {
        let text =
            format!("let s = {shape};\n\natlas skin on s {{\n    {settings}\n}}\n\nrender s;\n");
        let path = dir.path().join(format!("{name}.sdf"));
        std::fs::write(&path, &text).unwrap();
        let (reported, took) = place_all(&path, &["skin".to_string()], &[]);
        let written = std::fs::read_to_string(&path).unwrap();
        let (auto, _) = measure(&written, dir.path(), None);
        let def = &sdfc::driver::check(&written, Some(dir.path()))
            .program
            .atlases[0];
        let a = &auto[0];
        let whole = stretch_where_all(a, &[a]);
        eprintln!(
            "{name}: {} seeds, {} merges, {:.2} % (reported {:.2} %), stretch {:.3} / {:.3}, {:.1} s",
            def.seeds.len(), def.merges.len(), 100.0 * a.coverage, 100.0 * reported[0], whole.0, whole.1, took[0],
        );
        if a.coverage < 0.995
            || (a.coverage - reported[0]).abs() > 0.003
            || whole.1 > sdfc::uv::seeds::DEFAULT_MAX_STRETCH + STRETCH_SLACK
        {
            failures.push(name);
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}
