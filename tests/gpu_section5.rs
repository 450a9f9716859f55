//! The §5 examples on the GPU against the CPU reference: at surface points of each
//! render target, `cs_material` (the generated `scene_surface`, which reads the atlases
//! at the rest pose, mirrored, blended across smooth unions, on shell-mapped surfaces)
//! against `MaterialEval::eval_surface`: colour within 2/255 and the shading normal
//! within 1e-2, wherever the CPU's values are continuous (unchanged by 1e-4 moves: away
//! from seams, the frontiers of unmerged seeds, the hard union's switch, texture and
//! checker edges). The normal's tolerance is the sampler's fixed-point filtering (8
//! bits on lavapipe) of the normal map's texels, times 2 in decoding; see
//! tests/normal_map.rs. Skips loudly without an adapter (fails with
//! SDFC_REQUIRE_GPU=1). Loop walks: lavapipe is slow.

use glam::DVec3;
use sdfc::codegen::{Options, WalkForm};
use sdfc::driver::{check, Analysis};
use sdfc::gpu::{self, gpu_for_tests};
use sdfc::reference::material::MaterialEval;
use std::path::Path;

use crate::common;

fn analyze(name: &str) -> Analysis {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let src = std::fs::read_to_string(dir.join(name)).unwrap();
    let a = check(&src, Some(&dir));
    assert!(!a.has_errors(), "{name}: {:?}", a.diagnostics);
    a
}

#[test]
fn section_5_examples_agree_with_the_cpu() {
    let Some(gpu) = gpu_for_tests() else { return };
    for name in [
        "twisted_bar.sdf",
        "robot_mirrored.sdf",
        "shell_tiles.sdf",
        "shell_arrows.sdf",
    ] {
        let a = analyze(name);
        let target = a.scene.as_ref().unwrap().render.clone().unwrap();
        let m = MaterialEval::load(&a.program, &a.atlases).unwrap();
        // Ground planes are left out: they are no part of §5.
        let unbounded = !target.framing_bounds().is_finite();
        let points =
            common::surface_points(a.field(&target), 150, 31, |x| !(unbounded && x.y < -1.25));
        // Half a level-0 texel of the bricks at 1.5 repeats per unit.
        let footprint = 0.5 / (1.5 * 128.0);
        let samples: Vec<(DVec3, DVec3, f64)> =
            points.iter().map(|&(x, n)| (x, n, footprint)).collect();
        let options = Options {
            walk: WalkForm::Loop,
            ..Default::default()
        };
        let module = sdfc::driver::compile(&a, &options).unwrap().module;
        let got = gpu::eval_materials(&gpu, &module, m.textures(), &samples).unwrap();
        let (mut compared, mut colour, mut normal) = (0, 0.0f64, 0.0f64);
        for ((x, n), g) in points.iter().zip(&got) {
            let cpu = m.eval_surface(a.field(&target), *x, *n, footprint);
            let jumps = [DVec3::X, DVec3::Y, DVec3::Z].iter().any(|e| {
                let c = m.eval_surface(a.field(&target), *x + *e * 1e-4, *n, footprint);
                (c.color - cpu.color).abs().max_element() > 1.0 / 255.0
                    || (c.normal - cpu.normal).length() > 2e-3
            });
            if jumps {
                continue;
            }
            compared += 1;
            let c = DVec3::from_array(g.color.map(|v| v as f64));
            let gn = DVec3::from_array(g.normal.map(|v| v as f64));
            colour = colour.max((cpu.color - c).abs().max_element());
            normal = normal.max((cpu.normal - gn).length());
            assert!(
                (cpu.color - c).abs().max_element() <= 2.0 / 255.0,
                "{name} at {x}: colour {} vs {c}",
                cpu.color
            );
            assert!(
                (cpu.normal - gn).length() <= 1e-2,
                "{name} at {x}: normal {} vs {gn}",
                cpu.normal
            );
        }
        eprintln!("{name}: {compared}/150 compared, worst colour {colour:.4}, normal {normal:.2e}");
        // The mirrored robot's bevelled normal map turns steeply at every brick's edge,
        // so about half its points are near a jump of the normal.
        assert!(compared >= 60, "{name}: only {compared}");
    }
}
