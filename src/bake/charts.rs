//! Stage 2: the chart table, and the sample graph that makes borders identical.
//!
//! Every quad of the mesh is a chart, parameterized bilinearly over [0, 1]² from its
//! corners: corner 0 at (0, 0), 1 at (1, 0), 2 at (1, 1), 3 at (0, 1). Side `s` runs
//! from corner `s` to corner `s + 1`. On a manifold quad mesh two quads share one whole
//! side, one corner, or nothing, which are the paper's two topological rules (§4.1).
//!
//! A [`Samples`] holds one value per sample of every chart at one resolution `n` (the
//! chart's texels per side at that level), but stores each *shared* sample once: one
//! value per mesh vertex (the chart corners), `n − 2` per mesh edge (the side's inner
//! samples, in the edge's own direction from its lower to its higher vertex), and
//! `(n − 2)²` per chart interior. Reading a chart's `n × n` grid copies the shared
//! values in, so two charts' border texels are the same value, bitwise, by construction.

use super::mesh::QuadMesh;
use glam::DVec3;
use std::collections::HashMap;

/// The chart's bilinear patch: corner 0 at (0, 0), 1 at (1, 0), 2 at (1, 1), 3 at (0, 1).
pub fn bilinear(q: [DVec3; 4], u: f64, v: f64) -> DVec3 {
    q[0] * ((1.0 - u) * (1.0 - v))
        + q[1] * (u * (1.0 - v))
        + q[2] * (u * v)
        + q[3] * ((1.0 - u) * v)
}

/// One mesh edge: its vertices (`a < b`) and the charts that have it as a side.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    pub a: u32,
    pub b: u32,
    /// `(chart, side)`, in chart order.
    pub sides: Vec<(u32, u8)>,
}

/// The charts of a quad mesh and how they meet.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartTable {
    /// Each chart's corner vertices.
    pub corners: Vec<[u32; 4]>,
    /// Each chart's side edges, and whether side `s` runs from the edge's `b` to `a`.
    pub sides: Vec<[(u32, bool); 4]>,
    pub edges: Vec<Edge>,
    /// For each vertex, `(chart, corner)` of every chart that has it as a corner.
    pub around: Vec<Vec<(u32, u8)>>,
}

impl ChartTable {
    /// One chart per quad.
    pub fn new(mesh: &QuadMesh) -> ChartTable {
        let mut edges: Vec<Edge> = Vec::new();
        let mut lookup: HashMap<(u32, u32), u32> = HashMap::new();
        let mut sides = Vec::with_capacity(mesh.quads.len());
        let mut around = vec![Vec::new(); mesh.vertices.len()];
        for (c, q) in mesh.quads.iter().enumerate() {
            let mut chart_sides = [(0, false); 4];
            for s in 0..4 {
                let (from, to) = (q[s], q[(s + 1) % 4]);
                let key = (from.min(to), from.max(to));
                let e = *lookup.entry(key).or_insert_with(|| {
                    edges.push(Edge {
                        a: key.0,
                        b: key.1,
                        sides: Vec::new(),
                    });
                    edges.len() as u32 - 1
                });
                edges[e as usize].sides.push((c as u32, s as u8));
                chart_sides[s] = (e, from > to);
                around[q[s] as usize].push((c as u32, s as u8));
            }
            sides.push(chart_sides);
        }
        ChartTable {
            corners: mesh.quads.clone(),
            sides,
            edges,
            around,
        }
    }

    pub fn len(&self) -> usize {
        self.corners.len()
    }

    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    /// The charts' neighbours along each side: `(chart, side, reversed)` of every other
    /// chart sharing that side's edge; `reversed` when it runs the other way.
    pub fn neighbours(&self, chart: usize, side: usize) -> Vec<(u32, u8, bool)> {
        let (e, rev) = self.sides[chart][side];
        self.edges[e as usize]
            .sides
            .iter()
            .filter(|(c, _)| *c as usize != chart)
            .map(|&(c, s)| (c, s, self.sides[c as usize][s as usize].1 != rev))
            .collect()
    }
}

/// Chart-local texel `(i, j)` of the sample `k` (0 … n − 1 from the side's start) on
/// side `side`, `depth` texels inward.
pub fn side_texel(n: usize, side: usize, k: usize, depth: usize) -> (usize, usize) {
    match side {
        0 => (k, depth),
        1 => (n - 1 - depth, k),
        2 => (n - 1 - k, n - 1 - depth),
        _ => (depth, n - 1 - k),
    }
}

/// [`side_texel`] on a `w × h` chart (sides 0 and 2 are `w` texels long, 1 and 3 `h`).
pub fn side_texel_rect(w: usize, h: usize, side: usize, k: usize, depth: usize) -> (usize, usize) {
    match side {
        0 => (k, depth),
        1 => (w - 1 - depth, k),
        2 => (w - 1 - k, h - 1 - depth),
        _ => (depth, h - 1 - k),
    }
}

/// Chart-local texel of corner `q`.
pub fn corner_texel(n: usize, q: usize) -> (usize, usize) {
    side_texel(n, q, 0, 0)
}

/// One value per sample of a chart table at resolution `n`, shared samples stored once.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples<T> {
    pub n: usize,
    pub corners: Vec<T>,
    /// `n − 2` per edge, from `a` to `b`.
    pub edges: Vec<T>,
    /// `(n − 2)²` per chart, row by row.
    pub interiors: Vec<T>,
}

impl<T: Copy> Samples<T> {
    /// Computes every sample once: `corner(v)`, `edge(e, t)` for t in (0, 1) from `a` to
    /// `b`, and `interior(chart, u, v)`.
    pub fn build(
        table: &ChartTable,
        vertices: usize,
        n: usize,
        corner: impl Fn(usize) -> T + Sync,
        edge: impl Fn(usize, f64) -> T + Sync,
        interior: impl Fn(usize, f64, f64) -> T + Sync,
    ) -> Samples<T>
    where
        T: Send,
    {
        use rayon::prelude::*;
        let m = n - 2;
        let step = 1.0 / (n - 1) as f64;
        Samples {
            n,
            corners: (0..vertices).into_par_iter().map(&corner).collect(),
            edges: (0..table.edges.len() * m)
                .into_par_iter()
                .map(|i| edge(i / m, (i % m + 1) as f64 * step))
                .collect(),
            interiors: (0..table.len() * m * m)
                .into_par_iter()
                .map(|i| {
                    let (c, r) = (i / (m * m), i % (m * m));
                    interior(c, (r % m + 1) as f64 * step, (r / m + 1) as f64 * step)
                })
                .collect(),
        }
    }

    /// Every sample once: the corners, the edges', the interiors'.
    pub fn iter(&self) -> impl Iterator<Item = &T> {
        self.corners
            .iter()
            .chain(&self.edges)
            .chain(&self.interiors)
    }

    /// The sample of chart `c` at chart-local texel `(i, j)`.
    pub fn get(&self, table: &ChartTable, c: usize, i: usize, j: usize) -> T {
        let n = self.n;
        let m = n - 2;
        let last = n - 1;
        let on_u = i == 0 || i == last;
        let on_v = j == 0 || j == last;
        if on_u && on_v {
            let q = match (i == 0, j == 0) {
                (true, true) => 0,
                (false, true) => 1,
                (false, false) => 2,
                (true, false) => 3,
            };
            return self.corners[table.corners[c][q] as usize];
        }
        if !on_u && !on_v {
            return self.interiors[c * m * m + (j - 1) * m + (i - 1)];
        }
        // On a side: its parameter k from the side's start corner.
        let (side, k) = if j == 0 {
            (0, i)
        } else if i == last {
            (1, j)
        } else if j == last {
            (2, last - i)
        } else {
            (3, last - j)
        };
        let (e, reversed) = table.sides[c][side];
        let along = if reversed { last - k } else { k };
        self.edges[e as usize * m + along - 1]
    }

    /// Chart `c`'s whole `n × n` grid, row by row.
    pub fn grid(&self, table: &ChartTable, c: usize) -> Vec<T> {
        let n = self.n;
        (0..n * n)
            .map(|t| self.get(table, c, t % n, t / n))
            .collect()
    }

    /// The value on edge `e` at position `k` (0 … n − 1, from `a` to `b`), corners included.
    pub fn on_edge(&self, table: &ChartTable, e: usize, k: usize) -> T {
        let n = self.n;
        let edge = &table.edges[e];
        if k == 0 {
            self.corners[edge.a as usize]
        } else if k == n - 1 {
            self.corners[edge.b as usize]
        } else {
            self.edges[e * (n - 2) + k - 1]
        }
    }
}
