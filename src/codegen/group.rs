//! The WGSL of groups (`ir::group`): a large hard union as data in the `tables` buffer
//! (a constant per group: its offset), evaluated by a walker function shared by every
//! group with the same primitive kinds: one loop over the flattened bounding-volume
//! hierarchy, one `switch` arm per kind. `ir::group::Group::eval` is its CPU mirror.

use super::emit::Writer;
use crate::ir::group::{Group, INNER, RECORD_PARAMS};
use crate::ir::prim::{Kind, Slot, KINDS};
use crate::ir::Shape;
use std::fmt::Write;

/// Reads of the `tables` buffer as floats and vectors, and a group tree node's box
/// distance; emitted once per module that has a group.
pub const READERS: &str = "fn tables_f32(i: u32) -> f32 {
    return bitcast<f32>(tables[i]);
}

fn tables_vec3(i: u32) -> vec3<f32> {
    return vec3<f32>(bitcast<f32>(tables[i]), bitcast<f32>(tables[i + 1u]), bitcast<f32>(tables[i + 2u]));
}

// The distance from p to the box of the group tree node at word `at`: 0 inside.
fn group_box(at: u32, p: vec3<f32>) -> f32 {
    return length(max(max(tables_vec3(at) - p, p - tables_vec3(at + 4u)), vec3<f32>(0.0)));
}

";

/// The distance call of a primitive kind at local point `q`, its parameters read from
/// the record at word `k` in the kind's slot order ([`crate::ir::prim::KINDS`]).
fn call_of(code: u32) -> Option<String> {
    let kind = KINDS.get(code as usize)?;
    Some(kind_call(kind, |at, slot| {
        let k = if at == 0 {
            String::from("k")
        } else {
            format!("k + {at}u")
        };
        match slot {
            Slot::Float => format!("tables_f32({k})"),
            Slot::Vec3 => format!("tables_vec3({k})"),
        }
    }))
}

/// The call of `kind`'s distance function at `q`, each parameter the expression `arg`
/// gives for its first word (counted from the record's parameters) and its slot.
fn kind_call(kind: &Kind, arg: impl Fn(u32, Slot) -> String) -> String {
    let mut args = vec![String::from("q")];
    let mut at = 0u32;
    for &slot in kind.slots {
        args.push(arg(at, slot));
        at += words(slot);
    }
    format!("{}({})", kind.wgsl, args.join(", "))
}

/// The words of one parameter slot in a leaf record.
fn words(slot: Slot) -> u32 {
    slot.words() as u32
}

/// The words of a kind's parameters in a leaf record.
fn kind_words(kind: &Kind) -> u32 {
    kind.slots.iter().map(|&s| words(s)).sum()
}

/// The bit of a walker's mask that says some leaf holds a matrix.
const TURNED: u32 = 1 << 31;

/// The kinds of a group as a bit mask, with [`TURNED`] where a leaf is turned: one
/// walker function per mask (a group of unturned leaves of one kind reads neither a
/// record's head nor a matrix).
pub fn mask(g: &Group) -> u32 {
    let kinds = g.kinds().iter().fold(0, |m, k| m | (1 << k));
    if g.leaves.iter().any(|l| l.has_matrix()) {
        kinds | TURNED
    } else {
        kinds
    }
}

/// The call of a group's walker at point `p`: (distance, material).
pub fn call(g: &Group, p: &str) -> String {
    format!(
        "group_walk_{:x}(GROUP_{}_AT, {}u, {p})",
        mask(g),
        g.key,
        g.tree.len()
    )
}

/// `fn group_walk_MASK(at, nodes, p) -> vec2<f32>` (distance, material): the walk of a
/// group's tree whose leaves have the kinds of `mask`, from offset `at` of `tables`.
pub fn walker(mask: u32) -> String {
    let kinds: Vec<u32> = (0..31).filter(|k| mask & (1 << k) != 0).collect();
    let mut arms = String::new();
    for &code in &kinds {
        if let Some(c) = call_of(code) {
            let _ = writeln!(arms, "        case {code}u: {{ d = {c}; }}");
        }
    }
    // A leaf record's distance: its point in the primitive's frame, then its kind's arm.
    let frame = if mask & TURNED != 0 {
        String::from(
            "    let head = tables[r];
    var q = p + tables_vec3(r + 2u);
    var k = r + 5u;
    if ((head & 256u) != 0u) {
        q = mat3x3<f32>(tables_vec3(r + 5u), tables_vec3(r + 8u), tables_vec3(r + 11u)) * p + tables_vec3(r + 2u);
        k = r + 14u;
    }
",
        )
    } else {
        format!(
            "    let q = p + tables_vec3(r + 2u);
    let k = r + {RECORD_PARAMS}u;
"
        )
    };
    let body = match (&kinds[..], mask & TURNED != 0) {
        // One kind, no matrix: the record's head is not read.
        ([only], false) => format!("    return {};\n", call_of(*only).unwrap_or_else(|| "3.0e38".into())),
        (_, turned) => format!(
            "{}    var d = 3.0e38;\n    switch (head & 255u) {{\n{arms}        default: {{}}\n    }}\n    return d;\n",
            if turned { "" } else { "    let head = tables[r];\n" }
        ),
    };
    let leaf =
        format!("fn group_leaf_{mask:x}(r: u32, p: vec3<f32>) -> f32 {{\n{frame}{body}}}\n\n");
    leaf + &format!(
        "// A large union as data: a bounding-volume hierarchy over its primitives' boxes
// (`tables` from `at0`, `nodes` nodes), walked without a stack; a subtree whose box is
// farther than the best distance so far is skipped (ir::group mirrors this).
fn group_walk_{mask:x}(at0: u32, nodes: u32, p: vec3<f32>) -> vec2<f32> {{
    // Node i is words at0 + 8i: box min, skip, box max, record.
    // The first bound: the leaf reached by descending into the nearer child's box (a
    // node's children are the next node and the one after the first child's subtree).
    var i = 0u;
    loop {{
        if (tables[at0 + 8u * i + 7u] != {inner}u) {{
            break;
        }}
        let l = i + 1u;
        let r = tables[at0 + 8u * l + 3u];
        let bl = group_box(at0 + 8u * l, p);
        let br = group_box(at0 + 8u * r, p);
        i = select(l, r, br < bl);
    }}
    let first = tables[at0 + 8u * i + 7u];
    var best = vec2<f32>(group_leaf_{mask:x}(at0 + first, p), tables_f32(at0 + first + 1u));
    var best_record = first;
    i = 0u;
    loop {{
        if (i >= nodes) {{
            break;
        }}
        let at = at0 + 8u * i;
        let b = group_box(at, p);
        if (b > 0.0 && b > best.x) {{
            i = tables[at + 3u];
            continue;
        }}
        let record = tables[at + 7u];
        if (record != {inner}u) {{
            let d = group_leaf_{mask:x}(at0 + record, p);
            if (d < best.x || (d == best.x && record < best_record)) {{
                best = vec2<f32>(d, tables_f32(at0 + record + 1u));
                best_record = record;
            }}
        }}
        i = i + 1u;
    }}
    return best;
}}

",
        inner = INNER,
    )
}

/// Words before the tiles' entries in the `tiles` buffer: tile side in pixels, tiles
/// across, tiles down, groups per tile; the light's grid: cells across and down, its
/// origin (2) and cell size, its axes u (3) and v (3) (floats as bits); one unused.
/// Entries (start, count) follow by cell then group: the screen's tiles row by row,
/// the light's cells row by row, one empty cell; then the lists, [`TILE_ENTRY`] words
/// a listed leaf (`start` is the first word, `count` the leaves).
pub const TILES_HEADER: u32 = 16;

/// Words of one list entry in the `tiles` buffer: the leaf's record, then its box
/// (min, max) grown by the binning's margins, as f32 bits, for the per-ray test.
pub const TILE_ENTRY: u32 = 7;

/// How many of a tile list's first entries each ray culls (`scene_cull`, a two-word
/// mask per traced group); entries past them are read at every step.
pub const CULLED: u32 = 64;

/// A tile's entry count meaning "this tile's list was too long: walk the whole group".
pub const WHOLE: u32 = u32::MAX;

/// The call of group `g`'s tiled walker in slot `slot` at point `p`, in a function
/// with the tile in `tile`, skipping the entries the current ray's culling skips
/// (`scene_skip`, `codegen::tiles`) and starting from the leaves it cached
/// ([`cached_kind`]): (distance, material).
pub fn tiled_call(g: &Group, slot: u32, p: &str) -> String {
    let first = match cached_kind(g, slot) {
        Some(_) => format!("scene_cached_{slot}({p})"),
        None => String::from("vec2<f32>(3.0e38, 0.0)"),
    };
    format!(
        "group_tiled_{:x}(GROUP_{}_AT, {slot}u, tile, scene_skip[{slot}], {p}, {first})",
        mask(g),
        g.key,
    )
}

/// How many of the leaves a ray meets in a cached group's list the cull reads into the
/// invocation's registers (`scene_cull`, `codegen::tiles`), so that each step of the
/// trace evaluates them without reading a buffer.
pub const CACHED: u32 = 4;

/// The first slots whose groups may be cached (the registers grow with them).
pub const CACHED_SLOTS: u32 = 4;

/// The kind of group `g`'s leaves where the ray's first [`CACHED`] leaves in slot `slot`
/// are cached: one kind, no leaf turned, its parameters in at most four words (every
/// kind but the capsule), among the first [`CACHED_SLOTS`] slots.
pub fn cached_kind(g: &Group, slot: u32) -> Option<&'static Kind> {
    let m = mask(g);
    if slot >= CACHED_SLOTS || m & TURNED != 0 || m.count_ones() != 1 {
        return None;
    }
    let kind = KINDS.get(m.trailing_zeros() as usize)?;
    (kind_words(kind) <= 4).then_some(kind)
}

/// For a cached slot ([`cached_kind`]): `fn scene_cached_SLOT(p) -> vec2<f32>`, the union
/// of the leaves cached for the ray being traced (distance, material; ties to the
/// first, which is the first listed), and `fn scene_cache_leaf_SLOT(record)`, one leaf
/// read from its record into a `SceneLeaf`.
pub fn cached_leaves(slot: u32, at: &str, kind: &Kind) -> String {
    let swizzle = |at: u32, slot: Slot| {
        let lanes = &"xyzw"[at as usize..(at + words(slot)) as usize];
        format!("l.params.{lanes}")
    };
    let call = kind_call(kind, swizzle);
    let used = kind_words(kind);
    let params: Vec<String> = (0..4u32)
        .map(|w| match w < used {
            true => format!("tables_f32(r + {}u)", RECORD_PARAMS + w),
            false => String::from("0.0"),
        })
        .collect();
    let mut body = String::new();
    for j in 0..CACHED {
        let _ = write!(
            body,
            "    {{
        let l = scene_cache_{slot}[{j}];
        let q = p + l.frame.xyz;
        let d = select(3.0e38, {call}, {j}u < scene_cached_n[{slot}]);
        if (d < best.x) {{
            best = vec2<f32>(d, l.frame.w);
        }}
    }}
"
        );
    }
    format!(
        "// The leaves of traced group {slot} ({wgsl}) that the ray being traced meets first,
// read once by scene_cull.
var<private> scene_cache_{slot}: array<SceneLeaf, {CACHED}>;

// Leaf `record` of traced group {slot}: its translation and material, its parameters.
fn scene_cache_leaf_{slot}(record: u32) -> SceneLeaf {{
    let r = {at} + record;
    return SceneLeaf(vec4<f32>(tables_vec3(r + 2u), tables_f32(r + 1u)), vec4<f32>({params}));
}}

// The union of the cached leaves (the first scene_cached_n[{slot}] of them).
fn scene_cached_{slot}(p: vec3<f32>) -> vec2<f32> {{
    var best = vec2<f32>(3.0e38, 0.0);
{body}    return best;
}}

",
        wgsl = kind.wgsl,
        params = params.join(", "),
    )
}

/// `fn group_tiled_MASK(at0, slot, tile, skip, p, first) -> vec2<f32>`: the union of
/// `first` (the leaves the cull cached, [`cached_kind`], or nothing) and the leaves
/// listed for `tile` and `slot` (ties to the first listed, the lowest record, as the
/// tree walk's), less those of the first [`CULLED`] entries whose bit is set in `skip`
/// (those whose boxes the ray being traced misses, and those cached, which come before
/// any other the ray meets). A crowded tile's list (`WHOLE`)
/// never reaches it: such rays trace the whole scene (`scene_whole`, `codegen::tiles`).
/// One loop, no call to the tree walk: on Mesa's software adapter a branch's other
/// side costs as much as its own, every step.
pub fn tiled_walker(mask: u32) -> String {
    format!(
        "// A large union over the leaves a screen tile's rays can come near (the `tiles`
// buffer, binned by the runtime each frame: src/gpu/tiles.rs), less those the ray
// being traced misses or whose union scene_cull cached (`skip`), from `first` (that
// union, or nothing). A crowded tile (a list too long) is
// traced over the whole scene instead (scene_whole), and reads as empty here.
fn group_tiled_{mask:x}(at0: u32, slot: u32, tile: u32, skip: vec2<u32>, p: vec3<f32>, first: vec2<f32>) -> vec2<f32> {{
    let h = {TILES_HEADER}u + 2u * (tile * tiles[3] + slot);
    let start = tiles[h];
    let count = select(tiles[h + 1u], 0u, tiles[h + 1u] == {WHOLE}u);
    var best = first;
    // The first {CULLED} entries by their bits (x, then y), in order; then any past them.
    let low = select(0xffffffffu, (1u << min(count, 31u)) - 1u, count < 32u);
    let high = select(0xffffffffu, (1u << (min(max(count, 32u), 63u) - 32u)) - 1u, count < 64u);
    var bits = vec2<u32>(low, select(0u, high, count > 32u)) & ~skip;
    var next = {CULLED}u;
    loop {{
        var i = next;
        if (bits.x != 0u) {{
            i = firstTrailingBit(bits.x);
            bits.x = bits.x & (bits.x - 1u);
        }} else if (bits.y != 0u) {{
            i = 32u + firstTrailingBit(bits.y);
            bits.y = bits.y & (bits.y - 1u);
        }} else if (next < count) {{
            next = next + 1u;
        }} else {{
            break;
        }}
        let record = tiles[start + {TILE_ENTRY}u * i];
        let d = group_leaf_{mask:x}(at0 + record, p);
        if (d < best.x) {{
            best = vec2<f32>(d, tables_f32(at0 + record + 1u));
        }}
    }}
    return best;
}}

"
    )
}

impl Writer {
    /// A large union at point `p` into variable `d`: its leaves as data (the group's
    /// walker), then its other operands as code; the variable holding the union.
    pub(super) fn group(
        &mut self,
        shape: &Shape,
        (id, g): (crate::ir::NodeId, &std::sync::Arc<Group>),
        d: &str,
        p: &str,
    ) -> String {
        if !self.groups.iter().any(|x| x.key == g.key) {
            self.groups.push(g.clone());
        }
        let call = match self.tiled.get(&id) {
            Some(&slot) => tiled_call(g, slot, p),
            None => call(g, p),
        };
        let value = if self.blend {
            format!("{call}.xyyy * vec4<f32>(1.0, 1.0, 1.0, 0.0)")
        } else {
            call
        };
        self.line(&format!("let {d} = {value};"));
        let mode = if self.blend { "_blend" } else { "" };
        let mut acc = d.to_string();
        for &o in &g.others {
            let dd = self.shape(shape, o, p);
            let next = self.fresh("d");
            self.line(&format!("let {next} = op_union{mode}({acc}, {dd}, 0.0);"));
            acc = next;
        }
        acc
    }
}
