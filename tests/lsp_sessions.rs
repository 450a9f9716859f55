//! Random sessions of the real `sdfc lsp` over its stdio pipe. A session initializes,
//! opens one or two examples (as they are, or mutated: `tests/mutate`) at their real
//! paths, then makes a random sequence of full-text `didChange` edits (mutations,
//! insertions, deletions, quick fixes and placed seeds applied), requests at random
//! positions (hover, completion, definition, references, document symbols, formatting,
//! semantic tokens, signature help, inlay hints, code actions, rename), resolves of
//! "Place seeds automatically" when offered, `$/cancelRequest` of random outstanding
//! requests, and closes and reopens; then `shutdown` and `exit` (in some sessions
//! with requests still outstanding: a resolve still placing seeds may then go
//! unanswered, as the server exits first).
//!
//! Each session must see: exactly one response to every request (a result or an
//! error; a cancelled request may get RequestCancelled, -32800, and only a cancelled
//! one), never an internal error (-32603, nor "internal error" shown or on stderr), a
//! server that never dies, `shutdown` answered with null and exit status 0 after
//! `exit`, a peak resident memory (VmHWM, read before `exit`) under 1 GB, all within
//! 60 s (the cap only keeps a hung server from hanging the suite; the long run also
//! fails a session over 20 s).
//!
//! A session comes from one `u64` seed (what the client sends, not the server's
//! timing). A failing session's messages are written, framed, to
//! `target/tmp/lsp-session-SEED.txt` (`sdfc lsp < FILE` replays them);
//! `SDFC_LSP_SEED=N cargo test --release --test suite lsp_sessions::one_session --
//! --nocapture` runs session N alone. The 500-session run: `cargo test --release
//! --test suite lsp_sessions:: -- --ignored --nocapture` (`SDFC_LSP_SESSIONS` sets the count,
//! `SDFC_LSP_JOBS` how many run at a time).

#[allow(unused)]
use crate::gen;
use crate::mutate;

use gen::Rng;
use serde_json::{json, Value};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// A session still running after this is killed and fails (only so that a hung server
/// cannot hang the suite).
const CAP: Duration = Duration::from_secs(60);

/// The long run fails a session that takes longer than this.
const SLOW: Duration = Duration::from_secs(20);

/// The most resident memory the server may have had at its peak.
const MAX_RSS_KB: u64 = 1 << 20;

/// Resolves of "Place seeds automatically" per session at most (each places seeds on
/// a 40-cell grid: up to seconds).
const RESOLVES: usize = 3;

/// The seeds of the long run start here (the in-suite run takes 0, 1, 2, …).
const IGNORED_BASE: u64 = 5_000_000;

/// The error codes of the protocol this test looks for.
const INTERNAL_ERROR: i64 = -32603;
const REQUEST_CANCELLED: i64 = -32800;

// ---------------------------------------------------------------- the pipe

/// What the reader thread hands over.
enum Incoming {
    Message(Value),
    /// A frame that is not JSON, or broken framing: a failure.
    Bad(String),
}

/// A running `sdfc lsp`: its messages are read by a thread, its standard error
/// collected by another.
struct Server {
    child: Child,
    stdin: ChildStdin,
    messages: mpsc::Receiver<Incoming>,
    stderr: Arc<Mutex<String>>,
}

fn frame(v: &Value) -> String {
    let body = v.to_string();
    format!("Content-Length: {}\r\n\r\n{body}", body.len())
}

impl Server {
    fn spawn() -> Server {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sdfc"))
            .arg("lsp")
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stdin = child.stdin.take().unwrap();
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let mut err = child.stderr.take().unwrap();
        let stderr = Arc::new(Mutex::new(String::new()));
        let sink = stderr.clone();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = err.read(&mut buf) {
                if n == 0 {
                    break;
                }
                sink.lock()
                    .unwrap()
                    .push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        });
        let (tx, messages) = mpsc::channel();
        std::thread::spawn(move || loop {
            let mut len = None;
            loop {
                let mut line = String::new();
                match stdout.read_line(&mut line) {
                    Ok(0) => return,
                    Ok(_) => {}
                    Err(e) => {
                        let _ = tx.send(Incoming::Bad(format!("reading a header: {e}")));
                        return;
                    }
                }
                if line == "\r\n" {
                    break;
                }
                if let Some(n) = line.strip_prefix("Content-Length: ") {
                    len = n.trim().parse().ok();
                }
            }
            let Some(len) = len else {
                let _ = tx.send(Incoming::Bad("a frame without Content-Length".into()));
                return;
            };
            let mut body = vec![0; len];
            if let Err(e) = stdout.read_exact(&mut body) {
                let _ = tx.send(Incoming::Bad(format!("a frame cut short: {e}")));
                return;
            }
            let m = match serde_json::from_slice(&body) {
                Ok(v) => Incoming::Message(v),
                Err(e) => Incoming::Bad(format!(
                    "not JSON ({e}): {}",
                    String::from_utf8_lossy(&body)
                )),
            };
            if tx.send(m).is_err() {
                return;
            }
        });
        Server {
            child,
            stdin,
            messages,
            stderr,
        }
    }

    /// Writes the messages in one `write`, as a client flushing a burst does.
    fn write(&mut self, messages: &[Value]) -> std::io::Result<()> {
        let bytes: String = messages.iter().map(frame).collect();
        self.stdin.write_all(bytes.as_bytes())?;
        self.stdin.flush()
    }

    /// The server's peak resident memory (VmHWM), in KiB.
    fn peak_rss_kb(&self) -> Option<u64> {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).ok()?;
        status
            .lines()
            .find_map(|l| l.strip_prefix("VmHWM:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
    }
}

// ---------------------------------------------------------------- positions

/// The protocol position (UTF-16 columns, lines split at `\n`) of byte `offset`.
fn position(text: &str, offset: usize) -> Value {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count();
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    let character = text[start..offset].encode_utf16().count();
    json!({ "line": line, "character": character })
}

/// The byte offset of a protocol position (clamped to its line and to the text).
fn offset(text: &str, p: &Value) -> usize {
    let line = p["line"].as_u64().unwrap_or(0) as usize;
    let character = p["character"].as_u64().unwrap_or(0) as usize;
    let mut start = 0;
    for _ in 0..line {
        match text[start..].find('\n') {
            Some(i) => start += i + 1,
            None => return text.len(),
        }
    }
    let end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let mut units = 0;
    for (i, c) in text[start..end].char_indices() {
        if units >= character {
            return start + i;
        }
        units += c.len_utf16();
    }
    end
}

/// Text edits (`{range, newText}`) applied to `text`, the last first.
fn apply(text: &str, edits: &[Value]) -> Option<String> {
    let mut spans: Vec<(usize, usize, String)> = edits
        .iter()
        .map(|e| {
            let a = offset(text, &e["range"]["start"]);
            let b = offset(text, &e["range"]["end"]);
            (a, b.max(a), e["newText"].as_str().unwrap_or("").to_string())
        })
        .collect();
    spans.sort_by_key(|s| std::cmp::Reverse(s.0));
    let mut out = text.to_string();
    let mut last = usize::MAX;
    for (a, b, t) in spans {
        if b > last {
            // Overlapping edits: not applied.
            return None;
        }
        out.replace_range(a..b, &t);
        last = a;
    }
    Some(out)
}

/// A random position in `text`: on a token (start, middle or end), anywhere on a
/// line, at a line's end, or past the text.
fn random_position(rng: &mut Rng, text: &str) -> Value {
    match rng.below(8) {
        0..=3 => {
            let toks = mutate::lex(text);
            if toks.is_empty() {
                return json!({ "line": 0, "character": 0 });
            }
            let s = toks[rng.below(toks.len())].1;
            let at = match rng.below(3) {
                0 => s.start,
                1 => (s.start + s.end) / 2,
                _ => s.end,
            };
            position(text, at)
        }
        4 | 5 => position(text, mutate::boundary(rng, text)),
        6 => {
            let lines = text.split('\n').count();
            let line = rng.below(lines);
            json!({ "line": line, "character": 1000 + rng.below(100) })
        }
        _ => {
            let lines = text.split('\n').count();
            json!({ "line": lines + rng.below(5), "character": rng.below(30) })
        }
    }
}

// ---------------------------------------------------------------- the session

/// One document of the session, as the client sees it.
struct Doc {
    uri: String,
    original: String,
    text: String,
    version: i64,
    open: bool,
    /// The diagnostics last published for it.
    diagnostics: Vec<Value>,
    /// Its earlier texts, for undo.
    history: Vec<String>,
}

/// An outstanding request.
struct Sent {
    method: String,
    doc: Option<usize>,
    version: i64,
    at: Instant,
}

/// The figures of one session, or of many added up.
#[derive(Debug, Default, Clone)]
struct Tally {
    sessions: usize,
    requests: usize,
    responses: usize,
    notifications: usize,
    changes: usize,
    cancels: usize,
    cancelled_answers: usize,
    resolves: usize,
    resolved_edits: usize,
    applied_fixes: usize,
    applied_seeds: usize,
    closes: usize,
    errors: BTreeMap<i64, usize>,
    by_method: BTreeMap<String, usize>,
    peak_rss_kb: u64,
    peak_rss_seed: u64,
    slowest: Duration,
    slowest_seed: u64,
    /// The request answered last after it was sent: (time, method, session).
    slowest_request: (Duration, String, u64),
    /// Sessions that sent `shutdown` with requests outstanding.
    hasty: usize,
    /// Resolves never answered because the server exited first (hasty sessions only).
    abandoned: usize,
    /// The longest time from `exit` to the end of the process.
    slowest_exit: Duration,
}

impl Tally {
    fn add(&mut self, o: &Tally) {
        self.sessions += o.sessions;
        self.requests += o.requests;
        self.responses += o.responses;
        self.notifications += o.notifications;
        self.changes += o.changes;
        self.cancels += o.cancels;
        self.cancelled_answers += o.cancelled_answers;
        self.resolves += o.resolves;
        self.resolved_edits += o.resolved_edits;
        self.applied_fixes += o.applied_fixes;
        self.applied_seeds += o.applied_seeds;
        self.closes += o.closes;
        self.hasty += o.hasty;
        self.abandoned += o.abandoned;
        self.slowest_exit = self.slowest_exit.max(o.slowest_exit);
        for (k, v) in &o.errors {
            *self.errors.entry(*k).or_default() += v;
        }
        for (k, v) in &o.by_method {
            *self.by_method.entry(k.clone()).or_default() += v;
        }
        if o.peak_rss_kb > self.peak_rss_kb {
            self.peak_rss_kb = o.peak_rss_kb;
            self.peak_rss_seed = o.peak_rss_seed;
        }
        if o.slowest_request.0 > self.slowest_request.0 {
            self.slowest_request = o.slowest_request.clone();
        }
        if o.slowest > self.slowest {
            self.slowest = o.slowest;
            self.slowest_seed = o.slowest_seed;
        }
    }
}

struct Session {
    seed: u64,
    rng: Rng,
    server: Server,
    examples: Vec<(String, String)>,
    docs: Vec<Doc>,
    next_id: i64,
    outstanding: HashMap<i64, Sent>,
    /// Every request sent, by id: its method.
    sent: HashMap<i64, String>,
    /// Responses per id.
    answered: HashMap<i64, usize>,
    cancelled: HashSet<i64>,
    /// "Place seeds automatically" actions offered: (action, document, version).
    offered: Vec<(Value, usize, i64)>,
    /// Edits to apply (quick fixes, placed seeds): (document, version, edits, seeds).
    edits: Vec<(usize, i64, Vec<Value>, bool)>,
    resolves_left: usize,
    /// Every message sent, for the transcript.
    transcript: Vec<Value>,
    failures: Vec<String>,
    tally: Tally,
    started: Instant,
    /// The server is gone (a write failed or it exited).
    dead: bool,
    /// The shutdown was sent without waiting for the outstanding answers.
    hasty: bool,
}

/// The requests a session makes, with their weights.
const METHODS: &[(&str, usize)] = &[
    ("textDocument/hover", 6),
    ("textDocument/completion", 5),
    ("textDocument/definition", 4),
    ("textDocument/references", 4),
    ("textDocument/documentSymbol", 2),
    ("textDocument/formatting", 2),
    ("textDocument/semanticTokens/full", 2),
    ("textDocument/signatureHelp", 4),
    ("textDocument/inlayHint", 2),
    ("textDocument/codeAction", 4),
    ("textDocument/prepareRename", 1),
    ("textDocument/rename", 1),
];

impl Session {
    fn new(seed: u64, examples: &[(String, String)]) -> Session {
        Session {
            seed,
            rng: Rng::new(seed),
            server: Server::spawn(),
            examples: examples.to_vec(),
            docs: Vec::new(),
            next_id: 1,
            outstanding: HashMap::new(),
            sent: HashMap::new(),
            answered: HashMap::new(),
            cancelled: HashSet::new(),
            offered: Vec::new(),
            edits: Vec::new(),
            resolves_left: RESOLVES,
            transcript: Vec::new(),
            failures: Vec::new(),
            tally: Tally {
                sessions: 1,
                ..Tally::default()
            },
            started: Instant::now(),
            dead: false,
            hasty: false,
        }
    }

    fn fail(&mut self, why: String) {
        if self.failures.len() < 20 {
            self.failures.push(why);
        }
    }

    fn write(&mut self, messages: Vec<Value>) {
        if std::env::var_os("SDFC_LSP_TRACE").is_some() {
            for m in &messages {
                let s = m.to_string();
                eprintln!("-> {}", &s[..s.len().min(300)]);
            }
        }
        self.transcript.extend(messages.iter().cloned());
        if self.dead {
            return;
        }
        if let Err(e) = self.server.write(&messages) {
            self.dead = true;
            self.fail(format!("the server stopped reading its input: {e}"));
        }
    }

    /// A request (not yet written): its id is recorded as outstanding.
    fn request(&mut self, method: &str, params: Value, doc: Option<usize>) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let version = doc.map_or(0, |d| self.docs[d].version);
        self.outstanding.insert(
            id,
            Sent {
                method: method.to_string(),
                doc,
                version,
                at: Instant::now(),
            },
        );
        self.sent.insert(id, method.to_string());
        self.tally.requests += 1;
        *self.tally.by_method.entry(method.to_string()).or_default() += 1;
        json!({ "jsonrpc": "2.0", "id": id, "method": method, "params": params })
    }

    fn notification(method: &str, params: Value) -> Value {
        json!({ "jsonrpc": "2.0", "method": method, "params": params })
    }

    /// Handles one message from the server.
    fn handle(&mut self, m: Value) {
        if std::env::var_os("SDFC_LSP_TRACE").is_some() {
            let s = m.to_string();
            eprintln!("<- {}", &s[..s.len().min(300)]);
        }
        let has_id = m.get("id").is_some_and(|i| !i.is_null());
        if let Some(method) = m["method"].as_str() {
            if has_id {
                self.fail(format!("the server sent a request: {m}"));
                return;
            }
            self.tally.notifications += 1;
            if method == "textDocument/publishDiagnostics" {
                let p = &m["params"];
                if let Some(d) = self.docs.iter_mut().find(|d| p["uri"] == d.uri.as_str()) {
                    d.diagnostics = p["diagnostics"].as_array().cloned().unwrap_or_default();
                }
            }
            if method == "window/showMessage" || method == "window/logMessage" {
                let text = m["params"]["message"].as_str().unwrap_or("");
                if text.contains("internal error") || text.contains("panicked") {
                    self.fail(format!("{method}: {text}"));
                }
            }
            return;
        }
        let Some(id) = m["id"].as_i64() else {
            self.fail(format!("a response without a numeric id: {m}"));
            return;
        };
        self.tally.responses += 1;
        *self.answered.entry(id).or_default() += 1;
        let Some(sent) = self.outstanding.remove(&id) else {
            let what = if self.sent.contains_key(&id) {
                "a second response"
            } else {
                "a response to a request never sent"
            };
            self.fail(format!("{what} (id {id}): {m}"));
            return;
        };
        let took = sent.at.elapsed();
        if took > self.tally.slowest_request.0 {
            self.tally.slowest_request = (took, sent.method.clone(), self.seed);
        }
        if let Some(e) = m.get("error") {
            let code = e["code"].as_i64().unwrap_or(0);
            *self.tally.errors.entry(code).or_default() += 1;
            if code == INTERNAL_ERROR {
                self.fail(format!("internal error for {} (id {id}): {e}", sent.method));
            }
            if code == REQUEST_CANCELLED {
                if self.cancelled.contains(&id) {
                    self.tally.cancelled_answers += 1;
                } else {
                    self.fail(format!(
                        "RequestCancelled for {} (id {id}), never cancelled",
                        sent.method
                    ));
                }
            }
            return;
        }
        if m.get("result").is_none() {
            self.fail(format!("a response with neither result nor error: {m}"));
            return;
        }
        let Some(d) = sent.doc else { return };
        let uri = self.docs[d].uri.clone();
        match sent.method.as_str() {
            "textDocument/codeAction" => {
                for a in m["result"].as_array().into_iter().flatten() {
                    let title = a["title"].as_str().unwrap_or("");
                    if title.starts_with("Place seeds automatically")
                        || title.starts_with("Add seeds to cover the gaps")
                    {
                        self.offered.push((a.clone(), d, sent.version));
                    } else if let Some(edits) = a["edit"]["changes"][&uri].as_array() {
                        self.edits.push((d, sent.version, edits.clone(), false));
                    }
                }
            }
            "codeAction/resolve" => match m["result"]["edit"]["changes"][&uri].as_array() {
                Some(edits) => {
                    self.tally.resolved_edits += 1;
                    self.edits.push((d, sent.version, edits.clone(), true));
                }
                None => self.fail(format!("a resolve without an edit: {m}")),
            },
            "textDocument/formatting" => {
                if let Some(edits) = m["result"].as_array() {
                    if !edits.is_empty() {
                        self.edits.push((d, sent.version, edits.clone(), false));
                    }
                }
            }
            _ => {}
        }
    }

    /// Handles what the server has sent so far.
    fn drain(&mut self) {
        loop {
            match self.server.messages.try_recv() {
                Ok(Incoming::Message(m)) => self.handle(m),
                Ok(Incoming::Bad(why)) => self.fail(why),
                Err(_) => return,
            }
        }
    }

    /// Waits for the next message (up to `wait`); false when none came.
    fn receive(&mut self, wait: Duration) -> bool {
        match self.server.messages.recv_timeout(wait) {
            Ok(Incoming::Message(m)) => {
                self.handle(m);
                true
            }
            Ok(Incoming::Bad(why)) => {
                self.fail(why);
                true
            }
            Err(mpsc::RecvTimeoutError::Timeout) => false,
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                if !self.dead {
                    self.dead = true;
                    let status = self.server.child.try_wait().ok().flatten();
                    self.fail(format!("the server closed its output (status {status:?})"));
                }
                false
            }
        }
    }

    fn over_cap(&self) -> bool {
        self.started.elapsed() > CAP
    }

    /// Waits until every outstanding request is answered (or the cap).
    fn settle(&mut self) {
        while !self.outstanding.is_empty() && !self.dead && !self.over_cap() {
            self.receive(Duration::from_millis(200));
        }
    }

    fn open(&mut self, d: usize) {
        let doc = &mut self.docs[d];
        doc.version += 1;
        doc.open = true;
        let m = Self::notification(
            "textDocument/didOpen",
            json!({ "textDocument": { "uri": doc.uri, "languageId": "sdf", "version": doc.version, "text": doc.text } }),
        );
        self.write(vec![m]);
    }

    fn change(&mut self, d: usize, text: String) -> Value {
        let doc = &mut self.docs[d];
        doc.version += 1;
        let old = std::mem::replace(&mut doc.text, text);
        doc.history.push(old);
        self.tally.changes += 1;
        Self::notification(
            "textDocument/didChange",
            json!({ "textDocument": { "uri": doc.uri, "version": doc.version }, "contentChanges": [{ "text": doc.text }] }),
        )
    }

    /// A new text for document `d`: a mutation, an insertion or a deletion, an undo,
    /// the original back, or nothing at all.
    fn edited(&mut self, d: usize) -> String {
        let text = self.docs[d].text.clone();
        let rng = &mut self.rng;
        match rng.below(20) {
            0..=3 => mutate::mild_mutation(rng, &text).1,
            4..=6 => mutate::rough_edit(rng, &text, &self.examples).1,
            7..=10 => {
                // Undo, as far back as two edits (the history keeps the undone text
                // too: an undo is an edit of its own).
                let h = &self.docs[d].history;
                let back = 1 + rng.below(2);
                h.len()
                    .checked_sub(back)
                    .map_or(text.clone(), |k| h[k].clone())
            }
            11..=14 => {
                // Typing: a character or a few.
                let at = mutate::boundary(rng, &text);
                let typed = *rng.pick(&[
                    "a", ".", "(", ")", ",", " ", "\n", "s", "sphere(", "0.5", ";", "let x = ",
                    "/", "\"", "é",
                ]);
                format!("{}{typed}{}", &text[..at], &text[at..])
            }
            15..=17 => {
                let (a, b) = mutate::range(rng, &text, 12);
                format!("{}{}", &text[..a], &text[b..])
            }
            18 => self.docs[d].original.clone(),
            _ => {
                if rng.chance(0.5) {
                    String::new()
                } else {
                    text.repeat(2)
                }
            }
        }
    }

    /// A request of a random kind about document `d` (open or not) at random places.
    fn random_request(&mut self, d: usize) -> Value {
        let total: usize = METHODS.iter().map(|m| m.1).sum();
        let mut pick = self.rng.below(total);
        let mut method = METHODS[0].0;
        for (m, w) in METHODS {
            if pick < *w {
                method = m;
                break;
            }
            pick -= w;
        }
        let text = self.docs[d].text.clone();
        let uri = self.docs[d].uri.clone();
        let doc = json!({ "uri": uri });
        let pos = random_position(&mut self.rng, &text);
        let range = {
            let other = random_position(&mut self.rng, &text);
            let (a, b) = (offset(&text, &pos), offset(&text, &other));
            if self.rng.chance(0.2) {
                json!({ "start": { "line": 0, "character": 0 }, "end": { "line": text.split('\n').count(), "character": 0 } })
            } else if a <= b {
                json!({ "start": pos, "end": other })
            } else {
                json!({ "start": other, "end": pos })
            }
        };
        let params = match method {
            "textDocument/documentSymbol" | "textDocument/semanticTokens/full" => {
                json!({ "textDocument": doc })
            }
            "textDocument/formatting" => {
                json!({ "textDocument": doc, "options": { "tabSize": 4, "insertSpaces": true } })
            }
            "textDocument/inlayHint" => json!({ "textDocument": doc, "range": range }),
            "textDocument/codeAction" => json!({
                "textDocument": doc, "range": range, "context": { "diagnostics": [] }
            }),
            "textDocument/references" => json!({
                "textDocument": doc, "position": pos, "context": { "includeDeclaration": self.rng.chance(0.5) }
            }),
            "textDocument/rename" => json!({
                "textDocument": doc, "position": pos, "newName": *self.rng.pick(&["renamed", "x", "sphere", "let", "1a", "é"])
            }),
            _ => json!({ "textDocument": doc, "position": pos }),
        };
        self.request(method, params, Some(d))
    }

    /// A code action over an atlas of document `d` (where seeds are offered).
    fn atlas_action(&mut self, d: usize) -> Value {
        let text = self.docs[d].text.clone();
        let uri = self.docs[d].uri.clone();
        let atlases: Vec<usize> = mutate::lex(&text)
            .iter()
            .filter(|(t, _)| matches!(t, sdfc::syntax::lexer::Token::Atlas))
            .map(|(_, s)| s.start)
            .collect();
        let at = if atlases.is_empty() {
            mutate::boundary(&mut self.rng, &text)
        } else {
            atlases[self.rng.below(atlases.len())] + 2
        };
        let pos = position(&text, at);
        self.request(
            "textDocument/codeAction",
            json!({ "textDocument": { "uri": uri }, "range": { "start": pos, "end": pos }, "context": { "diagnostics": [] } }),
            Some(d),
        )
    }

    /// A code action on a diagnostic last published for document `d`, as an editor
    /// asks for the quick fixes under the cursor.
    fn fix_action(&mut self, d: usize) -> Value {
        let diags = &self.docs[d].diagnostics;
        let diag = diags[self.rng.below(diags.len())].clone();
        let uri = self.docs[d].uri.clone();
        self.request(
            "textDocument/codeAction",
            json!({ "textDocument": { "uri": uri }, "range": diag["range"], "context": { "diagnostics": [diag] } }),
            Some(d),
        )
    }

    /// One random step of the session.
    fn step(&mut self) {
        let d = self.rng.below(self.docs.len());
        match self.rng.below(100) {
            0..=21 => {
                // One edit, or a burst of them (typing).
                let n = if self.rng.chance(0.3) {
                    2 + self.rng.below(4)
                } else {
                    1
                };
                let mut burst = Vec::new();
                for _ in 0..n {
                    if !self.docs[d].open {
                        break;
                    }
                    let t = self.edited(d);
                    burst.push(self.change(d, t));
                }
                // Sometimes a request right behind the edits, in the same write.
                if self.rng.chance(0.5) {
                    burst.push(self.random_request(d));
                }
                self.write(burst);
            }
            22..=61 => {
                let n = if self.rng.chance(0.3) {
                    2 + self.rng.below(5)
                } else {
                    1
                };
                let burst: Vec<Value> = (0..n).map(|_| self.random_request(d)).collect();
                self.write(burst);
            }
            62..=69 => {
                // A cancellation of an outstanding request (or of one long answered).
                let mut ids: Vec<i64> = self.outstanding.keys().copied().collect();
                ids.sort();
                let id = if ids.is_empty() || self.rng.chance(0.1) {
                    // Ids sent so far only: a client never cancels a request it has not sent.
                    1 + self.rng.below(self.next_id as usize - 1) as i64
                } else {
                    ids[self.rng.below(ids.len())]
                };
                if self.outstanding.contains_key(&id) {
                    self.cancelled.insert(id);
                }
                self.tally.cancels += 1;
                let m = Self::notification("$/cancelRequest", json!({ "id": id }));
                self.write(vec![m]);
            }
            70..=71 => {
                if self.docs[d].open {
                    self.docs[d].open = false;
                    self.tally.closes += 1;
                    let m = Self::notification(
                        "textDocument/didClose",
                        json!({ "textDocument": { "uri": self.docs[d].uri } }),
                    );
                    self.write(vec![m]);
                    // Reopened at once half of the time.
                    if self.rng.chance(0.5) {
                        self.open(d);
                    }
                } else {
                    if self.rng.chance(0.5) {
                        let t = self.edited(d);
                        self.docs[d].text = t;
                    }
                    self.open(d);
                }
            }
            72..=79 => {
                let m = if self.rng.chance(0.5) || self.docs[d].diagnostics.is_empty() {
                    self.atlas_action(d)
                } else {
                    self.fix_action(d)
                };
                self.write(vec![m]);
            }
            80..=86 => {
                // A resolve of an offered action, sometimes cancelled at once.
                if self.offered.is_empty() || self.resolves_left == 0 {
                    return;
                }
                // One offered on the text as it is now, when there is one.
                let fresh: Vec<usize> = (0..self.offered.len())
                    .filter(|&k| self.offered[k].2 == self.docs[self.offered[k].1].version)
                    .collect();
                let k = if fresh.is_empty() || self.rng.chance(0.2) {
                    self.rng.below(self.offered.len())
                } else {
                    fresh[self.rng.below(fresh.len())]
                };
                let (action, doc, _) = self.offered.swap_remove(k);
                self.resolves_left -= 1;
                self.tally.resolves += 1;
                let m = self.request("codeAction/resolve", action, Some(doc));
                let id = m["id"].as_i64().unwrap();
                let mut burst = vec![m];
                if self.rng.chance(0.25) {
                    self.cancelled.insert(id);
                    self.tally.cancels += 1;
                    burst.push(Self::notification("$/cancelRequest", json!({ "id": id })));
                }
                // A hover behind it, answered meanwhile.
                burst.push(self.random_request(doc));
                self.write(burst);
            }
            87..=92 => {
                // An edit the server offered, applied when its document is unchanged.
                let fresh: Vec<usize> = (0..self.edits.len())
                    .filter(|&k| self.edits[k].1 == self.docs[self.edits[k].0].version)
                    .collect();
                if fresh.is_empty() {
                    return;
                }
                let k = fresh[self.rng.below(fresh.len())];
                let (doc, version, edits, seeds) = self.edits.swap_remove(k);
                if self.docs[doc].version != version || !self.docs[doc].open {
                    return;
                }
                if let Some(t) = apply(&self.docs[doc].text, &edits) {
                    if seeds {
                        self.tally.applied_seeds += 1;
                    } else {
                        self.tally.applied_fixes += 1;
                    }
                    let m = self.change(doc, t);
                    self.write(vec![m]);
                }
            }
            _ => self.settle(),
        }
        self.drain();
        // Now and then a pause, so that the server's batches vary.
        if self.rng.chance(0.3) {
            std::thread::sleep(Duration::from_millis(self.rng.below(30) as u64));
            self.drain();
        }
    }

    /// Runs the session; returns its tally and failures.
    fn run(mut self) -> (Tally, Vec<String>, Vec<Value>) {
        let root = url::Url::from_file_path(mutate::examples_dir())
            .unwrap()
            .to_string();
        let init = self.request(
            "initialize",
            json!({ "processId": null, "rootUri": root, "capabilities": {} }),
            None,
        );
        self.write(vec![init]);
        self.settle();
        let initialized = Self::notification("initialized", json!({}));
        self.write(vec![initialized]);
        // One or two examples, as they are or mutated.
        let n = 1 + self.rng.below(2);
        let mut names = HashSet::new();
        for _ in 0..n {
            let c = mutate::case(self.rng.next(), &self.examples);
            if !names.insert(c.example.clone()) {
                continue;
            }
            let path = mutate::examples_dir().join(&c.example);
            let original = std::fs::read_to_string(&path).unwrap();
            let text = if self.rng.chance(0.5) {
                original.clone()
            } else {
                c.text
            };
            self.docs.push(Doc {
                uri: url::Url::from_file_path(&path).unwrap().to_string(),
                original,
                text,
                version: 0,
                open: false,
                diagnostics: Vec::new(),
                history: Vec::new(),
            });
            let d = self.docs.len() - 1;
            self.open(d);
        }
        let steps = 20 + self.rng.below(100);
        for _ in 0..steps {
            if self.dead || self.over_cap() {
                break;
            }
            self.step();
        }
        // Every request answered, then shutdown and exit; in some sessions the shutdown
        // comes at once, while requests are still outstanding (a resolve placing seeds
        // on its thread may then never be answered: the server exits first).
        self.hasty = self.rng.chance(0.15);
        if !self.hasty {
            self.settle();
        }
        let shutdown = self.request("shutdown", Value::Null, None);
        let shutdown_id = shutdown["id"].as_i64().unwrap();
        self.write(vec![shutdown]);
        while self.outstanding.contains_key(&shutdown_id) && !self.dead && !self.over_cap() {
            self.receive(Duration::from_millis(200));
        }
        self.finish(shutdown_id)
    }

    fn finish(mut self, shutdown_id: i64) -> (Tally, Vec<String>, Vec<Value>) {
        if self.answered.get(&shutdown_id) != Some(&1) && !self.dead {
            self.fail("shutdown was not answered".into());
        }
        match self.server.peak_rss_kb() {
            Some(kb) => {
                self.tally.peak_rss_kb = kb;
                self.tally.peak_rss_seed = self.seed;
                if kb > MAX_RSS_KB {
                    self.fail(format!("peak RSS {kb} kB is over 1 GB"));
                }
            }
            None => self.fail("no /proc status for the server".into()),
        }
        let exit = Self::notification("exit", Value::Null);
        self.write(vec![exit]);
        let exit_sent = Instant::now();
        let status = loop {
            match self.server.child.try_wait() {
                Ok(Some(s)) => break Some(s),
                Ok(None) if self.over_cap() => break None,
                Ok(None) => std::thread::sleep(Duration::from_millis(10)),
                Err(e) => {
                    self.fail(format!("waiting for the server: {e}"));
                    break None;
                }
            }
        };
        let exit_took = exit_sent.elapsed();
        if exit_took > self.tally.slowest_exit {
            self.tally.slowest_exit = exit_took;
        }
        match status {
            Some(s) if s.code() == Some(0) => {}
            Some(s) => self.fail(format!("the server exited with {s:?}")),
            None => {
                self.fail(format!(
                    "the server was still running {} s after exit",
                    CAP.as_secs()
                ));
                let _ = self.server.child.kill();
                let _ = self.server.child.wait();
            }
        }
        // What it wrote before it ended: every message, to count each response once.
        let end = Instant::now() + Duration::from_secs(5);
        loop {
            match self
                .server
                .messages
                .recv_timeout(Duration::from_millis(100))
            {
                Ok(Incoming::Message(m)) => self.handle(m),
                Ok(Incoming::Bad(why)) => self.fail(why),
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
                Err(mpsc::RecvTimeoutError::Timeout) if Instant::now() > end => break,
                Err(mpsc::RecvTimeoutError::Timeout) => {}
            }
        }
        // (After a hasty shutdown, a resolve may go unanswered: the server exited.)
        let abandoned = |m: &str| self.hasty && m == "codeAction/resolve";
        self.tally.abandoned += self
            .sent
            .iter()
            .filter(|(id, m)| !self.answered.contains_key(id) && abandoned(m))
            .count();
        let mut unanswered: Vec<(i64, String)> = self
            .sent
            .iter()
            .filter(|(id, m)| !self.answered.contains_key(id) && !abandoned(m))
            .map(|(id, m)| (*id, m.clone()))
            .collect();
        unanswered.sort();
        if !unanswered.is_empty() {
            self.fail(format!("requests never answered: {unanswered:?}"));
        }
        let twice: Vec<i64> = self
            .answered
            .iter()
            .filter(|(_, n)| **n > 1)
            .map(|(id, _)| *id)
            .collect();
        if !twice.is_empty() {
            self.fail(format!("requests answered more than once: {twice:?}"));
        }
        let stderr = self.server.stderr.lock().unwrap().clone();
        for line in stderr.lines() {
            if line.contains("internal error") || line.contains("panicked") {
                self.fail(format!("stderr: {line}"));
            }
        }
        self.tally.hasty = usize::from(self.hasty);
        let took = self.started.elapsed();
        self.tally.slowest = took;
        self.tally.slowest_seed = self.seed;
        (self.tally, self.failures, self.transcript)
    }
}

/// Runs session `seed`; writes its transcript when it fails.
fn session(seed: u64, examples: &[(String, String)], slow_fails: bool) -> (Tally, Vec<String>) {
    let s = Session::new(seed, examples);
    let (tally, mut failures, transcript) = s.run();
    if slow_fails && tally.slowest > SLOW {
        failures.push(format!(
            "the session took {:.1} s (over {} s); its slowest request: {} answered after {:.1} s",
            tally.slowest.as_secs_f64(),
            SLOW.as_secs(),
            tally.slowest_request.1,
            tally.slowest_request.0.as_secs_f64()
        ));
    }
    if !failures.is_empty() {
        let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("lsp-session-{seed}.txt"));
        let framed: String = transcript.iter().map(frame).collect();
        let _ = std::fs::write(&path, framed);
        failures.push(format!("messages sent: {}", path.display()));
    }
    (tally, failures)
}

/// Runs sessions `base .. base + count` (on `jobs` threads); prints the figures and
/// returns the failures, by seed.
fn sessions(base: u64, count: u64, jobs: usize, slow_fails: bool) -> Vec<(u64, Vec<String>)> {
    let examples = mutate::examples();
    let started = Instant::now();
    let next = Mutex::new(base);
    let results: Mutex<(Tally, Vec<(u64, Vec<String>)>)> = Mutex::new(Default::default());
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1) {
            s.spawn(|| loop {
                let seed = {
                    let mut n = next.lock().unwrap();
                    if *n >= base + count {
                        return;
                    }
                    *n += 1;
                    *n - 1
                };
                let (tally, failures) = session(seed, &examples, slow_fails);
                if !failures.is_empty() {
                    eprintln!("FAILED session {seed}:\n  {}", failures.join("\n  "));
                }
                let mut r = results.lock().unwrap();
                r.0.add(&tally);
                if !failures.is_empty() {
                    r.1.push((seed, failures));
                }
            });
        }
    });
    let (t, mut failed) = results.into_inner().unwrap();
    failed.sort_by_key(|f| f.0);
    eprintln!(
        "lsp sessions: {} (seeds {base}..{}) in {:.1} s, {} failed",
        t.sessions,
        base + count,
        started.elapsed().as_secs_f64(),
        failed.len()
    );
    eprintln!(
        "  requests sent {}, responses {}, notifications {}; didChange {}, didClose {}; cancels sent {} (answered RequestCancelled {}); resolves {} (with an edit {}); applied: {} fixes or formattings, {} placed seeds",
        t.requests,
        t.responses,
        t.notifications,
        t.changes,
        t.closes,
        t.cancels,
        t.cancelled_answers,
        t.resolves,
        t.resolved_edits,
        t.applied_fixes,
        t.applied_seeds
    );
    eprintln!(
        "  sessions shut down with requests outstanding {} (resolves left unanswered at exit {}); longest exit {:.3} s",
        t.hasty,
        t.abandoned,
        t.slowest_exit.as_secs_f64()
    );
    eprintln!("  requests by method: {:?}", t.by_method);
    eprintln!("  error responses by code: {:?}", t.errors);
    eprintln!(
        "  slowest session {:.2} s (seed {}); slowest request {} answered after {:.2} s (seed {}); peak server RSS (VmHWM) {:.1} MiB (seed {})",
        t.slowest.as_secs_f64(),
        t.slowest_seed,
        t.slowest_request.1,
        t.slowest_request.0.as_secs_f64(),
        t.slowest_request.2,
        t.peak_rss_kb as f64 / 1024.0,
        t.peak_rss_seed
    );
    failed
}

fn assert_none(failed: &[(u64, Vec<String>)]) {
    if failed.is_empty() {
        return;
    }
    let list: Vec<String> = failed
        .iter()
        .map(|(seed, f)| format!("session {seed}:\n  {}", f.join("\n  ")))
        .collect();
    panic!(
        "{} sessions failed (SDFC_LSP_SEED=N … one_session runs one):\n{}",
        failed.len(),
        list.join("\n")
    );
}

/// The in-suite run: 20 sessions (about 25 s in release on two busy cores; seed
/// placement with its stretch target costs about three times what coverage alone did,
/// so the in-suite count went from 50 to 20 to keep CI under its 15 minutes).
#[test]
fn random_sessions_over_the_pipe() {
    let failed = sessions(0, 20, 1, false);
    assert_none(&failed);
}

/// The long run: 500 sessions (`SDFC_LSP_SESSIONS`; `SDFC_LSP_JOBS` at a time), each
/// also failing over 20 s.
#[test]
#[ignore]
fn many_random_sessions_over_the_pipe() {
    let env = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|n| n.parse().ok())
            .unwrap_or(d)
    };
    let failed = sessions(
        IGNORED_BASE,
        env("SDFC_LSP_SESSIONS", 500),
        env("SDFC_LSP_JOBS", 1) as usize,
        true,
    );
    assert_none(&failed);
}

/// `SDFC_LSP_SEED=N`: session N alone (nothing without the variable).
#[test]
fn one_session() {
    let Some(seed) = std::env::var("SDFC_LSP_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
    else {
        return;
    };
    let failed = sessions(seed, 1, 1, true);
    assert_none(&failed);
}
