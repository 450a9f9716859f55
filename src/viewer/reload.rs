//! Hot reload as a state machine, free of windows and GPUs: the scene's text goes in,
//! and the viewer keeps the last version that built (its analysis, module and
//! pipeline) until a newer one builds too.
//!
//! - good → bad (the file has errors, or its pipeline fails to build): the last good
//!   scene stays on screen, the diagnostics are kept for the terminal, and the window
//!   is marked stale;
//! - bad → good: the new pipeline replaces the old one and the stale mark goes;
//! - the same text again (an editor saving without changes, the viewer's own write
//!   coming back through the file watcher): nothing, unless textures changed.

use crate::access::Access;
use crate::codegen;
use crate::diagnostic;
use crate::driver::Compiled;
use crate::driver::{self, CompileError};
use crate::ide::Document;
use std::time::{Duration, Instant};

/// The version on screen: the text it came from, its analysis (for picking and seed
/// edits), its module and its pipeline.
pub struct Loaded<P> {
    pub doc: Document,
    pub compiled: Compiled,
    pub pipeline: P,
    /// Source to validated WGSL.
    pub compile_time: Duration,
}

/// What a reload did.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The text is the one on screen (or the one that failed last): nothing to do.
    Unchanged,
    /// The new version replaced the one on screen.
    Swapped,
    /// The new version does not build; the last good one stays. The report is what
    /// `sdfc check` prints for it (or the pipeline's error).
    Failed(String),
}

pub struct Reloader<P> {
    /// The file's name in reports.
    name: String,
    access: Access,
    /// The `let` shape shown instead of the render item's target (`--shape`).
    shape: Option<String>,
    pub(super) options: codegen::Options,
    pub good: Option<Loaded<P>>,
    /// The report of the file as it is, while it does not build: the window is stale.
    pub stale: Option<String>,
    /// The text of the last reload, built or not.
    last: Option<String>,
}

impl<P> Reloader<P> {
    pub fn new(
        name: impl Into<String>,
        access: Access,
        shape: Option<String>,
        options: codegen::Options,
    ) -> Self {
        Reloader {
            name: name.into(),
            access,
            shape,
            options,
            good: None,
            stale: None,
            last: None,
        }
    }

    /// Loads `text`, building its pipeline with `build` when it compiles. `force`
    /// reloads the same text again (a texture changed on disk).
    pub fn reload(
        &mut self,
        text: &str,
        force: bool,
        build: impl FnOnce(&Compiled) -> Result<P, String>,
    ) -> Outcome {
        if !force && self.last.as_deref() == Some(text) {
            return Outcome::Unchanged;
        }
        self.last = Some(text.to_string());
        let started = Instant::now();
        let mut analysis = driver::check_with(text, &self.access);
        diagnostic::cap(&mut analysis.diagnostics);
        let compiled = if analysis.has_errors() {
            Err(diagnostic::render(
                &self.name,
                text,
                &analysis.diagnostics,
                false,
            ))
        } else {
            driver::compile_shape(&analysis, self.shape.as_deref(), &self.options).map_err(|e| {
                match e {
                    CompileError::Scene(d) => diagnostic::render(&self.name, text, &d, false),
                    CompileError::Usage(m) => format!("error: {m}\n"),
                    CompileError::Internal {
                        diagnostic, naga, ..
                    } => format!(
                        "{}{naga}\n",
                        diagnostic::render(&self.name, text, &[*diagnostic], false)
                    ),
                }
            })
        };
        let compile_time = started.elapsed();
        let built = compiled.and_then(|c| match build(&c) {
            Ok(p) => Ok((c, p)),
            Err(e) => Err(format!("error: the pipeline did not build: {e}\n")),
        });
        match built {
            Ok((compiled, pipeline)) => {
                self.good = Some(Loaded {
                    doc: Document {
                        text: text.to_string(),
                        analysis,
                    },
                    compiled,
                    pipeline,
                    compile_time,
                });
                self.stale = None;
                Outcome::Swapped
            }
            Err(report) => {
                self.stale = Some(report.clone());
                Outcome::Failed(report)
            }
        }
    }

    /// Whether the scene on screen is the file as it is (edits are made on it only then).
    pub fn current(&self) -> Option<&Loaded<P>> {
        match self.stale {
            None => self.good.as_ref(),
            Some(_) => None,
        }
    }
}
