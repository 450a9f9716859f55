//! The manifest is a contract: `sdfc compile --manifest` writes, for every example,
//! a manifest that the versioned JSON Schema in `schemas/` accepts; every binding's
//! `used_by` names exactly the entry points that reach it, so that pipelines built
//! with one bind group layout per entry point from the manifest alone build (checked
//! in wgpu on the software adapter); `fs_main` fits WebGPU's default limits. And the
//! embedding example draws what `sdfc render` draws (below).

mod common;

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
    let dir = tempfile::tempdir().unwrap();
    let (wgsl, json) = (dir.path().join("m.wgsl"), dir.path().join("m.json"));
    let (wgsl, json) = (wgsl.to_str().unwrap(), json.to_str().unwrap());
    let args = ["compile", "--walk", "loop", "-o", wgsl, "--manifest", json];
    let (code, _, err) = common::sdfc(&[&args[..], &[scene.to_str().unwrap()]].concat());
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
            visibility,
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
    for name in [
        "displaced_column",
        "fit_blob",
        "robot",
        "normal_map",
        "shell_tiles",
    ] {
        let scene = Path::new("examples").join(format!("{name}.sdf"));
        let m = manifest_of(&scene);
        let source = std::fs::read_to_string(&scene).unwrap();
        let analysis = sdfc::check(&source, scene.parent());
        let options = sdfc::Options {
            walk: sdfc::WalkForm::Loop,
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

#[test]
fn the_embedding_example_draws_what_sdfc_render_draws() {
    if sdfc::gpu::gpu_for_tests().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for scene in ["examples/capsule.sdf", "examples/displaced_column.sdf"] {
        let (mine, reference) = (dir.path().join("embed.png"), dir.path().join("ref.png"));
        let out = Command::new(example())
            .args([scene, mine.to_str().unwrap(), "96x72"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{scene}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let reference_path = reference.to_str().unwrap();
        let args = [
            "render",
            scene,
            "--walk",
            "loop",
            // The library's default, as the example compiles it.
            "--gradients",
            "forward",
            "--size",
            "96x72",
            "-o",
            reference_path,
        ];
        let (code, _, err) = common::sdfc(&args);
        assert_eq!(code, 0, "{scene}: {err}");
        let (a, b) = (decode(&mine), decode(&reference));
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
