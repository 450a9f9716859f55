//! How much of the surface the bake's mesh holds: area-uniform samples of the zero set
//! ([`crate::reference::surface::surface_samples`]) against the mesh's triangles. A
//! part thinner than a cell (a shell, a slit, a small sphere) can fall between the
//! grid's corners, and dual contouring then leaves it out of the mesh without a sign;
//! the bake reports the share of the surface within the bounds it baked, by area, that
//! lies more than half a cell from the mesh, and `sdfc bake` warns when there is any.

use super::mesh::QuadMesh;
use crate::ir::{Aabb, Field};
use glam::{DVec3, IVec3};
use rayon::prelude::*;
use std::collections::HashMap;

/// The sampling grid, in cells along the longest side of the bounds baked: about
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
/// against `mesh`: its quads, each split along the diagonal `split_along_02` picks
/// (the exported mesh, with `--chart-quads` over 1, lies on finer quads between the
/// same corners). No samples (none within the bounds) is the default: not measured.
pub fn coverage(shape: Field<'_>, mesh: &QuadMesh, bounds: Aabb) -> Coverage {
    coverage_and_missed(shape, mesh, bounds).0
}

/// [`coverage`], and the samples it found missed (farther than [`HELD_CELLS`]).
pub fn coverage_and_missed(
    shape: Field<'_>,
    mesh: &QuadMesh,
    bounds: Aabb,
) -> (Coverage, Vec<DVec3>) {
    use crate::reference::surface::surface_samples_within;
    let Ok(mut samples) = surface_samples_within(shape, bounds, SAMPLE_GRID, 0) else {
        return (Coverage::default(), Vec::new());
    };
    // The sampler's margin: only what lies within the bounds was meshed for sure.
    samples.retain(|s| s.p.cmpge(bounds.min).all() && s.p.cmple(bounds.max).all());
    let cell = mesh.cell;
    let near = Nearby::new(mesh.triangles(), cell, bounds.min);
    let far: Vec<(f64, f64)> = samples
        .par_iter()
        // Nothing within two cells: say two.
        .map(|s| ((near.distance(s.p) / cell).min(2.0), s.area))
        .collect();
    let total: f64 = far.iter().map(|f| f.1).sum();
    let missed: f64 = far.iter().filter(|f| f.0 > HELD_CELLS).map(|f| f.1).sum();
    let points = samples
        .iter()
        .zip(&far)
        .filter(|(_, f)| f.0 > HELD_CELLS)
        .map(|(s, _)| s.p)
        .collect();
    let coverage = Coverage {
        // (An empty sum of floats is -0.)
        missed: if total > 0.0 {
            (missed / total).max(0.0)
        } else {
            0.0
        },
        farthest: far.iter().map(|f| f.0).fold(0.0, f64::max),
        samples: far.len(),
    };
    (coverage, points)
}

/// Triangles by the cubic buckets (two cells a side, from a corner: small keys) their
/// boxes touch: the distance from a point to the nearest of them within two cells.
pub struct Nearby {
    tris: Vec<[DVec3; 3]>,
    side: f64,
    corner: DVec3,
    buckets: HashMap<IVec3, Vec<u32>>,
}

impl Nearby {
    pub fn new(tris: Vec<[DVec3; 3]>, cell: f64, corner: DVec3) -> Nearby {
        let mut near = Nearby {
            tris,
            side: 2.0 * cell,
            corner,
            buckets: HashMap::new(),
        };
        for (i, [a, b, c]) in near.tris.iter().enumerate() {
            let (lo, hi) = (near.key(a.min(*b).min(*c)), near.key(a.max(*b).max(*c)));
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    for z in lo.z..=hi.z {
                        let bucket = near.buckets.entry(IVec3::new(x, y, z)).or_default();
                        bucket.push(i as u32);
                    }
                }
            }
        }
        near
    }

    fn key(&self, x: DVec3) -> IVec3 {
        ((x - self.corner) / self.side).floor().as_ivec3()
    }

    /// The distance from `p` to the nearest triangle in the 27 buckets around it (exact
    /// within two cells; infinite where none is there).
    pub fn distance(&self, p: DVec3) -> f64 {
        let k = self.key(p);
        let mut best = f64::INFINITY;
        for d in (0..27).map(|n| IVec3::new(n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1)) {
            for &i in self.buckets.get(&(k + d)).into_iter().flatten() {
                let [a, b, c] = self.tris[i as usize];
                best = best.min(to_triangle(p, a, b, c));
            }
        }
        best
    }
}

/// The distance from `p` to triangle `abc` (a degenerate one: to its sides).
pub fn to_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::to_triangle;
    use glam::DVec3;

    #[test]
    fn distances_to_a_triangle_over_its_face_sides_and_corners() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X * 2.0, DVec3::Y * 2.0);
        let at = |x: f64, y: f64, z: f64| to_triangle(DVec3::new(x, y, z), a, b, c);
        // Over the face: the height.
        assert!((at(0.5, 0.5, 3.0) - 3.0).abs() < 1e-12);
        assert!((at(0.5, 0.5, -0.25) - 0.25).abs() < 1e-12);
        // Beside the hypotenuse (x + y = 2): the distance to that side.
        assert!((at(2.0, 2.0, 0.0) - 2f64.sqrt()).abs() < 1e-12);
        // Past a corner: the distance to it.
        assert!((at(-3.0, -4.0, 0.0) - 5.0).abs() < 1e-12);
        assert!((at(3.0, 0.0, 1.0) - 2f64.sqrt()).abs() < 1e-12);
        // A degenerate triangle (a segment) is measured by its sides.
        assert!((to_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, b) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_buckets_find_the_nearest_triangle_within_two_cells() {
        use super::Nearby;
        // A fan of small triangles about the origin, and points around it.
        let tris: Vec<[DVec3; 3]> = (0..40)
            .map(|k| {
                let t = k as f64 * 0.157;
                let o = DVec3::new(t.cos(), t.sin(), 0.3 * (3.0 * t).sin());
                [
                    o,
                    o + DVec3::new(0.05, 0.0, 0.02),
                    o + DVec3::new(0.0, 0.04, -0.01),
                ]
            })
            .collect();
        let near = Nearby::new(tris.clone(), 0.1, DVec3::splat(-2.0));
        for k in 0..500 {
            let t = k as f64 * 0.7919;
            let p = DVec3::new(1.1 * t.cos(), 0.9 * t.sin(), 0.4 * (t * 1.3).cos());
            let brute = tris
                .iter()
                .map(|[a, b, c]| to_triangle(p, *a, *b, *c))
                .fold(f64::INFINITY, f64::min);
            let found = near.distance(p);
            if brute <= 0.2 {
                assert_eq!(found, brute, "{p}");
            } else {
                assert!(found >= brute, "{p}");
            }
        }
    }
}
