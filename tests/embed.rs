//! Embedding in a host's own wgpu program: `examples/embed.rs` compiles a scene, draws
//! it with its own device, queue and encoder through `sdfc::SceneRenderer`, and writes
//! a PNG that equals `sdfc render` of the same scene at the same size (`fs_main` and
//! `fs_aov` shade the same colour). `cargo test` builds the example beside the binary.

use std::path::PathBuf;
use std::process::Command;

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
        let out = Command::new(env!("CARGO_BIN_EXE_sdfc"))
            .args(["render", scene, "--walk", "loop", "--size", "96x72", "-o"])
            .arg(&reference)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{scene}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (a, b) = (decode(&mine), decode(&reference));
        assert_eq!(a.dimensions(), b.dimensions());
        // A picture, not a cleared target: the shape's shading has many colours.
        let colours: std::collections::HashSet<[u8; 4]> = a.pixels().map(|p| p.0).collect();
        assert!(
            colours.len() > 200,
            "{scene}: only {} colours",
            colours.len()
        );
        let worst = a
            .as_raw()
            .iter()
            .zip(b.as_raw())
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap();
        // The same shader on the same adapter: equal to within one level of 8 bits.
        assert!(worst <= 1, "{scene}: pixels differ by up to {worst}/255");
    }
}
