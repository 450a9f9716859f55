//! `sdfc bench --lsp-latency FILE`: the language server's didChange → publishDiagnostics
//! latency, measured in process over an in-memory connection (the same server loop as
//! `sdfc lsp`, without the stdio transport).

use super::read_source;
use lsp_server::{Connection, Message, Notification, Request, RequestId};
use serde_json::json;
use std::path::Path;
use std::process::ExitCode;
use std::time::{Duration, Instant};

type Error = Box<dyn std::error::Error + Send + Sync>;

fn send_note(conn: &Connection, method: &str, params: serde_json::Value) -> Result<(), Error> {
    conn.sender.send(Message::Notification(Notification::new(
        method.to_string(),
        params,
    )))?;
    Ok(())
}

/// Waits for the diagnostics of `version`; gives their count and whether they are the
/// front end's stage (a full set follows).
fn wait_diagnostics(conn: &Connection, version: i32) -> Result<(usize, bool), Error> {
    loop {
        match conn.receiver.recv_timeout(Duration::from_secs(600))? {
            Message::Notification(n)
                if n.method == "textDocument/publishDiagnostics"
                    && n.params["version"] == version =>
            {
                let count = n.params["diagnostics"].as_array().map_or(0, Vec::len);
                return Ok((count, n.params["sdfcStage"] == "front"));
            }
            _ => {}
        }
    }
}

/// Waits for both stages of `version`'s diagnostics (the front end's, then the full set;
/// one publish when the front end found errors); the times from `start` to each, and
/// the final count.
fn wait_stages(
    conn: &Connection,
    version: i32,
    start: Instant,
) -> Result<(Duration, Duration, usize), Error> {
    let (count, partial) = wait_diagnostics(conn, version)?;
    let front = start.elapsed();
    if !partial {
        return Ok((front, front, count));
    }
    let (count, _) = wait_diagnostics(conn, version)?;
    Ok((front, start.elapsed(), count))
}

/// The front end's and the full analysis's latencies of each edit.
pub(super) struct Latencies {
    pub front: Vec<Duration>,
    pub full: Vec<Duration>,
}

/// The time between the last publish of one edit and the next edit.
pub(super) const EDIT_INTERVAL: Duration = Duration::from_millis(100);

/// What each measured edit changes.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Edit {
    /// A comment added at the end, as when typing one: only trivia changes, so the
    /// server carries the last full analysis's back end over (`sdfc::incremental`).
    Comment,
    /// An unused shape added at the end: the tokens change and code generation emits
    /// the shape, so the whole analysis runs again (front end, atlases' geometry, code
    /// generation, naga).
    Token,
}

impl Edit {
    fn apply(self, text: &str, i: i32) -> String {
        match self {
            Edit::Comment => format!("{text}\n// edit {i}\n"),
            Edit::Token => {
                format!("{text}\nlet sdfc_bench_edit = sphere(1).translate([{i}, 0, 0]);\n")
            }
        }
    }
}

pub(super) fn measure(
    path: &Path,
    text: &str,
    edits: u32,
    kind: Edit,
) -> Result<(Latencies, usize), Error> {
    // A real `file:` URI of an absolute path, percent-encoded as editors send it: a
    // path with a space or a bracket written raw is no URI, and the server would never
    // answer for it (the file need not exist: `--scale` measures generated text).
    let abs = std::fs::canonicalize(path).or_else(|_| std::path::absolute(path))?;
    let uri = url::Url::from_file_path(&abs)
        .map(String::from)
        .map_err(|()| format!("{} has no file: URI", abs.display()))?;
    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || sdfc::lsp::serve(server).map_err(|e| e.to_string()));
    client.sender.send(Message::Request(Request::new(
        RequestId::from(1),
        String::from("initialize"),
        json!({ "capabilities": {} }),
    )))?;
    loop {
        if let Message::Response(_) = client.receiver.recv_timeout(Duration::from_secs(60))? {
            break;
        }
    }
    send_note(&client, "initialized", json!({}))?;
    send_note(
        &client,
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": uri, "languageId": "sdf", "version": 1, "text": text } }),
    )?;
    let (_, _, mut count) = wait_stages(&client, 1, Instant::now())?;
    let mut times = Latencies {
        front: Vec::new(),
        full: Vec::new(),
    };
    for i in 0..edits as i32 {
        // Edits come a typist's keystroke apart, not back to back: what the server does
        // after publishing (keeping the analysis, freeing the last one) is not charged
        // to the next edit.
        std::thread::sleep(EDIT_INTERVAL);
        let changed = kind.apply(text, i);
        let version = i + 2;
        let start = Instant::now();
        send_note(
            &client,
            "textDocument/didChange",
            json!({ "textDocument": { "uri": uri, "version": version }, "contentChanges": [{ "text": changed }] }),
        )?;
        let (front, full, n) = wait_stages(&client, version, start)?;
        times.front.push(front);
        times.full.push(full);
        count = n;
    }
    client.sender.send(Message::Request(Request::new(
        RequestId::from(2),
        String::from("shutdown"),
        json!(null),
    )))?;
    send_note(&client, "exit", json!(null))?;
    drop(client);
    let _ = thread.join();
    Ok((times, count))
}

pub fn run(path: &Path, edits: u32, json: Option<&Path>) -> ExitCode {
    let text = match read_source(path) {
        Ok(t) => t.text,
        Err(e) => {
            eprintln!("error: cannot read {}: {e}", path.display());
            return ExitCode::from(super::exit::USAGE);
        }
    };
    let mut measured = Vec::new();
    for kind in [Edit::Token, Edit::Comment] {
        match measure(path, &text, edits.max(1), kind) {
            Ok(r) => measured.push((kind, r)),
            Err(e) => {
                eprintln!("error: the language server failed: {e}");
                return ExitCode::from(super::exit::SCENE);
            }
        }
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let count = measured.first().map_or(0, |(_, (_, n))| *n);
    println!(
        "scene:     {} ({} bytes, {} diagnostics)",
        path.display(),
        text.len(),
        count
    );
    let mut report = serde_json::json!({
        "bench": "lsp latency",
        "scene": path.display().to_string(),
        "edits": edits.max(1),
        "diagnostics": count,
    });
    for (kind, (times, _)) in measured {
        let (prefix, title) = match kind {
            Edit::Token => (
                "",
                "a token edit (an unused shape added): the whole analysis",
            ),
            Edit::Comment => (
                "comment_",
                "a comment edit (trivia only): the back end carried over",
            ),
        };
        println!(
            "didChange → publishDiagnostics over {} edits, {title}:",
            times.full.len()
        );
        for (name, what, list) in [
            (
                "front",
                "the front end's (parse, names, types)",
                times.front,
            ),
            (
                "full",
                "the full set (also the atlases' geometry, code generation, naga)",
                times.full,
            ),
        ] {
            let q = quantiles(list);
            println!(
                "  {what}: p50 {:.2} ms   p95 {:.2} ms   min {:.2} ms   max {:.2} ms",
                ms(q[1]),
                ms(q[2]),
                ms(q[0]),
                ms(q[3])
            );
            report[format!("{prefix}{name}_p50_ms")] = ms(q[1]).into();
            report[format!("{prefix}{name}_p95_ms")] = ms(q[2]).into();
            report[format!("{prefix}{name}_min_ms")] = ms(q[0]).into();
            report[format!("{prefix}{name}_max_ms")] = ms(q[3]).into();
        }
    }
    if let Some(out) = json {
        if let Err(code) = super::report::write_json(out, &report) {
            return code;
        }
    }
    ExitCode::SUCCESS
}

/// Min, p50, p95 and max of a non-empty list.
pub(super) fn quantiles(mut v: Vec<Duration>) -> [Duration; 4] {
    v.sort();
    let pick = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    [v[0], pick(0.5), pick(0.95), v[v.len() - 1]]
}
