//! Code actions, inlay hints and cancellation over the in-memory connection.

use super::{stop, Client, URI};
use lsp_server::{Message, Notification, Request, RequestId};
use serde_json::json;
use std::time::Duration;

#[test]
fn code_action_fixes_a_misspelling() {
    let (mut c, handle) = Client::start();
    let text = "let ball = spher(1);\nrender ball;\n";
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": URI, "languageId": "sdf", "version": 1, "text": text } }),
    );
    let d = c.diagnostics();
    let diag = d["diagnostics"][0].clone();
    let actions = c.request(
        "textDocument/codeAction",
        json!({ "textDocument": { "uri": URI }, "range": diag["range"], "context": { "diagnostics": [diag] } }),
    );
    let list = actions.as_array().unwrap();
    assert_eq!(list.len(), 1, "{actions}");
    assert_eq!(list[0]["title"], "replace with `sphere`");
    assert_eq!(list[0]["kind"], "quickfix");
    assert_eq!(list[0]["isPreferred"], true);
    assert_eq!(list[0]["diagnostics"][0]["code"], "E0103");
    assert_eq!(
        list[0]["edit"]["changes"][URI],
        json!([{ "range": { "start": { "line": 0, "character": 11 }, "end": { "line": 0, "character": 16 } }, "newText": "sphere" }])
    );
    // Applying it (as the editor would) clears the diagnostics.
    c.notify("textDocument/didChange", json!({ "textDocument": { "uri": URI, "version": 2 }, "contentChanges": [{ "text": "let ball = sphere(1);\nrender ball;\n" }] }));
    let d = c.diagnostics();
    assert_eq!(d["version"], 2);
    assert_eq!(d["diagnostics"], json!([]));
    stop(c, handle);
}

#[test]
fn inlay_hints_over_the_protocol() {
    let (mut c, handle) = Client::start();
    let text = "let r = 2 * 0.25;\nlet ball = sphere(r);\natlas skin on ball {\n    seed a = [0, 0.5, 0];\n    seed b = [0.5, 0, 0];\n    merge a b;\n}\nrender ball;\n";
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": URI, "languageId": "sdf", "version": 1, "text": text } }),
    );
    assert_eq!(c.diagnostics()["diagnostics"], json!([]));
    let hints = c.request(
        "textDocument/inlayHint",
        json!({ "textDocument": { "uri": URI }, "range": { "start": { "line": 0, "character": 0 }, "end": { "line": 8, "character": 0 } } }),
    );
    let list = hints.as_array().unwrap();
    assert_eq!(list.len(), 2, "{hints}");
    assert_eq!(list[0]["label"], "= 0.5");
    assert_eq!(list[0]["position"], json!({ "line": 0, "character": 16 }));
    // A quarter of a great circle of radius 0.5: π/4.
    assert_eq!(list[1]["position"], json!({ "line": 5, "character": 11 }));
    let label = list[1]["label"].as_str().unwrap();
    let d: f64 = label
        .trim_matches(|ch: char| !ch.is_ascii_digit() && ch != '.')
        .parse()
        .unwrap();
    assert!((d - std::f64::consts::FRAC_PI_4).abs() < 2e-3, "{label}");
    stop(c, handle);
}

#[test]
fn cancelled_requests_are_not_answered_with_results() {
    let (mut c, handle) = Client::start();
    // A large scene keeps the server busy analysing while the request and its
    // cancellation queue up behind it; both are then read in one batch.
    // At its real path, so its texture resolves and the whole pipeline runs.
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/robot.sdf");
    let robot = std::fs::read_to_string(path).unwrap();
    let uri = format!("file://{path}");
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": uri, "languageId": "sdf", "version": 1, "text": robot } }),
    );
    let id = RequestId::from(900);
    c.conn
        .sender
        .send(Message::Request(Request::new(
            id.clone(),
            String::from("textDocument/hover"),
            json!({ "textDocument": { "uri": uri }, "position": { "line": 0, "character": 0 } }),
        )))
        .unwrap();
    c.conn
        .sender
        .send(Message::Notification(Notification::new(
            String::from("$/cancelRequest"),
            json!({ "id": 900 }),
        )))
        .unwrap();
    let response = loop {
        match c
            .conn
            .receiver
            .recv_timeout(Duration::from_secs(120))
            .unwrap()
        {
            Message::Response(r) if r.id == id => break r,
            _ => {}
        }
    };
    let err = response
        .response_result
        .expect_err("a cancelled request gets an error");
    assert_eq!(err.code, -32800, "RequestCancelled");
    // The server goes on answering, against the analysed robot: a seed name hovers
    // with its projected position.
    let (line, col) = robot
        .lines()
        .enumerate()
        .find_map(|(i, l)| {
            l.trim_start()
                .starts_with("seed ")
                .then(|| (i, l.find("seed ").unwrap() + 5))
        })
        .unwrap();
    let h = c.request(
        "textDocument/hover",
        json!({ "textDocument": { "uri": uri }, "position": { "line": line, "character": col } }),
    );
    assert!(
        h["contents"]["value"]
            .as_str()
            .unwrap_or("")
            .contains("projected to"),
        "{h}"
    );
    stop(c, handle);
}

#[test]
fn make_this_number_a_parameter() {
    let (mut c, handle) = Client::start();
    let text = "let ball = sphere(radius: 0.5); // the ball\nrender ball;\n";
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": URI, "languageId": "sdf", "version": 1, "text": text } }),
    );
    assert_eq!(c.diagnostics()["diagnostics"], json!([]));
    let at = json!({ "line": 0, "character": 27 });
    let actions = c.request(
        "textDocument/codeAction",
        json!({ "textDocument": { "uri": URI }, "range": { "start": at, "end": at }, "context": { "diagnostics": [] } }),
    );
    let list = actions.as_array().unwrap();
    let a = list
        .iter()
        .find(|a| a["title"] == "Make this number a parameter")
        .unwrap_or_else(|| panic!("{actions}"));
    assert_eq!(a["kind"], "refactor.extract");
    assert_eq!(
        a["edit"]["changes"][URI],
        json!([
            { "range": { "start": { "line": 0, "character": 0 }, "end": { "line": 0, "character": 0 } }, "newText": "param radius = 0.5 in [0.25, 1];\n" },
            { "range": { "start": { "line": 0, "character": 26 }, "end": { "line": 0, "character": 29 } }, "newText": "radius" }
        ])
    );
    // Applied, the scene checks clean and keeps its comment.
    let edited = "param radius = 0.5 in [0.25, 1];\nlet ball = sphere(radius: radius); // the ball\nrender ball;\n";
    c.notify("textDocument/didChange", json!({ "textDocument": { "uri": URI, "version": 2 }, "contentChanges": [{ "text": edited }] }));
    let d = c.diagnostics();
    assert_eq!(d["version"], 2);
    assert_eq!(d["diagnostics"], json!([]));
    // Hover on the parameter shows its range and default.
    let hover = c.request(
        "textDocument/hover",
        json!({ "textDocument": { "uri": URI }, "position": { "line": 1, "character": 28 } }),
    );
    let shown = hover["contents"]["value"].as_str().unwrap_or_default();
    assert!(
        shown.contains("param radius: float = 0.5 in [0.25, 1]"),
        "{hover}"
    );
    stop(c, handle);
}
