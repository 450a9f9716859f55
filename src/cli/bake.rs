//! `sdfc bake`: a textured scene → a textured mesh with a seamless atlas (.glb).

use super::{compile, exit, BakeArgs};
use indicatif::{ProgressBar, ProgressStyle};
use sdfc::bake::pipeline::{self, BakeError, Baked, Options, Progress, Refine, Resolution, Texels};
use sdfc::bake::{export, table::ChartsFile, MeshData};
use sdfc::fsutil::write_output;
use sdfc::gpu::Gpu;
use sdfc::ir::Aabb;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Mutex;

/// Parses `x,y,z`.
pub fn parse_point(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let bad = || format!("expected x,y,z (three finite numbers), found {s:?}");
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip(parts) {
        *o = p.trim().parse::<f64>().map_err(|_| bad())?;
        if !o.is_finite() {
            return Err(bad());
        }
    }
    Ok(out)
}

/// Parses `--texels`: `fit` or `points`.
pub fn parse_texels(s: &str) -> Result<Texels, String> {
    match s {
        "fit" => Ok(Texels::Fit),
        "points" => Ok(Texels::Points),
        _ => Err(format!("expected fit or points, found {s:?}")),
    }
}

/// Parses `--refine`: `auto` or a factor from 1 to [`refine::MAX_REFINE`].
pub fn parse_refine(s: &str) -> Result<Refine, String> {
    use sdfc::bake::mesh::refine;
    if s == "auto" {
        return Ok(Refine::Auto);
    }
    match s.parse::<usize>() {
        Ok(r) if (1..=refine::MAX_REFINE).contains(&r) => Ok(Refine::Times(r)),
        _ => Err(format!(
            "expected auto or a whole number from 1 to {} (fine cells along a refined cell's side), found {s:?}",
            refine::MAX_REFINE
        )),
    }
}

/// Progress bars on standard error (hidden when it is not a terminal).
struct Bars {
    bar: Mutex<Option<ProgressBar>>,
}

impl Progress for Bars {
    fn stage(&self, name: &'static str, total: usize) {
        let bar = ProgressBar::new(total as u64);
        bar.set_style(
            ProgressStyle::with_template("{msg:>8} [{bar:30}] {pos}/{len} ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(name);
        *self.bar.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }
    fn advance(&self, done: usize) {
        if let Some(b) = &*self.bar.lock().unwrap_or_else(|e| e.into_inner()) {
            b.inc(done as u64);
        }
    }
    fn finish(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish_and_clear();
        }
    }
}

fn status(e: &BakeError) -> u8 {
    match e {
        BakeError::NoMaterial | BakeError::Empty(..) | BakeError::Scene(_) => exit::SCENE,
        BakeError::Unbounded | BakeError::Option(_) => exit::USAGE,
        BakeError::Resource(_) => exit::RESOURCE,
        BakeError::Gpu(g) => exit::gpu(g),
    }
}

/// The region `flag` gives (none, or MIN MAX with MIN below MAX on every axis).
fn bounds(flag: &str, points: &[[f64; 3]]) -> Result<Option<Aabb>, String> {
    match points {
        [] => Ok(None),
        [lo, hi] => {
            let (min, max) = (glam::DVec3::from(*lo), glam::DVec3::from(*hi));
            if !min.cmplt(max).all() {
                return Err(format!(
                    "{flag}: the minimum {lo:?} must be below the maximum {hi:?} on every axis"
                ));
            }
            Ok(Some(Aabb { min, max }))
        }
        _ => Err(format!("{flag} takes two points: MIN MAX, each x,y,z")),
    }
}

/// The options of `args`, checked before any work.
pub fn options(args: &BakeArgs) -> Result<Options, String> {
    let resolution = match (args.grid, args.edge) {
        (Some(n), None) => Resolution::Cells(n),
        (None, Some(e)) => Resolution::Edge(e),
        (None, None) => Resolution::Cells(pipeline::DEFAULT_GRID),
        (Some(_), Some(_)) => return Err("give --grid or --edge, not both".into()),
    };
    let bounds = bounds("--bounds", &args.bounds)?;
    if args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf"))
    {
        return Err(format!(
            "-o {}: sdfc bake writes binary glTF with its images inside (.glb); a .gltf file is JSON: name the output .glb",
            args.output.display()
        ));
    }
    let style = match args.layout {
        super::Layout::Flat => pipeline::Style::Flat,
        super::Layout::Packed => pipeline::Style::Packed,
    };
    if style == pipeline::Style::Packed {
        if args.gutter > 0 {
            return Err("--gutter pads the flat layout's charts; the packed layout has none (its charts are fewer and larger, so a generic mip chain crosses fewer borders)".into());
        }
        if args.ktx2.is_some() {
            return Err("--ktx2 writes the flat layout's chart grid at every level (the stacked style); the packed layout's charts differ in size, so bake with --layout flat for it".into());
        }
    }
    let max_chart = match (args.max_chart, style) {
        (Some(_), pipeline::Style::Flat) => {
            return Err("--max-chart bounds the packed layout's grown charts; the flat layout's charts are one cell each (add --layout packed)".into());
        }
        (Some(m), _) => m,
        (None, _) => pipeline::DEFAULT_MAX_CHART,
    };
    if !(1..=pipeline::MAX_MAX_CHART).contains(&max_chart) {
        return Err(format!(
            "--max-chart {max_chart} is not between 1 and {}",
            pipeline::MAX_MAX_CHART
        ));
    }
    Ok(Options {
        size: args.size,
        resolution,
        bounds,
        chart_quads: args.chart_quads,
        gutter: args.gutter,
        style,
        max_chart,
        refine: args.refine,
        texels: args.texels,
        charts_file: args.charts.is_some(),
    })
}

/// Writes every output, or none: all are encoded first, then each is written atomically.
fn write_all(outputs: &[(PathBuf, Vec<u8>)]) -> Result<(), String> {
    let mut created: Vec<&PathBuf> = Vec::new();
    for (path, bytes) in outputs {
        let existed = path.symlink_metadata().is_ok();
        if let Err(e) = write_output(path, bytes) {
            // All or nothing: remove the files this run created before the failure.
            for p in created {
                let _ = std::fs::remove_file(p);
            }
            return Err(format!("cannot write {}: {e}", path.display()));
        }
        if !existed {
            created.push(path);
        }
    }
    Ok(())
}

/// The files to write, and the file's triangles; or the message and exit status.
fn encode(
    args: &BakeArgs,
    baked: &mut Baked,
    (name, material): (&str, &str),
) -> Result<(Vec<(PathBuf, Vec<u8>)>, usize), (String, u8)> {
    // The file shares the vertices inside each chart (the bake's own mesh is chart by
    // chart, as its images read it) and ends at --bounds' faces.
    let mesh = baked.take_exported_mesh();
    let triangles = mesh.indices.len() / 3;
    // The bake checked that a triangle is left before its GPU work; a cut whose every
    // piece folds in f32 (within a rounding error of the box's faces) could still leave
    // none.
    if triangles == 0 {
        return Err((
            String::from("no triangle of the mesh is left inside the bounds once cut (those at their faces fold to a line in f32): nothing to bake (a finer --grid or --edge, or bounds a little wider, keep the surface)"),
            exit::SCENE,
        ));
    }
    let encoded = encode_files(args, baked, mesh, (name, material));
    encoded
        .map(|out| (out, triangles))
        .map_err(|e| (format!("cannot encode the bake: {e}"), exit::RESOURCE))
}

/// The files of [`encode`] for the file's mesh `mesh` (dropped once in the `.glb`).
fn encode_files(
    args: &BakeArgs,
    baked: &Baked,
    mesh: MeshData,
    (name, material): (&str, &str),
) -> Result<Vec<(PathBuf, Vec<u8>)>, String> {
    let glb = export::glb(&mesh, &baked.textures, &baked.atlas, name, material)?;
    drop(mesh);
    let mut out = vec![(args.output.clone(), glb)];
    if let (Some(path), sdfc::bake::ChartLayout::Flat(layout)) = (&args.ktx2, &baked.atlas) {
        let levels: Vec<image::RgbaImage> = baked
            .levels
            .iter()
            .enumerate()
            .map(|(l, s)| sdfc::bake::images::stacked_level(&baked.table, layout, s, l))
            .collect();
        out.push((path.clone(), export::ktx2(&levels, true)?));
    }
    if let Some(path) = &args.object_normals {
        let img = sdfc::bake::images::object_normals(
            &baked.table,
            &baked.atlas,
            &baked.patches,
            &baked.levels,
        );
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .map_err(|e| e.to_string())?;
        out.push((path.clone(), png));
    }
    if let Some(path) = &args.charts {
        let file = ChartsFile::new(&baked.table, &baked.atlas, &baked.patches);
        let json = serde_json::to_vec_pretty(&file).map_err(|e| e.to_string())?;
        out.push((path.clone(), json));
    }
    Ok(out)
}

pub fn run(args: BakeArgs) -> ExitCode {
    args.run_time.install();
    let options = match options(&args) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(exit::USAGE);
        }
    };
    // Outputs that cannot be written fail now, not after the bake: a missing or
    // read-only folder, a folder in the file's place.
    let outputs: Vec<&PathBuf> = std::iter::once(&args.output)
        .chain(&args.ktx2)
        .chain(&args.charts)
        .chain(&args.object_normals)
        .collect();
    let flagged: Vec<(&str, &std::path::Path)> = [("-o", Some(&args.output))]
        .into_iter()
        .chain([
            ("--ktx2", args.ktx2.as_ref()),
            ("--charts", args.charts.as_ref()),
            ("--object-normals", args.object_normals.as_ref()),
        ])
        .filter_map(|(flag, p)| Some((flag, p?.as_path())))
        .collect();
    if let Err(e) = sdfc::fsutil::distinct_outputs(&flagged, &[("scene", args.scene.as_path())]) {
        eprintln!("error: {e}");
        return ExitCode::from(exit::USAGE);
    }
    for path in &outputs {
        if let Err(e) = sdfc::fsutil::check_writable(path) {
            eprintln!("error: cannot write {}: {e}", path.display());
            return ExitCode::from(exit::USAGE);
        }
    }
    let codegen_options = sdfc::codegen::Options {
        walk: args.walk,
        seed_grid: sdfc::codegen::SeedGridChoice::Auto,
        atlas: None,
        plain: false,
        cold: false,
        constant_uv: false,
        unions_as_code: false,
        prune: false,
        seed_data: sdfc::codegen::SeedData::Auto,
        bounds: sdfc::codegen::Bounds::Off,
        differences: false,
        tiles: false,
        multiscale: false,
    };
    let (_, analysis, compiled) =
        match compile::build(&args.scene, args.shape.as_deref(), &codegen_options) {
            Ok(x) => x,
            Err(code) => return code,
        };
    let Some(scene) = &analysis.scene else {
        return ExitCode::from(exit::SCENE);
    };
    // Nor may an output replace a texture the scene reads.
    let base = super::base_dir(&args.scene);
    let textures: Vec<PathBuf> = analysis
        .program
        .textures
        .iter()
        .map(|t| t.resolved.clone().unwrap_or_else(|| base.join(&t.path)))
        .collect();
    let inputs: Vec<(&str, &std::path::Path)> = std::iter::once(("scene", args.scene.as_path()))
        .chain(textures.iter().map(|t| ("texture", t.as_path())))
        .collect();
    if let Err(e) = sdfc::fsutil::distinct_outputs(&flagged, &inputs) {
        eprintln!("error: {e}");
        return ExitCode::from(exit::USAGE);
    }
    let shape = match sdfc::driver::pick_shape(scene, args.shape.as_deref()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(exit::USAGE);
        }
    };
    let gpu = match super::open_gpu(args.backend) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let bars = Bars {
        bar: Mutex::new(None),
    };
    let baked = match pipeline::bake(
        &gpu,
        &compiled.module,
        &base,
        analysis.field(shape),
        &options,
        &bars,
    ) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(status(&e));
        }
    };
    let name = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let material = material_name(&analysis.program, shape, &name);
    let mut baked = baked;
    let (outputs, triangles) = match encode(&args, &mut baked, (&name, &material)) {
        Ok(o) => o,
        Err((e, status)) => {
            eprintln!("error: {e}");
            return ExitCode::from(status);
        }
    };
    if let Err(e) = write_all(&outputs) {
        eprintln!("error: {e}");
        return ExitCode::from(exit::USAGE);
    }
    print_report(&baked, &gpu, baked.bounds.map(|_| triangles));
    for (path, bytes) in &outputs {
        eprintln!("wrote {} ({} bytes)", path.display(), bytes.len());
    }
    ExitCode::SUCCESS
}

/// The report's lines on what the images could not hold as the material has it:
/// undefined values, values out of range (clamped), emission over 1 (carried by the
/// strength), emission lost to it.
fn print_material(r: &sdfc::bake::pipeline::Report) {
    if r.undefined > 0 {
        eprintln!(
            "warning: the material is undefined (NaN or infinite) at {} of the {} level-0 samples, which the file's images cannot hold (NaN is written as 0, an infinity as its channel's limit): look for a division by zero, or a square root or logarithm of a negative number, in its expressions",
            r.undefined, r.shown
        );
    }
    if r.out_of_range > 0 {
        eprintln!(
            "warning: the material is out of the images' range at {} of the {} level-0 samples (colour, roughness and metallic hold 0 to 1, emission 0 or more): the file holds it clamped",
            r.out_of_range, r.shown
        );
    }
    let strength = r.emissive_strength;
    let strength = if strength < 1e6 {
        format!("{strength}")
    } else {
        format!("{strength:.3e}")
    };
    if r.emission_over_one > 0 {
        eprintln!(
            "emission:       over 1 at {} of the {} level-0 samples, up to {strength}: the emissive texture holds it divided by that, and the glTF's KHR_materials_emissive_strength multiplies it back (a viewer without that extension shows the emission that much dimmer)",
            r.emission_over_one, r.shown
        );
    }
    if r.emission_lost > 0 {
        eprintln!(
            "warning: divided by its largest value ({strength}), the emission rounds to 0 in the 8-bit emissive texture at {} of the {} level-0 samples that emit: a few very bright samples dim the rest (look for a division by a value near 0 in the emission)",
            r.emission_lost, r.emitting
        );
    }
}

/// The quality report: charts, utilisation, texel-density spread, time per stage; with
/// `cut`, the triangles of the file's mesh cut at `--bounds`.
pub fn print_report(baked: &Baked, gpu: &Gpu, cut: Option<usize>) {
    let r = &baked.report;
    let l = &baked.atlas;
    eprintln!("adapter:        {}", gpu.describe());
    eprintln!(
        "mesh:           {} cells (chart grid {}×{}×{}), {} triangles ({}×{} quads per cell)",
        r.cells, r.grid[0], r.grid[1], r.grid[2], r.triangles, r.chart_quads, r.chart_quads
    );
    if let Some(k) = cut {
        eprintln!("cut:            at the bounds' faces, {k} triangles in the file");
    }
    if r.folded > 0 {
        eprintln!(
            "folded:         {} triangles with two corners on one point left out of the file (no area; each lay folded onto a neighbour's edge)",
            r.folded
        );
    }
    if let Some(why) = &r.refine_dropped {
        eprintln!("refined:        none: the refined mesh's charts do not fit ({why}); baked the plain grid's mesh");
    }
    if r.refine > 1 {
        let capped = if r.refine_wanted > r.refined {
            format!(
                " (of {} that asked: the limit is {} fine cells)",
                r.refine_wanted,
                sdfc::bake::mesh::refine::MAX_FINE_CELLS
            )
        } else {
            String::new()
        };
        let mut why = match r.plain_coverage {
            Some(c) => format!(
                "; the plain grid's mesh missed {:.1} % of the surface",
                100.0 * c.missed
            ),
            None => String::new(),
        };
        if let Some(plain) = r.plain_chart_size.filter(|&p| p > r.chart_size) {
            why += &format!(
                " (its charts would have had {plain}² texels, these {}²: a larger --size keeps more, --refine 1 keeps the plain mesh)",
                r.chart_size
            );
        }
        eprintln!(
            "refined:        {} cells with detail finer than a cell, meshed {}× finer{capped}{why}",
            r.refined, r.refine
        );
    }
    match l {
        sdfc::bake::ChartLayout::Flat(f) => eprintln!(
            "atlas:          {}×{} flat, {} charts of {}² texels, {} levels (down to 2²){}",
            f.width,
            f.height,
            r.charts,
            r.chart_size,
            r.levels,
            if f.image_height() < f.height {
                format!(
                    "; the material's textures {}×{} (level 0), the levels below in images of their own",
                    f.width,
                    f.image_height()
                )
            } else {
                String::new()
            }
        ),
        sdfc::bake::ChartLayout::Packed(p) => eprintln!(
            "atlas:          {}×{} packed, {} charts of 1 to {} cells ({:.1} cells on average), {}² texels a cell, {} levels (down to 2² a cell)",
            p.width,
            p.height,
            r.charts,
            baked.patches.dims.iter().map(|d| d[0] * d[1]).max().unwrap_or(0),
            r.cells as f64 / r.charts.max(1) as f64,
            r.chart_size,
            r.levels
        ),
    }
    eprintln!(
        "utilisation:    {:.1} % of the atlas's texels",
        r.utilisation * 100.0
    );
    eprintln!(
        "memory:         about {} MiB at the peak, estimated (the limit is {} MiB)",
        r.estimated_peak >> 20,
        sdfc::bake::pipeline::MAX_BAKE_BYTES >> 20
    );
    eprintln!(
        "density spread: {:.3} (coefficient of variation of texels per unit length; {} sliver charts left out)",
        // (Adding 0 turns a -0 into 0.)
        r.density_spread + 0.0,
        r.slivers
    );
    eprintln!(
        "projection:     largest |f| at a texel point {:.2e} of the scale ({} samples)",
        r.max_residual, r.samples
    );
    if r.fit_samples > 0 {
        eprintln!(
            "texels:         inner texels fitted for a bilinear reader from {} more samples (--texels fit)",
            r.fit_samples
        );
    }
    print_material(r);
    let c = &r.coverage;
    // (Samples are not looked at past two cells.)
    let farthest = if c.farthest >= 2.0 {
        "2 cells or more".to_string()
    } else {
        format!("{:.2} cells", c.farthest)
    };
    if c.samples == 0 {
        eprintln!("surface held:   not measured (no surface sample within the bounds)");
    } else {
        eprintln!(
            "surface held:   {:.1} % by area within half a cell of the mesh (farthest of {} samples: {farthest})",
            100.0 * (1.0 - c.missed),
            c.samples,
        );
    }
    if c.missed > 0.0 {
        // What can help, from what this bake did.
        let remedy = if r.refine_dropped.is_some() {
            "the refined mesh that holds it was refused (the `refined:` line says why)"
        } else if r.refine < sdfc::bake::mesh::refine::MAX_REFINE {
            "a finer --grid or --edge, or --refine 8, holds more of it"
        } else {
            "a finer --grid or --edge holds more of it"
        };
        eprintln!(
            "warning: the mesh misses {:.1} % of the surface (by area, samples farther than half a cell from it, the farthest {farthest}): parts thinner than a cell fall between the grid's corners; {remedy}",
            100.0 * c.missed,
        );
    }
    let total: f64 = r.stages.iter().map(|(_, d)| d.as_secs_f64()).sum();
    for (name, d) in &r.stages {
        eprintln!("  {name:<14} {:>8.3} s", d.as_secs_f64());
    }
    eprintln!("  {:<14} {total:>8.3} s", "total");
}

/// `sdfc bench --bake`: the time of each stage of one bake, with the walk form `sdfc
/// bake` uses by default (the loop: lavapipe takes minutes to compile the robot's
/// unrolled walk, and the bake's cost is the shading, not the walk's form).
pub fn bench(scene: &std::path::Path, args: &super::BenchArgs) -> ExitCode {
    let bounds = match bounds("--bake-bounds", &args.bake_bounds) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(exit::USAGE);
        }
    };
    // What is not given is `sdfc bake`'s default.
    let defaults = Options::default();
    let options = Options {
        bounds,
        size: args.atlas_size.unwrap_or(defaults.size),
        style: match args.bake_layout {
            None => defaults.style,
            Some(super::Layout::Flat) => pipeline::Style::Flat,
            Some(super::Layout::Packed) => pipeline::Style::Packed,
        },
        texels: args.bake_texels.unwrap_or(defaults.texels),
        ..defaults
    };
    let base = super::base_dir(scene);
    let codegen = sdfc::codegen::Options {
        walk: sdfc::codegen::WalkForm::Loop,
        ..Default::default()
    };
    let (_, analysis, compiled) = match compile::build(scene, args.shape.as_deref(), &codegen) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let Some(ir) = &analysis.scene else {
        return ExitCode::from(exit::SCENE);
    };
    let shape = match sdfc::driver::pick_shape(ir, args.shape.as_deref()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(exit::USAGE);
        }
    };
    let gpu = match super::open_gpu(args.backend) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let baked = match pipeline::bake(
        &gpu,
        &compiled.module,
        &base,
        analysis.field(shape),
        &options,
        &pipeline::Quiet,
    ) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("error: {e}");
            // The bake's messages name `sdfc bake`'s flags.
            if matches!(
                e,
                BakeError::Option(_)
                    | BakeError::Resource(_)
                    | BakeError::Empty(..)
                    | BakeError::Unbounded
            ) {
                eprintln!("note: bench --bake bakes with sdfc bake's defaults, its --size, --layout, --texels and --bounds given as --atlas-size, --bake-layout, --bake-texels and --bake-bounds; for its other options (--grid, --refine, ...) run `sdfc bake`, whose report prints the same stage times");
            }
            return ExitCode::from(status(&e));
        }
    };
    print_report(&baked, &gpu, None);
    let r = &baked.report;
    let total: f64 = r.stages.iter().map(|(_, d)| d.as_secs_f64()).sum();
    let (name, slowest) = r
        .stages
        .iter()
        .max_by(|a, b| a.1.cmp(&b.1))
        .map(|(n, d)| (*n, d.as_secs_f64()))
        .unwrap_or(("none", 0.0));
    println!(
        "bake: {total:.3} s for a {}×{} atlas with {} levels; the slowest stage, {name}, is {:.0} % of it ({:.1} µs a level-0 sample in that stage)",
        baked.atlas.width(),
        baked.atlas.height(),
        baked.atlas.levels(),
        100.0 * slowest / total.max(1e-9),
        1e6 * slowest / r.samples.max(1) as f64
    );
    if let Some(path) = &args.json {
        let json = serde_json::json!({
            "bench": "bake",
            "scene": scene.display().to_string(),
            "adapter": gpu.describe(),
            "atlas": [baked.atlas.width(), baked.atlas.height()],
            "levels": baked.atlas.levels(),
            "samples": r.samples,
            "fit_samples": r.fit_samples,
            "estimated_peak_bytes": r.estimated_peak,
            "charts": r.charts,
            "refined_cells": r.refined,
            "refine": r.refine,
            "surface_missed": r.coverage.missed,
            "total_s": total,
            "stages": r.stages.iter().map(|(n, d)| serde_json::json!({
                "name": n,
                "s": d.as_secs_f64(),
            })).collect::<Vec<_>>(),
        });
        if let Err(code) = super::report::write_json(path, &json) {
            return code;
        }
    }
    ExitCode::SUCCESS
}

/// The glTF material's name: the scene's materials the baked shape paints, in the
/// order they are first painted, joined with `+` (the bake merges them into one
/// texture set); the scene's name when it paints none.
fn material_name(program: &sdfc::sema::Program, shape: &sdfc::ir::Shape, scene: &str) -> String {
    let mut names: Vec<&str> = Vec::new();
    for n in &shape.nodes {
        if let sdfc::ir::Op::Paint { material, .. } = n.op {
            let def = program.materials.get((material as usize).wrapping_sub(1));
            if let Some(m) = def.map(|m| m.name.as_str()) {
                if !names.contains(&m) {
                    names.push(m);
                }
            }
        }
    }
    if names.is_empty() {
        scene.to_string()
    } else {
        names.join("+")
    }
}
