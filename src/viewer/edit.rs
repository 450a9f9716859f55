//! The viewer's seed edits on the scene file: [`crate::ide::seed_edit`]'s text edits,
//! checked, written atomically (an editor with the file open reloads it cleanly), and
//! undone in reverse order.

use crate::access::Access;
use crate::diagnostic::{self, Edit};
use crate::fsutil::write_output;
use crate::ide::seed_edit::{checked, Checked};
use crate::ide::Document;
use std::path::{Path, PathBuf};

/// One edit the viewer made: the file before and after.
#[derive(Debug, Clone)]
struct Made {
    what: String,
    before: String,
    after: String,
}

pub struct SeedEditor {
    path: PathBuf,
    /// The files the scene may read (its folder and `--allow` ones), as the viewer's.
    access: Access,
    undo: Vec<Made>,
}

impl SeedEditor {
    pub fn new(path: &Path, access: Access) -> SeedEditor {
        SeedEditor {
            path: path.to_path_buf(),
            access,
            undo: Vec::new(),
        }
    }

    fn read(&self) -> Result<String, String> {
        std::fs::read_to_string(&self.path)
            .map_err(|e| format!("cannot read {}: {e}", self.path.display()))
    }

    /// Applies `edits` (made on `doc`, the scene on screen) to the file, when the result
    /// checks (and with `strict`, when it brings no new warning). Returns
    /// the new text, or the report of why not: the diagnostics as `sdfc check` prints
    /// them.
    pub fn apply(
        &mut self,
        what: &str,
        doc: &Document,
        edits: Result<Vec<Edit>, String>,
        strict: bool,
    ) -> Result<String, String> {
        let edits = edits.map_err(|e| format!("{what}: refused: {e}"))?;
        let on_disk = self.read()?;
        if on_disk != doc.text {
            return Err(format!(
                "{what}: refused: {} changed since it was loaded; try again after the reload",
                self.path.display()
            ));
        }
        match checked(doc, &edits, &self.access, strict) {
            Checked::Accepted { text, .. } => {
                write_output(&self.path, text.as_bytes())
                    .map_err(|e| format!("{what}: cannot write {}: {e}", self.path.display()))?;
                self.undo.push(Made {
                    what: what.to_string(),
                    before: doc.text.clone(),
                    after: text.clone(),
                });
                Ok(text)
            }
            Checked::Refused {
                text,
                reason,
                diagnostics,
            } => Err(format!(
                "{}{what}: refused: {reason}; {} was not changed",
                diagnostic::render(&self.path.display().to_string(), &text, &diagnostics, false),
                self.path.display()
            )),
        }
    }

    /// Reverts the last edit the viewer made, when the file is still as that edit left
    /// it. Returns the restored text and what was undone.
    pub fn undo(&mut self) -> Result<(String, String), String> {
        let Some(last) = self.undo.last().cloned() else {
            return Err(String::from("nothing to undo"));
        };
        // Popped only once the file is restored: an I/O error leaves it to try again.
        let on_disk = self.read()?;
        if on_disk != last.after {
            // Someone else edited the file since: undoing would lose their change.
            self.undo.clear();
            return Err(format!(
                "cannot undo `{}`: {} changed since the viewer edited it (undo in the editor)",
                last.what,
                self.path.display()
            ));
        }
        write_output(&self.path, last.before.as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", self.path.display()))?;
        self.undo.pop();
        Ok((last.before, last.what))
    }

    /// How many edits can be undone.
    pub fn depth(&self) -> usize {
        self.undo.len()
    }
}
