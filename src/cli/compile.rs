//! `sdfc compile`: a scene → one validated shader module (WGSL, SPIR-V, GLSL or MSL).

use super::{load, CompileArgs};
use sdfc::codegen::{self, targets::Output, Target};
use sdfc::fsutil::write_atomic;
use sdfc::ir;
use std::io::Write;
use std::process::ExitCode;

/// Exit status for an internal compiler error.
pub const ICE_EXIT: u8 = 3;

/// Generates and validates a module; on an internal compiler error, saves the WGSL
/// for the bug report and says where.
pub fn build(
    args_scene: &std::path::Path,
    options: &codegen::Options,
) -> Result<(codegen::Module, codegen::Validated), ExitCode> {
    let (source, analysis) = load(args_scene)?;
    build_checked(
        &args_scene.display().to_string(),
        &source,
        &analysis,
        options,
    )
}

/// [`build`] for a scene already read and checked (with no errors).
pub fn build_checked(
    name: &str,
    source: &str,
    analysis: &sdfc::driver::Analysis,
    options: &codegen::Options,
) -> Result<(codegen::Module, codegen::Validated), ExitCode> {
    let scene = ir::lower(&analysis.program);
    let prepared = (analysis.atlases.len() == analysis.program.atlases.len())
        .then_some(analysis.atlases.as_slice());
    let module = codegen::generate_prepared(&analysis.program, &scene, options, prepared).map_err(
        |diags| {
            eprint!("{}", sdfc::diagnostic::render(name, source, &diags, false));
            ExitCode::from(1)
        },
    )?;
    // Test hook: corrupts the module so that the internal-compiler-error path can be tested
    // end to end (tests/codegen.rs). Never set outside tests. `material` breaks the code
    // of the first material; anything else appends a broken function.
    let mut module = module;
    match std::env::var("SDFC_TEST_CORRUPT_WGSL").as_deref() {
        Ok("material") => module.corrupt_first_material(),
        Ok(_) => module.wgsl.push_str("\nfn corrupted( {\n"),
        Err(_) => {}
    }
    match codegen::validate(&module.wgsl) {
        Ok(v) => Ok((module, v)),
        Err(e) => {
            let path = std::env::temp_dir().join(format!("sdfc-ice-{}.wgsl", std::process::id()));
            let saved = write_atomic(&path, module.wgsl.as_bytes()).is_ok();
            // The error on the scene definition that produced the rejected code, then
            // naga's own report on the WGSL.
            eprint!(
                "{}",
                sdfc::diagnostic::render(name, source, &[module.internal_error(&e)], false)
            );
            eprintln!("{e}");
            if saved {
                eprintln!(
                    "note: the generated WGSL is saved at {}; please attach it to a bug report",
                    path.display()
                );
            }
            Err(ExitCode::from(ICE_EXIT))
        }
    }
}

pub fn run(args: CompileArgs) -> ExitCode {
    let options = codegen::Options {
        shape: args.shape.clone(),
        walk: args.walk,
        seed_grid: args.seed_grid,
        atlas: args.atlas.clone(),
        plain: false,
    };
    let (module, validated) = match build(&args.scene, &options) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let output = match codegen::translate(&validated, &module.wgsl, args.target, &args.entry) {
        Ok(o) => o,
        Err(e) => {
            eprintln!(
                "error[{}]: internal compiler error: naga could not translate to {:?}: {e}",
                sdfc::codes::E_INTERNAL,
                args.target
            );
            return ExitCode::from(ICE_EXIT);
        }
    };
    let bytes = match output {
        Output::Text(t) => t.into_bytes(),
        Output::Binary(b) => b,
    };
    if let Some(path) = &args.manifest {
        let json = serde_json::to_string_pretty(&module.manifest).unwrap_or_default();
        if let Err(e) = write_atomic(path, json.as_bytes()) {
            eprintln!("error: cannot write {}: {e}", path.display());
            return ExitCode::from(2);
        }
    }
    match &args.output {
        Some(path) => {
            if let Err(e) = write_atomic(path, &bytes) {
                eprintln!("error: cannot write {}: {e}", path.display());
                return ExitCode::from(2);
            }
        }
        None if args.target == Target::Spirv => {
            eprintln!("error: SPIR-V is binary; write it to a file with -o");
            return ExitCode::from(2);
        }
        None => {
            if std::io::stdout().write_all(&bytes).is_err() {
                return ExitCode::from(2);
            }
        }
    }
    ExitCode::SUCCESS
}
