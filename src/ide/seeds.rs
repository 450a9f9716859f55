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

/// The title of the action.
pub const TITLE: &str = "Place seeds automatically";

/// Surface samples: dual-contouring cells along the shape's longest side.
pub const GRID: usize = 40;

fn num(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

fn vec3(p: DVec3) -> String {
    format!("[{}, {}, {}]", num(p.x), num(p.y), num(p.z))
}

/// The placement as atlas statements, four spaces in.
pub fn statements(placement: &Placement) -> String {
    let mut out = String::new();
    for (k, (p, t)) in placement.seeds.iter().enumerate() {
        match t {
            Some(t) => out.push_str(&format!(
                "    seed s{k} = {} tangent {};\n",
                vec3(*p),
                vec3(*t)
            )),
            None => out.push_str(&format!("    seed s{k} = {};\n", vec3(*p))),
        }
    }
    for (a, b) in &placement.merges {
        out.push_str(&format!("    merge s{a} s{b};\n"));
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

/// The atlases whose item touches `range`, by name, with their item spans: where the
/// action is offered. Only when the document has no errors besides atlases without
/// seeds (what the action is for).
pub fn offered(doc: &Document, range: Span) -> Vec<(String, Span)> {
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
        .map(|a| (a.name.clone(), a.span))
        .collect()
}

/// Places seeds and merges for atlas `name` and returns the placement with the edit
/// that writes them into its block.
pub fn place_edit(
    doc: &Document,
    name: &str,
    options: PlaceOptions,
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
    let samples = surface_samples(&shape, GRID)?;
    let placement = place(def, &shape, &samples, options);
    let span = def.span;
    let item = doc
        .text
        .get(span.start..span.end)
        .ok_or_else(|| String::from("the atlas's span is outside the text"))?;
    let text = rewrite(item, &statements(&placement))
        .ok_or_else(|| format!("cannot find the body of atlas `{name}`"))?;
    Ok((placement, Edit { span, text }))
}
