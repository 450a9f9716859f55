//! The multi-scale atlas pass (`codegen::coarse`, `gpu::coarse`) against the per-pixel
//! walk at the same settings: the same module drawn with the pass and without it
//! (`Renderer::set_multiscale`). The colour must agree to 45 dB PSNR on every example
//! with atlases; where a pixel's uv was rebuilt, the atlas AOV's uv must agree with the
//! walk's to a small fraction of the atlas's reach; and the pass must rebuild most of a
//! smooth chart. GPU tests skip loudly without an adapter unless SDFC_REQUIRE_GPU=1.

use sdfc::codegen::Options;
use sdfc::driver;
use sdfc::gpu::{gpu_for_tests, Frame, Gpu, Renderer, ViewMode};
use sdfc::view::View;
use std::path::Path;

use crate::common;

/// The share of rebuilt pixels, the rebuilt uv's error against the walk (99th
/// percentile and largest, as fractions of the reach) and the colour PSNR.
struct Agreement {
    rebuilt: f64,
    p99: f64,
    worst: f64,
    psnr: f64,
}

fn frame(gpu: &Gpu, r: &Renderer, view: &View, mode: ViewMode, pass: bool) -> Frame {
    r.set_multiscale(pass);
    r.frames(gpu, view, mode, 0, 1).unwrap().0
}

fn agreement(gpu: &Gpu, example: &str, (w, h): (u32, u32)) -> Agreement {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(example);
    let source = std::fs::read_to_string(&path).unwrap();
    let base = path.parent().unwrap();
    let a = driver::check(&source, Some(base));
    assert!(a.diagnostics.is_empty(), "{example}: {:?}", a.diagnostics);
    let options = Options {
        multiscale: true,
        ..Default::default()
    };
    let module = driver::compile(&a, &options).unwrap().module;
    assert!(module.coarse_slots > 0, "{example} reads an atlas");
    let reach = a.atlases[0].as_ref().unwrap().params.max_distance;
    let r = Renderer::new(gpu, &module, base).unwrap();
    assert!(r.has_multiscale());
    let mut view = common::scene_view(&a, (w, h));
    let walked = frame(gpu, &r, &view, ViewMode::Walked, true);
    assert!(walked.timings.coarse_samples > 0);
    view.atlas_aov = true;
    let with = frame(gpu, &r, &view, ViewMode::Color, true);
    let without = frame(gpu, &r, &view, ViewMode::Color, false);
    assert_eq!(without.timings.coarse_samples, 0);
    let mut errors = Vec::new();
    let mut read = 0usize;
    for i in 0..(w * h) as usize {
        let (walks, rebuilt) = (walked.normal[i][3], walked.atlas[i][0]);
        if walks + rebuilt == 0.0 {
            continue;
        }
        read += 1;
        if walks > 0.0 {
            continue;
        }
        let (u, v) = (with.atlas[i], without.atlas[i]);
        if v[3] != 0.0 {
            continue;
        }
        assert_eq!(
            u[3], 0.0,
            "{example}: pixel {i} rebuilt from failed samples"
        );
        let e = ((u[0] - v[0]) as f64).hypot((u[1] - v[1]) as f64) / reach;
        errors.push(e);
    }
    errors.sort_by(f64::total_cmp);
    let at = |q: f64| errors[((errors.len() - 1) as f64 * q) as usize];
    let out = Agreement {
        rebuilt: errors.len() as f64 / read.max(1) as f64,
        p99: if errors.is_empty() { 0.0 } else { at(0.99) },
        worst: errors.last().copied().unwrap_or(0.0),
        psnr: common::psnr(&with.color, &without.color),
    };
    eprintln!(
        "{example} at {w}x{h}: {:.1} % of textured pixels rebuilt, uv error p99 {:.2e}, max {:.2e} of the reach, colour {:.1} dB",
        100.0 * out.rebuilt,
        out.p99,
        out.worst,
        out.psnr
    );
    out
}

/// Every example with atlases, with the pass and without: 45 dB, and the rebuilt uv
/// within 1e-3 of the reach everywhere and 5e-4 at the 99th percentile (measured:
/// 1.0–3.2e-4 and up to 8.7e-4, the affine fit's blindness to curvature).
fn every_example(gpu: &Gpu) {
    for example in [
        "sphere.sdf",
        "capsule.sdf",
        "plate.sdf",
        "robot.sdf",
        "normal_map.sdf",
        "textured_csg.sdf",
    ] {
        let a = agreement(gpu, example, (320, 240));
        assert!(a.psnr >= 45.0, "{example}: {:.1} dB", a.psnr);
        assert!(a.worst < 1e-3, "{example}: worst {:.2e}", a.worst);
        assert!(a.p99 < 5e-4, "{example}: p99 {:.2e}", a.p99);
        // The sphere's one chart is smooth: most of it is rebuilt.
        if example == "sphere.sdf" {
            assert!(a.rebuilt > 0.5, "{example}: {:.2}", a.rebuilt);
        }
    }
}

#[test]
fn the_pass_draws_every_example_as_the_per_pixel_walk_does() {
    let Some(gpu) = gpu_for_tests() else { return };
    every_example(&gpu);
}

/// The same on llvmpipe's GL (a writable storage buffer in the fragment stage), uv
/// bounds included: its AOVs are exact there too (rgba32uint bits, `codegen::aov`;
/// as rgba16float they rounded uv in the tens past the bounds, and this test held only
/// the colour).
#[test]
fn the_pass_draws_every_example_as_the_per_pixel_walk_does_on_gl() {
    let Some(gpu) = common::gl_for_tests() else {
        return;
    };
    every_example(&gpu);
}

/// The pass changes nothing it is not asked for: without `Options::multiscale`, or where
/// no material reads an atlas, the module is the same; with it, the module has the
/// `coarse` binding and the `cs_coarse` entry point, and materials call the rebuild.
#[test]
fn the_pass_is_in_a_module_only_where_asked_and_used() {
    let textured = "let b = sphere(1);\natlas a on b { seed s = [0, 0, 1]; }\nmaterial m { color = checker(a.uv, 4); }\nrender b.paint(m) {}\n";
    let plain = "let b = sphere(1);\nmaterial m { color = [1, 0, 0]; }\nrender b.paint(m) {}\n";
    let build = |src: &str, multiscale: bool| {
        let a = driver::check(src, None);
        assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
        let o = Options {
            multiscale,
            ..Default::default()
        };
        driver::compile(&a, &o).unwrap().module
    };
    let on = build(textured, true);
    let off = build(textured, false);
    assert_eq!(on.coarse_slots, 1);
    assert_eq!(off.coarse_slots, 0);
    assert!(on.wgsl.contains("fn cs_coarse(") && on.wgsl.contains("atlas_0_pixel(p, 1)"));
    assert!(!off.wgsl.contains("cs_coarse") && !off.wgsl.contains("coarse_rebuild"));
    let coarse = on
        .manifest
        .bindings
        .iter()
        .find(|b| b.name == "coarse")
        .unwrap();
    assert!(coarse.used_by.contains(&"cs_coarse") && coarse.used_by.contains(&"fs_main"));
    assert!(on
        .manifest
        .entry_points
        .iter()
        .any(|e| e.name == "cs_coarse"));
    assert!(!off
        .manifest
        .entry_points
        .iter()
        .any(|e| e.name == "cs_coarse"));
    assert!(!off.manifest.bindings.iter().any(|b| b.name == "coarse"));
    assert_eq!(build(plain, true).wgsl, build(plain, false).wgsl);
}

/// The coarse grid covers the frame: its last column and row reach the last pixel, and
/// the buffer holds one record per sample.
#[test]
fn the_coarse_grid_covers_every_pixel() {
    use sdfc::codegen::coarse::{buffer_bytes, grid, STEP};
    for (w, h) in [(1, 1), (4, 4), (5, 3), (320, 240), (641, 479)] {
        let (cols, rows) = grid(w, h);
        assert!(
            (cols - 1) * STEP >= w - 1 && (cols.max(2) - 2) * STEP < w.max(1),
            "{w}"
        );
        assert!(
            (rows - 1) * STEP >= h - 1 && (rows.max(2) - 2) * STEP < h.max(1),
            "{h}"
        );
        assert_eq!(buffer_bytes(w, h, 2), cols as u64 * rows as u64 * 9 * 16);
    }
}

/// An example checked, and its renderer with the multi-scale pass.
fn example_with_pass(gpu: &Gpu, example: &str) -> (driver::Analysis, Renderer) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(example);
    let source = std::fs::read_to_string(&path).unwrap();
    let a = driver::check(&source, path.parent());
    let options = Options {
        multiscale: true,
        ..Default::default()
    };
    let module = driver::compile(&a, &options).unwrap().module;
    let r = Renderer::new(gpu, &module, path.parent().unwrap()).unwrap();
    (a, r)
}

/// The GPU's rebuild against the f64 reference (`reference::coarse::rebuild`): the
/// example drawn with the pass, its coarse samples walked again on the CPU at the hits
/// the frame shows there, and every pixel rebuilt from them in f64 under the rule the
/// module was generated with (across the atlas's merges, or within one seed). Near the
/// fit's tolerance the f32 and f64 walks may decide differently, so the test asks that
/// most of the GPU's rebuilt pixels are the CPU's too, and that where both rebuild the
/// uv agree. Returns the pixels the GPU rebuilt, and those of them whose corners' nearest
/// seeds (in f64) were not one seed.
fn against_the_f64_reference(gpu: &Gpu, example: &str) -> (usize, usize) {
    use sdfc::reference::coarse::{
        across_merges, atlas_merged_bits, rebuild, same_seed, Corner, STEP, TOLERANCE,
    };
    let (a, r) = example_with_pass(gpu, example);
    let atlas = a.atlases[0].as_ref().unwrap();
    let bits = atlas_merged_bits(atlas);
    let merged: Box<dyn Fn(usize, usize) -> bool> = match &bits {
        Some(b) => Box::new(across_merges(b)),
        None => Box::new(same_seed),
    };
    let reach = atlas.params.max_distance;
    let (w, h) = (160u32, 120u32);
    let mut view = common::scene_view(&a, (w, h));
    let walked = frame(gpu, &r, &view, ViewMode::Walked, true);
    view.atlas_aov = true;
    let shown = frame(gpu, &r, &view, ViewMode::Color, true);
    let at = |x: u32, y: u32| (y * w + x) as usize;
    let corner = |i: u32, j: u32| {
        let (x, y) = ((i * STEP).min(w - 1), (j * STEP).min(h - 1));
        let q = shown.position[at(x, y)];
        let p = glam::DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64);
        Corner {
            position: p,
            material: if q[3] < 0.0 { -1 } else { 1 },
            sample: atlas.sample_at(p),
        }
    };
    let cols = (w + STEP - 2) / STEP + 1;
    let rows = (h + STEP - 2) / STEP + 1;
    let grid: Vec<Corner> = (0..rows)
        .flat_map(|j| (0..cols).map(move |i| (i, j)))
        .map(|(i, j)| corner(i, j))
        .collect();
    let (mut gpu_rebuilt, mut both, mut across, mut worst) = (0usize, 0usize, 0usize, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let i = at(x, y);
            let rebuilt = walked.normal[i][3] == 0.0 && walked.atlas[i][0] > 0.0;
            if !rebuilt || (x % STEP == 0 && y % STEP == 0) {
                continue;
            }
            gpu_rebuilt += 1;
            let (i0, j0) = ((x / STEP).min(cols - 1), (y / STEP).min(rows - 1));
            let (i1, j1) = ((i0 + 1).min(cols - 1), (j0 + 1).min(rows - 1));
            let c = |i: u32, j: u32| grid[(j * cols + i) as usize].clone();
            let corners = [c(i0, j0), c(i1, j0), c(i0, j1), c(i1, j1)];
            if corners
                .iter()
                .any(|k| k.sample.seed != corners[0].sample.seed)
            {
                across += 1;
            }
            let q = shown.position[i];
            let p = glam::DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64);
            if let Some(s) = rebuild(&corners, p, 1, TOLERANCE * reach, &*merged) {
                both += 1;
                let g = shown.atlas[i];
                let e = (s.uv - glam::DVec2::new(g[0] as f64, g[1] as f64)).length() / reach;
                worst = worst.max(e);
            }
        }
    }
    eprintln!(
        "{example}: GPU rebuilt {gpu_rebuilt} pixels ({across} between seeds); the f64 reference rebuilt {both} of them; largest uv difference {worst:.2e} of the reach"
    );
    assert!(gpu_rebuilt > 500, "{gpu_rebuilt}");
    assert!(
        both as f64 >= 0.8 * gpu_rebuilt as f64,
        "{both} of {gpu_rebuilt}"
    );
    assert!(worst < 1e-3, "{worst:.2e}");
    (gpu_rebuilt, across)
}

/// On the sphere (one seed; measured: all 810 of the GPU's rebuilt pixels are the CPU's,
/// within 2.3e-7 of the reach).
#[test]
fn the_rebuild_agrees_with_the_f64_reference() {
    let Some(gpu) = gpu_for_tests() else { return };
    let (_, across) = against_the_f64_reference(&gpu, "sphere.sdf");
    assert_eq!(across, 0);
}

/// On `plate.sdf`, whose 64 seeds are merged with their grid neighbours, the rebuild
/// crosses the merged frontiers (Alg. 2 blends there), as the f64 reference's does.
#[test]
fn across_merged_frontiers_the_rebuild_agrees_with_the_f64_reference() {
    let Some(gpu) = gpu_for_tests() else { return };
    let (rebuilt, across) = against_the_f64_reference(&gpu, "plate.sdf");
    assert!(across * 20 > rebuilt, "{across} of {rebuilt}");
}

/// Against the truth: on the sphere, whose log map is known in closed form, the uv
/// the pass rebuilds is as close to the exact log map as the per-pixel walk's own uv
/// (measured at 320 × 240 on lavapipe, over the 15,302 rebuilt pixels, of the reach:
/// median 5.1e-5 against 6.4e-5, p99 1.65e-4 against 1.73e-4, max 2.4e-4 both). The
/// rebuild's distance from the walk (p99 1.0e-4) is the size of the walk's own error,
/// which varies from pixel to pixel where the fit is smooth.
#[test]
fn on_the_sphere_the_rebuilt_uv_is_as_close_to_the_exact_log_map_as_the_walk() {
    use glam::{DVec2, DVec3};
    let Some(gpu) = gpu_for_tests() else { return };
    let (a, r) = example_with_pass(&gpu, "sphere.sdf");
    let atlas = a.atlases[0].as_ref().unwrap();
    let reach = atlas.params.max_distance;
    let seed = atlas.seeds[0].seed;
    // The unit sphere about the origin: the exact log map at the seed (notes).
    let exact = |x: DVec3| {
        let (m0, m) = (seed.p, x.normalize());
        let d = m0.dot(m).clamp(-1.0, 1.0).acos();
        let w = m - m0 * m0.dot(m);
        DVec2::new(w.dot(seed.e1), w.dot(seed.e2)) * (d / w.length())
    };
    let mut view = common::scene_view(&a, (320, 240));
    let walked = frame(&gpu, &r, &view, ViewMode::Walked, true);
    view.atlas_aov = true;
    let with = frame(&gpu, &r, &view, ViewMode::Color, true);
    let without = frame(&gpu, &r, &view, ViewMode::Color, false);
    let (mut walk, mut rebuilt) = (Vec::new(), Vec::new());
    for i in 0..with.atlas.len() {
        let is_rebuilt = walked.normal[i][3] == 0.0 && walked.atlas[i][0] > 0.0;
        if !is_rebuilt || without.atlas[i][3] != 0.0 {
            continue;
        }
        let q = with.position[i];
        let truth = exact(DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64));
        let err = |uv: [f32; 4]| (DVec2::new(uv[0] as f64, uv[1] as f64) - truth).length() / reach;
        walk.push(err(without.atlas[i]));
        rebuilt.push(err(with.atlas[i]));
    }
    assert!(rebuilt.len() > 5000, "{} rebuilt", rebuilt.len());
    let stats = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let at = |q: f64| v[((v.len() - 1) as f64 * q) as usize];
        (at(0.5), at(0.99), at(1.0))
    };
    let (w50, w99, wmax) = stats(&mut walk);
    let (r50, r99, rmax) = stats(&mut rebuilt);
    eprintln!(
        "{} rebuilt pixels, uv against the exact log map (of the reach): per-pixel walk p50 {w50:.2e} p99 {w99:.2e} max {wmax:.2e}; rebuilt p50 {r50:.2e} p99 {r99:.2e} max {rmax:.2e}",
        rebuilt.len()
    );
    assert!(
        r50 <= 1.1 * w50,
        "median: rebuilt {r50:.2e}, walk {w50:.2e}"
    );
    assert!(r99 <= 1.1 * w99, "p99: rebuilt {r99:.2e}, walk {w99:.2e}");
    assert!(
        rmax <= 1.25 * wmax,
        "max: rebuilt {rmax:.2e}, walk {wmax:.2e}"
    );
}

/// The table of merged seeds: symmetric, with the diagonal set, two words a row past 32
/// seeds, and only within its limit.
#[test]
fn the_table_of_merged_seeds_holds_exactly_the_merges() {
    use sdfc::reference::coarse::{merged_bits, MERGED_TABLE_SEEDS};
    let edges = [(0, 1), (33, 2), (39, 38)];
    let bits = merged_bits(40, edges).unwrap();
    assert_eq!(bits.row, 2);
    assert_eq!(bits.words.len(), 80);
    for i in 0..40 {
        for j in 0..40 {
            let want = i == j
                || edges
                    .iter()
                    .any(|&(a, b)| (a, b) == (i, j) || (b, a) == (i, j));
            assert_eq!(bits.get(i, j), want, "{i} {j}");
        }
    }
    assert!(merged_bits(1, []).is_none());
    assert!(merged_bits(MERGED_TABLE_SEEDS, []).is_some());
    assert!(merged_bits(MERGED_TABLE_SEEDS + 1, []).is_none());
}

/// The rule across merges, on four corners whose uv is affine in their position (so
/// the fit holds): corners of two seeds rebuild only where those are merged, three seeds
/// only where every two of them are, and the sample takes the heaviest corner's seed.
#[test]
fn the_rebuild_crosses_a_frontier_only_between_merged_seeds() {
    use glam::{DMat3, DVec2, DVec3};
    use sdfc::reference::coarse::{across_merges, merged_bits, rebuild, same_seed, Corner};
    use sdfc::uv::{Sample, Status};
    let corners = |seeds: [usize; 4]| -> [Corner; 4] {
        let at = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
        std::array::from_fn(|k| {
            let (x, y) = at[k];
            Corner {
                position: DVec3::new(x, y, 0.0),
                material: 1,
                sample: Sample {
                    status: Status::Ok,
                    uv: DVec2::new(0.5 + 0.3 * x - 0.1 * y, 0.2 + 0.4 * y),
                    distance: 1.0,
                    transport: DMat3::IDENTITY,
                    seed: Some(seeds[k]),
                    weight: 1.0,
                    tangent: DVec3::X,
                    bitangent: DVec3::Y,
                },
            }
        })
    };
    let p = DVec3::new(0.9, 0.8, 0.0);
    let two = corners([0, 0, 1, 1]);
    let s = rebuild(&two, p, 1, 1e-9, &same_seed);
    assert!(s.is_none());
    let unmerged = merged_bits(3, [(1, 2)]).unwrap();
    assert!(rebuild(&two, p, 1, 1e-9, &across_merges(&unmerged)).is_none());
    let merged = merged_bits(3, [(0, 1), (1, 2)]).unwrap();
    let s = rebuild(&two, p, 1, 1e-9, &across_merges(&merged)).unwrap();
    assert_eq!(s.seed, Some(1), "the corner at (1, 1) weighs most");
    assert!((s.uv - DVec2::new(0.5 + 0.27 - 0.08, 0.2 + 0.32)).length() < 1e-12);
    // Three seeds: 0 and 2 are not merged.
    let three = corners([0, 1, 2, 2]);
    assert!(rebuild(&three, p, 1, 1e-9, &across_merges(&merged)).is_none());
    let all = merged_bits(3, [(0, 1), (1, 2), (0, 2)]).unwrap();
    assert!(rebuild(&three, p, 1, 1e-9, &across_merges(&all)).is_some());
    // One seed needs no merge.
    assert!(rebuild(&corners([2; 4]), p, 1, 1e-9, &same_seed).is_some());
}

/// The module carries an atlas's table of merged seeds in its `tables` words, and its
/// materials rebuild across merges only where no material reads the atlas's `seed` or
/// `transport` (which change at a frontier) and the shape does not move.
#[test]
fn the_module_carries_the_table_of_merged_seeds_where_the_rule_may_cross() {
    use sdfc::reference::coarse::atlas_merged_bits;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/plate.sdf");
    let source = std::fs::read_to_string(&path).unwrap();
    let options = Options {
        multiscale: true,
        ..Default::default()
    };
    let compile = |src: &str| {
        let a = driver::check(src, path.parent());
        assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
        let m = driver::compile(&a, &options).unwrap().module;
        (a, m)
    };
    let (a, module) = compile(&source);
    let bits = atlas_merged_bits(a.atlases[0].as_ref().unwrap()).unwrap();
    assert_eq!(bits.row, 2);
    let call = regex_free_call(&module.wgsl);
    let (at, row) = call.expect("atlas_0_pixel calls coarse_rebuild");
    assert_eq!(row, 2);
    let words = &module.manifest.tables[at as usize..at as usize + bits.words.len()];
    assert_eq!(words, &bits.words[..]);
    // A material that reads the seed keeps to one seed's region.
    let seeded = source.replace("roughness = 0.7;", "roughness = 0.5 + 0.001 * tiles.seed;");
    assert_ne!(seeded, source);
    let (_, module) = compile(&seeded);
    assert_eq!(regex_free_call(&module.wgsl), Some((0, 0)));
}

/// The last two arguments (the table's first word and its row's words) of the
/// `coarse_rebuild` call in `atlas_0_pixel`.
fn regex_free_call(wgsl: &str) -> Option<(u32, u32)> {
    let body = &wgsl[wgsl.find("fn atlas_0_pixel(")?..];
    let call = &body[body.find("coarse_rebuild(")?..];
    let args = &call["coarse_rebuild(".len()..call.find(");")?];
    let mut last = args
        .rsplit(", ")
        .map(|a| a.trim_end_matches('u').parse::<u32>().ok());
    let row = last.next()??;
    let at = last.next()??;
    Some((at, row))
}
