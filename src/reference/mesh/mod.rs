//! A quad mesh of the zero set by dual contouring (the bake's stage 1).
//!
//! The distance is sampled (CPU reference, f64) at the corners of a regular grid. Every
//! grid edge whose ends have opposite signs gets one quad, joining the vertices of the
//! four cells around it; every cell with a sign change gets one vertex, placed at the
//! minimizer of the quadric error (QEF) of the tangent planes at its edge crossings
//! (Ju et al. 2002) within the cell, which keeps sharp edges and corners where the grid
//! allows. The vertex is then projected onto the surface (Π_f, to |f| < 1e-5 · scale).
//! A quad that placement folds takes its corners' clamped placement back ([`unfold`]);
//! vertices joined by a quad side under a tenth of a cell then share one point
//! ([`merge_close`]). Cells that may hold detail finer than themselves (a thin part, a
//! slit, a sharp wedge) can be meshed on a finer lattice, joined to the rest without
//! cracks ([`refine`], [`adaptive_contour`]).

use crate::ir::{eval, Aabb, Field};
use glam::DVec3;
use rayon::prelude::*;

pub mod refine;

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

impl QuadMesh {
    /// The quads' triangles, each quad split along the diagonal [`split_along_02`] picks.
    pub fn triangles(&self) -> Vec<[DVec3; 3]> {
        let mut out = Vec::with_capacity(2 * self.quads.len());
        for q in &self.quads {
            let p = q.map(|i| self.vertices[i as usize]);
            if split_along_02(p) {
                out.extend([[p[0], p[1], p[2]], [p[0], p[2], p[3]]]);
            } else {
                out.extend([[p[0], p[1], p[3]], [p[1], p[2], p[3]]]);
            }
        }
        out
    }

    /// Keeps the quads that may reach into `bounds`: those whose corners' box, grown by
    /// `margin` (the exported mesh's points, projected onto the surface, may bulge past
    /// the corners), meets them; and the vertices they use (renumbered in their order).
    /// The exported mesh is then cut at the bounds' faces (`bake::clip`); a surface just
    /// outside them, which the grid's margin of a cell reaches, is dropped here or there.
    pub fn retain_reaching(&mut self, bounds: Aabb, margin: f64) {
        self.quads.retain(|q| {
            let (lo, hi) = q.iter().map(|&i| self.vertices[i as usize]).fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), p| (lo.min(p), hi.max(p)),
            );
            (lo - margin).cmple(bounds.max).all() && (hi + margin).cmpge(bounds.min).all()
        });
        let mut new = vec![u32::MAX; self.vertices.len()];
        let mut kept = 0u32;
        for q in &mut self.quads {
            for i in q.iter_mut() {
                if new[*i as usize] == u32::MAX {
                    new[*i as usize] = kept;
                    kept += 1;
                }
                *i = new[*i as usize];
            }
        }
        let mut vertices = vec![DVec3::ZERO; kept as usize];
        let mut normals = vec![DVec3::ZERO; kept as usize];
        for (old, &n) in new.iter().enumerate() {
            if n != u32::MAX {
                vertices[n as usize] = self.vertices[old];
                normals[n as usize] = self.normals[old];
            }
        }
        (self.vertices, self.normals) = (vertices, normals);
    }
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
    adaptive_contour(shape, grid, tolerance, 1).mesh
}

/// What [`adaptive_contour`] made: the mesh, and how many cells it refined.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Contoured {
    pub mesh: QuadMesh,
    /// The cells meshed on the finer grid.
    pub refined: usize,
    /// The cells that asked for it ([`refine::max_refined`] at most are refined).
    pub wanted: usize,
    /// Fine cells that still hold two sheets or a sharp wedge (a finer refinement
    /// would part them).
    pub fine_two_sheets: usize,
}

/// Meshes the zero set of `shape` on `grid`, and meshes each cell that may hold detail
/// finer than itself on a grid `refine` times finer ([`refine`]); `refine` 1 is plain
/// dual contouring. `tolerance` is the projection's |f| bound.
pub fn adaptive_contour<'s>(
    shape: impl Into<Field<'s>>,
    grid: &Grid,
    tolerance: f64,
    refine: usize,
) -> Contoured {
    contour_refining(shape, grid, tolerance, refine, Refining::Select(&[]))
}

/// Which cells [`contour_refining`] refines.
#[derive(Debug, Clone)]
pub enum Refining<'a> {
    /// Those [`refine::select`] picks, and the cells (with the cells around them) that
    /// hold these points: surface samples a plainer mesh missed.
    Select(&'a [DVec3]),
    /// These cells (indices `i + nx (j + ny k)`): for tests of the joins between coarse
    /// and fine cells.
    Only(Vec<usize>),
}

/// [`adaptive_contour`], refining the cells `refining` names ([`refine::max_refined`]
/// at most).
pub fn contour_refining<'s>(
    shape: impl Into<Field<'s>>,
    grid: &Grid,
    tolerance: f64,
    refine: usize,
    refining: Refining<'_>,
) -> Contoured {
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
    let placed: Vec<Placed> = active
        .par_iter()
        .map(|&c| {
            let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
            place_vertex(shape, grid, &field, [i, j, k], tolerance)
        })
        .collect();

    let mut chosen = match refining {
        _ if refine < 2 => Vec::new(),
        Refining::Only(mut cells) => {
            cells.retain(|&c| c < nx * ny * nz);
            cells.sort_unstable();
            cells.dedup();
            cells
        }
        Refining::Select(missed) => {
            let mut cells = refine::select(shape, grid, &field, &index, &placed);
            refine::add_around(grid, &mut cells, missed);
            cells
        }
    };
    let wanted = chosen.len();
    chosen.truncate(refine::max_refined(refine));
    let mut chosen_len = 0;
    let (mut placed, quads, sizes) = if chosen.is_empty() {
        let quads = uniform_quads(grid, &field, &index, cell_at);
        let sizes = vec![grid.cell; placed.len()];
        (placed, quads, sizes)
    } else {
        let coarse = refine::Coarse {
            grid,
            field: &field,
            index: &index,
            placed,
        };
        let (placed, quads, sizes, refined) =
            refine::contour(shape, coarse, chosen, refine, tolerance);
        chosen_len = refined;
        (placed, quads, sizes)
    };
    let fine_two_sheets = placed
        .iter()
        .zip(&sizes)
        .filter(|(p, &size)| p.opposed && size < grid.cell)
        .count();
    unfold(shape, &mut placed, &quads, &sizes);
    let mut mesh = QuadMesh {
        vertices: placed.iter().map(|p| p.p).collect(),
        normals: placed.iter().map(|p| p.n).collect(),
        quads,
        cell: grid.cell,
    };
    merge_close(shape, &mut mesh, &sizes, tolerance);
    Contoured {
        mesh,
        refined: chosen_len,
        wanted,
        fine_two_sheets,
    }
}

/// One quad per sign-changing edge of the grid that has four cells around it, joining
/// their vertices (`index`: each cell's vertex, `u32::MAX` for none).
fn uniform_quads(
    grid: &Grid,
    field: &[f64],
    index: &[u32],
    cell_at: impl Fn(usize, usize, usize) -> usize,
) -> Vec<[u32; 4]> {
    let [nx, ny, _] = grid.dims;
    let inside = |i: usize, j: usize, k: usize| field[i + (nx + 1) * (j + (ny + 1) * k)] < 0.0;
    let mut quads = Vec::new();
    for (e, axis) in grid_edges(grid.dims) {
        let mut f = e;
        f[axis] += 1;
        let a = inside(e[0], e[1], e[2]);
        if a == inside(f[0], f[1], f[2]) {
            continue;
        }
        let (d1, d2) = ((axis + 1) % 3, (axis + 2) % 3);
        // The four cells around the edge must lie in the grid; with the grid's margin
        // they do wherever the surface stays inside it.
        if e[d1] == 0 || e[d2] == 0 || e[d1] >= grid.dims[d1] || e[d2] >= grid.dims[d2] {
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
    quads
}

/// Every edge between the corners of a grid of `dims` cells: its low corner and its
/// axis, z slowest, then y, x, and the axis fastest.
fn grid_edges(dims: [usize; 3]) -> impl Iterator<Item = ([usize; 3], usize)> {
    let [nx, ny, nz] = dims;
    (0..=nz)
        .flat_map(move |k| {
            (0..=ny).flat_map(move |j| {
                (0..=nx).flat_map(move |i| (0..3).map(move |axis| ([i, j, k], axis)))
            })
        })
        .filter(move |(e, axis)| e[*axis] < dims[*axis])
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
///
/// `sizes` holds each vertex's cell size: a side's limit is that of its smaller cell,
/// a cluster's that of its smallest.
fn merge_close<'s>(
    shape: impl Into<Field<'s>>,
    mesh: &mut QuadMesh,
    sizes: &[f64],
    tolerance: f64,
) {
    let shape: Field = shape.into();
    let limit_of = |a: u32, b: u32| MERGE_CELLS * sizes[a as usize].min(sizes[b as usize]);
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
            if (mesh.vertices[a as usize] - mesh.vertices[b as usize]).length() < limit_of(a, b) {
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
    // Each cluster's sum, size and limit, then its point.
    let mut clusters: std::collections::HashMap<u32, (DVec3, usize, f64)> = Default::default();
    for (i, &r) in roots.iter().enumerate() {
        let e = clusters.entry(r).or_insert((DVec3::ZERO, 0, f64::INFINITY));
        e.0 += mesh.vertices[i];
        e.1 += 1;
        e.2 = e.2.min(MERGE_CELLS * sizes[i]);
    }
    clusters.retain(|_, c| c.1 > 1);
    // Each cluster's mean, projected; a cluster whose members lie farther than the
    // limit from it (a chain), or whose projection lands farther, stays as it was.
    for (i, r) in roots.iter().enumerate() {
        if let Some(c) = clusters.get(r) {
            if (mesh.vertices[i] - c.0 / c.1 as f64).length() >= c.2 {
                clusters.remove(r);
            }
        }
    }
    clusters.retain(|_, (sum, count, limit)| {
        let mean = *sum / *count as f64;
        match eval::project(shape, mean, tolerance).filter(|p| (*p - mean).length() < *limit) {
            Some(p) => {
                *sum = p;
                true
            }
            None => false,
        }
    });
    for (i, r) in roots.iter().enumerate() {
        if let Some((p, _, _)) = clusters.get(r) {
            mesh.vertices[i] = *p;
            let n = eval::gradient(shape, *p).normalize_or_zero();
            if n != DVec3::ZERO {
                mesh.normals[i] = n;
            }
        }
    }
}

/// The vertex of one cell: the QEF minimizer of its edge crossings' tangent planes
/// within the cell ([`solve_qef`]), then projected onto the surface.
fn place_vertex<'s>(
    shape: impl Into<Field<'s>>,
    grid: &Grid,
    field: &[f64],
    [i, j, k]: [usize; 3],
    tolerance: f64,
) -> Placed {
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
    let lo = grid.corner(i, j, k);
    place_from(shape, &points, &normals, lo, grid.cell, tolerance)
}

/// The vertex of the cell from `lo` with side `cell` whose edges the surface crosses at
/// `points`, with the unit `normals` there.
fn place_from(
    shape: Field<'_>,
    points: &[DVec3],
    normals: &[DVec3],
    lo: DVec3,
    cell: f64,
    tolerance: f64,
) -> Placed {
    let mass = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
    let hi = lo + DVec3::splat(cell);
    let (qef, clamped) = solve_qef(points, normals, mass, lo, hi);
    let on_surface = |x: DVec3| {
        // Project; where that fails (a flat gradient), keep the mass point's projection or the mass point.
        let p = eval::project(shape, x, tolerance)
            .filter(|p| (*p - x).length() < 2.0 * cell)
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
    };
    let (p, n) = on_surface(qef);
    // Two crossings whose normals face apart: two sheets, or a wedge sharper than the
    // cell can hold ([`refine::select`]).
    let opposed = normals.iter().enumerate().any(|(a, na)| {
        normals[a + 1..]
            .iter()
            .any(|nb| na.dot(*nb) < refine::OPPOSED)
    });
    Placed {
        p,
        n,
        clamped: clamped.map(on_surface),
        opposed,
    }
}

/// A cell's vertex on the surface with its normal, and where the QEF's free minimizer
/// left the cell, the vertex its clamp to the cell would give ([`unfold`] falls back
/// on it).
struct Placed {
    p: DVec3,
    n: DVec3,
    clamped: Option<(DVec3, DVec3)>,
    /// Two of the crossings' normals face apart.
    opposed: bool,
}

/// Takes back the constrained placement ([`solve_qef`]) of every vertex of a quad that
/// it folds: a quad either of whose triangles (split as the export splits it) turns
/// more than 45° from the field's gradient at its centroid gets the clamped
/// placement at those of its corners that have one, in up to four passes (a vertex is
/// taken back once at most; the examples settle in two). A triangle with a side
/// shorter than [`merge_close`]'s limit is left out: such a side is joined (unless its
/// cluster is a chain, or its projection moves too far) and the triangle loses its
/// area. Where a crease runs along a cell's face, two cells' constrained vertices
/// can land on the face in the wrong order and fold the quad between them (`csg.sdf`'s
/// crown, `twisted_bar.sdf`'s rounded edges); clamped, they did not.
fn unfold<'s>(shape: Field<'s>, placed: &mut [Placed], quads: &[[u32; 4]], sizes: &[f64]) {
    let cos45 = std::f64::consts::FRAC_1_SQRT_2;
    let folded = |placed: &[Placed], q: &[u32; 4]| {
        let p = q.map(|i| placed[i as usize].p);
        let tris = if split_along_02(p) {
            [[0, 1, 2], [0, 2, 3]]
        } else {
            [[0, 1, 3], [1, 2, 3]]
        };
        tris.iter().any(|t| {
            let (a, b, c) = (p[t[0]], p[t[1]], p[t[2]]);
            // A side [`merge_close`] joins leaves no triangle to turn.
            let short = |x: usize, y: usize| {
                let (u, v) = (q[t[x]] as usize, q[t[y]] as usize);
                (p[t[x]] - p[t[y]]).length() < MERGE_CELLS * sizes[u].min(sizes[v])
            };
            if short(0, 1) || short(1, 2) || short(2, 0) {
                return false;
            }
            let n = (b - a).cross(c - a).normalize_or_zero();
            let g = eval::gradient(shape, (a + b + c) / 3.0).normalize_or_zero();
            n != DVec3::ZERO && g != DVec3::ZERO && n.dot(g) < cos45
        })
    };
    for _ in 0..4 {
        let revert: Vec<u32> = quads
            .par_iter()
            .filter(|q| q.iter().any(|&i| placed[i as usize].clamped.is_some()))
            .filter(|q| folded(placed, q))
            .flat_map_iter(|q| q.iter().copied())
            .collect();
        let mut changed = false;
        for i in revert {
            if let Some((p, n)) = placed[i as usize].clamped.take() {
                (placed[i as usize].p, placed[i as usize].n) = (p, n);
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

/// Whether a quad with corners `p` (in (0,0), (1,0), (1,1), (0,1) order) is split along
/// its diagonal 0–2 (else 1–3): along the shorter one, unless that folds a triangle
/// over, turning it more than 60° from the quad's own normal (its area vector, the
/// cross product of the diagonals) while the other diagonal keeps both nearer; then
/// along the one whose worse triangle turns less. Near a crease or a rim a dual
/// contouring quad can be far from flat, and the shorter diagonal then makes a sliver
/// facing away from the surface. The bake's `images::mesh_data` and texel placement
/// both read it, so texels lie on the triangles that are exported, and [`unfold`]
/// tests the triangles it makes.
pub fn split_along_02(p: [DVec3; 4]) -> bool {
    let shorter = (p[2] - p[0]).length() <= (p[3] - p[1]).length();
    let normal = (p[2] - p[0]).cross(p[3] - p[1]).normalize_or_zero();
    if normal == DVec3::ZERO {
        // Parallel diagonals: no normal to fold against.
        return shorter;
    }
    let facing = |a: usize, b: usize, c: usize| {
        let n = (p[b] - p[a]).cross(p[c] - p[a]).normalize_or_zero();
        if n == DVec3::ZERO {
            // A degenerate triangle turns nowhere.
            1.0
        } else {
            n.dot(normal)
        }
    };
    let along_02 = facing(0, 1, 2).min(facing(0, 2, 3));
    let along_13 = facing(0, 1, 3).min(facing(1, 2, 3));
    const FOLDED: f64 = 0.5;
    match (shorter, along_02 < FOLDED, along_13 < FOLDED) {
        (true, true, false) => false,
        (false, false, true) => true,
        (_, true, true) => along_02 >= along_13,
        _ => shorter,
    }
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

/// The point of the cell `lo`–`hi` minimizing Σ (n_i · (x − p_i))², regularized toward
/// `mass`: a truncated pseudo-inverse of AᵀA (singular values below 2 % of the largest
/// are dropped), so flat regions keep the mass point and edges and corners get their
/// sharp position. Where that minimizer leaves the cell, the least error within it:
/// the same solve with one or two coordinates held on the cell's faces, or a corner
/// ([`constrained`]). Clamping the free minimizer instead moves a vertex off its crease
/// wherever the crease's nearest point to the mass point lies in the next cell, and
/// along a curved rim that makes teeth.
///
/// Returns the point and, where it is not the free minimizer's clamp to the cell, that
/// clamp (for [`unfold`]).
fn solve_qef(
    points: &[DVec3],
    normals: &[DVec3],
    mass: DVec3,
    lo: DVec3,
    hi: DVec3,
) -> (DVec3, Option<DVec3>) {
    let mut ata = [[0.0f64; 3]; 3];
    let mut atb = [0.0f64; 3];
    let mut btb = 0.0;
    for (p, n) in points.iter().zip(normals) {
        let (nv, rhs) = (n.to_array(), n.dot(*p - mass));
        for r in 0..3 {
            for c in 0..3 {
                ata[r][c] += nv[r] * nv[c];
            }
            atb[r] += nv[r] * rhs;
        }
        btb += rhs * rhs;
    }
    // A NaN would stall the eigenvalue iteration; the inputs are finite in practice.
    if !ata.iter().flatten().chain(&atb).all(|v| v.is_finite()) {
        return (mass.clamp(lo, hi), None);
    }
    let largest = nalgebra::Matrix3::from_fn(|r, c| ata[r][c])
        .symmetric_eigenvalues()
        .amax();
    if largest.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return (mass.clamp(lo, hi), None);
    }
    let q = Qef {
        ata,
        atb,
        btb,
        largest,
    };
    let free = match q.solve([None; 3]) {
        Some(y) => mass + DVec3::from_array(y),
        None => return (mass.clamp(lo, hi), None),
    };
    if free.cmpge(lo).all() && free.cmple(hi).all() {
        return (free, None);
    }
    let clamped = free.clamp(lo, hi);
    match constrained(&q, mass, lo, hi, clamped) {
        Some(p) if p != clamped => (p, Some(clamped)),
        _ => (clamped, None),
    }
}

/// A quadric error in coordinates about the mass point: E(y) = yᵀ AᵀA y − 2 yᵀ Aᵀb + bᵀb,
/// with AᵀA's largest eigenvalue (positive).
struct Qef {
    ata: [[f64; 3]; 3],
    atb: [f64; 3],
    btb: f64,
    largest: f64,
}

impl Qef {
    fn error(&self, y: [f64; 3]) -> f64 {
        let mut e = self.btb;
        for r in 0..3 {
            e -= 2.0 * y[r] * self.atb[r];
            for c in 0..3 {
                e += y[r] * self.ata[r][c] * y[c];
            }
        }
        e
    }

    /// The minimizer with the coordinates given in `fixed` held there: a truncated
    /// pseudo-inverse over the free ones (singular values under 2 % of the whole
    /// matrix's largest dropped, so the free coordinates stay at the mass point along
    /// directions the planes do not fix). None where the result is not finite.
    fn solve(&self, fixed: [Option<f64>; 3]) -> Option<[f64; 3]> {
        use nalgebra::{DMatrix, DVector};
        let largest = self.largest;
        let free: Vec<usize> = (0..3).filter(|&k| fixed[k].is_none()).collect();
        let mut y = fixed.map(|f| f.unwrap_or(0.0));
        if !free.is_empty() {
            let m = DMatrix::from_fn(free.len(), free.len(), |r, c| self.ata[free[r]][free[c]]);
            let rhs = DVector::from_fn(free.len(), |r, _| {
                let row = free[r];
                self.atb[row]
                    - (0..3)
                        .filter_map(|k| fixed[k].map(|v| self.ata[row][k] * v))
                        .sum::<f64>()
            });
            let svd = m.svd(true, true);
            let x = svd.pseudo_inverse(0.02 * largest).ok()? * rhs;
            for (r, &k) in free.iter().enumerate() {
                y[k] = x[r];
            }
        }
        y.iter().all(|v| v.is_finite()).then_some(y)
    }
}

/// The least-error point of the cell `lo`–`hi` (about the mass point) among the
/// minimizers with one coordinate held on a face, two on an edge, or all three at a
/// corner, that lie in the cell, and the free minimizer's clamp `clamped` (the
/// truncated solves are not exact minimizers, so the clamp can be better); ties go to
/// the one nearest the mass point.
fn constrained(q: &Qef, mass: DVec3, lo: DVec3, hi: DVec3, clamped: DVec3) -> Option<DVec3> {
    let (lo, hi) = ((lo - mass).to_array(), (hi - mass).to_array());
    let slack = 1e-9 * (hi[0] - lo[0]).abs().max(1e-300);
    let first = (clamped - mass).to_array();
    let mut best: Option<(f64, f64, [f64; 3])> = Some((
        q.error(first),
        first.iter().map(|v| v * v).sum::<f64>(),
        first,
    ));
    // Each coordinate free (0), on the low side (1) or on the high side (2); not all free.
    for code in 1..27 {
        let pick = |k: usize| match (code / 3usize.pow(k as u32)) % 3 {
            1 => Some(lo[k]),
            2 => Some(hi[k]),
            _ => None,
        };
        let Some(y) = q.solve([pick(0), pick(1), pick(2)]) else {
            continue;
        };
        if (0..3).any(|k| y[k] < lo[k] - slack || y[k] > hi[k] + slack) {
            continue;
        }
        let (e, near) = (q.error(y), y.iter().map(|v| v * v).sum::<f64>());
        let better = match best {
            None => true,
            Some((be, bn, _)) => {
                let tie = 1e-9 * be.abs().max(q.btb).max(1e-300);
                e < be - tie || (e <= be + tie && near < bn)
            }
        };
        if better {
            best = Some((e, near, y));
        }
    }
    best.map(|(_, _, y)| {
        if y == first {
            // The clamp itself, bit for bit.
            clamped
        } else {
            (mass + DVec3::from_array(y))
                .clamp(mass + DVec3::from_array(lo), mass + DVec3::from_array(hi))
        }
    })
}
