//! The front end as one call: text → tokens → AST → checked program, with diagnostics.

use crate::diagnostic::{self, Diagnostic};
use crate::sema::{self, Program};
use crate::syntax::{self, Parsed};
use std::path::Path;

/// Everything the front end knows about one document.
#[derive(Debug, Clone)]
pub struct Analysis {
    pub parsed: Parsed,
    pub program: Program,
    /// Every diagnostic, sorted by position.
    pub diagnostics: Vec<Diagnostic>,
    /// The prepared atlases (projected seeds, solved merge graphs), one per atlas of the
    /// program, when [`check`] ran the geometric analysis (None where one failed).
    pub atlases: Vec<Option<crate::uv::Atlas>>,
}

impl Analysis {
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// Parses and checks a scene. `base_dir` is the folder of the scene file, for texture paths.
pub fn analyze(source: &str, base_dir: Option<&Path>) -> Analysis {
    let mut diagnostics = Vec::new();
    let parsed = syntax::parse(source, &mut diagnostics);
    let program = sema::check(&parsed.file, base_dir, &mut diagnostics);
    diagnostic::sort(&mut diagnostics);
    Analysis {
        parsed,
        program,
        diagnostics,
        atlases: Vec::new(),
    }
}

/// The whole check, as `sdfc check` and the language server run it: the front end and,
/// when it finds no errors, the compile-time geometry of the atlases (seed projection,
/// merge walks, frame and offset solves, obstruction tests) with its diagnostics.
pub fn check(source: &str, base_dir: Option<&Path>) -> Analysis {
    let mut analysis = analyze(source, base_dir);
    if !analysis.has_errors() {
        let (atlases, diags) = crate::uv::diagnose::prepare_all(&analysis.program);
        analysis.atlases = atlases;
        analysis.diagnostics.extend(diags);
        diagnostic::sort(&mut analysis.diagnostics);
    }
    analysis
}

/// [`check`] and, when it finds no errors, code generation and naga validation, as
/// `sdfc check` and the language server run them: everything the compiler would report.
pub fn check_all(source: &str, base_dir: Option<&Path>) -> Analysis {
    let mut analysis = check(source, base_dir);
    let more = codegen_diagnostics(&analysis);
    if !more.is_empty() {
        analysis.diagnostics.extend(more);
        diagnostic::sort(&mut analysis.diagnostics);
    }
    analysis
}

/// Code generation and naga validation of a scene [`check`] found no errors in. Where
/// naga rejects the module (an internal compiler error), the diagnostic is on the scene
/// definition that produced the rejected code.
pub fn codegen_diagnostics(analysis: &Analysis) -> Vec<Diagnostic> {
    codegen_diagnostics_with(analysis, |_| {})
}

/// [`codegen_diagnostics`] with a hook that may alter the module before validation (for
/// the tests of the internal-error path).
pub fn codegen_diagnostics_with(
    analysis: &Analysis,
    tamper: impl FnOnce(&mut crate::codegen::Module),
) -> Vec<Diagnostic> {
    use crate::codegen;
    if analysis.has_errors() {
        return Vec::new();
    }
    let scene = crate::ir::lower(&analysis.program);
    // A file of shapes with no render item (a library) is generated for its first shape.
    let shape = match (&analysis.program.render, scene.shapes.first()) {
        (Some(_), _) => None,
        (None, Some(first)) => Some(first.name.clone()),
        (None, None) => return Vec::new(),
    };
    let options = codegen::Options {
        shape,
        ..Default::default()
    };
    let prepared = (analysis.atlases.len() == analysis.program.atlases.len())
        .then_some(analysis.atlases.as_slice());
    match codegen::generate_prepared(&analysis.program, &scene, &options, prepared) {
        Err(diags) => diags,
        Ok(mut module) => {
            tamper(&mut module);
            match codegen::validate(&module.wgsl) {
                Ok(_) => Vec::new(),
                Err(e) => vec![module.internal_error(&e)],
            }
        }
    }
}
