//! `sdfc seeds`: automatic seeds and merges for an atlas ([`sdfc::uv::seeds`]), printed
//! as scene text or written into the scene file.

use super::{exit, read_source};
use sdfc::ide::seeds::{place_edit, statements};
use sdfc::uv::seeds::PlaceOptions;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(clap::Args)]
pub struct SeedsArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The atlas to fill (needed when the scene has more than one).
    #[arg(long)]
    pub atlas: Option<String>,
    /// The share of the surface (by area) that must end with status `ok`.
    #[arg(long, default_value = "0.995")]
    pub target_coverage: f64,
    /// The most seeds to place.
    #[arg(long, default_value_t = sdfc::uv::seeds::PlaceOptions::default().max_seeds)]
    pub max_seeds: usize,
    /// Surface samples: drawn uniformly by area on a grid of this many cells along the
    /// longest side (about two per cell-sized area).
    #[arg(long, default_value = "40")]
    pub grid: usize,
    /// Replace the atlas's seeds and merges in the file (atomically; the file is
    /// formatted) instead of printing them.
    #[arg(long)]
    pub write: bool,
    /// Keep the atlas's own seeds and merges and add seeds (and merges) only where
    /// the surface is still uncovered.
    #[arg(long)]
    pub keep: bool,
    /// The largest local stretch max(s1, 1/s2) wanted: where the placed atlas
    /// stretches more, seeds are added nearer (`inf`: place for coverage only).
    #[arg(long, default_value_t = sdfc::uv::seeds::DEFAULT_MAX_STRETCH)]
    pub max_stretch: f64,
}

/// "stretch (mean / 95th percentile): as written …, placed …" for the atlas `name`,
/// with a warning where the placed atlas misses the stretch target.
fn distortion(
    doc: &sdfc::ide::Document,
    name: &str,
    placement: &sdfc::uv::seeds::Placement,
    grid: usize,
    max_stretch: f64,
) -> Option<String> {
    let def = doc
        .analysis
        .program
        .atlases
        .iter()
        .find(|a| a.name == name)?;
    let shape = sdfc::ir::lower_shape(&def.shape)?;
    let samples = sdfc::reference::surface::surface_samples(&shape, grid).ok()?;
    let measure = |d: &sdfc::sema::AtlasDef| {
        let atlas = sdfc::uv::Atlas::prepare(d, &shape).ok()?;
        let (mean, p95, n) = sdfc::uv::seeds::stretch(&atlas, &samples);
        (n > 0).then(|| (format!("{mean:.3} / {p95:.3} over {n} samples"), p95))
    };
    let placed = sdfc::uv::seeds::with_seeds(def, &placement.seeds, &placement.merges);
    let written = if def.seeds.is_empty() {
        String::from("no seeds")
    } else {
        measure(def).map_or_else(|| String::from("not measurable"), |m| m.0)
    };
    let placed = measure(&placed);
    let mut out = format!(
        "stretch max(s1, 1/s2) (mean / 95th percentile): as written {written}; placed {}",
        placed
            .as_ref()
            .map_or_else(|| String::from("not measurable"), |m| m.0.clone())
    );
    if let Some((_, p95)) = placed.filter(|m| m.1 > max_stretch) {
        out.push_str(&format!(
            "\nwarning: the stretch target {max_stretch} is not reached (95th percentile {p95:.3}); try --max-seeds, or a larger --max-stretch"
        ));
    }
    Some(out)
}

pub fn run(args: SeedsArgs) -> ExitCode {
    let usage = |m: String| {
        eprintln!("error: {m}");
        ExitCode::from(exit::USAGE)
    };
    if !(args.target_coverage > 0.0 && args.target_coverage <= 1.0) {
        return usage(format!(
            "--target-coverage {} is not in (0, 1]",
            args.target_coverage
        ));
    }
    if !(1..=sdfc::sema::MAX_SEEDS).contains(&args.max_seeds) {
        return usage(format!(
            "--max-seeds {} is not between 1 and {}",
            args.max_seeds,
            sdfc::sema::MAX_SEEDS
        ));
    }
    if args.max_stretch.is_nan() || args.max_stretch <= 1.0 {
        return usage(format!(
            "--max-stretch {} is not above 1 (1 is an isometry; `inf` turns it off)",
            args.max_stretch
        ));
    }
    if !(4..=256).contains(&args.grid) {
        return usage(format!("--grid {} is not between 4 and 256", args.grid));
    }
    let name = args.scene.display().to_string();
    let source = match read_source(&args.scene) {
        Ok(s) if s.decoding.is_empty() => s.text,
        Ok(_) => return usage(format!("{name} is not UTF-8 text")),
        Err(e) => return usage(format!("cannot read {name}: {e}")),
    };
    let base = super::base_dir(&args.scene);
    let analysis = sdfc::driver::check(&source, Some(&base));
    // An atlas with no seed yet is an error for `check`, and what this command is for.
    let errors: Vec<_> = analysis
        .diagnostics
        .iter()
        .filter(|d| d.is_error() && d.code != sdfc::codes::E_NO_SEEDS)
        .cloned()
        .collect();
    if !errors.is_empty() {
        eprint!(
            "{}",
            sdfc::diagnostic::render(&name, &source, &errors, false)
        );
        return ExitCode::from(exit::SCENE);
    }
    let atlases = &analysis.program.atlases;
    let def = match (&args.atlas, atlases.len()) {
        (Some(a), _) => match atlases.iter().find(|d| &d.name == a) {
            Some(d) => d,
            None => return usage(format!("{name} has no atlas `{a}`")),
        },
        (None, 1) => &atlases[0],
        (None, 0) => return usage(format!("{name} has no atlas")),
        (None, _) => return usage(format!("{name} has several atlases: name one with --atlas")),
    };
    let atlas = def.name.clone();
    let started = Instant::now();
    let options = PlaceOptions {
        target: args.target_coverage,
        max_seeds: args.max_seeds,
        spacing: None,
        keep: args.keep,
        max_stretch: args.max_stretch.is_finite().then_some(args.max_stretch),
    };
    let doc = sdfc::ide::Document {
        text: source.clone(),
        analysis,
    };
    let (placement, edit) = match place_edit(&doc, &atlas, options, args.grid) {
        Ok(x) => x,
        Err(e) => return usage(e),
    };
    let took = started.elapsed();
    let (kept_seeds, kept_merges) = placement.kept;
    eprintln!(
        "atlas `{atlas}`: {} seeds ({kept_seeds} kept), {} merges ({kept_merges} kept), coverage {:.2} % of the surface by area (measured on samples drawn apart from placement's; {} failing), in {:.2} s",
        placement.seeds.len(),
        placement.merges.len(),
        100.0 * placement.coverage,
        placement.failing.len(),
        took.as_secs_f64()
    );
    if placement.coverage < args.target_coverage {
        let mut by: std::collections::BTreeMap<String, usize> = Default::default();
        for (_, s) in &placement.failing {
            *by.entry(format!("{s:?}")).or_default() += 1;
        }
        eprintln!(
            "warning: the target coverage {:.2} % is not reached; failing samples by status: {by:?} (thin regions or islands too small for a seed's walk; try --grid or the atlas's steps)",
            100.0 * args.target_coverage
        );
    }
    // The local stretch (`--view distortion`'s measure) of the atlas as written and as
    // placed, on the same samples.
    if let Some(report) = distortion(&doc, &atlas, &placement, args.grid, args.max_stretch) {
        eprintln!("{report}");
    }
    if !args.write {
        // The statements: all of them, or with --keep the added ones.
        let text = if args.keep {
            edit.text.trim_start_matches('\n').to_string()
        } else {
            statements(&placement)
        };
        print!("{text}");
        return ExitCode::SUCCESS;
    }
    let edited = format!(
        "{}{}{}",
        &source[..edit.span.start],
        edit.text,
        &source[edit.span.end..]
    );
    let formatted = sdfc::ide::format::format(&edited).unwrap_or(edited);
    let check = sdfc::driver::check(&formatted, Some(&base));
    // Other atlases may still be waiting for their seeds (E0115), as they
    // were before; this atlas now has some.
    if check
        .diagnostics
        .iter()
        .any(|d| d.is_error() && d.code != sdfc::codes::E_NO_SEEDS)
    {
        eprint!(
            "{}",
            sdfc::diagnostic::render(&name, &formatted, &check.diagnostics, false)
        );
        eprintln!("error: the placed seeds do not check; {name} was not changed");
        return ExitCode::from(exit::SCENE);
    }
    if let Err(e) = sdfc::fsutil::write_output(&args.scene, formatted.as_bytes()) {
        return usage(format!("cannot write {name}: {e}"));
    }
    eprintln!("wrote {name}");
    ExitCode::SUCCESS
}
