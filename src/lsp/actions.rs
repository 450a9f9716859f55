//! Code actions and inlay hints: thin conversions between the protocol and
//! [`crate::ide::actions`].

use super::dispatch::Failure;
use super::{convert, to_offset, to_position, to_range, Docs, Open};
use crate::ide::actions::{self, InlayKind};
use crate::ide::seeds;
use crate::span::Span;
use lsp_types as lsp;
use std::collections::HashMap;

pub(super) fn capabilities(caps: &mut lsp::ServerCapabilities) {
    caps.code_action_provider = Some(lsp::CodeActionProviderCapability::Options(
        lsp::CodeActionOptions {
            code_action_kinds: Some(vec![
                lsp::CodeActionKind::QUICKFIX,
                lsp::CodeActionKind::REFACTOR_REWRITE,
            ]),
            resolve_provider: Some(true),
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

/// The quick fixes of the diagnostics in the range.
pub(super) fn code_actions(
    docs: &Docs,
    p: lsp::CodeActionParams,
) -> Result<Option<lsp::CodeActionResponse>, Failure> {
    let uri = p.text_document.uri;
    let Some(o) = docs.get(uri.as_str()) else {
        return Ok(Some(Vec::new()));
    };
    let actions: Vec<lsp::CodeActionOrCommand> = actions::code_actions(&o.doc, span_of(o, p.range))
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
        .collect::<Vec<_>>();
    // "Place seeds automatically" on the atlas under the range: offered cheaply, its
    // edit computed on `codeAction/resolve` (placement takes about a second).
    let mut actions = actions;
    for (atlas, has_seeds) in seeds::offered(&o.doc, span_of(o, p.range)) {
        let modes: &[bool] = if has_seeds { &[false, true] } else { &[false] };
        for &keep in modes {
            let title = if keep {
                seeds::TITLE_KEEP
            } else {
                seeds::TITLE
            };
            actions.push(lsp::CodeActionOrCommand::CodeAction(lsp::CodeAction {
                title: format!("{title} in `{atlas}`"),
                kind: Some(lsp::CodeActionKind::REFACTOR_REWRITE),
                data: Some(
                    serde_json::json!({ "uri": uri.as_str(), "atlas": atlas, "keep": keep }),
                ),
                ..Default::default()
            }));
        }
    }
    // "Make this number a parameter" on the number under the range.
    if let Some(edits) = crate::ide::make_param::offered(&o.doc, span_of(o, p.range)) {
        let edits = edits
            .iter()
            .map(|e| lsp::TextEdit {
                range: to_range(&o.index, &o.doc.text, e.span),
                new_text: e.text.clone(),
            })
            .collect();
        actions.push(lsp::CodeActionOrCommand::CodeAction(lsp::CodeAction {
            title: String::from(crate::ide::make_param::TITLE),
            kind: Some(lsp::CodeActionKind::REFACTOR_EXTRACT),
            edit: Some(lsp::WorkspaceEdit {
                changes: Some(HashMap::from([(uri.clone(), edits)])),
                ..Default::default()
            }),
            ..Default::default()
        }));
    }
    Ok(Some(actions))
}

/// The edit of "place seeds automatically", computed against the latest text.
pub(super) fn resolve(docs: &Docs, mut a: lsp::CodeAction) -> Result<lsp::CodeAction, Failure> {
    let data = a.data.clone().unwrap_or_default();
    let (Some(uri), Some(atlas)) = (data["uri"].as_str(), data["atlas"].as_str()) else {
        return Err(Failure::new(
            lsp_server::ErrorCode::InvalidParams,
            String::from("this code action has nothing to resolve"),
        ));
    };
    let Some(o) = docs.get(uri) else {
        return Err(Failure::new(
            lsp_server::ErrorCode::InvalidParams,
            format!("{uri} is not open"),
        ));
    };
    let options = crate::uv::seeds::PlaceOptions {
        keep: data["keep"].as_bool().unwrap_or(false),
        ..Default::default()
    };
    let (_, edit) = seeds::place_edit(&o.doc, atlas, options, seeds::GRID)
        .map_err(|e| Failure::new(lsp_server::ErrorCode::RequestFailed, e))?;
    let uri: lsp::Uri = uri.parse().map_err(|_| {
        Failure::new(
            lsp_server::ErrorCode::InvalidParams,
            format!("bad uri {uri}"),
        )
    })?;
    a.edit = Some(lsp::WorkspaceEdit {
        changes: Some(HashMap::from([(
            uri,
            vec![lsp::TextEdit {
                range: to_range(&o.index, &o.doc.text, edit.span),
                new_text: edit.text,
            }],
        )])),
        ..Default::default()
    });
    Ok(a)
}

pub(super) fn inlay_hints(
    docs: &Docs,
    p: lsp::InlayHintParams,
) -> Result<Option<Vec<lsp::InlayHint>>, Failure> {
    let Some(o) = docs.get(p.text_document.uri.as_str()) else {
        return Ok(Some(Vec::new()));
    };
    let hints = actions::inlay_hints(&o.doc, span_of(o, p.range))
        .into_iter()
        .map(|h| lsp::InlayHint {
            position: to_position(&o.index, &o.doc.text, h.offset),
            label: lsp::InlayHintLabel::String(h.label),
            kind: None,
            text_edits: None,
            tooltip: Some(lsp::InlayHintTooltip::String(String::from(match h.kind {
                InlayKind::Value => "the folded value",
                InlayKind::Merge => "geodesic length of this merge (d_M)",
            }))),
            padding_left: Some(true),
            padding_right: Some(h.kind == InlayKind::Merge),
            data: None,
        })
        .collect();
    Ok(Some(hints))
}
