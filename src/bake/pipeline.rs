//! The bake, stage by stage: mesh, charts, texel points, GPU shading, mips, images.

mod counts;
mod plan;
mod report;

use super::charts::{ChartTable, Samples};
use super::clip::CUT_SLACK_CELLS;
use super::fit;
pub use super::fit::Texels;
use super::gpu::{BakePass, Shaded};
use super::images;
pub use super::memory::{
    estimated_peak_bytes, textures_footprint, Footprint, BASE_BYTES, CELL_BYTES,
    DISPATCH_POINT_BYTES, ENCODE_SAMPLE_BYTES, ENCODE_TEXEL_BYTES, FIT_BATCH_SAMPLE_BYTES,
    FIT_HELD_SAMPLE_BYTES, GRID_CORNER_BYTES, HANDOVER_SAMPLE_BYTES, LEVEL_SAMPLE_BYTES,
    MAX_BAKE_BYTES, SHADE_SAMPLE_BYTES, VERTEX_BYTES,
};
use super::mesh::{contour_refining, refine, Grid, QuadMesh, Refining};
use super::mips::{self, Texel};
use super::patches::{self, Patches};
use super::{ChartLayout, FlatLayout, MeshData, PackedLayout, Textures};
use crate::codegen::Module;
use crate::gpu::{Gpu, GpuError};
use crate::ir::{Aabb, Op, Shape};
use counts::{count_emission, count_material, emissive_strength};
use glam::DVec3;
use plan::{check_precision, length, plan};
pub use plan::{MAX_COORDINATE, MIN_F32_STEPS_A_CELL};
pub use report::Report;
use std::path::Path;
use std::time::Instant;

/// The channels of a baked texel (the mip chain's, re-exported for the memory estimate).
pub use super::mips::CHANNELS;

/// How fine the mesh is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Resolution {
    /// Cells along the longest side of the bounds.
    Cells(usize),
    /// The cell's edge length.
    Edge(f64),
}

/// The default grid: cells along the longest side.
pub const DEFAULT_GRID: usize = 48;
/// The default mesh quads along a chart's side.
pub const DEFAULT_CHART_QUADS: usize = 1;
/// The most mesh quads along a chart's side.
pub const MAX_CHART_QUADS: usize = 16;
/// The largest atlas side.
pub const MAX_SIZE: u32 = 16384;
/// The default longest side of a grown chart, in cells (`--max-chart`).
pub const DEFAULT_MAX_CHART: usize = 16;
/// The most cells along a grown chart's side.
pub const MAX_MAX_CHART: usize = 256;

/// How the atlas is laid out (§3, Table 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Style {
    /// §3.3: one chart per cell, all the same size, levels in a mip-map pattern.
    #[default]
    Flat,
    /// §3.4: conforming rectangles of cells grown over the mesh, each chart as many
    /// texels as its cells, packed in shelves with a lookup table.
    Packed,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// The atlas side, a power of two.
    pub size: u32,
    pub resolution: Resolution,
    /// Bounds for shapes without finite bounds (or to bake part of a shape).
    pub bounds: Option<Aabb>,
    /// Mesh quads along a chart's side: charts come from a grid this many times
    /// coarser than the mesh's, and each is split into `chart_quads²` mesh quads.
    pub chart_quads: usize,
    /// Texels of gutter around each level-0 chart, filled from its neighbours (for
    /// engines that build their own mip chains; see [`FlatLayout::gutter`]); 0: none.
    pub gutter: u32,
    pub style: Style,
    /// The longest side of a grown chart, in cells (packed only).
    pub max_chart: usize,
    /// Whether cells that may hold detail finer than themselves are meshed on a finer
    /// grid ([`refine`]).
    pub refine: Refine,
    /// Level-0 texels point-sampled, or fitted for a bilinear reader ([`fit`]).
    pub texels: Texels,
    /// Whether the caller writes the chart table as JSON (`--charts`): the memory
    /// model counts it.
    pub charts_file: bool,
}

/// Refinement of the mesh where a cell may hold detail finer than itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Refine {
    /// Mesh plainly; where that mesh misses part of the surface (the coverage line),
    /// mesh again with [`refine::FIRST_REFINE`], then twice as fine while fine cells
    /// hold two sheets or surface is missed, up to [`refine::MAX_REFINE`]. Scenes the
    /// plain grid holds keep their mesh and charts as they were.
    #[default]
    Auto,
    /// Refine this many times (1: never).
    Times(usize),
}

impl Default for Options {
    fn default() -> Options {
        Options {
            size: 2048,
            resolution: Resolution::Cells(DEFAULT_GRID),
            bounds: None,
            chart_quads: DEFAULT_CHART_QUADS,
            gutter: 0,
            style: Style::Flat,
            max_chart: DEFAULT_MAX_CHART,
            refine: Refine::Auto,
            texels: Texels::Points,
            charts_file: false,
        }
    }
}

/// Why a bake stopped.
#[derive(Debug)]
pub enum BakeError {
    /// The shape has no material.
    NoMaterial,
    /// The shape has no finite bounds and no `--bounds` was given.
    Unbounded,
    /// No surface inside the bounds, as sampled on a grid of this cell size; whether
    /// the mesh was refined as finely as a bake refines.
    Empty(f64, bool),
    /// A bad option (size, grid, bounds).
    Option(String),
    /// The shape cannot be baked as it is (empty, or where f32 coordinates cannot
    /// hold its surface).
    Scene(String),
    /// The charts do not fit, or the atlas is over the adapter's limits.
    Resource(String),
    Gpu(GpuError),
}

impl std::fmt::Display for BakeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BakeError::NoMaterial => f.write_str(
                "the shape has no material to bake: paint it first, as in `render shape.paint(MATERIAL);`",
            ),
            BakeError::Unbounded => f.write_str(
                "the shape has no finite bounds (a plane or an infinite repeat): give the region to bake with --bounds MIN MAX, for example --bounds -2,-2,-2 2,2,2",
            ),
            BakeError::Empty(cell, refined) => write!(
                f,
                "found no surface inside the bounds on a grid of {}-unit cells: nothing to bake (a part thinner than a cell can fall between the samples: a finer --grid or --edge{} finds it)",
                length(*cell),
                if *refined { "" } else { ", or --refine 8," }
            ),
            BakeError::Option(m) | BakeError::Resource(m) | BakeError::Scene(m) => f.write_str(m),
            BakeError::Gpu(e) => write!(f, "{e}"),
        }
    }
}

impl From<GpuError> for BakeError {
    fn from(e: GpuError) -> BakeError {
        BakeError::Gpu(e)
    }
}

/// A finished bake.
pub struct Baked {
    pub quads: QuadMesh,
    pub table: ChartTable,
    /// The cells' charts (one per cell in a flat atlas).
    pub patches: Patches,
    pub atlas: ChartLayout,
    /// Every level's samples, level 0 first.
    pub levels: Vec<Samples<Texel<CHANNELS>>>,
    /// Level 0's projected sample points.
    pub points: Samples<[f32; 3]>,
    /// The exported mesh's vertices by chart ([`images::vertex_grid`]): the texels'
    /// points are placed on its triangles.
    pub vertex_grid: Samples<[f64; 3]>,
    /// The exported mesh chart by chart, as the images read it (each cell's vertices
    /// its own, the whole of every cell kept): [`Baked::take_exported_mesh`] makes the
    /// file's of it.
    pub mesh: MeshData,
    pub textures: Textures,
    pub report: Report,
    /// The region baked (`--bounds`), where the exported mesh is cut.
    pub bounds: Option<Aabb>,
}

impl Baked {
    /// The mesh a file holds, taken out of the bake (`mesh` is left empty): the vertices
    /// inside each chart shared ([`images::weld`]); with `--bounds`, the triangles cut
    /// at the box's faces ([`super::clip::to_box`]; the texels need no change, being
    /// placed through the same linear map); and without the folded triangles, which
    /// have two corners on one point ([`super::folded::drop_folded`]). The bake's own
    /// mesh is dropped once welded, so the export holds two meshes at once, not three.
    pub fn take_exported_mesh(&mut self) -> MeshData {
        let mesh = std::mem::take(&mut self.mesh);
        let welded = images::weld(&mesh, self.vertex_grid.n);
        drop(mesh);
        let (mesh, folded) = super::folded::drop_folded(match self.bounds {
            Some(b) => super::clip::to_box(welded, b, CUT_SLACK_CELLS * self.quads.cell),
            None => welded,
        });
        self.report.folded = folded;
        mesh
    }
}

/// Whether any part of the shape is painted.
pub fn has_material(shape: &Shape) -> bool {
    shape.nodes.iter().any(|n| matches!(n.op, Op::Paint { .. }))
}

/// The bake's progress: a stage's name, then how far it is (done, total).
pub trait Progress: Sync {
    fn stage(&self, _name: &'static str, _total: usize) {}
    fn advance(&self, _done: usize) {}
    fn finish(&self) {}
}

/// No progress display.
pub struct Quiet;
impl Progress for Quiet {}

/// The level-0 sample points of a chart table over a quad mesh, each computed once,
/// where a rasterizer of the exported mesh looks for them: corners are the mesh
/// vertices, side samples lie on the exported mesh's edge (linear between its
/// consecutive vertices, shared by both charts), interior samples on the exported
/// triangles that hold them (`grid`: [`images::vertex_grid`]), linear in the texel's
/// chart-local (u, v) as TEXCOORD_0 is. Each comes with the footprint of one texel
/// (the spacing of the samples).
pub fn sample_points(
    mesh: &QuadMesh,
    table: &ChartTable,
    n: usize,
    grid: &Samples<[f64; 3]>,
) -> Samples<[f32; 4]> {
    let v = &mesh.vertices;
    let spacing = 1.0 / (n - 1) as f64;
    let pack = |p: DVec3, footprint: f64| [p.x as f32, p.y as f32, p.z as f32, footprint as f32];
    Samples::build(
        table,
        v.len(),
        n,
        |i| pack(v[i], mesh.cell * spacing),
        |e, t| {
            let edge = &table.edges[e];
            let (a, b) = (v[edge.a as usize], v[edge.b as usize]);
            pack(
                images::on_edge(grid, table, e, t),
                (b - a).length() * spacing,
            )
        },
        |c, s, t| images::interior_point(mesh, table, grid, c, (s, t), spacing),
    )
}

/// [`super::memory::check`] as a [`BakeError::Resource`]: the estimated peak, or why
/// the bake is refused.
pub fn check_memory(f: &Footprint) -> Result<u64, BakeError> {
    super::memory::check(f).map_err(BakeError::Resource)
}

/// Runs the whole bake of `shape` (with the environment of its heights: a shape of a
/// scene with displacements or shell maps comes from `driver::Analysis::field`; a
/// bare shape's `Field::plain` has none, and would bake the surface without them)
/// with the compiled scene `module`. A bake whose
/// [`estimated_peak_bytes`] is over [`MAX_BAKE_BYTES`] is refused before any GPU work
/// ([`BakeError::Resource`]): its mesh grid before meshing, the rest once the atlas
/// is laid out.
pub fn bake<'s>(
    gpu: &Gpu,
    module: &Module,
    base_dir: &Path,
    shape: crate::ir::Field<'s>,
    options: &Options,
    progress: &dyn Progress,
) -> Result<Baked, BakeError> {
    let mut report = Report::default();
    let mut clock = Instant::now();
    let mut lap = |report: &mut Report, name: &'static str| {
        report.stages.push((name, clock.elapsed()));
        clock = Instant::now();
    };
    let (grid, m, bounds) = plan(gpu, &shape, options)?;
    let texture_bytes = textures_footprint(module, base_dir);
    check_memory(&Footprint {
        texture_bytes,
        ..Footprint::grid(&grid)
    })?;
    let scale = crate::uv::atlas::scale(&shape);
    report.grid = grid.dims;
    report.chart_quads = m;

    // 1. Mesh.
    let times = match options.refine {
        Refine::Auto => 1,
        Refine::Times(r) => r,
    };
    let (mut quads, _) = contour(shape, &grid, scale, times, &[], &mut report, progress)?;
    clip(&mut quads, options);
    // With `--refine auto`, a plain mesh that found no surface (a part thinner than a
    // cell everywhere) is refined where the surface samples lie, as one that missed
    // some of it.
    if quads.quads.is_empty() && options.refine != Refine::Auto {
        return Err(BakeError::Empty(grid.cell, refined_most(options)));
    }
    lap(&mut report, "mesh");
    let missed;
    (report.coverage, missed) = super::coverage::coverage_and_missed(shape, &quads, bounds);
    lap(&mut report, "coverage");
    // The plain mesh, kept while a refined one is tried; what the search measured of the
    // refined mesh's coverage (measured once its charts fit); whether f32 holds the mesh
    // refined r times (`check_precision`).
    let (mut plain, mut refined_held) = (None, None);
    let holds = |r: usize| check_precision(bounds, grid.cell / (m * r) as f64).is_ok();
    if options.refine == Refine::Auto && report.coverage.missed > 0.0 && holds(refine::FIRST_REFINE)
    {
        report.plain_coverage = Some(report.coverage);
        let (refined, held) = refine_auto(
            shape,
            &grid,
            scale,
            bounds,
            &missed,
            options,
            &holds,
            &mut report,
            progress,
        )?;
        let kept = std::mem::replace(&mut quads, refined);
        report.plain_chart_size = flat_chart_size(&kept, options);
        plain = Some(kept);
        lap(&mut report, "mesh, refined");
        refined_held = Some(held);
    }

    if quads.quads.is_empty() {
        return Err(BakeError::Empty(grid.cell, refined_most(options)));
    }

    // 2. Charts and layout.
    let ((patches, table, atlas, estimate), kept) = lay_out_refined(
        &mut quads,
        plain,
        &grid,
        m,
        options,
        texture_bytes,
        &mut report,
    )?;
    if !kept {
        refined_held = None;
    }
    report.estimated_peak = estimate;
    report.vertices = quads.vertices.len();
    report.cells = table.len();
    report.charts = patches.len();
    report.chart_size = atlas.cell_size();
    report.levels = atlas.levels();
    lap(&mut report, "charts");
    // The refined mesh is baked: its coverage (the search measured the mesh it stopped
    // at when it stopped for that). Not measured before: a refined mesh whose charts do
    // not fit is dropped (shell_arrows at 256²: 2.3 s of a 14 s bake).
    if let Some(held) = refined_held {
        report.coverage = held.unwrap_or_else(|| super::coverage::coverage(shape, &quads, bounds));
        lap(&mut report, "coverage");
    }

    // 3 and 4. Texel points where the exported mesh's triangles put them, shaded on
    // the GPU.
    let project = |p: DVec3| crate::ir::eval::project(shape, p, 1e-5 * scale).unwrap_or(p);
    let grid_points = images::vertex_grid(&quads, &table, m, &project);
    check_reaches(options, &quads, &grid_points, &table, grid.cell)?;
    let n = atlas.cell_size() as usize;
    let (level0, points) = shade(
        gpu,
        module,
        base_dir,
        &quads,
        &table,
        n,
        &grid_points,
        options.texels,
        progress,
        &mut report,
        &mut lap,
    )?;
    report.max_residual /= scale;
    count_material(&mut report, &level0, &points, options.bounds);
    // 5. Mips.
    progress.stage("mips", 1);
    let levels = mips::chain(&table, level0);
    progress.finish();
    lap(&mut report, "mips");
    // 6. Images and the mesh.
    progress.stage("images", 1);
    let mesh = images::mesh_data(&quads, &table, &atlas, &patches, &grid_points);
    let strength = emissive_strength(&levels, &atlas, &points, options.bounds);
    let textures = images::atlas_images(&mesh, m, &table, &atlas, &patches, &levels, strength);
    report.emissive_strength = textures.emissive_strength;
    count_emission(&mut report, &levels[0], &points, options.bounds);
    progress.finish();
    lap(&mut report, "images");
    statistics(&mut report, (&quads, &table, &atlas, n), &mesh);
    Ok(Baked {
        quads,
        table,
        patches,
        atlas,
        levels,
        points,
        vertex_grid: grid_points,
        mesh,
        textures,
        report,
        bounds: options.bounds,
    })
}

/// `--refine auto`'s search, once the plain mesh missed the samples `missed`: refined
/// at [`refine::FIRST_REFINE`], then twice as fine each time while fine cells still
/// hold two sheets or surface is still missed, where f32 `holds` the finer cells and
/// every cell that asks can be refined that far (the cells asking do not depend on the
/// factor). In a flat atlas, a
/// mesh whose charts do not fit ends the search: the last one that fits is returned (a
/// finer one has more charts still), or this one where none does (the caller then
/// bakes the plain mesh). With the mesh, its coverage where the search measured it.
#[allow(clippy::too_many_arguments)]
fn refine_auto(
    shape: crate::ir::Field,
    grid: &Grid,
    scale: f64,
    bounds: Aabb,
    missed: &[DVec3],
    options: &Options,
    holds: &dyn Fn(usize) -> bool,
    report: &mut Report,
    progress: &dyn Progress,
) -> Result<(QuadMesh, Option<super::coverage::Coverage>), BakeError> {
    let fits = |mesh: &QuadMesh| {
        options.style != Style::Flat
            || FlatLayout::fit_with(mesh.quads.len(), options.size, options.gutter).is_some()
    };
    let mut r = refine::FIRST_REFINE;
    let mut fitted: Option<(QuadMesh, Report)> = None;
    loop {
        let (mut refined, left) = contour(shape, grid, scale, r, missed, report, progress)?;
        clip(&mut refined, options);
        if !fits(&refined) {
            return Ok(match fitted.take() {
                Some((earlier, its)) => {
                    *report = its;
                    (earlier, None)
                }
                None => (refined, None),
            });
        }
        let finer = 2 * r;
        if finer > refine::MAX_REFINE
            || report.refine_wanted > refine::max_refined(finer)
            || !holds(finer)
        {
            return Ok((refined, None));
        }
        if left == 0 {
            let held = super::coverage::coverage(shape, &refined, bounds);
            if held.missed == 0.0 {
                return Ok((refined, Some(held)));
            }
        }
        fitted = Some((refined, report.clone()));
        r = finer;
    }
}

/// Stage 2 where a refined mesh is in `quads` and the plain one in `plain` (or no
/// refinement was tried: `plain` is `None`): the layout of `quads`; or, where the
/// refined mesh's charts do not fit, the plain mesh's (put in `quads`, with the report
/// set back to it), and an error where the plain mesh has no surface either. With
/// whether the refined mesh was kept.
fn lay_out_refined(
    quads: &mut QuadMesh,
    plain: Option<QuadMesh>,
    grid: &Grid,
    m: usize,
    options: &Options,
    texture_bytes: u64,
    report: &mut Report,
) -> Result<(Laid, bool), BakeError> {
    match (lay_out_charts(quads, grid, m, options, texture_bytes), plain) {
        // The refined mesh's charts do not fit, and the plain mesh has none.
        (Err(BakeError::Resource(why)), Some(plain)) if plain.quads.is_empty() => {
            Err(BakeError::Resource(format!(
                "{why} (the plain grid found no surface, and the mesh refined where the surface lies was refused)"
            )))
        }
        // The refined mesh's charts do not fit where the plain mesh's may: bake that,
        // with the coverage line's warning, as before refinement.
        (Err(BakeError::Resource(why)), Some(plain)) => {
            *quads = plain;
            report.refine_dropped = Some(why);
            report.plain_chart_size = None;
            report.coverage = report.plain_coverage.take().unwrap_or_default();
            (report.refine, report.refined) = (1, 0);
            Ok((lay_out_charts(quads, grid, m, options, texture_bytes)?, false))
        }
        (laid, _) => Ok((laid?, true)),
    }
}

/// What a flat atlas would give the charts of `mesh` (the plain mesh, for the report
/// of a refined bake): `None` in a packed atlas, or for a mesh without quads.
fn flat_chart_size(mesh: &QuadMesh, options: &Options) -> Option<u32> {
    if options.style != Style::Flat || mesh.quads.is_empty() {
        return None;
    }
    FlatLayout::fit_with(mesh.quads.len(), options.size, options.gutter).map(|l| l.chart_size)
}

/// The report's figures of the mesh and the atlas: the triangles, the utilisation, the
/// texel density's spread and the slivers.
fn statistics(
    report: &mut Report,
    (quads, table, atlas, n): (&QuadMesh, &ChartTable, &ChartLayout, usize),
    mesh: &MeshData,
) {
    report.triangles = mesh.indices.len() / 3;
    report.utilisation = atlas.utilisation(table.len());
    (report.density_spread, report.slivers) = density_spread(quads, table, n);
}

/// That the file's mesh will hold a triangle: one that is not folded (two corners on one
/// point in f32, which the export leaves out: [`super::folded`]) and, with `--bounds`,
/// that has a part in them once cut (the quads kept may only come near them). Else the
/// bake finds no surface to bake (a thin frame on a coarse grid can mesh into folded
/// quads alone), which is said before the GPU's work.
fn check_reaches(
    options: &Options,
    quads: &QuadMesh,
    grid_points: &Samples<[f64; 3]>,
    table: &ChartTable,
    cell: f64,
) -> Result<(), BakeError> {
    let mut triangles =
        images::grid_triangles(grid_points, table).filter(|&t| !super::folded::is_folded(t));
    let held = match options.bounds {
        Some(b) => super::clip::reaches(triangles, b, CUT_SLACK_CELLS * quads.cell),
        None => triangles.next().is_some(),
    };
    if held {
        Ok(())
    } else {
        Err(BakeError::Empty(cell, refined_most(options)))
    }
}

/// Whether the mesh was refined as finely as a bake refines (`--refine 8`): then the
/// message for no surface does not suggest it.
fn refined_most(options: &Options) -> bool {
    options.refine == Refine::Times(refine::MAX_REFINE)
}

/// With `--bounds`, the part of the mesh that may reach into them
/// ([`QuadMesh::retain_reaching`], by half a cell: the exported mesh's points bulge past
/// a quad's corners by much less); [`Baked::take_exported_mesh`] then cuts the exported mesh
/// at their faces. The box is the user's: where it reaches past the shape's own bounds
/// (which hold the whole surface) it cuts nothing.
fn clip(mesh: &mut QuadMesh, options: &Options) {
    if let Some(b) = options.bounds {
        mesh.retain_reaching(b, 0.5 * mesh.cell);
    }
}

/// Stage 1: the mesh of `shape` by dual contouring over `grid`, cells with finer
/// detail `refine` times finer, and how many fine cells still hold two sheets (the
/// mesh may have no quads: the caller decides).
fn contour(
    shape: crate::ir::Field,
    grid: &Grid,
    scale: f64,
    refine: usize,
    missed: &[DVec3],
    report: &mut Report,
    progress: &dyn Progress,
) -> Result<(QuadMesh, usize), BakeError> {
    progress.stage("mesh", 1);
    let refining = Refining::Select(missed);
    let made = contour_refining(shape, grid, 1e-5 * scale, refine, refining);
    (report.refine, report.refined, report.refine_wanted) = (refine, made.refined, made.wanted);
    progress.finish();
    Ok((made.mesh, made.fine_two_sheets))
}

/// Stage 2: the charts (one a cell, or grown, which turns the quads to their charts'
/// directions), the chart table and the atlas's layout; refused when the layout does
/// not fit, or when the rest of the bake would take too much memory.
fn lay_out_charts(
    quads: &mut QuadMesh,
    grid: &Grid,
    m: usize,
    options: &Options,
    texture_bytes: u64,
) -> Result<Laid, BakeError> {
    let patches = match options.style {
        Style::Flat => Patches::singles(quads.quads.len()),
        Style::Packed => patches::grow(quads, options.max_chart),
    };
    // (After growing: the quads are turned to their charts' directions.)
    let table = ChartTable::new(quads);
    let (charts, size) = (patches.len(), options.size);
    let atlas: ChartLayout = match options.style {
        Style::Flat => FlatLayout::fit_with(charts, size, options.gutter).map(ChartLayout::Flat),
        Style::Packed => PackedLayout::fit(&patches.dims, size).map(ChartLayout::Packed),
    }
    .ok_or_else(|| {
        let gutter = match options.gutter {
            0 => String::new(),
            g => format!(" with a gutter of {g} texels (a chart at least as large as its gutter)"),
        };
        BakeError::Resource(format!(
            "{charts} charts do not fit a {size}×{size} atlas even at 2×2 texels a cell{gutter}: use a coarser --grid, a larger --size{}",
            if options.gutter > 0 { " or a narrower --gutter" } else { "" }
        ))
    })?;
    let vertices = quads.vertices.len();
    let f = footprint(grid, &table, vertices, &atlas, m, options, texture_bytes);
    let estimate = check_memory(&f)?;
    Ok((patches, table, atlas, estimate))
}

/// A laid-out atlas: the charts, the chart table, the layout, and the memory model's
/// estimate of the bake's peak with them.
type Laid = (Patches, ChartTable, ChartLayout, u64);

/// The whole bake's footprint once its atlas is laid out ([`Footprint::of`] with the
/// scene's textures).
fn footprint(
    grid: &Grid,
    table: &ChartTable,
    vertices: usize,
    atlas: &ChartLayout,
    m: usize,
    options: &Options,
    texture_bytes: u64,
) -> Footprint {
    Footprint {
        texture_bytes,
        charts_file: options.charts_file,
        ..Footprint::of(grid, table, vertices, atlas, m, options.texels)
    }
}

/// Stages 3 and 4: level 0's texel points (each shared one once), shaded on the GPU:
/// the filtered channels and the projected points. Sets the report's sample count and
/// largest residual (in scene units). Each buffer is dropped as soon as it is used,
/// for the memory model of [`estimated_peak_bytes`].
#[allow(clippy::too_many_arguments)]
fn shade(
    gpu: &Gpu,
    module: &Module,
    base_dir: &Path,
    quads: &QuadMesh,
    table: &ChartTable,
    n: usize,
    grid: &Samples<[f64; 3]>,
    texels: Texels,
    progress: &dyn Progress,
    report: &mut Report,
    lap: &mut dyn FnMut(&mut Report, &'static str),
) -> Result<(Samples<Texel<CHANNELS>>, Samples<[f32; 3]>), BakeError> {
    let points = sample_points(quads, table, n, grid);
    let (nc, ne) = (points.corners.len(), points.edges.len());
    let mut flat = points.corners;
    flat.extend(points.edges);
    flat.extend(points.interiors);
    report.samples = flat.len();
    lap(report, "texel points");

    let pass = BakePass::new(gpu, module, base_dir)?;
    lap(report, "pipeline (GPU)");
    progress.stage("shade", flat.len());
    let shaded = pass.run(gpu, &flat, &|k| progress.advance(k))?;
    drop(flat);
    progress.finish();
    let texel = |s: &Shaded| -> Texel<CHANNELS> {
        [
            s.color[0],
            s.color[1],
            s.color[2],
            s.roughness,
            s.metallic,
            s.emission[0],
            s.emission[1],
            s.emission[2],
            s.normal[0],
            s.normal[1],
            s.normal[2],
        ]
    };
    let mut level0 = Samples {
        n,
        corners: shaded[..nc].iter().map(texel).collect(),
        edges: shaded[nc..nc + ne].iter().map(texel).collect(),
        interiors: shaded[nc + ne..].iter().map(texel).collect(),
    };
    let position = |s: &Shaded| s.position;
    let projected = Samples {
        n,
        corners: shaded[..nc].iter().map(position).collect(),
        edges: shaded[nc..nc + ne].iter().map(position).collect(),
        interiors: shaded[nc + ne..].iter().map(position).collect(),
    };
    report.max_residual = shaded.iter().map(|s| s.residual as f64).fold(0.0, f64::max);
    drop(shaded);
    lap(report, "shade (GPU)");
    if texels == Texels::Fit {
        progress.stage("fit", fit::half_count(n) * table.len());
        report.fit_samples = fit::fit(gpu, &pass, quads, table, grid, &mut level0, &|k| {
            progress.advance(k)
        })?;
        progress.finish();
        lap(report, "fit (GPU)");
    }
    Ok((level0, projected))
}

/// The charts' texel density, (n − 1) texels over the square root of the chart's area:
/// its coefficient of variation over the charts whose area is at least 1 % of the
/// median, and how many are below that (slivers, where dual contouring put two
/// vertices at one sharp feature).
fn density_spread(mesh: &QuadMesh, table: &ChartTable, n: usize) -> (f64, usize) {
    let areas: Vec<f64> = table
        .corners
        .iter()
        .map(|q| {
            let p = q.map(|i| mesh.vertices[i as usize]);
            0.5 * ((p[1] - p[0]).cross(p[2] - p[0]).length()
                + (p[2] - p[0]).cross(p[3] - p[0]).length())
        })
        .collect();
    let mut sorted = areas.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    let densities: Vec<f64> = areas
        .iter()
        .filter(|&&a| a >= 0.01 * median && a > 0.0)
        .map(|a| (n - 1) as f64 / a.sqrt())
        .collect();
    let slivers = areas.len() - densities.len();
    let count = densities.len().max(1) as f64;
    let mean = densities.iter().sum::<f64>() / count;
    let var = densities.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / count;
    (var.sqrt() / mean.max(1e-12), slivers)
}
