//! The language server end to end: over an in-memory connection, and the real
//! `sdfc lsp` binary over stdio (in `lsp/stdio.rs`).

use lsp_server::{Connection, Message, Notification, Request, RequestId};
use serde_json::{json, Value};
use std::time::Duration;

struct Client {
    conn: Connection,
    next: i32,
}

impl Client {
    fn start() -> (Client, std::thread::JoinHandle<sdfc::lsp::Ended>) {
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

    /// The next publishDiagnostics, of either stage.
    fn publish(&self) -> Value {
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

    /// The full set of the next version's diagnostics (the front end's stage comes first).
    fn diagnostics(&self) -> Value {
        loop {
            let d = self.publish();
            if d.get("sdfcStage").is_none() {
                return d;
            }
        }
    }
}

const URI: &str = "file:///tmp/sdfc-lsp-test/scene.sdf";

/// Shuts the server down as a client does, and waits for it to exit.
fn stop(mut c: Client, handle: std::thread::JoinHandle<sdfc::lsp::Ended>) {
    c.request("shutdown", json!(null));
    c.notify("exit", json!(null));
    assert_eq!(handle.join().unwrap(), sdfc::lsp::Ended::Clean);
}

#[path = "lsp/actions.rs"]
mod actions;
#[path = "lsp/editing.rs"]
mod editing;
#[path = "lsp/stdio.rs"]
mod stdio;

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

    // Garbage and unknown requests are answered with errors, not crashes: every
    // request the server advertises checks its parameters (InvalidParams), and a
    // method it does not know is MethodNotFound.
    for method in [
        "textDocument/hover",
        "textDocument/definition",
        "textDocument/references",
        "textDocument/documentSymbol",
        "textDocument/formatting",
        "textDocument/semanticTokens/full",
        "textDocument/prepareRename",
        "textDocument/rename",
        "textDocument/completion",
        "textDocument/signatureHelp",
        "textDocument/codeAction",
        "textDocument/inlayHint",
    ] {
        let e = c
            .try_request(method, json!({ "nonsense": true }))
            .unwrap_err();
        assert_eq!(e.code, -32602, "{method}: {e:?}");
    }
    let e = c.try_request("sdfc/unknown", json!({})).unwrap_err();
    assert_eq!(e.code, -32601, "{e:?}");
    assert_eq!(e.message, "sdfc does not handle sdfc/unknown");
    // Only one initialize.
    let e = c
        .try_request("initialize", json!({ "capabilities": {} }))
        .unwrap_err();
    assert_eq!(e.code, -32600, "{e:?}");
    stop(c, handle);
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
    assert_eq!(handle.join().unwrap(), sdfc::lsp::Ended::Clean);
}

#[test]
fn texture_paths_resolve_in_folders_with_spaces() {
    // The folder's name is percent-encoded in the URI; the texture beside the scene
    // must be found (no E-diagnostic), which needs the URI decoded into a path.
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("my scenes #1");
    std::fs::create_dir_all(folder.join("textures")).unwrap();
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/examples/textures/bricks.png"),
        folder.join("textures/bricks.png"),
    )
    .unwrap();
    let uri = url::Url::from_file_path(folder.join("scene.sdf"))
        .unwrap()
        .to_string();
    assert!(uri.contains("my%20scenes%20%231"), "{uri}");
    let text = "let t = image(\"textures/bricks.png\");\nlet ball = sphere(1);\natlas skin on ball { seed a = [0, 1, 0]; }\nmaterial m { color = t.sample(skin.uv); }\nrender ball.paint(m);\n";
    let (c, handle) = Client::start();
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": uri, "languageId": "sdf", "version": 1, "text": text } }),
    );
    let d = c.diagnostics();
    let errors: Vec<&Value> = d["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["code"].as_str().is_some_and(|c| c.starts_with('E')))
        .collect();
    assert!(errors.is_empty(), "{errors:?}");
    stop(c, handle);
}

#[test]
fn front_end_diagnostics_come_first_then_the_full_set() {
    let (c, handle) = Client::start();
    // An unused `let` (the front end's warning) and a seed far off the sphere, which
    // projects onto the other's point (the atlas geometry's note and warning: only the
    // back end finds them).
    let text = "let unused = 1;\nlet ball = sphere(1);\natlas skin on ball {\n    seed a = [0, 1, 0];\n    seed far = [0, 50, 0];\n}\nrender ball;\n";
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": URI, "languageId": "sdf", "version": 1, "text": text } }),
    );
    let codes = |d: &Value| -> Vec<String> {
        d["diagnostics"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x["code"].as_str().unwrap().to_string())
            .collect()
    };
    let front = c.publish();
    assert_eq!(
        (front["version"].clone(), front["sdfcStage"].clone()),
        (json!(1), json!("front"))
    );
    assert_eq!(codes(&front), ["W0001"]);
    let full = c.publish();
    assert_eq!(full["version"], 1);
    assert!(full.get("sdfcStage").is_none());
    let mut all = codes(&full);
    all.sort();
    assert_eq!(all, ["N0001", "W0001", "W0004"]);
    // Comments and whitespace only: the back end's diagnostics are carried over, moved
    // with their tokens, in one publish (no front stage); they equal a fresh analysis's.
    let line_of = |d: &Value, code: &str| -> Vec<Value> {
        d["diagnostics"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|x| x["code"] == code)
            .map(|x| x["range"].clone())
            .collect()
    };
    let trivia = format!("// a comment\n{}", text.replace("seed far", "seed   far"));
    c.notify("textDocument/didChange", json!({ "textDocument": { "uri": URI, "version": 3 }, "contentChanges": [{ "text": trivia }] }));
    let carried = c.publish();
    assert_eq!(carried["version"], 3);
    assert!(carried.get("sdfcStage").is_none(), "{carried}");
    let fresh = sdfc::driver::check_all(&trivia, None);
    assert_eq!(
        carried["diagnostics"].as_array().unwrap().len(),
        fresh.diagnostics.len()
    );
    for code in ["N0001", "W0001", "W0004"] {
        let (before, after) = (line_of(&full, code), line_of(&carried, code));
        assert_eq!(before.len(), after.len(), "{code}");
        for (b, a) in before.iter().zip(&after) {
            assert_eq!(
                a["start"]["line"].as_u64().unwrap(),
                b["start"]["line"].as_u64().unwrap() + 1,
                "{code}: {b} then {a}"
            );
        }
    }
    // `seed   far`'s warning starts where the fresh analysis puts it.
    let far = fresh
        .diagnostics
        .iter()
        .find(|d| d.code == "W0004")
        .unwrap()
        .span()
        .unwrap();
    let start = &line_of(&carried, "W0004")[0]["start"];
    let (line, col) = (
        start["line"].as_u64().unwrap() as usize,
        start["character"].as_u64().unwrap() as usize,
    );
    let offset: usize = trivia
        .split_inclusive('\n')
        .take(line)
        .map(str::len)
        .sum::<usize>()
        + col;
    assert_eq!(offset, far.start);
    // An unused constant is never read by the back end: carried too, in one publish,
    // with the front end's new warning.
    let inert = format!("{trivia}let spare = [1, 2];\n");
    c.notify("textDocument/didChange", json!({ "textDocument": { "uri": URI, "version": 4 }, "contentChanges": [{ "text": inert }] }));
    let carried = c.publish();
    assert_eq!(carried["version"], 4);
    assert!(carried.get("sdfcStage").is_none(), "{carried}");
    let mut all = codes(&carried);
    all.sort();
    assert_eq!(all, ["N0001", "W0001", "W0001", "W0004"]);
    // A change the back end reads runs it again: the front stage comes first.
    let moved = trivia.replace("[0, 50, 0]", "[0, 60, 0]");
    c.notify("textDocument/didChange", json!({ "textDocument": { "uri": URI, "version": 6 }, "contentChanges": [{ "text": moved }] }));
    assert_eq!(c.publish()["sdfcStage"], "front");
    assert!(c.publish().get("sdfcStage").is_none());
    // A front-end error is the whole analysis: one publish, not marked.
    let broken = "let ball = spher(1);\nrender ball;\n";
    c.notify("textDocument/didChange", json!({ "textDocument": { "uri": URI, "version": 7 }, "contentChanges": [{ "text": broken }] }));
    let only = c.publish();
    assert_eq!(only["version"], 7);
    assert!(only.get("sdfcStage").is_none());
    assert_eq!(codes(&only), ["E0103"]);
    stop(c, handle);
}
