//! The server loop: the lifecycle (initialize, shutdown, exit), batches of messages,
//! analyses on a worker thread ([`super::worker`]), and cancellation.
//!
//! A reader thread moves every message from the connection into an unbounded queue
//! as soon as it arrives. `lsp-server`'s stdio connection hands messages over a
//! channel of capacity zero, so without it "everything waiting" would be at most one
//! message, and every keystroke of a burst would get its own analysis.

use super::dispatch::{respond, Failure, NotificationDispatcher};
use super::threads::{discard, panic_message};
use super::worker::{self, Done, Job};
use super::{answer, publish, Docs, Error};
use crossbeam_channel::{select, Receiver, Sender};
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, RequestId, Response};
use lsp_types as lsp;
use lsp_types::notification::{
    Cancel, DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, Exit,
    Notification as _,
};
use lsp_types::request::{Initialize, Request as _, Shutdown};
use std::collections::{HashMap, HashSet};
use std::time::{Duration, Instant};

/// How long a request waits for the analysis of a text changed before it, before it is
/// answered against the last finished one (so the server keeps answering while a large
/// document is checked).
const WAIT_FOR_ANALYSIS: Duration = Duration::from_secs(2);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Before the `initialize` request: requests get `ServerNotInitialized`.
    Uninitialized,
    Running,
    /// After `shutdown`: requests get `InvalidRequest`, and `exit` ends the server.
    ShutDown,
}

/// A request of the batch: answered at once (the lifecycle), or after the batch's
/// analysis against the latest text.
enum Pending {
    Ready(Response),
    Deferred(Request),
}

pub(super) struct Server {
    conn: Connection,
    phase: Phase,
    docs: Docs,
    /// Texts opened or changed in this batch, the latest per document.
    changed: Vec<(lsp::Uri, String, i32)>,
    /// The analysis worker's jobs and results.
    jobs: Sender<Job>,
    done: Receiver<Done>,
    /// The latest version sent to the worker of each document still being analysed.
    analysing: HashMap<String, i32>,
    /// Requests the client cancelled.
    cancelled: HashSet<RequestId>,
    /// The workspace folders (from `initialize`), where documents may read files.
    roots: Vec<std::path::PathBuf>,
    /// Answers computed on threads of their own (see [`Server::in_background`]).
    background: (Sender<Response>, Receiver<Response>),
    /// The requests being answered in the background, not yet answered.
    in_flight: HashSet<RequestId>,
}

/// Requests whose answers can take seconds (placing seeds walks the whole surface):
/// they are computed on a thread of their own, so the loop keeps answering hover,
/// cancellations, `shutdown` and `exit` meanwhile.
const BACKGROUND: &[&str] = &["codeAction/resolve"];

/// Moves every message of the connection into an unbounded queue, from a thread
/// that ends when the connection closes or the server stops listening.
fn queue(conn: &Connection) -> Receiver<Message> {
    let (tx, rx) = crossbeam_channel::unbounded();
    let receiver = conn.receiver.clone();
    std::thread::Builder::new()
        .name(String::from("sdfc-lsp-queue"))
        .spawn(move || {
            for m in receiver {
                if tx.send(m).is_err() {
                    break;
                }
            }
        })
        .expect("a thread for the message queue");
    rx
}

/// How the server ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ended {
    /// `exit` (or the end of the input) after `shutdown`: exit status 0.
    Clean,
    /// `exit` (or the end of the input) without `shutdown`: exit status 1, as the
    /// specification asks.
    WithoutShutdown,
}

/// Serves one client on a connection until it exits or closes the connection.
///
/// Messages are taken in batches: everything that arrived while the server was busy.
/// Each document changed in a batch goes to the analysis worker once, at its latest
/// text; its diagnostics are published with that version when the analysis is done.
/// The batch's requests wait for the analyses of their batch (at most
/// [`WAIT_FOR_ANALYSIS`]) and are answered against the latest finished analysis, except
/// those the client cancelled (`$/cancelRequest`), which get `RequestCancelled` without
/// being computed. A cancellation that arrives during the wait still counts.
pub fn serve(conn: Connection) -> Result<Ended, Error> {
    tune_allocator();
    let inbox = queue(&conn);
    let (jobs, done) = worker::start();
    let mut server = Server {
        conn,
        phase: Phase::Uninitialized,
        docs: Docs::new(),
        changed: Vec::new(),
        jobs,
        done,
        analysing: HashMap::new(),
        cancelled: HashSet::new(),
        roots: Vec::new(),
        background: crossbeam_channel::unbounded(),
        in_flight: HashSet::new(),
    };
    let mut carried: Vec<Message> = Vec::new();
    loop {
        let mut batch = std::mem::take(&mut carried);
        while batch.is_empty() {
            select! {
                recv(inbox) -> m => match m {
                    Ok(m) => batch.push(m),
                    // The client closed the connection.
                    Err(_) => return Ok(server.ended()),
                },
                recv(server.done) -> d => {
                    if let Ok(d) = d {
                        server.finished(d)?;
                    }
                }
                recv(server.background.1) -> r => {
                    if let Ok(r) = r {
                        server.background_done(r)?;
                    }
                }
            }
        }
        batch.extend(inbox.try_iter());
        let mut pending = Vec::new();
        let mut exit = false;
        for msg in batch {
            match msg {
                Message::Request(req) => pending.push(server.classify(req)),
                Message::Notification(n) if n.method == Exit::METHOD => {
                    exit = true;
                    break;
                }
                Message::Notification(n) => server.notify(n)?,
                Message::Response(_) => {}
            }
        }
        server.analyse();
        if !exit && pending.iter().any(|p| server.waits_for_analysis(p)) {
            // What arrives during the wait goes to the next batch, but its cancellations
            // already apply to this one's requests.
            carried = server.wait(&inbox)?;
        }
        for p in pending {
            let p = match p {
                Pending::Deferred(req)
                    if BACKGROUND.contains(&req.method.as_str())
                        && !server.cancelled.contains(&req.id) =>
                {
                    server.in_background(req);
                    continue;
                }
                p => p,
            };
            let resp = server.answer(p);
            server.conn.sender.send(Message::Response(resp))?;
        }
        server.cancelled.clear();
        if exit {
            return Ok(server.ended());
        }
    }
}

impl Server {
    fn ended(&self) -> Ended {
        match self.phase {
            Phase::ShutDown => Ended::Clean,
            _ => Ended::WithoutShutdown,
        }
    }

    /// Answers the lifecycle requests in order, and defers the others.
    fn classify(&mut self, req: Request) -> Pending {
        let lifecycle =
            |id, result: Result<serde_json::Value, Failure>| Pending::Ready(respond(id, result));
        match (self.phase, req.method.as_str()) {
            (Phase::Uninitialized, Initialize::METHOD) => {
                self.phase = Phase::Running;
                self.roots = super::workspace_roots(&req.params);
                lifecycle(
                    req.id,
                    Ok(serde_json::to_value(super::initialize_result())
                        .expect("capabilities serialize")),
                )
            }
            (Phase::Uninitialized, _) => lifecycle(
                req.id,
                Err(Failure::new(
                    ErrorCode::ServerNotInitialized,
                    format!("{} before initialize", req.method),
                )),
            ),
            (Phase::Running, Shutdown::METHOD) => {
                self.phase = Phase::ShutDown;
                lifecycle(req.id, Ok(serde_json::Value::Null))
            }
            (Phase::Running, Initialize::METHOD) => lifecycle(
                req.id,
                Err(Failure::new(
                    ErrorCode::InvalidRequest,
                    "the server is already initialized",
                )),
            ),
            (Phase::Running, _) => Pending::Deferred(req),
            (Phase::ShutDown, _) => lifecycle(
                req.id,
                Err(Failure::new(
                    ErrorCode::InvalidRequest,
                    format!("{} after shutdown", req.method),
                )),
            ),
        }
    }

    fn answer(&self, p: Pending) -> Response {
        match p {
            Pending::Ready(r) => r,
            Pending::Deferred(req) if self.cancelled.contains(&req.id) => respond::<()>(
                req.id,
                Err(Failure::new(
                    ErrorCode::RequestCanceled,
                    "cancelled by the client",
                )),
            ),
            Pending::Deferred(req) => {
                // A panic inside a request is answered as an internal error, and the
                // server keeps serving (as rust-analyzer does).
                answer_caught(&self.docs, req)
            }
        }
    }

    /// Applies a notification; before `initialize`, notifications are dropped.
    fn notify(&mut self, n: Notification) -> Result<(), Error> {
        if n.method == super::transport::SKIPPED {
            let why = n.params["message"]
                .as_str()
                .unwrap_or("a message was skipped");
            eprintln!("sdfc lsp: {why}");
            return show_error(&self.conn, why);
        }
        if self.phase == Phase::Uninitialized {
            return Ok(());
        }
        NotificationDispatcher::new(n, self)
            .on::<DidOpenTextDocument, Error>(|s, p| {
                let d = p.text_document;
                s.queue(d.uri, d.text, d.version);
                Ok(())
            })?
            .on::<DidChangeTextDocument, Error>(|s, p| {
                // Full sync: the last change holds the whole text.
                if let Some(change) = p.content_changes.into_iter().last() {
                    s.queue(p.text_document.uri, change.text, p.text_document.version);
                }
                Ok(())
            })?
            .on::<DidCloseTextDocument, Error>(|s, p| {
                let uri = p.text_document.uri;
                s.changed.retain(|(u, _, _)| *u != uri);
                if let Some(old) = s.docs.remove(uri.as_str()) {
                    discard(old);
                }
                // The worker forgets what it kept of the document.
                let _ = s.jobs.send(Job {
                    uri: uri.clone(),
                    text: String::new(),
                    version: 0,
                    roots: Vec::new(),
                    closed: true,
                    forget: false,
                });
                s.analysing.remove(uri.as_str());
                publish(&s.conn, &uri, None, false)
            })?
            .on::<Cancel, Error>(|s, p| {
                let id = match p.id {
                    lsp::NumberOrString::Number(i) => RequestId::from(i),
                    lsp::NumberOrString::String(s) => RequestId::from(s),
                };
                // A request answered in the background is answered now; its late
                // result is dropped.
                if s.in_flight.remove(&id) {
                    let resp = respond::<()>(
                        id,
                        Err(Failure::new(
                            ErrorCode::RequestCanceled,
                            "cancelled by the client",
                        )),
                    );
                    s.conn.sender.send(Message::Response(resp))?;
                    return Ok(());
                }
                s.cancelled.insert(id);
                Ok(())
            })?;
        Ok(())
    }

    /// Answers `req` on a thread of its own, against a copy of its document as it is
    /// now; the answer comes back through `background` (a panic is an internal error).
    fn in_background(&mut self, req: Request) {
        let uri = req.params["data"]["uri"]
            .as_str()
            .or_else(|| req.params["textDocument"]["uri"].as_str())
            .unwrap_or_default()
            .to_string();
        let mut docs = Docs::new();
        if let Some(o) = self.docs.get(&uri) {
            docs.insert(uri, o.clone());
        }
        let request = req.id.clone();
        self.in_flight.insert(request.clone());
        let tx = self.background.0.clone();
        let spawned = std::thread::Builder::new()
            .name(String::from("sdfc-lsp-request"))
            .stack_size(64 << 20)
            .spawn(move || {
                let resp = answer_caught(&docs, req);
                // The loop is gone when the server has stopped: nothing to answer.
                let _ = tx.send(resp);
                discard(docs);
            });
        if let Err(e) = spawned {
            eprintln!("sdfc lsp: no thread for a request: {e}");
            self.in_flight.remove(&request);
            let resp = respond::<()>(
                request,
                Err(Failure::new(
                    ErrorCode::InternalError,
                    format!("no thread to answer the request: {e}"),
                )),
            );
            let _ = self.conn.sender.send(Message::Response(resp));
        }
    }

    /// A background answer: sent, unless the request was cancelled and answered since.
    fn background_done(&mut self, resp: Response) -> Result<(), Error> {
        if self.in_flight.remove(&resp.id) {
            self.conn.sender.send(Message::Response(resp))?;
        }
        Ok(())
    }

    /// Queues a document's latest text for the analysis at the end of the batch.
    fn queue(&mut self, uri: lsp::Uri, text: String, version: i32) {
        self.changed.retain(|(u, _, _)| *u != uri);
        self.changed.push((uri, text, version));
    }

    /// Whether a request is about a document whose analysis is still running.
    fn waits_for_analysis(&self, p: &Pending) -> bool {
        let Pending::Deferred(req) = p else {
            return false;
        };
        req.params["textDocument"]["uri"]
            .as_str()
            .is_some_and(|uri| self.analysing.contains_key(uri))
    }

    /// Sends each document changed in the batch to the worker, once, at its latest text.
    fn analyse(&mut self) {
        for (uri, text, version) in std::mem::take(&mut self.changed) {
            self.analysing.insert(uri.as_str().to_string(), version);
            let job = Job {
                uri,
                text,
                version,
                roots: self.roots.clone(),
                closed: false,
                forget: false,
            };
            // The worker only stops when the server does.
            let _ = self.jobs.send(job);
        }
    }

    /// Waits until no analysis is outstanding or [`WAIT_FOR_ANALYSIS`] has passed,
    /// publishing what finishes; returns the messages that arrived meanwhile, after
    /// applying their cancellations.
    fn wait(&mut self, inbox: &Receiver<Message>) -> Result<Vec<Message>, Error> {
        let deadline = Instant::now() + WAIT_FOR_ANALYSIS;
        let mut arrived = Vec::new();
        let waiting: Vec<String> = self.analysing.keys().cloned().collect();
        while waiting.iter().any(|u| self.analysing.contains_key(u)) {
            let Some(left) = deadline.checked_duration_since(Instant::now()) else {
                break;
            };
            select! {
                recv(self.done) -> d => match d {
                    Ok(d) => self.finished(d)?,
                    Err(_) => break,
                },
                recv(inbox) -> m => match m {
                    Ok(m) => arrived.push(m),
                    Err(_) => break,
                },
                default(left) => break,
            }
        }
        arrived.extend(inbox.try_iter());
        for m in &arrived {
            if let Message::Notification(n) = m {
                if n.method == Cancel::METHOD {
                    self.notify(n.clone())?;
                }
            }
        }
        Ok(arrived)
    }

    /// A finished analysis: published and kept, unless the document was closed since or
    /// a newer version is already kept.
    fn finished(&mut self, d: Done) -> Result<(), Error> {
        let key = d.uri.as_str().to_string();
        let Some(&latest) = self.analysing.get(&key) else {
            // Closed since.
            return Ok(());
        };
        // The front end's stage is published at once; requests wait for the back end's.
        if latest == d.version && !d.partial {
            self.analysing.remove(&key);
        }
        match d.result {
            Ok(o) => {
                // Never an older version over a newer one, nor the front end's stage
                // over the back end's of the same version.
                if self.docs.get(&key).is_some_and(|old| {
                    old.version > o.version || (old.version == o.version && d.partial)
                }) {
                    return Ok(());
                }
                publish(&self.conn, &d.uri, Some(&o), d.partial)?;
                if let Some(old) = self.docs.insert(key, o) {
                    discard(old);
                }
            }
            Err(why) => {
                eprintln!(
                    "sdfc lsp: internal error while checking {}: {why}",
                    d.uri.as_str()
                );
                show_error(
                    &self.conn,
                    &format!("sdfc: internal error while checking: {why}"),
                )?;
            }
        }
        Ok(())
    }
}

/// The server keeps and frees a large document's texts and analyses on every edit. With
/// glibc's default thresholds each text over 128 KiB is a fresh mapping and freed memory
/// goes back to the kernel, so every edit page-faults its memory in again: measured on a
/// 5,000-line scene, the front end's p95 went from 41 to 23 ms with these (the heap
/// keeps up to 128 MiB free; blocks up to 32 MiB come from the heap). Process-wide.
fn tune_allocator() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets two of glibc's tuning parameters; it takes the arena
    // locks itself and is safe to call at any time.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 128 << 20);
    }
}

/// The answer to `req`; a panic inside it is answered as an internal error and logged.
fn answer_caught(docs: &Docs, req: Request) -> Response {
    let (id, method) = (req.id.clone(), req.method.clone());
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| answer(docs, req))).unwrap_or_else(
        |panic| {
            let why = panic_message(&panic);
            eprintln!("sdfc lsp: internal error in {method}: {why}");
            respond::<()>(
                id,
                Err(Failure::new(
                    ErrorCode::InternalError,
                    format!("internal error in {method}: {why}"),
                )),
            )
        },
    )
}

/// Shows the user an error (`window/showMessage`).
fn show_error(conn: &Connection, message: &str) -> Result<(), Error> {
    use lsp_types::notification::ShowMessage;
    let params = lsp::ShowMessageParams {
        typ: lsp::MessageType::ERROR,
        message: message.to_string(),
    };
    conn.sender.send(Message::Notification(Notification::new(
        ShowMessage::METHOD.to_string(),
        params,
    )))?;
    Ok(())
}
