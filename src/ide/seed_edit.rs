//! Seed edits as text edits: add, move and remove a seed, and merge two, in an atlas
//! block. The viewer's mouse actions (`sdfc view`) make them; they are [`Edit`]s like
//! the language server's code actions, applied with [`super::actions::apply`], so
//! comments, formatting and every other byte of the file stay as they were.
//!
//! Each function only computes the edits. [`checked`] applies them and analyses the
//! result: an edit is taken only when the scene still checks without errors, and a
//! merge also only when the compiler accepts that merge (no warning on it: unreachable
//! seeds, an obstruction on a cycle).

use super::Document;
use crate::diagnostic::{Diagnostic, Edit};
use crate::sema::AtlasDef;
use crate::span::Span;
use crate::syntax::ast::{AtlasStmt, ItemKind};
use glam::DVec3;

/// A number as written into the scene: `decimals` at most, no trailing zeros.
pub fn number(x: f64, decimals: usize) -> String {
    let s = format!("{x:.decimals$}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" || s.is_empty() {
        "0".into()
    } else {
        s.to_string()
    }
}

/// A position as a vector literal, with nine decimals at most (picking is exact to
/// 1e-9 of the scene's size).
pub fn vec3(p: DVec3) -> String {
    let n = |x| number(x, 9);
    format!("[{}, {}, {}]", n(p.x), n(p.y), n(p.z))
}

fn atlas<'a>(doc: &'a Document, name: &str) -> Result<&'a AtlasDef, String> {
    doc.analysis
        .program
        .atlases
        .iter()
        .find(|a| a.name == name)
        .ok_or_else(|| format!("no atlas `{name}`"))
}

/// The statements of an atlas's block in the syntax tree.
pub(super) fn body<'a>(doc: &'a Document, def: &AtlasDef) -> Result<&'a [AtlasStmt], String> {
    doc.analysis
        .parsed
        .file
        .items
        .iter()
        .find_map(|item| match &item.kind {
            ItemKind::Atlas { name, body, .. } if name.span == doc_def_span(doc, def) => {
                Some(body.as_slice())
            }
            _ => None,
        })
        .ok_or_else(|| format!("atlas `{}` has no block to edit", def.name))
}

/// The span of an atlas's name where it is defined.
fn doc_def_span(doc: &Document, def: &AtlasDef) -> Span {
    doc.analysis.program.def(def.def).span
}

/// The start of the line holding `offset`.
pub(super) fn line_start(text: &str, offset: usize) -> usize {
    text[..offset].rfind('\n').map_or(0, |i| i + 1)
}

/// The end of the line holding `offset`, past its newline.
pub(super) fn line_end(text: &str, offset: usize) -> usize {
    text[offset..]
        .find('\n')
        .map_or(text.len(), |i| offset + i + 1)
}

/// The whitespace that starts the line holding `offset`.
pub(super) fn indent(text: &str, offset: usize) -> &str {
    let start = line_start(text, offset);
    let rest = &text[start..];
    &rest[..rest.len() - rest.trim_start_matches([' ', '\t']).len()]
}

/// Where a new statement goes and the text that puts `stmt` there: on its own line
/// after the last statement for which `after` holds (else after the last statement),
/// with that statement's indentation; on the same line when code follows it there
/// (`{ seed a = …; }`); first in the block when it is empty.
fn insertion(
    doc: &Document,
    def: &AtlasDef,
    after: impl Fn(&AtlasStmt) -> bool,
    stmt: &str,
) -> Edit {
    let text = &doc.text;
    let span_of = |s: &AtlasStmt| match s {
        AtlasStmt::Setting(s) => s.span,
        AtlasStmt::Seed { span, .. } | AtlasStmt::Merge { span, .. } => *span,
        AtlasStmt::Error(span) => *span,
    };
    let stmts = body(doc, def).unwrap_or(&[]);
    let anchor = stmts
        .iter()
        .rev()
        .find(|s| after(s))
        .or(stmts.last())
        .map(span_of);
    let (end, ind) = match anchor {
        Some(span) => (
            span.end.min(text.len()),
            indent(text, span.start).to_string(),
        ),
        None => {
            let item = &text[def.span.start..def.span.end.min(text.len())];
            let Some(open) = item.find('{') else {
                return Edit {
                    span: Span::new(def.span.end, def.span.end),
                    text: format!(" {{ {stmt} }}"),
                };
            };
            (
                def.span.start + open + 1,
                format!("{}    ", indent(text, def.span.start)),
            )
        }
    };
    let eol = text[end..].find('\n').map_or(text.len(), |i| end + i);
    let rest = text[end..eol].trim();
    let (at, text) = if rest.is_empty() || rest.starts_with("//") {
        if eol == text.len() {
            (eol, format!("\n{ind}{stmt}\n"))
        } else {
            (eol + 1, format!("{ind}{stmt}\n"))
        }
    } else {
        (end, format!(" {stmt}"))
    };
    Edit {
        span: Span::new(at, at),
        text,
    }
}

/// A name `sK` that no definition of the program has.
pub fn fresh_seed_name(doc: &Document) -> String {
    let taken = |n: &str| doc.analysis.program.defs.iter().any(|d| d.name == n);
    (0..)
        .map(|k| format!("s{k}"))
        .find(|n| !taken(n))
        .expect("an unused name")
}

/// Adds `seed NAME = [x, y, z];` to atlas `atlas`, after its last seed. Returns the
/// edits and the new seed's name.
pub fn add_seed(doc: &Document, atlas_name: &str, p: DVec3) -> Result<(Vec<Edit>, String), String> {
    let def = atlas(doc, atlas_name)?;
    let name = fresh_seed_name(doc);
    let stmt = format!("seed {name} = {};", vec3(p));
    let edit = insertion(doc, def, |s| matches!(s, AtlasStmt::Seed { .. }), &stmt);
    Ok((vec![edit], name))
}

/// Moves seed `seed` of atlas `atlas` to `p`: its position is rewritten as a literal
/// (a tangent, when it has one, stays).
pub fn move_seed(
    doc: &Document,
    atlas_name: &str,
    seed: &str,
    p: DVec3,
) -> Result<Vec<Edit>, String> {
    let def = atlas(doc, atlas_name)?;
    let s = def
        .seeds
        .iter()
        .find(|s| s.name == seed)
        .ok_or_else(|| format!("atlas `{atlas_name}` has no seed `{seed}`"))?;
    Ok(vec![Edit {
        span: s.position_span,
        text: vec3(p),
    }])
}

/// The span that removing the statement at `span` deletes: the statement, and its line
/// when nothing else is on it (its indentation, a comment after it and the newline).
fn statement_removal(text: &str, span: Span) -> Span {
    let start = line_start(text, span.start);
    let end = line_end(text, span.end.min(text.len()));
    let before = &text[start..span.start];
    let after = text[span.end..end].trim();
    if before.trim().is_empty() && (after.is_empty() || after.starts_with("//")) {
        Span::new(start, end)
    } else {
        span
    }
}

/// Removes seed `seed` from atlas `atlas`, with its merges: a `merge` statement that
/// names it loses the pairs through it, and goes when none is left. A seed that is
/// used anywhere but in its atlas's merges is not removed.
pub fn remove_seed(doc: &Document, atlas_name: &str, seed: &str) -> Result<Vec<Edit>, String> {
    let def = atlas(doc, atlas_name)?;
    let text = &doc.text;
    let s = def
        .seeds
        .iter()
        .find(|s| s.name == seed)
        .ok_or_else(|| format!("atlas `{atlas_name}` has no seed `{seed}`"))?;
    let item = doc.analysis.program.def(s.def).item_span;
    let stmts = body(doc, def)?;
    let merge_spans: Vec<Span> = stmts
        .iter()
        .filter_map(|st| match st {
            AtlasStmt::Merge { span, .. } => Some(*span),
            _ => None,
        })
        .collect();
    if let Some(r) = doc.analysis.program.references_to(s.def).find(|r| {
        !merge_spans
            .iter()
            .any(|m| m.start <= r.span.start && r.span.end <= m.end)
    }) {
        return Err(format!(
            "seed `{seed}` is used outside its merges (at byte {}); remove that use first",
            r.span.start
        ));
    }
    let mut edits = vec![Edit {
        span: statement_removal(text, item),
        text: String::new(),
    }];
    for st in stmts {
        let AtlasStmt::Merge { seeds, span } = st else {
            continue;
        };
        if !seeds.iter().any(|n| n.name == seed) {
            continue;
        }
        // The pairs of the chain that do not touch the seed, as chains again.
        let names: Vec<&str> = seeds.iter().map(|n| n.name.as_str()).collect();
        let mut chains: Vec<Vec<&str>> = Vec::new();
        for pair in names.windows(2) {
            if pair.contains(&seed) {
                continue;
            }
            match chains.last_mut() {
                Some(c) if c.last() == Some(&pair[0]) => c.push(pair[1]),
                _ => chains.push(vec![pair[0], pair[1]]),
            }
        }
        if chains.is_empty() {
            edits.push(Edit {
                span: statement_removal(text, *span),
                text: String::new(),
            });
        } else {
            // (A comment inside the statement, between its names, goes with it.)
            let ind = indent(text, span.start).to_string();
            let rewritten: Vec<String> = chains
                .iter()
                .map(|c| format!("merge {};", c.join(" ")))
                .collect();
            edits.push(Edit {
                span: *span,
                text: rewritten.join(&format!("\n{ind}")),
            });
        }
    }
    Ok(edits)
}

/// Merges seeds `a` and `b` of atlas `atlas`: `merge a b;` after the last merge or
/// seed statement, whichever comes last.
pub fn merge(doc: &Document, atlas_name: &str, a: &str, b: &str) -> Result<Vec<Edit>, String> {
    let def = atlas(doc, atlas_name)?;
    let index = |n: &str| {
        def.seeds
            .iter()
            .position(|s| s.name == n)
            .ok_or_else(|| format!("atlas `{atlas_name}` has no seed `{n}`"))
    };
    let (ia, ib) = (index(a)?, index(b)?);
    if ia == ib {
        return Err(format!("seed `{a}` cannot be merged with itself"));
    }
    if def
        .merges
        .iter()
        .any(|m| (m.a, m.b) == (ia, ib) || (m.a, m.b) == (ib, ia))
    {
        return Err(format!("seeds `{a}` and `{b}` are already merged"));
    }
    let stmt = format!("merge {a} {b};");
    Ok(vec![insertion(
        doc,
        def,
        |s| matches!(s, AtlasStmt::Merge { .. } | AtlasStmt::Seed { .. }),
        &stmt,
    )])
}

/// The outcome of [`checked`]: the edited text and its analysis, or why it was refused
/// with the diagnostics that refuse it (rendered against the edited text).
pub enum Checked {
    Accepted {
        text: String,
        doc: Document,
    },
    Refused {
        text: String,
        reason: String,
        diagnostics: Vec<Diagnostic>,
    },
}

/// Applies `edits` to the document and checks the result (reading textures under
/// `access`): refused when it has errors (an unreachable merge is one), or when
/// `strict` is set and it has a warning the document did not have (a merge that
/// closes a cycle with an obstruction).
pub fn checked(
    doc: &Document,
    edits: &[Edit],
    access: &crate::access::Access,
    strict: bool,
) -> Checked {
    let text = super::actions::apply(&doc.text, edits);
    let after = Document::with_access(text.clone(), access);
    let errors: Vec<Diagnostic> = after
        .analysis
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .cloned()
        .collect();
    if !errors.is_empty() {
        return Checked::Refused {
            text,
            reason: String::from("the edited scene has errors"),
            diagnostics: errors,
        };
    }
    if strict {
        // Warnings the edit brought (by code and message, as spans move): a merge that
        // closes a cycle with an obstruction, or merges seeds already merged.
        // Counted, so that a second warning like one already there is new too.
        let key = |d: &Diagnostic| (d.code, d.message.clone());
        let mut before: Vec<_> = doc.analysis.diagnostics.iter().map(key).collect();
        let new: Vec<Diagnostic> = after
            .analysis
            .diagnostics
            .iter()
            .filter(|d| match before.iter().position(|k| *k == key(d)) {
                Some(i) => {
                    before.swap_remove(i);
                    false
                }
                None => true,
            })
            .cloned()
            .collect();
        if !new.is_empty() {
            return Checked::Refused {
                text,
                reason: String::from("the compiler does not accept this merge"),
                diagnostics: new,
            };
        }
    }
    Checked::Accepted { text, doc: after }
}
