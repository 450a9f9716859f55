//! The manifest is a contract: `sdfc compile --manifest` writes, for every example,
//! a manifest that the versioned JSON Schema in `schemas/` accepts; every binding's
//! `used_by` names exactly the entry points that reach it, so that pipelines built
//! with one bind group layout per entry point from the manifest alone build (checked
//! in wgpu on the software adapter); `fs_main` fits WebGPU's default limits. And the
//! embedding example draws what `sdfc render` draws (below).

use crate::common;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn schema() -> jsonschema::Validator {
    let text = std::fs::read_to_string("schemas/manifest.v1.json").unwrap();
    let schema: Value = serde_json::from_str(&text).unwrap();
    jsonschema::validator_for(&schema).expect("the schema is a valid JSON Schema")
}

/// The manifest `sdfc compile` writes for `scene` (loop walk).
fn manifest_of(scene: &Path) -> Value {
    manifest_with(scene, &[])
}

/// [`manifest_of`], with `extra` arguments to `sdfc compile`.
fn manifest_with(scene: &Path, extra: &[&str]) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let (wgsl, json) = (dir.path().join("m.wgsl"), dir.path().join("m.json"));
    let (wgsl, json) = (wgsl.to_str().unwrap(), json.to_str().unwrap());
    let args = ["compile", "--walk", "loop", "-o", wgsl, "--manifest", json];
    let (code, _, err) = common::sdfc(&[&args[..], extra, &[scene.to_str().unwrap()]].concat());
    assert_eq!(code, 0, "{}: {err}", scene.display());
    serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
}

fn examples() -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir("examples")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "sdf"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_example_manifest_meets_the_schema() {
    let validator = schema();
    for scene in examples() {
        let m = manifest_of(&scene);
        let errors: Vec<String> = validator
            .iter_errors(&m)
            .map(|e| format!("{e} at {}", e.instance_path()))
            .collect();
        assert!(
            errors.is_empty(),
            "{}: {}",
            scene.display(),
            errors.join("\n")
        );
        // The scene's own values are there: nine globals, bounds, a far distance that
        // reaches across them from the camera.
        let scene_values = &m["scene"];
        assert_eq!(
            scene_values["globals"].as_array().unwrap().len(),
            9,
            "{}",
            scene.display()
        );
        let far = scene_values["globals"][8][0].as_f64().unwrap();
        assert!(far > 0.0, "{}: far {far}", scene.display());
    }
}

#[test]
fn a_module_with_the_multiscale_pass_states_its_contract() {
    use sdfc::codegen::coarse;
    let m = manifest_with(Path::new("examples/robot.sdf"), &["--multiscale"]);
    let errors: Vec<String> = schema().iter_errors(&m).map(|e| e.to_string()).collect();
    assert!(errors.is_empty(), "{}", errors.join("\n"));
    let c = &m["coarse"];
    assert_eq!(c["entry_point"], "cs_coarse");
    assert_eq!(c["step"], coarse::STEP);
    let slots = c["slots"].as_u64().unwrap();
    assert!(slots >= 1, "{c}");
    assert_eq!(c["vec4s_per_sample"].as_u64().unwrap(), 1 + 4 * slots);
    let side = coarse::WORKGROUP_SIDE;
    assert_eq!(c["workgroup_size"], serde_json::json!([side, side, 1]));
    // The entry point and the binding the contract names are the module's.
    let ep = m["entry_points"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["name"] == "cs_coarse")
        .expect("cs_coarse among the entry points");
    assert_eq!(ep["workgroup_size"], c["workgroup_size"]);
    let b = m["bindings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["name"] == "coarse")
        .expect("the coarse binding");
    assert_eq!(
        (&b["group"], &b["binding"]),
        (&serde_json::json!(0), &c["binding"])
    );
    assert_eq!(b["kind"], "storage-read-write");
    for user in ["fs_main", "cs_coarse"] {
        assert!(
            b["used_by"].as_array().unwrap().iter().any(|u| u == user),
            "{b}"
        );
    }
    // The steps in words give the runtime's grid, buffer and dispatch at any size.
    let step = coarse::STEP;
    for (w, h) in [
        (1, 1),
        (2, 3),
        (5, 4),
        (160, 90),
        (641, 479),
        (1920, 1080),
        (3840, 2160),
    ] {
        let axis = |n: u32| (n.max(1) + step - 2) / step + 1;
        let (columns, rows) = (axis(w), axis(h));
        assert_eq!((columns, rows), coarse::grid(w, h), "{w}x{h}");
        let bytes = columns as u64 * rows as u64 * (1 + 4 * slots) * 16;
        assert_eq!(bytes, coarse::buffer_bytes(w, h, slots as usize), "{w}x{h}");
        assert_eq!(
            (columns.div_ceil(side), rows.div_ceil(side)),
            coarse::workgroups(w, h),
            "{w}x{h}"
        );
        // The pass covers every pixel: the last column and row reach the frame's edge.
        assert!((columns - 1) * step >= w - 1 && (rows - 1) * step >= h - 1);
    }
    // Without --multiscale, or for a scene whose materials read no atlas: no pass.
    for (scene, extra) in [
        ("examples/robot.sdf", &[][..]),
        ("examples/primitives.sdf", &["--multiscale"][..]),
    ] {
        let m = manifest_with(Path::new(scene), extra);
        assert!(m.get("coarse").is_none(), "{scene} {extra:?}");
        let names: Vec<&str> = m["entry_points"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["name"].as_str().unwrap())
            .collect();
        assert!(
            !names.contains(&"cs_coarse"),
            "{scene} {extra:?}: {names:?}"
        );
    }
}

#[test]
fn the_schema_rejects_what_breaks_the_contract() {
    let validator = schema();
    let m = manifest_of(Path::new("examples/sphere.sdf"));
    assert!(validator.is_valid(&m));
    let mut wrong = m.clone();
    wrong["version"] = Value::from(2);
    assert!(
        !validator.is_valid(&wrong),
        "a version 2 manifest passed the version 1 schema"
    );
    let mut wrong = m.clone();
    wrong["bindings"][0]["used_by"] = serde_json::json!(["fs_nowhere"]);
    assert!(!validator.is_valid(&wrong), "an unknown entry point passed");
    let mut wrong = m;
    wrong["unexplained"] = Value::from(1);
    assert!(
        !validator.is_valid(&wrong),
        "a field the schema does not describe passed"
    );
}

#[test]
fn a_displacement_texture_is_used_by_the_compute_entry_points_that_evaluate_the_scene() {
    // The case: the height inside `scene_map` samples its texture, so cs_points
    // and cs_grid use it too. The users are exact, not a superset: a texture only a
    // material reads (the column's bricks) is not used by them.
    let users = |b: &Value| -> Vec<String> {
        b["used_by"]
            .as_array()
            .unwrap()
            .iter()
            .map(|u| u.as_str().unwrap().to_string())
            .collect()
    };
    for name in ["displaced_column", "displaced_sphere", "fit_blob"] {
        let m = manifest_of(&Path::new("examples").join(format!("{name}.sdf")));
        let textures: Vec<&Value> = m["bindings"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|b| b["kind"] == "texture-2d")
            .collect();
        let height = textures
            .iter()
            .find(|b| users(b).contains(&"cs_points".to_string()))
            .unwrap_or_else(|| panic!("{name}: no texture is used by cs_points"));
        for ep in [
            "cs_points",
            "cs_grid",
            "cs_material",
            "cs_bake",
            "fs_main",
            "fs_aov",
        ] {
            assert!(
                users(height).contains(&ep.to_string()),
                "{name}: {} not used by {ep}",
                height["name"]
            );
        }
        if name == "displaced_column" {
            let material_only = textures
                .iter()
                .filter(|b| !users(b).contains(&"cs_points".to_string()))
                .count();
            assert!(
                material_only > 0,
                "displaced_column: every texture is listed for cs_points"
            );
        }
    }
}

#[test]
fn fs_main_fits_webgpu_default_limits() {
    let m = manifest_of(Path::new("examples/capsule.sdf"));
    let targets = m["render_targets"].as_array().unwrap();
    let main = targets.iter().find(|t| t["entry"] == "fs_main").unwrap();
    assert_eq!(main["formats"], serde_json::json!(["rgba8unorm-srgb"]));
    // WebGPU's default maxColorAttachmentBytesPerSample.
    assert!(main["bytes_per_sample"].as_u64().unwrap() <= 32);
    let aov = targets.iter().find(|t| t["entry"] == "fs_aov").unwrap();
    assert_eq!(
        aov["bytes_per_sample"], 56,
        "rgba8unorm-srgb (8) and three rgba32float (16 each)"
    );
}

/// One bind group layout per group from the manifest's bindings that name `entry`.
fn layouts(device: &wgpu::Device, m: &Value, entry: &str) -> Vec<wgpu::BindGroupLayout> {
    let visibility = match entry {
        "vs_main" | "fs_main" | "fs_aov" => wgpu::ShaderStages::VERTEX_FRAGMENT,
        _ => wgpu::ShaderStages::COMPUTE,
    };
    let mut groups: Vec<Vec<wgpu::BindGroupLayoutEntry>> = vec![Vec::new(), Vec::new()];
    // WebGPU: a writable storage buffer is not visible to the vertex stage.
    let writable = match visibility {
        wgpu::ShaderStages::VERTEX_FRAGMENT => wgpu::ShaderStages::FRAGMENT,
        v => v,
    };
    for b in m["bindings"].as_array().unwrap() {
        let users = b["used_by"].as_array().unwrap();
        if !users.iter().any(|u| u == entry) {
            continue;
        }
        let ty = match b["kind"].as_str().unwrap() {
            "uniform" => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            "storage-read" | "storage-read-write" => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage {
                    read_only: b["kind"] == "storage-read",
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            "texture-2d" => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            _ => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        };
        let group = b["group"].as_u64().unwrap() as usize;
        groups[group].push(wgpu::BindGroupLayoutEntry {
            binding: b["binding"].as_u64().unwrap() as u32,
            visibility: if b["kind"] == "storage-read-write" {
                writable
            } else {
                visibility
            },
            ty,
            count: None,
        });
    }
    groups
        .iter()
        .map(|entries| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: None,
                entries,
            })
        })
        .collect()
}

#[test]
fn pipelines_build_with_layouts_from_the_manifest_users_alone() {
    let Some(gpu) = sdfc::gpu::gpu_for_tests() else {
        return;
    };
    let device = &gpu.device;
    // The examples with textures, tables (seed grids, large unions) and displacement.
    // The robot also with the multi-scale pass: cs_coarse and the coarse binding.
    for (name, multiscale) in [
        ("displaced_column", false),
        ("fit_blob", false),
        ("robot", false),
        ("robot", true),
        ("normal_map", false),
        ("shell_tiles", false),
    ] {
        let scene = Path::new("examples").join(format!("{name}.sdf"));
        let m = manifest_with(&scene, if multiscale { &["--multiscale"] } else { &[] });
        assert_eq!(m.get("coarse").is_some(), multiscale, "{name}");
        let source = std::fs::read_to_string(&scene).unwrap();
        let analysis = sdfc::check(&source, scene.parent());
        let options = sdfc::Options {
            walk: sdfc::WalkForm::Loop,
            multiscale,
            ..Default::default()
        };
        let wgsl = sdfc::compile(&analysis, &options).unwrap().module.wgsl;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(name),
            source: wgpu::ShaderSource::Wgsl(wgsl.into()),
        });
        for ep in m["entry_points"].as_array().unwrap() {
            let entry = ep["name"].as_str().unwrap();
            if ep["stage"] != "compute" && entry != "fs_main" {
                continue;
            }
            let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
            let groups = layouts(
                device,
                &m,
                if entry == "fs_main" { "fs_main" } else { entry },
            );
            let refs: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(Some).collect();
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &refs,
                immediate_size: 0,
            });
            if entry == "fs_main" {
                let _pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: None,
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_main"),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::TextureFormat::Rgba8UnormSrgb.into())],
                    }),
                    primitive: Default::default(),
                    depth_stencil: None,
                    multisample: Default::default(),
                    multiview_mask: None,
                    cache: None,
                });
            } else {
                let _pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: None,
                    layout: Some(&layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                });
            }
            let error = pollster::block_on(scope.pop());
            assert!(error.is_none(), "{name} {entry}: {error:?}");
        }
    }
}

// ---- Embedding in a host's own wgpu program.
// Embedding in a host's own wgpu program: `examples/embed.rs` compiles a scene, draws
// it with its own device, queue and encoder through `sdfc::SceneRenderer`, and writes
// a PNG that equals `sdfc render` of the same scene at the same size (`fs_main` and
// `fs_aov` shade the same colour). `cargo test` builds the example beside the binary.
fn example() -> PathBuf {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_sdfc"));
    let exe = bin
        .parent()
        .unwrap()
        .join("examples")
        .join(format!("embed{}", std::env::consts::EXE_SUFFIX));
    assert!(
        exe.exists(),
        "{} is missing: `cargo test` builds the examples (not with a --test filter alone; \
         run `cargo build --release --examples` first)",
        exe.display()
    );
    exe
}

fn decode(path: &std::path::Path) -> image::RgbaImage {
    image::open(path).unwrap().to_rgba8()
}

/// The embedding example's frame of `scene` at `size`, with `extra` arguments.
fn embedded(dir: &Path, scene: &str, size: &str, extra: &[&str]) -> image::RgbaImage {
    let path = dir.join("embed.png");
    let out = Command::new(example())
        .args([scene, path.to_str().unwrap(), size])
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{scene}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    decode(&path)
}

/// `sdfc render` of `scene` as the example compiles it (loop walk, and forward
/// gradients: the library's default).
fn rendered(dir: &Path, scene: &str, size: &str, extra: &[&str]) -> image::RgbaImage {
    common::render_as_library(scene, size, extra, &dir.join("ref.png"))
}

#[test]
fn the_embedding_example_runs_the_multiscale_pass_as_sdfc_render_does() {
    if sdfc::gpu::gpu_for_tests().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (scene, size) = ("examples/sphere.sdf", "320x240");
    let mine = embedded(dir.path(), scene, size, &["--multiscale"]);
    let with = rendered(dir.path(), scene, size, &["--multiscale", "on"]);
    let without = rendered(dir.path(), scene, size, &["--multiscale", "off"]);
    // The pass changes some pixels (rebuilt uv near checker edges), so a host that did
    // not run it would draw `without`.
    let changed = |a: &image::RgbaImage, b: &image::RgbaImage| {
        a.pixels()
            .zip(b.pixels())
            .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 1))
            .count()
    };
    assert!(
        changed(&with, &without) > 0,
        "the pass changed nothing here"
    );
    let worst = common::worst_byte_difference(mine.as_raw(), with.as_raw());
    assert!(
        worst <= 1,
        "embedded with the pass against render: up to {worst}/255"
    );
    assert_eq!(changed(&mine, &with), 0);
}

#[test]
fn the_embedding_example_draws_what_sdfc_render_draws() {
    if sdfc::gpu::gpu_for_tests().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for scene in ["examples/capsule.sdf", "examples/displaced_column.sdf"] {
        let a = embedded(dir.path(), scene, "96x72", &[]);
        let b = rendered(dir.path(), scene, "96x72", &[]);
        assert_eq!(a.dimensions(), b.dimensions());
        // A picture, not a cleared target: the shape's shading has many colours.
        let colours: std::collections::HashSet<[u8; 4]> = a.pixels().map(|p| p.0).collect();
        assert!(
            colours.len() > 200,
            "{scene}: only {} colours",
            colours.len()
        );
        let worst = common::worst_byte_difference(a.as_raw(), b.as_raw());
        // The same shader on the same adapter: equal to within one level of 8 bits.
        assert!(worst <= 1, "{scene}: pixels differ by up to {worst}/255");
    }
}
