//! Per-tile culling, the runtime's half (`codegen::tiles` writes the shader's): every
//! frame, each leaf of a traced group is binned into the screen tiles its box can
//! project into, and the render's trace evaluates, in a pixel's tile, only the leaves
//! listed there.
//!
//! Why it is exact. A leaf's box is grown by the trace's hit tolerance (`epsilon ×
//! max(t, 1)` at the box's farthest point) and by twice the normal's tap distance,
//! then projected to the screen (its corners, so the rectangle holds the projection
//! of the whole box) and widened by a pixel for single precision. A pixel whose
//! centre lies outside that rectangle has a ray that never comes within those margins
//! of the leaf, so along the ray, at the hit and at the normal's taps, the leaf is
//! farther than the nearest listed leaf: the trace meets the same surface at the same
//! point, with the same material and normal, in steps no shorter than the whole
//! union's. A box that reaches behind the eye is listed in every tile.
//!
//! Within a tile, each ray goes further (`codegen::tiles::cull`): a list entry holds
//! the leaf's grown box as well as its record, and the shader skips, for the whole
//! trace of one ray, the first 64 entries whose boxes that ray misses, the same test
//! as the binning's done exactly per ray; where the render target is its groups
//! alone, the ray is traced only between its first entry into a box and its last
//! exit. The boxes are grown by the larger of the screen's and the light's margins
//! and a little more for single precision (`tests/tiles.rs` checks that every ray
//! that meets a leaf's margins meets its entry's box).
//!
//! Limits, checked before the work: a tile lists at most [`MAX_PER_TILE`] leaves of
//! a group (past that the shader walks the group's whole tree there, which is what it
//! does without tiles), and the lists of a frame hold at most [`MAX_WORDS`] words
//! (past that the per-tile limit is halved until they fit).

use crate::codegen::tiles::{Tiling, TILES_HEADER, TILE_ENTRY, WHOLE};
use crate::view::View;
use glam::{DMat3, DVec3};

/// A tile's side in pixels.
pub const TILE: u32 = 4;

/// The most leaves of one group a tile lists; past it the tile walks the whole tree.
pub const MAX_PER_TILE: u32 = 256;

/// The most words of leaf lists in a frame's `tiles` buffer (16 MiB: 599,186 listed
/// leaves, [`TILE_ENTRY`] words each).
pub const MAX_WORDS: usize = 1 << 22;

/// A frame's `tiles` buffer, with what it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Binned {
    pub words: Vec<u32>,
    /// Tiles across and down.
    pub across: u32,
    pub down: u32,
    /// The sun's grid, whose cells follow the screen's tiles.
    pub light: LightGrid,
    /// Entries (tile, group) that walk the whole tree.
    pub whole: usize,
    /// Leaves listed, over every entry.
    pub leaves: usize,
}

impl Binned {
    /// The entry of `tile` and `slot`: its leaf records, or `None` for the whole tree.
    pub fn list(&self, tile: u32, slot: u32) -> Option<Vec<u32>> {
        self.boxes(tile, slot)
            .map(|l| l.into_iter().map(|(record, _)| record).collect())
    }

    /// The entry of `tile` and `slot`: its leaves' records with the boxes the shader
    /// tests rays against (min, max), or `None` for the whole tree.
    pub fn boxes(&self, tile: u32, slot: u32) -> Option<Vec<(u32, [f32; 6])>> {
        let groups = self.words[3];
        let h = (TILES_HEADER + 2 * (tile * groups + slot)) as usize;
        let (start, count) = (self.words[h] as usize, self.words[h + 1]);
        let at = |i: usize| {
            let e = &self.words[start + i * TILE_ENTRY as usize..][..TILE_ENTRY as usize];
            (e[0], std::array::from_fn(|k| f32::from_bits(e[1 + k])))
        };
        (count != WHOLE).then(|| (0..count as usize).map(at).collect())
    }

    /// The tile of the pixel at integer position (`x`, `y`).
    pub fn tile_of(&self, x: u32, y: u32) -> u32 {
        (y / TILE).min(self.down - 1) * self.across + (x / TILE).min(self.across - 1)
    }
}

/// The pixels (first and last column, first and last row) whose centres the box
/// `[lo, hi]` can project onto in `view`; `None` when none (behind the eye or off the
/// screen).
fn footprint(view: &View, to_camera: &DMat3, lo: DVec3, hi: DVec3) -> Option<[u32; 4]> {
    let (w, h) = (view.width.max(1) as f64, view.height.max(1) as f64);
    let all = [0, view.width.max(1) - 1, 0, view.height.max(1) - 1];
    let tan = (view.camera.fov * 0.5).tan();
    let aspect = w / h;
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    let mut behind = 0;
    for i in 0..8 {
        let q = DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        // (depth, right, up): the ray through screen point (a, b) is forward + a right + b up.
        let c = *to_camera * (q - view.camera.eye);
        if c.x <= 1e-9 * (1.0 + c.y.abs() + c.z.abs()) {
            behind += 1;
            continue;
        }
        let px = (c.y / (c.x * aspect * tan) + 1.0) * 0.5 * w;
        let py = (1.0 - c.z / (c.x * tan)) * 0.5 * h;
        (x0, x1, y0, y1) = (x0.min(px), x1.max(px), y0.min(py), y1.max(py));
    }
    if behind == 8 {
        return None;
    }
    if behind > 0 {
        return Some(all);
    }
    // Pixel i's centre is i + 0.5; one more pixel each way for single precision.
    let first = |v: f64| (v - 0.5).floor() - 1.0;
    let last = |v: f64| (v - 0.5).ceil() + 1.0;
    let (fx, lx, fy, ly) = (first(x0), last(x1), first(y0), last(y1));
    if lx < 0.0 || ly < 0.0 || fx > w - 1.0 || fy > h - 1.0 {
        return None;
    }
    let clamp = |v: f64, n: f64| v.clamp(0.0, n - 1.0) as u32;
    Some([clamp(fx, w), clamp(lx, w), clamp(fy, h), clamp(ly, h)])
}

/// The light's grid: the plane across the sun's direction, where shadow rays (all
/// parallel) are points, cut into square cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightGrid {
    pub across: u32,
    pub down: u32,
    pub origin: [f64; 2],
    pub cell: f64,
    /// The plane's axes.
    pub u: DVec3,
    pub v: DVec3,
}

impl LightGrid {
    /// The cell of the shadow ray through `p`, counted after the screen's tiles; the
    /// one past the grid (an empty list) when `p` is off it.
    pub fn cell_of(&self, p: DVec3, first: u32) -> u32 {
        let c = [
            (p.dot(self.u) - self.origin[0]) / self.cell,
            (p.dot(self.v) - self.origin[1]) / self.cell,
        ];
        if c[0] < 0.0 || c[1] < 0.0 || c[0] >= self.across as f64 || c[1] >= self.down as f64 {
            return first + self.across * self.down;
        }
        first + c[1] as u32 * self.across + c[0] as u32
    }

    /// The grid over `spans` (each leaf's extent along `u` and `v`), with cells about
    /// twice a typical leaf's side and at most [`MAX_LIGHT_CELLS`] across.
    fn over(spans: &[[f64; 4]], u: DVec3, v: DVec3) -> LightGrid {
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        let mut sides: Vec<f64> = Vec::with_capacity(spans.len());
        for s in spans {
            lo = [lo[0].min(s[0]), lo[1].min(s[2])];
            hi = [hi[0].max(s[1]), hi[1].max(s[3])];
            sides.push((s[1] - s[0]).max(s[3] - s[2]));
        }
        if spans.is_empty() {
            (lo, hi) = ([0.0; 2], [1.0; 2]);
            sides.push(1.0);
        }
        sides.sort_by(f64::total_cmp);
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        let cell = (2.0 * sides[sides.len() / 2])
            .max(extent / MAX_LIGHT_CELLS as f64)
            .max(1e-9);
        // One cell more on every side, for single precision at the grid's edge.
        let origin = [lo[0] - cell, lo[1] - cell];
        let count = |a: f64, b: f64| (((b - a) / cell).ceil() as u32 + 2).min(MAX_LIGHT_CELLS + 2);
        LightGrid {
            across: count(lo[0], hi[0]),
            down: count(lo[1], hi[1]),
            origin,
            cell,
            u,
            v,
        }
    }
}

/// The most light cells across and down.
pub const MAX_LIGHT_CELLS: u32 = 256;

/// Every leaf's cells as (slot, leaf: an index into [`Leaves`], first cell, rectangle
/// of cells: first and last across, first and last down), slot by slot in record
/// order, the screen's tiles before the light's cells; the light's grid.
type Rect = (u32, u32, u32, [u32; 4]);

/// Every leaf's record and its box grown by the larger of its two margins (the
/// screen's and the light's), as a list entry holds them: the shader's per-ray test
/// (`scene_cull`) reads the box.
type Leaves = Vec<(u32, [f64; 6])>;

fn leaf_cells(
    tiling: &Tiling,
    view: &View,
    (across, down): (u32, u32),
) -> (Vec<Rect>, Leaves, LightGrid) {
    let (w, h) = (view.width.max(1), view.height.max(1));
    let c = &view.camera;
    let basis = DMat3::from_cols(c.forward, c.right, c.up);
    let to_camera = (basis.determinant().abs() > 1e-12).then(|| basis.inverse());
    let scale = tiling.tap * 1e3;
    let l = view.sun.direction.try_normalize().unwrap_or(DVec3::Y);
    let u = l.any_orthonormal_vector();
    let v = l.cross(u);
    let mut rects: Vec<Rect> = Vec::new();
    let mut spans: Vec<(u32, u32, [f64; 4])> = Vec::new();
    let mut leaves: Leaves = Vec::new();
    for (slot, g) in tiling.groups.iter().enumerate() {
        for (b, &record) in g.boxes.iter().zip(&g.records) {
            let leaf = leaves.len() as u32;
            let far = [b.min, b.max]
                .iter()
                .map(|&q| (q - c.eye).abs())
                .fold(DVec3::ZERO, DVec3::max)
                .length();
            let margin =
                1.01 * (view.epsilon * far.max(1.0) + 2.0 * 3f64.sqrt() * tiling.tap) + 1e-6;
            let pixels = match &to_camera {
                Some(m) => footprint(view, m, b.min - margin, b.max + margin),
                None => Some([0, w - 1, 0, h - 1]),
            };
            if let Some([x0, x1, y0, y1]) = pixels {
                let rect = [x0 / TILE, x1 / TILE, y0 / TILE, y1 / TILE];
                rects.push((slot as u32, leaf, 0, rect));
            }
            // Shadow rays stop at 1e-4 × SCENE_SCALE (scene_shadow); single precision
            // rounds a point's projection by about 1e-6 of its distance from the origin,
            // and the ray's direction by about 1e-7 of the distance it travels.
            let size = b.min.abs().max(b.max.abs()).length();
            let grow = 1.01e-4 * scale + 4e-6 * (1.0 + size) + 2e-7 * view.far + 1e-6;
            // The shader tests rays against this box in single precision: a little
            // more for its rounding (about 1e-7 of the distances it subtracts).
            let m = margin.max(grow) + 1e-6 * (size + view.far);
            let (lo, hi) = (b.min - m, b.max + m);
            leaves.push((record, [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]));
            let mut span = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
            for i in 0..8 {
                let q = DVec3::new(
                    if i & 1 == 0 { b.min.x } else { b.max.x },
                    if i & 2 == 0 { b.min.y } else { b.max.y },
                    if i & 4 == 0 { b.min.z } else { b.max.z },
                );
                let (a, bb) = (q.dot(u), q.dot(v));
                span = [
                    span[0].min(a),
                    span[1].max(a),
                    span[2].min(bb),
                    span[3].max(bb),
                ];
            }
            let span = [
                span[0] - grow,
                span[1] + grow,
                span[2] - grow,
                span[3] + grow,
            ];
            spans.push((slot as u32, leaf, span));
        }
    }
    let only: Vec<[f64; 4]> = spans.iter().map(|s| s.2).collect();
    let light = LightGrid::over(&only, u, v);
    let first = across * down;
    for &(slot, leaf, s) in &spans {
        let cell =
            |x: f64, o: f64, n: u32| (((x - o) / light.cell).floor().max(0.0) as u32).min(n - 1);
        let (ou, ov) = (light.origin[0], light.origin[1]);
        let r = [
            cell(s[0], ou, light.across),
            cell(s[1], ou, light.across),
            cell(s[2], ov, light.down),
            cell(s[3], ov, light.down),
        ];
        rects.push((slot, leaf, first, r));
    }
    (rects, leaves, light)
}

/// Bins `tiling`'s leaves into the screen tiles of `view` and the cells of its sun's
/// grid: the words of the `tiles` buffer (`codegen::tiles` reads them).
pub fn bin(tiling: &Tiling, view: &View) -> Binned {
    let (w, h) = (view.width.max(1), view.height.max(1));
    let (across, down) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let groups = tiling.groups.len() as u32;
    let (rects, leaves, light) = leaf_cells(tiling, view, (across, down));
    let (u, v) = (light.u, light.v);
    // Cells: the screen's tiles, the light's cells, and one empty cell past the grid.
    let cells = across * down + light.across * light.down + 1;
    let entries = (cells * groups) as usize;
    let row = |base: u32| if base == 0 { across } else { light.across };
    let each = |(slot, base, rect): (u32, u32, &[u32; 4]), f: &mut dyn FnMut(usize)| {
        for y in rect[2]..=rect[3] {
            for x in rect[0]..=rect[1] {
                f(((base + y * row(base) + x) * groups + slot) as usize);
            }
        }
    };
    let mut counts = vec![0u32; entries];
    for (slot, _, base, rect) in &rects {
        each((*slot, *base, rect), &mut |e| {
            counts[e] = counts[e].saturating_add(1)
        });
    }
    // The per-tile limit, halved until the lists fit.
    let mut cap = MAX_PER_TILE;
    let listed_words = |cap: u32| -> usize {
        counts
            .iter()
            .filter(|&&n| n <= cap)
            .map(|&n| n as usize * TILE_ENTRY as usize)
            .sum()
    };
    while cap > 0 && listed_words(cap) > MAX_WORDS {
        cap /= 2;
    }
    let head = TILES_HEADER as usize + 2 * entries;
    let mut words = vec![0u32; head];
    let f = |x: f64| (x as f32).to_bits();
    words[..TILES_HEADER as usize].copy_from_slice(&[
        TILE,
        across,
        down,
        groups,
        light.across,
        light.down,
        f(light.origin[0]),
        f(light.origin[1]),
        f(light.cell),
        f(u.x),
        f(u.y),
        f(u.z),
        f(v.x),
        f(v.y),
        f(v.z),
        0,
    ]);
    let mut next = vec![0u32; entries];
    let mut at = head as u32;
    let mut whole = 0;
    for (e, &n) in counts.iter().enumerate() {
        let h = TILES_HEADER as usize + 2 * e;
        if n > cap {
            words[h..h + 2].copy_from_slice(&[0, WHOLE]);
            whole += 1;
        } else {
            words[h..h + 2].copy_from_slice(&[at, n]);
            next[e] = at;
            at += n * TILE_ENTRY;
        }
    }
    words.resize(at as usize, 0);
    // In slot order, then record order: each list ascends, as ties need. An entry is
    // the leaf's record and its box (min, max, as f32 bits).
    for (slot, leaf, base, rect) in &rects {
        let (record, b) = leaves[*leaf as usize];
        let mut entry = [record; TILE_ENTRY as usize];
        for k in 0..6 {
            entry[1 + k] = (b[k] as f32).to_bits();
        }
        each((*slot, *base, rect), &mut |e| {
            if counts[e] <= cap {
                let n = next[e] as usize;
                words[n..n + TILE_ENTRY as usize].copy_from_slice(&entry);
                next[e] += TILE_ENTRY;
            }
        });
    }
    let leaves = (at as usize - head) / TILE_ENTRY as usize;
    Binned {
        words,
        across,
        down,
        light,
        whole,
        leaves,
    }
}
