//! Formatting, semantic tokens, rename, completion and signature help: thin
//! conversions between the protocol and [`crate::ide`].

use super::dispatch::Failure;
use super::{at, to_position, to_range, Docs, Open};
use crate::ide::complete::{self, CompletionKind};
use crate::ide::format;
use crate::ide::rename;
use crate::ide::semantic::{self, TokenKind};
use lsp_types as lsp;
use std::collections::HashMap;

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
fn encode_tokens(o: &Open) -> lsp::SemanticTokens {
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

/// The one formatting edit, or none (a document with syntax errors is left alone).
pub(super) fn formatting(
    docs: &Docs,
    p: lsp::DocumentFormattingParams,
) -> Result<Option<Vec<lsp::TextEdit>>, Failure> {
    let edits = docs
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
    Ok(Some(edits))
}

pub(super) fn semantic_tokens(
    docs: &Docs,
    p: lsp::SemanticTokensParams,
) -> Result<Option<lsp::SemanticTokensResult>, Failure> {
    let tokens = docs.get(p.text_document.uri.as_str()).map(encode_tokens);
    Ok(tokens.map(lsp::SemanticTokensResult::Tokens))
}

pub(super) fn prepare_rename(
    docs: &Docs,
    p: lsp::TextDocumentPositionParams,
) -> Result<Option<lsp::PrepareRenameResponse>, Failure> {
    let Some((o, offset)) = at(docs, &p) else {
        return Ok(None);
    };
    let (span, placeholder) =
        rename::prepare_rename(&o.doc, offset).map_err(|e| Failure::failed(e.0))?;
    Ok(Some(lsp::PrepareRenameResponse::RangeWithPlaceholder {
        range: to_range(&o.index, &o.doc.text, span),
        placeholder,
    }))
}

pub(super) fn rename(
    docs: &Docs,
    p: lsp::RenameParams,
) -> Result<Option<lsp::WorkspaceEdit>, Failure> {
    let pos = p.text_document_position;
    let (o, offset) = at(docs, &pos).ok_or_else(|| Failure::failed("the document is not open"))?;
    let spans = rename::rename(&o.doc, offset, &p.new_name).map_err(|e| Failure::failed(e.0))?;
    let edits = spans
        .into_iter()
        .map(|s| lsp::TextEdit {
            range: to_range(&o.index, &o.doc.text, s),
            new_text: p.new_name.clone(),
        })
        .collect();
    Ok(Some(lsp::WorkspaceEdit {
        changes: Some(HashMap::from([(pos.text_document.uri, edits)])),
        ..Default::default()
    }))
}

pub(super) fn completion(
    docs: &Docs,
    p: lsp::CompletionParams,
) -> Result<Option<lsp::CompletionResponse>, Failure> {
    let items: Vec<lsp::CompletionItem> = at(docs, &p.text_document_position)
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
    Ok(Some(lsp::CompletionResponse::Array(items)))
}

pub(super) fn signature_help(
    docs: &Docs,
    p: lsp::SignatureHelpParams,
) -> Result<Option<lsp::SignatureHelp>, Failure> {
    Ok(
        at(docs, &p.text_document_position_params).and_then(|(o, offset)| {
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
        }),
    )
}
