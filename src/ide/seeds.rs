//! "Place seeds automatically": the automatic placement of [`crate::uv::seeds`] as an
//! edit of an atlas block, for the language server's code action and `sdfc seeds
//! --write` alike. Placing takes one to a few seconds, so the server offers
//! the action cheaply and computes the edit only when it is chosen (`codeAction/resolve`).

use super::{seed_edit, Document};
use crate::diagnostic::Edit;
use crate::reference::surface::{surface_samples, surface_samples_salted};
use crate::sema::AtlasDef;
use crate::span::Span;
use crate::syntax::ast::AtlasStmt;
use crate::uv::seeds::{place, PlaceOptions, Placement};
use glam::DVec3;

/// The titles of the actions: all seeds anew, or the seeds there kept and added to.
pub const TITLE: &str = "Place seeds automatically";
pub const TITLE_KEEP: &str = "Add seeds to cover the gaps";

/// The surface samples' grid: cells along the shape's longest side (the default).
pub const GRID: usize = 40;

/// A position as a vector literal, six decimals at most.
fn vec3(p: DVec3) -> String {
    let n = |x| super::seed_edit::number(x, 6);
    format!("[{}, {}, {}]", n(p.x), n(p.y), n(p.z))
}

/// The placement as atlas statements, four spaces in: every seed and merge, named
/// `s0`, `s1`, …
pub fn statements(placement: &Placement) -> String {
    let names: Vec<String> = (0..placement.seeds.len())
        .map(|k| format!("s{k}"))
        .collect();
    added(placement, &names, 0, 0)
}

/// The statements of the seeds from `from_seed` on and the merges from `from_merge`
/// on, with the seeds named by `names`.
fn added(placement: &Placement, names: &[String], from_seed: usize, from_merge: usize) -> String {
    let mut out = String::new();
    for (k, (p, t)) in placement.seeds.iter().enumerate().skip(from_seed) {
        let name = &names[k];
        match t {
            Some(t) => out.push_str(&format!(
                "    seed {name} = {} tangent {};\n",
                vec3(*p),
                vec3(*t)
            )),
            None => out.push_str(&format!("    seed {name} = {};\n", vec3(*p))),
        }
    }
    for (a, b) in placement.merges.iter().skip(from_merge) {
        out.push_str(&format!("    merge {} {};\n", names[*a], names[*b]));
    }
    out
}

/// The edit that writes `statements` into atlas `def`'s block instead of its seeds
/// and merges, over the atlas item's span. Built from the syntax tree: each `seed` and
/// `merge` statement goes, with the whitespace that only served it (its line when
/// nothing else is on it; else the spaces between it and the code before it, or after
/// it when it starts its line), and the blank lines that its going would double;
/// every other byte stays (settings, comments, a comment after a seed on its line).
/// The new statements go on their own lines before the closing brace, which goes on
/// its own line at the item's indentation.
pub fn replace_seeds(doc: &Document, def: &AtlasDef, statements: &str) -> Result<Edit, String> {
    let text = doc.text.as_str();
    let span = def.span;
    let no_body = || format!("cannot find the body of atlas `{}`", def.name);
    let item = text.get(span.start..span.end).ok_or_else(no_body)?;
    let close = span.start + item.rfind('}').ok_or_else(no_body)?;
    let from = def.shape_span.end.clamp(span.start, close);
    let open = from + text[from..close].find('{').ok_or_else(no_body)?;
    let spans: Vec<Span> = seed_edit::body(doc, def)?
        .iter()
        .filter_map(|s| match s {
            AtlasStmt::Seed { span, .. } | AtlasStmt::Merge { span, .. } => Some(*span),
            _ => None,
        })
        .filter(|s| open < s.start && s.end <= close)
        .collect();
    let mut removed = merged(statement_removals(text, &spans));
    removed.extend(doubled_blank_lines(text, open, close, &removed));
    let removed = merged(removed);
    let mut out = String::new();
    let mut at = span.start;
    for r in &removed {
        out.push_str(&text[at..r.start]);
        at = r.end;
    }
    out.push_str(&text[at..close]);
    out.truncate(out.trim_end_matches([' ', '\t']).len());
    if !out.ends_with('\n') {
        out.push('\n');
    }
    out.push_str(statements);
    out.push_str(seed_edit::indent(text, span.start));
    out.push_str(&text[close..span.end]);
    Ok(Edit { span, text: out })
}

/// The pieces of `from..to` outside `spans` (sorted; clipped to the range).
fn gaps(from: usize, to: usize, spans: &[Span]) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut at = from;
    for s in spans {
        let (a, b) = (s.start.clamp(from, to), s.end.clamp(from, to));
        if a > at {
            out.push(at..a);
        }
        at = at.max(b);
    }
    if at < to {
        out.push(at..to);
    }
    out
}

/// The end of the line holding `offset`, before its newline.
fn line_stop(text: &str, offset: usize) -> usize {
    text[offset..].find('\n').map_or(text.len(), |i| offset + i)
}

/// The ranges that removing the statements at `spans` (sorted) deletes: the lines they
/// are on when nothing else is (apart from whitespace); else each statement with the
/// spaces and tabs before it, or after it when no code comes before it on its line.
fn statement_removals(text: &str, spans: &[Span]) -> Vec<Span> {
    let mut out = Vec::new();
    let mut k = 0;
    while k < spans.len() {
        // The statements on the lines from the first one's to the last one's.
        let start = seed_edit::line_start(text, spans[k].start);
        let mut j = k;
        let mut stop = line_stop(text, spans[k].end);
        while j + 1 < spans.len() && spans[j + 1].start <= stop {
            j += 1;
            stop = line_stop(text, spans[j].end);
        }
        let group = &spans[k..=j];
        let blank = |r: std::ops::Range<usize>| text[r].trim().is_empty();
        if gaps(start, stop, group).into_iter().all(blank) {
            out.push(Span::new(start, seed_edit::line_end(text, stop)));
        } else {
            for (n, s) in group.iter().enumerate() {
                let line = seed_edit::line_start(text, s.start);
                if gaps(line, s.start, &group[..n]).into_iter().all(blank) {
                    let rest = &text[s.end..];
                    let after = rest.len() - rest.trim_start_matches([' ', '\t']).len();
                    out.push(Span::new(s.start, s.end + after));
                } else {
                    let before = text[..s.start].trim_end_matches([' ', '\t']).len();
                    out.push(Span::new(before.max(line), s.end));
                }
            }
        }
        k = j + 1;
    }
    out
}

/// The ranges sorted, with those that overlap or touch joined.
fn merged(mut ranges: Vec<Span>) -> Vec<Span> {
    ranges.sort_by_key(|r| (r.start, r.end));
    let mut out: Vec<Span> = Vec::new();
    for r in ranges {
        match out.last_mut() {
            Some(last) if r.start <= last.end => last.end = last.end.max(r.end),
            _ => out.push(r),
        }
    }
    out
}

/// The blank lines of the block between `open` and `close` that the lines `removed`
/// (sorted, joined) would leave doubled, first in the block or last in it: a blank
/// line right after removed lines when the line kept before them is blank or the
/// block's first, or when the closing brace's line follows.
fn doubled_blank_lines(text: &str, open: usize, close: usize, removed: &[Span]) -> Vec<Span> {
    let first = seed_edit::line_end(text, open);
    let last = seed_edit::line_start(text, close);
    let mut out = Vec::new();
    let (mut blank_before, mut removed_since) = (true, false);
    let mut a = first;
    while a < last {
        let b = seed_edit::line_end(text, a).min(last);
        if removed.iter().any(|r| r.start <= a && b <= r.end) {
            removed_since = true;
        } else {
            let blank = text[a..b].trim().is_empty();
            if blank && removed_since && (blank_before || b == last) {
                out.push(Span::new(a, b));
            } else {
                blank_before = blank;
                removed_since = false;
            }
        }
        a = b;
    }
    out
}

/// The atlases whose item touches `range`, by name, with whether they have seeds (to
/// keep): where the actions are offered. Only when the document has no errors besides
/// atlases without seeds (what the actions are for).
pub fn offered(doc: &Document, range: Span) -> Vec<(String, bool)> {
    let blocking = doc
        .analysis
        .diagnostics
        .iter()
        .any(|d| d.is_error() && d.code != crate::codes::E_NO_SEEDS);
    if blocking {
        return Vec::new();
    }
    doc.analysis
        .program
        .atlases
        .iter()
        .filter(|a| a.span.start <= range.end && range.start <= a.span.end)
        .map(|a| (a.name.clone(), !a.seeds.is_empty()))
        .collect()
}

/// Places seeds on area-uniform samples and reports the coverage measured on a second,
/// independent draw of the same density: placement covers its own samples by
/// construction (the robot: 99.67 % of the fresh draw; 99.87 % by the coverage test's
/// independent measure). Placing again with the fresh draw added cost three times the time and
/// gained little.
fn place_held_out(
    def: &crate::sema::AtlasDef,
    shape: &crate::ir::Shape,
    options: PlaceOptions,
    grid: usize,
) -> Result<Placement, String> {
    let samples = surface_samples(shape, grid)?;
    let mut placement = place(def, shape, &samples, options);
    let fresh = surface_samples_salted(shape, grid, 1)?;
    let (coverage, failing) = crate::uv::seeds::coverage_on(def, shape, &placement, &fresh);
    placement.coverage = coverage;
    placement.failing = failing;
    Ok(placement)
}

/// Places seeds and merges for atlas `name` (area-uniform surface samples on a
/// `grid`-cell grid, [`GRID`] by default; coverage measured on a fresh draw) and returns the placement with the edit that writes them into
/// its block: the whole block's seeds and merges replaced, or with `options.keep` the
/// new ones added.
pub fn place_edit(
    doc: &Document,
    name: &str,
    options: PlaceOptions,
    grid: usize,
) -> Result<(Placement, Edit), String> {
    options.check()?;
    let def = doc
        .analysis
        .program
        .atlases
        .iter()
        .find(|a| a.name == name)
        .ok_or_else(|| format!("no atlas `{name}`"))?;
    let shape = crate::ir::lower_shape(&def.shape)
        .ok_or_else(|| format!("the shape of atlas `{name}` cannot be lowered"))?;
    let placement = place_held_out(def, &shape, options, grid)?;
    // Keeping seeds that do not prepare would name new seeds after them.
    if options.keep && placement.kept.0 != def.seeds.len() {
        return Err(format!(
            "the seeds of atlas `{name}` cannot be prepared (see its diagnostics): fix them, or place all seeds anew"
        ));
    }
    let span = def.span;
    let item = doc
        .text
        .get(span.start..span.end)
        .ok_or_else(|| String::from("the atlas's span is outside the text"))?;
    if options.keep {
        // New statements before the block's closing brace; the seeds there keep their
        // names, new ones are `autoK` (numbered past any name already taken).
        let close = item
            .rfind('}')
            .ok_or_else(|| format!("cannot find the body of atlas `{name}`"))?;
        let (seeds, merges) = placement.kept;
        let mut names: Vec<String> = def.seeds.iter().map(|s| s.name.clone()).collect();
        let mut k = 0;
        while names.len() < placement.seeds.len() {
            let candidate = format!("auto{k}");
            k += 1;
            if !names.contains(&candidate) {
                names.push(candidate);
            }
        }
        let text = added(&placement, &names, seeds, merges);
        let at = span.start + close;
        let before = item[..close].trim_end_matches([' ', '\t']);
        let lead = if before.ends_with('\n') { "" } else { "\n" };
        let edit = Edit {
            span: Span::new(at, at),
            text: format!("{lead}{text}"),
        };
        return Ok((placement, edit));
    }
    let edit = replace_seeds(doc, def, &statements(&placement))?;
    Ok((placement, edit))
}
