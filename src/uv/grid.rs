//! The seed acceleration structure: a uniform grid over the atlas's bounds, built at
//! compile time. Each cell lists the seeds that any point in the cell could pick,
//! sorted by a lower bound of their Euclidean distance from the cell; seeds whose
//! bound is at least D are left out (a walk to them fails as too_far). A search visits
//! a cell's list in order and stops at the first seed whose bound is not below the
//! best geodesic distance so far: every seed after it is at least as far in Euclidean
//! distance, hence in geodesic distance (Eq. 35), so the search stays exact while a
//! point visits only the seeds near it. Points outside the grid use the last list,
//! which holds every seed with bound 0 (the plain scan).

use glam::DVec3;

/// Cells per axis at most.
pub const MAX_CELLS_PER_AXIS: usize = 16;

#[derive(Debug, Clone, PartialEq)]
pub struct SeedGrid {
    pub min: DVec3,
    pub cell: DVec3,
    pub dims: [usize; 3],
    /// cells + 2 entries: list k is items[start[k]..start[k + 1]]; the last list (index
    /// `cells`) is every seed, for points outside the grid.
    pub start: Vec<u32>,
    pub items: Vec<u32>,
    /// The lower bound of each item's Euclidean distance from its cell.
    pub bound: Vec<f64>,
}

impl SeedGrid {
    /// One cell holding every seed: the plain scan, with no early stop.
    pub fn single(n: usize) -> SeedGrid {
        SeedGrid {
            min: DVec3::ZERO,
            cell: DVec3::ZERO,
            dims: [0, 0, 0],
            start: vec![0, n as u32],
            items: (0..n as u32).collect(),
            bound: vec![0.0; n],
        }
    }

    /// A grid over `[min, max]` with about two cells per seed, flat axes collapsed.
    pub fn build(seeds: &[DVec3], min: DVec3, max: DVec3, max_distance: f64) -> SeedGrid {
        let n = seeds.len();
        let extent = (max - min).max(DVec3::splat(1e-9));
        let target = (2 * n).max(1) as f64;
        // The largest cell count per axis (for the longest axis) whose product stays
        // within about two cells per seed.
        let longest = extent.max_element();
        let mut dims = [1usize; 3];
        for k in 1..=MAX_CELLS_PER_AXIS {
            let size = longest / k as f64;
            let d = [
                ((extent.x / size).round() as usize).clamp(1, MAX_CELLS_PER_AXIS),
                ((extent.y / size).round() as usize).clamp(1, MAX_CELLS_PER_AXIS),
                ((extent.z / size).round() as usize).clamp(1, MAX_CELLS_PER_AXIS),
            ];
            if (d[0] * d[1] * d[2]) as f64 > target {
                break;
            }
            dims = d;
        }
        let cell = extent / DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
        let cells = dims[0] * dims[1] * dims[2];
        let mut start = Vec::with_capacity(cells + 2);
        let mut items = Vec::new();
        let mut bound = Vec::new();
        for c in 0..cells {
            let (ix, iy, iz) = (
                c % dims[0],
                (c / dims[0]) % dims[1],
                c / (dims[0] * dims[1]),
            );
            let lo = min + cell * DVec3::new(ix as f64, iy as f64, iz as f64);
            let hi = lo + cell;
            let centre = 0.5 * (lo + hi);
            let mut list: Vec<(f64, f64, usize)> = seeds
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let q = p.clamp(lo, hi);
                    ((*p - q).length(), (*p - centre).length(), i)
                })
                .filter(|(b, _, _)| *b < max_distance)
                .collect();
            list.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            start.push(items.len() as u32);
            for (b, _, i) in list {
                items.push(i as u32);
                bound.push(b);
            }
        }
        start.push(items.len() as u32);
        items.extend(0..n as u32);
        bound.extend(std::iter::repeat_n(0.0, n));
        start.push(items.len() as u32);
        SeedGrid {
            min,
            cell,
            dims,
            start,
            items,
            bound,
        }
    }

    pub fn cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// The list to search for a point: its cell's, or the full list outside the grid.
    pub fn list(&self, x: DVec3) -> usize {
        let cells = self.cells();
        if cells == 0 {
            return 0;
        }
        let rel = (x - self.min) / self.cell;
        let ok = (0..3).all(|k| rel[k] >= 0.0 && rel[k] <= self.dims[k] as f64);
        if !ok {
            return cells;
        }
        let i = |k: usize| (rel[k].floor() as usize).min(self.dims[k] - 1);
        i(0) + self.dims[0] * (i(1) + self.dims[1] * i(2))
    }

    /// The items and bounds of list `k`.
    pub fn entries(&self, k: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (s, e) = (self.start[k] as usize, self.start[k + 1] as usize);
        (s..e).map(move |t| (self.items[t] as usize, self.bound[t]))
    }
}
