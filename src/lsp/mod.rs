//! `sdfc lsp`: a thin Language Server Protocol layer over [`crate::ide`].
//!
//! Full-document sync; every change re-analyses the document and publishes its
//! diagnostics tagged with the document version. Requests are answered against
//! the latest text. Positions are UTF-16, converted with `line-index`.
//! Formatting, semantic tokens, rename, completion and signature help are in
//! [`features`]; code actions and inlay hints in [`actions`].

mod actions;
mod features;

use crate::diagnostic::{Diagnostic, Severity};
use crate::ide::{self, Document, SymbolKind};
use crate::span::Span;
use line_index::{LineCol, LineIndex, TextSize, WideEncoding, WideLineCol};
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, Response};
use lsp_types as lsp;
use std::collections::HashMap;
use std::path::PathBuf;
use std::str::FromStr;

type Error = Box<dyn std::error::Error + Send + Sync>;

struct Open {
    version: i32,
    doc: Document,
    index: LineIndex,
}

fn to_position(index: &LineIndex, text: &str, offset: usize) -> lsp::Position {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let lc = index.line_col(TextSize::from(offset as u32));
    let wide = index
        .to_wide(WideEncoding::Utf16, lc)
        .unwrap_or(WideLineCol {
            line: lc.line,
            col: lc.col,
        });
    lsp::Position {
        line: wide.line,
        character: wide.col,
    }
}

fn to_range(index: &LineIndex, text: &str, span: Span) -> lsp::Range {
    lsp::Range {
        start: to_position(index, text, span.start),
        end: to_position(index, text, span.end),
    }
}

fn to_offset(index: &LineIndex, p: lsp::Position) -> Option<usize> {
    let lc: LineCol = index.to_utf8(
        WideEncoding::Utf16,
        WideLineCol {
            line: p.line,
            col: p.character,
        },
    )?;
    index.offset(lc).map(|o| u32::from(o) as usize)
}

/// The folder of a `file:` URI, for texture paths.
fn base_dir(uri: &lsp::Uri) -> Option<PathBuf> {
    let path = uri.as_str().strip_prefix("file://")?;
    PathBuf::from(path).parent().map(PathBuf::from)
}

fn convert(uri: &lsp::Uri, o: &Open, d: &Diagnostic) -> lsp::Diagnostic {
    let text = &o.doc.text;
    let mut message = d.message.clone();
    for n in &d.notes {
        message.push_str(&format!("\nnote: {n}"));
    }
    if let Some(h) = &d.help {
        message.push_str(&format!("\nhelp: {h}"));
    }
    let related: Vec<lsp::DiagnosticRelatedInformation> = d
        .secondary
        .iter()
        .map(|l| lsp::DiagnosticRelatedInformation {
            location: lsp::Location {
                uri: uri.clone(),
                range: to_range(&o.index, text, l.span),
            },
            message: l.message.clone(),
        })
        .collect();
    lsp::Diagnostic {
        // A diagnostic about no place in the file is shown at its start.
        range: d
            .span()
            .map_or_else(lsp::Range::default, |s| to_range(&o.index, text, s)),
        severity: Some(match d.severity {
            Severity::Error => lsp::DiagnosticSeverity::ERROR,
            Severity::Warning => lsp::DiagnosticSeverity::WARNING,
            Severity::Note => lsp::DiagnosticSeverity::INFORMATION,
        }),
        code: Some(lsp::NumberOrString::String(d.code.to_string())),
        source: Some(String::from("sdfc")),
        message,
        related_information: (!related.is_empty()).then_some(related),
        ..Default::default()
    }
}

fn publish(conn: &Connection, uri: &lsp::Uri, o: Option<&Open>) -> Result<(), Error> {
    let (diagnostics, version) = match o {
        Some(o) => (
            o.doc
                .analysis
                .diagnostics
                .iter()
                .map(|d| convert(uri, o, d))
                .collect(),
            Some(o.version),
        ),
        None => (Vec::new(), None),
    };
    let params = lsp::PublishDiagnosticsParams {
        uri: uri.clone(),
        diagnostics,
        version,
    };
    conn.sender.send(Message::Notification(Notification::new(
        String::from("textDocument/publishDiagnostics"),
        params,
    )))?;
    Ok(())
}

fn capabilities() -> lsp::ServerCapabilities {
    let mut caps = lsp::ServerCapabilities {
        text_document_sync: Some(lsp::TextDocumentSyncCapability::Kind(
            lsp::TextDocumentSyncKind::FULL,
        )),
        hover_provider: Some(lsp::HoverProviderCapability::Simple(true)),
        definition_provider: Some(lsp::OneOf::Left(true)),
        references_provider: Some(lsp::OneOf::Left(true)),
        document_symbol_provider: Some(lsp::OneOf::Left(true)),
        ..Default::default()
    };
    features::capabilities(&mut caps);
    actions::capabilities(&mut caps);
    caps
}

/// Serves one client on a connection until it exits.
///
/// Messages are taken in batches: everything already waiting when the server is free.
/// Each document changed in a batch is analysed once, at its latest text, and its
/// diagnostics are published with that version; requests are then answered against
/// that text, except those the client cancelled (`$/cancelRequest`), which get
/// `RequestCancelled` without being computed.
pub fn serve(conn: Connection) -> Result<(), Error> {
    let caps = serde_json::to_value(capabilities())?;
    conn.initialize(caps)?;
    let mut docs: HashMap<String, Open> = HashMap::new();
    while let Ok(first) = conn.receiver.recv() {
        let mut batch = vec![first];
        while let Ok(m) = conn.receiver.try_recv() {
            batch.push(m);
        }
        let mut cancelled = std::collections::HashSet::new();
        let mut changed: Vec<(lsp::Uri, String, i32)> = Vec::new();
        let mut requests = Vec::new();
        for msg in batch {
            match msg {
                Message::Request(req) => requests.push(req),
                Message::Notification(n) if n.method == "$/cancelRequest" => {
                    if let Ok(p) = serde_json::from_value::<lsp::CancelParams>(n.params) {
                        cancelled.insert(match p.id {
                            lsp::NumberOrString::Number(i) => lsp_server::RequestId::from(i),
                            lsp::NumberOrString::String(s) => lsp_server::RequestId::from(s),
                        });
                    }
                }
                Message::Notification(n) => notify(&conn, &mut docs, &mut changed, n)?,
                Message::Response(_) => {}
            }
        }
        for (uri, text, version) in changed {
            let o = open(&uri, text, version);
            publish(&conn, &uri, Some(&o))?;
            docs.insert(uri.as_str().to_string(), o);
        }
        for req in requests {
            if conn.handle_shutdown(&req)? {
                return Ok(());
            }
            let resp = if cancelled.contains(&req.id) {
                Response::new_err(
                    req.id,
                    ErrorCode::RequestCanceled as i32,
                    String::from("cancelled by the client"),
                )
            } else {
                answer(&docs, req)
            };
            conn.sender.send(Message::Response(resp))?;
        }
    }
    Ok(())
}

fn open(uri: &lsp::Uri, text: String, version: i32) -> Open {
    let doc = Document::new(text, base_dir(uri).as_deref());
    let index = LineIndex::new(&doc.text);
    Open {
        version,
        doc,
        index,
    }
}

/// Applies a notification. Opened and changed texts are queued in `changed` (the latest
/// per document) to be analysed once the batch is read.
fn notify(
    conn: &Connection,
    docs: &mut HashMap<String, Open>,
    changed: &mut Vec<(lsp::Uri, String, i32)>,
    n: Notification,
) -> Result<(), Error> {
    let mut queue = |uri: lsp::Uri, text: String, version: i32| {
        changed.retain(|(u, _, _)| u != &uri);
        changed.push((uri, text, version));
    };
    match n.method.as_str() {
        "textDocument/didOpen" => {
            // Malformed notifications are ignored: there is no one to answer.
            let Ok(p) = serde_json::from_value::<lsp::DidOpenTextDocumentParams>(n.params) else {
                return Ok(());
            };
            queue(
                p.text_document.uri,
                p.text_document.text,
                p.text_document.version,
            );
        }
        "textDocument/didChange" => {
            // Malformed notifications are ignored: there is no one to answer.
            let Ok(p) = serde_json::from_value::<lsp::DidChangeTextDocumentParams>(n.params) else {
                return Ok(());
            };
            // Full sync: the last change holds the whole text.
            if let Some(change) = p.content_changes.into_iter().last() {
                queue(p.text_document.uri, change.text, p.text_document.version);
            }
        }
        "textDocument/didClose" => {
            // Malformed notifications are ignored: there is no one to answer.
            let Ok(p) = serde_json::from_value::<lsp::DidCloseTextDocumentParams>(n.params) else {
                return Ok(());
            };
            changed.retain(|(u, _, _)| u != &p.text_document.uri);
            docs.remove(p.text_document.uri.as_str());
            publish(conn, &p.text_document.uri, None)?;
        }
        _ => {}
    }
    Ok(())
}

fn respond<T: serde::Serialize>(id: lsp_server::RequestId, value: T) -> Response {
    Response::new_ok(id, value)
}

/// Answers a request against the latest text; malformed or unknown requests get errors.
fn answer(docs: &HashMap<String, Open>, req: Request) -> Response {
    let id = req.id.clone();
    let at = |params: &lsp::TextDocumentPositionParams| -> Option<(&Open, usize)> {
        let o = docs.get(params.text_document.uri.as_str())?;
        let offset = to_offset(&o.index, params.position)?;
        Some((o, offset))
    };
    let bad = |e: serde_json::Error| {
        Response::new_err(
            req.id.clone(),
            ErrorCode::InvalidParams as i32,
            e.to_string(),
        )
    };
    match req.method.as_str() {
        "textDocument/hover" => {
            match serde_json::from_value::<lsp::HoverParams>(req.params.clone()) {
                Ok(p) => {
                    let h = at(&p.text_document_position_params).and_then(|(o, offset)| {
                        let h = ide::hover(&o.doc, offset)?;
                        Some(lsp::Hover {
                            contents: lsp::HoverContents::Markup(lsp::MarkupContent {
                                kind: lsp::MarkupKind::Markdown,
                                value: h.markdown,
                            }),
                            range: Some(to_range(&o.index, &o.doc.text, h.span)),
                        })
                    });
                    respond(id, h)
                }
                Err(e) => bad(e),
            }
        }
        "textDocument/definition" => {
            match serde_json::from_value::<lsp::GotoDefinitionParams>(req.params.clone()) {
                Ok(p) => {
                    let uri = p.text_document_position_params.text_document.uri.clone();
                    let loc = at(&p.text_document_position_params).and_then(|(o, offset)| {
                        let span = ide::definition(&o.doc, offset)?;
                        Some(lsp::GotoDefinitionResponse::Scalar(lsp::Location {
                            uri,
                            range: to_range(&o.index, &o.doc.text, span),
                        }))
                    });
                    respond(id, loc)
                }
                Err(e) => bad(e),
            }
        }
        "textDocument/references" => {
            match serde_json::from_value::<lsp::ReferenceParams>(req.params.clone()) {
                Ok(p) => {
                    let uri = p.text_document_position.text_document.uri.clone();
                    let locs: Vec<lsp::Location> = at(&p.text_document_position)
                        .map(|(o, offset)| {
                            ide::references(&o.doc, offset, p.context.include_declaration)
                                .into_iter()
                                .map(|s| lsp::Location {
                                    uri: uri.clone(),
                                    range: to_range(&o.index, &o.doc.text, s),
                                })
                                .collect()
                        })
                        .unwrap_or_default();
                    respond(id, locs)
                }
                Err(e) => bad(e),
            }
        }
        "textDocument/documentSymbol" => {
            match serde_json::from_value::<lsp::DocumentSymbolParams>(req.params.clone()) {
                Ok(p) => {
                    let symbols = docs
                        .get(p.text_document.uri.as_str())
                        .map(|o| {
                            ide::symbols(&o.doc)
                                .iter()
                                .map(|s| symbol(o, s))
                                .collect::<Vec<_>>()
                        })
                        .unwrap_or_default();
                    respond(id, lsp::DocumentSymbolResponse::Nested(symbols))
                }
                Err(e) => bad(e),
            }
        }
        m if features::METHODS.contains(&m) => features::answer(docs, req.clone()),
        m if actions::METHODS.contains(&m) => actions::answer(docs, req.clone()),
        other => Response::new_err(
            id,
            ErrorCode::MethodNotFound as i32,
            format!("sdfc does not handle {other}"),
        ),
    }
}

#[allow(deprecated)]
fn symbol(o: &Open, s: &ide::Symbol) -> lsp::DocumentSymbol {
    let kind = match s.kind {
        SymbolKind::Let => lsp::SymbolKind::VARIABLE,
        SymbolKind::Atlas => lsp::SymbolKind::NAMESPACE,
        SymbolKind::Material => lsp::SymbolKind::STRUCT,
        SymbolKind::Render => lsp::SymbolKind::EVENT,
        SymbolKind::Seed => lsp::SymbolKind::CONSTANT,
        SymbolKind::Merge => lsp::SymbolKind::OPERATOR,
    };
    lsp::DocumentSymbol {
        name: s.name.clone(),
        detail: None,
        kind,
        tags: None,
        deprecated: None,
        range: to_range(&o.index, &o.doc.text, s.span),
        selection_range: to_range(&o.index, &o.doc.text, s.selection),
        children: (!s.children.is_empty())
            .then(|| s.children.iter().map(|c| symbol(o, c)).collect()),
    }
}

/// Serves on standard input and output.
pub fn run_stdio() -> Result<(), Error> {
    let (conn, io) = Connection::stdio();
    serve(conn)?;
    io.join()?;
    Ok(())
}

/// Parses a URI (for tests and clients of this module).
pub fn uri(s: &str) -> Option<lsp::Uri> {
    lsp::Uri::from_str(s).ok()
}
