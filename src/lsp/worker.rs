//! Analyses run on a worker thread, so the server keeps answering while a large
//! document is being checked. The worker takes the latest text of each document that
//! changed (older texts queued behind a newer one are skipped) and analyses it in two
//! stages, each sent back as it finishes: the front end (parse, names, types: the
//! diagnostics most edits change, in milliseconds), then the back end (the atlases'
//! geometry, lowering, code generation and naga), which a newer text of the same
//! document queued meanwhile cancels. The worker keeps each document's last parse, so
//! unchanged items are not parsed again ([`ItemCache`]), and an edit of comments and
//! whitespace only skips the back end: the last full analysis's is carried over
//! ([`crate::incremental`]). A panic inside an analysis comes back as its message.

use super::{open, Open, Stage};
use crate::diagnostic::Diagnostic;
use crate::incremental::BackEnd;
use crate::syntax::ItemCache;
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
    /// The document was closed: forget what is kept of it (nothing is analysed).
    pub closed: bool,
    /// Forget what is kept of the document before analysing this text (it was closed
    /// since the last text analysed).
    pub forget: bool,
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
            let mut docs: HashMap<String, Kept> = HashMap::new();
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
                    closed,
                    forget,
                } = batch.remove(0);
                if closed || forget {
                    if let Some(old) = docs.remove(uri.as_str()) {
                        super::server::discard(old);
                    }
                    if closed {
                        continue;
                    }
                }
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
                let key = uri.as_str().to_string();
                let kept = docs.entry(key.clone()).or_default();
                if kept.roots != roots {
                    *kept = Kept {
                        roots: roots.clone(),
                        ..Kept::default()
                    };
                }
                let front = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    let items = Some(&mut kept.items);
                    open(&uri, text.clone(), version, &roots, Stage::Front, items)
                }))
                .map_err(|panic| super::server::panic_message(&panic));
                let front = match (front, &kept.back_end) {
                    // An edit of comments and whitespace only: the last full analysis's
                    // back end, carried over, makes this the whole analysis.
                    (Ok(o), Some(back_end)) => match carry(back_end, o) {
                        Ok(whole) => {
                            if !send(Ok(whole), false) {
                                return;
                            }
                            continue;
                        }
                        Err(o) => Ok(o),
                    },
                    (front, _) => front,
                };
                if front.is_err() {
                    // A panic may have left the kept items half updated.
                    docs.remove(&key);
                }
                let front_diags: Vec<Diagnostic> = front
                    .as_ref()
                    .map(|o| o.doc.analysis.diagnostics.clone())
                    .unwrap_or_default();
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
                let kept = docs.entry(key.clone()).or_default();
                kept.roots = roots.clone();
                let full = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    let items = Some(&mut kept.items);
                    open(&uri, text, version, &roots, Stage::Full, items)
                }))
                .map_err(|panic| super::server::panic_message(&panic));
                match &full {
                    Ok(o) => {
                        let back_end = BackEnd::of(&o.doc.text, &front_diags, &o.doc.analysis);
                        if let Some(old) = kept.back_end.replace(back_end) {
                            super::server::discard(old);
                        }
                    }
                    Err(_) => {
                        docs.remove(&key);
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

/// What the worker keeps of each document between its texts: the items of its last
/// parse ([`ItemCache`]) and the back end of its last full analysis, for the folders it
/// could read then.
#[derive(Default)]
struct Kept {
    roots: Vec<PathBuf>,
    items: ItemCache,
    back_end: Option<BackEnd>,
}

/// The whole analysis of `front`'s text when it differs from the back end's only in
/// trivia ([`crate::incremental`]); else `front` back.
fn carry(back_end: &BackEnd, mut front: Open) -> Result<Open, Open> {
    if front.doc.analysis.has_errors() {
        return Err(front);
    }
    let (text, analysis) = (&front.doc.text, &front.doc.analysis);
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        back_end.carried(text, analysis)
    })) {
        Ok(Some(carried)) => {
            carried.complete(&mut front.doc.analysis);
            Ok(front)
        }
        Ok(None) | Err(_) => Err(front),
    }
}

/// Moves the jobs waiting in `inbox` into `batch`: the latest text per document, in the
/// order documents first appear.
fn take_newer(batch: &mut Vec<Job>, inbox: &Receiver<Job>) {
    for mut job in inbox.try_iter() {
        match batch.iter_mut().find(|j| j.uri == job.uri) {
            Some(j) => {
                // A document closed and opened again starts afresh.
                job.forget |= j.closed || j.forget;
                *j = job;
            }
            None => batch.push(job),
        }
    }
}
