//! The files a served scene is built from, watched (notify: inotify on Linux): the
//! folders that hold them are watched, and a change to one of the files (not to its
//! neighbours) sends a message. Editors that save by renaming a new file over the old
//! one are seen too, as the folder is watched rather than the file.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};

/// Watches a set of files, which may change.
pub struct Watch {
    watcher: notify::RecommendedWatcher,
    dirs: BTreeSet<PathBuf>,
    files: Arc<Mutex<BTreeSet<PathBuf>>>,
}

impl Watch {
    /// Starts watching nothing; each change to a watched file sends `()` on `tx`.
    pub fn new(tx: Sender<()>) -> Result<Watch, String> {
        let files: Arc<Mutex<BTreeSet<PathBuf>>> = Arc::default();
        let seen = files.clone();
        let handler = move |event: notify::Result<notify::Event>| {
            let Ok(event) = event else { return };
            if matches!(event.kind, notify::EventKind::Access(_)) {
                return;
            }
            let files = seen.lock().unwrap_or_else(|e| e.into_inner());
            if event.paths.iter().any(|p| files.contains(p)) {
                let _ = tx.send(());
            }
        };
        let watcher = notify::recommended_watcher(handler).map_err(|e| e.to_string())?;
        Ok(Watch {
            watcher,
            dirs: BTreeSet::new(),
            files,
        })
    }

    /// Watches exactly `paths` (made canonical where they exist); the folders that
    /// could not be watched, with why.
    pub fn set(&mut self, paths: &[PathBuf]) -> Vec<String> {
        use notify::Watcher;
        let files: BTreeSet<PathBuf> = paths.iter().map(|p| canonical(p)).collect();
        let dirs: BTreeSet<PathBuf> = files
            .iter()
            .filter_map(|f| f.parent().map(Path::to_path_buf))
            .collect();
        let mut problems = Vec::new();
        for gone in self.dirs.difference(&dirs) {
            let _ = self.watcher.unwatch(gone);
        }
        for new in dirs.difference(&self.dirs) {
            if let Err(e) = self.watcher.watch(new, notify::RecursiveMode::NonRecursive) {
                problems.push(format!("cannot watch {}: {e}", new.display()));
            }
        }
        self.dirs = dirs;
        *self.files.lock().unwrap_or_else(|e| e.into_inner()) = files;
        problems
    }
}

/// The path with its folder made canonical (the file itself may be missing for a
/// moment while an editor replaces it).
fn canonical(path: &Path) -> PathBuf {
    if let Ok(p) = std::fs::canonicalize(path) {
        return p;
    }
    match (path.parent(), path.file_name()) {
        (Some(dir), Some(name)) => {
            let dir = if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            };
            std::fs::canonicalize(dir)
                .map(|d| d.join(name))
                .unwrap_or_else(|_| path.to_path_buf())
        }
        _ => path.to_path_buf(),
    }
}
