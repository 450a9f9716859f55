//! The chart table as JSON (`sdfc bake --charts FILE`): for tests and outside tools
//! that check seams. Each chart has its rectangle in the flat atlas at every level
//! (`[x, y, width, height]` in texels) and its neighbours along each side, with
//! orientation: side `s` runs from corner `s` to corner `s + 1` (corner 0 at chart-local
//! (0, 0), 1 at (1, 0), 2 at (1, 1), 3 at (0, 1); u grows with the image's x, v with y);
//! a neighbour `{chart, side, reversed}` shares the whole side, and `reversed` says
//! that its side runs the other way, so texel k of one is texel n − 1 − k of the other.

use super::charts::ChartTable;
use super::FlatLayout;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Neighbour {
    pub chart: u32,
    pub side: u8,
    pub reversed: bool,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChartEntry {
    /// The mesh vertices at its corners (shared with the charts around them).
    pub corners: [u32; 4],
    /// `[x, y, width, height]` per level, level 0 first.
    pub rects: Vec<[u32; 4]>,
    /// Per side, every chart across it (one on a closed manifold mesh).
    pub neighbours: [Vec<Neighbour>; 4],
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChartsFile {
    pub layout: FlatLayout,
    pub charts: Vec<ChartEntry>,
}

impl ChartsFile {
    pub fn new(table: &ChartTable, layout: &FlatLayout) -> ChartsFile {
        let charts = (0..table.len())
            .map(|c| ChartEntry {
                corners: table.corners[c],
                rects: (0..layout.levels())
                    .map(|l| {
                        let [x, y] = layout.chart_origin(c, l);
                        let n = layout.size_at(l);
                        [x, y, n, n]
                    })
                    .collect(),
                neighbours: std::array::from_fn(|s| {
                    table
                        .neighbours(c, s)
                        .into_iter()
                        .map(|(chart, side, reversed)| Neighbour {
                            chart,
                            side,
                            reversed,
                        })
                        .collect()
                }),
            })
            .collect();
        ChartsFile {
            layout: layout.clone(),
            charts,
        }
    }
}
