//! Stage 2, grown: charts larger than one quad, for the packed layout (§3.4).
//!
//! A chart here is a rectangle of `a × b` mesh quads ("cells") that meets its neighbours
//! conformingly: two charts share one whole side, one corner, or nothing (the paper's
//! two topological rules, §4.1), with no T-junction anywhere.
//!
//! The layout is the quad mesh's **extended separatrices**. A vertex is *singular* when
//! it is not an interior vertex of valence 4 with four quads around it (dual contouring
//! puts these at the corners of the grid's terraces, at sharp corners and where the
//! surface turns from one axis to another). From every singular vertex, every edge is
//! followed straight on (through each regular vertex, to the edge opposite the one it
//! came by) until it reaches another singular vertex. The traced edges cut the mesh
//! into regions with no singular vertex inside, whose boundaries turn only at convex
//! corners, so each region that is a disc is a rectangle of the quad grid. A line ends
//! only at a singular vertex, where every edge is a line, so no corner of one chart
//! lies inside another's side: the layout is conforming by construction. A region that
//! is not a rectangle (a tube with no singular vertex, a wrap-around) and a rectangle
//! longer than `max_side` cells are cut by more lines, each traced in both directions
//! until it ends at singular vertices, which keeps the layout conforming.
//!
//! This follows the mesh's own structure, so the charts on a box's flat faces become
//! whole faces, while a sphere's terraced grid gives many small ones. No flatness test
//! is needed: each cell keeps its own bilinear parameterization, and a chart's
//! parameter is the cells' placed side by side, so its distortion is the cells'.
//!
//! [`grow`] rotates every quad's corners so that the quad's own (u, v) is the chart's
//! direction: cell `(i, j)` of chart `p` covers `[i, i + 1] × [j, j + 1] / (a, b)` of
//! the chart's [0, 1]², with the quad's corner 0 at its `(i, j)` corner.

use super::charts::ChartTable;
use super::mesh::QuadMesh;
use crate::asset::ChartLayout;

/// The grown charts of a quad mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Patches {
    /// Each chart's cells along u and along v.
    pub dims: Vec<[u32; 2]>,
    /// Each chart's cells (mesh quads), row by row: `cells[p][j · a + i]`.
    pub cells: Vec<Vec<u32>>,
    /// Each cell's chart and its column and row in it.
    pub place: Vec<[u32; 3]>,
}

impl Patches {
    /// One chart per cell (every quad its own chart).
    pub fn singles(cells: usize) -> Patches {
        Patches {
            dims: vec![[1, 1]; cells],
            cells: (0..cells as u32).map(|c| vec![c]).collect(),
            place: (0..cells as u32).map(|c| [c, 0, 0]).collect(),
        }
    }

    pub fn len(&self) -> usize {
        self.dims.len()
    }

    pub fn is_empty(&self) -> bool {
        self.dims.is_empty()
    }

    /// The chart's corner vertices, corner 0 at (0, 0), 1 at (1, 0), 2 at (1, 1),
    /// 3 at (0, 1), after [`grow`] has rotated the quads.
    pub fn corners(&self, quads: &[[u32; 4]], p: usize) -> [u32; 4] {
        let [a, b] = self.dims[p].map(|d| d as usize);
        let cell = |i: usize, j: usize| quads[self.cells[p][j * a + i] as usize];
        [
            cell(0, 0)[0],
            cell(a - 1, 0)[1],
            cell(a - 1, b - 1)[2],
            cell(0, b - 1)[3],
        ]
    }

    /// The cells along side `s` of chart `p`, from the side's start corner, with the
    /// cell side that lies on it (side `s` of each cell, as the quads are rotated).
    pub fn side_cells(&self, p: usize, s: usize) -> Vec<u32> {
        let [a, b] = self.dims[p].map(|d| d as usize);
        let cells = &self.cells[p];
        match s {
            0 => (0..a).map(|i| cells[i]).collect(),
            1 => (0..b).map(|j| cells[j * a + a - 1]).collect(),
            2 => (0..a).rev().map(|i| cells[(b - 1) * a + i]).collect(),
            _ => (0..b).rev().map(|j| cells[j * a]).collect(),
        }
    }
}

impl Patches {
    /// The charts across side `s` of chart `p`: `(chart, side, reversed)` of each
    /// (one on a manifold mesh, none at a mesh boundary, more at a non-manifold edge,
    /// where dual contouring made one). `table` is the chart table of the rotated
    /// quads. An error when the side is not shared whole (a T-junction).
    pub fn across(
        &self,
        table: &ChartTable,
        p: usize,
        s: usize,
    ) -> Result<Vec<(u32, u8, bool)>, String> {
        let cells = self.side_cells(p, s);
        let len = cells.len();
        let mut found: Option<Vec<(u32, u8, bool)>> = None;
        for (k, &c) in cells.iter().enumerate() {
            let mut here = Vec::new();
            for (c2, s2, rev) in table.neighbours(c as usize, s) {
                let p2 = self.place[c2 as usize][0];
                let theirs = self.side_cells(p2 as usize, s2 as usize);
                let k2 = if rev { len.wrapping_sub(1 + k) } else { k };
                if theirs.len() != len || theirs.get(k2) != Some(&c2) {
                    return Err(format!(
                        "side {s} of chart {p} meets chart {p2} partly (a T-junction)"
                    ));
                }
                here.push((p2, s2, rev));
            }
            here.sort_unstable();
            match &found {
                None => found = Some(here),
                Some(seen) if *seen != here => {
                    return Err(format!(
                        "side {s} of chart {p} meets different charts along it"
                    ))
                }
                Some(_) => {}
            }
        }
        Ok(found.unwrap_or_default())
    }

    /// Checks the paper's two topological rules: any two charts share one whole side,
    /// one corner, or nothing (and every side meets one side of one chart whole).
    pub fn check_conforming(&self, table: &ChartTable) -> Result<(), String> {
        use std::collections::{BTreeSet, HashMap};
        let quads = &table.corners;
        // Each chart's boundary vertices, side by side.
        let boundary = |p: usize, s: usize| -> Vec<u32> {
            let cells = self.side_cells(p, s);
            let mut v: Vec<u32> = cells.iter().map(|&c| quads[c as usize][s]).collect();
            v.push(quads[*cells.last().expect("a side has cells") as usize][(s + 1) % 4]);
            v
        };
        let mut on: HashMap<u32, Vec<u32>> = HashMap::new();
        for p in 0..self.len() {
            self.across(table, p, 0)?;
            self.across(table, p, 1)?;
            self.across(table, p, 2)?;
            self.across(table, p, 3)?;
            let mut mine = BTreeSet::new();
            for s in 0..4 {
                mine.extend(boundary(p, s));
            }
            for v in mine {
                on.entry(v).or_default().push(p as u32);
            }
        }
        let mut shared: HashMap<(u32, u32), BTreeSet<u32>> = HashMap::new();
        for (v, charts) in &on {
            for (k, &a) in charts.iter().enumerate() {
                for &b in &charts[k + 1..] {
                    shared.entry((a.min(b), a.max(b))).or_default().insert(*v);
                }
            }
        }
        for ((a, b), verts) in shared {
            let corners = |p: u32| self.corners(quads, p as usize);
            let ok = if verts.len() == 1 {
                let v = *verts.iter().next().expect("one");
                corners(a).contains(&v) && corners(b).contains(&v)
            } else {
                let side_of = |p: u32| {
                    (0..4).any(|s| {
                        boundary(p as usize, s)
                            .into_iter()
                            .collect::<BTreeSet<u32>>()
                            == verts
                    })
                };
                side_of(a) && side_of(b)
            };
            if !ok {
                return Err(format!(
                    "charts {a} and {b} share {} vertices, neither one corner nor one whole side",
                    verts.len()
                ));
            }
        }
        Ok(())
    }
}

/// The edges at each vertex, and which vertices are singular.
struct Structure<'a> {
    table: &'a ChartTable,
    /// Per vertex, its edges.
    at: Vec<Vec<u32>>,
    singular: Vec<bool>,
}

impl Structure<'_> {
    fn other(&self, e: u32, v: u32) -> u32 {
        let edge = &self.table.edges[e as usize];
        if edge.a == v {
            edge.b
        } else {
            edge.a
        }
    }

    /// The edge at regular vertex `w` opposite `e`: the one in neither quad of `e`.
    fn opposite(&self, e: u32, w: u32) -> Option<u32> {
        let t = self.table;
        let mut near: Vec<u32> = vec![e];
        for &(c, _) in &t.edges[e as usize].sides {
            for s in 0..4 {
                let (f, _) = t.sides[c as usize][s];
                let edge = &t.edges[f as usize];
                if edge.a == w || edge.b == w {
                    near.push(f);
                }
            }
        }
        let rest: Vec<u32> = self.at[w as usize]
            .iter()
            .copied()
            .filter(|f| !near.contains(f))
            .collect();
        (rest.len() == 1).then(|| rest[0])
    }

    /// Follows the line of `e` beyond `w` until a singular vertex or a traced edge.
    fn extend(&self, line: &mut [bool], mut e: u32, mut w: u32) {
        while !self.singular[w as usize] {
            let Some(next) = self.opposite(e, w) else {
                return;
            };
            if line[next as usize] {
                return;
            }
            line[next as usize] = true;
            w = self.other(next, w);
            e = next;
        }
    }

    /// Traces the whole line through `e`, both ways.
    fn trace(&self, line: &mut [bool], e: u32) {
        line[e as usize] = true;
        let edge = &self.table.edges[e as usize];
        let (a, b) = (edge.a, edge.b);
        self.extend(line, e, b);
        self.extend(line, e, a);
    }
}

/// A cell placed in a region: its column, row and which of its sides faces −v.
#[derive(Clone, Copy, PartialEq, Eq)]
struct Placed {
    i: i64,
    j: i64,
    k: u8,
}

/// Lays out the region of `start` (cells joined across non-line edges) on a grid.
/// `Err(cells)` when it is not a full rectangle of distinct cells.
fn place_region(
    t: &ChartTable,
    line: &[bool],
    start: usize,
    at: &mut [Option<Placed>],
) -> Result<Vec<usize>, Vec<usize>> {
    let mut region = vec![start];
    at[start] = Some(Placed { i: 0, j: 0, k: 0 });
    let mut ok = true;
    let mut next = 0;
    while next < region.len() {
        let c = region[next];
        next += 1;
        let p = at[c].expect("placed");
        // (side offset from k, di, dj, how the neighbour's k follows from its side).
        for (off, di, dj) in [(1u8, 1i64, 0i64), (3, -1, 0), (2, 0, 1), (0, 0, -1)] {
            let s = (p.k + off) % 4;
            let (e, rev) = t.sides[c][s as usize];
            if line[e as usize] {
                continue;
            }
            let edge = &t.edges[e as usize];
            let Some(&(c2, s2)) = edge
                .sides
                .iter()
                .find(|&&(c2, s2)| (c2 as usize, s2) != (c, s))
            else {
                continue;
            };
            let c2 = c2 as usize;
            // A consistently oriented mesh runs a shared edge both ways.
            if t.sides[c2][s2 as usize].1 == rev {
                ok = false;
            }
            // The side of the neighbour we enter by is its −u, +u, −v or +v side.
            let k2 = match off {
                1 => (s2 + 1) % 4,
                3 => (s2 + 3) % 4,
                2 => s2,
                _ => (s2 + 2) % 4,
            };
            let want = Placed {
                i: p.i + di,
                j: p.j + dj,
                k: k2,
            };
            match at[c2] {
                None => {
                    at[c2] = Some(want);
                    region.push(c2);
                }
                Some(seen) if seen != want => ok = false,
                Some(_) => {}
            }
        }
    }
    if ok {
        let (mut i0, mut i1, mut j0, mut j1) = (i64::MAX, i64::MIN, i64::MAX, i64::MIN);
        for &c in &region {
            let p = at[c].expect("placed");
            (i0, i1, j0, j1) = (i0.min(p.i), i1.max(p.i), j0.min(p.j), j1.max(p.j));
        }
        let (a, b) = ((i1 - i0 + 1) as usize, (j1 - j0 + 1) as usize);
        let mut seen = vec![false; a * b];
        for &c in &region {
            let p = at[c].expect("placed");
            let k = (p.j - j0) as usize * a + (p.i - i0) as usize;
            ok &= !std::mem::replace(&mut seen[k], true);
        }
        ok &= region.len() == a * b;
        if ok {
            for &c in &region {
                let p = at[c].as_mut().expect("placed");
                p.i -= i0;
                p.j -= j0;
            }
            return Ok(region);
        }
    }
    Err(region)
}

/// Grows conforming rectangular charts of at most `max_side` cells a side over `mesh`
/// (see the module docs), and rotates its quads to match them.
pub fn grow(mesh: &mut QuadMesh, max_side: usize) -> Patches {
    let max_side = max_side.max(1) as i64;
    let table = ChartTable::new(mesh);
    let nv = mesh.vertices.len();
    let mut at: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for (e, edge) in table.edges.iter().enumerate() {
        at[edge.a as usize].push(e as u32);
        at[edge.b as usize].push(e as u32);
    }
    // Regular: an interior vertex with four quads, or a boundary vertex on a straight
    // stretch of boundary (two quads) or at a convex corner of it (one quad).
    let singular: Vec<bool> = (0..nv)
        .map(|v| {
            let quads = table.around[v].len();
            let open = at[v]
                .iter()
                .filter(|&&e| table.edges[e as usize].sides.len() == 1)
                .count();
            let manifold = at[v]
                .iter()
                .all(|&e| table.edges[e as usize].sides.len() <= 2);
            let regular = match open {
                0 => quads == 4 && at[v].len() == 4,
                2 => (quads == 2 && at[v].len() == 3) || (quads == 1 && at[v].len() == 2),
                _ => false,
            };
            !(manifold && regular)
        })
        .collect();
    let s = Structure {
        table: &table,
        at,
        singular,
    };
    let mut line = vec![false; table.edges.len()];
    // Mesh boundaries, non-manifold edges and orientation flips are lines too.
    for (e, edge) in table.edges.iter().enumerate() {
        let flipped = edge.sides.len() == 2 && {
            let [(c1, s1), (c2, s2)] = [edge.sides[0], edge.sides[1]];
            table.sides[c1 as usize][s1 as usize].1 == table.sides[c2 as usize][s2 as usize].1
        };
        if (edge.sides.len() != 2 || flipped) && !line[e] {
            s.trace(&mut line, e as u32);
        }
    }
    for v in 0..nv {
        if s.singular[v] {
            for &e in &s.at[v] {
                if !line[e as usize] {
                    s.trace(&mut line, e);
                }
            }
        }
    }
    // Regions; cut the ones that are not rectangles or are too long, until none is.
    loop {
        let mut placed: Vec<Option<Placed>> = vec![None; table.len()];
        let mut regions = Vec::new();
        let mut cut = false;
        for c in 0..table.len() {
            if placed[c].is_some() {
                continue;
            }
            match place_region(&table, &line, c, &mut placed) {
                Ok(region) => {
                    // Too long: cut after column (row) max_side.
                    for c in &region {
                        let p = placed[*c].expect("placed");
                        let (side, at_edge) = if p.i == max_side - 1 {
                            ((p.k + 1) % 4, true)
                        } else if p.j == max_side - 1 {
                            ((p.k + 2) % 4, true)
                        } else {
                            (0, false)
                        };
                        let e = table.sides[*c][side as usize].0 as usize;
                        if at_edge && !line[e] {
                            // Only when the region goes on past it.
                            let beyond = table.edges[e].sides.len() == 2;
                            if beyond {
                                s.trace(&mut line, e as u32);
                                cut = true;
                            }
                        }
                    }
                    regions.push(region);
                }
                Err(region) => {
                    // Not a rectangle: cut along one edge inside it and look again.
                    let inner = region.iter().find_map(|&c| {
                        (0..4)
                            .map(|k| table.sides[c][k].0 as usize)
                            .find(|&e| !line[e])
                    });
                    match inner {
                        Some(e) => s.trace(&mut line, e as u32),
                        // (Cannot happen: a region of several cells has an inner edge.)
                        None => {}
                    }
                    cut = true;
                    regions.push(region);
                }
            }
        }
        if cut {
            continue;
        }
        let mut patches = Patches {
            dims: Vec::with_capacity(regions.len()),
            cells: Vec::with_capacity(regions.len()),
            place: vec![[0; 3]; table.len()],
        };
        for region in regions {
            let p = patches.dims.len();
            let (mut a, mut b) = (0, 0);
            for &c in &region {
                let q = placed[c].expect("placed");
                a = a.max(q.i as usize + 1);
                b = b.max(q.j as usize + 1);
            }
            let mut cells = vec![0u32; a * b];
            for &c in &region {
                let q = placed[c].expect("placed");
                cells[q.j as usize * a + q.i as usize] = c as u32;
                patches.place[c] = [p as u32, q.i as u32, q.j as u32];
                let quad = mesh.quads[c];
                mesh.quads[c] = std::array::from_fn(|r| quad[(r + q.k as usize) % 4]);
            }
            patches.dims.push([a as u32, b as u32]);
            patches.cells.push(cells);
        }
        return patches;
    }
}

/// Where the atlas layout puts each cell: the packed layout through the patches.
impl Patches {
    /// The top-left texel of cell `c`'s `n_l × n_l` samples at level `l`.
    pub fn cell_origin(&self, atlas: &ChartLayout, c: usize, l: usize) -> [u32; 2] {
        match atlas {
            ChartLayout::Flat(layout) => layout.chart_origin(c, l),
            ChartLayout::Packed(layout) => {
                let [p, i, j] = self.place[c];
                layout.cell_origin(p as usize, i, j, l)
            }
        }
    }

    /// The level-0 atlas coordinate (glTF TEXCOORD_0) of cell `c`'s local (u, v).
    pub fn texcoord(&self, atlas: &ChartLayout, c: usize, u: f64, v: f64) -> [f32; 2] {
        match atlas {
            ChartLayout::Flat(layout) => layout.texcoord(c, u, v),
            ChartLayout::Packed(layout) => {
                let [p, i, j] = self.place[c];
                let [a, b] = self.dims[p as usize];
                layout.texcoord(
                    p as usize,
                    (i as f64 + u) / a as f64,
                    (j as f64 + v) / b as f64,
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// An `n × n` grid of quads in the plane z = 0 (a disc: every inner vertex regular).
    fn sheet(n: usize) -> QuadMesh {
        let mut vertices = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                vertices.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut quads = Vec::new();
        for j in 0..n {
            for i in 0..n {
                // Rotate some quads' corners: the layout must not care.
                let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                let r = (i * 7 + j * 3) % 4;
                quads.push(std::array::from_fn(|k| q[(k + r) % 4]));
            }
        }
        QuadMesh {
            normals: vec![DVec3::Z; vertices.len()],
            vertices,
            quads,
            cell: 1.0,
        }
    }

    #[test]
    fn a_sheet_is_one_chart_and_its_quads_line_up() {
        let mut m = sheet(5);
        let p = grow(&mut m, 64);
        assert_eq!(p.dims, vec![[5, 5]]);
        // Every rotated quad has its corner 0 at its (i, j) corner and u along +x or
        // the chart's own u (the chart may be placed turned as a whole).
        let v = &m.vertices;
        let du = v[m.quads[p.cells[0][0] as usize][1] as usize]
            - v[m.quads[p.cells[0][0] as usize][0] as usize];
        for &c in &p.cells[0] {
            let q = m.quads[c as usize];
            assert_eq!(v[q[1] as usize] - v[q[0] as usize], du);
            assert_eq!(v[q[2] as usize] - v[q[3] as usize], du);
        }
        // The chart's corners are the sheet's.
        let corners = p.corners(&m.quads, 0);
        let mut got: Vec<u32> = corners.to_vec();
        got.sort();
        assert_eq!(got, vec![0, 5, 30, 35]);
    }

    /// An `n × m` grid of quads closed up in u (a tube) or in both (a torus): every
    /// vertex of a torus is regular, so no line starts anywhere, and the one region
    /// is no rectangle; the cuts must still leave conforming rectangles.
    fn wrapped(n: usize, m: usize, torus: bool) -> QuadMesh {
        let rows = if torus { m } else { m + 1 };
        let (r, t) = (2.0, 0.7);
        let mut vertices = Vec::new();
        for j in 0..rows {
            for i in 0..n {
                let (a, b) = (
                    i as f64 / n as f64 * std::f64::consts::TAU,
                    j as f64 / m as f64 * std::f64::consts::TAU,
                );
                vertices.push(if torus {
                    DVec3::new(
                        (r + t * b.cos()) * a.cos(),
                        (r + t * b.cos()) * a.sin(),
                        t * b.sin(),
                    )
                } else {
                    DVec3::new(a.cos(), a.sin(), j as f64)
                });
            }
        }
        let id = |i: usize, j: usize| ((j % rows) * n + i % n) as u32;
        let mut quads = Vec::new();
        for j in 0..m {
            for i in 0..n {
                quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        QuadMesh {
            normals: vec![DVec3::Z; vertices.len()],
            vertices,
            quads,
            cell: 1.0,
        }
    }

    #[test]
    fn tubes_and_tori_are_cut_into_conforming_rectangles() {
        for torus in [false, true] {
            let mut m = wrapped(8, 5, torus);
            let p = grow(&mut m, 64);
            let table = ChartTable::new(&m);
            p.check_conforming(&table).unwrap();
            assert_eq!(p.dims.iter().map(|d| d[0] * d[1]).sum::<u32>(), 40);
            assert!(p.len() < 40, "torus {torus}: {} charts", p.len());
            for c in 0..p.len() {
                for s in 0..4 {
                    let across = p.across(&table, c, s).unwrap();
                    assert_eq!(
                        across.is_empty(),
                        !torus && [0, 2].contains(&s) && {
                            // Only a tube's two rims are mesh boundaries.
                            let cells = p.side_cells(c, s);
                            table.neighbours(cells[0] as usize, s).is_empty()
                        }
                    );
                }
            }
        }
    }

    #[test]
    fn long_charts_are_cut_and_stay_conforming() {
        let mut m = sheet(7);
        let p = grow(&mut m, 3);
        let mut dims = p.dims.clone();
        dims.sort();
        // 7 = 3 + 3 + 1 both ways: a 3 × 3 grid of charts.
        assert_eq!(p.len(), 9);
        assert!(dims.iter().all(|d| d[0] <= 3 && d[1] <= 3));
        assert_eq!(dims.iter().map(|d| d[0] * d[1]).sum::<u32>(), 49);
        p.check_conforming(&ChartTable::new(&m)).unwrap();
    }
}
