//! `sdfc compile`: a scene → one validated, compacted shader module (WGSL, SPIR-V,
//! GLSL or MSL).

use super::{load, CompileArgs};
use sdfc::codegen::{self, targets::Output, Target};
use sdfc::driver::{self, Analysis, CompileError, Compiled};
use sdfc::fsutil::write_output;
use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

/// Reads, checks and compiles a scene through the driver; problems are printed and
/// come back as the exit status.
pub fn build(
    path: &Path,
    shape: Option<&str>,
    options: &codegen::Options,
) -> Result<(String, Analysis, Compiled), ExitCode> {
    let (source, analysis) = load(path)?;
    let name = path.display().to_string();
    let compiled =
        driver::compile_shape(&analysis, shape, options).map_err(|e| report(&name, &source, e))?;
    Ok((source, analysis, compiled))
}

/// Prints why [`driver::compile`] made no module, and gives the exit status: 1 for the
/// scene's errors, 2 for a usage error, 3 for an internal compiler error (the WGSL is
/// saved for the bug report, under one name per scene).
pub fn report(name: &str, source: &str, error: CompileError) -> ExitCode {
    match error {
        CompileError::Scene(diags) => {
            eprint!("{}", sdfc::diagnostic::render(name, source, &diags, false));
            ExitCode::from(super::exit::SCENE)
        }
        CompileError::Usage(message) => {
            eprintln!("error: {message}");
            ExitCode::from(super::exit::USAGE)
        }
        CompileError::Internal {
            diagnostic,
            naga,
            module,
        } => {
            // The error on the scene definition that produced the rejected code, then
            // naga's own report on the WGSL.
            eprint!(
                "{}",
                sdfc::diagnostic::render(name, source, &[*diagnostic], false)
            );
            eprintln!("{naga}");
            save_for_report(name, &module.wgsl);
            ExitCode::from(super::exit::ICE)
        }
    }
}

/// Saves the WGSL of an internal compiler error as `sdfc-ice-STEM.wgsl` in the temporary
/// folder (one file per scene, replaced by the next report) and says where.
pub(super) fn save_for_report(name: &str, wgsl: &str) {
    let stem = Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .filter(|s| !s.is_empty() && *s != "-")
        .unwrap_or("stdin");
    let stem: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let path = std::env::temp_dir().join(format!("sdfc-ice-{stem}.wgsl"));
    // Not write_output: the name is predictable in a shared folder, so a link there is
    // replaced, never followed.
    if sdfc::fsutil::replace_file(&path, wgsl.as_bytes()).is_ok() {
        eprintln!(
            "note: the generated WGSL is saved at {}; please attach it to a bug report",
            path.display()
        );
    }
}

pub fn run(args: CompileArgs) -> ExitCode {
    let options = codegen::Options {
        walk: args.walk,
        seed_grid: args.seed_grid,
        atlas: args.atlas.clone(),
        plain: false,
        cold: false,
        constant_uv: false,
        unions_as_code: args.unions_as_code,
        prune: args.prune,
        seed_data: args.seed_data,
        bounds: args.bounds,
        differences: false,
        tiles: false,
        multiscale: args.multiscale,
    };
    let coarse = args.multiscale && args.entry == "cs_coarse";
    if args.target == Target::Glsl
        && !coarse
        && !codegen::ENTRY_POINTS.iter().any(|(e, _)| *e == args.entry)
    {
        let names = codegen::ENTRY_POINTS.iter().map(|(e, _)| *e);
        eprintln!(
            "error: the module has no entry point `{}`; {}",
            args.entry,
            driver::suggest(&args.entry, names)
        );
        return ExitCode::from(super::exit::USAGE);
    }
    let (_, analysis, mut compiled) = match build(&args.scene, args.shape.as_deref(), &options) {
        Ok(x) => x,
        Err(code) => return code,
    };
    // Users get only what their scene uses: the library's unused functions are already
    // gone (codegen::shake), so WGSL is the very text naga validated, and the other
    // targets are written from the validated module, compacted.
    let output = match args.target {
        Target::Wgsl => Ok(Output::Text(compiled.module.wgsl.clone())),
        _ => codegen::compact(&compiled.validated).and_then(|compact| {
            codegen::translate(&compact, &compiled.module.header, args.target, &args.entry)
        }),
    };
    let output = match output {
        Ok(o) => o,
        Err(e) => {
            eprintln!(
                "error[{}]: internal compiler error: naga could not write {:?}: {e}",
                sdfc::codes::E_INTERNAL,
                args.target
            );
            save_for_report(&args.scene.display().to_string(), &compiled.module.wgsl);
            return ExitCode::from(super::exit::ICE);
        }
    };
    let bytes = match output {
        Output::Text(t) => t.into_bytes(),
        Output::Binary(b) => b,
    };
    let words = compiled.module.manifest.tables.len();
    if words > 0 && args.manifest.is_none() {
        eprintln!(
            "note: the module reads the `tables` storage buffer ({words} words: seed grids, the multi-scale pass's merged seeds, large unions); `--manifest FILE` writes its contents"
        );
    }
    if let Some(path) = &args.manifest {
        // The scene's own values: its view's globals (as `sdfc render` uploads them, in
        // the colour view) and the rendered shape's bounds.
        compiled.module.manifest.scene = sdfc::gpu::scene_values(&analysis, args.shape.as_deref());
        let json = serde_json::to_string_pretty(&compiled.module.manifest).unwrap_or_default();
        if let Err(e) = write_output(path, json.as_bytes()) {
            eprintln!("error: cannot write {}: {e}", path.display());
            return ExitCode::from(super::exit::USAGE);
        }
    }
    match &args.output {
        Some(path) => {
            if let Err(e) = write_output(path, &bytes) {
                eprintln!("error: cannot write {}: {e}", path.display());
                return ExitCode::from(super::exit::USAGE);
            }
        }
        None if args.target == Target::Spirv => {
            eprintln!("error: SPIR-V is binary; write it to a file with -o");
            return ExitCode::from(super::exit::USAGE);
        }
        None => {
            if std::io::stdout().write_all(&bytes).is_err() {
                return ExitCode::from(super::exit::USAGE);
            }
        }
    }
    ExitCode::SUCCESS
}
