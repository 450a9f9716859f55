//! The bake's report: the stages' times and the quality figures (`sdfc bake` prints it).

use std::time::Duration;

/// The stages' times and the quality figures.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Report {
    /// The chart grid's cells per axis.
    pub grid: [usize; 3],
    /// Mesh quads along a chart's side.
    pub chart_quads: usize,
    /// Cells meshed on the finer grid, the factor (1: none), and the cells that asked
    /// for it.
    pub refined: usize,
    pub refine: usize,
    pub refine_wanted: usize,
    /// With [`Refine::Auto`](super::Refine::Auto), what the plain mesh missed, where that made it refine.
    pub plain_coverage: Option<crate::bake::coverage::Coverage>,
    /// With [`Refine::Auto`](super::Refine::Auto) in a flat atlas, the texels a side the plain mesh's charts
    /// would have had, where the bake refined (more charts share the atlas).
    pub plain_chart_size: Option<u32>,
    /// With [`Refine::Auto`](super::Refine::Auto), why the refined mesh was not baked (its charts do not
    /// fit the atlas), where the plain one was.
    pub refine_dropped: Option<String>,
    pub vertices: usize,
    /// Cells: the chart grid's quads (each a chart in a flat atlas).
    pub cells: usize,
    pub charts: usize,
    /// A cell's level-0 samples a side.
    pub chart_size: u32,
    pub levels: usize,
    /// Used texels (every chart at every level) over the atlas's texels.
    pub utilisation: f64,
    /// Coefficient of variation of the charts' texel density (texels per unit length),
    /// over the charts that are not slivers.
    pub density_spread: f64,
    /// Charts with less than 1 % of the median chart's area.
    pub slivers: usize,
    /// The largest |f| at a level-0 sample point after projection, over the scale.
    pub max_residual: f64,
    /// How much of the surface the mesh holds ([`crate::bake::coverage`]).
    pub coverage: crate::bake::coverage::Coverage,
    pub samples: usize,
    /// The sub-texel samples shaded for [`Texels::Fit`](super::Texels::Fit) (0 with `Points`).
    pub fit_samples: usize,
    /// The bake's mesh's triangles (before the export's cut).
    pub triangles: usize,
    /// The triangles left out of the file's mesh as folded, with two corners on one
    /// point ([`crate::bake::folded::drop_folded`]): set by [`Baked::take_exported_mesh`](super::Baked::take_exported_mesh).
    pub folded: usize,
    /// Level-0 samples the file shows: with `--bounds`, those in them (the counts below
    /// are of these).
    pub shown: usize,
    /// Level-0 samples where the material is undefined (a channel not finite): the
    /// images hold 0 there.
    pub undefined: usize,
    /// Level-0 samples whose emission is finite and over 1, which the glTF's emissive
    /// texture (0 to 1) holds divided by [`Report::emissive_strength`] (an infinite one
    /// counts in [`Report::undefined`]).
    pub emission_over_one: usize,
    /// Level-0 samples where a finite colour, roughness or metallic value lies outside
    /// 0 to 1, or a finite emission below 0, by more than half an 8-bit step: the
    /// images hold them clamped.
    pub out_of_range: usize,
    /// The largest finite emission, where it is over 1 (else 1): the glTF's
    /// `KHR_materials_emissive_strength`
    /// ([`Textures::emissive_strength`](crate::asset::Textures::emissive_strength); 0
    /// in a report whose images were not made).
    pub emissive_strength: f32,
    /// Level-0 samples that emit (a channel finite and over 0).
    pub emitting: usize,
    /// Of those, the samples whose emission rounds to 0 in the 8-bit emissive texture
    /// once divided by [`Report::emissive_strength`] (a few very bright samples dim the
    /// rest).
    pub emission_lost: usize,
    /// The memory model's estimate of the bake's peak, in bytes, for the mesh and atlas
    /// baked ([`crate::bake::memory::estimated_peak_bytes`]; at most [`MAX_BAKE_BYTES`](super::MAX_BAKE_BYTES)).
    pub estimated_peak: u64,
    pub stages: Vec<(&'static str, Duration)>,
}
