//! Per-tile culling of the render's trace (`Options::tiles`): the groups reached from
//! the render target through hard unions and paints alone (`ir::group::traced`) are
//! evaluated, along a pixel's ray, over the leaves that its screen tile's rays can
//! come near: lists the runtime bins from the camera every frame (`gpu::tiles`) into
//! the `tiles` storage buffer. Shadow rays, all parallel, read the lists of their cell
//! in a grid across the sun's direction, binned the same way. Everything else (atlas
//! walks, compute entry points) evaluates the whole field.
//!
//! What this module writes: `scene_tile(pixel)` (the pixel's tile),
//! `scene_shadow_cell(p)` (a shadow ray's cell) and `scene_trace_map(p, tile)` (the
//! field the trace, its normal and the shadow ray read), which without tiling are
//! `0u`, `0u` and `scene_map(p)`; with it, the render target once more with its traced
//! groups through their tile's list (`codegen::group::tiled_walker`).

use super::emit::Writer;
use crate::ir::group::Group;
use crate::ir::{Aabb, NodeId, Shape};
use std::collections::HashMap;
use std::fmt::Write;

pub use super::group::{TILES_HEADER, WHOLE};

/// One traced group: its leaves' boxes (world space: nothing above the group moves
/// it) and their records, in record order.
#[derive(Debug, Clone, PartialEq)]
pub struct TracedGroup {
    pub boxes: Vec<Aabb>,
    pub records: Vec<u32>,
}

/// What the runtime needs to bin a module's traced groups into tiles.
#[derive(Debug, Clone, PartialEq)]
pub struct Tiling {
    /// By slot (the `slot` argument of `group_tiled_*`).
    pub groups: Vec<TracedGroup>,
    /// The distance of the trace normal's taps from the hit (`1e-3 × SCENE_SCALE`,
    /// `scene_trace_normal` in shaders/entry.wgsl.in).
    pub tap: f64,
}

/// The traced groups of the render target and their slots, by node; none when the
/// target has none (or its unions are written as code).
pub fn slots(target: &Shape, unions_as_code: bool) -> HashMap<NodeId, u32> {
    if unions_as_code {
        return HashMap::new();
    }
    crate::ir::group::traced(target)
        .into_iter()
        .enumerate()
        .map(|(slot, id)| (id, slot as u32))
        .collect()
}

/// The [`Tiling`] of `slots` (from [`slots`]); `scale` is `SCENE_SCALE`.
pub fn tiling(target: &Shape, slots: &HashMap<NodeId, u32>, scale: f64) -> Tiling {
    let mut by_slot: Vec<(u32, &std::sync::Arc<Group>)> = slots
        .iter()
        .filter_map(|(&id, &slot)| Some((slot, target.group(id)?)))
        .collect();
    by_slot.sort_by_key(|&(slot, _)| slot);
    Tiling {
        groups: by_slot
            .into_iter()
            .map(|(_, g)| TracedGroup {
                boxes: g.leaves.iter().map(|l| l.bounds).collect(),
                records: g.records(),
            })
            .collect(),
        tap: 1e-3 * scale,
    }
}

/// `scene_tile` and `scene_trace_map`: with `slots`, the render target `target` again,
/// its traced groups through their tiles (returns the groups it calls); without, the
/// pixel's tile is 0 and the trace reads `scene_map`.
pub fn functions(
    out: &mut String,
    target: &Shape,
    slots: &HashMap<NodeId, u32>,
    (unions_as_code, guard_cost): (bool, Option<f64>),
) -> Vec<std::sync::Arc<Group>> {
    if slots.is_empty() {
        out.push_str(
            "// The pixel's screen tile and the field the trace reads (no per-tile culling).
fn scene_tile(pixel: vec2<f32>) -> u32 {
    return 0u;
}

fn scene_shadow_cell(p: vec3<f32>) -> u32 {
    return 0u;
}

fn scene_trace_map(p: vec3<f32>, tile: u32) -> vec2<f32> {
    return scene_map(p);
}

",
        );
        return Vec::new();
    }
    let mut w = Writer::new("scene_trace_map");
    w.unions_as_code = unions_as_code;
    w.guard_cost = guard_cost;
    w.tiled = slots.clone();
    let d = w.shape(target, target.root(), "p");
    let _ = write!(
        out,
        "// The pixel's screen tile (the `tiles` buffer's header: side, across, down).
fn scene_tile(pixel: vec2<f32>) -> u32 {{
    let side = max(tiles[0], 1u);
    let x = min(u32(pixel.x) / side, max(tiles[1], 1u) - 1u);
    let y = min(u32(pixel.y) / side, max(tiles[2], 1u) - 1u);
    return y * tiles[1] + x;
}}

// The cell of the shadow ray through p in the light's grid (the header's words 4-14),
// after the screen's tiles; the empty cell past the grid when p is off it.
fn scene_shadow_cell(p: vec3<f32>) -> u32 {{
    let first = tiles[1] * tiles[2];
    let across = tiles[4];
    let down = tiles[5];
    let u = vec3<f32>(bitcast<f32>(tiles[9]), bitcast<f32>(tiles[10]), bitcast<f32>(tiles[11]));
    let v = vec3<f32>(bitcast<f32>(tiles[12]), bitcast<f32>(tiles[13]), bitcast<f32>(tiles[14]));
    let c = (vec2<f32>(dot(p, u), dot(p, v)) - vec2<f32>(bitcast<f32>(tiles[6]), bitcast<f32>(tiles[7]))) / bitcast<f32>(tiles[8]);
    if (c.x < 0.0 || c.y < 0.0 || c.x >= f32(across) || c.y >= f32(down)) {{
        return first + across * down;
    }}
    return first + min(u32(c.y), down - 1u) * across + min(u32(c.x), across - 1u);
}}

{}// The render target as the trace reads it: its traced groups over the leaves of the
// pixel's tile.
fn scene_trace_map(p: vec3<f32>, tile: u32) -> vec2<f32> {{
    sdf_evals = sdf_evals + 1u;
{}    return {d};
}}

",
        w.helpers, w.out
    );
    w.groups
}
