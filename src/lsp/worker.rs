//! Analyses run on a worker thread, so the server keeps answering while a large
//! document is being checked. The worker takes the latest text of each document that
//! changed (older texts queued behind a newer one are skipped) and analyses it in two
//! stages, each sent back as it finishes: the front end (parse, names, types: the
//! diagnostics most edits change, in milliseconds), then the back end (the atlases'
//! geometry, lowering, code generation and naga), which a newer text of the same
//! document queued meanwhile cancels. A panic inside an analysis comes back as its
//! message.

use super::{open, Open, Stage};
use crossbeam_channel::{unbounded, Receiver, Sender};
use lsp_types as lsp;
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
                // A front end with errors is the whole analysis: the back end needs a
                // checked program.
                let whole = front.as_ref().map_or(true, |o| o.doc.analysis.has_errors());
                if !send(front, !whole) {
                    return;
                }
                if whole {
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
                if !send(full, false) {
                    return;
                }
            }
        })
        .expect("a thread for analyses");
    (jobs, done)
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
