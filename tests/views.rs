//! The view mode and the atlas AOV's switch as pipeline constants (`codegen::views`,
//! `Options::view_constants`): `sdfc render`, the viewer and the benchmarks build one
//! pipeline per view, so that the driver compiles that view's code alone. Every view
//! must draw the same picture, to the byte, as the module that reads the view from its
//! globals (what `compile` and `export-web` write for hosts), and each view's pipeline
//! is built once, at its first frame.

use sdfc::choice::Choice;
use sdfc::codegen::{Options, WalkForm};
use sdfc::driver;
use sdfc::gpu::{gpu_for_tests, Renderer, ViewMode};

mod common;

fn module(src: &str, view_constants: bool) -> sdfc::codegen::Module {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let a = driver::check(src, Some(&dir));
    assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
    driver::compile(
        &a,
        &Options {
            walk: WalkForm::Loop,
            tiles: true,
            view_constants,
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
fn only_a_module_asked_for_them_has_the_view_constants() {
    let src = robot();
    let runtime = module(&src, false);
    assert!(!runtime.view_constants);
    assert!(!runtime.wgsl.contains("override SCENE_VIEW"));
    assert!(runtime
        .wgsl
        .contains("let view = i32(g.resolution.w) + opaque;"));
    let constant = module(&src, true);
    assert!(constant.view_constants);
    assert!(constant.wgsl.contains("override SCENE_VIEW: i32 = 0;"));
    assert!(constant
        .wgsl
        .contains("override SCENE_ATLAS_AOV: bool = false;"));
    assert!(constant.wgsl.contains("let view = SCENE_VIEW;"));
    // Neither the view nor the AOV switch is read from the globals any more.
    assert!(!constant.wgsl.contains("g.resolution.w"));
    assert!(!constant.wgsl.contains("g.camera_forward.w"));
    // What a host gets is unchanged: `sdfc compile` leaves them out.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("robot.wgsl");
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/robot.sdf");
    let (code, _, err) = common::sdfc(&[
        "compile",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!std::fs::read_to_string(&out).unwrap().contains("override"));
}

#[test]
fn every_view_draws_the_same_with_the_view_as_a_constant() {
    let Some(gpu) = gpu_for_tests() else { return };
    let src = robot();
    let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let runtime = Renderer::new(&gpu, &module(&src, false), &here).unwrap();
    let constant = Renderer::new(&gpu, &module(&src, true), &here).unwrap();
    let a = driver::check(&src, Some(&here));
    let mut view = common::scene_view(&a, (48, 64));
    for aov in [false, true] {
        view.atlas_aov = aov;
        for &(mode, name, _) in ViewMode::CHOICES {
            if mode == ViewMode::Level {
                // Baked meshes only.
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
            // One pipeline for every view where the globals hold it; else each view's
            // own, built at its first frame (the renderer's first is colour, no AOV).
            assert!(a.timings.pipeline_built.is_none(), "{what}");
            let first_is_built = mode != ViewMode::Color || aov;
            assert_eq!(
                first.timings.pipeline_built.is_some(),
                first_is_built,
                "{what}"
            );
            assert!(again.timings.pipeline_built.is_none(), "{what}");
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
