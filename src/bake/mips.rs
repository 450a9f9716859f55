//! Stage 5: the boundary-symmetric mip filter of §4.5 (Figs. 15–16).
//!
//! Level `l + 1` comes from level `l` in two steps:
//! 1. a 3 × 3 Gaussian (1 2 1 ⊗ 1 2 1 / 16) at every sample of level `l`. A side
//!    sample gathers its missing row from every chart across the side; a corner sample
//!    gathers from every chart around the vertex, arranged uniformly: the centre keeps
//!    4/16, the first samples along the vertex's edges share 8/16 and the charts'
//!    diagonal samples share 4/16, whatever the vertex's valence (4/16 and 2/16 and
//!    1/16 each at valence 4, the plain 3 × 3 kernel).
//! 2. linear interpolation of the smoothed samples to level `l + 1`'s sample points,
//!    spaced 1 / (n/2 − 1) apart in the chart's parameter.
//!
//! Both steps compute each shared sample once, in the [`Samples`] store, so border
//! texels stay bitwise identical at every level. At a mesh boundary (a side with one
//! chart) the missing row is the chart's own (a mirror).

use super::charts::{corner_texel, side_texel, ChartTable, Samples};
use rayon::prelude::*;

/// The channels filtered through the mip chain: colour (3), roughness, metallic,
/// emission (3), object-space normal (3).
pub const CHANNELS: usize = 11;

/// The emission's channels within a sample's [`CHANNELS`].
pub const EMISSION: std::ops::Range<usize> = 5..8;

/// A sample's channels.
pub type Texel<const K: usize> = [f32; K];

fn axpy<const K: usize>(acc: &mut [f64; K], w: f64, x: &Texel<K>) {
    for (a, v) in acc.iter_mut().zip(x) {
        *a += w * *v as f64;
    }
}

fn to_texel<const K: usize>(acc: [f64; K]) -> Texel<K> {
    acc.map(|a| a as f32)
}

/// Step 1: the boundary-symmetric 3 × 3 Gaussian at every sample (n ≥ 4).
pub fn smooth<const K: usize>(table: &ChartTable, s: &Samples<Texel<K>>) -> Samples<Texel<K>> {
    let n = s.n;
    assert!(n >= 4, "the mip filter needs at least 4 samples per side");
    let m = n - 2;
    let last = n - 1;
    let w = [0.25, 0.5, 0.25];

    // Corners: the vertex's own value, its edges' first samples, its charts' diagonals.
    let corners = (0..s.corners.len())
        .into_par_iter()
        .map(|v| {
            let around = &table.around[v];
            if around.is_empty() {
                return s.corners[v];
            }
            let mut acc = [0.0; K];
            axpy(&mut acc, 0.25, &s.corners[v]);
            let mut edges: Vec<u32> = Vec::with_capacity(2 * around.len());
            for &(c, q) in around {
                for side in [q as usize, (q as usize + 3) % 4] {
                    let e = table.sides[c as usize][side].0;
                    if !edges.contains(&e) {
                        edges.push(e);
                    }
                }
            }
            let we = 0.5 / edges.len() as f64;
            for &e in &edges {
                let edge = &table.edges[e as usize];
                let k = if edge.a as usize == v { 1 } else { last - 1 };
                axpy(&mut acc, we, &s.on_edge(table, e as usize, k));
            }
            let wd = 0.25 / around.len() as f64;
            for &(c, q) in around {
                let (i, j) = corner_texel(n, q as usize);
                let i = if i == 0 { 1 } else { last - 1 };
                let j = if j == 0 { 1 } else { last - 1 };
                axpy(&mut acc, wd, &s.get(table, c as usize, i, j));
            }
            to_texel(acc)
        })
        .collect();

    // Side samples: the row along the edge, and the first inner row of every chart on it.
    let edges = (0..table.edges.len() * m)
        .into_par_iter()
        .map(|t| {
            let (e, k) = (t / m, t % m + 1);
            let edge = &table.edges[e];
            let mut acc = [0.0; K];
            for (d, wk) in w.iter().enumerate() {
                axpy(&mut acc, 0.5 * wk, &s.on_edge(table, e, k + d - 1));
            }
            let across = 0.5 / edge.sides.len().max(1) as f64;
            for &(c, side) in &edge.sides {
                let reversed = table.sides[c as usize][side as usize].1;
                for (d, wk) in w.iter().enumerate() {
                    let along = k + d - 1;
                    let ks = if reversed { last - along } else { along };
                    let (i, j) = side_texel(n, side as usize, ks, 1);
                    axpy(&mut acc, across * wk, &s.get(table, c as usize, i, j));
                }
            }
            to_texel(acc)
        })
        .collect();

    // Interiors: the plain kernel over the chart's grid.
    let interiors = (0..table.len())
        .into_par_iter()
        .flat_map_iter(|c| {
            let g = s.grid(table, c);
            let mut out = Vec::with_capacity(m * m);
            for j in 1..=m {
                for i in 1..=m {
                    let mut acc = [0.0; K];
                    for (dj, wj) in w.iter().enumerate() {
                        for (di, wi) in w.iter().enumerate() {
                            axpy(&mut acc, wi * wj, &g[(j + dj - 1) * n + i + di - 1]);
                        }
                    }
                    out.push(to_texel(acc));
                }
            }
            out
        })
        .collect();
    Samples {
        n,
        corners,
        edges,
        interiors,
    }
}

fn lerp<const K: usize>(a: &Texel<K>, b: &Texel<K>, t: f64) -> Texel<K> {
    std::array::from_fn(|c| (a[c] as f64 + (b[c] as f64 - a[c] as f64) * t) as f32)
}

/// Where level-(n/2) sample `k` falls in level n's samples: (index, fraction).
fn source(n: usize, k: usize) -> (usize, f64) {
    let x = k as f64 * (n - 1) as f64 / (n / 2 - 1) as f64;
    let i = (x.floor() as usize).min(n - 2);
    (i, x - i as f64)
}

/// Step 2: linear interpolation of the smoothed samples to the next level's points.
pub fn interpolate<const K: usize>(table: &ChartTable, s: &Samples<Texel<K>>) -> Samples<Texel<K>> {
    let n = s.n;
    let h = n / 2;
    let m = h - 2;
    let edges = (0..table.edges.len() * m)
        .into_par_iter()
        .map(|t| {
            let (e, k) = (t / m, t % m + 1);
            let (i, f) = source(n, k);
            lerp(&s.on_edge(table, e, i), &s.on_edge(table, e, i + 1), f)
        })
        .collect();
    let interiors = (0..table.len())
        .into_par_iter()
        .flat_map_iter(|c| {
            let g = s.grid(table, c);
            let mut out = Vec::with_capacity(m * m);
            for j in 1..=m {
                for i in 1..=m {
                    let (x, fx) = source(n, i);
                    let (y, fy) = source(n, j);
                    let top = lerp(&g[y * n + x], &g[y * n + x + 1], fx);
                    let bottom = lerp(&g[(y + 1) * n + x], &g[(y + 1) * n + x + 1], fx);
                    out.push(lerp(&top, &bottom, fy));
                }
            }
            out
        })
        .collect();
    Samples {
        n: h,
        corners: s.corners.clone(),
        edges,
        interiors,
    }
}

/// Every level from `level0` down to 2 samples per side.
pub fn chain<const K: usize>(
    table: &ChartTable,
    level0: Samples<Texel<K>>,
) -> Vec<Samples<Texel<K>>> {
    let mut levels = vec![level0];
    while levels.last().is_some_and(|l| l.n >= 4) {
        let last = levels.last().expect("non-empty");
        let next = interpolate(table, &smooth(table, last));
        levels.push(next);
    }
    levels
}
