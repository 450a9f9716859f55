//! The packed layout (§3.4) with grown charts: the charts are conforming rectangles of
//! quads (the paper's two topological rules), far fewer than the quads on flat faces,
//! their border texels are bitwise identical at every level, and the baked mesh drawn
//! through the packed lookup matches the same bake in the flat layout.
//! GPU tests skip loudly without an adapter unless SDFC_REQUIRE_GPU=1.

use crate::common;

use common::assert_borders_identical;
use sdfc::bake::pipeline::{self, Baked, Options, Quiet, Resolution, Style};
use sdfc::bake::table::ChartsFile;
use sdfc::bake::ChartLayout;
use sdfc::gpu::{gpu_for_tests, Gpu, MeshRenderer, ViewMode};

/// A box and a sphere beside it: flat faces (where charts grow) and a curved surface
/// (where dual contouring's irregular vertices keep them small), and a smooth material.
/// (Where the two touched, the lines from the irregular vertices along the join would
/// run on straight across the box's faces and cut them up: conforming charts must.)
const SCENE: &str = "
let s = box([0.8, 0.5, 0.6]) | sphere(0.45).translate([1.5, 0.2, 0]);
material m {
    color = [0.5 + 0.4 * sin(position.x * 2.0), 0.5 + 0.4 * cos(position.y * 1.5), 0.5 + 0.3 * sin(position.z * 2.5)];
    roughness = 0.3 + 0.2 * position.y;
    metallic = 0.2;
}
render s.paint(m) {
    camera = orbit(target: [0.2, 0.1, 0], distance: 4, yaw: 35deg, pitch: 25deg);
}
";

fn bake(gpu: &Gpu, style: Style, max_chart: usize) -> Baked {
    let dir = tempfile::tempdir().unwrap();
    let (analysis, compiled) = common::check_and_compile_loop(SCENE, dir.path());
    let shape = sdfc::driver::pick_shape(analysis.scene.as_ref().unwrap(), None).unwrap();
    let options = Options {
        size: 512,
        resolution: Resolution::Cells(16),
        style,
        max_chart,
        ..Options::default()
    };
    let field = analysis.field(shape);
    pipeline::bake(gpu, &compiled.module, dir.path(), field, &options, &Quiet).unwrap()
}

#[test]
fn grown_charts_conform_and_keep_borders_identical_at_every_level() {
    let Some(gpu) = gpu_for_tests() else { return };
    let baked = bake(&gpu, Style::Packed, 6);
    let ChartLayout::Packed(layout) = &baked.atlas else {
        panic!("a packed atlas")
    };
    layout.check().unwrap();
    baked.patches.check_conforming(&baked.table).unwrap();
    let (charts, cells) = (baked.patches.len(), baked.table.len());
    eprintln!(
        "{charts} charts over {cells} cells, {}×{} atlas, {:.1} % used",
        layout.width,
        layout.height,
        100.0 * baked.atlas.utilisation(cells)
    );
    assert!(charts * 2 < cells, "{charts} charts over {cells} cells");
    assert!(baked.patches.dims.iter().all(|d| d[0] <= 6 && d[1] <= 6));
    assert!(
        baked.patches.dims.iter().any(|d| d[0] * d[1] >= 12),
        "no chart grew"
    );

    let file = ChartsFile::new(&baked.table, &baked.atlas, &baked.patches);
    assert_eq!(file.levels, layout.levels());
    // Closed mesh: a chart across every side (more than one only at the odd
    // non-manifold edge dual contouring makes where the sphere meets the box).
    assert!(file
        .charts
        .iter()
        .all(|c| c.neighbours.iter().all(|n| !n.is_empty())));
    let (sides, corners) =
        assert_borders_identical(&baked.textures.base_color, &file, "packed colour");
    assert_borders_identical(
        &baked.textures.metallic_roughness,
        &file,
        "packed metallic-roughness",
    );
    let normals = sdfc::bake::images::object_normals(
        &baked.table,
        &baked.atlas,
        &baked.patches,
        &baked.levels,
    );
    assert_borders_identical(&normals, &file, "packed object normals");
    assert!(
        sides > 500 && corners > 100,
        "{sides} side texels, {corners} corners"
    );

    // Inside a grown chart the cells' shared rows are the same samples too: each cell's
    // n_l × n_l block in the image is its own grid of the level, for every cell.
    for (l, level) in baked.levels.iter().enumerate() {
        let n = level.n;
        for c in 0..cells {
            let [x0, y0] = baked.patches.cell_origin(&baked.atlas, c, l);
            let grid = level.grid(&baked.table, c);
            for j in 0..n {
                for i in 0..n {
                    let t = grid[j * n + i];
                    let px = baked
                        .textures
                        .base_color
                        .get_pixel(x0 + i as u32, y0 + j as u32);
                    let want = [t[0], t[1], t[2]].map(sdfc::bake::images::srgb8);
                    assert_eq!(
                        [px[0], px[1], px[2]],
                        want,
                        "level {l} cell {c} texel ({i}, {j})"
                    );
                }
            }
        }
    }
    // Every mesh vertex's texture coordinate lies in its chart's level-0 rectangle.
    let m = 1;
    for (c, place) in baked.patches.place.iter().enumerate() {
        let [x, y, w, h] = baked.atlas.rect(place[0] as usize, 0).map(|v| v as f32);
        for k in 0..(m + 1) * (m + 1) {
            let tc = baked.mesh.texcoords[c * (m + 1) * (m + 1) + k];
            let (tx, ty) = (tc[0] * layout.width as f32, tc[1] * layout.height as f32);
            assert!(tx >= x + 0.5 - 1e-3 && tx <= x + w - 0.5 + 1e-3, "cell {c}");
            assert!(ty >= y + 0.5 - 1e-3 && ty <= y + h - 0.5 + 1e-3, "cell {c}");
        }
    }
}

/// The packed lookup in the mesh renderer (per-vertex chart entry, per-level rectangle,
/// Eq. 1–2 per cell) draws what the flat layout draws: the same samples, placed
/// differently. Also at a distance, where coarser levels are read.
#[test]
fn the_packed_atlas_renders_as_the_flat_one_does() {
    let Some(gpu) = gpu_for_tests() else { return };
    let packed = bake(&gpu, Style::Packed, 16);
    let flat = bake(&gpu, Style::Flat, 16);
    assert_eq!(packed.atlas.cell_size(), flat.atlas.cell_size());
    let analysis = sdfc::driver::check(SCENE, None);
    let shape = sdfc::driver::pick_shape(analysis.scene.as_ref().unwrap(), None).unwrap();
    let view = sdfc::view::View::new(analysis.program.render.as_ref(), shape);
    for (distance, (w, h)) in [(1.0, (160, 120)), (6.0, (96, 72))] {
        let mut v = view.clone();
        (v.width, v.height) = (w, h);
        // (The scene's camera is 4 from its target.)
        v.camera.eye -= v.camera.forward * (4.0 * (distance - 1.0));
        let draw = |b: &Baked, mode| {
            MeshRenderer::new(&gpu, &b.mesh, &b.textures, &b.atlas)
                .unwrap()
                .render(&gpu, &v, mode)
                .unwrap()
        };
        let (a, b) = (
            draw(&packed, ViewMode::Albedo),
            draw(&flat, ViewMode::Albedo),
        );
        let p = common::psnr(&a.color, &b.color);
        eprintln!("packed against flat, albedo, {distance}× the distance: PSNR {p:.1} dB");
        assert!(p >= 40.0, "albedo at {distance}×: PSNR {p:.1} dB");
        let (a, b) = (draw(&packed, ViewMode::Color), draw(&flat, ViewMode::Color));
        let p = common::psnr(&a.color, &b.color);
        eprintln!("packed against flat, colour, {distance}× the distance: PSNR {p:.1} dB");
        assert!(p >= 36.0, "colour at {distance}×: PSNR {p:.1} dB");
    }
}
