//! The language server's message handling. The input is the server's standard input:
//! base-protocol framing read by `sdfc::lsp::transport::read_loop`, whose messages go,
//! after an `initialize` handshake, to `sdfc::lsp::serve` over an in-memory connection.
//! Inputs that start with `#` instead are a document: the bytes after it are opened
//! as a scene and every request the server offers is made at positions taken from the
//! text, so the fuzzer reaches the editor features without having to invent JSON.
//! Never a panic, and the server ends when the client hangs up.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lsp_server::{Connection, Message, Notification, Request, RequestId};
use serde_json::json;

#[path = "common.rs"]
mod common;

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

fuzz_target!(|data: &[u8]| {
    let messages: Vec<Message> = if let Some(rest) = data.strip_prefix(b"#") {
        document_messages(&common::text(rest))
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
});
