//! Formatting, semantic tokens, rename, completion and signature help over
//! the in-memory connection.

use super::{stop, Client, URI};
use serde_json::{json, Value};

fn open(c: &mut Client, text: &str, version: i32) {
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": URI, "languageId": "sdf", "version": version, "text": text } }),
    );
    c.diagnostics();
}

fn at(line: u32, character: u32) -> Value {
    json!({ "textDocument": { "uri": URI }, "position": { "line": line, "character": character } })
}

#[test]
fn formatting() {
    let (mut c, handle) = Client::start();
    open(&mut c, "let a=sphere(1); // ball\nrender a;\n", 1);
    let params = json!({ "textDocument": { "uri": URI }, "options": { "tabSize": 4, "insertSpaces": true } });
    let edits = c.request("textDocument/formatting", params.clone());
    // One minimal edit: `=` gets its spaces, and the comment its two.
    let edits = edits.as_array().unwrap();
    assert_eq!(edits.len(), 1);
    assert_eq!(
        edits[0]["range"]["start"],
        json!({ "line": 0, "character": 5 })
    );
    assert_eq!(
        edits[0]["range"]["end"],
        json!({ "line": 0, "character": 16 })
    );
    assert_eq!(edits[0]["newText"], " = sphere(1); ");
    // Formatted text: no edits; a syntax error: no edits either.
    open(&mut c, "let a = sphere(1);  // ball\nrender a;\n", 2);
    assert_eq!(
        c.request("textDocument/formatting", params.clone()),
        json!([])
    );
    open(&mut c, "let a = sphere(1)\nrender   a;\n", 3);
    assert_eq!(c.request("textDocument/formatting", params), json!([]));
    stop(c, handle);
}

#[test]
fn semantic_tokens() {
    let (mut c, handle) = Client::start();
    // "größe" makes UTF-16 columns differ from bytes; the block comment spans two lines.
    open(
        &mut c,
        "let s = \"größe\"; let r = s;\n/* a\nb */ let t = sphere(radius: 1);\n",
        1,
    );
    let t = c.request(
        "textDocument/semanticTokens/full",
        json!({ "textDocument": { "uri": URI } }),
    );
    let data: Vec<u64> = t["data"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    // (delta line, delta start, length, type, modifiers): types index the legend;
    // modifier bit 0 is declaration, bit 1 builtin.
    let expected: Vec<u64> = vec![
        0, 0, 3, 0, 0, // let: keyword
        0, 4, 1, 6, 1, // s: variable, declaration
        0, 4, 7, 2, 0, // "größe": string, 7 UTF-16 units
        0, 9, 3, 0, 0, // let
        0, 4, 1, 6, 1, // r
        0, 4, 1, 6, 0, // s: variable
        1, 0, 4, 3, 0, // "/* a": comment, first line
        1, 0, 4, 3, 0, // "b */": comment, second line
        0, 5, 3, 0, 0, // let
        0, 4, 1, 6, 1, // t
        0, 4, 6, 5, 2, // sphere: function, builtin
        0, 7, 6, 10, 0, // radius: parameter
        0, 8, 1, 1, 0, // 1: number
    ];
    assert_eq!(data, expected);
    stop(c, handle);
}

#[test]
fn rename_and_prepare_rename() {
    let (mut c, handle) = Client::start();
    open(
        &mut c,
        "let r = 0.5;\nlet ball = sphere(r);\nrender ball.translate([r, 0, 0]);\n",
        1,
    );
    let prep = c.request("textDocument/prepareRename", at(1, 18));
    assert_eq!(prep["placeholder"], "r");
    assert_eq!(
        prep["range"]["start"],
        json!({ "line": 1, "character": 18 })
    );
    let mut params = at(2, 24);
    params["newName"] = json!("radius");
    let edit = c.request("textDocument/rename", params);
    let edits = edit["changes"][URI].as_array().unwrap();
    let starts: Vec<(u64, u64)> = edits
        .iter()
        .map(|e| {
            (
                e["range"]["start"]["line"].as_u64().unwrap(),
                e["range"]["start"]["character"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(starts, [(0, 4), (1, 18), (2, 23)]);
    assert!(edits.iter().all(|e| e["newText"] == "radius"));
    // Builtins, keywords and bad names are refused with an error.
    let e = c
        .try_request("textDocument/prepareRename", at(1, 12))
        .unwrap_err();
    assert!(
        e.message.contains("`sphere` is a builtin function"),
        "{e:?}"
    );
    let mut params = at(0, 4);
    params["newName"] = json!("render");
    let e = c.try_request("textDocument/rename", params).unwrap_err();
    assert_eq!(e.code, -32803);
    assert_eq!(e.message, "`render` is a keyword");
    let mut params = at(0, 4);
    params["newName"] = json!("ball");
    assert!(c.try_request("textDocument/rename", params).is_err());
    stop(c, handle);
}

#[test]
fn completion_and_signature_help() {
    let (mut c, handle) = Client::start();
    let text = "let ball = sphere(1);\natlas skin on ball { seed a = [0, 0, 1]; }\nmaterial m { color = skin. }\nrender ball.translate([0, 1, 0]);\n";
    open(&mut c, text, 1);
    let items = c.request("textDocument/completion", at(2, 26));
    let labels: Vec<&str> = items
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["label"].as_str().unwrap())
        .collect();
    assert_eq!(labels, ["uv", "distance", "status", "transport", "seed"]);
    assert_eq!(items[0]["kind"], 5); // Field
    assert_eq!(items[0]["detail"], "field<vec2>");
    // Inside the call: named arguments first, then names and builtins.
    let items = c.request("textDocument/completion", at(0, 18));
    let items = items.as_array().unwrap();
    assert_eq!(items[0]["label"], "radius:");
    assert_eq!(items[0]["insertText"], "radius: ");
    let sphere = items.iter().find(|i| i["label"] == "sphere").unwrap();
    assert_eq!(sphere["detail"], "sphere(radius: float = 1) -> shape");
    assert!(!items.iter().any(|i| i["label"] == "ball"));

    let help = c.request("textDocument/signatureHelp", at(3, 26));
    assert_eq!(help["activeParameter"], 1);
    let sig = &help["signatures"][0];
    assert_eq!(
        sig["label"],
        "translate(shape: shape, offset: vec3) -> shape"
    );
    assert_eq!(sig["parameters"][1]["label"], json!([24, 36]));
    assert_eq!(
        c.request("textDocument/signatureHelp", at(3, 2)),
        json!(null)
    );
    // After `ball.`: the shape's methods only.
    let items = c.request("textDocument/completion", at(3, 12));
    let labels: Vec<&str> = items
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["label"].as_str().unwrap())
        .collect();
    assert!(
        labels.contains(&"translate") && labels.contains(&"paint"),
        "{labels:?}"
    );
    assert!(
        !labels
            .iter()
            .any(|l| ["sphere", "orbit", "sin"].contains(l)),
        "{labels:?}"
    );
    // After a named argument, the next parameter not given is active.
    open(&mut c, "let c = cylinder(radius: 0.2, ", 2);
    let help = c.request("textDocument/signatureHelp", at(0, 30));
    assert_eq!(help["activeParameter"], 1, "{help}");
    assert_eq!(help["signatures"][0]["activeParameter"], 1);
    stop(c, handle);
}
