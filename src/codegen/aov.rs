//! The AOVs as the bits of their floats (`shaders/aov_bits.wgsl.in`): a second
//! fragment entry point for an adapter that renders to `rgba32uint` but not to
//! `rgba32float` (wgpu's GL backend on a desktop GL core profile). The runtime appends
//! it to a generated module only on such an adapter, so exported modules and their
//! manifests do not change; a baked mesh's renderer always carries it.

use super::template::{self, AOV_BITS};

/// The scene render's entry point with its AOVs as bits (beside `fs_aov`).
pub const SCENE_ENTRY: &str = "fs_aov_bits";
/// The baked mesh renderer's (beside its `fs_main`).
pub const MESH_ENTRY: &str = "fs_bits";

fn bits(entry: &str, arguments: &str, call: &str) -> String {
    template::fill(
        AOV_BITS,
        &[
            ("entry", entry.to_string()),
            ("arguments", arguments.to_string()),
            ("call", call.to_string()),
        ],
    )
    .expect("shaders/aov_bits.wgsl.in names exactly entry, arguments and call")
}

/// `wgsl`, a generated module, with [`SCENE_ENTRY`]: `fs_aov`'s pixel with its AOVs
/// as bits.
pub fn with_scene_bits(wgsl: &str) -> String {
    format!(
        "{wgsl}\n{}",
        bits(SCENE_ENTRY, "in: VertexOut", "shade_pixel(in.position.xy)")
    )
}

/// The mesh renderer's [`MESH_ENTRY`] (its `fs_main`'s fragment with the AOVs as bits).
pub(super) fn mesh_bits() -> String {
    bits(
        MESH_ENTRY,
        "in: VertexOut, @builtin(front_facing) front: bool",
        "mesh_fragment(in, front)",
    )
}
