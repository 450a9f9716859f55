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

/// Waits for the diagnostics of `version`; gives their count.
fn wait_diagnostics(conn: &Connection, version: i32) -> Result<usize, Error> {
    loop {
        match conn.receiver.recv_timeout(Duration::from_secs(600))? {
            Message::Notification(n)
                if n.method == "textDocument/publishDiagnostics"
                    && n.params["version"] == version =>
            {
                return Ok(n.params["diagnostics"].as_array().map_or(0, |a| a.len()));
            }
            _ => {}
        }
    }
}

pub(super) fn measure(
    path: &Path,
    text: &str,
    edits: u32,
) -> Result<(Vec<Duration>, usize), Error> {
    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || sdfc::lsp::serve(server).map_err(|e| e.to_string()));
    let abs = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let uri = format!("file://{}", abs.display());
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
    let count = wait_diagnostics(&client, 1)?;
    let mut times = Vec::new();
    for i in 0..edits as i32 {
        // An edit that changes the text but not the scene: a comment at the end, as when
        // typing; each one is a full re-analysis.
        let changed = format!("{text}\n// edit {i}\n");
        let version = i + 2;
        let start = Instant::now();
        send_note(
            &client,
            "textDocument/didChange",
            json!({ "textDocument": { "uri": uri, "version": version }, "contentChanges": [{ "text": changed }] }),
        )?;
        wait_diagnostics(&client, version)?;
        times.push(start.elapsed());
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
    let (mut times, count) = match measure(path, &text, edits.max(1)) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: the language server failed: {e}");
            return ExitCode::from(super::exit::SCENE);
        }
    };
    times.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let pick = |q: f64| times[((times.len() - 1) as f64 * q).round() as usize];
    println!(
        "scene:     {} ({} bytes, {} diagnostics)",
        path.display(),
        text.len(),
        count
    );
    println!(
        "didChange → publishDiagnostics over {} edits (parse, check, compile-time geometry, code generation, naga):",
        times.len()
    );
    println!(
        "p50 {:.2} ms   p95 {:.2} ms   min {:.2} ms   max {:.2} ms",
        ms(pick(0.5)),
        ms(pick(0.95)),
        ms(times[0]),
        ms(times[times.len() - 1])
    );
    if let Some(out) = json {
        let report = serde_json::json!({
            "bench": "lsp latency",
            "scene": path.display().to_string(),
            "edits": times.len(),
            "diagnostics": count,
            "p50_ms": ms(pick(0.5)),
            "p95_ms": ms(pick(0.95)),
            "min_ms": ms(times[0]),
            "max_ms": ms(times[times.len() - 1]),
        });
        if let Err(code) = super::bench::write_json(out, &report) {
            return code;
        }
    }
    ExitCode::SUCCESS
}
