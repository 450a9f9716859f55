//! `codeAction/resolve` ("Place seeds automatically") over the real stdio pipe: it is
//! answered on a thread of its own, so the server keeps answering hover, cancellations,
//! `shutdown` and `exit` while the seeds are placed (a couple of seconds on this
//! document, which once hung the whole server).

use super::{did_open, Pipe};
use serde_json::{json, Value};
use std::time::{Duration, Instant};

const URI: &str = "file:///tmp/sdfc-lsp-test/pyramid.sdf";

/// The document whose "Place seeds automatically" once never finished.
const TEXT: &str = "let b = pyramid(0.95).translate([0, 0.2659, 0]); atlas a on b { seed s0 = [0.3, 0.3, 0.3]; } render b;";

/// A column of `TEXT` (one line, ASCII: bytes are UTF-16 units).
fn column(of: &str) -> usize {
    TEXT.find(of).unwrap()
}

/// Opens `TEXT`, waits for its full diagnostics, and returns the "Place seeds
/// automatically" action offered over the atlas (request id 2).
fn open_and_offer(p: &mut Pipe) -> Value {
    let caps = p.initialize();
    assert_eq!(
        caps["result"]["capabilities"]["codeActionProvider"]["resolveProvider"],
        true
    );
    p.send(did_open(URI, TEXT));
    let d = p.diagnostics();
    assert_eq!(d["uri"], URI, "{d}");
    let at = column("atlas a") + 2;
    p.send(
        json!({ "jsonrpc": "2.0", "id": 2, "method": "textDocument/codeAction", "params": {
        "textDocument": { "uri": URI },
        "range": { "start": { "line": 0, "character": at }, "end": { "line": 0, "character": at } },
        "context": { "diagnostics": [] } } }),
    );
    let r = p.response(2);
    let action = r["result"]
        .as_array()
        .unwrap_or_else(|| panic!("{r}"))
        .iter()
        .find(|a| {
            a["title"]
                .as_str()
                .is_some_and(|t| t.starts_with("Place seeds automatically"))
        })
        .unwrap_or_else(|| panic!("no \"Place seeds automatically\": {r}"))
        .clone();
    assert!(action["edit"].is_null(), "the edit waits for resolve");
    assert_eq!(action["data"]["atlas"], "a", "{action}");
    assert_eq!(action["data"]["keep"], false, "{action}");
    action
}

fn resolve(id: i64, action: &Value) -> Value {
    json!({ "jsonrpc": "2.0", "id": id, "method": "codeAction/resolve", "params": action })
}

/// A hover over `pyramid`.
fn hover(id: i64) -> Value {
    json!({ "jsonrpc": "2.0", "id": id, "method": "textDocument/hover", "params": {
        "textDocument": { "uri": URI },
        "position": { "line": 0, "character": column("pyramid") + 2 } } })
}

fn cancel(id: i64) -> Value {
    json!({ "jsonrpc": "2.0", "method": "$/cancelRequest", "params": { "id": id } })
}

fn assert_hover(m: &Value) {
    assert!(
        m["result"]["contents"]["value"]
            .as_str()
            .is_some_and(|v| v.contains("pyramid")),
        "{m}"
    );
}

/// Reads messages until every id in `ids` has a response; returns every response read
/// (ids in `ids` or not), in the order they came.
fn responses_until(p: &mut Pipe, ids: &[i64]) -> Vec<Value> {
    let mut seen = Vec::new();
    while !ids
        .iter()
        .all(|id| seen.iter().any(|m: &Value| m["id"] == *id))
    {
        let m = p.read();
        if m.get("id").is_some() && m.get("method").is_none() {
            seen.push(m);
        }
    }
    seen
}

fn position(seen: &[Value], id: i64) -> usize {
    seen.iter()
        .position(|m| m["id"] == id)
        .unwrap_or_else(|| panic!("no response to {id}: {seen:?}"))
}

/// Sends `shutdown` (id 999), reads until its answer (returning every response read on
/// the way), sends `exit`, and waits for the process to end with status 0. The 60 s
/// cap only keeps a hung server from hanging the suite; it is not a timing assertion.
fn shut_down(mut p: Pipe) -> Vec<Value> {
    p.send(json!({ "jsonrpc": "2.0", "id": 999, "method": "shutdown", "params": null }));
    let seen = responses_until(&mut p, &[999]);
    let r = &seen[position(&seen, 999)];
    assert_eq!(r["result"], Value::Null, "{r}");
    assert!(r.get("error").is_none(), "{r}");
    p.send(json!({ "jsonrpc": "2.0", "method": "exit", "params": null }));
    let cap = Instant::now() + Duration::from_secs(60);
    let status = loop {
        if let Some(s) = p.child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > cap {
            let _ = p.child.kill();
            let _ = p.child.wait();
            panic!("the server was still running 60 s after exit");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(status.code(), Some(0), "{status:?}");
    seen
}

/// A resolve, then at once a hover: the hover is answered before the resolve, the
/// resolve's edit then comes, and the server shuts down and exits cleanly.
///
/// Why the order is not a race: the resolve and the hover go in one write. When the
/// server reads them in one batch (the usual case), the resolve is handed to its thread
/// and the hover answered in that same pass, while a background answer is only sent
/// from the top of the loop, after the pass: the hover comes first however fast the
/// placement is. When the reader splits them over two batches, the hover's batch is
/// read as soon as the resolve's has been handed off (microseconds, nothing is analysed:
/// the diagnostics are in), while placing seeds on this document takes seconds. A
/// resolve answered first means the loop waited for the placement: the old hang.
#[test]
fn a_slow_resolve_does_not_block_hover_or_shutdown_over_the_pipe() {
    let mut p = Pipe::spawn();
    let action = open_and_offer(&mut p);
    p.write(&[resolve(3, &action), hover(4)]);
    let seen = responses_until(&mut p, &[3, 4]);
    assert!(
        position(&seen, 4) < position(&seen, 3),
        "the hover waited for the resolve: {seen:?}"
    );
    assert_hover(&seen[position(&seen, 4)]);
    let resolved = &seen[position(&seen, 3)];
    assert!(resolved.get("error").is_none(), "{resolved}");
    assert_eq!(resolved["result"]["title"], action["title"]);
    let edits = resolved["result"]["edit"]["changes"][URI]
        .as_array()
        .unwrap_or_else(|| panic!("{resolved}"));
    assert_eq!(edits.len(), 1, "{resolved}");
    // The edit replaces the atlas block's seeds: it lies within the atlas item.
    let range = &edits[0]["range"];
    let (start, end) = (
        range["start"]["character"].as_u64().unwrap() as usize,
        range["end"]["character"].as_u64().unwrap() as usize,
    );
    assert_eq!(
        (
            range["start"]["line"].as_u64(),
            range["end"]["line"].as_u64()
        ),
        (Some(0), Some(0)),
        "{range}"
    );
    let atlas = column("atlas a")..column(" render b;");
    assert!(
        atlas.start <= start && start <= end && end <= atlas.end,
        "{range} outside the atlas {atlas:?}"
    );
    let new_text = edits[0]["newText"].as_str().unwrap();
    assert!(new_text.contains("seed s0 = "), "{new_text}");
    assert!(
        !new_text.contains("[0.3, 0.3, 0.3]"),
        "the old seed stays: {new_text}"
    );
    // Applied, the edit gives a scene without errors whose atlas has the new seeds only.
    let edited = format!("{}{new_text}{}", &TEXT[..start], &TEXT[end..]);
    assert!(!edited.contains("[0.3, 0.3, 0.3]"), "{edited}");
    let a = sdfc::driver::check(&edited, None);
    assert!(
        !a.diagnostics.iter().any(|d| d.is_error()),
        "{edited}\n{:?}",
        a.diagnostics
    );
    shut_down(p);
}

/// A resolve cancelled in the write that sends it: answered once, with RequestCancelled;
/// the hover after it is answered, and the server shuts down cleanly.
#[test]
fn a_cancelled_resolve_is_answered_once_as_cancelled_over_the_pipe() {
    let mut p = Pipe::spawn();
    let action = open_and_offer(&mut p);
    p.write(&[resolve(3, &action), cancel(3), hover(4)]);
    let mut seen = responses_until(&mut p, &[3, 4]);
    let r = &seen[position(&seen, 3)];
    assert_eq!(r["error"]["code"], -32800, "{r}");
    assert!(r.get("result").is_none(), "{r}");
    assert_hover(&seen[position(&seen, 4)]);
    // A resolve not cancelled, placing the same seeds on a thread started after the
    // cancelled one's (if that one was started at all): once it is answered, the
    // cancelled one's late result has had its time to (wrongly) come out.
    p.send(resolve(5, &action));
    seen.extend(responses_until(&mut p, &[5]));
    let r5 = &seen[position(&seen, 5)];
    assert!(r5["result"]["edit"]["changes"][URI].is_array(), "{r5}");
    seen.extend(shut_down(p));
    let answers: Vec<&Value> = seen.iter().filter(|m| m["id"] == 3).collect();
    assert_eq!(
        answers.len(),
        1,
        "one response to the cancelled resolve: {answers:?}"
    );
}

/// A resolve cancelled while its thread is placing seeds: the cancellation is answered
/// at once (before the next request's answer), the late result is dropped, and the
/// server shuts down cleanly.
///
/// The hover (id 4) sent after the resolve is answered only once the resolve has been
/// handed to its thread (same pass or an earlier one), so the cancellation sent after
/// that answer finds it in flight, unless the placement (seconds) finished in the
/// milliseconds between: then the resolve's result would come out, and this fails.
#[test]
fn a_resolve_cancelled_in_flight_is_answered_at_once_and_once_over_the_pipe() {
    let mut p = Pipe::spawn();
    let action = open_and_offer(&mut p);
    p.write(&[resolve(3, &action), hover(4)]);
    let mut seen = responses_until(&mut p, &[4]);
    assert!(
        seen.iter().all(|m| m["id"] != 3),
        "the resolve was answered before the hover: {seen:?}"
    );
    p.write(&[cancel(3), hover(5)]);
    seen.extend(responses_until(&mut p, &[3, 5]));
    let r = &seen[position(&seen, 3)];
    assert_eq!(r["error"]["code"], -32800, "{r}");
    assert!(
        position(&seen, 3) < position(&seen, 5),
        "the cancellation waited: {seen:?}"
    );
    assert_hover(&seen[position(&seen, 5)]);
    // As above: a second resolve, started later, lets the cancelled one's thread finish
    // before the shutdown, so a late result would show.
    p.send(resolve(6, &action));
    seen.extend(responses_until(&mut p, &[6]));
    assert!(
        seen[position(&seen, 6)]["result"]["edit"].is_object(),
        "{seen:?}"
    );
    seen.extend(shut_down(p));
    let answers: Vec<&Value> = seen.iter().filter(|m| m["id"] == 3).collect();
    assert_eq!(
        answers.len(),
        1,
        "one response to the cancelled resolve: {answers:?}"
    );
}
