//! Analyses run on a worker thread, so the server keeps answering while a large
//! document is being checked. The worker takes the latest text of each document that
//! changed (older texts queued behind a newer one are skipped) and sends each analysis
//! back; a panic inside an analysis comes back as its message.

use super::{open, Open};
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
            while let Ok(first) = inbox.recv() {
                // The latest text per document, in the order documents first appear.
                let mut batch: Vec<Job> = vec![first];
                for job in inbox.try_iter() {
                    match batch.iter_mut().find(|j| j.uri == job.uri) {
                        Some(j) => *j = job,
                        None => batch.push(job),
                    }
                }
                for job in batch {
                    let Job {
                        uri,
                        text,
                        version,
                        roots,
                    } = job;
                    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        open(&uri, text, version, &roots)
                    }))
                    .map_err(|panic| super::server::panic_message(&panic));
                    if results
                        .send(Done {
                            uri,
                            version,
                            result,
                        })
                        .is_err()
                    {
                        return;
                    }
                }
            }
        })
        .expect("a thread for analyses");
    (jobs, done)
}
