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
    }
}
