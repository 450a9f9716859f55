//! `sdfc bake` end to end: every example bakes, the Khronos glTF-Validator finds
//! nothing to report, the written files keep border texels identical at every level,
//! and bad input gets a clear message, the documented exit status and no file.
//! GPU tests skip loudly without an adapter unless SDFC_REQUIRE_GPU=1.

use crate::common;

use common::{assert_borders_identical, gltf_validate, sdfc};
use sdfc::bake::table::ChartsFile;
use sdfc::gpu::gpu_for_tests;

fn has_gpu() -> bool {
    gpu_for_tests().is_some()
}

#[test]
fn every_example_bakes_validates_and_keeps_borders_identical() {
    if !has_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut examples: Vec<_> = std::fs::read_dir("examples")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .collect();
    examples.sort();
    assert!(examples.len() >= 8);
    for example in &examples {
        let stem = example.file_stem().unwrap().to_string_lossy().into_owned();
        let glb = dir.path().join(format!("{stem}.glb"));
        let charts = dir.path().join(format!("{stem}.json"));
        let ktx2 = dir.path().join(format!("{stem}.ktx2"));
        let normals = dir.path().join(format!("{stem}.normals.png"));
        // The examples with a ground plane have no finite bounds: they need --bounds.
        // The loop walk: this test is not about the walk's form, and on the software
        // adapter the unrolled one takes minutes to compile where the shader cache is
        // cold (robot.sdf: 172 s against 2 s).
        let mut args = vec!["bake", example.to_str().unwrap(), "--walk", "loop"];
        // The bounds given, where the mesh is cut.
        let mut cut: Option<([f32; 3], [f32; 3])> = None;
        if ["blend", "primitives"].contains(&stem.as_str()) {
            args.extend(["--bounds", "-3,-1,-3", "3,2,3"]);
            cut = Some(([-3.0, -1.0, -3.0], [3.0, 2.0, 3.0]));
        }
        // The plates are 0.2 thick and 16 wide: an 8-cell grid falls through them, so
        // bake a corner of each at a finer grid.
        let plate = stem.starts_with("plate");
        if plate {
            cut = Some(([-0.5; 3], [0.5; 3]));
            args.extend([
                "--bounds",
                "-0.5,-0.5,-0.5",
                "0.5,0.5,0.5",
                "--edge",
                "0.08",
            ]);
        }
        // Two examples in the packed layout (grown charts): the same checks hold, but
        // for the KTX2 file (the flat layout's stacked levels).
        let packed = ["robot", "csg"].contains(&stem.as_str());
        if packed {
            args.extend(["--layout", "packed"]);
        } else {
            args.extend(["--ktx2", ktx2.to_str().unwrap()]);
        }
        args.extend([
            "-o",
            glb.to_str().unwrap(),
            "--size",
            "128",
            "--charts",
            charts.to_str().unwrap(),
            "--object-normals",
            normals.to_str().unwrap(),
        ]);
        if !plate {
            args.extend(["--grid", "8"]);
        }
        // One example with a gutter: the same checks hold.
        if stem == "capsule" {
            args.push("--gutter");
        }
        // One packed example with charts of 3 × 3 quads: its file is welded inside each
        // chart with the weld's lookup of the cells' sides alone.
        let chart_quads: usize = if stem == "csg" { 3 } else { 1 };
        if chart_quads > 1 {
            args.extend(["--chart-quads", "3"]);
        }
        // Two with fitted texels, one in each layout: the same checks hold.
        let fit = ["normal_map", "robot"].contains(&stem.as_str());
        if fit {
            args.extend(["--texels", "fit"]);
        }
        let (mut code, _, mut err) = sdfc(&args);
        // Other examples on a ground plane: the message names --bounds; bake the
        // region above the floor, as a user would.
        if code == 2 && err.contains("no finite bounds") {
            args.extend(["--bounds", "-3,-1,-3", "3,3,3"]);
            cut = Some(([-3.0, -1.0, -3.0], [3.0; 3]));
            (code, _, err) = sdfc(&args);
        }
        assert_eq!(code, 0, "{stem}: {err}");
        assert!(
            err.contains("utilisation:") && err.contains("shade (GPU)"),
            "{stem}: {err}"
        );
        assert_eq!(err.contains("--texels fit)"), fit, "{stem}: {err}");
        // The coverage line, and its warning where a thin shell falls between the corners
        // of this coarse grid.
        assert!(err.contains("surface held:"), "{stem}: {err}");
        if stem == "warps" {
            // Refined 4 times (8 times does not fit 128²), a little is still missed.
            assert!(err.contains("meshed 4× finer"), "{stem}: {err}");
            assert!(err.contains("warning: the mesh misses"), "{stem}: {err}");
        }
        // The robot's limbs fall between this coarse grid's corners: refined (packed),
        // its mesh holds the whole surface, and its file goes through the same checks.
        if stem == "robot" {
            assert!(
                err.contains("cells with detail finer than a cell, meshed 2× finer; the plain grid's mesh missed"),
                "{stem}: {err}"
            );
            assert!(!err.contains("warning: the mesh misses"), "{stem}: {err}");
        }
        // A corner of a plate (--bounds): the surface outside the bounds is not missed.
        if plate {
            assert!(!err.contains("warning: the mesh misses"), "{stem}: {err}");
        }
        if let Some(report) = gltf_validate(&glb) {
            assert_eq!(
                (report.errors, report.warnings),
                (0, 0),
                "{stem}: the glTF-Validator reports {:?}",
                report.messages
            );
        }
        let bytes = std::fs::read(&glb).unwrap();
        let (mesh, textures, layout) = sdfc::bake::export::read_glb(&bytes).expect("reads back");
        assert!(mesh.indices.len() >= 3 * 2 * 8, "{stem}");
        // With --bounds the mesh is cut at their faces: inside them, and the plate's
        // corner reaches the four that cross it (x and z = ±0.5) exactly.
        if let Some((min, max)) = cut {
            for a in 0..3 {
                let coords = mesh.positions.iter().map(|p| p[a]);
                let (lo, hi) = coords.fold((f32::MAX, f32::MIN), |(l, h), c| (l.min(c), h.max(c)));
                assert!(
                    lo >= min[a] && hi <= max[a],
                    "{stem}: axis {a} spans {lo} to {hi}"
                );
                if plate && a != 1 {
                    assert_eq!((lo, hi), (min[a], max[a]), "{stem}: axis {a}");
                }
            }
        }
        let file: ChartsFile = serde_json::from_slice(&std::fs::read(&charts).unwrap()).unwrap();
        assert_eq!(file.layout, layout, "{stem}");
        let cells = match &layout {
            sdfc::bake::ChartLayout::Flat(_) => file.charts.len(),
            sdfc::bake::ChartLayout::Packed(p) => p
                .charts
                .iter()
                .map(|c| (c.cells[0] * c.cells[1]) as usize)
                .sum(),
        };
        // The triangles left out as folded (two corners on one point), as the report
        // says: none is left in the file, and no edge is held by more than two triangles
        // (by position) where the mesh has no pinch (the folded ones had made the edges
        // around a collapsed quad non-manifold).
        let folded = common::report_count(&err, "folded:");
        let held = common::edges_by_position(&mesh);
        for t in mesh.indices.chunks_exact(3) {
            let p = |k: usize| mesh.positions[t[k] as usize];
            assert!(
                p(0) != p(1) && p(1) != p(2) && p(0) != p(2),
                "{stem}: a folded triangle {t:?} in the file"
            );
        }
        let over = held.values().filter(|&&n| n > 2).count();
        // Four keep a few edges held by four triangles at this coarse grid (8 cells):
        // there two sheets of their surface, facing opposite ways, pass through one
        // cell, and both sheets' quads share its one dual vertex (a pinch that dual
        // contouring makes; 2, 15, 6 and 11 edges when this was written). Every other
        // example is manifold here.
        if !["blend", "csg", "primitives", "warps"].contains(&stem.as_str()) {
            assert_eq!(over, 0, "{stem}: edges held by more than two triangles");
        }
        // Uncut, two triangles a quad, less the folded ones, and one piece a chart (a
        // cut chart may lose all its triangles or fall apart; a chart of one quad
        // collapsed to a point loses its two).
        if cut.is_none() {
            assert_eq!(
                cells * chart_quads * chart_quads * 6,
                mesh.indices.len() + 3 * folded,
                "{stem}: two triangles per quad"
            );
        }
        // Welded: each chart is one connected piece of the mesh (by shared vertex
        // index), and the file has fewer vertices than three per triangle's corner.
        let pieces = common::mesh_pieces(&mesh);
        let charts_in_layout = match &layout {
            sdfc::bake::ChartLayout::Flat(_) => file.charts.len(),
            sdfc::bake::ChartLayout::Packed(p) => p.charts.len(),
        };
        if cut.is_none() {
            assert!(
                pieces <= charts_in_layout && pieces + folded / 2 >= charts_in_layout,
                "{stem}: {pieces} pieces for {charts_in_layout} charts ({folded} folded triangles left out)"
            );
        }
        eprintln!(
            "{stem}: {} vertices for {} triangles in {pieces} pieces (4 a cell unwelded: {}); {folded} folded left out; {over} edges held by more than two",
            mesh.positions.len(),
            mesh.indices.len() / 3,
            cells * 4
        );
        if packed {
            assert!(
                matches!(layout, sdfc::bake::ChartLayout::Packed(_)),
                "{stem}"
            );
            // (At this coarse grid a few charts grow: tests/bake_packed.rs measures more.)
            assert!(
                file.charts.len() < cells,
                "{stem}: {} charts of {cells} cells",
                file.charts.len()
            );
        }
        let (sides, _) = assert_borders_identical(&textures.base_color, &file, &stem);
        assert_borders_identical(&textures.metallic_roughness, &file, &stem);
        assert!(sides > 0, "{stem}: no shared sides");
        let normals = image::open(&normals).unwrap().to_rgba8();
        assert_borders_identical(&normals, &file, &stem);
        // The bake renders from the scene's own camera, at the scene's size or --size.
        if stem == "sphere" {
            // The bake drawn from the scene's camera at 64 × 48, with `extra` flags.
            let render_glb = |out: &std::path::Path, extra: &[&str]| {
                let mut args = vec![
                    "render",
                    glb.to_str().unwrap(),
                    "--camera-from",
                    example.to_str().unwrap(),
                    "--size",
                    "64x48",
                    "-o",
                    out.to_str().unwrap(),
                ];
                args.extend_from_slice(extra);
                let (code, _, err) = sdfc(&args);
                assert_eq!(code, 0, "{err}");
            };
            let png = dir.path().join("sphere-mesh.png");
            render_glb(&png, &[]);
            let img = image::open(&png).unwrap();
            assert_eq!((img.width(), img.height()), (64, 48));
            let (code, _, err) = sdfc(&[
                "render",
                example.to_str().unwrap(),
                "--camera-from",
                example.to_str().unwrap(),
            ]);
            assert_eq!(code, 2, "{err}");
            assert!(err.contains("--camera-from is for"), "{err}");
            // As a generic glTF viewer reads it: the same picture, within filtering.
            let standard = dir.path().join("sphere-standard.png");
            render_glb(&standard, &["--filter", "standard"]);
            let (a, b) = (
                image::open(&png).unwrap().to_rgb8(),
                image::open(&standard).unwrap().to_rgb8(),
            );
            let mean = a
                .as_raw()
                .iter()
                .zip(b.as_raw())
                .map(|(x, y)| (*x as f64 - *y as f64).abs())
                .sum::<f64>()
                / a.as_raw().len() as f64;
            assert!(
                a != b && mean < 4.0,
                "standard against atlas filter: mean {mean:.2}/255"
            );
            let (code, _, err) =
                sdfc(&["render", example.to_str().unwrap(), "--filter", "standard"]);
            assert_eq!(code, 2, "{err}");
            assert!(err.contains("--filter is for"), "{err}");
        }
        // The KTX2 file holds one level per atlas level.
        if !packed {
            let bytes = std::fs::read(&ktx2).unwrap();
            let reader = ktx2::Reader::new(&bytes[..]).expect("a KTX2 file");
            assert_eq!(
                reader.header().level_count as usize,
                layout.levels(),
                "{stem}"
            );
        }
    }
}

#[test]
fn bad_input_gets_a_message_a_status_and_no_file() {
    if !has_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let out = dir.path().join("out.glb");
    let out_s = out.to_str().unwrap().to_string();
    let plain = write("plain.sdf", "render sphere(1);");
    let plane = write(
        "plane.sdf",
        "material m { color = [1, 0, 0]; }\nrender plane([0, 1, 0], 0).paint(m);",
    );
    let sphere = write(
        "sphere.sdf",
        "material m { color = [1, 0, 0]; }\nrender sphere(1).paint(m);",
    );
    let far = write(
        "far.sdf",
        "material m { color = [1, 0, 0]; }\nrender sphere(1).translate([1e7, 0, 0]).paint(m);",
    );
    let huge = write(
        "huge.sdf",
        "material m { color = [1, 0, 0]; }\nrender sphere(1e11).paint(m);",
    );
    let empty = write(
        "empty.sdf",
        "material m { color = [1, 0, 0]; }\nrender (sphere(1) & sphere(1).translate([5, 0, 0])).paint(m);",
    );
    let cases: Vec<(Vec<&str>, i32, &str)> = vec![
        (vec![&plain], 1, "no material"),
        (vec![&plane], 2, "--bounds"),
        (
            vec![&plane, "--bounds", "-1,2,-1", "1,3,1"],
            1,
            "no surface inside the bounds",
        ),
        // A plane 0.05 short of the bounds: the grid's margin reaches it, the mesh
        // keeps nothing of it.
        (
            vec![&plane, "--bounds", "-1,0.05,-1", "1,3,1"],
            1,
            "no surface inside the bounds",
        ),
        (
            vec![&plane, "--bounds", "1,1,1", "-1,-1,-1"],
            2,
            "must be below",
        ),
        (vec![&sphere, "--size", "300"], 2, "power of two"),
        (
            vec![&sphere, "--refine", "9"],
            2,
            "expected auto or a whole number from 1 to 8",
        ),
        (
            vec![&sphere, "--refine", "0"],
            2,
            "expected auto or a whole number from 1 to 8",
        ),
        (vec![&sphere, "--grid", "1"], 2, "cells"),
        (
            vec![&sphere, "--texels", "nearest"],
            2,
            "expected fit or points",
        ),
        (
            vec![&sphere, "--grid", "8", "--size", "16"],
            5,
            "do not fit",
        ),
        (
            vec![&sphere, "--grid", "8", "--size", "16", "--layout", "packed"],
            5,
            "do not fit",
        ),
        (
            vec![&sphere, "--layout", "packed", "--gutter"],
            2,
            "--gutter",
        ),
        (
            vec![&sphere, "--layout", "packed", "--ktx2", "x.ktx2"],
            2,
            "--ktx2",
        ),
        (
            vec![&sphere, "--layout", "packed", "--max-chart", "0"],
            2,
            "--max-chart",
        ),
        (vec![&sphere, "--max-chart", "4"], 2, "add --layout packed"),
        (
            vec![&sphere, "--size", "32768"],
            2,
            "a power of two from 16 to 16384",
        ),
        (vec![&sphere, "--edge", "1e-30"], 2, "2.000e30 cells"),
        (
            vec![&sphere, "--grid", "4", "--chart-quads", "4"],
            2,
            "it needs at least 2",
        ),
        // Where f32 coordinates cannot hold the surface: the shape refused, not baked
        // into a mesh of collapsed triangles (exit 0 before).
        (vec![&far], 1, "units from the origin, where f32 positions"),
        (vec![&huge], 1, "a bake holds coordinates up to 1e9"),
        (vec![&empty], 1, "the shape is empty"),
    ];
    for (args, status, message) in cases {
        let mut all = vec!["bake"];
        all.extend(args.iter().copied());
        all.extend(["-o", &out_s]);
        let (code, _, err) = sdfc(&all);
        assert_eq!(code, status, "{all:?}: {err}");
        assert!(err.contains(message), "{all:?}: {err}");
        assert!(!out.exists(), "{all:?} left {}", out.display());
    }
    // No surface after --refine 8: the message does not suggest it again.
    let (code, _, err) = sdfc(&[
        "bake",
        &plane,
        "--bounds",
        "-1,0.05,-1",
        "1,3,1",
        "--refine",
        "8",
        "-o",
        &out_s,
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("no surface inside the bounds") && !err.contains("--refine 8"),
        "{err}"
    );
    // Unwritable outputs: a missing folder, a folder in place of the file.
    let missing = dir.path().join("no/such/folder/out.glb");
    let (code, _, err) = sdfc(&[
        "bake",
        &sphere,
        "--grid",
        "6",
        "--size",
        "64",
        "-o",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot write"), "{err}");
    let folder = dir.path().join("folder.glb");
    std::fs::create_dir(&folder).unwrap();
    let (code, _, err) = sdfc(&[
        "bake",
        &sphere,
        "--grid",
        "6",
        "--size",
        "64",
        "-o",
        folder.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot write"), "{err}");
    // Every output is checked before the bake: an unwritable --object-normals leaves
    // no .glb behind.
    let (code, _, err) = sdfc(&[
        "bake",
        &sphere,
        "--grid",
        "6",
        "--size",
        "64",
        "-o",
        &out_s,
        "--object-normals",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot write") && !out.exists(), "{err}");
    // Bounds that miss a bounded shape are a usage error.
    let (code, _, err) = sdfc(&["bake", &sphere, "--bounds", "5,5,5", "6,6,6", "-o", &out_s]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("do not overlap"), "{err}");
    // Nothing but what the test made is in the folder: no temporary files left.
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "empty.sdf",
            "far.sdf",
            "folder.glb",
            "huge.sdf",
            "plain.sdf",
            "plane.sdf",
            "sphere.sdf",
        ]
    );
}

/// `--bounds` cut the exported mesh at their faces (bake/clip.rs), whatever their size:
/// a box thinner than a mesh cell across a plane bakes the strip it holds (it was
/// refused, when the mesh kept whole quads), exactly: its ends on the box's faces, its
/// area the strip's. A flat face along a face of the box is kept whole, and the
/// material's warnings count only what the file shows.
#[test]
fn bounds_cut_the_file_at_their_faces_whatever_their_size() {
    if !has_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let plane = dir.path().join("plane.sdf");
    std::fs::write(
        &plane,
        "material m { color = [1, 0, 0]; }\nrender plane([0, 1, 0], 0).paint(m);",
    )
    .unwrap();
    let glb = dir.path().join("strip.glb");
    let (code, _, err) = sdfc(&[
        "bake",
        plane.to_str().unwrap(),
        "--bounds",
        "-1,-1,0",
        "1,1,0.01",
        "--size",
        "256",
        "-o",
        glb.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("warning: the mesh misses"), "{err}");
    if let Some(report) = gltf_validate(&glb) {
        assert_eq!(
            (report.errors, report.warnings),
            (0, 0),
            "{:?}",
            report.messages
        );
    }
    let (mesh, _, _) = sdfc::bake::export::read_glb(&std::fs::read(&glb).unwrap()).unwrap();
    let span = |a: usize| {
        let c = mesh.positions.iter().map(|p| p[a]);
        c.fold((f32::MAX, f32::MIN), |(l, h), c| (l.min(c), h.max(c)))
    };
    assert_eq!(span(0), (-1.0, 1.0));
    let (lo, hi) = span(1);
    assert!(
        lo.abs() < 1e-9 && hi.abs() < 1e-9,
        "off the plane: {lo} to {hi}"
    );
    assert_eq!(span(2), (0.0, 0.01));
    let p = |i: u32| glam::DVec3::from_array(mesh.positions[i as usize].map(f64::from));
    let area: f64 = mesh
        .indices
        .chunks_exact(3)
        .map(|t| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length())
        .sum();
    assert!(
        (area - 0.02).abs() < 1e-6,
        "the strip's area is {area}, not 0.02"
    );
    let line = format!(
        "cut:            at the bounds' faces, {} triangles in the file",
        mesh.indices.len() / 3
    );
    assert!(err.contains(&line), "{err}");

    // A flat face along a face of the box (its vertices a rounding error off it) is kept
    // whole (the box's bottom at y = -0.4 had no triangle, at random): the unit box's
    // face of area 1, on the plane exactly.
    let cube = dir.path().join("cube.sdf");
    std::fs::write(
        &cube,
        "material m { color = [0.5, 0.5, 0.5]; }\nrender box([1, 1, 1]).translate([0, 0.1, 0]).paint(m);",
    )
    .unwrap();
    let out = dir.path().join("cube.glb");
    let out_s = out.to_str().unwrap();
    let small = [
        "--grid", "16", "--size", "256", "--walk", "loop", "-o", out_s,
    ];
    let bake = |scene: &std::path::Path, extra: &[&str]| {
        let mut args = vec!["bake", scene.to_str().unwrap()];
        args.extend_from_slice(extra);
        args.extend_from_slice(&small);
        sdfc(&args)
    };
    let (code, _, err) = bake(&cube, &["--bounds", "-1,-0.4,-1", "1,3,1"]);
    assert_eq!(code, 0, "{err}");
    let (mesh, _, _) = sdfc::bake::export::read_glb(&std::fs::read(&out).unwrap()).unwrap();
    let p = |i: u32| glam::DVec3::from_array(mesh.positions[i as usize].map(f64::from));
    let bottom: f64 = mesh
        .indices
        .chunks_exact(3)
        .filter(|t| t.iter().all(|&i| mesh.positions[i as usize][1] == -0.4))
        .map(|t| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length())
        .sum();
    assert!(
        (bottom - 1.0).abs() < 1e-4,
        "the bottom face's area is {bottom}"
    );
    assert!(mesh.positions.iter().all(|p| p[1] >= -0.4));

    // The material's warnings count what the file shows: an emission below 0 only
    // where x < 0.58, cut away by the box, is not said; uncut, it is.
    let glow = dir.path().join("glow.sdf");
    std::fs::write(
        &glow,
        "material m { color = [0.5, 0.5, 0.5]; emission = [position.x - 0.58, 0, 0]; }\nrender sphere(1).paint(m);",
    )
    .unwrap();
    let (code, _, err) = bake(&glow, &["--bounds", "0.6,-1.2,-1.2", "1.2,1.2,1.2"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("out of the images' range"), "{err}");
    let (code, _, err) = bake(&glow, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("out of the images' range"), "{err}");
    // So does the emissive strength: an emission of 3 x, at most 0.9 in the box, needs
    // none (a strength from the part cut away dimmed what the file shows).
    std::fs::write(
        &glow,
        "material m { color = [0.5, 0.5, 0.5]; emission = [max(position.x * 3, 0), 0, 0]; }\nrender sphere(1).paint(m);",
    )
    .unwrap();
    let (code, _, err) = bake(&glow, &["--bounds", "-1.2,-1.2,-1.2", "0.3,1.2,1.2"]);
    assert_eq!(code, 0, "{err}");
    let (_, textures, _) = sdfc::bake::export::read_glb(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(textures.emissive_strength, 1.0, "{err}");
    assert!(!err.contains("emission:"), "{err}");
    let (code, _, err) = bake(&glow, &[]);
    assert_eq!(code, 0, "{err}");
    let (_, textures, _) = sdfc::bake::export::read_glb(&std::fs::read(&out).unwrap()).unwrap();
    assert!(textures.emissive_strength > 2.9, "{err}");
}

/// Outputs are checked before any work, a GPU or not: a name ending in a separator or
/// in `/.`, a file name too long for the temporary file it is written through, a
/// `.gltf` name for binary glTF, a texture the scene reads (it was overwritten), and
/// `bench --json` naming the scene (it was overwritten); bench's bake flags need
/// `--bake`, which takes no `--seed-sweep`.
#[test]
fn outputs_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let out_s = dir.path().join("out.glb").to_str().unwrap().to_string();
    let sphere = write(
        "sphere.sdf",
        "material m { color = [1, 0, 0]; }\nrender sphere(1).paint(m);",
    );
    // Outputs checked before the bake: a name ending in a separator, a file name longer
    // than file systems take, a .gltf name for binary glTF.
    let long = dir.path().join(format!("{}.glb", "a".repeat(220)));
    for (o, message) in [
        (format!("{out_s}/"), "names a folder"),
        (format!("{out_s}/."), "names a folder"),
        (long.to_str().unwrap().to_string(), "at most 215"),
        (
            dir.path().join("x.gltf").to_str().unwrap().to_string(),
            "name the output .glb",
        ),
    ] {
        let (code, _, err) = sdfc(&["bake", &sphere, "--grid", "6", "--size", "64", "-o", &o]);
        assert_eq!(code, 2, "{o}: {err}");
        assert!(err.contains(message), "{o}: {err}");
    }
    // Nor may an output replace a texture the scene reads (it replaced it before).
    let texture = dir.path().join("red.png");
    image::RgbaImage::from_pixel(4, 4, image::Rgba([255, 0, 0, 255]))
        .save(&texture)
        .unwrap();
    let textured = write(
        "textured.sdf",
        "let red = image(\"red.png\");\nmaterial m { color = red.sample([0.5, 0.5]).rgb; }\nrender sphere(1).paint(m);",
    );
    let before = std::fs::read(&texture).unwrap();
    let (code, _, err) = sdfc(&[
        "bake",
        &textured,
        "--grid",
        "6",
        "--size",
        "64",
        "-o",
        texture.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("the same file as the input texture"), "{err}");
    assert_eq!(std::fs::read(&texture).unwrap(), before);
    // `bench --json` may not replace the scene; bench's bake flags need --bake.
    let scene_before = std::fs::read(&sphere).unwrap();
    let (code, _, err) = sdfc(&[
        "bench",
        &sphere,
        "--bake",
        "--atlas-size",
        "64",
        "--json",
        &sphere,
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("the same file as the input scene"), "{err}");
    assert_eq!(std::fs::read(&sphere).unwrap(), scene_before);
    for args in [
        vec!["bench", sphere.as_str(), "--atlas-size", "64"],
        vec!["bench", "--bake", "--seed-sweep"],
    ] {
        let (code, _, err) = sdfc(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("required arguments were not provided") && err.contains("--bake")
                || err.contains("'--bake' cannot be used with '--seed-sweep'"),
            "{args:?}: {err}"
        );
    }
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["red.png", "sphere.sdf", "textured.sdf"]);
}

/// A part thinner than every cell of the plain grid (a 0.01-thick plate on cells of
/// 0.25): the plain mesh finds no surface, and `--refine auto` meshes it finer where
/// the surface samples lie, as where a plain mesh misses part of it (it exited 1, "no
/// surface", while `--refine 8` baked it).
#[test]
fn auto_refinement_finds_a_part_the_plain_grid_misses_entirely() {
    if !has_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("thin.sdf");
    std::fs::write(
        &scene,
        "material m { color = [0.5, 0.5, 0.5]; }\nrender box([2, 0.01, 2]).paint(m);",
    )
    .unwrap();
    let out = dir.path().join("thin.glb");
    let args = [
        "bake",
        scene.to_str().unwrap(),
        "--grid",
        "16",
        "--size",
        "256",
        "--walk",
        "loop",
        "-o",
        out.to_str().unwrap(),
    ];
    let (code, _, err) = sdfc(&args);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("missed 100.0 % of the surface"), "{err}");
    assert!(err.contains("surface held:   100.0 %"), "{err}");
    if let Some(report) = gltf_validate(&out) {
        assert_eq!(
            (report.errors, report.warnings),
            (0, 0),
            "{:?}",
            report.messages
        );
    }
    // Never refined, it finds nothing, and says what would.
    let (code, _, err) = sdfc(&[&args[..], &["--refine", "1"]].concat());
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("no surface inside the bounds") && err.contains("--refine 8"),
        "{err}"
    );
}

/// A box frame 0.03 thick on cells of 0.042 (a red team's scene): the plain grid's mesh
/// is folded quads alone (each with two corners on one point), which the file leaves
/// out. Never refined, that is no surface (exit 1, before the GPU's work), not an empty
/// file that failed to encode (it had exited 5, "the mesh is empty"); refined, it bakes
/// with the folded triangles counted.
#[test]
fn a_mesh_of_folded_quads_alone_is_no_surface() {
    if !has_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("frame.sdf");
    std::fs::write(
        &scene,
        "material m { color = [0.5, 0.5, 0.5]; }\nrender box_frame([1, 1, 1], 0.03).paint(m);",
    )
    .unwrap();
    let out = dir.path().join("frame.glb");
    let args = [
        "bake",
        scene.to_str().unwrap(),
        "--grid",
        "24",
        "--size",
        "512",
        "--walk",
        "loop",
        "-o",
        out.to_str().unwrap(),
    ];
    for refine in ["1", "2"] {
        let (code, _, err) = sdfc(&[&args[..], &["--refine", refine]].concat());
        assert_eq!(code, 1, "--refine {refine}: {err}");
        assert!(
            err.contains("no surface inside the bounds") && err.contains("--refine 8"),
            "--refine {refine}: {err}"
        );
        assert!(!err.contains("shade (GPU)"), "--refine {refine}: {err}");
        assert!(!out.exists(), "--refine {refine}");
    }
    let (code, _, err) = sdfc(&args);
    assert_eq!(code, 0, "{err}");
    assert!(common::report_count(&err, "folded:") > 0, "{err}");
    let (mesh, _, _) = sdfc::bake::export::read_glb(&std::fs::read(&out).unwrap()).unwrap();
    assert!(!mesh.indices.is_empty());
}

/// The bake's memory model (`pipeline::estimated_peak_bytes`) is the formula its
/// documentation states, with each phase the largest for some bake.
#[test]
fn the_bake_memory_model_is_its_formula() {
    use sdfc::bake::pipeline::{estimated_peak_bytes, Footprint, CHANNELS, LEVEL_SAMPLE_BYTES};
    // The formula's numbers come from the code: 11 f32 channels a sample.
    assert_eq!((CHANNELS, LEVEL_SAMPLE_BYTES), (11, 44));
    let formula = |f: &Footprint| -> (u64, &str) {
        let s = f.samples;
        // The scene's textures are held while the pass lives (shade, handover, fit).
        let t = f.texture_bytes;
        let phases = [
            (80 * s + 272 * s.min(1 << 20) + t, "shade"),
            (120 * s + t, "handover"),
            // --charts' JSON: 800 bytes a cell while the outputs are encoded.
            (
                81 * s + 48 * f.texels + if f.charts_file { 800 * f.cells } else { 0 },
                "encode",
            ),
            (
                56 * s + 124 * f.fit_batch + 272 * f.fit_batch.min(1 << 20) + t,
                "fit",
            ),
        ];
        let (most, phase) = phases.into_iter().max_by_key(|p| p.0).unwrap();
        let after = 800 * f.cells + 256 * f.vertices + most;
        let mesh = 16 * f.grid_corners;
        let phase = if mesh > after { "mesh" } else { phase };
        ((128 << 20) + mesh.max(after), phase)
    };
    let sphere = |samples: u64, texels: u64| Footprint {
        grid_corners: 51 * 51 * 51,
        cells: 10746,
        vertices: 4 * 10746,
        samples,
        texels,
        fit_batch: 0,
        texture_bytes: 0,
        charts_file: false,
    };
    let cases = [
        // The one-sphere scene at --size 1024, 4096 and 16384 (flat, grid 48).
        (sphere(526_556, 1024 * 1008), "shade"),
        (sphere(10_326_908, 4096 * 4032), "encode"),
        (sphere(173_322_236, 16384 * 16128), "encode"),
        // Many samples in a small image (no such layout exists; the phase does).
        (sphere(50_000_000, 1000), "handover"),
        // The red team's sphere at --grid 256 --size 2048 with --charts (308,574 charts
        // of 4² texels; the JSON's 227 MB had been left out of the model).
        (
            Footprint {
                cells: 308_574,
                vertices: 4 * 308_574,
                charts_file: true,
                ..sphere(5_000_000, 2048 * 2048)
            },
            "encode",
        ),
        // A small bake fitting its texels (--texels fit at --size 256: all its charts
        // in one batch, three sub-texel samples a texel, outweigh its 30,000 samples).
        (
            Footprint {
                fit_batch: 90_000,
                ..sphere(30_000, 256 * 256)
            },
            "fit",
        ),
        (
            Footprint {
                grid_corners: 515 * 515 * 515,
                ..Footprint::default()
            },
            "mesh",
        ),
        // Three 8192² textures (the red team's scene at --size 128): 2.5 GiB while the
        // pass shades, which the model left out (the bake peaked at 2.9 GB, accepted).
        (
            Footprint {
                texture_bytes: sdfc::bake::export::gltf::texture_bytes(8192, 8192, 3),
                ..sphere(10_000, 128 * 128)
            },
            "shade",
        ),
    ];
    for (f, phase) in cases {
        assert_eq!(estimated_peak_bytes(&f), formula(&f).0, "{f:?}");
        assert_eq!(formula(&f).1, phase, "{f:?}");
    }
    // The figures in the report: 4096 is accepted (about 1.7 GiB), 8192 is not.
    let mib = |f: &Footprint| estimated_peak_bytes(f) >> 20;
    assert_eq!(mib(&sphere(10_326_908, 4096 * 4032)), 1700);
    assert_eq!(mib(&sphere(173_322_236, 16384 * 16128)), 25_631);
}

/// The memory check refuses what the model puts over 2 GiB, and only that.
#[test]
fn the_bake_memory_check_accepts_just_under_its_limit() {
    use sdfc::bake::pipeline::{
        check_memory, estimated_peak_bytes, BakeError, Footprint, MAX_BAKE_BYTES,
    };
    assert_eq!(MAX_BAKE_BYTES, 2 << 30);
    // The mesh grid alone, exactly at the limit and one corner past it.
    let grid = |grid_corners| Footprint {
        grid_corners,
        ..Footprint::default()
    };
    let at = (MAX_BAKE_BYTES - (128 << 20)) / 16;
    assert_eq!(estimated_peak_bytes(&grid(at)), MAX_BAKE_BYTES);
    assert_eq!(check_memory(&grid(at)).unwrap(), MAX_BAKE_BYTES);
    match check_memory(&grid(at + 1)) {
        Err(BakeError::Resource(m)) => assert!(
            m.contains("about 2049 MiB of memory")
                && m.contains("mesh grid of 125829121 corners")
                && m.contains("over the limit of 2048 MiB for a bake"),
            "{m}"
        ),
        other => panic!("{other:?}"),
    }
    // An atlas: the most samples the limit takes with a 3:2 image of as many texels.
    let atlas = |samples: u64| Footprint {
        cells: 10746,
        vertices: 4 * 10746,
        samples,
        texels: samples * 3 / 2,
        ..Footprint::default()
    };
    let (mut lo, mut hi) = (0u64, 1 << 30);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if estimated_peak_bytes(&atlas(mid)) <= MAX_BAKE_BYTES {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    assert!(check_memory(&atlas(lo)).unwrap() > MAX_BAKE_BYTES - 200);
    match check_memory(&atlas(lo + 1)) {
        Err(BakeError::Resource(m)) => assert!(
            m.contains(&format!("estimated from {} level-0 samples", lo + 1))
                && m.contains("use a smaller --size"),
            "{m}"
        ),
        other => panic!("{other:?}"),
    }
}

/// `Footprint::of` counts the level-0 samples the bake shades (each shared one once)
/// and the atlas's texels, on a real mesh and layout.
#[test]
fn the_footprint_counts_the_samples_the_bake_shades() {
    use sdfc::bake::charts::ChartTable;
    use sdfc::bake::fit::{half_count, half_points, BATCH_POINTS};
    use sdfc::bake::pipeline::{sample_points, Footprint, Texels};
    use sdfc::bake::{ChartLayout, FlatLayout, PackedLayout, Patches};
    use sdfc::reference::mesh::{dual_contour, Grid};
    let dir = tempfile::tempdir().unwrap();
    let source = "material m { color = [1, 0, 0]; }\nrender box([1, 0.5, 0.7]).paint(m);";
    let analysis = sdfc::driver::check(source, Some(dir.path()));
    let scene = analysis.scene.as_ref().expect("scene");
    let shape = sdfc::driver::pick_shape(scene, None).expect("shape");
    let grid = Grid::over(shape.root_node().bounds, 9);
    let quads = dual_contour(shape, &grid, 1e-6);
    let table = ChartTable::new(&quads);
    let singles = Patches::singles(table.len());
    for (size, m) in [(256, 1), (1024, 2)] {
        for atlas in [
            ChartLayout::Flat(FlatLayout::fit(table.len(), size).unwrap()),
            ChartLayout::Packed(PackedLayout::fit(&singles.dims, size).unwrap()),
        ] {
            let of = |texels| Footprint::of(&grid, &table, quads.vertices.len(), &atlas, m, texels);
            let f = of(Texels::Points);
            assert_eq!(f.fit_batch, 0);
            // --texels fit holds at most a batch of whole charts' sub-texel samples.
            let n = atlas.cell_size() as usize;
            let per_chart = half_points(n).len();
            assert!(per_chart > 0, "{n}² texels a chart");
            assert_eq!(half_count(n), per_chart);
            let charts = (BATCH_POINTS / per_chart).max(1).min(table.len());
            let fit = of(Texels::Fit);
            assert_eq!(fit.fit_batch, (per_chart * charts) as u64);
            assert_eq!(
                Footprint {
                    fit_batch: 0,
                    ..fit
                },
                f
            );
            let grid_points = sdfc::bake::images::vertex_grid(&quads, &table, m, &|p| p);
            let points = sample_points(&quads, &table, atlas.cell_size() as usize, &grid_points);
            let shaded = points.corners.len() + points.edges.len() + points.interiors.len();
            assert_eq!(f.samples, shaded as u64, "{size}");
            assert_eq!(f.texels, (atlas.width() * atlas.height()) as u64);
            assert_eq!(f.cells, table.len() as u64);
            assert_eq!(f.vertices, (table.len() * (m + 1) * (m + 1)) as u64);
            let [x, y, z] = grid.dims.map(|d| d as u64 + 1);
            assert_eq!(f.grid_corners, x * y * z);
        }
    }
}

/// A bake over the memory limit is refused at once, before any GPU work, with exit 5
/// and a message naming the limit and the estimate: `--size 16384` took 14 GB and
/// 147 s on a one-sphere scene before the limit.
#[test]
fn bakes_over_the_memory_limit_are_refused_before_any_work() {
    if !has_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
    for (extra, message) in [
        (&["--size", "16384"][..], "about 25632 MiB of memory"),
        (&["--size", "8192"][..], "about 6466 MiB of memory"),
        (&["--grid", "512"][..], "estimated from its mesh grid"),
    ] {
        let mut args = vec!["bake", "examples/sphere.sdf", "-o", out.to_str().unwrap()];
        args.extend(extra);
        let (code, _, err) = sdfc(&args);
        assert_eq!(code, 5, "{args:?}: {err}");
        // (An adapter with smaller textures refuses the size first, as a limit too.)
        let side = err.contains("over this GPU's limit");
        assert!(
            side || err.contains(message) && err.contains("over the limit of 2048 MiB for a bake"),
            "{args:?}: {err}"
        );
        // Refused before the shading stage: no progress past the layout.
        assert!(!err.contains("shade (GPU)"), "{err}");
        assert!(!out.exists());
    }
    // A bake under the limit runs, and its report prints the estimate: the formula
    // test's one-sphere scene at --size 1024 (`the_bake_memory_model_is_its_formula`).
    let (code, _, err) = sdfc(&[
        "bake",
        "examples/sphere.sdf",
        "--size",
        "1024",
        "--walk",
        "loop",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let expected = sdfc::bake::pipeline::estimated_peak_bytes(&sdfc::bake::pipeline::Footprint {
        grid_corners: 51 * 51 * 51,
        cells: 10746,
        vertices: 4 * 10746,
        samples: 526_556,
        texels: 1024 * 1008,
        fit_batch: 0,
        texture_bytes: 0,
        charts_file: false,
    });
    assert_eq!(expected >> 20, 323);
    assert!(
        err.contains(
            "memory:         about 323 MiB at the peak, estimated (the limit is 2048 MiB)"
        ),
        "{err}"
    );
    std::fs::remove_file(&out).unwrap();
    // The scene's textures count: three 8192² images are about 2.5 GiB while the pass
    // loads them (a small bake of such a scene peaked at 2.9 GB, accepted).
    let big = dir.path().join("big.png");
    image::GrayImage::from_pixel(8192, 8192, image::Luma([128]))
        .save(&big)
        .unwrap();
    let mut scene = String::new();
    for k in 0..3 {
        let copy = dir.path().join(format!("big{k}.png"));
        std::fs::copy(&big, &copy).unwrap();
        scene += &format!("let t{k} = image(\"big{k}.png\");\n");
    }
    scene += "material m { color = t0.sample([0.5, 0.5]).rgb * t1.sample([0.2, 0.2]).rgb + t2.sample([0.1, 0.7]).rgb; }\nrender sphere(1).paint(m);\n";
    let path = dir.path().join("textured.sdf");
    std::fs::write(&path, scene).unwrap();
    let (code, _, err) = sdfc(&[
        "bake",
        path.to_str().unwrap(),
        "--size",
        "128",
        "--grid",
        "8",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 5, "{err}");
    assert!(
        err.contains("MiB of the scene's textures") && err.contains("or smaller textures"),
        "{err}"
    );
    assert!(!err.contains("shade (GPU)") && !out.exists(), "{err}");
}

/// `sdfc bench --bake`: one bake, its report and the slowest stage, and its `--json`
/// with the refinement (waving_robot's slit: refined twice, all its surface held).
#[test]
fn bench_bake_reports_the_stages_and_the_refinement() {
    if !has_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bake.json");
    let (code, out, err) = sdfc(&[
        "bench",
        "--bake",
        "examples/waving_robot.sdf",
        "--atlas-size",
        "256",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("bake: ") && out.contains("the slowest stage"),
        "{out}"
    );
    assert!(err.contains("refined:        "), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(v["bench"], "bake");
    assert_eq!(v["refine"], 2, "{v}");
    assert!(v["refined_cells"].as_u64().unwrap() > 0, "{v}");
    assert_eq!(v["surface_missed"], 0.0, "{v}");
    let stages: Vec<&str> = v["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert!(stages.contains(&"mesh, refined"), "{stages:?}");
    assert!(!stages.contains(&"fit (GPU)"), "{stages:?}");
    assert_eq!(v["fit_samples"], 0, "{v}");
    // The memory model's estimate for this bake: in the JSON, and on the report's line.
    let peak = v["estimated_peak_bytes"].as_u64().unwrap();
    assert!((128 << 20..2 << 30).contains(&peak), "{v}");
    assert!(
        err.contains(&format!(
            "memory:         about {} MiB at the peak",
            peak >> 20
        )),
        "{err}"
    );
    // An unbounded scene bakes within --bake-bounds, and without them says which flag.
    let plane = dir.path().join("plane.sdf");
    std::fs::write(
        &plane,
        "material m { color = [1, 0, 0]; }\nrender plane([0, 1, 0], 0).paint(m);",
    )
    .unwrap();
    let bench_plane = |extra: &[&str]| {
        let mut args = vec![
            "bench",
            "--bake",
            plane.to_str().unwrap(),
            "--atlas-size",
            "128",
        ];
        args.extend_from_slice(extra);
        sdfc(&args)
    };
    let (code, _, err) = bench_plane(&[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--bake-bounds"), "{err}");
    let (code, _, err) = bench_plane(&["--bake-bounds", "-1,-1,-1", "1,1,1"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("surface held:"), "{err}");
    // Without --bake, where clap's `requires` does not hold (a flag --bake conflicts
    // with), it is refused all the same.
    // So are the bake's flags that have defaults (they ran the sweep, ignored).
    for flag in [
        &["--bake-bounds", "-1,-1,-1", "1,1,1"][..],
        &["--atlas-size", "512"],
        &["--bake-layout", "packed"],
        &["--bake-texels", "fit"],
    ] {
        let mut args = vec!["bench", "--seed-sweep"];
        args.extend_from_slice(flag);
        let (code, _, err) = sdfc(&args);
        assert_eq!(code, 2, "{flag:?}: {err}");
        assert!(
            err.contains(&format!("{} is an option of --bake", flag[0]))
                && err.contains("it needs --bake"),
            "{flag:?}: {err}"
        );
    }

    // With fitted texels: the fit's stage and its samples.
    let (code, _, err) = sdfc(&[
        "bench",
        "--bake",
        "examples/robot.sdf",
        "--atlas-size",
        "512",
        "--bake-texels",
        "fit",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("--texels fit)"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert!(v["fit_samples"].as_u64().unwrap() > 0, "{v}");
    assert!(
        v["stages"]
            .as_array()
            .unwrap()
            .iter()
            .any(|s| s["name"] == "fit (GPU)"),
        "{v}"
    );
}

/// A material the images cannot hold as such is reported, not written silently:
/// undefined values (here 1 / 0 on the whole surface) are warned about, and emission
/// over 1 (a glTF emissive texture holds 0 to 1) is carried by
/// `KHR_materials_emissive_strength`: the texture holds it divided by the strength,
/// and the file stays valid. A plain material gets neither line nor extension.
#[test]
fn undefined_and_hdr_materials_are_reported_and_hdr_emission_is_carried() {
    if !has_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let bake = |name: &str, material: &str| {
        let scene = dir.path().join(format!("{name}.sdf"));
        std::fs::write(
            &scene,
            format!("material m {{ {material} }}\nrender sphere(1).paint(m);"),
        )
        .unwrap();
        let out = dir.path().join(format!("{name}.glb"));
        let (code, _, err) = sdfc(&[
            "bake",
            scene.to_str().unwrap(),
            "--grid",
            "8",
            "--size",
            "128",
            "--walk",
            "loop",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
        (err, out)
    };
    let (err, hdr) = bake(
        "undefined",
        "color = [0.5, 0.5, 0.5] + [1, 0, 0] * (1 / (position.x * 0)); emission = [2, 0.5, 0.1];",
    );
    let samples = |what: &str| -> (usize, usize) {
        let line = err
            .lines()
            .find(|l| l.contains(what))
            .unwrap_or_else(|| panic!("{what}: {err}"));
        let words: Vec<&str> = line.split_whitespace().collect();
        let at = words.iter().position(|w| *w == "at").unwrap();
        (
            words[at + 1].parse().unwrap(),
            words[at + 4].parse().unwrap(),
        )
    };
    // Every sample: 1 / ±0 is infinite everywhere, the emission is 2 everywhere.
    let (n, of) = samples("the material is undefined");
    assert!(n == of && n > 0, "{err}");
    let (n, of) = samples("emission:       over 1");
    assert!(n == of && n > 0, "{err}");
    assert!(err.contains("up to 2:"), "{err}");
    // The strength is the largest emission, 2; the texture holds [2, 0.5, 0.1] / 2 in
    // sRGB: 255, 137 (0.25) and 63 (0.05), where clipping would give 255, 188, 89.
    let read = |glb: &std::path::Path| {
        let bytes = std::fs::read(glb).unwrap();
        let (_, textures, _) = sdfc::bake::export::read_glb(&bytes).expect("reads back");
        (bytes, textures)
    };
    let (bytes, textures) = read(&hdr);
    assert_eq!(textures.emissive_strength, 2.0);
    let emissive = textures.emissive.expect("an emissive texture");
    let texel = emissive.get_pixel(0, 0).0;
    assert_eq!(texel, [255, 137, 63, 255]);
    let text = String::from_utf8_lossy(&bytes);
    assert!(text.contains("\"extensionsUsed\":[\"KHR_materials_emissive_strength\"]"));
    assert!(!text.contains("extensionsRequired"));
    if let Some(report) = gltf_validate(&hdr) {
        assert_eq!(
            (report.errors, report.warnings),
            (0, 0),
            "the glTF-Validator reports {:?}",
            report.messages
        );
    }
    assert!(!err.contains("rounds to 0"), "{err}");
    // One very bright point dims the rest to 0 in the 8-bit texture: said.
    let (err, _) = bake(
        "spike",
        "color = [0.5, 0.5, 0.5]; emission = [1 / (position.x * position.x * position.x * position.x + 1e-12), 0, 0];",
    );
    assert!(
        err.contains("the emission rounds to 0 in the 8-bit emissive texture at"),
        "{err}"
    );
    // A computed emission below 0 on the half x < 0, and a colour over 1 on the half
    // z > 0 (a constant out of range is a compile error): clamped, and said.
    let (err, _) = bake(
        "clamped",
        "color = [0.5, 0.5, 0.5] + [1, 0, 0] * max(position.z, 0) * 2; emission = [position.x, 0, 0];",
    );
    let line = err
        .lines()
        .find(|l| l.contains("the material is out of the images' range at"))
        .unwrap_or_else(|| panic!("{err}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let at = words.iter().position(|w| *w == "at").unwrap();
    let (n, of): (usize, usize) = (
        words[at + 1].parse().unwrap(),
        words[at + 4].parse().unwrap(),
    );
    assert!(n > of / 3 && n < of, "{n} of {of}: {err}");
    let (err, plain) = bake("plain", "color = [0.5, 0.5, 0.5]; emission = [1, 0.5, 0];");
    assert!(
        !err.contains("undefined") && !err.contains("emission:") && !err.contains("range"),
        "{err}"
    );
    let (bytes, textures) = read(&plain);
    assert_eq!(textures.emissive_strength, 1.0);
    assert!(!String::from_utf8_lossy(&bytes).contains("emissive_strength"));
}
