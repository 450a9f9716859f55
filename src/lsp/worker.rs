//! Analyses run on a worker thread, so the server keeps answering while a large
//! document is being checked. The worker takes the latest text of each document that
//! changed (older texts queued behind a newer one are skipped) and analyses it in two
//! stages, each sent back as it finishes: the front end (parse, names, types: the
//! diagnostics most edits change, in milliseconds), then the back end (the atlases'
//! geometry, lowering, code generation and naga), which a newer text of the same
//! document queued meanwhile cancels. An edit of comments and whitespace only skips
//! the back end: the last full analysis's is carried over ([`crate::incremental`]). A
//! panic inside an analysis comes back as its message.

use super::{open, Open, Stage};
use crate::diagnostic::Diagnostic;
use crossbeam_channel::{unbounded, Receiver, Sender};
use lsp_types as lsp;
use std::collections::HashMap;
use std::path::PathBuf;

/// A document text to analyse.
pub(super) struct Job {
    pub uri: lsp::Uri,
    pub text: String,
    pub version: i32,
    pub roots: Vec<PathBuf>,
}

/// A finished analysis: the document, or the message of the panic that ended it.
pub(super) struct Done {
    pub uri: lsp::Uri,
    pub version: i32,
    pub result: Result<Open, String>,
    /// The front end's stage: the back end's follows (unless cancelled).
    pub partial: bool,
}

/// Starts the worker; it ends when the job sender is dropped.
pub(super) fn start() -> (Sender<Job>, Receiver<Done>) {
    let (jobs, inbox) = unbounded::<Job>();
    let (results, done) = unbounded::<Done>();
    std::thread::Builder::new()
        .name(String::from("sdfc-lsp-analysis"))
        // Deep (but valid) scenes recurse; the passes also grow their stacks on demand.
        .stack_size(64 << 20)
        .spawn(move || {
            let mut batch: Vec<Job> = Vec::new();
            // The last full analysis of each document, for edits of trivia only.
            let mut last: HashMap<String, Last> = HashMap::new();
            loop {
                if batch.is_empty() {
                    match inbox.recv() {
                        Ok(job) => batch.push(job),
                        Err(_) => return,
                    }
                }
                take_newer(&mut batch, &inbox);
                let Job {
                    uri,
                    text,
                    version,
                    roots,
                } = batch.remove(0);
                let send = |result, partial| {
                    results
                        .send(Done {
                            uri: uri.clone(),
                            version,
                            result,
                            partial,
                        })
                        .is_ok()
                };
                let front = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    open(&uri, text.clone(), version, &roots, Stage::Front)
                }))
                .map_err(|panic| super::server::panic_message(&panic));
                // An edit of comments and whitespace only: the last full analysis's back
                // end, carried over, is the whole analysis.
                let key = uri.as_str().to_string();
                let carried = match (&front, last.get(&key)) {
                    (Ok(o), Some(l)) if l.roots == roots => {
                        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| l.carry(o)))
                            .ok()
                            .flatten()
                    }
                    _ => None,
                };
                if let Some(o) = carried {
                    last.insert(key, Last::new(&o, front_diagnostics(&front), roots));
                    if !send(Ok(o), false) {
                        return;
                    }
                    continue;
                }
                let front_diags = front_diagnostics(&front);
                // A front end with errors is the whole analysis: the back end needs a
                // checked program.
                let whole = front.as_ref().map_or(true, |o| o.doc.analysis.has_errors());
                if !send(front, !whole) {
                    return;
                }
                if whole {
                    last.remove(&key);
                    continue;
                }
                // A newer text of this document cancels its back end.
                take_newer(&mut batch, &inbox);
                if batch.iter().any(|j| j.uri == uri) {
                    continue;
                }
                let full = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    open(&uri, text, version, &roots, Stage::Full)
                }))
                .map_err(|panic| super::server::panic_message(&panic));
                match &full {
                    Ok(o) => {
                        last.insert(key, Last::new(o, front_diags, roots));
                    }
                    Err(_) => {
                        last.remove(&key);
                    }
                }
                if !send(full, false) {
                    return;
                }
            }
        })
        .expect("a thread for analyses");
    (jobs, done)
}

/// A document's last full analysis, with its front end's diagnostics and the folders it
/// could read.
struct Last {
    text: String,
    front: Vec<Diagnostic>,
    analysis: crate::driver::Analysis,
    roots: Vec<PathBuf>,
}

impl Last {
    fn new(o: &Open, front: Vec<Diagnostic>, roots: Vec<PathBuf>) -> Last {
        Last {
            text: o.doc.text.clone(),
            front,
            analysis: o.doc.analysis.clone(),
            roots,
        }
    }

    /// The full analysis of `front`'s text, when it differs from this one's only in
    /// trivia ([`crate::incremental`]).
    fn carry(&self, front: &Open) -> Option<Open> {
        let analysis = crate::incremental::carry_back_end(
            &self.text,
            &self.front,
            &self.analysis,
            &front.doc.text,
            front.doc.analysis.clone(),
        )?;
        Some(Open {
            version: front.version,
            doc: crate::ide::Document {
                text: front.doc.text.clone(),
                analysis,
            },
            index: front.index.clone(),
        })
    }
}

fn front_diagnostics(front: &Result<Open, String>) -> Vec<Diagnostic> {
    front
        .as_ref()
        .map(|o| o.doc.analysis.diagnostics.clone())
        .unwrap_or_default()
}

/// Moves the jobs waiting in `inbox` into `batch`: the latest text per document, in the
/// order documents first appear.
fn take_newer(batch: &mut Vec<Job>, inbox: &Receiver<Job>) {
    for job in inbox.try_iter() {
        match batch.iter_mut().find(|j| j.uri == job.uri) {
            Some(j) => *j = job,
            None => batch.push(job),
        }
    }
}
