//! A quad mesh of the zero set by dual contouring (the bake's stage 1).
//!
//! The distance is sampled (CPU reference, f64) at the corners of a regular grid. Every
//! grid edge whose ends have opposite signs gets one quad, joining the vertices of the
//! four cells around it; every cell with a sign change gets one vertex, placed at the
//! minimizer of the quadric error (QEF) of the tangent planes at its edge crossings
//! (Ju et al. 2002), which keeps sharp edges and corners where the grid allows. The
//! vertex is then projected onto the surface (Π_f, to |f| < 1e-5 · scale). Vertices joined
//! by a quad side under a tenth of a cell then share one point ([`merge_close`]).

use crate::ir::{eval, Aabb, Field};
use glam::DVec3;
use rayon::prelude::*;

/// The finest grid a bake may ask for, in cells along the longest side.
pub const MAX_GRID: usize = 512;

/// A quad mesh: each quad's corners in counter-clockwise order seen from outside.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QuadMesh {
    pub vertices: Vec<DVec3>,
    /// Unit surface normals at the vertices (the normalized gradient).
    pub normals: Vec<DVec3>,
    pub quads: Vec<[u32; 4]>,
    /// The grid's cell size.
    pub cell: f64,
}

/// The grid: `dims` cells along each axis from `origin`, cubic cells of `cell`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    pub origin: DVec3,
    pub cell: f64,
    pub dims: [usize; 3],
}

impl Grid {
    /// A grid over `bounds` (finite) with `cells` cells along its longest side and a
    /// margin of one cell, so a closed surface inside the bounds gives a closed mesh.
    pub fn over(bounds: Aabb, cells: usize) -> Grid {
        let size = bounds.max - bounds.min;
        let cell = size.max_element().max(1e-9) / cells.max(1) as f64;
        let dims = ((size / cell).ceil() + DVec3::splat(2.0)).as_uvec3();
        let padding = (dims.as_dvec3() * cell - size) * 0.5;
        Grid {
            origin: bounds.min - padding,
            cell,
            dims: [dims.x as usize, dims.y as usize, dims.z as usize],
        }
    }

    fn corner(&self, i: usize, j: usize, k: usize) -> DVec3 {
        self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.cell
    }
}

/// Meshes the zero set of `shape` on `grid`. `tolerance` is the projection's |f| bound.
pub fn dual_contour<'s>(shape: impl Into<Field<'s>>, grid: &Grid, tolerance: f64) -> QuadMesh {
    let shape: Field = shape.into();
    let [nx, ny, nz] = grid.dims;
    let (px, py) = (nx + 1, ny + 1);
    let at = |i: usize, j: usize, k: usize| i + px * (j + py * k);
    // Distances at the grid's corners, one z-slab per task. A corner exactly on the
    // surface counts as outside, so every sign change is strict.
    let field: Vec<f64> = (0..=nz)
        .into_par_iter()
        .flat_map_iter(|k| {
            (0..=ny).flat_map(move |j| {
                (0..=nx).map(move |i| eval::distance(shape, grid.corner(i, j, k)))
            })
        })
        .collect();
    let inside = |i: usize, j: usize, k: usize| field[at(i, j, k)] < 0.0;

    // The cells with a sign change get a vertex.
    let cell_at = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
    let active: Vec<usize> = (0..nx * ny * nz)
        .filter(|&c| {
            let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
            let s = inside(i, j, k);
            (0..8).any(|b| inside(i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2)) != s)
        })
        .collect();
    let mut index = vec![u32::MAX; nx * ny * nz];
    for (v, &c) in active.iter().enumerate() {
        index[c] = v as u32;
    }
    let placed: Vec<(DVec3, DVec3)> = active
        .par_iter()
        .map(|&c| {
            let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
            place_vertex(shape, grid, &field, [i, j, k], tolerance)
        })
        .collect();

    // One quad per sign-changing edge that has four cells around it.
    let mut quads = Vec::new();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                for axis in 0..3 {
                    let e = [i, j, k];
                    let mut f = e;
                    f[axis] += 1;
                    if f[0] > nx || f[1] > ny || f[2] > nz {
                        continue;
                    }
                    let a = inside(e[0], e[1], e[2]);
                    if a == inside(f[0], f[1], f[2]) {
                        continue;
                    }
                    let (d1, d2) = ((axis + 1) % 3, (axis + 2) % 3);
                    // The four cells around the edge must lie in the grid; with the
                    // grid's margin they do wherever the surface stays inside it.
                    if e[d1] == 0 || e[d2] == 0 || e[d1] >= grid.dims[d1] || e[d2] >= grid.dims[d2]
                    {
                        continue;
                    }
                    let cell = |o1: usize, o2: usize| {
                        let mut c = e;
                        c[d1] = c[d1] + o1 - 1;
                        c[d2] = c[d2] + o2 - 1;
                        index[cell_at(c[0], c[1], c[2])]
                    };
                    // Counter-clockwise around +axis: (-,-), (+,-), (+,+), (-,+).
                    let q = [cell(0, 0), cell(1, 0), cell(1, 1), cell(0, 1)];
                    if q.contains(&u32::MAX) {
                        continue;
                    }
                    // Inside at the low end: the surface faces +axis.
                    quads.push(if a { q } else { [q[0], q[3], q[2], q[1]] });
                }
            }
        }
    }
    let mut mesh = QuadMesh {
        vertices: placed.iter().map(|p| p.0).collect(),
        normals: placed.iter().map(|p| p.1).collect(),
        quads,
        cell: grid.cell,
    };
    merge_close(shape, &mut mesh, tolerance);
    mesh
}

/// Vertices joined by a quad side shorter than this many cells become one point.
pub const MERGE_CELLS: f64 = 0.1;

/// Gives vertices joined by a quad side shorter than [`MERGE_CELLS`] one position:
/// where a crease or corner passes near a cell's face, the QEF puts both cells'
/// vertices on it a hair apart, and the quads between them split into a sliver whose
/// face normal is noise (a fin). Joined, the sliver has no area at all. Each cluster
/// (by union over such sides) goes to its mean, projected onto the surface, with the
/// gradient there for its normal, when every member lies within [`MERGE_CELLS`] of the
/// mean and the projection moves it less than that: a member moves by under two
/// tenths of a cell (about half a tenth for a pair). The quads keep their four corners
/// (a chart still has four), some of which now coincide.
fn merge_close<'s>(shape: impl Into<Field<'s>>, mesh: &mut QuadMesh, tolerance: f64) {
    let shape: Field = shape.into();
    let limit = MERGE_CELLS * mesh.cell;
    let mut parent: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    let mut merged = false;
    for q in &mesh.quads {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            if (mesh.vertices[a as usize] - mesh.vertices[b as usize]).length() < limit {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                    merged = true;
                }
            }
        }
    }
    if !merged {
        return;
    }
    let roots: Vec<u32> = (0..mesh.vertices.len() as u32)
        .map(|i| root(&mut parent, i))
        .collect();
    // Each cluster's sum and size, then its point.
    let mut clusters: std::collections::HashMap<u32, (DVec3, usize)> = Default::default();
    for (i, &r) in roots.iter().enumerate() {
        let e = clusters.entry(r).or_insert((DVec3::ZERO, 0));
        e.0 += mesh.vertices[i];
        e.1 += 1;
    }
    clusters.retain(|_, c| c.1 > 1);
    // Each cluster's mean, projected; a cluster whose members lie farther than the
    // limit from it (a chain), or whose projection lands farther, stays as it was.
    for (i, r) in roots.iter().enumerate() {
        if let Some(c) = clusters.get(r) {
            if (mesh.vertices[i] - c.0 / c.1 as f64).length() >= limit {
                clusters.remove(r);
            }
        }
    }
    clusters.retain(|_, (sum, count)| {
        let mean = *sum / *count as f64;
        match eval::project(shape, mean, tolerance).filter(|p| (*p - mean).length() < limit) {
            Some(p) => {
                *sum = p;
                true
            }
            None => false,
        }
    });
    for (i, r) in roots.iter().enumerate() {
        if let Some((p, _)) = clusters.get(r) {
            mesh.vertices[i] = *p;
            let n = eval::gradient(shape, *p).normalize_or_zero();
            if n != DVec3::ZERO {
                mesh.normals[i] = n;
            }
        }
    }
}

/// The vertex of one cell: the QEF minimizer of its edge crossings' tangent planes,
/// clamped to the cell, then projected onto the surface.
fn place_vertex<'s>(
    shape: impl Into<Field<'s>>,
    grid: &Grid,
    field: &[f64],
    [i, j, k]: [usize; 3],
    tolerance: f64,
) -> (DVec3, DVec3) {
    let shape: Field = shape.into();
    let [nx, ny, _] = grid.dims;
    let at = |i: usize, j: usize, k: usize| field[i + (nx + 1) * (j + (ny + 1) * k)];
    let mut points = Vec::with_capacity(12);
    let mut normals = Vec::with_capacity(12);
    const EDGES: [([usize; 3], [usize; 3]); 12] = [
        ([0, 0, 0], [1, 0, 0]),
        ([0, 1, 0], [1, 1, 0]),
        ([0, 0, 1], [1, 0, 1]),
        ([0, 1, 1], [1, 1, 1]),
        ([0, 0, 0], [0, 1, 0]),
        ([1, 0, 0], [1, 1, 0]),
        ([0, 0, 1], [0, 1, 1]),
        ([1, 0, 1], [1, 1, 1]),
        ([0, 0, 0], [0, 0, 1]),
        ([1, 0, 0], [1, 0, 1]),
        ([0, 1, 0], [0, 1, 1]),
        ([1, 1, 0], [1, 1, 1]),
    ];
    for (a, b) in EDGES {
        let fa = at(i + a[0], j + a[1], k + a[2]);
        let fb = at(i + b[0], j + b[1], k + b[2]);
        if (fa < 0.0) == (fb < 0.0) {
            continue;
        }
        let pa = grid.corner(i + a[0], j + a[1], k + a[2]);
        let pb = grid.corner(i + b[0], j + b[1], k + b[2]);
        let x = crossing(shape, pa, pb, fa, fb);
        let n = eval::gradient(shape, x).normalize_or_zero();
        points.push(x);
        normals.push(n);
    }
    let mass = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
    let lo = grid.corner(i, j, k);
    let hi = lo + DVec3::splat(grid.cell);
    let qef = solve_qef(&points, &normals, mass, grid.cell).clamp(lo, hi);
    // Project; where that fails (a flat gradient), keep the mass point's projection or the mass point.
    let p = eval::project(shape, qef, tolerance)
        .filter(|p| (*p - qef).length() < 2.0 * grid.cell)
        .or_else(|| eval::project(shape, mass, tolerance))
        .unwrap_or(mass);
    let n = eval::gradient(shape, p).normalize_or_zero();
    let n = if n == DVec3::ZERO {
        normals
            .iter()
            .copied()
            .sum::<DVec3>()
            .normalize_or(DVec3::Y)
    } else {
        n
    };
    (p, n)
}

/// Where the surface crosses the segment a–b (opposite signs): a few steps of
/// regula falsi on the f64 distance.
fn crossing<'s>(
    shape: impl Into<Field<'s>>,
    mut a: DVec3,
    mut b: DVec3,
    mut fa: f64,
    mut fb: f64,
) -> DVec3 {
    let shape: Field = shape.into();
    let mut x = a;
    for _ in 0..12 {
        let t = (fa / (fa - fb)).clamp(0.01, 0.99);
        x = a + (b - a) * t;
        let fx = eval::distance(shape, x);
        if fx.abs() < 1e-12 {
            break;
        }
        if (fx < 0.0) == (fa < 0.0) {
            a = x;
            fa = fx;
        } else {
            b = x;
            fb = fx;
        }
    }
    x
}

/// The point minimizing Σ (n_i · (x − p_i))², regularized toward `mass`: a truncated
/// pseudo-inverse of AᵀA (singular values below 2 % of the largest are dropped), so
/// flat regions keep the mass point and edges and corners get their sharp position.
fn solve_qef(points: &[DVec3], normals: &[DVec3], mass: DVec3, _cell: f64) -> DVec3 {
    use nalgebra::{Matrix3, Vector3};
    let mut ata = Matrix3::<f64>::zeros();
    let mut atb = Vector3::<f64>::zeros();
    for (p, n) in points.iter().zip(normals) {
        let nv = Vector3::new(n.x, n.y, n.z);
        let rhs = n.dot(*p - mass);
        ata += nv * nv.transpose();
        atb += nv * rhs;
    }
    let svd = ata.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return mass;
    };
    let largest = svd.singular_values.max();
    // Also stops a NaN.
    if largest.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return mass;
    }
    let mut inv = Matrix3::<f64>::zeros();
    for s in 0..3 {
        let sv = svd.singular_values[s];
        if sv > 0.02 * largest {
            inv[(s, s)] = 1.0 / sv;
        }
    }
    let x = v_t.transpose() * inv * u.transpose() * atb;
    let out = mass + DVec3::new(x.x, x.y, x.z);
    if out.is_finite() {
        out
    } else {
        mass
    }
}
