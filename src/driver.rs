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
