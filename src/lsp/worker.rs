//! Analyses run on worker threads, so the server keeps answering while a large
//! document is being checked. The front-end worker takes the latest text of each
//! document that changed (older texts queued behind a newer one are skipped), runs the
//! front end (parse, names, types: the diagnostics most edits change, in milliseconds)
//! and sends it back at once; the back end (the atlases' geometry, lowering, code
//! generation and naga) runs on a thread of its own, so the next edit's front end does
//! not wait for the last edit's back end. A newer text of the same document queued
//! meanwhile cancels a back end not yet started; one that finishes late is not
//! published over a newer version (the server keeps the newest). Both threads keep
//! each document's last parse, so unchanged items are not parsed again
//! ([`ItemCache`]), and an edit of comments and whitespace only skips the back end: the
//! last full analysis's is carried over ([`crate::incremental`]). A panic inside an
//! analysis comes back as its message.

use super::threads::{discard, panic_message};
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
    let (back_jobs, finished) = start_back_end(results.clone());
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
                // The back ends finished meanwhile, for the trivia edits to carry over.
                for f in finished.try_iter() {
                    if let Some(kept) = docs.get_mut(&f.key).filter(|k| k.roots == f.roots) {
                        if let Some(old) = std::mem::replace(&mut kept.back_end, f.back_end) {
                            discard(old);
                        }
                    }
                }
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
                        discard(old);
                    }
                    let forget = BackJob {
                        uri: uri.clone(),
                        text: String::new(),
                        version,
                        roots: roots.clone(),
                        front_diags: Vec::new(),
                        forget: true,
                    };
                    if back_jobs.send(forget).is_err() {
                        return;
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
                .map_err(|panic| panic_message(&panic));
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
                let job = BackJob {
                    uri,
                    text,
                    version,
                    roots,
                    front_diags,
                    forget: false,
                };
                if back_jobs.send(job).is_err() {
                    return;
                }
            }
        })
        .expect("a thread for analyses");
    (jobs, done)
}

/// A back end to run: a text whose front end was published; or, with `forget`, a
/// document closed or reopened, whose kept parse goes.
struct BackJob {
    uri: lsp::Uri,
    text: String,
    version: i32,
    roots: Vec<PathBuf>,
    front_diags: Vec<Diagnostic>,
    forget: bool,
}

/// A finished back end, for the front-end worker to carry over trivia edits (None: it
/// panicked, and nothing is carried).
struct Finished {
    key: String,
    roots: Vec<PathBuf>,
    back_end: Option<BackEnd>,
}

/// Starts the back-end thread: it sends full analyses to `results` and what the front
/// end carries over back to the front-end worker. It ends when the job sender is
/// dropped.
fn start_back_end(results: Sender<Done>) -> (Sender<BackJob>, Receiver<Finished>) {
    let (jobs, inbox) = unbounded::<BackJob>();
    let (finished, finished_rx) = unbounded::<Finished>();
    std::thread::Builder::new()
        .name(String::from("sdfc-lsp-back-end"))
        .stack_size(64 << 20)
        .spawn(move || {
            // Each document's parse, as of the last back end run on it, and its roots.
            let mut items: HashMap<String, (Vec<PathBuf>, ItemCache)> = HashMap::new();
            while let Ok(first) = inbox.recv() {
                // The latest text per document: older back ends not started are cancelled.
                let mut batch: Vec<BackJob> = vec![first];
                for job in inbox.try_iter() {
                    // A text replaces the document's last queued text, unless a forget
                    // came between them.
                    match batch.iter_mut().rev().find(|j| j.uri == job.uri) {
                        Some(j) if !j.forget && !job.forget => *j = job,
                        _ => batch.push(job),
                    }
                }
                for job in batch {
                    let key = job.uri.as_str().to_string();
                    if job.forget {
                        if let Some(old) = items.remove(&key) {
                            discard(old);
                        }
                        continue;
                    }
                    let kept = items.entry(key.clone()).or_default();
                    if kept.0 != job.roots {
                        *kept = (job.roots.clone(), ItemCache::default());
                    }
                    let full = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        let cache = Some(&mut kept.1);
                        open(
                            &job.uri,
                            job.text,
                            job.version,
                            &job.roots,
                            Stage::Full,
                            cache,
                        )
                    }))
                    .map_err(|panic| panic_message(&panic));
                    let back_end = match &full {
                        Ok(o) => Some(BackEnd::of(&o.doc.text, &job.front_diags, &o.doc.analysis)),
                        Err(_) => {
                            // A panic may have left the kept items half updated.
                            items.remove(&key);
                            None
                        }
                    };
                    let done = Done {
                        uri: job.uri,
                        version: job.version,
                        result: full,
                        partial: false,
                    };
                    let carried = Finished {
                        key,
                        roots: job.roots,
                        back_end,
                    };
                    // The carry first: once the client sees this publish, an edit it
                    // sends finds the back end there to carry over.
                    if finished.send(carried).is_err() || results.send(done).is_err() {
                        return;
                    }
                }
            }
        })
        .expect("a thread for back ends");
    (jobs, finished_rx)
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
