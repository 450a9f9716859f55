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

/// Surface samples for placing seeds in the `seeds_write` target: a coarse grid keeps
/// each input fast (`sdfc seeds --grid 12`).
pub const SEEDS_GRID: usize = 12;

/// At most this many atlases of one input are placed (each placement walks the surface).
pub const SEEDS_ATLASES: usize = 2;

/// `sdfc seeds --write` and "Place seeds automatically": on a scene that checks (an
/// atlas without seeds aside, as `sdfc seeds` allows), the first [`SEEDS_ATLASES`]
/// atlases get their seeds placed ([`sdfc::ide::seeds::place_edit`]), anew and kept.
/// Never a panic; applied, each edit gives a text that parses, that formats, and that
/// keeps every byte of the input outside the replaced `seed` and `merge` statements
/// (see [`assert_seeds_edit`]). Inputs may start with `#`, as the `lsp` target's
/// documents do (the `#` is dropped). Returns how many edits were checked.
pub fn seeds_write(data: &[u8], base: &Path) -> usize {
    let data = data.strip_prefix(b"#").unwrap_or(data);
    let text = text(data);
    let analysis = sdfc::driver::check(&text, Some(base));
    assert_spans(&text, &analysis.diagnostics);
    let blocking = analysis
        .diagnostics
        .iter()
        .any(|d| d.is_error() && d.code != sdfc::codes::E_NO_SEEDS);
    if blocking {
        return 0;
    }
    let doc = sdfc::ide::Document { text, analysis };
    let names: Vec<String> = doc
        .analysis
        .program
        .atlases
        .iter()
        .take(SEEDS_ATLASES)
        .map(|a| a.name.clone())
        .collect();
    let mut checked = 0;
    for name in &names {
        for keep in [false, true] {
            if place_seeds(&doc, name, keep, SEEDS_GRID).is_some() {
                checked += 1;
            }
        }
    }
    checked
}

/// Places the seeds of atlas `name` of `doc` (anew, or with `keep` added to its own),
/// applies the edit and checks it ([`assert_seeds_edit`]); returns the edited text, or
/// `None` when placing refused (an `Err`, which is not a failure).
pub fn place_seeds(
    doc: &sdfc::ide::Document,
    name: &str,
    keep: bool,
    grid: usize,
) -> Option<String> {
    let options = sdfc::uv::seeds::PlaceOptions {
        keep,
        ..Default::default()
    };
    let (placement, edit) = sdfc::ide::seeds::place_edit(doc, name, options, grid).ok()?;
    let output = assert_seeds_edit(doc, name, keep, &placement, &edit);
    Some(output)
}

/// The spans of atlas `name`'s `seed` and `merge` statements in the syntax tree of
/// `doc`, sorted, and the offset of its block's closing brace.
pub fn seed_statement_spans(doc: &sdfc::ide::Document, name: &str) -> (Vec<sdfc::Span>, usize) {
    use sdfc::syntax::ast::{AtlasStmt, ItemKind};
    let def = doc
        .analysis
        .program
        .atlases
        .iter()
        .find(|a| a.name == name)
        .unwrap_or_else(|| panic!("no atlas `{name}`"));
    let item = &doc.text[def.span.start..def.span.end];
    let close = def.span.start + item.rfind('}').expect("the atlas block's `}`");
    let mut spans: Vec<sdfc::Span> = doc
        .analysis
        .parsed
        .file
        .items
        .iter()
        .filter_map(|item| match &item.kind {
            ItemKind::Atlas { name: n, body, .. } if n.name == name => Some(body),
            _ => None,
        })
        .flatten()
        .filter_map(|s| match s {
            AtlasStmt::Seed { span, .. } | AtlasStmt::Merge { span, .. } => Some(*span),
            _ => None,
        })
        .filter(|s| def.span.start <= s.start && s.end <= close)
        .collect();
    spans.sort_by_key(|s| s.start);
    (spans, close)
}

/// The properties of a placement's edit of atlas `name` (`keep`: the seeds kept and
/// added to): applied to `doc`'s text, the output parses without errors and formats
/// (idempotently, tokens kept); with `keep` it is the input with the new statements
/// inserted before the block's closing brace; else it is the input with the atlas's
/// `seed` and `merge` statements replaced by the placed ones, every other byte kept
/// (whitespace aside only where it served a removed statement or ended the block).
/// Returns the output.
pub fn assert_seeds_edit(
    doc: &sdfc::ide::Document,
    name: &str,
    keep: bool,
    placement: &sdfc::uv::seeds::Placement,
    edit: &sdfc::diagnostic::Edit,
) -> String {
    let input = doc.text.as_str();
    let (spans, close) = seed_statement_spans(doc, name);
    let e = edit.span;
    assert!(
        e.start <= e.end && e.end <= input.len(),
        "the edit {}..{} is outside the text of {} bytes",
        e.start,
        e.end,
        input.len()
    );
    let output = sdfc::ide::actions::apply(input, std::slice::from_ref(edit));
    let context = || format!("--- input\n{input}\n--- output\n{output}");
    if keep {
        assert_eq!(
            (e.start, e.end),
            (close, close),
            "adding seeds is not an insertion before the block's `}}`\n{}",
            context()
        );
    } else {
        // The placed statements close the edit's text: the block's indentation and its
        // closing brace (and what followed it in the item) come after them.
        let inserted = sdfc::ide::seeds::statements(placement);
        let at = edit
            .text
            .rfind(&inserted)
            .unwrap_or_else(|| panic!("the edit lacks the placed statements\n{}", context()));
        let tail = &edit.text[at + inserted.len()..];
        assert!(
            tail.trim_start_matches([' ', '\t']) == &input[close..e.end],
            "after the placed statements: {tail:?}\n{}",
            context()
        );
        assert_only_statements_replaced(input, &output, &spans, e.start + at, &inserted, close);
    }
    let mut diags = Vec::new();
    let _ = sdfc::syntax::parse(&output, &mut diags);
    let errors: Vec<_> = diags.iter().filter(|d| d.is_error()).collect();
    assert!(
        errors.is_empty(),
        "the edited text does not parse: {errors:?}\n{}",
        context()
    );
    format(output.as_bytes());
    output
}

/// The property of a seed rewrite (tests/seeds_write.rs): `output` with `inserted`
/// (at byte `p`) taken out is `input` with the statements at `spans` taken out, up to
/// whitespace taken out next to those statements (or just before the closing brace
/// `close`) and whitespace put in right around the insertion. Checked by aligning the
/// two texts: every byte other than whitespace must stay, in order.
pub fn assert_only_statements_replaced(
    input: &str,
    output: &str,
    spans: &[sdfc::Span],
    p: usize,
    inserted: &str,
    close: usize,
) {
    let context = || format!("--- input\n{input}\n--- output\n{output}");
    assert_eq!(
        output.get(p..p + inserted.len()),
        Some(inserted),
        "the placed statements are not at {p}\n{}",
        context()
    );
    let o = format!("{}{}", &output[..p], &output[p + inserted.len()..]);
    let (a, b) = (input.as_bytes(), o.as_bytes());
    let mut deleted = vec![false; a.len()];
    let mut statement = vec![false; a.len()];
    let mut put_in = std::collections::BTreeSet::new();
    let (mut i, mut j, mut k) = (0, 0, 0);
    while i < a.len() || j < b.len() {
        if k < spans.len() && spans[k].start == i {
            for x in spans[k].start..spans[k].end {
                deleted[x] = true;
                statement[x] = true;
            }
            i = spans[k].end;
            k += 1;
        } else if i < a.len() && j < b.len() && a[i] == b[j] {
            i += 1;
            j += 1;
        } else if i < a.len() && a[i].is_ascii_whitespace() {
            deleted[i] = true;
            i += 1;
        } else if j < b.len() && b[j].is_ascii_whitespace() {
            put_in.insert(j);
            j += 1;
        } else {
            panic!(
                "a byte other than whitespace changed at input {i} / output {j}\n{}",
                context()
            );
        }
    }
    assert_eq!(
        k,
        spans.len(),
        "statements left: {:?}\n{}",
        &spans[k..],
        context()
    );
    // Each run of removed bytes holds a statement, or lies in whitespace that touches one
    // or the closing brace. (The alignment is greedy: where a statement's line and a
    // blank line beside it go, it may keep the statement's newline and take out the
    // blank line's, which is the same text.)
    let mut x = 0;
    while x < a.len() {
        if !deleted[x] {
            x += 1;
            continue;
        }
        let start = x;
        while x < a.len() && deleted[x] {
            x += 1;
        }
        let (mut l, mut r) = (start, x);
        while l > 0 && a[l - 1].is_ascii_whitespace() {
            l -= 1;
        }
        while r < a.len() && a[r].is_ascii_whitespace() {
            r += 1;
        }
        let touches = (l > 0 && statement[l - 1]) || (r < a.len() && statement[r]) || r == close;
        assert!(
            statement[start..x].contains(&true) || touches,
            "whitespace {start}..{x} ({:?}) removed away from any statement\n{}",
            &input[start..x],
            context()
        );
    }
    // Whitespace put in only next to the inserted statements.
    let (mut lo, mut hi) = (p, p);
    while lo > 0 && put_in.contains(&(lo - 1)) {
        lo -= 1;
    }
    while put_in.contains(&hi) {
        hi += 1;
    }
    assert_eq!(
        put_in.len(),
        hi - lo,
        "whitespace put in away from the new statements: {put_in:?} (insertion at {p})\n{}",
        context()
    );
}

/// `sdfc render MESH.glb`'s reader, [`sdfc::bake::export::read_glb`], on any bytes:
/// never a panic, and what it accepts is what its documentation promises, checked
/// here independently of the crate's own checks too (in u64, so that no overflow can
/// hide a chart outside the images): the mesh passes `check_mesh`, the layout
/// `check_atlas` and every chart of every level lies inside the atlas, the textures
/// are the atlas's size, at most `MAX_IMAGE_SIZE` a side and `MAX_TEXTURE_BYTES` in
/// all. Returns the reader's refusal, if any (tests/glb_fuzz.rs counts them).
pub fn glb(data: &[u8]) -> Result<(), sdfc::bake::export::ReadError> {
    use sdfc::bake::export::gltf::{texture_bytes, MAX_IMAGE_SIZE, MAX_TEXTURE_BYTES};
    use sdfc::bake::export::{check_atlas, check_mesh, check_textures};
    let (mesh, textures, atlas) = sdfc::bake::export::read_glb(data)?;
    check_mesh(&mesh).expect("read_glb returned a mesh that check_mesh refuses");
    check_atlas(&atlas).expect("read_glb returned a layout that check_atlas refuses");
    check_textures(&textures, &atlas).expect("read_glb returned textures of another size");
    let (w, h) = (atlas.width(), atlas.height());
    let images = 3 + textures.emissive.is_some() as usize;
    assert!(
        w <= MAX_IMAGE_SIZE && h <= MAX_IMAGE_SIZE,
        "read_glb returned a {w}×{h} atlas"
    );
    assert!(
        texture_bytes(w, h, images) <= MAX_TEXTURE_BYTES,
        "read_glb returned {images} textures of {w}×{h}, over the memory limit"
    );
    if let Err(e) = layout_inside(&atlas) {
        panic!("read_glb returned a layout that check_atlas accepts but that is unsafe: {e}: {atlas:?}");
    }
    Ok(())
}

/// Every chart of every level of `atlas` inside its image, computed in u64 (no
/// overflow): the flat layout's grid at each level, each packed chart's whole block.
pub fn layout_inside(atlas: &sdfc::bake::ChartLayout) -> Result<(), String> {
    use sdfc::bake::ChartLayout;
    let (w, h) = (atlas.width() as u64, atlas.height() as u64);
    match atlas {
        ChartLayout::Flat(l) => {
            let n = l.chart_size as u64;
            if n < 2 || !n.is_power_of_two() || l.gutter as u64 > n {
                return Err(format!("chart size {n}, gutter {}", l.gutter));
            }
            if l.level_origins.is_empty() || l.columns == 0 || l.rows == 0 {
                return Err("an empty layout".into());
            }
            for (level, &[x, y]) in l.level_origins.iter().enumerate() {
                let size = n.checked_shr(level as u32).unwrap_or(0);
                if size < 2 {
                    return Err(format!("level {level} has charts of {size} texels"));
                }
                let stride = size + if level == 0 { 2 * l.gutter as u64 } else { 0 };
                let right = x as u64 + l.columns as u64 * stride;
                let bottom = y as u64 + l.rows as u64 * stride;
                if right > w || bottom > h {
                    return Err(format!(
                        "level {level} reaches ({right}, {bottom}), past the {w}×{h} image"
                    ));
                }
            }
        }
        ChartLayout::Packed(l) => {
            let n = l.cell_size as u64;
            if n < 2 || !n.is_power_of_two() || l.levels as u64 != n.ilog2() as u64 {
                return Err(format!("cell size {n} with {} levels", l.levels));
            }
            let size = |c: u32, level: u32| c as u64 * ((n >> level) - 1) + 1;
            for (p, chart) in l.charts.iter().enumerate() {
                let [cu, cv] = chart.cells;
                if cu == 0 || cv == 0 {
                    return Err(format!("packed chart {p} has no cells"));
                }
                let below: u64 = (1..l.levels).map(|level| size(cu, level)).sum();
                let bw = size(cu, 0).max(below);
                let bh = size(cv, 0) + if l.levels > 1 { size(cv, 1) } else { 0 };
                let [x, y] = chart.origin.map(u64::from);
                if x + bw > w || y + bh > h {
                    return Err(format!(
                        "packed chart {p}'s block {bw}×{bh} at ({x}, {y}) leaves the {w}×{h} image"
                    ));
                }
            }
        }
    }
    Ok(())
}
