//! What `sdfc serve` serves, rebuilt from the scene file: the page's files in memory
//! (the ones `sdfc export-web` writes), and the state the page's event stream reports:
//! a generation counter of good builds, and the diagnostics of the file as it is while
//! it does not build. A build that fails keeps the last good files.

use crate::access::Access;
use crate::codegen;
use crate::diagnostic;
use crate::driver::{self, CompileError};
use crate::ir::texture::Textures;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// What a scene is built from: its file, what it may read, and the module's options.
#[derive(Debug, Clone)]
pub struct Source {
    /// The scene file.
    pub scene: PathBuf,
    /// The folders the scene may read textures from.
    pub access: Access,
    /// The `let` shape shown instead of the `render` item's target.
    pub shape: Option<String>,
    /// The module's options (the loop walk by default, as for `export-web`).
    pub options: codegen::Options,
}

/// A good build: the page's files by path (`scene.wgsl`, `textures/0/0.png`, …), the
/// warnings as `sdfc check` prints them, and the texture files it read.
#[derive(Debug, Clone, PartialEq)]
pub struct Built {
    /// The page's files, by their path below the page.
    pub files: HashMap<String, Vec<u8>>,
    /// The warnings, rendered without colour; empty when there are none.
    pub warnings: String,
    /// The texture files read, as resolved.
    pub textures: Vec<PathBuf>,
}

/// A failed build: the report as the command line prints it (without colour), and the
/// diagnostics as JSON objects (`sdfc check --format json`).
#[derive(Debug, Clone, PartialEq)]
pub struct Failed {
    /// The report.
    pub text: String,
    /// One object per diagnostic (empty for a failure that is not one, as an unreadable
    /// file or a texture that does not decode).
    pub diagnostics: Vec<serde_json::Value>,
    /// The texture files the scene resolved (to watch for a fix).
    pub textures: Vec<PathBuf>,
}

/// The page's title: the scene file's name without its extension.
pub fn title(scene: &Path) -> String {
    scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| String::from("scene"))
}

/// Reads, checks and compiles the scene, and makes the page's files.
pub fn build(source: &Source) -> Result<Built, Failed> {
    let name = source
        .scene
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let plain = |text: String| Failed {
        text,
        diagnostics: Vec::new(),
        textures: Vec::new(),
    };
    let bytes = read_limited(&source.scene, crate::syntax::MAX_SOURCE_BYTES)
        .map_err(|e| plain(format!("error: cannot read {name}: {e}\n")))?;
    let (text, decoding) = crate::syntax::decode(&bytes);
    let mut analysis = driver::check_with(&text, &source.access);
    analysis.add_decoding(decoding);
    diagnostic::cap(&mut analysis.diagnostics);
    let textures: Vec<PathBuf> = analysis
        .program
        .textures
        .iter()
        .filter_map(|t| t.resolved.clone())
        .collect();
    let failed = |diags: &[diagnostic::Diagnostic], extra: &str| Failed {
        text: format!("{}{extra}", diagnostic::render(&name, &text, diags, false)),
        diagnostics: diagnostic::to_json_all(&name, &text, diags)
            .iter()
            .filter_map(|j| serde_json::from_str(j).ok())
            .collect(),
        textures: textures.clone(),
    };
    if analysis.has_errors() {
        return Err(failed(&analysis.diagnostics, ""));
    }
    let mut compiled = driver::compile_shape(&analysis, source.shape.as_deref(), &source.options)
        .map_err(|e| match e {
        CompileError::Scene(d) => failed(&d, ""),
        CompileError::Usage(m) => plain(format!("error: {m}\n")),
        CompileError::Internal {
            diagnostic, naga, ..
        } => failed(&[*diagnostic], &format!("{naga}\n")),
    })?;
    compiled.module.manifest.scene = crate::gpu::scene_values(&analysis, source.shape.as_deref());
    let decoded = Textures::load(&analysis.program).map_err(|e| Failed {
        text: format!("error: {e}\n"),
        diagnostics: Vec::new(),
        textures: textures.clone(),
    })?;
    let files = super::super::files(&title(&source.scene), &compiled.module, &decoded)
        .map_err(|e| plain(format!("error: {e}\n")))?;
    let files = files
        .into_iter()
        .map(|(p, b)| (p.to_string_lossy().replace('\\', "/"), b))
        .collect();
    let mut warnings = if analysis.diagnostics.is_empty() {
        String::new()
    } else {
        diagnostic::render(&name, &text, &analysis.diagnostics, false)
    };
    for w in super::super::warnings(&compiled.module) {
        warnings += &format!("warning: {w}\n");
    }
    Ok(Built {
        files,
        warnings,
        textures,
    })
}

/// Reads at most `limit` bytes of a regular file; a longer file is an error.
fn read_limited(path: &Path, limit: usize) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    if !std::fs::metadata(path)?.is_file() {
        return Err(std::io::Error::other("it is not a file"));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(limit as u64 + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() > limit {
        return Err(std::io::Error::other(format!(
            "it is larger than the limit of {limit} bytes"
        )));
    }
    Ok(bytes)
}

/// A good build's files by path, shared with the connections that serve them.
pub type Files = Arc<HashMap<String, Vec<u8>>>;

/// The state the server shares between the builder and the connections.
#[derive(Debug, Default)]
pub struct State {
    /// Bumped on every change the page should hear of.
    pub version: u64,
    /// The number of good builds so far (the page's `sdfcGeneration`).
    pub generation: u64,
    /// The last good build's files, if any.
    pub files: Option<Files>,
    /// The last good build's warnings.
    pub warnings: String,
    /// The file as it is, while it does not build.
    pub failed: Option<Failed>,
}

impl State {
    /// The event the page hears for this state: `scene` (a good build to show, with its
    /// generation and warnings) or `diagnostics` (the file as it is does not build; the
    /// page keeps the last good generation). One line of JSON as its data.
    pub fn event(&self) -> String {
        let (name, data) = match &self.failed {
            Some(f) => (
                "diagnostics",
                serde_json::json!({
                    "generation": self.generation,
                    "text": f.text,
                    "diagnostics": f.diagnostics,
                }),
            ),
            None => (
                "scene",
                serde_json::json!({ "generation": self.generation, "warnings": self.warnings }),
            ),
        };
        format!("event: {name}\ndata: {data}\n\n")
    }

    /// Takes a build's outcome; whether the page should hear of it (a build equal to
    /// the one served, or a failure equal to the one reported, changes nothing).
    pub fn publish(&mut self, outcome: Result<Built, Failed>) -> bool {
        match outcome {
            Ok(built) => {
                let same = self.failed.is_none()
                    && self.files.as_deref() == Some(&built.files)
                    && self.warnings == built.warnings;
                if same {
                    return false;
                }
                self.generation += 1;
                self.files = Some(Arc::new(built.files));
                self.warnings = built.warnings;
                self.failed = None;
            }
            Err(f) => {
                if self.failed.as_ref() == Some(&f) {
                    return false;
                }
                self.failed = Some(f);
            }
        }
        self.version += 1;
        true
    }
}

/// [`State`] behind a lock, with a condition variable the event streams wait on.
#[derive(Debug, Default)]
pub struct Shared {
    /// The state.
    pub state: Mutex<State>,
    /// Notified after each published change.
    pub changed: Condvar,
}

impl Shared {
    /// Publishes a build's outcome and wakes the event streams when it changed
    /// something; whether it did.
    pub fn publish(&self, outcome: Result<Built, Failed>) -> bool {
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let changed = state.publish(outcome);
        if changed {
            self.changed.notify_all();
        }
        changed
    }

    /// Waits up to `timeout` for a version other than `seen`: the new version and its
    /// event, or None on a timeout.
    pub fn wait(&self, seen: Option<u64>, timeout: Duration) -> Option<(u64, String)> {
        let state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let (state, _) = self
            .changed
            .wait_timeout_while(state, timeout, |s| Some(s.version) == seen)
            .unwrap_or_else(|e| e.into_inner());
        (Some(state.version) != seen).then(|| (state.version, state.event()))
    }

    /// The last good build's files and its generation.
    pub fn files(&self) -> (u64, Option<Files>) {
        let state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        (state.generation, state.files.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn built(wgsl: &str) -> Built {
        Built {
            files: HashMap::from([("scene.wgsl".to_string(), wgsl.as_bytes().to_vec())]),
            warnings: String::new(),
            textures: Vec::new(),
        }
    }

    fn failed(text: &str) -> Failed {
        Failed {
            text: text.into(),
            diagnostics: vec![serde_json::json!({"code": "E0001"})],
            textures: Vec::new(),
        }
    }

    #[test]
    fn a_failure_keeps_the_last_good_files_and_generation() {
        let mut s = State::default();
        assert!(s.publish(Ok(built("a"))));
        assert_eq!((s.generation, s.version), (1, 1));
        assert!(s.event().starts_with("event: scene\ndata: {"));
        // The same build again: nothing to tell.
        assert!(!s.publish(Ok(built("a"))));
        assert!(s.publish(Err(failed("error[E0001]"))));
        assert_eq!((s.generation, s.version), (1, 2));
        assert_eq!(s.files.as_ref().unwrap()["scene.wgsl"], b"a");
        let event = s.event();
        assert!(event.starts_with("event: diagnostics\ndata: {"), "{event}");
        assert!(event.contains("E0001") && event.ends_with("}\n\n"));
        assert!(!s.publish(Err(failed("error[E0001]"))));
        // The fix, even back to the same files, is a new generation (the page cleared
        // nothing yet: it must hear that the errors are gone).
        assert!(s.publish(Ok(built("a"))));
        assert_eq!((s.generation, s.version), (2, 3));
        assert!(s.publish(Ok(built("b"))));
        assert_eq!(s.generation, 3);
    }

    #[test]
    fn waiting_returns_a_newer_version_or_times_out() {
        let shared = Shared::default();
        assert!(shared.wait(Some(0), Duration::from_millis(10)).is_none());
        let (v, event) = shared.wait(None, Duration::from_millis(10)).unwrap();
        assert_eq!(v, 0);
        assert!(event.starts_with("event: scene"));
        shared.publish(Err(failed("x")));
        let (v, event) = shared.wait(Some(0), Duration::from_millis(10)).unwrap();
        assert_eq!(v, 1);
        assert!(event.starts_with("event: diagnostics"));
    }
}
