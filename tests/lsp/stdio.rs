//! The real `sdfc lsp` binary over a stdio pipe: what the in-memory connection cannot
//! show (how the transport hands messages over, how the process ends).

use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// A running `sdfc lsp` and the messages it writes, read by a thread so that a server
/// that stops answering fails the test instead of hanging it.
pub struct Pipe {
    child: Child,
    stdin: ChildStdin,
    messages: mpsc::Receiver<Value>,
}

fn frame(v: &Value) -> String {
    let body = v.to_string();
    format!("Content-Length: {}\r\n\r\n{body}", body.len())
}

impl Pipe {
    pub fn spawn() -> Pipe {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sdfc"))
            .arg("lsp")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let stdin = child.stdin.take().unwrap();
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let (tx, messages) = mpsc::channel();
        std::thread::spawn(move || loop {
            let mut len = None;
            loop {
                let mut line = String::new();
                if stdout.read_line(&mut line).unwrap_or(0) == 0 {
                    return;
                }
                if line == "\r\n" {
                    break;
                }
                if let Some(n) = line.strip_prefix("Content-Length: ") {
                    len = n.trim().parse().ok();
                }
            }
            let mut body = vec![0; len.expect("a Content-Length header")];
            stdout.read_exact(&mut body).unwrap();
            if tx.send(serde_json::from_slice(&body).unwrap()).is_err() {
                return;
            }
        });
        Pipe {
            child,
            stdin,
            messages,
        }
    }

    /// Writes every message in one `write`, as a client flushing a burst does.
    pub fn write(&mut self, messages: &[Value]) {
        let bytes: String = messages.iter().map(frame).collect();
        self.stdin.write_all(bytes.as_bytes()).unwrap();
        self.stdin.flush().unwrap();
    }

    pub fn send(&mut self, message: Value) {
        self.write(&[message]);
    }

    /// The next message from the server.
    pub fn read(&mut self) -> Value {
        self.messages
            .recv_timeout(Duration::from_secs(120))
            .expect("the server answers")
    }

    /// The response to request `id`, skipping notifications.
    pub fn response(&mut self, id: i64) -> Value {
        loop {
            let m = self.read();
            if m["id"] == id {
                return m;
            }
        }
    }

    /// The next publishDiagnostics, of either stage.
    pub fn publish(&mut self) -> Value {
        loop {
            let m = self.read();
            if m["method"] == "textDocument/publishDiagnostics" {
                return m["params"].clone();
            }
        }
    }

    /// The next full set of diagnostics the server publishes (the front end's stage
    /// comes first).
    pub fn diagnostics(&mut self) -> Value {
        loop {
            let d = self.publish();
            if d.get("sdfcStage").is_none() {
                return d;
            }
        }
    }

    pub fn initialize(&mut self) -> Value {
        self.send(json!({ "jsonrpc": "2.0", "id": 1, "method": "initialize", "params": { "capabilities": {} } }));
        let r = self.response(1);
        self.send(json!({ "jsonrpc": "2.0", "method": "initialized", "params": {} }));
        r
    }

    /// Sends `shutdown` and `exit`, and waits for the process.
    pub fn stop(mut self) -> ExitStatus {
        self.send(json!({ "jsonrpc": "2.0", "id": 999, "method": "shutdown", "params": null }));
        assert_eq!(self.response(999)["result"], Value::Null);
        self.exit()
    }

    /// Sends `exit` and waits for the process.
    pub fn exit(mut self) -> ExitStatus {
        self.send(json!({ "jsonrpc": "2.0", "method": "exit", "params": null }));
        self.child.wait().unwrap()
    }
}

fn did_open(uri: &str, text: &str) -> Value {
    json!({ "jsonrpc": "2.0", "method": "textDocument/didOpen", "params": { "textDocument": { "uri": uri, "languageId": "sdf", "version": 1, "text": text } } })
}

fn did_change(uri: &str, version: i32, text: &str) -> Value {
    json!({ "jsonrpc": "2.0", "method": "textDocument/didChange", "params": { "textDocument": { "uri": uri, "version": version }, "contentChanges": [{ "text": text }] } })
}

/// The robot example at its real path (its texture resolves, so every analysis runs the
/// whole pipeline and keeps the server busy for a while).
fn robot() -> (String, String) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/robot.sdf");
    let uri = url::Url::from_file_path(path).unwrap().to_string();
    (uri, std::fs::read_to_string(path).unwrap())
}

#[test]
fn the_real_binary_speaks_lsp_over_stdio() {
    let mut p = Pipe::spawn();
    assert!(p.initialize()["result"]["capabilities"]["textDocumentSync"].is_number());
    p.send(did_open(super::URI, "render sphre(1);"));
    let d = p.diagnostics();
    assert_eq!(d["diagnostics"][0]["code"], "E0103");
    assert!(p.stop().success());
}

#[test]
fn the_front_end_stage_comes_first_over_the_pipe() {
    let (uri, text) = robot();
    let mut p = Pipe::spawn();
    p.initialize();
    // An unused `let`: the front end's warning, in both stages; the robot's atlas
    // geometry only in the second (its N0001 notes for the seeds moved onto the surface).
    p.send(did_open(&uri, &format!("let spare = 1;\n{text}")));
    let codes = |d: &Value| -> Vec<String> {
        d["diagnostics"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x["code"].as_str().unwrap().to_string())
            .collect()
    };
    let front = p.publish();
    assert_eq!(
        (&front["version"], &front["sdfcStage"]),
        (&json!(1), &json!("front"))
    );
    assert_eq!(codes(&front), ["W0001"]);
    let full = p.publish();
    assert_eq!(full["version"], 1);
    assert!(full.get("sdfcStage").is_none());
    assert!(codes(&full).contains(&"W0001".to_string()));
    assert!(p.stop().success());
}

#[test]
fn a_comment_edit_is_one_publish_over_the_pipe() {
    // The unused `let`'s warning (front end); a seed far off the sphere, which the atlas
    // geometry warns about and moves (back end).
    let uri = super::URI;
    let text = "let unused = 1;\nlet ball = sphere(1);\natlas skin on ball {\n    seed a = [0, 1, 0];\n    seed far = [0, 50, 0];\n}\nrender ball;\n";
    let mut p = Pipe::spawn();
    p.initialize();
    p.send(did_open(uri, text));
    let full = p.diagnostics();
    assert_eq!(full["version"], 1);
    // The back end is carried over: the next publish is the whole set, at once, with
    // every diagnostic one line further down.
    p.send(did_change(uri, 2, &format!("// a comment\n{text}")));
    let carried = p.publish();
    assert_eq!(carried["version"], 2);
    assert!(carried.get("sdfcStage").is_none(), "{carried}");
    let lines = |d: &Value| -> Vec<(String, u64)> {
        d["diagnostics"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| {
                let line = x["range"]["start"]["line"].as_u64().unwrap();
                (x["code"].as_str().unwrap().to_string(), line)
            })
            .collect()
    };
    let moved: Vec<(String, u64)> = lines(&full).into_iter().map(|(c, l)| (c, l + 1)).collect();
    assert!(moved.iter().any(|(c, _)| c == "W0001"), "{moved:?}");
    assert!(moved.iter().any(|(c, _)| c == "W0004"), "{moved:?}");
    assert_eq!(lines(&carried), moved);
    assert!(p.stop().success());
}

#[test]
fn a_burst_of_changes_is_analysed_once_over_the_pipe() {
    let (uri, text) = robot();
    let mut p = Pipe::spawn();
    p.initialize();
    p.send(did_open(&uri, &text));
    assert_eq!(p.diagnostics()["version"], 1);
    // Twenty keystrokes, written at once: the server reads them all while it analyses
    // the first, so it analyses (and publishes) once or twice, not twenty times.
    let burst: Vec<Value> = (2..=21)
        .map(|v| did_change(&uri, v, &format!("{text}\nlet edit = sphere({v});\n")))
        .collect();
    p.write(&burst);
    let mut versions = Vec::new();
    while versions.last() != Some(&21) {
        versions.push(p.diagnostics()["version"].as_i64().unwrap());
    }
    assert!(versions.len() <= 3, "one analysis per change: {versions:?}");
    assert!(versions.windows(2).all(|w| w[0] < w[1]), "{versions:?}");
    assert!(p.stop().success());
}

#[test]
fn a_request_cancelled_while_the_server_is_busy_is_cancelled_over_the_pipe() {
    let (uri, text) = robot();
    let mut p = Pipe::spawn();
    p.initialize();
    p.send(did_open(&uri, &text));
    p.diagnostics();
    // A change the back end reads (a comment would be carried over at once) keeps the
    // server analysing while the request and its cancellation
    // arrive. The server reads everything that arrived during an analysis before it
    // answers, so the cancellation counts unless the pipe's reader thread has not even
    // parsed these few hundred bytes by the end of a whole analysis of the robot: the
    // one race left, inherent to cancelling over a stream.
    p.write(&[
        did_change(&uri, 2, &format!("{text}\nlet edit = sphere(1);\n")),
        json!({ "jsonrpc": "2.0", "id": 7, "method": "textDocument/hover", "params": { "textDocument": { "uri": uri }, "position": { "line": 0, "character": 0 } } }),
        json!({ "jsonrpc": "2.0", "method": "$/cancelRequest", "params": { "id": 7 } }),
    ]);
    let r = p.response(7);
    assert_eq!(r["error"]["code"], -32800, "{r}");
    // Later requests are answered.
    p.send(json!({ "jsonrpc": "2.0", "id": 8, "method": "textDocument/documentSymbol", "params": { "textDocument": { "uri": uri } } }));
    assert!(p.response(8)["result"]
        .as_array()
        .is_some_and(|s| !s.is_empty()));
    assert!(p.stop().success());
}

#[test]
fn the_lifecycle_is_answered_at_every_step() {
    let mut p = Pipe::spawn();
    // Before initialize: ServerNotInitialized, and notifications are dropped.
    p.send(json!({ "jsonrpc": "2.0", "id": 1, "method": "textDocument/hover", "params": { "textDocument": { "uri": super::URI }, "position": { "line": 0, "character": 0 } } }));
    assert_eq!(p.response(1)["error"]["code"], -32002);
    p.send(did_open(super::URI, "render sphre(1);"));
    p.send(json!({ "jsonrpc": "2.0", "id": 2, "method": "initialize", "params": { "capabilities": {} } }));
    // The next message is the reply: the dropped didOpen published nothing.
    let init = p.read();
    assert_eq!(init["id"], 2, "{init}");
    assert_eq!(init["result"]["serverInfo"]["name"], "sdfc");
    // A shutdown before `initialized` gets its reply; after it, requests are refused,
    // and `exit` ends the server with success.
    p.send(json!({ "jsonrpc": "2.0", "id": 3, "method": "shutdown", "params": null }));
    let r = p.response(3);
    assert_eq!(r["result"], Value::Null, "{r}");
    assert!(r.get("error").is_none(), "{r}");
    p.send(json!({ "jsonrpc": "2.0", "id": 4, "method": "textDocument/documentSymbol", "params": { "textDocument": { "uri": super::URI } } }));
    assert_eq!(p.response(4)["error"]["code"], -32600);
    assert!(p.exit().success());
    // `exit` without `shutdown` ends the server too, with a failure status.
    let mut p = Pipe::spawn();
    p.initialize();
    assert_eq!(p.exit().code(), Some(1));
}

/// A message whose Content-Length is over the limit is skipped and reported to the user
/// (`window/showMessage`); the server does not allocate it and keeps serving.
#[test]
fn an_oversized_message_is_reported_and_skipped() {
    let mut p = Pipe::spawn();
    p.initialize();
    let claimed = sdfc::lsp::transport::MAX_MESSAGE_BYTES + 1;
    let padding = " ".repeat(claimed);
    p.stdin
        .write_all(format!("Content-Length: {claimed}\r\n\r\n{padding}").as_bytes())
        .unwrap();
    let shown = loop {
        let m = p.read();
        if m["method"] == "window/showMessage" {
            break m;
        }
    };
    assert_eq!(shown["params"]["type"], 1, "{shown}");
    assert!(
        shown["params"]["message"]
            .as_str()
            .unwrap()
            .contains("over the limit"),
        "{shown}"
    );
    p.send(did_open(super::URI, "render sphre(1);"));
    let d = p.diagnostics();
    assert_eq!(d["diagnostics"][0]["code"], "E0103", "{d}");
    assert!(p.stop().success());
}

/// `shutdown` and `exit` in one write: the reply to shutdown, then exit status 0.
#[test]
fn shutdown_and_exit_in_one_batch_exit_cleanly() {
    let mut p = Pipe::spawn();
    p.initialize();
    p.write(&[
        json!({ "jsonrpc": "2.0", "id": 7, "method": "shutdown", "params": null }),
        json!({ "jsonrpc": "2.0", "method": "exit", "params": null }),
    ]);
    assert_eq!(p.response(7)["result"], Value::Null);
    assert_eq!(p.child.wait().unwrap().code(), Some(0));
}

/// In the language server, the workspace folders are roots too: a document may read a
/// texture beside its own folder inside the workspace, and nothing outside it.
#[test]
fn workspace_folders_bound_what_documents_read() {
    let root = tempfile::tempdir().unwrap();
    let ws = root.path().join("ws");
    std::fs::create_dir_all(ws.join("scenes")).unwrap();
    std::fs::create_dir_all(ws.join("shared")).unwrap();
    std::fs::copy(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui/textures/bricks.png"),
        ws.join("shared/t.png"),
    )
    .unwrap();
    std::fs::copy(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui/textures/bricks.png"),
        root.path().join("outside.png"),
    )
    .unwrap();
    let file_uri = |p: &std::path::Path| format!("file://{}", p.display());
    let doc = file_uri(&ws.join("scenes/s.sdf"));
    let text = "let a = image(\"../shared/t.png\");\nlet b = image(\"../../outside.png\");\nlet s = sphere(1);\nrender s { camera = orbit(); }\n";
    let mut p = Pipe::spawn();
    p.send(
        json!({ "jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {
        "capabilities": {},
        "workspaceFolders": [{ "uri": file_uri(&ws), "name": "ws" }]
    } }),
    );
    p.response(1);
    p.send(json!({ "jsonrpc": "2.0", "method": "initialized", "params": {} }));
    p.send(did_open(&doc, text));
    let d = p.diagnostics();
    let refused: Vec<u64> = d["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["code"] == "E0306")
        .map(|d| d["range"]["start"]["line"].as_u64().unwrap())
        .collect();
    assert_eq!(refused, [1], "only the texture outside the workspace: {d}");
    assert!(p.stop().success());
}

/// While a large document is analysed (on the worker thread), requests about another
/// document are answered at once, and the large one's diagnostics come later.
#[test]
fn requests_are_answered_while_a_large_document_is_analysed() {
    let mut p = Pipe::spawn();
    p.initialize();
    p.send(did_open(super::URI, "let s = sphere(1);\nrender s;\n"));
    p.diagnostics();
    let big_uri = "file:///tmp/sdfc-lsp-test/big.sdf";
    let big: String = (0..5_000)
        .map(|i| format!("let a{i} = sphere(1).translate([{i}, 0, 0]);\n"))
        .chain(["render a0;\n".to_string()])
        .collect();
    p.send(did_open(big_uri, &big));
    let asked = std::time::Instant::now();
    p.send(
        json!({ "jsonrpc": "2.0", "id": 5, "method": "textDocument/hover", "params": {
        "textDocument": { "uri": super::URI }, "position": { "line": 0, "character": 9 } } }),
    );
    let mut big_published_first = false;
    loop {
        let m = p.read();
        if m["method"] == "textDocument/publishDiagnostics" && m["params"]["uri"] == big_uri {
            big_published_first = true;
        }
        if m["id"] == 5 {
            assert!(m["result"]["contents"].is_object(), "{m}");
            break;
        }
    }
    let answered = asked.elapsed();
    // The big document's diagnostics still arrive, for its version.
    let d = loop {
        let d = p.diagnostics();
        if d["uri"] == big_uri {
            break d;
        }
    };
    let analysed = asked.elapsed();
    assert_eq!(d["version"], 1);
    assert!(
        !big_published_first && answered < analysed,
        "the hover waited for the big analysis: answered after {answered:?}, analysed after {analysed:?}"
    );
    assert!(p.stop().success());
}

/// "Place seeds automatically" over the real pipe: offered on an atlas with no seeds
/// (E0115), without an edit; resolved into an edit of the atlas block that keeps its
/// settings; the edited text has seeds and checks clean (no diagnostic at all).
#[test]
fn place_seeds_automatically_is_a_resolved_code_action() {
    let mut p = Pipe::spawn();
    let caps = p.initialize();
    assert_eq!(
        caps["result"]["capabilities"]["codeActionProvider"]["resolveProvider"],
        true
    );
    let text = "let body = capsule(a: [0, -0.6, 0], b: [0, 0.6, 0], radius: 0.4);\natlas skin on body {\n    steps = 12;\n}\nmaterial m { color = [skin.uv, 0]; }\nrender body.paint(m);\n";
    p.send(did_open(super::URI, text));
    let d = p.diagnostics();
    assert_eq!(d["diagnostics"][0]["code"], "E0115");
    p.send(
        json!({ "jsonrpc": "2.0", "id": 2, "method": "textDocument/codeAction", "params": {
        "textDocument": { "uri": super::URI },
        "range": { "start": { "line": 1, "character": 2 }, "end": { "line": 1, "character": 2 } },
        "context": { "diagnostics": [] } } }),
    );
    let r = p.response(2);
    let list = r["result"].as_array().unwrap();
    let action = list
        .iter()
        .find(|a| a["title"] == "Place seeds automatically in `skin`")
        .unwrap_or_else(|| panic!("{r}"))
        .clone();
    assert_eq!(action["kind"], "refactor.rewrite");
    assert!(action["edit"].is_null(), "the edit waits for resolve");
    p.send(json!({ "jsonrpc": "2.0", "id": 3, "method": "codeAction/resolve", "params": action }));
    let resolved = p.response(3)["result"].clone();
    let edits = resolved["edit"]["changes"][super::URI]
        .as_array()
        .unwrap()
        .clone();
    assert_eq!(edits.len(), 1);
    assert_eq!(
        edits[0]["range"]["start"],
        json!({ "line": 1, "character": 0 })
    );
    assert_eq!(
        edits[0]["range"]["end"],
        json!({ "line": 3, "character": 1 })
    );
    let block = edits[0]["newText"].as_str().unwrap();
    assert!(
        block.contains("steps = 12;") && block.contains("seed s1 = "),
        "{block}"
    );
    // Applying the edit (lines 1..=3 replaced) gives a scene that checks clean.
    let lines: Vec<&str> = text.lines().collect();
    let edited = format!("{}\n{block}\n{}\n", lines[0], lines[4..].join("\n"));
    let a = sdfc::driver::check(&edited, None);
    assert!(a.diagnostics.is_empty(), "{edited}\n{:?}", a.diagnostics);
    p.send(did_change(super::URI, 2, &edited));
    assert_eq!(p.diagnostics()["diagnostics"], json!([]));
    // With seeds there, "add seeds to cover the gaps" is offered too.
    p.send(
        json!({ "jsonrpc": "2.0", "id": 4, "method": "textDocument/codeAction", "params": {
        "textDocument": { "uri": super::URI },
        "range": { "start": { "line": 1, "character": 2 }, "end": { "line": 1, "character": 2 } },
        "context": { "diagnostics": [] } } }),
    );
    let r = p.response(4);
    let titles: Vec<&str> = r["result"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|a| a["title"].as_str())
        .collect();
    assert_eq!(
        titles,
        [
            "Place seeds automatically in `skin`",
            "Add seeds to cover the gaps in `skin`"
        ],
        "{r}"
    );
    assert!(p.stop().success());
}

#[path = "resolve.rs"]
mod resolve;
