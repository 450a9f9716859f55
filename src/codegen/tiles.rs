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
use crate::ir::prim::Kind;
use crate::ir::{Aabb, NodeId, Op, Shape};
use std::collections::HashMap;
use std::fmt::Write;

pub use super::group::{CACHED, CULLED, TILES_HEADER, TILE_ENTRY, WHOLE};

/// The pipeline-overridable constant of a module with per-tile culling that keeps
/// the whole-scene paths for crowded tiles ([`DISPATCH`]); true unless a pipeline
/// says otherwise.
pub const CROWDED: &str = "SCENE_CROWDED";

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

// The trace of a pixel's ray, the normal at its hit and the sun's visibility from there.
fn scene_trace(ro: vec3<f32>, rd: vec3<f32>, max_steps: i32, tile: u32) -> vec4<f32> {
    return scene_march(ro, rd, max_steps, tile, vec2<f32>(0.0, globals.trace.x));
}

fn scene_trace_normal(p: vec3<f32>, tile: u32) -> vec3<f32> {
    return scene_listed_normal(p, tile);
}

fn scene_shadow(p: vec3<f32>, l: vec3<f32>) -> f32 {
    return scene_shadow_march(p, l, 0u, vec2<f32>(0.0, globals.trace.x));
}

",
        );
        out.push_str(&marches("", "scene_trace_map"));
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

{}{}// The render target as the trace reads it: its traced groups over the leaves of the
// pixel's tile.
fn scene_trace_map(p: vec3<f32>, tile: u32) -> vec2<f32> {{
    sdf_evals = sdf_evals + 1u;
{}    return {d};
}}

",
        cull(&cached(target, slots), only_groups(target)),
        w.helpers,
        w.out
    );
    out.push_str(&marches("", "scene_trace_map"));
    out.push_str(&marches("_whole", "scene_whole_map"));
    out.push_str(DISPATCH);
    w.groups
}

/// By slot, the traced groups whose rays' first leaves are cached
/// ([`super::group::cached_kind`]): the name of the group's offset and its leaves' kind.
fn cached(target: &Shape, slots: &HashMap<NodeId, u32>) -> Vec<Option<(String, &'static Kind)>> {
    let mut out = vec![None; slots.len()];
    for (&id, &slot) in slots {
        if let Some(g) = target.group(id) {
            out[slot as usize] = super::group::cached_kind(g, slot)
                .map(|kind| (format!("GROUP_{}_AT", g.key), kind));
        }
    }
    out
}

/// `shaders/trace.wgsl.in` over the field `map`, its functions named with `suffix`.
fn marches(suffix: &str, map: &str) -> String {
    super::template::fill(
        super::template::TRACE,
        &[("suffix", suffix.to_string()), ("map", map.to_string())],
    )
    .expect("shaders/trace.wgsl.in names exactly suffix and map")
}

/// With per-tile culling: the trace, its normal and the shadow ray, each over the
/// leaves its ray meets, or over the whole scene where a list it reads was too long
/// (`scene_whole`). The branch is taken once a ray, outside the marches' loops, and
/// only in a pipeline built with [`CROWDED`] true (its default): the runtime builds
/// another with it false for the frames where no list is too long (`gpu::render`), in
/// which the whole-scene paths compile away. (On Mesa's software adapter a branch not
/// taken still runs, and a loop's body once: 2.5 ms of a 7 ms frame of 1,200
/// scattered spheres at 160 × 120.)
const DISPATCH: &str = "// Whether a tile's list may be too long (the whole-scene paths below): the runtime
// builds the pipeline of a frame without such a list with this false.
override SCENE_CROWDED: bool = true;

// The whole scene, for rays whose tiles' lists were too long.
fn scene_whole_map(p: vec3<f32>, tile: u32) -> vec2<f32> {
    return scene_map(p);
}

// The trace of a pixel's ray over the leaves it meets in its tile's lists.
fn scene_trace(ro: vec3<f32>, rd: vec3<f32>, max_steps: i32, tile: u32) -> vec4<f32> {
    let span = scene_cull(ro, rd, tile, globals.trace.x);
    if (SCENE_CROWDED && scene_whole) {
        return scene_march_whole(ro, rd, max_steps, tile, vec2<f32>(0.0, globals.trace.x));
    }
    return scene_march(ro, rd, max_steps, tile, span);
}

// The normal at the hit p of the last scene_trace, over the leaves its ray met.
fn scene_trace_normal(p: vec3<f32>, tile: u32) -> vec3<f32> {
    if (SCENE_CROWDED && scene_whole) {
        return scene_whole_normal(p);
    }
    return scene_listed_normal(p, tile);
}

// scene_normal as a loop over its taps, none unless the ray is whole: on Mesa's
// software adapter the branch not taken still runs, but a loop's body only once.
fn scene_whole_normal(p: vec3<f32>) -> vec3<f32> {
    let h = 1e-3 * SCENE_SCALE;
    var g = vec3<f32>(0.0);
    for (var k = 0u; k < select(0u, 4u, scene_whole); k = k + 1u) {
        // The taps k.xyy, k.yyx, k.yxy, k.xxx of scene_normal, k = (1, -1).
        let e = vec3<f32>(select(-1.0, 1.0, k == 0u || k == 3u), select(-1.0, 1.0, k >= 2u), select(-1.0, 1.0, k == 1u || k == 3u));
        g = g + e * scene_map(p + e * h).x;
    }
    return normalize(g);
}

// The sun's visibility from p along l, over the leaves of its light cell the ray meets.
fn scene_shadow(p: vec3<f32>, l: vec3<f32>) -> f32 {
    let cell = scene_shadow_cell(p);
    let span = scene_cull(p, l, cell, globals.trace.x);
    var seen: f32;
    if (SCENE_CROWDED && scene_whole) {
        seen = scene_shadow_march_whole(p, l, cell, vec2<f32>(0.0, globals.trace.x));
    } else {
        seen = scene_shadow_march(p, l, cell, span);
    }
    scene_cull_none();
    return seen;
}

";

/// Whether the render target is its traced groups alone: reached from the root
/// through hard unions and paints (`ir::group::traced`), with no operands as code
/// anywhere on the way. Then nothing but the groups' leaves can meet a ray.
fn only_groups(target: &Shape) -> bool {
    let mut stack = vec![target.root()];
    while let Some(id) = stack.pop() {
        if let Some(g) = target.group(id) {
            if !g.others.is_empty() || target.is_shared(id) || target[id].dynamic.is_some() {
                return false;
            }
            continue;
        }
        match &target[id].op {
            Op::Csg { a, b, .. } if crate::ir::group::is_hard_union(&target[id].op) => {
                stack.push(*b);
                stack.push(*a);
            }
            Op::Paint { child, .. } => stack.push(*child),
            _ => return false,
        }
    }
    true
}

/// `scene_cull(ro, rd, tile, far) -> vec2<f32>`: which of the first [`CULLED`] entries of each
/// traced group's list in `tile` the ray `ro + t rd`, 0 <= t <= far, misses (a slab
/// test against the entry's grown box), into `scene_skip`, which the tiled walkers
/// read (the trace, then the normal at its hit); `scene_cull_none()` clears it after
/// the shadow ray, so that a call off any culled ray reads whole lists. A ray
/// that misses a leaf's grown box never comes within the trace's tolerance of it, nor
/// within the normal's taps (`gpu::tiles`), so skipping it changes no hit. Returns
/// the span of the ray where it may meet the surface: with `only` (the target is its
/// groups alone, [`only_groups`]), from the nearest entry into a box it meets to the
/// farthest exit (empty, start past end, where it meets none), else `(0, far)`.
///
/// In the slots `cached` names (by slot: the group's offset and its leaves' kind), the
/// first [`CACHED`] leaves the ray meets are read into registers (`scene_cache_SLOT`,
/// [`super::group::cached_leaves`]) and skipped in the list: the walker's loop then
/// reads only the leaves past them, and a ray that meets few leaves reads no buffer at
/// its steps (docs/performance.md, "A ray's first leaves in registers", for what it
/// saved).
fn cull(cached: &[Option<(String, &'static Kind)>], only: bool) -> String {
    const _: () = assert!(CULLED == 64, "the mask is two words");
    let slots = cached.len();
    let (set, clear, leaves) = cull_slots(cached);
    let (first, span) = if only {
        (
            " (the target is its traced groups alone: from the nearest entry into a box\n// to the farthest exit, empty where it meets none)",
            "scene_span",
        )
    } else {
        (
            " (all of it: the target has operands as code)",
            "vec2<f32>(0.0, far)",
        )
    };
    format!(
        "// Per traced group, the entries of the tile's list the ray being traced misses.
// (entries 0-31 in x, 32-63 in y).
var<private> scene_skip: array<vec2<u32>, {slots}>;

// The nearest entry of the ray into a box it meets and its farthest exit from one,
// over the lists culled so far (0 and far where a list was not culled whole).
var<private> scene_span: vec2<f32>;

// Whether a list the ray reads was too long (`WHOLE`): it then traces the whole scene.
var<private> scene_whole: bool;

// Per traced group, how many leaves scene_cull cached for the ray being traced.
var<private> scene_cached_n: array<u32, {slots}>;

// A cached leaf: its translation and material (w), its parameters.
struct SceneLeaf {{
    frame: vec4<f32>,
    params: vec4<f32>,
}}

// One list culled to a ray: the entries it misses or caches (bits as scene_skip's), how
// many it cached and their records (0 past them).
struct SceneCulled {{
    skip: vec2<u32>,
    cached: u32,
    first: vec4<u32>,
}}

{leaves}// Bit i (of x, then of y from 32 on) set where the ray ro + t / inv (0 <= t <= far)
// misses entry i's box, for the first {CULLED} entries of `tile`'s list of group `slot`;
// the first `cache` (at most {CACHED}) entries it meets are set too and their records kept.
fn scene_cull_list(ro: vec3<f32>, inv: vec3<f32>, tile: u32, slot: u32, far: f32, cache: u32) -> SceneCulled {{
    let h = {TILES_HEADER}u + 2u * (tile * tiles[3] + slot);
    let start = tiles[h];
    let count = tiles[h + 1u];
    var out = SceneCulled(vec2<u32>(0u), 0u, vec4<u32>(0u));
    if (count == {WHOLE}u || count > {CULLED}u) {{
        scene_span = vec2<f32>(0.0, far);
    }}
    if (count == {WHOLE}u) {{
        scene_whole = true;
        return out;
    }}
    var skip = vec2<u32>(0u);
    for (var i = 0u; i < min(count, {CULLED}u); i = i + 1u) {{
        let e = start + {TILE_ENTRY}u * i;
        let lo = vec3<f32>(bitcast<f32>(tiles[e + 1u]), bitcast<f32>(tiles[e + 2u]), bitcast<f32>(tiles[e + 3u]));
        let hi = vec3<f32>(bitcast<f32>(tiles[e + 4u]), bitcast<f32>(tiles[e + 5u]), bitcast<f32>(tiles[e + 6u]));
        let a = (lo - ro) * inv;
        let b = (hi - ro) * inv;
        let near = max(max(min(a.x, b.x), min(a.y, b.y)), max(min(a.z, b.z), 0.0));
        let far_side = min(min(max(a.x, b.x), max(a.y, b.y)), min(max(a.z, b.z), far));
        let bit = 1u << (i & 31u);
        let mark = select(vec2<u32>(bit, 0u), vec2<u32>(0u, bit), i >= 32u);
        if (near > far_side) {{
            skip = skip | mark;
        }} else {{
            scene_span = vec2<f32>(min(scene_span.x, near), max(scene_span.y, far_side));
            if (out.cached < cache) {{
                let n = out.cached;
                out.first = select(out.first, vec4<u32>(tiles[e]), vec4<bool>(n == 0u, n == 1u, n == 2u, n == 3u));
                out.cached = n + 1u;
                skip = skip | mark;
            }}
        }}
    }}
    out.skip = skip;
    return out;
}}

// Culls the tiles' lists to the ray ro + t rd, 0 <= t <= far (rd need not be unit);
// returns the span of the ray where it may meet the surface{first}.
fn scene_cull(ro: vec3<f32>, rd: vec3<f32>, tile: u32, far: f32) -> vec2<f32> {{
    // A direction component of 0 becomes a tiny one: the slab is then all or nothing.
    let inv = 1.0 / select(rd, vec3<f32>(1e-30), abs(rd) < vec3<f32>(1e-30));
    scene_span = vec2<f32>(2.0 * far + 1.0, 0.0);
    scene_whole = false;
{set}    return {span};
}}

// Every listed entry again, for any call off a culled ray (scene_shadow ends with it,
// so the shadow ray's masks never reach a later normal).
fn scene_cull_none() {{
{clear}}}

"
    )
}

/// `scene_cull`'s statements for each slot (`set`), `scene_cull_none`'s (`clear`), and
/// the cached slots' leaves and their union (`cached_leaves`), for [`cull`].
fn cull_slots(cached: &[Option<(String, &'static Kind)>]) -> (String, String, String) {
    const _: () = assert!(CACHED == 4, "the cached records are a vec4");
    let (mut set, mut clear, mut leaves) = (String::new(), String::new(), String::new());
    for (k, cache) in cached.iter().enumerate() {
        let _ = writeln!(
            clear,
            "    scene_skip[{k}] = vec2<u32>(0u);\n    scene_cached_n[{k}] = 0u;"
        );
        let Some((at, kind)) = cache else {
            let _ = writeln!(
                set,
                "    scene_skip[{k}] = scene_cull_list(ro, inv, tile, {k}u, far, 0u).skip;\n    scene_cached_n[{k}] = 0u;"
            );
            continue;
        };
        let _ = writeln!(
            set,
            "    let c{k} = scene_cull_list(ro, inv, tile, {k}u, far, {CACHED}u);
    scene_skip[{k}] = c{k}.skip;
    scene_cached_n[{k}] = c{k}.cached;"
        );
        for (j, lane) in ["x", "y", "z", "w"].iter().enumerate() {
            let _ = writeln!(
                set,
                "    scene_cache_{k}[{j}] = scene_cache_leaf_{k}(c{k}.first.{lane});"
            );
        }
        leaves.push_str(&super::group::cached_leaves(k as u32, at, kind));
    }
    (set, clear, leaves)
}
