//! `sdfc lsp`: a thin Language Server Protocol layer over [`crate::ide`].
//!
//! Full-document sync; every change re-analyses the document and publishes its
//! diagnostics tagged with the document version. Requests are answered against
//! the latest text. Positions are UTF-16, converted with `line-index`.
//! The loop, the lifecycle and cancellation are in [`server`]; typed dispatch in
//! [`dispatch`]; formatting, semantic tokens, rename, completion and signature help
//! in [`features`]; code actions and inlay hints in [`actions`].

mod actions;
mod dispatch;
mod features;
mod server;
mod threads;
pub mod transport;
mod worker;

pub use server::{serve, Ended};

use crate::diagnostic::{Diagnostic, Severity};
use crate::ide::{self, Document, SymbolKind};
use crate::span::Span;
use dispatch::{Failure, RequestDispatcher};
use line_index::{LineCol, LineIndex, TextSize, WideEncoding, WideLineCol};
use lsp_server::{Connection, Message, Notification, Request, Response};
use lsp_types as lsp;
use std::collections::HashMap;
use std::path::PathBuf;
use std::str::FromStr;

type Error = Box<dyn std::error::Error + Send + Sync>;

/// The open documents, by URI.
type Docs = HashMap<String, Open>;

#[derive(Clone)]
pub(super) struct Open {
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

/// The folder of a `file:` URI, for texture paths: percent-decoded (a folder named
/// `my scenes` arrives as `my%20scenes`), by the rules of the platform's paths.
fn base_dir(uri: &lsp::Uri) -> Option<PathBuf> {
    let path = url::Url::parse(uri.as_str()).ok()?.to_file_path().ok()?;
    path.parent().map(PathBuf::from)
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

/// Publishes a document's diagnostics. The front end's stage, which the full set follows
/// for the same version, is marked `"sdfcStage": "front"` (a field clients ignore; tests
/// and `sdfc bench --lsp-latency` read it).
fn publish(
    conn: &Connection,
    uri: &lsp::Uri,
    o: Option<&Open>,
    partial: bool,
) -> Result<(), Error> {
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
    let mut params = serde_json::to_value(lsp::PublishDiagnosticsParams {
        uri: uri.clone(),
        diagnostics,
        version,
    })?;
    if partial {
        params["sdfcStage"] = "front".into();
    }
    conn.sender.send(Message::Notification(Notification::new(
        String::from(
            <lsp::notification::PublishDiagnostics as lsp::notification::Notification>::METHOD,
        ),
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

/// The reply to `initialize`.
fn initialize_result() -> lsp::InitializeResult {
    lsp::InitializeResult {
        capabilities: capabilities(),
        server_info: Some(lsp::ServerInfo {
            name: String::from("sdfc"),
            version: Some(String::from(env!("CARGO_PKG_VERSION"))),
        }),
    }
}

/// The folders of the workspace, from `initialize`: a document may read files in its
/// own folder and in these.
fn workspace_roots(params: &serde_json::Value) -> Vec<PathBuf> {
    let Ok(p) = serde_json::from_value::<lsp::InitializeParams>(params.clone()) else {
        return Vec::new();
    };
    #[allow(deprecated)]
    let mut uris: Vec<String> = p.root_uri.iter().map(|u| u.as_str().to_string()).collect();
    for f in p.workspace_folders.into_iter().flatten() {
        uris.push(f.uri.as_str().to_string());
    }
    uris.iter()
        .filter_map(|u| url::Url::parse(u).ok()?.to_file_path().ok())
        .collect()
}

/// How far an analysis goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    /// Parse, names and types (`driver::analyze_with`).
    Front,
    /// Everything `sdfc check` and `compile` report (`driver::check_all_with`).
    Full,
}

fn open(
    uri: &lsp::Uri,
    text: String,
    version: i32,
    roots: &[PathBuf],
    stage: Stage,
    cache: Option<&mut crate::syntax::ItemCache>,
) -> Open {
    let mut access = crate::access::Access::new(base_dir(uri).as_deref());
    for r in roots {
        access.allow(r);
    }
    let doc = match stage {
        Stage::Front => Document::front_reusing(text, &access, cache),
        Stage::Full => Document::full_reusing(text, &access, cache),
    };
    let index = LineIndex::new(&doc.text);
    Open {
        version,
        doc,
        index,
    }
}

/// Answers a request against the latest texts: every request the server handles, by
/// its `lsp_types` type.
pub(super) fn answer(docs: &Docs, req: Request) -> Response {
    use lsp::request::*;
    RequestDispatcher::new(req, docs)
        .on::<HoverRequest>(hover)
        .on::<GotoDefinition>(definition)
        .on::<References>(references)
        .on::<DocumentSymbolRequest>(document_symbols)
        .on::<Formatting>(features::formatting)
        .on::<SemanticTokensFullRequest>(features::semantic_tokens)
        .on::<PrepareRenameRequest>(features::prepare_rename)
        .on::<Rename>(features::rename)
        .on::<Completion>(features::completion)
        .on::<SignatureHelpRequest>(features::signature_help)
        .on::<CodeActionRequest>(actions::code_actions)
        .on::<CodeActionResolveRequest>(actions::resolve)
        .on::<InlayHintRequest>(actions::inlay_hints)
        .finish()
}

/// The open document at a position, and the position as a byte offset.
fn at<'a>(docs: &'a Docs, p: &lsp::TextDocumentPositionParams) -> Option<(&'a Open, usize)> {
    let o = docs.get(p.text_document.uri.as_str())?;
    Some((o, to_offset(&o.index, p.position)?))
}

fn hover(docs: &Docs, p: lsp::HoverParams) -> Result<Option<lsp::Hover>, Failure> {
    Ok(
        at(docs, &p.text_document_position_params).and_then(|(o, offset)| {
            let h = ide::hover(&o.doc, offset)?;
            Some(lsp::Hover {
                contents: lsp::HoverContents::Markup(lsp::MarkupContent {
                    kind: lsp::MarkupKind::Markdown,
                    value: h.markdown,
                }),
                range: Some(to_range(&o.index, &o.doc.text, h.span)),
            })
        }),
    )
}

fn definition(
    docs: &Docs,
    p: lsp::GotoDefinitionParams,
) -> Result<Option<lsp::GotoDefinitionResponse>, Failure> {
    let pos = p.text_document_position_params;
    Ok(at(docs, &pos).and_then(|(o, offset)| {
        let span = ide::definition(&o.doc, offset)?;
        Some(lsp::GotoDefinitionResponse::Scalar(lsp::Location {
            uri: pos.text_document.uri.clone(),
            range: to_range(&o.index, &o.doc.text, span),
        }))
    }))
}

fn references(docs: &Docs, p: lsp::ReferenceParams) -> Result<Option<Vec<lsp::Location>>, Failure> {
    let pos = p.text_document_position;
    let locs = at(docs, &pos)
        .map(|(o, offset)| {
            ide::references(&o.doc, offset, p.context.include_declaration)
                .into_iter()
                .map(|s| lsp::Location {
                    uri: pos.text_document.uri.clone(),
                    range: to_range(&o.index, &o.doc.text, s),
                })
                .collect()
        })
        .unwrap_or_default();
    Ok(Some(locs))
}

fn document_symbols(
    docs: &Docs,
    p: lsp::DocumentSymbolParams,
) -> Result<Option<lsp::DocumentSymbolResponse>, Failure> {
    let symbols = docs
        .get(p.text_document.uri.as_str())
        .map(|o| ide::symbols(&o.doc).iter().map(|s| symbol(o, s)).collect())
        .unwrap_or_default();
    Ok(Some(lsp::DocumentSymbolResponse::Nested(symbols)))
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
pub fn run_stdio() -> Result<Ended, Error> {
    let (conn, io) = transport::stdio();
    let ended = serve(conn)?;
    // The server has let go of the connection, so the writer can finish.
    io.join()?;
    Ok(ended)
}

/// Parses a URI (for tests and clients of this module).
pub fn uri(s: &str) -> Option<lsp::Uri> {
    lsp::Uri::from_str(s).ok()
}
