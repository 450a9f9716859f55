//! The chart table as JSON (`sdfc bake --charts FILE`): for tests and outside tools
//! that check seams. Each chart has its rectangle in the flat atlas at every level
//! (`[x, y, width, height]` in texels) and its neighbours along each side, with
//! orientation: side `s` runs from corner `s` to corner `s + 1` (corner 0 at chart-local
//! (0, 0), 1 at (1, 0), 2 at (1, 1), 3 at (0, 1); u grows with the image's x, v with y);
//! a neighbour `{chart, side, reversed}` shares the whole side, and `reversed` says
//! that its side runs the other way, so texel k of one is texel n − 1 − k of the other.

//!
//! In a packed atlas a chart is a rectangle of cells, `[width, height]` texels per
//! level; side `s`'s texels are those of [`super::charts::side_texel_rect`].

use super::charts::ChartTable;
use super::{ChartLayout, Patches};
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
    pub layout: ChartLayout,
    /// The number of levels.
    pub levels: usize,
    pub charts: Vec<ChartEntry>,
}

impl ChartsFile {
    /// The chart table of `atlas`: its charts are `patches` (every cell its own chart in
    /// a flat atlas) over the cells of `table`. A packed chart's neighbours come from
    /// [`Patches::across`]; a side it cannot pair whole (never, for charts from
    /// [`super::patches::grow`]) is listed with no neighbour.
    pub fn new(table: &ChartTable, atlas: &ChartLayout, patches: &Patches) -> ChartsFile {
        let charts = (0..patches.len())
            .map(|p| ChartEntry {
                corners: patches.corners(&table.corners, p),
                rects: (0..atlas.levels()).map(|l| atlas.rect(p, l)).collect(),
                neighbours: std::array::from_fn(|s| match atlas {
                    ChartLayout::Flat(_) => table
                        .neighbours(p, s)
                        .into_iter()
                        .map(|(chart, side, reversed)| Neighbour {
                            chart,
                            side,
                            reversed,
                        })
                        .collect(),
                    ChartLayout::Packed(_) => patches
                        .across(table, p, s)
                        .unwrap_or_default()
                        .into_iter()
                        .map(|(chart, side, reversed)| Neighbour {
                            chart,
                            side,
                            reversed,
                        })
                        .collect(),
                }),
            })
            .collect();
        ChartsFile {
            layout: atlas.clone(),
            levels: atlas.levels(),
            charts,
        }
    }
}
