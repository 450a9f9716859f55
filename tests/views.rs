//! The view mode and the atlas AOV's switch as pipeline constants (`codegen::views`):
//! every module declares `SCENE_VIEW` and `SCENE_ATLAS_AOV` (default -1: read from the
//! globals). `sdfc render`, the viewer and the benchmarks build one pipeline per view,
//! so that the driver compiles that view's code alone; a host that sets no constant
//! draws every view with one pipeline. Both must draw the same picture, and each view's
//! pipeline is built once, at its first frame.

use sdfc::choice::Choice;
use sdfc::codegen::{Options, WalkForm};
use sdfc::driver;
use sdfc::gpu::{gpu_for_tests, Gpu, Renderer, ViewMode};

use crate::common;

fn module(src: &str, tiles: bool) -> sdfc::codegen::Module {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let a = driver::check(src, Some(&dir));
    assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
    driver::compile(
        &a,
        &Options {
            walk: WalkForm::Loop,
            tiles,
            ..Default::default()
        },
    )
    .unwrap()
    .module
}

fn robot() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/robot.sdf");
    std::fs::read_to_string(path).unwrap()
}

#[test]
fn every_module_declares_the_view_constants_and_its_manifest_says_so() {
    let src = robot();
    let m = module(&src, false);
    assert!(m.wgsl.contains("override SCENE_VIEW: i32 = -1;"));
    assert!(m.wgsl.contains("override SCENE_ATLAS_AOV: i32 = -1;"));
    assert!(m
        .wgsl
        .contains("let view = select(i32(g.resolution.w) + opaque, SCENE_VIEW, SCENE_VIEW >= 0);"));
    let names: Vec<_> = m
        .manifest
        .pipeline_constants
        .iter()
        .map(|c| c.name)
        .collect();
    assert_eq!(names, ["SCENE_VIEW", "SCENE_ATLAS_AOV"]);
    assert!(m
        .manifest
        .pipeline_constants
        .iter()
        .all(|c| c.default == -1 && c.ty == "i32"));
    // What `sdfc compile` writes for hosts has them too, and the other languages get
    // the defaults (naga's back ends take no pipeline constants).
    let dir = tempfile::tempdir().unwrap();
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/robot.sdf");
    for (target, file) in [
        ("wgsl", "robot.wgsl"),
        ("msl", "robot.metal"),
        ("spirv", "robot.spv"),
    ] {
        let out = dir.path().join(file);
        let (code, _, err) = common::sdfc(&[
            "compile",
            scene.to_str().unwrap(),
            "--target",
            target,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{target}: {err}");
        let bytes = std::fs::read(&out).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert_eq!(
            text.contains("override SCENE_VIEW"),
            target == "wgsl",
            "{target}"
        );
    }
}

/// Draws `scene` (a host's `SceneRenderer`, no pipeline constant set) into a
/// `width` × `height` sRGB target and reads it back.
fn host_frame(gpu: &Gpu, scene: &sdfc::SceneRenderer, (width, height): (u32, u32)) -> Vec<u8> {
    let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host frame"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let row = (4 * width).div_ceil(256) * 256;
    let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("host readback"),
        size: (row * height) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let view = target.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("host"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        scene.draw(&mut pass);
    }
    encoder.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(height),
            },
        },
        target.size(),
    );
    gpu.queue.submit([encoder.finish()]);
    readback
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.unwrap());
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
    let data = readback.slice(..).get_mapped_range().unwrap();
    let mut pixels = Vec::new();
    for y in 0..height as usize {
        let start = y * row as usize;
        pixels.extend_from_slice(&data[start..start + 4 * width as usize]);
    }
    pixels
}

/// Every view (15 of them; `level` is for baked meshes), with and without the atlas
/// AOV: the runtime's pipeline per view (the constants set) draws what one pipeline
/// with the defaults draws from the globals' view, to the byte (a `Renderer` built with
/// the defaults, for the AOVs too) and within one 8-bit level against a host's
/// `SceneRenderer` (its `fs_main`); each view's pipeline is built at its first frame.
#[test]
fn every_view_draws_the_same_with_the_view_as_a_constant() {
    let Some(gpu) = gpu_for_tests() else { return };
    let src = robot();
    let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let m = module(&src, false);
    let constant = Renderer::new(&gpu, &m, &here).unwrap();
    let runtime = Renderer::new(&gpu, &m, &here).unwrap();
    runtime.set_views_from_globals(true);
    let a = driver::check(&src, Some(&here));
    let textures = sdfc::Textures::load(&a.program).unwrap();
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let host = sdfc::SceneRenderer::new(&gpu.device, &gpu.queue, &m, &textures, format).unwrap();
    let (w, h) = (48, 64);
    let mut view = common::scene_view(&a, (w, h));
    // The runtime form's one pipeline, built at its first frame and never again.
    let warm = runtime
        .frames(&gpu, &view, ViewMode::Normal, 0, 1)
        .unwrap()
        .0;
    assert!(warm.timings.pipeline_built.is_some());
    for aov in [false, true] {
        view.atlas_aov = aov;
        for &(mode, name, _) in ViewMode::CHOICES {
            if mode == ViewMode::Level {
                continue;
            }
            let a = runtime.frames(&gpu, &view, mode, 0, 1).unwrap().0;
            let first = constant.frames(&gpu, &view, mode, 0, 1).unwrap().0;
            let again = constant.frames(&gpu, &view, mode, 0, 1).unwrap().0;
            let what = format!("view {name}, atlas AOV {aov}");
            assert_eq!(a.color, first.color, "{what}: colour");
            assert_eq!(a.position, first.position, "{what}: position");
            assert_eq!(a.normal, first.normal, "{what}: normal and steps");
            if aov {
                assert_eq!(a.atlas, first.atlas, "{what}: atlas AOV");
                assert!(
                    first.atlas.iter().any(|t| t[3] == 0.0),
                    "{what}: some pixel has an atlas sample"
                );
            }
            assert_eq!(first.color, again.color, "{what}: drawn again");
            assert!(a.timings.pipeline_built.is_none(), "{what}");
            let first_is_built = mode != ViewMode::Color || aov;
            assert_eq!(
                first.timings.pipeline_built.is_some(),
                first_is_built,
                "{what}"
            );
            assert!(again.timings.pipeline_built.is_none(), "{what}");
            if !aov {
                host.set_globals(&gpu.queue, &sdfc::globals(&view, mode));
                let theirs = host_frame(&gpu, &host, (w, h));
                let worst = common::worst_byte_difference(&theirs, &first.color);
                assert!(
                    worst <= 1,
                    "{what}: the host's frame differs by {worst}/255"
                );
                let distinct: std::collections::HashSet<&[u8]> = theirs.chunks(4).collect();
                assert!(
                    mode != ViewMode::Color || distinct.len() > 100,
                    "{what}: a picture, not a clear"
                );
            }
        }
    }
}

#[test]
fn a_renderer_asked_for_a_view_builds_that_one_first() {
    let Some(gpu) = gpu_for_tests() else { return };
    let src = robot();
    let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let m = module(&src, true);
    let r = Renderer::new_for(&gpu, &m, &here, (ViewMode::Normal, false)).unwrap();
    let a = driver::check(&src, Some(&here));
    let view = common::scene_view(&a, (24, 32));
    let normal = r.frames(&gpu, &view, ViewMode::Normal, 0, 1).unwrap().0;
    assert!(normal.timings.pipeline_built.is_none());
    let color = r.frames(&gpu, &view, ViewMode::Color, 0, 1).unwrap().0;
    assert!(color.timings.pipeline_built.is_some());
    assert_ne!(normal.color, color.color);
}

#[test]
fn render_writes_the_uv_aov_it_documents() {
    // `--aov uv=FILE` was documented in `render --help` and refused by the parser.
    if gpu_for_tests().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (png, uv) = (dir.path().join("s.png"), dir.path().join("uv.exr"));
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere.sdf");
    let (code, _, err) = common::sdfc(&[
        "render",
        scene.to_str().unwrap(),
        "--size",
        "40x30",
        "-o",
        png.to_str().unwrap(),
        "--aov",
        &format!("uv={}", uv.display()),
    ]);
    assert_eq!(code, 0, "{err}");
    let exr = exr::prelude::read_first_rgba_layer_from_file(
        &uv,
        |res, _| vec![vec![[0.0f32; 3]; res.width()]; res.height()],
        |px: &mut Vec<Vec<[f32; 3]>>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y()][pos.x()] = [r, g, b]
        },
    )
    .unwrap();
    let texels: Vec<[f32; 3]> = exr
        .layer_data
        .channel_data
        .pixels
        .into_iter()
        .flatten()
        .collect();
    assert_eq!(texels.len(), 40 * 30);
    // u, v and the walk's status: 0 where the sphere's atlas reached, -1 off the surface.
    let ok: Vec<&[f32; 3]> = texels.iter().filter(|t| t[2] == 0.0).collect();
    assert!(ok.len() > 100, "{} pixels with a sample", ok.len());
    assert!(
        texels.iter().any(|t| t[2] == -1.0),
        "the background has none"
    );
    let us: Vec<f32> = ok.iter().map(|t| t[0]).collect();
    let spread =
        us.iter().cloned().fold(f32::MIN, f32::max) - us.iter().cloned().fold(f32::MAX, f32::min);
    assert!(spread > 0.1, "u varies over the sphere: {spread}");
    let (code, _, err) =
        common::sdfc(&["render", scene.to_str().unwrap(), "--aov", "albedo=x.exr"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("choose depth, normal, position, steps or uv"),
        "{err}"
    );
}
