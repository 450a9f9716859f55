//! Code actions and inlay hints: thin conversions between the protocol and
//! [`crate::ide::actions`].

use super::{convert, to_offset, to_position, to_range, Open};
use crate::ide::actions::{self, InlayKind};
use crate::span::Span;
use lsp_server::{ErrorCode, Request, Response};
use lsp_types as lsp;
use std::collections::HashMap;

/// The requests answered here.
pub(super) const METHODS: &[&str] = &["textDocument/codeAction", "textDocument/inlayHint"];

pub(super) fn capabilities(caps: &mut lsp::ServerCapabilities) {
    caps.code_action_provider = Some(lsp::CodeActionProviderCapability::Options(
        lsp::CodeActionOptions {
            code_action_kinds: Some(vec![lsp::CodeActionKind::QUICKFIX]),
            ..Default::default()
        },
    ));
    caps.inlay_hint_provider = Some(lsp::OneOf::Left(true));
}

/// A protocol range as a byte span of the document (clamped to it).
fn span_of(o: &Open, r: lsp::Range) -> Span {
    let end = o.doc.text.len();
    let start = to_offset(&o.index, r.start).unwrap_or(0).min(end);
    let stop = to_offset(&o.index, r.end).unwrap_or(end).min(end);
    Span::new(start, stop.max(start))
}

pub(super) fn answer(docs: &HashMap<String, Open>, req: Request) -> Response {
    let id = req.id.clone();
    let bad = |e: serde_json::Error| {
        Response::new_err(
            req.id.clone(),
            ErrorCode::InvalidParams as i32,
            e.to_string(),
        )
    };
    let params = req.params.clone();
    match req.method.as_str() {
        "textDocument/codeAction" => {
            let p: lsp::CodeActionParams = match serde_json::from_value(params) {
                Ok(p) => p,
                Err(e) => return bad(e),
            };
            let uri = p.text_document.uri;
            let actions: Vec<lsp::CodeActionOrCommand> = docs
                .get(uri.as_str())
                .map(|o| {
                    actions::code_actions(&o.doc, span_of(o, p.range))
                        .into_iter()
                        .map(|a| {
                            let edits = a
                                .edits
                                .iter()
                                .map(|e| lsp::TextEdit {
                                    range: to_range(&o.index, &o.doc.text, e.span),
                                    new_text: e.text.clone(),
                                })
                                .collect();
                            lsp::CodeActionOrCommand::CodeAction(lsp::CodeAction {
                                title: a.title,
                                kind: Some(lsp::CodeActionKind::QUICKFIX),
                                diagnostics: Some(vec![convert(&uri, o, &a.diagnostic)]),
                                edit: Some(lsp::WorkspaceEdit {
                                    changes: Some(HashMap::from([(uri.clone(), edits)])),
                                    ..Default::default()
                                }),
                                is_preferred: Some(a.preferred),
                                ..Default::default()
                            })
                        })
                        .collect()
                })
                .unwrap_or_default();
            Response::new_ok(id, actions)
        }
        "textDocument/inlayHint" => {
            let p: lsp::InlayHintParams = match serde_json::from_value(params) {
                Ok(p) => p,
                Err(e) => return bad(e),
            };
            let hints: Vec<lsp::InlayHint> = docs
                .get(p.text_document.uri.as_str())
                .map(|o| {
                    actions::inlay_hints(&o.doc, span_of(o, p.range))
                        .into_iter()
                        .map(|h| lsp::InlayHint {
                            position: to_position(&o.index, &o.doc.text, h.offset),
                            label: lsp::InlayHintLabel::String(h.label),
                            kind: None,
                            text_edits: None,
                            tooltip: Some(lsp::InlayHintTooltip::String(String::from(
                                match h.kind {
                                    InlayKind::Value => "the folded value",
                                    InlayKind::Merge => "geodesic length of this merge (d_M)",
                                },
                            ))),
                            padding_left: Some(true),
                            padding_right: Some(h.kind == InlayKind::Merge),
                            data: None,
                        })
                        .collect()
                })
                .unwrap_or_default();
            Response::new_ok(id, hints)
        }
        other => Response::new_err(
            id,
            ErrorCode::MethodNotFound as i32,
            format!("sdfc does not handle {other}"),
        ),
    }
}
