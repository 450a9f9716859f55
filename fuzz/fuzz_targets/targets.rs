//! The bodies of the fuzz targets, as plain functions: the libFuzzer binaries in this
//! folder call them, and `tests/fuzz_smoke.rs` of the main crate runs each over the
//! seed corpora (the examples and the UI cases) in every `cargo test`, on stable.
#![allow(dead_code)]

use lsp_server::{Connection, Message, Notification, Request, RequestId};
use serde_json::json;
use std::path::Path;

/// The input as text, the way `sdfc check` reads a file: invalid UTF-8 is replaced.
pub fn text(data: &[u8]) -> String {
    sdfc::syntax::decode(data).0
}

/// Every span of every diagnostic lies inside the text, on character boundaries.
pub fn assert_spans(text: &str, diags: &[sdfc::Diagnostic]) {
    for d in diags {
        let spans = d
            .primary
            .iter()
            .chain(&d.secondary)
            .map(|l| l.span)
            .chain(d.fixes.iter().flat_map(|f| f.edits.iter().map(|e| e.span)));
        for s in spans {
            assert!(
                s.start <= s.end
                    && s.end <= text.len()
                    && text.is_char_boundary(s.start)
                    && text.is_char_boundary(s.end),
                "{}: span {}..{} outside the text of {} bytes",
                d.code,
                s.start,
                s.end,
                text.len()
            );
        }
    }
    // Rendering the diagnostics must not panic either.
    let _ = sdfc::diagnostic::render("fuzz.sdf", text, diags, false);
}

/// The lexer and parser: never a panic, every span inside the text.
pub fn parse(data: &[u8]) {
    let text = text(data);
    let mut diags = Vec::new();
    let _ = sdfc::syntax::lexer::lex(&text, &mut diags);
    let mut diags = Vec::new();
    let _parsed = sdfc::syntax::parse(&text, &mut diags);
    assert_spans(&text, &diags);
}

/// The whole check (front end, atlas geometry, lowering): never a panic, every span
/// inside the text. `base` is the folder texture paths are relative to.
pub fn check(data: &[u8], base: &Path) {
    let text = text(data);
    let analysis = sdfc::driver::check(&text, Some(base));
    assert_spans(&text, &analysis.diagnostics);
}

/// The check, code generation and naga validation: never a panic, never an internal
/// compiler error (E0900: naga rejected generated code), every span inside the text.
pub fn check_all(data: &[u8], base: &Path) {
    let text = text(data);
    let analysis = sdfc::driver::check_all(&text, Some(base));
    assert_spans(&text, &analysis.diagnostics);
    if let Some(d) = analysis
        .diagnostics
        .iter()
        .find(|d| d.code == sdfc::codes::E_INTERNAL)
    {
        panic!(
            "internal compiler error: {} / {}",
            d.message,
            d.notes.join(" / ")
        );
    }
}

fn tokens(text: &str) -> Vec<String> {
    let mut diags = Vec::new();
    sdfc::syntax::lexer::lex(text, &mut diags)
        .tokens
        .iter()
        .map(|(t, _)| format!("{t:?}"))
        .collect()
}

/// The formatter: formatting twice changes nothing, and formatting never changes the
/// token stream (comments aside, which it keeps but the lexer sets apart).
pub fn format(data: &[u8]) {
    let text = text(data);
    let Ok(once) = sdfc::ide::format::format(&text) else {
        return;
    };
    let twice = sdfc::ide::format::format(&once)
        .unwrap_or_else(|d| panic!("the formatted text has errors: {d:?}\n{once}"));
    assert_eq!(once, twice, "formatting twice changed the text");
    assert_eq!(
        tokens(&text),
        tokens(&once),
        "formatting changed the tokens:\n{text}\n---\n{once}"
    );
}

/// The language server's message handling. The input is the server's standard input:
/// base-protocol framing read by `sdfc::lsp::transport::read_loop`, whose messages go,
/// after an `initialize` handshake, to `sdfc::lsp::serve` over an in-memory connection.
/// Inputs that start with `#` instead are a document: the bytes after it are opened
/// as a scene and every request the server offers is made at positions taken from the
/// text, so the fuzzer reaches the editor features without having to invent JSON.
/// Never a panic, and the server ends when the client hangs up.
pub fn lsp(data: &[u8]) {
    let messages: Vec<Message> = if let Some(rest) = data.strip_prefix(b"#") {
        document_messages(&text(rest))
    } else {
        let (tx, rx) = crossbeam_channel::unbounded();
        let _ = sdfc::lsp::transport::read_loop(&mut &data[..], &tx);
        drop(tx);
        rx.try_iter().collect()
    };
    let (server, client) = Connection::memory();
    let handle = std::thread::spawn(move || sdfc::lsp::serve(server));
    let send = |m: Message| {
        let _ = client.sender.send(m);
    };
    send(Message::Request(Request::new(
        RequestId::from(1),
        "initialize".into(),
        json!({ "capabilities": {}, "rootUri": "file:///fuzz" }),
    )));
    send(Message::Notification(Notification::new(
        "initialized".into(),
        json!({}),
    )));
    for m in messages {
        send(m);
    }
    let Connection { sender, receiver } = client;
    drop(sender);
    // Answers are drained while the server works, so it never blocks on a full channel.
    let drain = std::thread::spawn(move || receiver.iter().count());
    match handle.join() {
        Ok(_) => {}
        Err(e) => std::panic::resume_unwind(e),
    }
    let _ = drain.join();
}

const URI: &str = "file:///fuzz/scene.sdf";

fn document_messages(text: &str) -> Vec<Message> {
    let mut out = vec![Message::Notification(Notification::new(
        "textDocument/didOpen".into(),
        json!({ "textDocument": { "uri": URI, "languageId": "sdf", "version": 1, "text": text } }),
    ))];
    let lines: Vec<&str> = text.split('\n').collect();
    let doc = json!({ "uri": URI });
    let mut id = 100;
    let mut req = |method: &str, params: serde_json::Value, out: &mut Vec<Message>| {
        id += 1;
        out.push(Message::Request(Request::new(
            RequestId::from(id),
            method.into(),
            params,
        )));
    };
    for method in [
        "textDocument/formatting",
        "textDocument/semanticTokens/full",
        "textDocument/documentSymbol",
        "textDocument/inlayHint",
    ] {
        let params = json!({
            "textDocument": doc,
            "options": { "tabSize": 4, "insertSpaces": true },
            "range": { "start": { "line": 0, "character": 0 }, "end": { "line": lines.len(), "character": 0 } },
        });
        req(method, params, &mut out);
    }
    // A few positions: line starts, ends and middles (in UTF-16 units, and past them).
    for (line, l) in lines.iter().enumerate().take(8) {
        let n = l.encode_utf16().count();
        for character in [0, n / 2, n, n + 3] {
            let pos = json!({ "line": line, "character": character });
            let at = json!({ "textDocument": doc, "position": pos });
            for method in [
                "textDocument/hover",
                "textDocument/definition",
                "textDocument/references",
                "textDocument/completion",
                "textDocument/signatureHelp",
                "textDocument/prepareRename",
            ] {
                let mut p = at.clone();
                p["context"] = json!({ "includeDeclaration": true });
                req(method, p, &mut out);
            }
            let mut p = at.clone();
            p["newName"] = json!("renamed");
            req("textDocument/rename", p, &mut out);
            req(
                "textDocument/codeAction",
                json!({
                    "textDocument": doc,
                    "range": { "start": pos, "end": pos },
                    "context": { "diagnostics": [] },
                }),
                &mut out,
            );
        }
    }
    // An edit: the text with its last line dropped, then closed.
    let edited = text.rsplit_once('\n').map_or("", |(a, _)| a);
    out.push(Message::Notification(Notification::new(
        "textDocument/didChange".into(),
        json!({ "textDocument": { "uri": URI, "version": 2 }, "contentChanges": [{ "text": edited }] }),
    )));
    out.push(Message::Notification(Notification::new(
        "textDocument/didClose".into(),
        json!({ "textDocument": { "uri": URI } }),
    )));
    out
}
