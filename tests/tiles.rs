//! Per-tile culling (`codegen::tiles`, `gpu::tiles`). On the CPU, in f64: every leaf a
//! pixel's ray comes within the trace's margins of (a slab test against its grown box)
//! is listed in the pixel's tile, and every leaf a shadow ray meets in the ray's light
//! cell, from cameras outside and inside the scene; the per-tile limit sends a crowded
//! tile to the whole tree. On the GPU: the same scenes traced with and without tiles
//! hit the same pixels, with the same normals, and shade alike but for shadow rays
//! that graze a sphere.

use glam::DVec3;
use sdfc::bench::{city, scattered};
use sdfc::codegen::Options;
use sdfc::driver;
use sdfc::gpu::{gpu_for_tests, tiles, Renderer, ViewMode};
use sdfc::view::View;

use crate::common;
use common::Rng;

fn analysis(src: &str) -> driver::Analysis {
    let a = driver::check(src, None);
    assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
    a
}

fn module(a: &driver::Analysis, tiles: bool) -> sdfc::codegen::Module {
    driver::compile(
        a,
        &Options {
            tiles,
            ..Default::default()
        },
    )
    .unwrap()
    .module
}

use common::scene_view as view_of;

/// The ray parameter where the ray meets box [lo, hi], if it does at t ≥ 0.
fn slab(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-300 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1).then_some(t0)
}

/// Every pixel's ray: each leaf whose box, grown by the margins the trace needs (its
/// hit tolerance at the box's farthest point and twice the normal's tap), the ray
/// meets is listed in the pixel's tile (or the tile walks the whole group).
fn screen_lists_are_conservative(a: &driver::Analysis, view: &View) -> usize {
    let m = module(a, true);
    let tiling = m.tiling.as_ref().expect("the scene has traced groups");
    let binned = tiles::bin(tiling, view);
    let c = &view.camera;
    let (w, h) = (view.width as f64, view.height as f64);
    let tan = (c.fov * 0.5).tan();
    let mut met = 0;
    for y in 0..view.height {
        for x in 0..view.width {
            let ndc = (
                2.0 * (x as f64 + 0.5) / w - 1.0,
                1.0 - 2.0 * (y as f64 + 0.5) / h,
            );
            let d = (c.forward + ndc.0 * (w / h) * tan * c.right + ndc.1 * tan * c.up).normalize();
            let tile = binned.tile_of(x, y);
            for (slot, g) in tiling.groups.iter().enumerate() {
                let Some(list) = binned.list(tile, slot as u32) else {
                    continue;
                };
                let entries = binned.boxes(tile, slot as u32).unwrap();
                for (b, record) in g.boxes.iter().zip(&g.records) {
                    let far = (b.min - c.eye).abs().max((b.max - c.eye).abs()).length();
                    let margin = view.epsilon * far.max(1.0) + 2.0 * 3f64.sqrt() * tiling.tap;
                    if slab(c.eye, d, b.min - margin, b.max + margin).is_some() {
                        met += 1;
                        let Ok(at) = list.binary_search(record) else {
                            panic!("pixel ({x}, {y}) meets record {record} of group {slot}, unlisted in tile {tile}");
                        };
                        // The shader's per-ray test (scene_cull) keeps it: the ray meets
                        // the box the entry holds, in single precision.
                        let e = entries[at].1.map(f64::from);
                        let (lo, hi) = (DVec3::new(e[0], e[1], e[2]), DVec3::new(e[3], e[4], e[5]));
                        assert!(
                            slab(c.eye, d, lo, hi).is_some(),
                            "pixel ({x}, {y}) meets record {record}, but not its entry's box"
                        );
                    }
                }
                assert!(list.windows(2).all(|p| p[0] < p[1]), "lists ascend");
            }
        }
    }
    met
}

#[test]
fn every_leaf_a_pixels_ray_can_meet_is_in_its_tile() {
    let a = analysis(&scattered(400, 0));
    let mut view = view_of(&a, (96, 72));
    let met = screen_lists_are_conservative(&a, &view);
    assert!(met > 500, "the rays meet leaves ({met})");
    // From inside the cloud, boxes reach behind the eye and across the screen's edges.
    view.camera =
        sdfc::view::Camera::look_at(DVec3::new(0.3, 0.2, 0.1), DVec3::new(3.0, -1.0, 2.0), 1.2);
    let met = screen_lists_are_conservative(&a, &view);
    assert!(met > 500, "the rays meet leaves ({met})");
    // A city: a ground (code) beside the group, most rays hitting.
    let a = analysis(&city(300, 0));
    let view = view_of(&a, (80, 60));
    screen_lists_are_conservative(&a, &view);
}

#[test]
fn every_leaf_a_shadow_ray_can_meet_is_in_its_cell() {
    let a = analysis(&scattered(400, 0));
    let view = view_of(&a, (64, 48));
    let m = module(&a, true);
    let tiling = m.tiling.as_ref().unwrap();
    let binned = tiles::bin(tiling, &view);
    let l = view.sun.direction.normalize();
    let first = binned.across * binned.down;
    let threshold = 1e-4 * tiling.tap * 1e3;
    let mut rng = Rng(7);
    let (mut met, mut off) = (0, 0);
    for _ in 0..40000 {
        let p = DVec3::new(rng.unit(), rng.unit(), rng.unit()) * 14.0 - 7.0;
        let cell = binned.light.cell_of(p, first);
        if cell == first + binned.light.across * binned.light.down {
            off += 1;
        }
        let g = &tiling.groups[0];
        let list = binned.list(cell, 0).expect("no cell is crowded here");
        let entries = binned.boxes(cell, 0).unwrap();
        for (b, record) in g.boxes.iter().zip(&g.records) {
            if slab(p, l, b.min - threshold, b.max + threshold).is_some() {
                met += 1;
                let Ok(at) = list.binary_search(record) else {
                    panic!("a shadow ray from {p} meets record {record}, unlisted in cell {cell}");
                };
                let e = entries[at].1.map(f64::from);
                let (lo, hi) = (DVec3::new(e[0], e[1], e[2]), DVec3::new(e[3], e[4], e[5]));
                assert!(
                    slab(p, l, lo, hi).is_some(),
                    "a shadow ray from {p} meets record {record}, but not its entry's box"
                );
            }
        }
    }
    assert!(
        met > 1000 && off > 100,
        "rays meet leaves ({met}) and leave the grid ({off})"
    );
}

#[test]
fn a_crowded_tile_walks_the_whole_group() {
    // 300 spheres about one point fill every tile past the per-tile limit.
    let mut src = String::new();
    for part in 0..6 {
        src.push_str(&format!("let part{part} =\n"));
        for i in 0..50 {
            let x = ((part * 50 + i) % 7) as f64 * 0.01;
            let sep = if i + 1 < 50 { " |" } else { ";" };
            src.push_str(&format!("    sphere(1).translate([{x}, 0, 0]){sep}\n"));
        }
    }
    src.push_str("let heap = part0 | part1 | part2 | part3 | part4 | part5;\n");
    src.push_str(
        "render heap {\n    camera = look_at(eye: [0, 0, 4], target: [0, 0, 0], fov: 60deg);\n}\n",
    );
    let a = analysis(&src);
    let view = view_of(&a, (32, 32));
    let m = module(&a, true);
    let binned = tiles::bin(m.tiling.as_ref().unwrap(), &view);
    let centre = binned.tile_of(16, 16);
    assert!(300 > tiles::MAX_PER_TILE);
    assert_eq!(
        binned.list(centre, 0),
        None,
        "past the limit: the whole tree"
    );
    assert!(binned.whole > 0);
    // The shader takes that path (the whole scene for the trace, its normal and the
    // shadow ray): the same picture as without tiles.
    let Some(gpu) = gpu_for_tests() else { return };
    let [a, b] = both(&gpu, &src, (32, 32), ViewMode::Normal);
    assert!(a.position.iter().filter(|p| p[3] >= 0.0).count() > 100);
    assert!(common::worst_byte_difference(&a.color, &b.color) <= 6);
    let [a, b] = both(&gpu, &src, (32, 32), ViewMode::Color);
    assert!(common::worst_byte_difference(&a.color, &b.color) <= 6);
    // The first crowded frame builds the crowded pipeline, and its timings say so; the
    // next frame finds it built. (`render --timings` prints the line.)
    assert!(
        a.timings.pipeline_built.is_none(),
        "no tiles, no crowded pipeline"
    );
    let tiled = Renderer::new(&gpu, &m, std::path::Path::new(".")).unwrap();
    let first = tiled.frames(&gpu, &view, ViewMode::Color, 0, 1).unwrap().0;
    let second = tiled.frames(&gpu, &view, ViewMode::Color, 0, 1).unwrap().0;
    assert!(first.timings.pipeline_built.is_some());
    assert!(second.timings.pipeline_built.is_none());
}

/// 400 scattered spheres over a floor that is no leaf of their group (a smooth union).
fn cloud_over_a_floor() -> String {
    scattered(400, 0).replace(
        "render cloud.paint(checkered)",
        "render (cloud | smooth_union(box([20, 0.1, 20]), sphere(0.5), 0.3).translate([0, -6, 0])).paint(checkered)",
    )
}

#[test]
fn a_ray_skips_the_listed_leaves_it_misses() {
    // The module's trace reads, per ray, only the entries whose boxes it meets, and
    // with nothing but groups in the target, only the span between them.
    let a = analysis(&scattered(400, 0));
    let wgsl = module(&a, true).wgsl;
    for f in [
        "fn scene_cull(",
        "fn scene_march_whole(",
        "fn scene_shadow_march_whole(",
    ] {
        assert!(wgsl.contains(f), "{f}");
    }
    assert!(
        wgsl.contains("    return scene_span;"),
        "the span of a cloud"
    );
    // With a floor as code beside the group, the whole ray stays open.
    let floor = module(&analysis(&cloud_over_a_floor()), true).wgsl;
    assert!(floor.contains("fn scene_cull("));
    assert!(floor.contains("    return vec2<f32>(0.0, far);\n}"));
    assert!(!floor.contains("    return scene_span;"));
    // The listed walker never calls the tree walk: the crowded tile's rays do instead.
    let walker = &wgsl[wgsl.find("fn group_tiled_").unwrap()..];
    let walker = &walker[..walker.find("\n}\n").unwrap()];
    assert!(!walker.contains("group_walk_"), "{walker}");
}

#[test]
fn a_module_has_tiles_only_when_asked_and_it_has_a_traced_group() {
    let a = analysis(&scattered(100, 0));
    let tiled = module(&a, true);
    assert!(tiled.manifest.bindings.iter().any(|b| b.name == "tiles"));
    assert!(tiled.wgsl.contains("fn group_tiled_"));
    let plain = module(&a, false);
    assert!(plain.tiling.is_none());
    assert!(!plain.manifest.bindings.iter().any(|b| b.name == "tiles"));
    // No group reached through hard unions and paints: the module is the same.
    let small = analysis(&scattered(12, 0));
    assert_eq!(module(&small, true).wgsl, module(&small, false).wgsl);
    // A group under a smooth union is not traced through tiles.
    let mut src = String::from("let cloud =\n");
    for i in 0..20 {
        let sep = if i + 1 < 20 { " |" } else { ";" };
        src.push_str(&format!(
            "    sphere(0.1).translate([{}, 0, 0]){sep}\n",
            i as f64 * 0.3
        ));
    }
    src.push_str("let both = smooth_union(cloud, box([1, 0.1, 1]), 0.2);\nrender both {}\n");
    let a = analysis(&src);
    assert!(module(&a, true).tiling.is_none());
}

/// Both renders of `src` at `size` in view `mode`: (without tiles, with them).
fn both(
    gpu: &sdfc::gpu::Gpu,
    src: &str,
    size: (u32, u32),
    mode: ViewMode,
) -> [sdfc::gpu::Frame; 2] {
    let a = analysis(src);
    let view = view_of(&a, size);
    [false, true].map(|t| {
        let r = Renderer::new(gpu, &module(&a, t), std::path::Path::new(".")).unwrap();
        r.frames(gpu, &view, mode, 0, 1).unwrap().0
    })
}

#[test]
fn tiles_trace_the_same_surface_on_the_gpu() {
    let Some(gpu) = gpu_for_tests() else { return };
    same_surface(&gpu);
}

#[test]
fn tiles_trace_the_same_surface_on_gl() {
    // The `tiles` storage buffer in a fragment shader, on llvmpipe's GL as well.
    let Some(gpu) = common::gl_for_tests() else {
        return;
    };
    same_surface(&gpu);
}

/// How many (tile, group) lists of `src` at `size` hold 1 to 32 leaves, 33 to 64 (the
/// mask's second word, `codegen::tiles::CULLED`), and more (read at every step).
fn list_lengths(src: &str, size: (u32, u32)) -> [usize; 3] {
    let a = analysis(src);
    let m = module(&a, true);
    let tiling = m.tiling.as_ref().expect("the scene has traced groups");
    let binned = tiles::bin(tiling, &view_of(&a, size));
    let mut bands = [0; 3];
    for tile in 0..binned.across * binned.down {
        for slot in 0..tiling.groups.len() as u32 {
            let n = binned.list(tile, slot).map_or(0, |l| l.len());
            if n > 0 {
                bands[(n > 32) as usize + (n > 64) as usize] += 1;
            }
        }
    }
    bands
}

/// The GPU comparison's scenes (below) read lists in both words of the per-ray mask
/// and past it: a test of the mask that cannot miss its second word.
#[test]
fn the_compared_scenes_list_past_each_word_of_the_mask() {
    assert_eq!(sdfc::codegen::tiles::CULLED, 64);
    let mut bands = [0; 3];
    for (name, src) in compared_scenes() {
        let b = list_lengths(&src, (96, 72));
        eprintln!("{name}: lists of 1-32, 33-64, over 64 leaves: {b:?}");
        (0..3).for_each(|k| bands[k] += b[k]);
    }
    assert!(bands.iter().all(|&n| n > 0), "{bands:?}");
}

/// `n` small spheres (radius 0.06 to 0.14) through a cube of side 2.4, in unions of
/// 20, seen from 6 units: a tile's lists run from a few leaves to past the per-ray mask.
fn dense_cloud(n: usize) -> String {
    let mut rng = Rng(7);
    let mut src = String::new();
    let groups = n.div_ceil(20);
    for g in 0..groups {
        src.push_str(&format!("let g{g} =\n"));
        let end = ((g + 1) * 20).min(n);
        for i in g * 20..end {
            let c = [0; 3].map(|_| 2.4 * rng.unit() - 1.2);
            let r = 0.06 + 0.08 * rng.unit();
            let sep = if i + 1 < end { " |" } else { ";" };
            src.push_str(&format!(
                "    sphere({r:.3}).translate([{:.3}, {:.3}, {:.3}]){sep}\n",
                c[0], c[1], c[2]
            ));
        }
    }
    let names: Vec<String> = (0..groups).map(|g| format!("g{g}")).collect();
    src.push_str(&format!(
        "render ({}) {{\n    camera = look_at(eye: [0, 1, 6], target: [0, 0, 0], fov: 40deg);\n}}\n",
        names.join(" | ")
    ));
    src
}

/// One traced group of 48 leaves through a cube, painted red and blue in turn, the
/// leaves' kinds taken from `kinds` in turn.
fn painted_group(kinds: &[&str]) -> String {
    let mut rng = Rng(11);
    let mut src = String::from(
        "material red {\n    color = [0.8, 0.1, 0.1];\n}\nmaterial blue {\n    color = [0.1, 0.2, 0.9];\n}\nlet cloud =\n",
    );
    for i in 0..48 {
        let c = [0; 3].map(|_| 3.0 * rng.unit() - 1.5);
        let (kind, paint) = (kinds[i % kinds.len()], ["red", "blue"][i % 2]);
        let sep = if i + 1 < 48 { " |" } else { ";" };
        src.push_str(&format!(
            "    {kind}.translate([{:.3}, {:.3}, {:.3}]).paint({paint}){sep}\n",
            c[0], c[1], c[2]
        ));
    }
    src.push_str(
        "render cloud {\n    camera = look_at(eye: [0, 1.5, 6], target: [0, 0, 0], fov: 40deg);\n}\n",
    );
    src
}

const ROUND_BOX: &str = "round_box([0.4, 0.3, 0.35], radius: 0.05)";
const CYLINDER: &str = "cylinder(0.15, 0.4)";
const CAPSULE: &str = "capsule(a: [0, -0.15, 0], b: [0.15, 0.15, 0], radius: 0.1)";
const TURNED_BOX: &str =
    "round_box([0.35, 0.3, 0.2], radius: 0.08).rotate(axis: [1, 1, 0], angle: 35deg)";

#[test]
fn a_rays_first_leaves_are_cached_where_a_group_is_one_unturned_kind() {
    // The cull reads the first leaves a ray meets into registers for a group of one
    // kind, unturned, whose parameters fit four words; the walker starts from them.
    let wgsl = |src: &str| module(&analysis(src), true).wgsl;
    let cached = [
        (
            painted_group(&[ROUND_BOX]),
            "sd_round_box(q, l.params.xyz, l.params.w)",
        ),
        (
            painted_group(&[CYLINDER]),
            "sd_cylinder(q, l.params.x, l.params.y)",
        ),
        (city(300, 0), "sd_sphere(q, l.params.x)"),
    ];
    for (src, call) in cached {
        let w = wgsl(&src);
        assert!(w.contains(call), "{call}");
        assert!(w.contains("scene_skip[0], p, scene_cached_0(p))"));
    }
    // Seven words (a capsule), turned leaves, or two kinds: the loop reads them all.
    for kinds in [&[CAPSULE][..], &[TURNED_BOX], &[ROUND_BOX, CYLINDER]] {
        let w = wgsl(&painted_group(kinds));
        assert!(w.contains("fn group_tiled_"), "{kinds:?}");
        assert!(!w.contains("fn scene_cached_"), "{kinds:?}");
        assert!(w.contains("scene_skip[0], p, vec2<f32>(3.0e38, 0.0))"));
    }
}

/// The scenes traced with and without tiles on the GPU.
fn compared_scenes() -> [(&'static str, String); 6] {
    [
        ("scattered(400)", scattered(400, 0)),
        ("city(300)", city(300, 0)),
        ("scattered(400) over a floor as code", cloud_over_a_floor()),
        ("a dense cloud of 1,200", dense_cloud(1200)),
        ("round boxes, painted (cached)", painted_group(&[ROUND_BOX])),
        (
            "capsules and turned round boxes, painted",
            painted_group(&[CAPSULE, TURNED_BOX]),
        ),
    ]
}

fn same_surface(gpu: &sdfc::gpu::Gpu) {
    for (name, src) in compared_scenes() {
        // Normals: the same hits, the same normals up to where in the hit tolerance
        // each trace stopped.
        let [a, b] = both(gpu, &src, (96, 72), ViewMode::Normal);
        let mut hits = 0;
        for i in 0..a.position.len() {
            let (ha, hb) = (a.position[i][3] >= 0.0, b.position[i][3] >= 0.0);
            assert_eq!(
                ha, hb,
                "{name}: pixel {i} hit {ha} without tiles, {hb} with"
            );
            if ha {
                hits += 1;
                let tol = 2e-3 * a.position[i][3].max(1.0);
                assert!(
                    (a.position[i][3] - b.position[i][3]).abs() < tol,
                    "{name}: depth at {i}"
                );
            }
        }
        assert!(hits > 150, "{name}: {hits} hits");
        let worst = common::worst_byte_difference(&a.color, &b.color);
        assert!(worst <= 6, "{name}: normals differ by {worst}/255");
        // Colours: shadows too. A shadow ray grazing a sphere within its threshold may
        // go either way with other steps: a few pixels.
        let [a, b] = both(gpu, &src, (96, 72), ViewMode::Color);
        let differ = (0..a.color.len() / 4)
            .filter(|&i| (0..3).any(|k| a.color[4 * i + k].abs_diff(b.color[4 * i + k]) > 8))
            .count();
        eprintln!("{name}: {hits} hits, {differ} pixels differ by over 8/255 in colour");
        assert!(
            differ * 100 <= hits,
            "{name}: {differ} of {hits} pixels shade differently"
        );
    }
}

#[test]
fn the_lean_pipeline_form_is_validated_with_the_module() {
    // naga's pipeline-constant pass rejects a constant used on both sides of an early
    // return (ExpressionAlreadyInScope) that the plain module passes: sdfc's validation
    // builds that form too, so the runtime never meets it first.
    let wgsl = "override SCENE_CROWDED: bool = true;
fn f(a: vec3<f32>, b: vec3<f32>) -> mat3x3<f32> {
    let c = dot(a, b);
    let identity = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
    if (c <= -0.999999) {
        return identity;
    }
    let k = cross(a, b);
    let j = mat3x3<f32>(vec3<f32>(0.0, k.z, -k.y), vec3<f32>(-k.z, 0.0, k.x), vec3<f32>(k.y, -k.x, 0.0));
    return mat3x3<f32>(identity[0] + j[0], identity[1] + j[1], identity[2] + j[2]);
}
@compute @workgroup_size(1)
fn main() {
    if (SCENE_CROWDED) {
        let x = f(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0));
    }
}
";
    let e = sdfc::codegen::validate(wgsl)
        .err()
        .expect("the lean form is rejected");
    assert!(e.message.contains("SCENE_CROWDED = false"), "{}", e.message);
    // Without the override, the same module passes.
    let plain = wgsl.replace(
        "override SCENE_CROWDED: bool = true;",
        "const SCENE_CROWDED = true;",
    );
    assert!(sdfc::codegen::validate(&plain).is_ok());
    // Every module with tiles passes in both forms (here with an atlas's walk).
    let a = analysis(&city(300, 1));
    assert!(module(&a, true).wgsl.contains("override SCENE_CROWDED"));
}
