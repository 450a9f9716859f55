//! Atlases on moving shapes: an atlas whose own shape depends on a run-time parameter
//! has its geometry (seed projections, frames, merge walks, offsets, σ) recomputed on
//! the CPU when the parameter changes, and uploaded to the `tables` buffer, never by
//! compiling again. The oracle is the scene compiled at that value: the same atlas on
//! the CPU, and the same picture on the GPU, from one pipeline.

use glam::DVec3;
use sdfc::access::Access;
use sdfc::gpu::{gpu_for_tests, Renderer, ViewMode};
use sdfc::view::View;

use crate::common;

/// An ellipsoid whose x radius is a parameter, with a merged atlas of three seeds on it
/// (front, the right side, the top), textured by a checker on its uv.
const SCENE: &str = "param w = 1.2 in [0.8, 1.6];
let body = ellipsoid([w, 0.8, 0.7]);
atlas skin on body {
    steps = 16;
    max_distance = 2;
    seed front = [0.1, 0.1, 0.7] tangent [1, 0, 0];
    seed side = [1.2, 0.1, 0];
    seed top = [0, 0.8, 0.1];
    merge front side;
    merge front top;
}
material m { color = mix([0.9, 0.8, 0.2], [0.1, 0.2, 0.6], checker(skin.uv, 8)); }
render body.paint(m) {
    camera = orbit(target: [0, 0, 0], distance: 3.2, yaw: 35deg, pitch: 25deg);
    size = [128, 96];
}
";

const ENDS: [f64; 2] = [0.8, 1.6];

fn analyze(w: Option<f64>) -> sdfc::driver::Analysis {
    let mut access = Access::new(None);
    if let Some(w) = w {
        access.set_param("w", &[w]);
    }
    let a = sdfc::driver::check_all_with(SCENE, &access);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    a
}

fn module(a: &sdfc::driver::Analysis) -> sdfc::Module {
    a.compiled.as_ref().expect("a module").module.clone()
}

#[test]
fn the_recomputed_atlas_equals_the_atlas_compiled_at_the_value() {
    let base = module(&analyze(None));
    assert_eq!(base.moving.len(), 1, "the atlas's shape moves");
    // The key of recomputation reads the parameters the shape reads, nothing else.
    let key = |w: Option<f64>, t: Option<f64>| {
        base.moving_key(&|n| match n {
            "w" => w.map(|w| vec![w]),
            "time" => t.map(|t| vec![t]),
            _ => None,
        })
    };
    assert_eq!(key(None, None), key(None, Some(3.0)));
    assert_ne!(key(None, None), key(Some(0.8), None));
    for w in ENDS {
        let at = analyze(Some(w));
        let compiled = at.atlases[0].as_ref().unwrap();
        let recomputed = base.moving[0]
            .at_params(&|n| (n == "w").then(|| vec![w]))
            .unwrap();
        for (a, b) in recomputed.seeds.iter().zip(&compiled.seeds) {
            assert!((a.seed.p - b.seed.p).length() < 1e-9, "w = {w}: seed moved");
            assert!((a.offset - b.offset).length() < 1e-9, "w = {w}: offset");
        }
        assert!((recomputed.sigma - compiled.sigma).abs() < 1e-9);
        // The side seed moved with the surface.
        let before = base.moving[0].atlas.seeds[1].seed.p;
        assert!(
            (recomputed.seeds[1].seed.p - before).length() > 0.1,
            "w = {w}"
        );
        let shape = at.scene.as_ref().unwrap().render.clone().unwrap();
        let mut worst = 0.0f64;
        for (x, _) in common::surface_points(&shape, 200, 3, |_| true) {
            let (s, t) = (recomputed.sample(x), compiled.sample(x));
            assert_eq!(s.status, t.status, "w = {w}: at {x}");
            worst = worst.max((s.uv - t.uv).length());
        }
        assert!(worst <= 1e-5, "w = {w}: the uv differ by {worst}");
        // And the module's words are the compiled module's.
        let words = base.tables_at(&|n| (n == "w").then(|| vec![w])).unwrap();
        let compiled_words = &module(&at).manifest.tables;
        assert_eq!(words.len(), compiled_words.len());
        for (a, b) in words.iter().zip(compiled_words) {
            let (x, y) = (f32::from_bits(*a), f32::from_bits(*b));
            assert!(a == b || (x - y).abs() <= 1e-6, "w = {w}: {x} against {y}");
        }
    }
}

#[test]
fn a_slider_on_the_atlas_shape_renders_as_the_scene_compiled_at_its_value() {
    let Some(gpu) = gpu_for_tests() else { return };
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let a = analyze(None);
    let base = module(&a);
    // One pipeline for every value.
    let renderer = Renderer::new(&gpu, &base, root).unwrap();
    for w in ENDS {
        let at = analyze(Some(w));
        let shape = at.scene.as_ref().unwrap().render.clone().unwrap();
        let mut view = View::new(at.program.render.as_ref(), &shape);
        view.atlas_aov = true;
        let values = |n: &str| (n == "w").then(|| vec![w]);
        // The block alone (the atlas left where it was), then with the atlas recomputed.
        renderer.set_params(&gpu, &base.manifest.params.bytes(&values));
        let (stale, _) = renderer.frames(&gpu, &view, ViewMode::Color, 0, 1).unwrap();
        let took = renderer.set_param_values(&gpu, &base, &values).unwrap();
        assert!(took.is_some(), "new values recompute the atlas");
        assert!(
            renderer
                .set_param_values(&gpu, &base, &values)
                .unwrap()
                .is_none(),
            "the same values again recompute nothing"
        );
        let (moved, _) = renderer.frames(&gpu, &view, ViewMode::Color, 0, 1).unwrap();
        let compiled = sdfc::gpu::render(&gpu, &module(&at), &view, ViewMode::Color, root).unwrap();
        let (mean, share) = common::image_difference(&moved.color, &compiled.color);
        let (stale_mean, _) = common::image_difference(&stale.color, &compiled.color);
        eprintln!(
            "w = {w}: recomputed {mean:.3}/255 ({share:.4} over 16), not recomputed {stale_mean:.2}/255, recomputation {:.2} ms",
            took.unwrap().as_secs_f64() * 1e3
        );
        assert!(mean <= 0.25 && share <= 0.001, "w = {w}: {mean}, {share}");
        // Without the recomputation the checker visibly slides: the test can fail.
        assert!(
            stale_mean >= 1.0,
            "w = {w}: the stale atlas differs by {stale_mean} only"
        );
        // The uv on the GPU against the recomputed CPU atlas.
        let cpu = base.moving[0].at_params(&values).unwrap();
        let mut errors: Vec<f64> = Vec::new();
        for (p, uv) in moved.position.iter().zip(&moved.atlas) {
            if p[3] < 0.0 || uv[3] != 0.0 {
                continue;
            }
            let s = cpu.sample(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
            errors.push(((s.uv.x - uv[0] as f64).powi(2) + (s.uv.y - uv[1] as f64).powi(2)).sqrt());
        }
        errors.sort_by(f64::total_cmp);
        let p99 = errors[errors.len() * 99 / 100];
        eprintln!(
            "w = {w}: {} pixels, uv against the CPU: 99th percentile {p99:e}",
            errors.len()
        );
        assert!(
            errors.len() > 2000,
            "w = {w}: {} pixels compared",
            errors.len()
        );
        // A percentile, not the largest: where f32 and f64 choose different nearest
        // seeds (along the seam between the side and the top, which are not merged) the
        // uv differ by a chart.
        assert!(p99 <= 2e-3, "w = {w}: GPU uv against the CPU by {p99}");
    }
}

/// `sdfc render --animate` on breathing_robot.sdf (its atlas on the torso, whose depth
/// follows `time`): each frame, from one pipeline with the atlas recomputed, equals the
/// frame `sdfc render --time T` compiles at that time. The page exported from it says
/// that it keeps the atlas where it lies.
#[test]
fn an_animation_of_a_moving_atlas_equals_each_frame_compiled_at_its_time() {
    if gpu_for_tests().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("sdfc-moving-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/breathing_robot.sdf");
    let pattern = dir.join("f%02d.png");
    let common = ["--size", "60x80", "--walk", "loop"];
    let mut args = vec!["render", scene, "--animate", "1.5", "--fps", "2"];
    args.extend(common);
    args.extend(["-o", pattern.to_str().unwrap()]);
    let (code, _, err) = common::sdfc(&args);
    assert_eq!(code, 0, "{err}");
    for (i, t) in [0.0, 0.5, 1.0].iter().enumerate() {
        let still = dir.join(format!("t{i}.png"));
        let time = t.to_string();
        let mut args = vec!["render", scene, "--time", &time];
        args.extend(common);
        args.extend(["-o", still.to_str().unwrap()]);
        let (code, _, err) = common::sdfc(&args);
        assert_eq!(code, 0, "{err}");
        let frame = image::open(dir.join(format!("f{i:02}.png")))
            .unwrap()
            .to_rgba8();
        let still = image::open(&still).unwrap().to_rgba8();
        let (mean, share) = common::image_difference(frame.as_raw(), still.as_raw());
        eprintln!("time {t}: frame against its own compile {mean:.3}/255");
        assert!(mean <= 0.25 && share <= 0.002, "time {t}: {mean}, {share}");
    }
    let (code, _, err) = common::sdfc(&[
        "export-web",
        scene,
        "-o",
        dir.join("page").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning: atlas `skin` is on a shape that moves"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
