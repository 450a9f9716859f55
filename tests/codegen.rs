//! Code generation: the WGSL library, every example at every target, snapshots of
//! the generated scene code, the manifest, and `sdfc compile`.

use sdfc::codegen::{self, targets::Output, Target};
use sdfc::driver::analyze;
use sdfc::ir;
use std::path::Path;

fn generate(src: &str, dir: Option<&Path>) -> Result<codegen::Module, Vec<sdfc::Diagnostic>> {
    let a = analyze(src, dir);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    codegen::generate(&a.program, &ir::lower(&a.program), None)
}

#[test]
fn library_files_validate_on_their_own() {
    for (name, text) in [
        ("sdf.wgsl", codegen::SDF_LIBRARY),
        ("render.wgsl", codegen::RENDER_LIBRARY),
    ] {
        if let Err(e) = codegen::validate(text) {
            panic!("shaders/{name} does not validate:\n{e}");
        }
    }
}

fn every_target(name: &str, module: &codegen::Module) {
    let v = codegen::validate(&module.wgsl)
        .unwrap_or_else(|e| panic!("{name}: naga rejects the generated WGSL:\n{e}"));
    for target in [Target::Wgsl, Target::Spirv, Target::Msl] {
        match codegen::translate(&v, &module.wgsl, target, "") {
            Ok(Output::Text(t)) => assert!(!t.is_empty()),
            Ok(Output::Binary(b)) => {
                assert_eq!(&b[..4], &0x0723_0203u32.to_le_bytes(), "{name}: not SPIR-V")
            }
            Err(e) => panic!("{name}: {target:?}: {e}"),
        }
    }
    for entry in ["vs_main", "fs_main", "cs_points", "cs_grid"] {
        if let Err(e) = codegen::translate(&v, &module.wgsl, Target::Glsl, entry) {
            panic!("{name}: GLSL {entry}: {e}");
        }
    }
}

/// Every example compiles, validates and translates to all four targets.
#[test]
fn every_example_compiles_at_every_target() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut compiled = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "sdf") {
            continue;
        }
        let src = std::fs::read_to_string(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let module = generate(&src, Some(&dir)).unwrap_or_else(|d| panic!("{name}: {d:?}"));
        every_target(&name, &module);
        compiled += 1;
    }
    assert!(compiled >= 5, "only {compiled} examples");
}

/// The scene part of a module (after the shared library), for snapshots.
fn scene_part(m: &codegen::Module) -> String {
    let start = m.wgsl.find("// ---- scene ----").unwrap();
    let end = m.wgsl.find("struct Material {").unwrap();
    m.wgsl[start..end].to_string()
}

#[test]
fn wgsl_snapshots() {
    let cases = [
        ("sphere", "render sphere(0.5);"),
        ("csg_materials", "material red { color = [1, 0, 0]; } material blue { color = [0, 0, 1]; roughness = 0.2; }\nlet a = sphere(1).paint(red);\nrender smooth_union(a, box([1, 2, 1]).translate([1, 0, 0]).paint(blue), 0.2) - cylinder(0.2, 4);"),
        ("warps", "let t = box([1, 2, 1]).twist(rate: 0.5);\nrender t.rotate(axis: [1, 1, 0], angle: 30deg).repeat([4, 4, 4]).scale([1, 2, 1]);"),
        ("fields", "material m { color = mix([1, 1, 1], 0.5 + 0.5 * normal, checker(position.xz, 4)); roughness = clamp(position.y, 0, 1); }\nrender sphere(1).paint(m);"),
    ];
    for (name, src) in cases {
        let m = generate(src, None).unwrap();
        every_target(name, &m);
        insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false, omit_expression => true, description => src }, {
            insta::assert_snapshot!(format!("wgsl_{name}"), scene_part(&m));
        });
    }
}

#[test]
fn manifest_describes_bindings_and_textures() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let m = generate(
        "let t = image(\"textures/bricks.png\");\nmaterial m { color = t.sample(position.xz, wrap: \"mirror\"); }\nrender sphere(1).paint(m);",
        Some(&dir),
    )
    .unwrap();
    every_target("textured", &m);
    assert_eq!(m.manifest.textures.len(), 1);
    assert_eq!(m.manifest.textures[0].path, "textures/bricks.png");
    assert_eq!(m.manifest.textures[0].wrap, "mirror");
    let kinds: Vec<(u32, u32, &str)> = m
        .manifest
        .bindings
        .iter()
        .map(|b| (b.group, b.binding, b.kind))
        .collect();
    assert_eq!(
        kinds,
        vec![
            (0, 0, "uniform"),
            (0, 1, "texture-2d"),
            (0, 2, "sampler"),
            (1, 0, "uniform"),
            (1, 1, "storage-read"),
            (1, 2, "storage-read-write")
        ]
    );
    // The header comment documents the same bindings.
    for b in &m.manifest.bindings {
        assert!(
            m.wgsl.contains(&format!(
                "@group({}) @binding({}) {} {}",
                b.group, b.binding, b.kind, b.name
            )),
            "header lacks {}",
            b.name
        );
    }
    assert_eq!(m.manifest.globals_layout.len(), 9);
}

#[test]
fn lipschitz_bound_reaches_the_shader() {
    let m = generate("render box(1).twist(rate: 2);", None).unwrap();
    let l = m.manifest.lipschitz;
    assert!(l > 1.5, "{l}");
    assert!(m.wgsl.contains(&format!(
        "const SCENE_LIPSCHITZ: f32 = {};",
        codegen::lit(l)
    )));
}

mod common;
use common::sdfc;

#[test]
fn compile_command_writes_every_target() {
    let dir = tempfile::tempdir().unwrap();
    for (target, file) in [
        ("wgsl", "out.wgsl"),
        ("spirv", "out.spv"),
        ("glsl", "out.glsl"),
        ("msl", "out.metal"),
    ] {
        let out = dir.path().join(file);
        let manifest = dir.path().join(format!("{file}.json"));
        let (code, _, err) = sdfc(&[
            "compile",
            "examples/warps.sdf",
            "--target",
            target,
            "-o",
            out.to_str().unwrap(),
            "--manifest",
            manifest.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{target}: {err}");
        assert!(std::fs::metadata(&out).unwrap().len() > 1000);
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap();
        assert_eq!(m["entry_points"][1][0], "fs_main");
    }
    // No stray temporary files are left beside the outputs.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 8);
    let (code, stdout, _) = sdfc(&["compile", "examples/warps.sdf"]);
    assert_eq!(code, 0);
    assert!(stdout.contains("fn sdf_twisted(p: vec3<f32>) -> f32"));
    assert_eq!(
        sdfc(&["compile", "examples/warps.sdf", "--target", "spirv"]).0,
        2
    );
    assert_eq!(sdfc(&["compile", "tests/ui/unknown_name.sdf"]).0, 1);
    // A seed on a hole's axis has no gradient to project along.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.sdf");
    std::fs::write(&bad, "let s = sphere(1) - cylinder(0.2, 4);\natlas a on s { seed x = [0, 0.5, 0]; }\nmaterial m { color = [a.uv, 0]; }\nrender s.paint(m);").unwrap();
    let (code, _, err) = sdfc(&["compile", bad.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(
        err.contains("E0401") && err.contains("seed `x` cannot be projected"),
        "{err}"
    );
}

#[test]
fn naga_rejection_is_an_internal_compiler_error_with_the_wgsl_saved() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .args(["compile", "examples/warps.sdf"])
        .env("SDFC_TEST_CORRUPT_WGSL", "1")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("error[E0900]: internal compiler error: naga rejected the generated WGSL"),
        "{err}"
    );
    let saved = err
        .lines()
        .find_map(|l| l.strip_prefix("note: the generated WGSL is saved at "))
        .and_then(|l| l.split(';').next())
        .expect("the path of the saved WGSL");
    let text = std::fs::read_to_string(saved).unwrap();
    assert!(text.contains("fn sdf_twisted") && text.contains("fn corrupted( {"));
    let _ = std::fs::remove_file(saved);
}

/// naga's rejection of code generated from a scene definition is reported on that
/// definition's span in the scene, not on a WGSL line.
#[test]
fn naga_rejection_points_at_the_scene_definition() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .args(["compile", "examples/plate.sdf"])
        .env("SDFC_TEST_CORRUPT_WGSL", "material")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    let src = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/plate.sdf"),
    )
    .unwrap();
    let line = src
        .lines()
        .position(|l| l.starts_with("material tiled"))
        .unwrap()
        + 1;
    assert!(
        err.contains(&format!("┌─ examples/plate.sdf:{line}:1")),
        "{err}"
    );
    assert!(
        err.contains("naga rejected the WGSL generated for material `tiled`"),
        "{err}"
    );
    assert!(
        err.contains("note: the generated WGSL is saved at"),
        "{err}"
    );
    if let Some(saved) = err
        .lines()
        .find_map(|l| l.strip_prefix("note: the generated WGSL is saved at "))
        .and_then(|l| l.split(';').next())
    {
        let _ = std::fs::remove_file(saved);
    }
}
