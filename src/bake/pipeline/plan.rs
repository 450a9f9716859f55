//! The bake's plan, checked before any work: the options, the region baked and its
//! mesh grid, and whether f32 (glTF's positions, the GPU's arithmetic) holds the
//! region's mesh cells.

use super::{has_material, BakeError, Options, Refine, Resolution, MAX_CHART_QUADS, MAX_SIZE};
use crate::bake::mesh::{refine, Grid, MAX_GRID};
use crate::gpu::Gpu;
use crate::ir::Shape;

/// Checks the options and `shape` before any work: the mesh grid, the chart quads and
/// the bounds baked (the shape's own, within `--bounds`).
pub(super) fn plan(
    gpu: &Gpu,
    shape: &Shape,
    options: &Options,
) -> Result<(Grid, usize, crate::ir::Aabb), BakeError> {
    if !has_material(shape) {
        return Err(BakeError::NoMaterial);
    }
    if !options.size.is_power_of_two() || !(16..=MAX_SIZE).contains(&options.size) {
        return Err(BakeError::Option(format!(
            "--size {}: the atlas width must be a power of two from 16 to {MAX_SIZE}",
            options.size
        )));
    }
    let side = gpu.device.limits().max_texture_dimension_2d;
    if options.size > side {
        return Err(BakeError::Resource(format!(
            "--size {} is over this GPU's limit of {side} texels a side",
            options.size
        )));
    }
    let own = shape.root_node().bounds;
    let bounds = match options.bounds {
        Some(b) => b.intersect(own),
        None if own.is_finite() => own,
        None => return Err(BakeError::Unbounded),
    };
    let extent = bounds.max - bounds.min;
    if !bounds.is_finite() || extent.min_element() < 0.0 || extent.max_element() <= 0.0 {
        return Err(match options.bounds {
            Some(_) => BakeError::Option(String::from(
                "--bounds do not overlap the shape's own bounds: there is nothing of it to bake there",
            )),
            None => BakeError::Scene(String::from(
                "the shape is empty: its bounds hold no volume (an intersection of parts that do not meet, or a size of 0?), so there is nothing to bake",
            )),
        });
    }
    let longest = (bounds.max - bounds.min).max_element();
    let cells = match options.resolution {
        Resolution::Cells(n) => n as f64,
        Resolution::Edge(e) if e > 0.0 && e.is_finite() => (longest / e).ceil(),
        Resolution::Edge(e) => {
            return Err(BakeError::Option(format!(
                "--edge {e} is not a positive length"
            )))
        }
    };
    if !(2.0..=MAX_GRID as f64).contains(&cells) {
        return Err(BakeError::Option(format!(
            "the grid would have {} cells along its longest side; the range is 2 to {MAX_GRID} (change --grid or --edge)",
            if cells < 1e9 { format!("{cells}") } else { format!("{cells:.3e}") }
        )));
    }
    let cells = cells as usize;
    if let Refine::Times(r) = options.refine {
        if !(1..=refine::MAX_REFINE).contains(&r) {
            return Err(BakeError::Option(format!(
                "--refine {r} is not auto or between 1 and {}",
                refine::MAX_REFINE
            )));
        }
    }
    let m = options.chart_quads;
    if !(1..=MAX_CHART_QUADS).contains(&m) {
        return Err(BakeError::Option(format!(
            "--chart-quads {m} is not between 1 and {MAX_CHART_QUADS}"
        )));
    }
    if cells.div_ceil(m) < 2 {
        return Err(BakeError::Option(format!(
            "--chart-quads {m} on a grid of {cells} cells leaves a chart grid of {} along its longest side; it needs at least 2 (a finer --grid or --edge, or fewer --chart-quads)",
            cells.div_ceil(m)
        )));
    }
    // The mesh's cells: the chart grid's split m × m, and finer where refined (`auto`
    // stops short of a factor that f32 cannot hold: `refine_auto`).
    let finest = match options.refine {
        Refine::Times(r) => r,
        Refine::Auto => 1,
    };
    let cell = longest / (cells.div_ceil(m) * m * finest) as f64;
    // The region is the user's where --bounds set it: then an option to change.
    check_precision(bounds, cell).map_err(|e| match (e, options.bounds) {
        (BakeError::Scene(m), Some(_)) => BakeError::Option(m),
        (e, _) => e,
    })?;
    // Charts come from the coarser grid; the mesh splits each into m × m quads.
    let grid = Grid::over(bounds, cells.div_ceil(m));
    Ok((grid, m, bounds))
}

/// The largest coordinate a bake holds, in scene units: past it the GPU's f32
/// arithmetic (squares of distances, the projection's Newton steps) loses the surface
/// (a sphere of radius 1e11 baked with every normal the same).
pub const MAX_COORDINATE: f64 = 1e9;

/// The fewest steps of f32 (glTF's positions and the GPU's) a mesh cell must span
/// where the shape lies: a unit sphere 1e6 units from the origin at `--grid 16` has
/// two (positions 0.0625 apart, cells of 0.125), and its mesh came out with collapsed
/// triangles; at the default grid a unit sphere bakes up to 8,192 units out.
pub const MIN_F32_STEPS_A_CELL: f64 = 64.0;

/// A length for a message: three decimals where they show it, else three significant
/// digits.
pub(super) fn length(x: f64) -> String {
    if (1e-3..1e6).contains(&x.abs()) {
        format!("{x:.3}")
    } else {
        format!("{x:.3e}")
    }
}

/// Refuses a region that f32 coordinates cannot hold: farther from the origin than
/// [`MAX_COORDINATE`], or so far for its cells of side `cell` that a cell spans fewer
/// than [`MIN_F32_STEPS_A_CELL`] steps of f32 there.
pub(super) fn check_precision(bounds: crate::ir::Aabb, cell: f64) -> Result<(), BakeError> {
    let reach = bounds.min.abs().max(bounds.max.abs()).max_element();
    if reach > MAX_COORDINATE {
        return Err(BakeError::Scene(format!(
            "the region to bake reaches {} units from the origin; a bake holds coordinates up to {MAX_COORDINATE:e} (the GPU's f32 arithmetic loses the surface past that): scale the shape down, or give --bounds nearer the origin",
            length(reach)
        )));
    }
    // The spacing of f32 values at `reach` (to the next one up; at least the smallest
    // subnormal, at 0).
    let r = reach as f32;
    let step = (f32::from_bits(r.to_bits() + 1) - r) as f64;
    if cell < MIN_F32_STEPS_A_CELL * step {
        return Err(BakeError::Scene(format!(
            "the shape lies {} units from the origin, where f32 positions (a glTF file's and the GPU's) are {} apart: too coarse for mesh cells of {} (a cell needs at least {MIN_F32_STEPS_A_CELL} of those steps): move the shape nearer the origin (translate it), or bake a coarser --grid",
            length(reach),
            length(step),
            length(cell)
        )));
    }
    Ok(())
}
