//! The packed layout (§3.4, Table 1): grown charts of different sizes, each with its
//! own mip pyramid, packed into one texture with a lookup table.
//!
//! Every cell (mesh quad of the chart grid) has `cell_size` = N samples a side at level
//! 0, N a power of two, and N/2^l at level l, as in the flat layout; a chart of `a × b`
//! cells places its cells side by side, sharing the samples on their common sides, so
//! at level l it is `a·(n_l − 1) + 1` by `b·(n_l − 1) + 1` texels with n_l = N/2^l: a
//! rectangle whose texel density is the same as every other chart's. The outermost
//! texel centres lie on the chart's boundary (the half-texel inset): chart-local
//! (u, v) ∈ [0, 1]² maps to texel `origin_l + 0.5 + (u, v) · (w_l − 1, h_l − 1)`.
//!
//! A chart's pyramid is one block: level 0 at the block's top left, and levels 1, 2, …
//! side by side below it. The blocks are packed in shelves, tallest first, left to
//! right, as the paper does ([SGR96]): the texture is `size` wide and only as tall as
//! the shelves. The lookup table is [`PackedLayout::charts`] (each block's origin and
//! cells), serialized into the glTF's `extras.sdfc_atlas`, and the per-level rectangles
//! follow from it ([`PackedLayout::rect`]).
//!
//! The paper also lets charts of the same size differ in resolution (by area or
//! detail); here resolution follows the chart's size, so the texel density is uniform
//! and neighbouring sides always have the same samples.

use serde::{Deserialize, Serialize};

/// One chart of the packed layout: its block's top-left texel and its cells along u, v.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PackedChart {
    pub origin: [u32; 2],
    pub cells: [u32; 2],
}

/// Where every chart's levels lie in the packed atlas.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PackedLayout {
    /// The atlas image's width and height in texels.
    pub width: u32,
    pub height: u32,
    /// N: a cell's level-0 samples a side (a power of two, at least 2).
    pub cell_size: u32,
    /// The number of levels, from N samples a cell down to 2.
    pub levels: u32,
    pub charts: Vec<PackedChart>,
}

/// The longest side, in texels, of a cell or a chart that a layout read from a file
/// may have (far beyond any image a reader decodes; it keeps every texel sum of a
/// chart's pyramid inside u32).
pub const MAX_SIDE: u32 = 1 << 24;

/// A chart's size in texels at level `l`, for `cells` cells and cell size `n`.
fn size(cells: [u32; 2], n: u32, l: usize) -> [u32; 2] {
    let nl = n >> l;
    cells.map(|c| c * (nl - 1) + 1)
}

/// A chart's block (its whole pyramid) in texels, and each level's offset in it.
fn block(cells: [u32; 2], n: u32, levels: usize) -> ([u32; 2], Vec<[u32; 2]>) {
    let s0 = size(cells, n, 0);
    let mut offsets = vec![[0, 0]];
    let mut x = 0;
    for l in 1..levels {
        offsets.push([x, s0[1]]);
        x += size(cells, n, l)[0];
    }
    let below = if levels > 1 { size(cells, n, 1)[1] } else { 0 };
    ([s0[0].max(x), s0[1] + below], offsets)
}

impl PackedLayout {
    pub fn levels(&self) -> usize {
        self.levels as usize
    }

    /// The samples a cell side has at level `l`.
    pub fn cell_at(&self, l: usize) -> u32 {
        self.cell_size >> l
    }

    /// Chart `p`'s rectangle at level `l`: `[x, y, width, height]` in texels.
    pub fn rect(&self, p: usize, l: usize) -> [u32; 4] {
        let chart = &self.charts[p];
        let (_, offsets) = block(chart.cells, self.cell_size, self.levels());
        let [w, h] = size(chart.cells, self.cell_size, l);
        [
            chart.origin[0] + offsets[l][0],
            chart.origin[1] + offsets[l][1],
            w,
            h,
        ]
    }

    /// The top-left texel of cell `(i, j)` of chart `p` at level `l` (its `n_l × n_l`
    /// samples; neighbouring cells of a chart share a row or column).
    pub fn cell_origin(&self, p: usize, i: u32, j: u32, l: usize) -> [u32; 2] {
        let [x, y, _, _] = self.rect(p, l);
        let step = self.cell_at(l) - 1;
        [x + i * step, y + j * step]
    }

    /// The level-0 atlas coordinate (glTF TEXCOORD_0, in [0, 1]) of chart-local (u, v).
    pub fn texcoord(&self, p: usize, u: f64, v: f64) -> [f32; 2] {
        let [x, y, w, h] = self.rect(p, 0);
        [
            ((x as f64 + 0.5 + u * (w - 1) as f64) / self.width as f64) as f32,
            ((y as f64 + 0.5 + v * (h - 1) as f64) / self.height as f64) as f32,
        ]
    }

    /// The packed layout of charts with these cells (along u, v) in an atlas `size`
    /// wide and at most `size` tall, with the largest cell size that fits; `None` when
    /// even 2 samples a cell do not.
    pub fn fit(dims: &[[u32; 2]], size: u32) -> Option<PackedLayout> {
        let mut n = if size >= 2 { 1 << size.ilog2() } else { 0 };
        while n >= 2 {
            if let Some(layout) = PackedLayout::pack(dims, size, n) {
                return Some(layout);
            }
            n /= 2;
        }
        None
    }

    /// Shelf packing at cell size `n` (see the module docs), if it fits.
    fn pack(dims: &[[u32; 2]], size: u32, n: u32) -> Option<PackedLayout> {
        let levels = n.ilog2() as usize;
        let blocks: Vec<[u32; 2]> = dims.iter().map(|&d| block(d, n, levels).0).collect();
        let mut order: Vec<usize> = (0..dims.len()).collect();
        order.sort_by_key(|&p| {
            (
                std::cmp::Reverse(blocks[p][1]),
                std::cmp::Reverse(blocks[p][0]),
                p,
            )
        });
        let mut charts = vec![
            PackedChart {
                origin: [0, 0],
                cells: [1, 1],
            };
            dims.len()
        ];
        let (mut x, mut y, mut shelf) = (0u64, 0u64, 0u64);
        for p in order {
            let [w, h] = blocks[p].map(u64::from);
            if w > size as u64 {
                return None;
            }
            if x + w > size as u64 {
                y += shelf;
                (x, shelf) = (0, 0);
            }
            if shelf == 0 {
                shelf = h;
            }
            if y + h > size as u64 {
                return None;
            }
            charts[p] = PackedChart {
                origin: [x as u32, y as u32],
                cells: dims[p],
            };
            x += w;
        }
        Some(PackedLayout {
            width: size,
            height: (y + shelf).max(1) as u32,
            cell_size: n,
            levels: levels as u32,
            charts,
        })
    }

    /// The texels that hold samples (every chart at every level) over the image's.
    pub fn utilisation(&self) -> f64 {
        let used: u64 = (0..self.charts.len())
            .flat_map(|p| (0..self.levels()).map(move |l| (p, l)))
            .map(|(p, l)| {
                let [_, _, w, h] = self.rect(p, l);
                w as u64 * h as u64
            })
            .sum();
        used as f64 / (self.width as u64 * self.height as u64) as f64
    }

    /// Checks that the layout is well formed (from a file): a power-of-two cell size,
    /// as many levels as it has, every chart's block inside the image, no two
    /// overlapping.
    pub fn check(&self) -> Result<(), String> {
        let n = self.cell_size;
        if n < 2 || n > MAX_SIDE || !n.is_power_of_two() || self.levels != n.ilog2() {
            return Err(format!(
                "the packed layout's cell size {n} with {} levels is not a power of two of at least 2 with log2(N) levels",
                self.levels
            ));
        }
        let mut rects = Vec::with_capacity(self.charts.len());
        for (p, chart) in self.charts.iter().enumerate() {
            // Each side in u64 first: [`block`]'s u32 sums then cannot overflow.
            let side = |c: u32| c as u64 * n as u64;
            if chart.cells.contains(&0) || chart.cells.iter().any(|&c| side(c) > MAX_SIDE as u64) {
                return Err(format!("packed chart {p} has {:?} cells", chart.cells));
            }
            let ([w, h], _) = block(chart.cells, n, self.levels());
            let [x, y] = chart.origin.map(u64::from);
            if x + w as u64 > self.width as u64 || y + h as u64 > self.height as u64 {
                return Err(format!(
                    "packed chart {p} lies outside the {}×{} atlas",
                    self.width, self.height
                ));
            }
            rects.push((x, y, x + w as u64, y + h as u64, p));
        }
        // Overlaps: sweep by x. The blocks open at the sweep's x are disjoint in y (or
        // two already overlap), so a new block can only overlap the open blocks just
        // above and below its top edge: O(C log C) for any input.
        rects.sort();
        let mut open: std::collections::BTreeMap<u64, (u64, usize)> = Default::default();
        let mut ends: std::collections::BinaryHeap<std::cmp::Reverse<(u64, u64)>> =
            Default::default();
        for &(x0, y0, x1, y1, p) in &rects {
            while let Some(&std::cmp::Reverse((end, top))) = ends.peek() {
                if end > x0 {
                    break;
                }
                ends.pop();
                open.remove(&top);
            }
            let above = open.range(..=y0).next_back();
            let below = open.range(y0..).next();
            for (&top, &(bottom, q)) in above.into_iter().chain(below) {
                if top < y1 && y0 < bottom {
                    return Err(format!("packed charts {q} and {p} overlap"));
                }
            }
            open.insert(y0, (y1, p));
            ends.push(std::cmp::Reverse((x1, y0)));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pyramids_fit_their_blocks_and_nothing_overlaps() {
        let dims: Vec<[u32; 2]> = (0..40).map(|k| [1 + k % 5, 1 + (k * 7) % 3]).collect();
        let layout = PackedLayout::fit(&dims, 512).expect("fits");
        layout.check().expect("well formed");
        assert!(layout.height <= 512);
        // Level l of a 3-cell chart at N = 16: 3 · (16/2^l − 1) + 1 texels.
        let p = dims.iter().position(|d| d[0] == 3).unwrap();
        let n = layout.cell_size;
        for l in 0..layout.levels() {
            assert_eq!(layout.rect(p, l)[2], 3 * ((n >> l) - 1) + 1);
        }
        // The same charts at half the cell size would leave a lot unused: the fit
        // picked the largest.
        assert!(PackedLayout::pack(&dims, 512, n * 2).is_none());
        assert!(layout.utilisation() > 0.4, "{}", layout.utilisation());
    }

    #[test]
    fn texcoords_put_the_corners_on_border_texel_centres() {
        let layout = PackedLayout::fit(&[[2, 3], [1, 1]], 128).unwrap();
        let [x, y, w, h] = layout.rect(0, 0);
        let tc = layout.texcoord(0, 1.0, 1.0);
        assert_eq!(tc[0] * layout.width as f32, (x + w) as f32 - 0.5);
        assert_eq!(tc[1] * layout.height as f32, (y + h) as f32 - 0.5);
    }
}
