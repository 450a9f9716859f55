//! The language server end to end: over an in-memory connection, and the real
//! `sdfc lsp` binary over stdio.

use lsp_server::{Connection, Message, Notification, Request, RequestId};
use serde_json::{json, Value};
use std::time::Duration;

struct Client {
    conn: Connection,
    next: i32,
}

impl Client {
    fn start() -> (Client, std::thread::JoinHandle<()>) {
        let (server, client) = Connection::memory();
        let handle = std::thread::spawn(move || sdfc::lsp::serve(server).unwrap());
        let mut c = Client {
            conn: client,
            next: 1,
        };
        let caps = c.request("initialize", json!({ "capabilities": {} }));
        let caps = &caps["capabilities"];
        assert_eq!(caps["hoverProvider"], true);
        assert_eq!(caps["documentFormattingProvider"], true);
        assert_eq!(caps["renameProvider"]["prepareProvider"], true);
        assert_eq!(
            caps["completionProvider"]["triggerCharacters"],
            json!(["."])
        );
        assert_eq!(
            caps["signatureHelpProvider"]["triggerCharacters"],
            json!(["(", ","])
        );
        assert_eq!(caps["semanticTokensProvider"]["full"], true);
        assert_eq!(
            caps["semanticTokensProvider"]["legend"]["tokenTypes"],
            json!([
                "keyword",
                "number",
                "string",
                "comment",
                "operator",
                "function",
                "variable",
                "namespace",
                "enumMember",
                "struct",
                "parameter",
                "property"
            ])
        );
        c.notify("initialized", json!({}));
        (c, handle)
    }

    fn request(&mut self, method: &str, params: Value) -> Value {
        self.try_request(method, params)
            .unwrap_or_else(|e| panic!("{method}: {e:?}"))
    }

    fn try_request(
        &mut self,
        method: &str,
        params: Value,
    ) -> Result<Value, lsp_server::ResponseError> {
        let id = RequestId::from(self.next);
        self.next += 1;
        self.conn
            .sender
            .send(Message::Request(Request::new(
                id.clone(),
                method.to_string(),
                params,
            )))
            .unwrap();
        loop {
            match self
                .conn
                .receiver
                .recv_timeout(Duration::from_secs(30))
                .unwrap()
            {
                Message::Response(r) if r.id == id => return r.response_result,
                _ => {}
            }
        }
    }

    fn notify(&self, method: &str, params: Value) {
        self.conn
            .sender
            .send(Message::Notification(Notification::new(
                method.to_string(),
                params,
            )))
            .unwrap();
    }

    fn diagnostics(&self) -> Value {
        loop {
            if let Message::Notification(n) = self
                .conn
                .receiver
                .recv_timeout(Duration::from_secs(30))
                .unwrap()
            {
                if n.method == "textDocument/publishDiagnostics" {
                    return n.params;
                }
            }
        }
    }
}

const URI: &str = "file:///tmp/sdfc-lsp-test/scene.sdf";

/// Shuts the server down as a client does, and waits for it to exit.
fn stop(mut c: Client, handle: std::thread::JoinHandle<()>) {
    c.request("shutdown", json!(null));
    c.notify("exit", json!(null));
    handle.join().unwrap();
}

#[path = "lsp/actions.rs"]
mod actions;
#[path = "lsp/editing.rs"]
mod editing;

#[test]
fn diagnostics_hover_definition_references_symbols() {
    let (mut c, handle) = Client::start();
    // Two errors: an unknown function and a misspelled name, on lines 1 and 2 (0-based).
    let broken = "let radius = 0.5;\nlet ball = spher(radius);\nlet ring = torus(radus, 0.1);\nrender ball | ring;\n";
    c.notify("textDocument/didOpen", json!({ "textDocument": { "uri": URI, "languageId": "sdf", "version": 1, "text": broken } }));
    let d = c.diagnostics();
    assert_eq!(d["version"], 1);
    let list = d["diagnostics"].as_array().unwrap();
    assert_eq!(list.len(), 2, "{list:?}");
    assert_eq!(list[0]["code"], "E0103");
    assert_eq!(
        list[0]["range"],
        json!({ "start": { "line": 1, "character": 11 }, "end": { "line": 1, "character": 16 } })
    );
    assert_eq!(list[1]["code"], "E0100");
    assert_eq!(
        list[1]["range"]["start"],
        json!({ "line": 2, "character": 17 })
    );
    assert!(list[1]["message"]
        .as_str()
        .unwrap()
        .contains("did you mean `radius`?"));

    let fixed = "let radius = 0.5;\nlet ball = sphere(radius);\nlet ring = torus(radius, 0.1);\nrender ball | ring;\n";
    c.notify("textDocument/didChange", json!({ "textDocument": { "uri": URI, "version": 2 }, "contentChanges": [{ "text": fixed }] }));
    let d = c.diagnostics();
    assert_eq!(d["version"], 2);
    assert_eq!(d["diagnostics"], json!([]));

    let hover = c.request(
        "textDocument/hover",
        json!({ "textDocument": { "uri": URI }, "position": { "line": 1, "character": 13 } }),
    );
    assert!(
        hover["contents"]["value"]
            .as_str()
            .unwrap()
            .contains("sphere(radius: float = 1) -> shape"),
        "{hover}"
    );
    let def = c.request(
        "textDocument/definition",
        json!({ "textDocument": { "uri": URI }, "position": { "line": 3, "character": 8 } }),
    );
    assert_eq!(def["range"]["start"], json!({ "line": 1, "character": 4 }));
    let refs = c.request("textDocument/references", json!({ "textDocument": { "uri": URI }, "position": { "line": 0, "character": 5 }, "context": { "includeDeclaration": true } }));
    assert_eq!(refs.as_array().unwrap().len(), 3);
    let symbols = c.request(
        "textDocument/documentSymbol",
        json!({ "textDocument": { "uri": URI } }),
    );
    let names: Vec<&str> = symbols
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["radius", "ball", "ring", "render"]);

    // Garbage and unknown requests are answered with errors, not crashes.
    let id = RequestId::from(99);
    c.conn
        .sender
        .send(Message::Request(Request::new(
            id.clone(),
            String::from("textDocument/hover"),
            json!({ "nonsense": true }),
        )))
        .unwrap();
    c.conn
        .sender
        .send(Message::Request(Request::new(
            RequestId::from(100),
            String::from("sdfc/unknown"),
            json!({}),
        )))
        .unwrap();
    let mut errors = 0;
    while errors < 2 {
        if let Message::Response(r) = c
            .conn
            .receiver
            .recv_timeout(Duration::from_secs(30))
            .unwrap()
        {
            assert!(r.response_result.is_err());
            errors += 1;
        }
    }
    c.request("shutdown", json!(null));
    c.notify("exit", json!(null));
    handle.join().unwrap();
}

#[test]
fn utf16_positions() {
    let (mut c, handle) = Client::start();
    // "größe" is 5 UTF-16 units; the unknown name starts after it.
    let text = "let label = \"größe\"; let s = sphere(nope);\nrender s;\n";
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": URI, "languageId": "sdf", "version": 7, "text": text } }),
    );
    let d = c.diagnostics();
    let e = d["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["code"] == "E0100")
        .unwrap()
        .clone();
    assert_eq!(e["range"]["start"], json!({ "line": 0, "character": 36 }));
    c.request("shutdown", json!(null));
    c.notify("exit", json!(null));
    handle.join().unwrap();
}

#[test]
fn the_real_binary_speaks_lsp_over_stdio() {
    use std::io::{BufRead, BufReader, Read, Write};
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .arg("lsp")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut send = |v: Value| {
        let body = v.to_string();
        write!(stdin, "Content-Length: {}\r\n\r\n{body}", body.len()).unwrap();
        stdin.flush().unwrap();
    };
    let mut read = || -> Value {
        let mut len = 0;
        loop {
            let mut line = String::new();
            stdout.read_line(&mut line).unwrap();
            if line == "\r\n" {
                break;
            }
            if let Some(n) = line.strip_prefix("Content-Length: ") {
                len = n.trim().parse().unwrap();
            }
        }
        let mut body = vec![0; len];
        stdout.read_exact(&mut body).unwrap();
        serde_json::from_slice(&body).unwrap()
    };
    send(
        json!({ "jsonrpc": "2.0", "id": 1, "method": "initialize", "params": { "capabilities": {} } }),
    );
    assert!(read()["result"]["capabilities"]["textDocumentSync"].is_number());
    send(json!({ "jsonrpc": "2.0", "method": "initialized", "params": {} }));
    send(
        json!({ "jsonrpc": "2.0", "method": "textDocument/didOpen", "params": { "textDocument": { "uri": URI, "languageId": "sdf", "version": 1, "text": "render sphre(1);" } } }),
    );
    let d = read();
    assert_eq!(d["method"], "textDocument/publishDiagnostics");
    assert_eq!(d["params"]["diagnostics"][0]["code"], "E0103");
    send(json!({ "jsonrpc": "2.0", "id": 2, "method": "shutdown", "params": null }));
    assert_eq!(read()["id"], 2);
    send(json!({ "jsonrpc": "2.0", "method": "exit", "params": null }));
    assert!(child.wait().unwrap().success());
}
