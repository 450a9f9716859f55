//! `sdfc bake` end to end: every example bakes, the Khronos glTF-Validator finds
//! nothing to report, the written files keep border texels identical at every level,
//! and bad input gets a clear message, the documented exit status and no file.
//! GPU tests skip loudly without an adapter unless SDFC_REQUIRE_GPU=1.

mod common;

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
        if ["blend", "primitives"].contains(&stem.as_str()) {
            args.extend(["--bounds", "-3,-1,-3", "3,2,3"]);
        }
        // The plates are 0.2 thick and 16 wide: an 8-cell grid falls through them, so
        // bake a corner of each at a finer grid.
        let plate = stem.starts_with("plate");
        if plate {
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
        let (mut code, _, mut err) = sdfc(&args);
        // Other examples on a ground plane: the message names --bounds; bake the
        // region above the floor, as a user would.
        if code == 2 && err.contains("no finite bounds") {
            args.extend(["--bounds", "-3,-1,-3", "3,3,3"]);
            (code, _, err) = sdfc(&args);
        }
        assert_eq!(code, 0, "{stem}: {err}");
        assert!(
            err.contains("utilisation:") && err.contains("shade (GPU)"),
            "{stem}: {err}"
        );
        if let Some(report) = gltf_validate(&glb) {
            assert_eq!(
                (report.errors, report.warnings),
                (0, 0),
                "{stem}: the glTF-Validator reports {:?}",
                report.messages
            );
        }
        let (mesh, textures, layout) =
            sdfc::bake::export::read_glb(&std::fs::read(&glb).unwrap()).expect("reads back");
        assert!(mesh.indices.len() >= 3 * 2 * 8, "{stem}");
        let file: ChartsFile = serde_json::from_slice(&std::fs::read(&charts).unwrap()).unwrap();
        assert_eq!(file.layout, layout, "{stem}");
        let cells = match &layout {
            sdfc::bake::Atlas::Flat(_) => file.charts.len(),
            sdfc::bake::Atlas::Packed(p) => p
                .charts
                .iter()
                .map(|c| (c.cells[0] * c.cells[1]) as usize)
                .sum(),
        };
        assert_eq!(
            cells * 6,
            mesh.indices.len(),
            "{stem}: two triangles per cell"
        );
        if packed {
            assert!(matches!(layout, sdfc::bake::Atlas::Packed(_)), "{stem}");
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
            let png = dir.path().join("sphere-mesh.png");
            let (code, _, err) = sdfc(&[
                "render",
                glb.to_str().unwrap(),
                "--camera-from",
                example.to_str().unwrap(),
                "--size",
                "64x48",
                "-o",
                png.to_str().unwrap(),
            ]);
            assert_eq!(code, 0, "{err}");
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
    let cases: Vec<(Vec<&str>, i32, &str)> = vec![
        (vec![&plain], 1, "no material"),
        (vec![&plane], 2, "--bounds"),
        (
            vec![&plane, "--bounds", "-1,2,-1", "1,3,1"],
            1,
            "no surface inside the bounds",
        ),
        (
            vec![&plane, "--bounds", "1,1,1", "-1,-1,-1"],
            2,
            "must be below",
        ),
        (vec![&sphere, "--size", "300"], 2, "power of two"),
        (vec![&sphere, "--grid", "1"], 2, "cells"),
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
        ["folder.glb", "plain.sdf", "plane.sdf", "sphere.sdf"]
    );
}
