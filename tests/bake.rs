//! The bake (`src/bake`): border identity at every level, seams, the GPU against the
//! CPU reference, and bad input. GPU tests skip loudly without an adapter unless
//! SDFC_REQUIRE_GPU=1. Bakes are small (256² atlases, coarse grids): lavapipe is slow.

use crate::common;

use common::assert_borders_identical;
use glam::DVec3;
use sdfc::bake::charts::side_texel;
use sdfc::bake::pipeline::{self, BakeError, Baked, Options, Quiet, Resolution};
use sdfc::bake::table::ChartsFile;
use sdfc::gpu::gpu_for_tests;
use sdfc::gpu::Gpu;
use sdfc::ir::{eval, Aabb};
use std::path::Path;

fn bake_source(
    gpu: &Gpu,
    source: &str,
    base: &Path,
    options: &Options,
) -> Result<Baked, BakeError> {
    let (analysis, compiled) = common::check_and_compile_loop(source, base);
    let scene = analysis.scene.as_ref().expect("scene");
    let shape = sdfc::driver::pick_shape(scene, None).expect("shape");
    pipeline::bake(
        gpu,
        &compiled.module,
        base,
        analysis.field(shape),
        options,
        &Quiet,
    )
}

/// Every level-0 texel of a bake with its surface point and footprint, in the bake's
/// order (corners, edges, interiors).
fn level0_texels(baked: &Baked) -> (Vec<[f32; 3]>, Vec<[f32; 11]>, Vec<f64>) {
    let inputs = pipeline::sample_points(
        &baked.quads,
        &baked.table,
        baked.levels[0].n,
        &baked.vertex_grid,
    );
    let footprints = inputs
        .corners
        .iter()
        .chain(&inputs.edges)
        .chain(&inputs.interiors)
        .map(|p| p[3] as f64)
        .collect();
    let p = &baked.points;
    let points = p
        .corners
        .iter()
        .chain(&p.edges)
        .chain(&p.interiors)
        .copied()
        .collect();
    let l0 = &baked.levels[0];
    let texels = l0
        .corners
        .iter()
        .chain(&l0.edges)
        .chain(&l0.interiors)
        .copied()
        .collect();
    (points, texels, footprints)
}

fn small(grid: usize) -> Options {
    Options {
        size: 256,
        resolution: Resolution::Cells(grid),
        bounds: None,
        chart_quads: 1,
        ..Options::default()
    }
}

/// A smooth procedural material: colour is a smooth function of position.
const SMOOTH: &str = "
let s = sphere(1) | box([0.6, 0.6, 0.6]).translate([0.8, 0, 0]);
material m {
    color = [0.5 + 0.4 * sin(position.x * 2.0), 0.5 + 0.4 * cos(position.y * 1.5), 0.5 + 0.3 * sin(position.z * 2.5)];
    roughness = 0.3 + 0.2 * position.y;
    metallic = 0.2;
}
render s.paint(m);
";

#[test]
fn borders_are_identical_at_every_level_and_seams_are_no_steeper_than_the_inside() {
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = tempfile::tempdir().unwrap();
    let options = Options {
        size: 512,
        ..small(10)
    };
    let baked = bake_source(&gpu, SMOOTH, dir.path(), &options).expect("bakes");
    let file = ChartsFile::new(&baked.table, &baked.atlas, &baked.patches);
    assert!(file.levels >= 2, "{:?}", file.layout);
    let (sides, corners) =
        assert_borders_identical(&baked.textures.base_color, &file, "base colour");
    assert_borders_identical(
        &baked.textures.metallic_roughness,
        &file,
        "metallic-roughness",
    );
    assert!(
        sides > 1000 && corners > 100,
        "{sides} side texels, {corners} corners compared"
    );
    // Every chart has a neighbour on each side: the sphere-and-box mesh is closed.
    assert!(file
        .charts
        .iter()
        .all(|c| c.neighbours.iter().all(|n| n.len() == 1)));

    // The float samples too, bitwise (before quantization).
    for level in &baked.levels {
        let n = level.n;
        for (c, chart) in file.charts.iter().enumerate() {
            let g = level.grid(&baked.table, c);
            for s in 0..4 {
                for nb in &chart.neighbours[s] {
                    let h = level.grid(&baked.table, nb.chart as usize);
                    for k in 0..n {
                        let kk = if nb.reversed { n - 1 - k } else { k };
                        let (i, j) = side_texel(n, s, k, 0);
                        let (i2, j2) = side_texel(n, nb.side as usize, kk, 0);
                        let (a, b) = (g[j * n + i], h[j2 * n + i2]);
                        assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
                    }
                }
            }
        }
    }

    // Seams: per level, the largest colour step across a border — between the first
    // inner texels on either side, two texel spacings apart, so halved — is no larger
    // than the largest step between neighbouring texels inside the charts.
    for (l, level) in baked.levels.iter().enumerate() {
        let n = level.n;
        if n < 3 {
            continue;
        }
        let step = |a: &[f32; 11], b: &[f32; 11]| {
            (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0f32, f32::max)
        };
        let (mut inside, mut across) = (0.0f32, 0.0f32);
        for (c, chart) in file.charts.iter().enumerate() {
            let g = level.grid(&baked.table, c);
            for j in 0..n {
                for i in 0..n {
                    if i + 1 < n {
                        inside = inside.max(step(&g[j * n + i], &g[j * n + i + 1]));
                    }
                    if j + 1 < n {
                        inside = inside.max(step(&g[j * n + i], &g[(j + 1) * n + i]));
                    }
                }
            }
            for (s, nbs) in chart.neighbours.iter().enumerate() {
                let nb = &nbs[0];
                let h = level.grid(&baked.table, nb.chart as usize);
                for k in 0..n {
                    let kk = if nb.reversed { n - 1 - k } else { k };
                    let (i, j) = side_texel(n, s, k, 1);
                    let (i2, j2) = side_texel(n, nb.side as usize, kk, 1);
                    across = across.max(step(&g[j * n + i], &h[j2 * n + i2]) / 2.0);
                }
            }
        }
        assert!(
            across <= inside,
            "level {l}: step across borders {across} against {inside} inside"
        );
        eprintln!("level {l} ({n}²): largest step inside {inside:.4}, across borders {across:.4}");
    }
}

#[test]
fn gpu_texel_points_and_colours_match_the_cpu_reference() {
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = tempfile::tempdir().unwrap();
    let baked = bake_source(&gpu, SMOOTH, dir.path(), &small(8)).expect("bakes");
    let analysis = sdfc::driver::check(SMOOTH, None);
    let shape = sdfc::driver::pick_shape(analysis.scene.as_ref().unwrap(), None).unwrap();
    let scale = sdfc::uv::atlas::scale(shape);
    let p = &baked.points;
    let all: Vec<&[f32; 3]> = p
        .corners
        .iter()
        .chain(&p.edges)
        .chain(&p.interiors)
        .collect();
    let mut worst = 0.0f64;
    for x in all.iter().step_by(7) {
        let x = DVec3::new(x[0] as f64, x[1] as f64, x[2] as f64);
        // On the surface within 1e-4 of the scale, by the f64 distance …
        worst = worst.max(eval::distance(shape, x).abs() / scale);
        // … and near the f64 projection of the same point.
        let y = eval::project(shape, x, 1e-12).expect("projects");
        assert!((y - x).length() < 1e-4 * scale);
    }
    assert!(
        worst < 1e-4,
        "largest |f| at a GPU texel point: {worst:e} of the scale"
    );
    // Colours: the material is position-only, so the CPU evaluates it exactly.
    let level0 = &baked.levels[0];
    let texels: Vec<_> = level0
        .corners
        .iter()
        .chain(&level0.edges)
        .chain(&level0.interiors)
        .collect();
    let mut worst_colour = 0.0f64;
    for (t, x) in texels.iter().zip(&all).step_by(5) {
        let x = DVec3::new(x[0] as f64, x[1] as f64, x[2] as f64);
        let want = [
            0.5 + 0.4 * (x.x * 2.0).sin(),
            0.5 + 0.4 * (x.y * 1.5).cos(),
            0.5 + 0.3 * (x.z * 2.5).sin(),
            0.3 + 0.2 * x.y,
            0.2,
        ];
        for (k, w) in want.iter().enumerate() {
            worst_colour = worst_colour.max((t[k] as f64 - w).abs());
        }
    }
    assert!(
        worst_colour < 1.0 / 255.0,
        "colour difference {worst_colour}"
    );
}

#[test]
fn bad_input_gets_a_clear_error() {
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = tempfile::tempdir().unwrap();
    let plain = "render sphere(1);";
    assert!(matches!(
        bake_source(&gpu, plain, dir.path(), &small(8)),
        Err(BakeError::NoMaterial)
    ));
    let plane = "material m { color = [1, 0, 0]; }\nrender plane([0, 1, 0], 0).paint(m);";
    assert!(matches!(
        bake_source(&gpu, plane, dir.path(), &small(8)),
        Err(BakeError::Unbounded)
    ));
    // With bounds, the plane bakes: an open mesh, charts on its rim have no neighbour.
    let bounded = Options {
        bounds: Some(Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        }),
        ..small(6)
    };
    let baked = bake_source(&gpu, plane, dir.path(), &bounded).expect("a bounded plane bakes");
    assert!(baked.table.len() >= 16);
    // Bounds with no surface in them.
    let away = Options {
        bounds: Some(Aabb {
            min: DVec3::new(-1.0, 0.5, -1.0),
            max: DVec3::new(1.0, 1.0, 1.0),
        }),
        ..small(6)
    };
    assert!(matches!(
        bake_source(&gpu, plane, dir.path(), &away),
        Err(BakeError::Empty(..))
    ));
    let sphere = "material m { color = [1, 0, 0]; }\nrender sphere(1).paint(m);";
    for size in [100, 0, 8, 1 << 20] {
        let o = Options { size, ..small(6) };
        let e = bake_source(&gpu, sphere, dir.path(), &o).err();
        assert!(
            matches!(e, Some(BakeError::Option(_))),
            "size {size}: {e:?}"
        );
    }
    let too_fine = Options {
        resolution: Resolution::Cells(100_000),
        ..small(6)
    };
    assert!(matches!(
        bake_source(&gpu, sphere, dir.path(), &too_fine),
        Err(BakeError::Option(_))
    ));
}

#[test]
fn flat_layouts_fit_without_overlap() {
    use sdfc::bake::FlatLayout;
    for size in [16u32, 64, 256, 2048] {
        for charts in [1usize, 2, 3, 7, 40, 100, 1000, 5000] {
            let Some(l) = FlatLayout::fit(charts, size) else {
                // Only when even 2² charts cannot fit.
                assert!(
                    charts * 4 > (size * size) as usize * 2 / 3,
                    "{charts} in {size}"
                );
                continue;
            };
            assert!(l.chart_size.is_power_of_two() && l.chart_size >= 2);
            assert!(l.width <= size && l.height <= size, "{l:?}");
            assert_eq!(l.size_at(l.levels() - 1), 2, "down to 2² texels: {l:?}");
            let mut used = vec![false; (l.width * l.height) as usize];
            for c in 0..charts {
                for lv in 0..l.levels() {
                    let [x, y] = l.chart_origin(c, lv);
                    let n = l.size_at(lv);
                    for j in y..y + n {
                        for i in x..x + n {
                            assert!(i < l.width && j < l.height, "{l:?}: chart {c} level {lv}");
                            let k = (j * l.width + i) as usize;
                            assert!(!used[k], "{l:?}: chart {c} level {lv} overlaps");
                            used[k] = true;
                        }
                    }
                }
            }
            // A larger chart size would not fit (the largest is chosen).
            let bigger = l.chart_size * 2;
            if bigger <= size {
                let rows = (charts as u32).div_ceil(size / bigger);
                assert!(rows * bigger > 2 * size / 3, "{l:?}: {bigger} would fit");
            }
            // Texture coordinates of the chart corners land on texel centres.
            let tc = l.texcoord(charts - 1, 1.0, 1.0);
            let [x, y] = l.chart_origin(charts - 1, 0);
            let n = l.chart_size as f32;
            assert!((tc[0] * l.width as f32 - (x as f32 + n - 0.5)).abs() < 1e-3);
            assert!((tc[1] * l.image_height() as f32 - (y as f32 + n - 0.5)).abs() < 1e-3);
            // Level 0 is the image's top rows, the levels below it.
            assert!(l
                .level_origins
                .iter()
                .skip(1)
                .all(|o| o[1] >= l.image_height()));
        }
    }
}

/// The baked texels of a textured example against the f64 CPU reference of its
/// material (`reference::material`), evaluated at the GPU's texel points and normals with the
/// texel's footprint. Implicit UVs in f32 may pick another seed on a frontier, and the
/// sampler's fixed-point filtering differs from the CPU's exact one by up to 3/255
/// (see `reference::material::texture`): at least 90 % of the texels agree within 3/255.
#[test]
fn baked_textured_texels_match_the_cpu_material_reference() {
    let Some(gpu) = gpu_for_tests() else { return };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/capsule.sdf");
    let source = std::fs::read_to_string(&path).unwrap();
    let base = path.parent().unwrap();
    let baked = bake_source(&gpu, &source, base, &small(10)).expect("bakes");
    let analysis = sdfc::driver::check(&source, Some(base));
    let eval = sdfc::reference::material::MaterialEval::load(&analysis.program, &analysis.atlases)
        .unwrap();
    let (points, texels, footprints) = level0_texels(&baked);
    let (mut within, mut compared) = (0, 0);
    for k in (0..texels.len()).step_by(11) {
        let t = texels[k];
        let x = DVec3::new(
            points[k][0] as f64,
            points[k][1] as f64,
            points[k][2] as f64,
        );
        let n = DVec3::new(t[8] as f64, t[9] as f64, t[10] as f64);
        // The painted material is materials[0], id 1.
        let want = eval.eval(1, x, n, footprints[k]);
        let got = [t[0], t[1], t[2], t[3], t[4]].map(|v| v as f64);
        let expected = [
            want.color.x,
            want.color.y,
            want.color.z,
            want.roughness,
            want.metallic,
        ];
        let worst = got
            .iter()
            .zip(&expected)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        compared += 1;
        if worst <= 3.0 / 255.0 {
            within += 1;
        }
    }
    let share = within as f64 / compared as f64;
    eprintln!("{within} of {compared} texels within 3/255 of the CPU reference");
    assert!(
        compared > 100 && share >= 0.9,
        "{within} of {compared} within 3/255"
    );
}

/// Larger charts (`chart_quads`): a chart covers m × m mesh quads. The charts still
/// meet side to side, their border texels stay identical, and the mesh is watertight:
/// every vertex on a chart's side has a twin, at the bitwise same position, in the
/// chart across.
#[test]
fn larger_charts_keep_borders_identical_and_the_mesh_watertight() {
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = tempfile::tempdir().unwrap();
    let m = 3;
    let options = Options {
        chart_quads: m,
        ..small(24)
    };
    let baked = bake_source(&gpu, SMOOTH, dir.path(), &options).expect("bakes");
    let file = ChartsFile::new(&baked.table, &baked.atlas, &baked.patches);
    assert_borders_identical(&baked.textures.base_color, &file, "chart_quads 3");
    let charts = baked.table.len();
    assert_eq!(baked.mesh.indices.len(), charts * m * m * 6);
    let n = m + 1;
    let at = |c: usize, (i, j): (usize, usize)| baked.mesh.positions[c * n * n + j * n + i];
    for (c, chart) in file.charts.iter().enumerate() {
        for s in 0..4 {
            let nb = &chart.neighbours[s][0];
            for k in 0..n {
                let kk = if nb.reversed { m - k } else { k };
                let a = at(c, side_texel(n, s, k, 0));
                let b = at(nb.chart as usize, side_texel(n, nb.side as usize, kk, 0));
                assert_eq!(
                    a.map(f32::to_bits),
                    b.map(f32::to_bits),
                    "chart {c} side {s} vertex {k}"
                );
            }
        }
    }
    // Every mesh vertex lies on the surface.
    let analysis = sdfc::driver::check(SMOOTH, None);
    let shape = sdfc::driver::pick_shape(analysis.scene.as_ref().unwrap(), None).unwrap();
    let scale = sdfc::uv::atlas::scale(shape);
    for p in &baked.mesh.positions {
        let x = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        assert!(eval::distance(shape, x).abs() < 1e-5 * scale);
    }
}

/// What a bake's tangent-space normal map decodes to, at level 0, in the frame a
/// rasterizer rebuilds from the exported mesh (barycentric over the triangle that holds
/// the texel; `m × m` quads a chart).
struct Decoded {
    texels: usize,
    /// Texels whose encoded z is below zero (blue under 128).
    below: usize,
    /// Texels whose baked normal points into the mesh (z < 0 in that frame).
    inward: usize,
    /// The largest angle between a decoded normal and the baked one, where that points
    /// out of the mesh.
    worst_out: f64,
    /// The largest angle between a decoded normal and the baked one's direction in the
    /// tangent plane, where that points into the mesh.
    worst_in: f64,
}

fn decode_normal_map(baked: &Baked, m: usize) -> Decoded {
    let level = &baked.levels[0];
    let n = level.n;
    let mut d = Decoded {
        texels: 0,
        below: 0,
        inward: 0,
        worst_out: 0.0,
        worst_in: 0.0,
    };
    for c in 0..baked.table.len() {
        let [x0, y0] = baked.patches.cell_origin(&baked.atlas, c, 0);
        let grid = level.grid(&baked.table, c);
        for j in 0..n {
            for i in 0..n {
                let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                let (t, nrm, w) = sdfc::bake::images::render_frame(&baked.mesh, m, c, u, v);
                let b = nrm.cross(t) * w;
                let px = baked
                    .textures
                    .normal
                    .get_pixel(x0 + i as u32, y0 + j as u32);
                let e = |k: usize| px[k] as f64 / 255.0 * 2.0 - 1.0;
                let decoded = DVec3::new(e(0), e(1), e(2)).normalize();
                let g = &grid[j * n + i];
                let want = DVec3::new(g[8] as f64, g[9] as f64, g[10] as f64).normalize();
                let local = DVec3::new(want.dot(t), want.dot(b), want.dot(nrm));
                d.texels += 1;
                d.below += usize::from(px[2] < 128);
                if local.z < 0.0 {
                    d.inward += 1;
                    let flat = DVec3::new(local.x, local.y, 0.0).normalize();
                    d.worst_in = d.worst_in.max(decoded.angle_between(flat).to_degrees());
                } else {
                    d.worst_out = d.worst_out.max(decoded.angle_between(local).to_degrees());
                }
            }
        }
    }
    d
}

/// The tangent-space normal map decodes to the baked object-space normal, within 8-bit
/// quantization. Checked at level 0 with 2 × 2 quads per chart, so texels fall in every
/// triangle of every split. Where the sphere meets the box, some triangles are far
/// from the field's gradient and the baked normal points into the mesh: there the map
/// holds that normal's direction in the tangent plane (below).
#[test]
fn the_normal_map_decodes_to_the_object_space_normal() {
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = tempfile::tempdir().unwrap();
    let options = Options {
        chart_quads: 2,
        ..small(16)
    };
    let baked = bake_source(&gpu, SMOOTH, dir.path(), &options).expect("bakes");
    let d = decode_normal_map(&baked, 2);
    eprintln!(
        "{} of {} texels point into the mesh; worst {:.2}° (others), {:.2}° (those)",
        d.inward, d.texels, d.worst_out, d.worst_in
    );
    // An 8-bit component is off by at most 1/255 in [-1, 1]: about 0.5° at worst.
    assert!(d.worst_out < 0.8, "worst angle {:.3}°", d.worst_out);
    assert!(d.worst_in < 1.0, "worst angle {:.3}° (inward)", d.worst_in);
    assert_eq!(d.below, 0);
}

/// Where the baked normal points into the mesh (the capsule's drilled rim, whose
/// triangles' normals are far from the field's gradient), the tangent-space map holds
/// the nearest normal out of the surface instead: no texel of any chart has z < 0, each
/// such texel decodes to the baked normal's own direction in the tangent plane (z = 0),
/// and every other texel still decodes to the baked normal. The example as a user
/// bakes it (512², the default grid and charts).
#[test]
fn tangent_space_normals_point_out_of_the_surface() {
    let Some(gpu) = gpu_for_tests() else { return };
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let source = std::fs::read_to_string(base.join("capsule.sdf")).unwrap();
    let options = Options {
        size: 512,
        ..Options::default()
    };
    let baked = bake_source(&gpu, &source, &base, &options).expect("bakes");
    let d = decode_normal_map(&baked, options.chart_quads);
    eprintln!(
        "capsule at 512²: {} of {} level-0 texels point into the mesh; worst {:.2}° (those), {:.2}° (others)",
        d.inward, d.texels, d.worst_in, d.worst_out
    );
    assert_eq!(d.below, 0, "texels with z < 0");
    // The capsule's rim has such texels (232 of 130,560 when measured): this test
    // sees the clamp at work.
    assert!(d.inward > 0, "no inward normal: the test checks nothing");
    // 8 bits: about 0.5° at worst, a little more for a grazing normal, whose z rounds
    // to +1/255.
    assert!(d.worst_in < 1.0, "{}", d.worst_in);
    assert!(d.worst_out < 0.8, "{}", d.worst_out);
}

/// The gutter (`--gutter 2`): each level-0 chart is padded with 2 texels from the charts
/// across its sides (enough for a generic chain's level 1, whose texels span 2). A generic engine's own mip chain (a 2 × 2 box
/// filter of the whole image) then averages each chart's border with its real
/// neighbour's texels: at that chain's level 1, the two sides of every chart border
/// agree far better than without the gutter, where they average unrelated charts.
#[test]
fn the_gutter_keeps_generic_mip_chains_close_across_borders() {
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = tempfile::tempdir().unwrap();
    let seam = |gutter: u32, size: u32| -> (f64, Baked) {
        let options = Options {
            gutter,
            size,
            ..small(10)
        };
        let baked = bake_source(&gpu, SMOOTH, dir.path(), &options).expect("bakes");
        let img = &baked.textures.base_color;
        let (w, h) = (img.width() / 2, img.height() / 2);
        // The generic chain's level 1: a 2 × 2 box filter of the image.
        let half: Vec<[f64; 3]> = (0..w * h)
            .map(|k| {
                let (x, y) = (2 * (k % w), 2 * (k / w));
                let mut acc = [0.0; 3];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let p = img.get_pixel(x + dx, y + dy);
                    for c in 0..3 {
                        acc[c] += p[c] as f64 / 4.0;
                    }
                }
                acc
            })
            .collect();
        // Bilinear at level-0 texel centre (x, y), as a sampler would read level 1.
        let sample = |x: u32, y: u32| -> [f64; 3] {
            let (fx, fy) = ((x as f64 + 0.5) / 2.0 - 0.5, (y as f64 + 0.5) / 2.0 - 0.5);
            let (x0, y0) = (fx.floor().max(0.0) as u32, fy.floor().max(0.0) as u32);
            let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
            let at = |x: u32, y: u32| half[(y.min(h - 1) * w + x.min(w - 1)) as usize];
            std::array::from_fn(|c| {
                let top = at(x0, y0)[c] * (1.0 - tx) + at(x0 + 1, y0)[c] * tx;
                let bottom = at(x0, y0 + 1)[c] * (1.0 - tx) + at(x0 + 1, y0 + 1)[c] * tx;
                top * (1.0 - ty) + bottom * ty
            })
        };
        let file = ChartsFile::new(&baked.table, &baked.atlas, &baked.patches);
        let mut worst = 0.0f64;
        for chart in &file.charts {
            let n = chart.rects[0][2] as usize;
            for s in 0..4 {
                let nb = &chart.neighbours[s][0];
                let other = &file.charts[nb.chart as usize];
                for k in 1..n - 1 {
                    let kk = if nb.reversed { n - 1 - k } else { k };
                    let (i, j) = side_texel(n, s, k, 0);
                    let (i2, j2) = side_texel(n, nb.side as usize, kk, 0);
                    let a = sample(chart.rects[0][0] + i as u32, chart.rects[0][1] + j as u32);
                    let b = sample(other.rects[0][0] + i2 as u32, other.rects[0][1] + j2 as u32);
                    worst = worst.max((0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max));
                }
            }
        }
        (worst, baked)
    };
    let (with, baked) = seam(2, 256);
    let (without, _) = seam(0, 256);
    eprintln!("largest step across borders at a generic chain's level 1: {with:.1} with the gutter, {without:.1} without (of 255)");
    assert!(
        with * 4.0 < without,
        "{with} with the gutter, {without} without"
    );
    assert!(with <= 12.0, "{with}");
    // The gutter holds the neighbours' texels, and the borders stay identical.
    let file = ChartsFile::new(&baked.table, &baked.atlas, &baked.patches);
    let flat = |b: &Baked| match &b.atlas {
        sdfc::bake::ChartLayout::Flat(l) => l.clone(),
        sdfc::bake::ChartLayout::Packed(_) => panic!("a flat bake"),
    };
    assert_eq!(flat(&baked).gutter, 2);
    assert_borders_identical(&baked.textures.base_color, &file, "with a gutter");
    // sdfc's own renderer reads inside the charts only: with and without a gutter
    // (at sizes where the chart size is the same, asserted below), the renders agree.
    let (_, baked) = seam(2, 512);
    let (_, plain) = seam(0, 256);
    assert_eq!(flat(&plain).chart_size, flat(&baked).chart_size);
    let analysis = sdfc::driver::check(SMOOTH, None);
    let shape = sdfc::driver::pick_shape(analysis.scene.as_ref().unwrap(), None).unwrap();
    let mut view = sdfc::view::View::new(analysis.program.render.as_ref(), shape);
    (view.width, view.height) = (96, 72);
    let draw = |b: &Baked| {
        let r = sdfc::gpu::MeshRenderer::new(&gpu, &b.mesh, &b.textures, &b.atlas).unwrap();
        r.render(&gpu, &view, sdfc::gpu::ViewMode::Color)
            .unwrap()
            .color
    };
    let (a, b) = (draw(&baked), draw(&plain));
    let worst = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
    assert!(worst <= 2, "the renders differ by {worst}");
}

/// Normal maps are baked: the baked texels' normals of examples/normal_map.sdf are the
/// material's shading normal (Eqs. 50–52, from the CPU reference at the texel's point
/// with the surface normal there), not the surface's; at least 90 % within 2° (the
/// sampler's fixed-point filtering moves a bevel's normal by up to about 1°, see
/// tests/normal_map.rs), and the normal map tilts them visibly from the surface normal.
#[test]
fn baked_normals_carry_the_normal_map() {
    let Some(gpu) = gpu_for_tests() else { return };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/normal_map.sdf");
    let source = std::fs::read_to_string(&path).unwrap();
    let base = path.parent().unwrap();
    let baked = bake_source(&gpu, &source, base, &small(8)).expect("bakes");
    let analysis = sdfc::driver::check(&source, Some(base));
    let shape = analysis.scene.as_ref().unwrap().render.clone().unwrap();
    let eval = sdfc::reference::material::MaterialEval::load(&analysis.program, &analysis.atlases)
        .unwrap();
    let (points, texels, footprints) = level0_texels(&baked);
    let (mut within, mut compared, mut tilted) = (0, 0, 0);
    for k in (0..texels.len()).step_by(7) {
        let t = texels[k];
        let x = DVec3::from_array(points[k].map(|v| v as f64));
        let n = sdfc::ir::eval::gradient(analysis.field(&shape), x).normalize();
        let want = eval
            .eval_surface(analysis.field(&shape), x, n, footprints[k])
            .normal;
        let got = DVec3::new(t[8] as f64, t[9] as f64, t[10] as f64).normalize();
        compared += 1;
        if got.angle_between(want).to_degrees() <= 2.0 {
            within += 1;
        }
        if got.angle_between(n).to_degrees() > 5.0 {
            tilted += 1;
        }
    }
    let share = within as f64 / compared as f64;
    eprintln!("{within} of {compared} baked normals within 2° of the material's; {tilted} tilted over 5° from the surface");
    assert!(compared > 100 && share >= 0.9, "{within} of {compared}");
    assert!(
        tilted * 10 > compared,
        "{tilted} of {compared} tilted: the normal map is not baked"
    );
}

/// What a rasterizer shows is what was baked: for every level-0 texel, the point any
/// rasterizer interpolates at that texel's TEXCOORD_0 (linear over the exported
/// triangle whose texture coordinates hold it, found from the exported mesh alone),
/// projected onto the surface, is the point the texel shaded. Checked on a curved
/// scene with 3 × 3 quads per chart and in both layouts.
#[test]
fn each_texel_shades_the_point_a_rasterizer_interpolates_at_its_uv() {
    use sdfc::bake::pipeline::Style;
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = tempfile::tempdir().unwrap();
    // Curved everywhere (projections near a crease depend on the method, not on this).
    let source = SMOOTH.replace(
        "sphere(1) | box([0.6, 0.6, 0.6]).translate([0.8, 0, 0])",
        "smooth_union(sphere(1), sphere(0.6).translate([0.9, 0.2, 0]), 0.3)",
    );
    let analysis = sdfc::driver::check(&source, None);
    let shape = sdfc::driver::pick_shape(analysis.scene.as_ref().unwrap(), None).unwrap();
    let scale = sdfc::uv::atlas::scale(shape);
    for style in [Style::Flat, Style::Packed] {
        let m = 3;
        let options = Options {
            chart_quads: m,
            style,
            ..small(16)
        };
        let baked = bake_source(&gpu, &source, dir.path(), &options).expect("bakes");
        let mesh = &baked.mesh;
        let n = baked.levels[0].n;
        let (per_chart, verts) = (6 * m * m, (m + 1) * (m + 1));
        let (mut worst, mut checked) = (0.0f64, 0);
        for c in 0..baked.table.len() {
            let tris = &mesh.indices[c * per_chart..(c + 1) * per_chart];
            for j in 1..n - 1 {
                for i in 1..n - 1 {
                    let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                    let uv = baked.patches.texcoord(&baked.atlas, c, u, v);
                    let uv = glam::DVec2::new(uv[0] as f64, uv[1] as f64);
                    // The exported triangle whose texture coordinates hold the texel.
                    let mut best: Option<(f64, DVec3)> = None;
                    for t in tris.chunks(3) {
                        let k = [t[0] as usize, t[1] as usize, t[2] as usize];
                        assert!(k.iter().all(|&k| k / verts == c), "chart {c}'s triangles");
                        let q = k.map(|k| {
                            let x = mesh.texcoords[k];
                            glam::DVec2::new(x[0] as f64, x[1] as f64)
                        });
                        let d = (q[1] - q[0]).perp_dot(q[2] - q[0]);
                        let b1 = (uv - q[0]).perp_dot(q[2] - q[0]) / d;
                        let b2 = (q[1] - q[0]).perp_dot(uv - q[0]) / d;
                        let w = [1.0 - b1 - b2, b1, b2];
                        let inside = w.iter().copied().fold(f64::INFINITY, f64::min);
                        let p = k.iter().zip(w).fold(DVec3::ZERO, |s, (&k, w)| {
                            let x = mesh.positions[k];
                            s + DVec3::new(x[0] as f64, x[1] as f64, x[2] as f64) * w
                        });
                        if best.is_none_or(|b| inside > b.0) {
                            best = Some((inside, p));
                        }
                    }
                    let (inside, x) = best.unwrap();
                    assert!(
                        inside > -1e-3,
                        "chart {c} texel ({i}, {j}) is in no triangle"
                    );
                    let rasterized = eval::project(shape, x, 1e-9 * scale).unwrap_or(x);
                    let shaded = baked.points.get(&baked.table, c, i, j);
                    let shaded = DVec3::new(shaded[0] as f64, shaded[1] as f64, shaded[2] as f64);
                    let off = (rasterized - shaded).length() / scale;
                    worst = worst.max(off);
                    checked += 1;
                }
            }
        }
        eprintln!("{style:?}: {checked} texels, worst distance {worst:.2e} of the scene's size");
        assert!(checked > 1000, "{checked}");
        assert!(
            worst < 2e-4,
            "{style:?}: a texel shaded a point {worst:e} away"
        );
    }
}

/// The exported split of a quad: the shorter diagonal where both splits lie flat, the
/// other where the shorter one folds a triangle over (the capsule's rim slivers,
/// 0.196 % of its triangles turned over 45° before, none after).
#[test]
fn a_quad_is_split_along_the_diagonal_that_does_not_fold_it() {
    use glam::DVec3;
    use sdfc::bake::images::split_along_02;
    // Flat, a little longer along 1–3: the shorter diagonal 0–2.
    let flat = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.1, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, 1.1, 0.0),
    ];
    assert!(split_along_02(flat));
    // A dart: corner 2 pulled past corner 3 (and a little up), as dual contouring
    // places vertices along a curved crease. 0–2 is shorter, but the triangle (0, 2, 3)
    // then faces away from the quad's normal; 1–3 keeps both facing it.
    let folded = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(-0.1, 1.3, 0.2),
        DVec3::new(0.0, 1.0, 0.0),
    ];
    assert!((folded[2] - folded[0]).length() < (folded[3] - folded[1]).length());
    let n = (folded[2] - folded[0])
        .cross(folded[3] - folded[1])
        .normalize();
    let facing = |a: usize, b: usize, c: usize| {
        (folded[b] - folded[a])
            .cross(folded[c] - folded[a])
            .normalize()
            .dot(n)
    };
    assert!(facing(0, 1, 2).min(facing(0, 2, 3)) < 0.5);
    assert!(facing(0, 1, 3).min(facing(1, 2, 3)) >= 0.5);
    assert!(!split_along_02(folded));
}

/// Every exported triangle has one bitangent sign (glTF's TANGENT w) at its three
/// vertices, ±1. A rasterizer interpolates w: between vertices of opposite signs the
/// bitangent shrinks through zero and the normal map draws wedges (issue 40: the dark
/// notches along `warps.sdf`'s twisted box). Taken vertex by vertex, the sign flipped
/// wherever a corner's normal (the field's gradient) stood across the chart's own
/// plane, as on a crease. Before one sign a chart: the twisted box at grid 12 mixed
/// signs in 96 of 364 triangles, at grid 24 in 360 of 1,692, and `csg.sdf` at grid 24
/// in 72 of 2,884.
#[test]
fn every_triangle_keeps_one_bitangent_sign() {
    use sdfc::bake::pipeline::{Refine, Style};
    let Some(gpu) = gpu_for_tests() else { return };
    let dir = tempfile::tempdir().unwrap();
    let csg =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/csg.sdf"))
            .unwrap();
    let cases = [
        ("twisted", common::TWISTED_BOX, 12, Style::Flat),
        ("twisted", common::TWISTED_BOX, 12, Style::Packed),
        ("twisted", common::TWISTED_BOX, 24, Style::Flat),
        ("twisted", common::TWISTED_BOX, 24, Style::Packed),
        ("csg", csg.as_str(), 24, Style::Flat),
    ];
    for (name, source, grid, style) in cases {
        let options = Options {
            size: 1024,
            style,
            refine: Refine::Times(1),
            ..small(grid)
        };
        let baked = bake_source(&gpu, source, dir.path(), &options).expect("bakes");
        let m = &baked.mesh;
        assert!(m.tangents.iter().all(|t| t[3] == 1.0 || t[3] == -1.0));
        let mixed = m
            .indices
            .chunks(3)
            .filter(|t| {
                let w = |k: u32| m.tangents[k as usize][3];
                w(t[1]) != w(t[0]) || w(t[2]) != w(t[0])
            })
            .count();
        assert_eq!(
            mixed,
            0,
            "{name}, grid {grid}, {style:?}: {mixed} of {} triangles mix bitangent signs",
            m.indices.len() / 3
        );
    }
}
