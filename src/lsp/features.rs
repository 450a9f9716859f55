//! Formatting, semantic tokens, rename, completion and signature help: thin
//! conversions between the protocol and [`crate::ide`].

use super::{to_offset, to_position, to_range, Open};
use crate::ide::complete::{self, CompletionKind};
use crate::ide::format;
use crate::ide::rename;
use crate::ide::semantic::{self, TokenKind};
use lsp_server::{ErrorCode, Request, Response};
use lsp_types as lsp;
use std::collections::HashMap;

/// The requests answered here.
pub(super) const METHODS: &[&str] = &[
    "textDocument/formatting",
    "textDocument/semanticTokens/full",
    "textDocument/prepareRename",
    "textDocument/rename",
    "textDocument/completion",
    "textDocument/signatureHelp",
];

fn token_type(kind: TokenKind) -> lsp::SemanticTokenType {
    match kind {
        TokenKind::Keyword => lsp::SemanticTokenType::KEYWORD,
        TokenKind::Number => lsp::SemanticTokenType::NUMBER,
        TokenKind::String => lsp::SemanticTokenType::STRING,
        TokenKind::Comment => lsp::SemanticTokenType::COMMENT,
        TokenKind::Operator => lsp::SemanticTokenType::OPERATOR,
        TokenKind::Function => lsp::SemanticTokenType::FUNCTION,
        TokenKind::Variable => lsp::SemanticTokenType::VARIABLE,
        TokenKind::Atlas => lsp::SemanticTokenType::NAMESPACE,
        TokenKind::Seed => lsp::SemanticTokenType::ENUM_MEMBER,
        TokenKind::Material => lsp::SemanticTokenType::STRUCT,
        TokenKind::Parameter => lsp::SemanticTokenType::PARAMETER,
        TokenKind::Property => lsp::SemanticTokenType::PROPERTY,
    }
}

/// Bit 0: declaration; bit 1: defaultLibrary (builtins).
pub(super) fn legend() -> lsp::SemanticTokensLegend {
    lsp::SemanticTokensLegend {
        token_types: TokenKind::ALL.iter().map(|k| token_type(*k)).collect(),
        token_modifiers: vec![
            lsp::SemanticTokenModifier::DECLARATION,
            lsp::SemanticTokenModifier::DEFAULT_LIBRARY,
        ],
    }
}

pub(super) fn capabilities(caps: &mut lsp::ServerCapabilities) {
    caps.document_formatting_provider = Some(lsp::OneOf::Left(true));
    caps.semantic_tokens_provider = Some(
        lsp::SemanticTokensServerCapabilities::SemanticTokensOptions(lsp::SemanticTokensOptions {
            legend: legend(),
            full: Some(lsp::SemanticTokensFullOptions::Bool(true)),
            ..Default::default()
        }),
    );
    caps.rename_provider = Some(lsp::OneOf::Right(lsp::RenameOptions {
        prepare_provider: Some(true),
        work_done_progress_options: Default::default(),
    }));
    caps.completion_provider = Some(lsp::CompletionOptions {
        trigger_characters: Some(vec![String::from(".")]),
        ..Default::default()
    });
    caps.signature_help_provider = Some(lsp::SignatureHelpOptions {
        trigger_characters: Some(vec![String::from("("), String::from(",")]),
        retrigger_characters: None,
        work_done_progress_options: Default::default(),
    });
}

fn utf16_len(s: &str) -> u32 {
    s.encode_utf16().count() as u32
}

/// Semantic tokens, split at line breaks (clients do not all take multi-line
/// tokens) and delta-encoded.
fn semantic_tokens(o: &Open) -> lsp::SemanticTokens {
    let text = &o.doc.text;
    let mut data = Vec::new();
    let (mut line, mut col) = (0u32, 0u32);
    for t in semantic::semantic_tokens(&o.doc) {
        let token_type = TokenKind::ALL
            .iter()
            .position(|k| *k == t.kind)
            .unwrap_or(0) as u32;
        let modifiers = u32::from(t.declaration) | (u32::from(t.builtin) << 1);
        let mut start = t.span.start;
        for piece in text[t.span.range()].split('\n') {
            let len = utf16_len(piece.trim_end_matches('\r'));
            let p = to_position(&o.index, text, start);
            if len > 0 {
                let delta_line = p.line - line;
                let delta_start = if delta_line == 0 {
                    p.character - col
                } else {
                    p.character
                };
                data.push(lsp::SemanticToken {
                    delta_line,
                    delta_start,
                    length: len,
                    token_type,
                    token_modifiers_bitset: modifiers,
                });
                (line, col) = (p.line, p.character);
            }
            start += piece.len() + 1;
        }
    }
    lsp::SemanticTokens {
        result_id: None,
        data,
    }
}

fn completion_kind(k: CompletionKind) -> lsp::CompletionItemKind {
    match k {
        CompletionKind::Function => lsp::CompletionItemKind::FUNCTION,
        CompletionKind::Variable => lsp::CompletionItemKind::VARIABLE,
        CompletionKind::Atlas => lsp::CompletionItemKind::MODULE,
        CompletionKind::Material => lsp::CompletionItemKind::STRUCT,
        CompletionKind::Seed => lsp::CompletionItemKind::ENUM_MEMBER,
        CompletionKind::Constant => lsp::CompletionItemKind::CONSTANT,
        CompletionKind::Keyword => lsp::CompletionItemKind::KEYWORD,
        CompletionKind::Parameter => lsp::CompletionItemKind::PROPERTY,
        CompletionKind::Setting => lsp::CompletionItemKind::PROPERTY,
        CompletionKind::Field => lsp::CompletionItemKind::FIELD,
    }
}

fn markdown(value: String) -> lsp::Documentation {
    lsp::Documentation::MarkupContent(lsp::MarkupContent {
        kind: lsp::MarkupKind::Markdown,
        value,
    })
}

/// Answers one of [`METHODS`].
pub(super) fn answer(docs: &HashMap<String, Open>, req: Request) -> Response {
    let id = req.id.clone();
    let failed = |message: String| {
        Response::new_err(req.id.clone(), ErrorCode::RequestFailed as i32, message)
    };
    let bad = |e: serde_json::Error| {
        Response::new_err(
            req.id.clone(),
            ErrorCode::InvalidParams as i32,
            e.to_string(),
        )
    };
    let at = |p: &lsp::TextDocumentPositionParams| -> Option<(&Open, usize)> {
        let o = docs.get(p.text_document.uri.as_str())?;
        Some((o, to_offset(&o.index, p.position)?))
    };
    let params = req.params.clone();
    match req.method.as_str() {
        "textDocument/formatting" => {
            let p: lsp::DocumentFormattingParams = match serde_json::from_value(params) {
                Ok(p) => p,
                Err(e) => return bad(e),
            };
            // A document with syntax errors is left alone: no edits.
            let edits: Vec<lsp::TextEdit> = docs
                .get(p.text_document.uri.as_str())
                .and_then(|o| {
                    let text = &o.doc.text;
                    let formatted = format::format(text).ok()?;
                    let (span, new_text) = format::minimal_edit(text, &formatted)?;
                    Some(vec![lsp::TextEdit {
                        range: to_range(&o.index, text, span),
                        new_text,
                    }])
                })
                .unwrap_or_default();
            Response::new_ok(id, edits)
        }
        "textDocument/semanticTokens/full" => {
            let p: lsp::SemanticTokensParams = match serde_json::from_value(params) {
                Ok(p) => p,
                Err(e) => return bad(e),
            };
            let tokens = docs.get(p.text_document.uri.as_str()).map(semantic_tokens);
            Response::new_ok(id, tokens.map(lsp::SemanticTokensResult::Tokens))
        }
        "textDocument/prepareRename" => {
            let p: lsp::TextDocumentPositionParams = match serde_json::from_value(params) {
                Ok(p) => p,
                Err(e) => return bad(e),
            };
            let Some((o, offset)) = at(&p) else {
                return Response::new_ok(id, Option::<lsp::PrepareRenameResponse>::None);
            };
            match rename::prepare_rename(&o.doc, offset) {
                Ok((span, placeholder)) => Response::new_ok(
                    id,
                    lsp::PrepareRenameResponse::RangeWithPlaceholder {
                        range: to_range(&o.index, &o.doc.text, span),
                        placeholder,
                    },
                ),
                Err(e) => failed(e.0),
            }
        }
        "textDocument/rename" => {
            let p: lsp::RenameParams = match serde_json::from_value(params) {
                Ok(p) => p,
                Err(e) => return bad(e),
            };
            let Some((o, offset)) = at(&p.text_document_position) else {
                return failed(String::from("the document is not open"));
            };
            match rename::rename(&o.doc, offset, &p.new_name) {
                Ok(spans) => {
                    let edits = spans
                        .into_iter()
                        .map(|s| lsp::TextEdit {
                            range: to_range(&o.index, &o.doc.text, s),
                            new_text: p.new_name.clone(),
                        })
                        .collect();
                    let uri = p.text_document_position.text_document.uri;
                    Response::new_ok(
                        id,
                        lsp::WorkspaceEdit {
                            changes: Some(HashMap::from([(uri, edits)])),
                            ..Default::default()
                        },
                    )
                }
                Err(e) => failed(e.0),
            }
        }
        "textDocument/completion" => {
            let p: lsp::CompletionParams = match serde_json::from_value(params) {
                Ok(p) => p,
                Err(e) => return bad(e),
            };
            let items: Vec<lsp::CompletionItem> = at(&p.text_document_position)
                .map(|(o, offset)| complete::completions(&o.doc, offset))
                .unwrap_or_default()
                .into_iter()
                .map(|c| lsp::CompletionItem {
                    label: c.label,
                    kind: Some(completion_kind(c.kind)),
                    detail: c.detail,
                    documentation: c.documentation.map(markdown),
                    insert_text: c.insert_text,
                    ..Default::default()
                })
                .collect();
            Response::new_ok(id, lsp::CompletionResponse::Array(items))
        }
        "textDocument/signatureHelp" => {
            let p: lsp::SignatureHelpParams = match serde_json::from_value(params) {
                Ok(p) => p,
                Err(e) => return bad(e),
            };
            let help = at(&p.text_document_position_params).and_then(|(o, offset)| {
                let h = complete::signature_help(&o.doc, offset)?;
                let parameters = h
                    .parameters
                    .iter()
                    .map(|&(s, e)| lsp::ParameterInformation {
                        label: lsp::ParameterLabel::LabelOffsets([
                            utf16_len(&h.label[..s]),
                            utf16_len(&h.label[..e]),
                        ]),
                        documentation: None,
                    })
                    .collect();
                let active = h.active_parameter.map(|a| a as u32);
                Some(lsp::SignatureHelp {
                    signatures: vec![lsp::SignatureInformation {
                        label: h.label,
                        documentation: Some(markdown(h.documentation)),
                        parameters: Some(parameters),
                        active_parameter: active,
                    }],
                    active_signature: Some(0),
                    active_parameter: active,
                })
            });
            Response::new_ok(id, help)
        }
        other => Response::new_err(
            id,
            ErrorCode::MethodNotFound as i32,
            format!("sdfc does not handle {other}"),
        ),
    }
}
