//! Code actions (the fixes diagnostics carry), inlay hints (folded constant values and
//! geodesic merge lengths) and hover on `merge` statements.

use super::{Document, Hover};
use crate::diagnostic::{Diagnostic, Edit};
use crate::sema::{DefKind, Value};
use crate::span::Span;
use crate::syntax::ast::{AtlasStmt, ExprKind, ItemKind};

/// A quick fix for one diagnostic.
#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    pub title: String,
    /// The diagnostic it fixes.
    pub diagnostic: Diagnostic,
    pub edits: Vec<Edit>,
    /// The fix the editor may apply without asking (the only fix of its diagnostic).
    pub preferred: bool,
}

/// Where a diagnostic's fixes are offered: its primary span, widened to the whole
/// seed statement for a diagnostic about a seed's written position (such as "snap
/// seed to surface"), so that the cursor anywhere on the seed finds it.
fn reach(doc: &Document, d: &Diagnostic) -> Option<Span> {
    let span = d.span()?;
    let program = &doc.analysis.program;
    Some(
        program
            .atlases
            .iter()
            .flat_map(|a| &a.seeds)
            .find(|s| s.position_span == span)
            .map_or(span, |s| program.def(s.def).item_span.to(span)),
    )
}

/// The fixes of every diagnostic whose [`reach`] touches `range`.
pub fn code_actions(doc: &Document, range: Span) -> Vec<Action> {
    let touches = |s: Span| s.start <= range.end && range.start <= s.end;
    let mut out = Vec::new();
    for d in &doc.analysis.diagnostics {
        if !reach(doc, d).is_some_and(touches) {
            continue;
        }
        for f in &d.fixes {
            out.push(Action {
                title: f.title.clone(),
                diagnostic: d.clone(),
                edits: f.edits.clone(),
                preferred: d.fixes.len() == 1,
            });
        }
    }
    out
}

/// The text of a document after applying edits (non-overlapping, any order).
pub fn apply(text: &str, edits: &[Edit]) -> String {
    let mut edits: Vec<&Edit> = edits.iter().collect();
    edits.sort_by_key(|e| std::cmp::Reverse(e.span.start));
    let mut out = text.to_string();
    for e in edits {
        if e.span.end <= out.len() && e.span.start <= e.span.end {
            out.replace_range(e.span.start..e.span.end, &e.text);
        }
    }
    out
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InlayKind {
    /// The folded value of a `let` whose expression is not a plain literal.
    Value,
    /// The geodesic length of a merge edge, between its two seed names.
    Merge,
}

#[derive(Debug, Clone, PartialEq)]
pub struct InlayHint {
    /// Byte offset the hint is drawn at.
    pub offset: usize,
    pub label: String,
    pub kind: InlayKind,
}

fn is_literal(kind: &ExprKind) -> bool {
    match kind {
        ExprKind::Number { .. } | ExprKind::Bool(_) | ExprKind::Str(_) => true,
        ExprKind::Unary { expr, .. } => is_literal(&expr.kind),
        ExprKind::Vector(items) => items.iter().all(|i| is_literal(&i.kind)),
        _ => false,
    }
}

/// Inlay hints inside `range`: folded constants and merge lengths.
pub fn inlay_hints(doc: &Document, range: Span) -> Vec<InlayHint> {
    let program = &doc.analysis.program;
    let inside = |o: usize| range.start <= o && o <= range.end;
    let mut out = Vec::new();
    for item in &doc.analysis.parsed.file.items {
        let ItemKind::Let { name, value } = &item.kind else {
            continue;
        };
        if is_literal(&value.kind) || !inside(value.span.end) {
            continue;
        }
        let Some(def) = program
            .defs
            .iter()
            .find(|d| d.kind == DefKind::Let && d.span == name.span)
        else {
            continue;
        };
        if matches!(def.value, Value::Float(_) | Value::Vec(_) | Value::Bool(_)) {
            out.push(InlayHint {
                offset: value.span.end,
                label: format!("= {}", def.value.display()),
                kind: InlayKind::Value,
            });
        }
    }
    for (k, atlas) in program.atlases.iter().enumerate() {
        let Some(Some(prepared)) = doc.analysis.atlases.get(k) else {
            continue;
        };
        for (m, merge) in atlas.merges.iter().enumerate() {
            // The merge's span runs from its first seed name to its second: the hint goes
            // in the gap, just after the first name.
            let text = doc.text.get(merge.span.start..merge.span.end).unwrap_or("");
            let first = text.find(|c: char| c.is_whitespace()).unwrap_or(text.len());
            let offset = merge.span.start + first;
            if !inside(offset) {
                continue;
            }
            let label = match prepared.graph.edges.iter().find(|e| e.merge == m) {
                Some(e) => format!("─ {:.3} ─", e.length),
                None => String::from("─ unreachable ─"),
            };
            out.push(InlayHint {
                offset,
                label,
                kind: InlayKind::Merge,
            });
        }
    }
    out.sort_by_key(|h| h.offset);
    out
}

/// Hover on a `merge` statement (away from its seed names, which hover as seeds): each
/// edge's geodesic length, transport angle and offset residual.
pub fn merge_hover(doc: &Document, offset: usize) -> Option<Hover> {
    let program = &doc.analysis.program;
    for item in &doc.analysis.parsed.file.items {
        let ItemKind::Atlas { name, body, .. } = &item.kind else {
            continue;
        };
        let Some(k) = program.atlases.iter().position(|a| a.name == name.name) else {
            continue;
        };
        let atlas = &program.atlases[k];
        for s in body {
            let AtlasStmt::Merge { seeds, span } = s else {
                continue;
            };
            if !span.contains(offset) {
                continue;
            }
            let names: Vec<&str> = seeds.iter().map(|s| s.name.as_str()).collect();
            let mut text = format!(
                "```sdf\nmerge {}\n```\nin atlas `{}`",
                names.join(" "),
                atlas.name
            );
            let prepared = doc.analysis.atlases.get(k).and_then(|p| p.as_ref());
            for (m, def) in atlas.merges.iter().enumerate() {
                if !span.contains(def.span.start) {
                    continue;
                }
                let (a, b) = (&atlas.seeds[def.a].name, &atlas.seeds[def.b].name);
                let edge = prepared.and_then(|p| p.graph.edges.iter().find(|e| e.merge == m));
                text += &match (prepared, edge) {
                    (_, Some(e)) => {
                        let angle = glam::DQuat::from_mat3(&e.transport)
                            .to_axis_angle()
                            .1
                            .to_degrees();
                        format!(
                            "\n\n`{a}` – `{b}`: geodesic length {:.4}; transport turns {angle:.1}°; offset residual {:.1}%",
                            e.length,
                            100.0 * e.residual
                        )
                    }
                    (Some(_), None) => {
                        format!("\n\n`{a}` – `{b}`: not merged (the walk between them failed)")
                    }
                    (None, None) => format!(
                        "\n\n`{a}` – `{b}`: fix the errors in the file to see its geodesic length"
                    ),
                };
            }
            return Some(Hover {
                span: *span,
                markdown: text,
            });
        }
    }
    None
}
