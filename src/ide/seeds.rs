//! "Place seeds automatically": the automatic placement of [`crate::uv::seeds`] as an
//! edit of an atlas block, for the language server's code action and `sdfc seeds
//! --write` alike. Placing takes about a second on the robot, so the server offers
//! the action cheaply and computes the edit only when it is chosen (`codeAction/resolve`).

use super::Document;
use crate::bake::mesh::surface_samples;
use crate::diagnostic::Edit;
use crate::span::Span;
use crate::uv::seeds::{place, PlaceOptions, Placement};
use glam::DVec3;

/// The titles of the actions: all seeds anew, or the seeds there kept and added to.
pub const TITLE: &str = "Place seeds automatically";
pub const TITLE_KEEP: &str = "Add seeds to cover the gaps";

/// Surface samples: dual-contouring cells along the shape's longest side (the default).
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

/// An atlas item's text with `statements` instead of its seeds and merges (other
/// settings and comments on their own lines stay); `None` without a body.
pub fn rewrite(item: &str, statements: &str) -> Option<String> {
    let open = item.find('{')?;
    let close = item.rfind('}')?;
    let inner = &item[open + 1..close];
    let mut kept = String::new();
    for line in inner.split_inclusive('\n') {
        let t = line.trim_start();
        if t.starts_with("seed ") || t.starts_with("merge ") {
            continue;
        }
        kept.push_str(line);
    }
    let mut body = String::from(kept.trim_end());
    body.push('\n');
    body.push_str(statements);
    Some(format!(
        "{}{{{}}}{}",
        &item[..open],
        body,
        &item[close + 1..]
    ))
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

/// Places seeds and merges for atlas `name` (surface samples on a `grid`-cell mesh,
/// [`GRID`] by default) and returns the placement with the edit that writes them into
/// its block: the whole block's seeds and merges replaced, or with `options.keep` the
/// new ones added.
pub fn place_edit(
    doc: &Document,
    name: &str,
    options: PlaceOptions,
    grid: usize,
) -> Result<(Placement, Edit), String> {
    let def = doc
        .analysis
        .program
        .atlases
        .iter()
        .find(|a| a.name == name)
        .ok_or_else(|| format!("no atlas `{name}`"))?;
    let shape = crate::ir::lower_shape(&def.shape)
        .ok_or_else(|| format!("the shape of atlas `{name}` cannot be lowered"))?;
    let samples = surface_samples(&shape, grid)?;
    let placement = place(def, &shape, &samples, options);
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
    let text = rewrite(item, &statements(&placement))
        .ok_or_else(|| format!("cannot find the body of atlas `{name}`"))?;
    Ok((placement, Edit { span, text }))
}
