//! How much of the surface the bake's mesh holds: area-uniform samples of the zero set
//! ([`crate::reference::surface::surface_samples`]) against the mesh's triangles. A
//! part thinner than a cell (a shell, a slit, a small sphere) can fall between the
//! grid's corners, and dual contouring then leaves it out of the mesh without a sign;
//! the bake reports the share of the surface within the bounds it baked, by area, that
//! lies more than half a cell from the mesh, and `sdfc bake` warns when there is any.

use super::images::split_along_02;
use super::mesh::QuadMesh;
use crate::ir::{Aabb, Field};
use glam::{DVec3, IVec3};
use rayon::prelude::*;
use std::collections::HashMap;

/// The sampling grid, in cells along the longest side of the shape's bounds: about
/// two samples per cell-sized area of the surface at this grid, a few thousand for
/// the examples (an f64 evaluation of the field for every 1/128 of a cell's volume
/// near the surface).
pub const SAMPLE_GRID: usize = 24;

/// A sample counts as held when a triangle of the mesh lies within this many of its
/// cells (the mesh's goal: `tests/bake_mesh.rs`).
pub const HELD_CELLS: f64 = 0.5;

/// What [`coverage`] found.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Coverage {
    /// The share of the surface's area (by the samples' areas) farther than
    /// [`HELD_CELLS`] from the mesh.
    pub missed: f64,
    /// The farthest sample from the mesh, in cells (at most 2: farther is not looked at).
    pub farthest: f64,
    /// Samples within the bounds (none: not measured).
    pub samples: usize,
}

/// The surface of `shape` within `bounds` (the box the mesh was made over, finite)
/// against `mesh`: its quads, each split along the diagonal [`split_along_02`] picks
/// (the exported mesh, with `--chart-quads` over 1, lies on finer quads between the
/// same corners). No samples (none within the bounds) is the default: not measured.
pub fn coverage(shape: Field<'_>, mesh: &QuadMesh, bounds: Aabb) -> Coverage {
    use crate::reference::surface::surface_samples_within;
    let Ok(mut samples) = surface_samples_within(shape, bounds, SAMPLE_GRID, 0) else {
        return Coverage::default();
    };
    // The sampler's margin: only what lies within the bounds was meshed for sure.
    samples.retain(|s| s.p.cmpge(bounds.min).all() && s.p.cmple(bounds.max).all());
    let cell = mesh.cell;
    let mut tris = Vec::with_capacity(2 * mesh.quads.len());
    for q in &mesh.quads {
        let p = q.map(|i| mesh.vertices[i as usize]);
        if split_along_02(p) {
            tris.extend([[p[0], p[1], p[2]], [p[0], p[2], p[3]]]);
        } else {
            tris.extend([[p[0], p[1], p[3]], [p[1], p[2], p[3]]]);
        }
    }
    // Triangles by the buckets (two cells a side, from the bounds' corner: small keys)
    // their boxes touch.
    let key = |x: DVec3| ((x - bounds.min) / (2.0 * cell)).floor().as_ivec3();
    let mut buckets: HashMap<IVec3, Vec<u32>> = HashMap::new();
    for (i, [a, b, c]) in tris.iter().enumerate() {
        let (lo, hi) = (key(a.min(*b).min(*c)), key(a.max(*b).max(*c)));
        for x in lo.x..=hi.x {
            for y in lo.y..=hi.y {
                for z in lo.z..=hi.z {
                    buckets
                        .entry(IVec3::new(x, y, z))
                        .or_default()
                        .push(i as u32);
                }
            }
        }
    }
    let far: Vec<(f64, f64)> = samples
        .par_iter()
        .map(|s| {
            let k = key(s.p);
            let mut best = f64::INFINITY;
            for d in (0..27).map(|n| IVec3::new(n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1)) {
                for &i in buckets.get(&(k + d)).into_iter().flatten() {
                    let [a, b, c] = tris[i as usize];
                    best = best.min(to_triangle(s.p, a, b, c));
                }
            }
            // Nothing in the 27 buckets around: farther than two cells.
            ((best / cell).min(2.0), s.area)
        })
        .collect();
    let total: f64 = far.iter().map(|f| f.1).sum();
    let missed: f64 = far.iter().filter(|f| f.0 > HELD_CELLS).map(|f| f.1).sum();
    Coverage {
        // (An empty sum of floats is -0.)
        missed: if total > 0.0 {
            (missed / total).max(0.0)
        } else {
            0.0
        },
        farthest: far.iter().map(|f| f.0).fold(0.0, f64::max),
        samples: far.len(),
    }
}

/// The distance from `p` to triangle `abc`.
fn to_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let n = (b - a).cross(c - a);
    let area2 = n.length();
    if area2 > 1e-18 {
        let n = n / area2;
        let q = p - n * n.dot(p - a);
        // Inside when the three sub-triangles turn the same way.
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| (v - u).cross(q - u).dot(n) >= 0.0);
        if inside {
            return (p - q).length();
        }
    }
    let segment = |u: DVec3, v: DVec3| {
        let d = v - u;
        let t = ((p - u).dot(d) / d.length_squared().max(1e-30)).clamp(0.0, 1.0);
        (p - (u + d * t)).length()
    };
    segment(a, b).min(segment(b, c)).min(segment(c, a))
}
