//! Dual contouring refined where a cell may hold detail finer than itself.
//!
//! A part thinner than a cell can pass between the grid's corners, which then see no
//! sign change, and a cell can hold two sheets (a slit) or a wedge sharper than one
//! vertex holds; plain dual contouring drops the first and folds the others. Such a
//! cell ([`select`]) is meshed on a lattice [`Coarse::grid`]'s cell ÷ `r` apart, the
//! others as before, and the two meet without cracks as in dual contouring on an
//! octree (Ju et al. 2002): a quad is made for every *minimal* edge (an edge of the
//! finest cells around it) that the surface crosses, joining the vertices of the
//! (three or four) cells around it, and each cell's vertex minimizes the quadric error
//! of the crossings on the minimal edges of its boundary. Where a coarse cell meets
//! fine ones across a face, a quad has two corners in the coarse cell: it is a
//! triangle, kept as a quad with a repeated corner.

use super::{crossing, place_from, Grid, Placed, QuadMesh};
use crate::ir::{eval, Field};
use glam::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;

/// Crossing normals or corner gradients whose cosine is below this face apart (about
/// 105°): two sheets, or a wedge sharper than 75°. A box's right-angled edges are not.
pub(super) const OPPOSED: f64 = -0.25;

/// The most fine cells a mesh holds: [`max_refined`] cells are refined. Past it, the
/// first cells asked for (those with two sheets first) are refined.
pub const MAX_FINE_CELLS: usize = 1 << 21;

/// The most cells refined `r` times: 32,768 at 4, 4,096 at 8.
pub fn max_refined(r: usize) -> usize {
    MAX_FINE_CELLS / r.max(1).pow(3)
}

/// The finest refinement: fine cells along a refined cell's side.
pub const MAX_REFINE: usize = 8;

/// The first refinement `sdfc bake --refine auto` tries (then twice as fine, up to
/// [`MAX_REFINE`], while fine cells still hold two sheets or surface is missed).
pub const FIRST_REFINE: usize = 2;

/// The plain grid's data that refinement reads.
pub(super) struct Coarse<'a> {
    pub grid: &'a Grid,
    pub field: &'a [f64],
    /// Each cell's vertex in `placed`, `u32::MAX` for none.
    pub index: &'a [u32],
    pub placed: Vec<Placed>,
}

/// The cells to refine, in order: cells whose crossings' normals face apart (two
/// sheets, a sharp wedge), then cells near the surface with two corners of one sign
/// between which the surface may pass unseen: their gradients face apart, away from
/// each other outside the shape (a thin part between them) or toward each other
/// inside it (a thin gap), and their distances leave room for it (|f_a| + |f_b| under
/// twice the corners' distance, which allows fields that overestimate by 2×). The
/// inside of a thin part, and the empty middle of a gap, do not qualify. Then the
/// cells near the surface around the first kind.
pub(super) fn select(
    shape: Field<'_>,
    grid: &Grid,
    field: &[f64],
    index: &[u32],
    placed: &[Placed],
) -> Vec<usize> {
    let [nx, ny, nz] = grid.dims;
    let reach = 3f64.sqrt() * grid.cell;
    let corner = |i: usize, j: usize, k: usize| i + (nx + 1) * (j + (ny + 1) * k);
    let corners_of = |c: usize| {
        let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
        [0, 1, 2, 3, 4, 5, 6, 7].map(|b| (i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2)))
    };
    let near = |c: usize| {
        corners_of(c)
            .iter()
            .filter(|&&(i, j, k)| field[corner(i, j, k)].abs() < reach)
            .count()
            >= 2
    };
    let two_sheets: Vec<usize> = (0..nx * ny * nz)
        .filter(|&c| index[c] != u32::MAX && placed[index[c] as usize].opposed)
        .collect();
    let band: Vec<usize> = (0..nx * ny * nz)
        .filter(|&c| near(c) && !(index[c] != u32::MAX && placed[index[c] as usize].opposed))
        .collect();
    // The gradient at every corner of the band that is near the surface, once.
    let mut corners: Vec<usize> = band
        .iter()
        .flat_map(|&c| corners_of(c))
        .map(|(i, j, k)| corner(i, j, k))
        .filter(|&x| field[x].abs() < reach)
        .collect();
    corners.sort_unstable();
    corners.dedup();
    let position = |x: usize| {
        let (i, j, k) = (
            x % (nx + 1),
            (x / (nx + 1)) % (ny + 1),
            x / ((nx + 1) * (ny + 1)),
        );
        grid.corner(i, j, k)
    };
    let gradients: HashMap<usize, DVec3> = corners
        .par_iter()
        .map(|&x| (x, eval::gradient(shape, position(x)).normalize_or_zero()))
        .collect();
    let hidden: Vec<usize> = band
        .par_iter()
        .copied()
        .filter(|&c| {
            let at: Vec<(DVec3, f64, DVec3)> = corners_of(c)
                .iter()
                .map(|&(i, j, k)| corner(i, j, k))
                .filter_map(|x| gradients.get(&x).map(|g| (position(x), field[x], *g)))
                .collect();
            at.iter().enumerate().any(|(a, &(pa, fa, ga))| {
                at[a + 1..].iter().any(|&(pb, fb, gb)| {
                    let side = if fa < 0.0 { -1.0 } else { 1.0 };
                    (fa < 0.0) == (fb < 0.0)
                        && ga.dot(gb) < OPPOSED
                        && side * (ga - gb).dot(pa - pb) > 0.0
                        && fa.abs() + fb.abs() < 2.0 * (pa - pb).length()
                })
            })
        })
        .collect();
    // And the ring of cells near the surface around the cells with two sheets, so that
    // fine cells meet coarse ones a cell away from them, where one sheet passes: a
    // coarse vertex beside a slit would otherwise take crossings of both its walls and
    // fold the triangles between (`waving_robot.sdf` refined 4 times: 16 turned
    // triangles without the ring, 4 with it).
    let ring = two_sheets.len();
    let mut out: Vec<usize> = two_sheets.into_iter().chain(hidden).collect();
    let mut seen: std::collections::HashSet<usize> = out.iter().copied().collect();
    for at in 0..ring {
        let c = out[at];
        let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
        for d in 0..27 {
            let (a, b, e) = (i + d % 3, j + (d / 3) % 3, k + d / 9);
            if a == 0 || b == 0 || e == 0 || a > nx || b > ny || e > nz {
                continue;
            }
            let n = (a - 1) + nx * ((b - 1) + ny * (e - 1));
            if near(n) && seen.insert(n) {
                out.push(n);
            }
        }
    }
    out
}

/// Appends to `cells` (keeping its order) the cells that hold `points`, and the cells
/// around them, that it does not hold yet: where a mesh missed a surface sample, the
/// detail is within a cell of it.
pub(super) fn add_around(grid: &Grid, cells: &mut Vec<usize>, points: &[DVec3]) {
    let [nx, ny, nz] = grid.dims;
    let mut seen: std::collections::HashSet<usize> = cells.iter().copied().collect();
    for p in points {
        let at = ((*p - grid.origin) / grid.cell).floor();
        for d in 0..27 {
            let c = at
                + DVec3::new(
                    (d % 3) as f64 - 1.0,
                    ((d / 3) % 3) as f64 - 1.0,
                    (d / 9) as f64 - 1.0,
                );
            if c.min_element() < 0.0 || c.x >= nx as f64 || c.y >= ny as f64 || c.z >= nz as f64 {
                continue;
            }
            let index = c.x as usize + nx * (c.y as usize + ny * c.z as usize);
            if seen.insert(index) {
                cells.push(index);
            }
        }
    }
}

/// A cell of the mesh: a coarse cell by index, or a fine cell by its lattice corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Leaf {
    Coarse(usize),
    Fine([usize; 3]),
}

/// The lattice: coarse corners from the grid's samples, the points inside refined
/// cells sampled anew, one block of `(r + 1)³` a cell.
struct Lattice<'a> {
    grid: &'a Grid,
    field: &'a [f64],
    r: usize,
    blocks: HashMap<usize, usize>,
    values: Vec<f64>,
}

impl Lattice<'_> {
    fn cell_index(&self, c: [usize; 3]) -> usize {
        c[0] + self.grid.dims[0] * (c[1] + self.grid.dims[1] * c[2])
    }

    fn refined(&self, c: [usize; 3]) -> bool {
        self.blocks.contains_key(&self.cell_index(c))
    }

    /// The point of lattice coordinates `x` (a coarse corner at multiples of `r`).
    fn point(&self, x: [usize; 3]) -> DVec3 {
        let r = self.r;
        if x.iter().all(|v| v % r == 0) {
            self.grid.corner(x[0] / r, x[1] / r, x[2] / r)
        } else {
            let h = self.grid.cell / r as f64;
            self.grid.origin + DVec3::new(x[0] as f64, x[1] as f64, x[2] as f64) * h
        }
    }

    /// The distance at lattice point `x`: a coarse corner's sample, or the sample of a
    /// refined cell holding `x`; None where no refined cell holds it.
    fn value(&self, x: [usize; 3]) -> Option<f64> {
        let (r, [nx, ny, _]) = (self.r, self.grid.dims);
        if x.iter().all(|v| v % r == 0) {
            return Some(self.field[x[0] / r + (nx + 1) * (x[1] / r + (ny + 1) * (x[2] / r))]);
        }
        let options = x.map(|v| {
            if v % r == 0 {
                [(v / r).checked_sub(1), Some(v / r)]
            } else {
                [Some(v / r), None]
            }
        });
        for a in options[0].iter().flatten() {
            for b in options[1].iter().flatten() {
                for c in options[2].iter().flatten() {
                    let cell = [*a, *b, *c];
                    if cell.iter().zip(self.grid.dims).any(|(v, d)| *v >= d) {
                        continue;
                    }
                    if let Some(&block) = self.blocks.get(&self.cell_index(cell)) {
                        let l = [0, 1, 2].map(|k| x[k] - cell[k] * r);
                        let w = r + 1;
                        return Some(self.values[block * w * w * w + l[0] + w * (l[1] + w * l[2])]);
                    }
                }
            }
        }
        None
    }

    /// The cell holding the point of doubled lattice coordinates `q` (never on a cell's
    /// face), or None outside the grid.
    fn leaf(&self, q: [i64; 3]) -> Option<Leaf> {
        let r = self.r as i64;
        if q.iter().any(|&v| v < 0) {
            return None;
        }
        let c = q.map(|v| (v / (2 * r)) as usize);
        if c.iter().zip(self.grid.dims).any(|(v, d)| *v >= d) {
            return None;
        }
        Some(if self.refined(c) {
            Leaf::Fine(q.map(|v| (v / 2) as usize))
        } else {
            Leaf::Coarse(self.cell_index(c))
        })
    }
}

/// A minimal edge the surface crosses: its ends and their distances, whether the low
/// end is inside, and the cells around it counter-clockwise about its axis.
struct Crossed {
    ends: [DVec3; 2],
    values: [f64; 2],
    low_inside: bool,
    around: [Leaf; 4],
}

/// The mesh with `chosen` cells refined `r` times: the vertices (placed), the quads,
/// and each vertex's cell size.
pub(super) fn contour(
    shape: Field<'_>,
    coarse: Coarse<'_>,
    mut chosen: Vec<usize>,
    r: usize,
    tolerance: f64,
) -> (Vec<Placed>, Vec<[u32; 4]>, Vec<f64>, usize) {
    let grid = coarse.grid;
    let [nx, ny, _] = grid.dims;
    let mut lattice = Lattice {
        grid,
        field: coarse.field,
        r,
        blocks: HashMap::new(),
        values: Vec::new(),
    };
    let unpack = |c: usize| [c % nx, (c / nx) % ny, c / (nx * ny)];
    // Refine, then refine the cells around any coarse edge that the refined cells cross
    // more than once (a coarse vertex cannot stand for two crossings of one edge: its
    // quads would share a side twice), until none is left or the limit is reached.
    let mut new = chosen.len();
    while new > 0 {
        let from = chosen.len() - new;
        add_blocks(shape, &mut lattice, &chosen[from..]);
        let mut more = crossed_twice(&lattice, &chosen[from..]);
        more.truncate(max_refined(r).saturating_sub(chosen.len()));
        new = more.len();
        chosen.extend(more);
    }
    let chosen = &chosen[..];
    let edges = crossed_edges(&lattice, chosen);

    // Vertices in order of first appearance; fine cells, and coarse cells beside a
    // refined one, place theirs from the crossings on their boundary's minimal edges.
    let mut vertex: HashMap<Leaf, u32> = HashMap::new();
    let mut leaves: Vec<Leaf> = Vec::new();
    let mut beside_fine = std::collections::HashSet::new();
    for e in &edges {
        let fine = e.around.iter().any(|l| matches!(l, Leaf::Fine(_)));
        for l in e.around {
            vertex.entry(l).or_insert_with(|| {
                leaves.push(l);
                leaves.len() as u32 - 1
            });
            if let (true, Leaf::Coarse(c)) = (fine, l) {
                beside_fine.insert(c);
            }
        }
    }
    let general = |l: &Leaf| match l {
        Leaf::Fine(_) => true,
        Leaf::Coarse(c) => beside_fine.contains(c) || coarse.index[*c] == u32::MAX,
    };
    let crossings: Vec<Option<(DVec3, DVec3)>> = edges
        .par_iter()
        .map(|e| {
            e.around.iter().any(general).then(|| {
                let x = crossing(shape, e.ends[0], e.ends[1], e.values[0], e.values[1]);
                (x, eval::gradient(shape, x).normalize_or_zero())
            })
        })
        .collect();
    let mut gathered: Vec<(Vec<DVec3>, Vec<DVec3>)> = vec![Default::default(); leaves.len()];
    for (e, x) in edges.iter().zip(&crossings) {
        let Some((p, n)) = x else { continue };
        let mut seen: Vec<Leaf> = Vec::with_capacity(4);
        for l in e.around {
            if general(&l) && !seen.contains(&l) {
                seen.push(l);
                let g = &mut gathered[vertex[&l] as usize];
                g.0.push(*p);
                g.1.push(*n);
            }
        }
    }
    let fine = grid.cell / r as f64;
    let mut old: Vec<Option<Placed>> = coarse.placed.into_iter().map(Some).collect();
    let placed_general: Vec<Option<Placed>> = leaves
        .par_iter()
        .zip(&gathered)
        .map(|(l, (points, normals))| {
            if !general(l) {
                return None;
            }
            Some(match *l {
                Leaf::Fine(x) => {
                    place_from(shape, points, normals, lattice.point(x), fine, tolerance)
                }
                Leaf::Coarse(c) => {
                    let [i, j, k] = unpack(c);
                    place_from(
                        shape,
                        points,
                        normals,
                        grid.corner(i, j, k),
                        grid.cell,
                        tolerance,
                    )
                }
            })
        })
        .collect();
    let placed: Vec<Placed> = leaves
        .iter()
        .zip(placed_general)
        .map(|(l, p)| match (l, p) {
            (_, Some(p)) => p,
            (Leaf::Coarse(c), None) => old[coarse.index[*c] as usize]
                .take()
                .expect("each coarse vertex is placed once"),
            (Leaf::Fine(_), None) => unreachable!("fine cells place their own vertices"),
        })
        .collect();
    let sizes = leaves
        .iter()
        .map(|l| match l {
            Leaf::Fine(_) => fine,
            Leaf::Coarse(_) => grid.cell,
        })
        .collect();
    let quads = edges
        .iter()
        .map(|e| {
            let q = e.around.map(|l| vertex[&l]);
            // Inside at the low end: the surface faces +axis.
            if e.low_inside {
                q
            } else {
                [q[0], q[3], q[2], q[1]]
            }
        })
        .collect();
    (placed, quads, sizes, chosen.len())
}

/// Samples the blocks of the cells `cells` (not yet refined) into `lattice`.
fn add_blocks(shape: Field<'_>, lattice: &mut Lattice<'_>, cells: &[usize]) {
    let (r, [nx, ny, _]) = (lattice.r, lattice.grid.dims);
    let w = r + 1;
    let first = lattice.blocks.len();
    let values: Vec<f64> = cells
        .par_iter()
        .flat_map_iter(|&c| {
            let cell = [c % nx, (c / nx) % ny, c / (nx * ny)];
            let lattice = &*lattice;
            (0..w * w * w).map(move |l| {
                let x = [l % w, (l / w) % w, l / (w * w)];
                let at = [0, 1, 2].map(|k| cell[k] * r + x[k]);
                match lattice.value(at) {
                    Some(v) if x.iter().all(|v| v % r == 0) => v,
                    _ => eval::distance(shape, lattice.point(at)),
                }
            })
        })
        .collect();
    lattice.values.extend(values);
    for (b, &c) in cells.iter().enumerate() {
        lattice.blocks.insert(c, first + b);
    }
}

/// The unrefined cells around the coarse edges of `cells` whose fine samples change
/// sign more than once along them, each once, in order.
fn crossed_twice(lattice: &Lattice<'_>, cells: &[usize]) -> Vec<usize> {
    let (r, grid) = (lattice.r, lattice.grid);
    let [nx, ny, _] = grid.dims;
    let mut out = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for &c in cells {
        let cell = [c % nx, (c / nx) % ny, c / (nx * ny)];
        for axis in 0..3 {
            let (d1, d2) = ((axis + 1) % 3, (axis + 2) % 3);
            for (o1, o2) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let mut start = cell.map(|v| v * r);
                start[d1] += o1 * r;
                start[d2] += o2 * r;
                let signs: Vec<bool> = (0..=r)
                    .filter_map(|t| {
                        let mut x = start;
                        x[axis] += t;
                        lattice.value(x).map(|v| v < 0.0)
                    })
                    .collect();
                if signs.windows(2).filter(|p| p[0] != p[1]).count() < 2 {
                    continue;
                }
                // The four cells around this coarse edge.
                for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let mut around = cell;
                    around[d1] += o1;
                    around[d2] += o2;
                    if around[d1] < a || around[d2] < b {
                        continue;
                    }
                    around[d1] -= a;
                    around[d2] -= b;
                    if around.iter().zip(grid.dims).any(|(v, d)| *v >= d) || lattice.refined(around)
                    {
                        continue;
                    }
                    let index = lattice.cell_index(around);
                    if seen.insert(index) {
                        out.push(index);
                    }
                }
            }
        }
    }
    out
}

/// The minimal edges the surface crosses, in a fixed order: the coarse edges no
/// refined cell touches (in the grid's order), then the fine edges of the refined
/// cells (sorted, each once). An edge without four cells around it in the grid is left
/// out, as in plain dual contouring.
fn crossed_edges(lattice: &Lattice<'_>, chosen: &[usize]) -> Vec<Crossed> {
    let (grid, r) = (lattice.grid, lattice.r);
    let [nx, ny, _] = grid.dims;
    // An edge from lattice point `x` along `axis`, `step` lattice units long.
    let make = |x: [usize; 3], axis: usize, step: usize| -> Option<Crossed> {
        let mut y = x;
        y[axis] += step;
        let (fa, fb) = (lattice.value(x)?, lattice.value(y)?);
        if (fa < 0.0) == (fb < 0.0) {
            return None;
        }
        let (d1, d2) = ((axis + 1) % 3, (axis + 2) % 3);
        let mid = x.map(|v| 2 * v as i64);
        let at = |o1: i64, o2: i64| {
            let mut q = mid;
            q[axis] += step as i64;
            q[d1] += o1 * step as i64;
            q[d2] += o2 * step as i64;
            lattice.leaf(q)
        };
        // Counter-clockwise around +axis: (-,-), (+,-), (+,+), (-,+).
        let around = [at(-1, -1)?, at(1, -1)?, at(1, 1)?, at(-1, 1)?];
        Some(Crossed {
            ends: [lattice.point(x), lattice.point(y)],
            values: [fa, fb],
            low_inside: fa < 0.0,
            around,
        })
    };
    let mut out = Vec::new();
    for (e, axis) in super::grid_edges(grid.dims) {
        // Split where a refined cell has this edge on its boundary.
        let (d1, d2) = ((axis + 1) % 3, (axis + 2) % 3);
        let touched = [(0, 0), (1, 0), (0, 1), (1, 1)].iter().any(|&(o1, o2)| {
            let mut c = e;
            if (o1 == 1 && c[d1] == 0) || (o2 == 1 && c[d2] == 0) {
                return false;
            }
            c[d1] -= o1;
            c[d2] -= o2;
            c.iter().zip(grid.dims).all(|(v, d)| *v < d) && lattice.refined(c)
        });
        if touched {
            continue;
        }
        if let Some(edge) = make(e.map(|v| v * r), axis, r) {
            out.push(edge);
        }
    }
    // Each refined cell's crossed fine edges (its faces' twice where two refined
    // cells meet), then each once in the lattice's order.
    let w = r + 1;
    let mut fine: Vec<(([usize; 3], usize), Crossed)> = chosen
        .par_iter()
        .flat_map_iter(|&c| {
            let cell = [c % nx, (c / nx) % ny, c / (nx * ny)];
            let make = &make;
            (0..3).flat_map(move |axis| {
                (0..w * w * w).filter_map(move |l| {
                    let x = [l % w, (l / w) % w, l / (w * w)];
                    if x[axis] == r {
                        return None;
                    }
                    let at = [0, 1, 2].map(|k| cell[k] * r + x[k]);
                    make(at, axis, 1).map(|e| ((at, axis), e))
                })
            })
        })
        .collect();
    fine.sort_unstable_by_key(|&((x, axis), _)| (x[2], x[1], x[0], axis));
    fine.dedup_by_key(|&mut (key, _)| key);
    out.extend(fine.into_iter().map(|(_, e)| e));
    out
}

/// For tests: whether a quad mesh's every edge has exactly two quad sides, counting a
/// quad's repeated corner as no side: a closed surface has no open edge.
pub fn open_edges(mesh: &QuadMesh) -> usize {
    let mut count: HashMap<(u32, u32), usize> = HashMap::new();
    for q in &mesh.quads {
        for s in 0..4 {
            let (a, b) = (q[s], q[(s + 1) % 4]);
            if a != b {
                *count.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
    }
    count.values().filter(|&&n| n != 2).count()
}
