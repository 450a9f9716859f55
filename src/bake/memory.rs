//! The bake's memory model: what a bake holds at its peak, estimated from its
//! footprint before the work ([`estimated_peak_bytes`]), and the check against
//! [`MAX_BAKE_BYTES`] that refuses a bake over it.

use super::charts::ChartTable;
use super::fit::{self, Texels};
use super::mesh::Grid;
use super::mips::CHANNELS;
use super::ChartLayout;
use crate::codegen::Module;
use crate::gpu::compute::MAX_POINTS_PER_DISPATCH;
use std::path::Path;

/// What a bake's memory depends on: see [`estimated_peak_bytes`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Footprint {
    /// The mesh stage's grid corners (its distance samples).
    pub grid_corners: u64,
    /// Cells: the chart grid's quads (the chart table's length).
    pub cells: u64,
    /// The exported mesh's vertices, `(m + 1)²` a cell for `--chart-quads m`.
    pub vertices: u64,
    /// Level-0 samples, each shared one once (corners, edges' inner samples, interiors).
    pub samples: u64,
    /// The atlas image's texels, width × height.
    pub texels: u64,
    /// The sub-texel samples `--texels fit` holds at once (0 without it).
    pub fit_batch: u64,
    /// The scene's textures while the bake's pass loads them (decoded, on the GPU with
    /// their mips, staged: [`crate::bake::export::gltf::texture_bytes`] of each, from the
    /// image files' headers).
    pub texture_bytes: u64,
    /// Whether `--charts`' JSON is written (encoded beside the other outputs:
    /// [`CHARTS_FILE_CELL_BYTES`] a cell).
    pub charts_file: bool,
}

impl Footprint {
    /// The mesh stage's part alone, known before meshing.
    pub fn grid(grid: &Grid) -> Footprint {
        Footprint {
            grid_corners: grid.dims.iter().map(|&d| d as u64 + 1).product(),
            ..Footprint::default()
        }
    }

    /// The whole bake's, once the atlas is laid out: `n` samples a cell side at level 0
    /// over `table`'s charts, on a mesh of `vertices` vertices, `m` quads a chart side.
    pub fn of(
        grid: &Grid,
        table: &ChartTable,
        vertices: usize,
        atlas: &ChartLayout,
        m: usize,
        texels: Texels,
    ) -> Self {
        let n = atlas.cell_size() as u64;
        let fit_batch = match texels {
            Texels::Points => 0,
            Texels::Fit => fit::batch_samples(n as usize, table.len()) as u64,
        };
        let inner = n.saturating_sub(2);
        let cells = table.len() as u64;
        Footprint {
            samples: vertices as u64 + table.edges.len() as u64 * inner + cells * inner * inner,
            texels: atlas.width() as u64 * atlas.height() as u64,
            cells,
            vertices: cells * (m as u64 + 1).pow(2),
            fit_batch,
            ..Footprint::grid(grid)
        }
    }
}

/// The largest estimated peak memory of a bake ([`estimated_peak_bytes`]): 2 GiB.
pub const MAX_BAKE_BYTES: u64 = 2 << 30;
/// The process and the GPU driver besides the bake's own data (measured on lavapipe:
/// 98 MiB with the device open, 119 MiB with the bake's pipeline compiled).
pub const BASE_BYTES: u64 = 128 << 20;
/// A mesh-stage grid corner: its f64 distance, the u32 index of its cell, and rayon's
/// slack while it joins the slabs (measured: 13.4 at grid 400).
pub const GRID_CORNER_BYTES: u64 = 16;
/// One sample of one level: [`CHANNELS`] f32s.
pub const LEVEL_SAMPLE_BYTES: u64 = 4 * CHANNELS as u64;
/// A level-0 sample while it is shaded: its point (16) and its [`Shaded`](super::gpu::Shaded) result (64).
pub const SHADE_SAMPLE_BYTES: u64 = 16 + 64;
/// A point of the dispatch in flight: its input (16), the GPU's output and readback
/// buffers (64 each) and the two copies of the readback (64 each).
pub const DISPATCH_POINT_BYTES: u64 = 16 + 4 * 64;
/// A level-0 sample when the shaded results become level 0: the [`Shaded`](super::gpu::Shaded) result
/// (64), level 0 ([`LEVEL_SAMPLE_BYTES`]) and the projected point (12). Filtering
/// level 0 holds less: the point, level 0, its smoothed copy and level 1 (111).
pub const HANDOVER_SAMPLE_BYTES: u64 = 64 + LEVEL_SAMPLE_BYTES + 12;
/// A level-0 sample while the outputs are encoded: every level (44 × 4/3 ≤ 59), the
/// projected point (12) and `--ktx2`'s stacked levels (4 × 4/3, twice: 11).
pub const ENCODE_SAMPLE_BYTES: u64 = LEVEL_SAMPLE_BYTES * 4 / 3 + 12 + 11;
/// A level-0 sample while `--texels fit` runs: level 0 ([`LEVEL_SAMPLE_BYTES`]) and the
/// projected point (12).
pub const FIT_HELD_SAMPLE_BYTES: u64 = LEVEL_SAMPLE_BYTES + 12;
/// A sub-texel sample of the fit's batch: its point (16) and its [`Shaded`](super::gpu::Shaded) result
/// (64), held together while the batch is shaded, then the result with the batch's
/// fitted texels (fewer than its samples: [`LEVEL_SAMPLE_BYTES`] covers them and each
/// chart's f64 scratch). The dispatch in flight adds [`DISPATCH_POINT_BYTES`] per point,
/// at most [`MAX_POINTS_PER_DISPATCH`] of them.
pub const FIT_BATCH_SAMPLE_BYTES: u64 = 16 + 64 + LEVEL_SAMPLE_BYTES;
/// An atlas texel while the outputs are encoded: four RGBA8 images (16), the .glb's
/// PNGs in its buffer and in the file (at worst 12 each: RGB, incompressible), and
/// `--object-normals` (an RGBA8 image and its PNG: 8).
pub const ENCODE_TEXEL_BYTES: u64 = 16 + 2 * 12 + 8;
/// A cell, whatever the atlas: the quad mesh (vertex, normal, quad: 64), the chart
/// table (corners, sides, two edges, a vertex's charts: about 230), the charts
/// (`Patches`, about 60), its entry in a packed layout and that entry's JSON copies
/// (about 200) and the per-cell work of the images and statistics (about 250).
pub const CELL_BYTES: u64 = 800;
/// A cell in `--charts`' JSON while the outputs are encoded: its entry (pretty-printed,
/// about 740 bytes: the sphere at `--grid 256`, 308,574 charts, wrote 227 MB and
/// peaked 140 MiB higher than without it) and the table it is printed from.
pub const CHARTS_FILE_CELL_BYTES: u64 = 800;
/// An exported vertex, at the .glb's encoding: its point in the bake's vertex grid
/// (f64: 24); the exported mesh's position, normal, tangent and texture coordinate
/// (48) and its share of the indices (at most 24: two triangles a quad, about a quad a
/// vertex); the welded copy the file holds (as much), and the file's buffer (as much,
/// made into the file in place); and 16 more, measured: the allocator's slack, the
/// weld's table of the cells' side vertices. Measured where vertices are most of a
/// bake (`--grid 512 --chart-quads 16`, 289 vertices a cell, `--size 512`): the
/// one-sphere scene (1.38 M vertices) peaked at 436 MiB against about 480 estimated,
/// shell_arrows.sdf (4.97 M) at 1,320 MiB against about 1,360. Before the export
/// stopped copying the mesh and the buffer they peaked at 584 and 1,794 MiB, against
/// about 366 and 1,000 estimated at 168 bytes a vertex. (At `--chart-quads` 1 or 2
/// every vertex goes through the weld's table, some 60–120 bytes each while it is
/// built, before the buffer exists; there cells and samples are most of a bake.) Since
/// the export drops the bake's own mesh once welded (`Baked::take_exported_mesh`) it
/// holds two meshes at once, not three, and the same bakes peaked at 356 and 1,058 MiB
/// (the sphere cut in half by `--bounds`, whose cut makes a third copy for a moment,
/// at 279 against about 350): the constant keeps the third copy as a margin, which
/// also holds the moment when folded triangles are dropped (a second index list and
/// four bytes a vertex).
pub const VERTEX_BYTES: u64 = 24 + 3 * (48 + 24) + 16;

/// The estimated peak memory of a bake and of writing its outputs, in bytes: the
/// largest of its phases, over [`BASE_BYTES`]. With S the level-0 samples (about the
/// level-0 texels of the charts) and T the atlas image's texels:
///
/// ```text
/// mesh:   16 B × grid corners                       (then freed)
/// after:  800 B × cells + 256 B × exported vertices
///         + max(80 B × S + 272 B × min(S, 2^20)     shading, one dispatch in flight,
///               + X,                                the scene's textures X bytes,
///               120 B × S + X,                      shaded results → level 0
///               56 B × S + 124 B × F                --texels fit, F at once,
///               + 272 B × min(F, 2^20) + X,
///               81 B × S + 48 B × T                 encoding the outputs
///               (+ 800 B × cells with --charts))
/// ```
///
/// Derived from the buffers each stage holds at once (the constants above), and
/// checked against peak resident sizes measured with `/usr/bin/time -v`: it is
/// 3–30 % over them (the peak is 0.77–0.97 of it on the examples, at the default grid
/// and with `--chart-quads` up to 16), the margin being mostly the PNGs taken as
/// incompressible.
pub fn estimated_peak_bytes(f: &Footprint) -> u64 {
    let s = f.samples;
    let dispatch = s.min(MAX_POINTS_PER_DISPATCH as u64);
    let mesh = GRID_CORNER_BYTES * f.grid_corners;
    let shade = SHADE_SAMPLE_BYTES * s + DISPATCH_POINT_BYTES * dispatch;
    let handover = HANDOVER_SAMPLE_BYTES * s;
    let encode = ENCODE_SAMPLE_BYTES * s
        + ENCODE_TEXEL_BYTES * f.texels
        + if f.charts_file {
            CHARTS_FILE_CELL_BYTES * f.cells
        } else {
            0
        };
    let fit = FIT_HELD_SAMPLE_BYTES * s
        + FIT_BATCH_SAMPLE_BYTES * f.fit_batch
        + DISPATCH_POINT_BYTES * f.fit_batch.min(MAX_POINTS_PER_DISPATCH as u64);
    // The textures are held while the pass lives: it shades, its results become
    // level 0, it fits.
    let (shade, handover, fit) = (
        shade + f.texture_bytes,
        handover + f.texture_bytes,
        fit + f.texture_bytes,
    );
    let after =
        CELL_BYTES * f.cells + VERTEX_BYTES * f.vertices + shade.max(handover).max(encode).max(fit);
    BASE_BYTES + mesh.max(after)
}

/// The estimate of [`estimated_peak_bytes`], or a message naming it and
/// [`MAX_BAKE_BYTES`] when it is over (`pipeline::check_memory` makes it a
/// `BakeError::Resource`).
pub fn check(f: &Footprint) -> Result<u64, String> {
    let estimate = estimated_peak_bytes(f);
    if estimate <= MAX_BAKE_BYTES {
        return Ok(estimate);
    }
    let mib = |b: u64| b.div_ceil(1 << 20);
    let textures = match f.texture_bytes {
        0 => String::new(),
        b => format!(", with {} MiB of the scene's textures", mib(b)),
    };
    let (what, fix) = if f.samples == 0 {
        (
            format!("its mesh grid of {} corners", f.grid_corners),
            "a coarser --grid or --edge",
        )
    } else {
        (
            format!(
                "{} level-0 samples, {} atlas texels and {} cells",
                f.samples, f.texels, f.cells
            ),
            "a smaller --size, a coarser --grid or --edge, or a smaller --chart-quads",
        )
    };
    Err(format!(
        "the bake would need about {} MiB of memory at its peak (estimated from {what}{textures}), over the limit of {} MiB for a bake: use {fix}{}",
        mib(estimate),
        mib(MAX_BAKE_BYTES),
        if f.texture_bytes > 0 {
            " (or smaller textures)"
        } else {
            ""
        }
    ))
}

/// The scene's textures' part of the footprint ([`Footprint::texture_bytes`]), from
/// their files' headers; a file that cannot be read counts nothing (loading it reports
/// why).
pub fn textures_footprint(module: &Module, base_dir: &Path) -> u64 {
    module
        .manifest
        .textures
        .iter()
        .filter_map(|t| image::image_dimensions(base_dir.join(&t.path)).ok())
        .map(|(w, h)| crate::bake::export::gltf::texture_bytes(w, h, 1))
        .fold(0u64, u64::saturating_add)
}
