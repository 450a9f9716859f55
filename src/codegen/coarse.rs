//! The multi-scale atlas pass (`Options::multiscale`; "multi-scale rendering" of the
//! Implicit UVs paper's §7): the atlases that materials read are walked once per
//! [`STEP`] × [`STEP`] pixels by the compute entry point `cs_coarse`, into the `coarse`
//! storage buffer, and the render's materials rebuild each pixel's sample from the four
//! coarse samples around it where they agree, walking only where they do not (chart
//! borders, seams, silhouettes, failed walks, curved or bent uv). The rules are in
//! `shaders/coarse.wgsl.in` and, in f64, `reference::coarse` (with the constants); the
//! runtime side is `gpu::coarse`.
//!
//! What this module writes: the template's code, with the slots (the atlases materials
//! read, in index order), which slots each material reads (`coarse_reads`), the
//! samples `cs_coarse` walks, and `atlas_K_pixel(p, m)`, which a material of id `m`
//! calls instead of `atlas_K_at(p, true)`. Everything else (displacements, the atlas
//! views, the compute entry points) walks as without the pass: `coarse_pixel` is
//! negative outside `shade_pixel`.

use super::manifest::{CoarsePass, COARSE_HOW};
use super::{internal, template, Generator, Options};
use crate::diagnostic::Diagnostic;
use crate::reference::coarse::atlas_merged_bits;
use crate::uv::Atlas;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write;

pub use crate::reference::coarse::{CONDITION, FLATNESS, STEP, TOLERANCE};

/// The atlases materials read (the slots, by atlas index) and, per material case id,
/// the atlases it reads.
#[derive(Debug, Clone, Default)]
pub struct Reads {
    pub by_material: Vec<(i32, BTreeSet<usize>)>,
    /// Atlases whose `seed` or `transport` a material reads: their rebuilt pixels stay
    /// within one seed's region.
    pub discrete: BTreeSet<usize>,
}

impl Reads {
    /// The slots: every atlas some material reads, in index order.
    pub fn slots(&self) -> Vec<usize> {
        let all: BTreeSet<usize> = self
            .by_material
            .iter()
            .flat_map(|(_, s)| s.iter().copied())
            .collect();
        all.into_iter().collect()
    }
}

impl Generator<'_> {
    /// With `Options::multiscale`, the pass's code (after the materials, whose reads it
    /// needs); returns the slots (zero without the pass) and the atlas AOV's expression:
    /// with the pass, the chosen atlas as materials read it.
    pub(super) fn multiscale_pass(
        &mut self,
        atlases: &[Option<Atlas>],
        options: &Options,
    ) -> Result<(usize, String), Vec<Diagnostic>> {
        let merged = match self.multiscale {
            true => self.merged_tables(atlases),
            false => BTreeMap::new(),
        };
        let pass = match self.multiscale {
            true => code(&self.reads, atlases, &merged).map_err(internal)?,
            false => None,
        };
        let Some(pass) = pass else {
            return Ok((0, String::from("scene_atlas(p)")));
        };
        self.out.push_str(&pass);
        let slots = self.reads.slots();
        let all = &self.program.atlases;
        let chosen = match options.atlas.as_deref() {
            Some(name) => all.iter().position(|a| a.name == name),
            None => (!all.is_empty()).then_some(0),
        };
        let aov = match chosen {
            Some(k) if slots.contains(&k) => format!("atlas_{k}_pixel(p, i32(hit.z + 0.5))"),
            _ => String::from("scene_atlas(p)"),
        };
        Ok((slots.len(), aov))
    }
}

impl Generator<'_> {
    /// The tables of merged seeds (`reference::coarse::MergedBits`) of the atlases whose
    /// rebuilt pixels may cross merged frontiers, appended to the `tables` buffer: by
    /// atlas index, the table's first word and its row's words. Not for an atlas whose
    /// `seed` or `transport` a material reads (they change at a frontier), a moving one
    /// (the host rewrites its merges), or one past `MERGED_TABLE_SEEDS` seeds.
    fn merged_tables(&mut self, atlases: &[Option<Atlas>]) -> BTreeMap<usize, (u32, u32)> {
        let mut out = BTreeMap::new();
        for a in self.reads.slots() {
            let moving = self.moving.iter().any(|m| m.index == a);
            if moving || self.reads.discrete.contains(&a) {
                continue;
            }
            let Some(bits) = atlases
                .get(a)
                .and_then(Option::as_ref)
                .and_then(atlas_merged_bits)
            else {
                continue;
            };
            out.insert(a, (self.tables.len() as u32, bits.row as u32));
            self.tables.extend(bits.words);
        }
        out
    }
}

/// The pass's code, or `None` when no material reads an atlas (the module is then as
/// without the pass). `atlases` are the prepared atlases by index; `merged`, by atlas
/// index, the first word and the row's words of the atlases' tables of merged seeds in
/// the `tables` buffer (an atlas without one rebuilds within one seed's region).
pub fn code(
    reads: &Reads,
    atlases: &[Option<Atlas>],
    merged: &BTreeMap<usize, (u32, u32)>,
) -> Result<Option<String>, String> {
    let slots = reads.slots();
    if slots.is_empty() {
        return Ok(None);
    }
    if slots.len() > 31 {
        return Err(format!(
            "the multi-scale pass holds at most 31 atlases read by materials, not {}",
            slots.len()
        ));
    }
    let slot_of = |a: usize| slots.iter().position(|&s| s == a).unwrap_or(0);
    let mut arms = String::new();
    for (m, used) in &reads.by_material {
        if used.is_empty() {
            continue;
        }
        let mask: u32 = used.iter().map(|&a| 1u32 << slot_of(a)).sum();
        let _ = writeln!(
            arms,
            "        case {m}: {{\n            return {mask}u;\n        }}"
        );
    }
    let mut samples = String::new();
    let mut pixel = String::new();
    for (k, &a) in slots.iter().enumerate() {
        let at = 1 + 4 * k;
        let _ = writeln!(
            samples,
            "    if ((reads & {bit}u) != 0u) {{\n        coarse_store(base + {at}u, atlas_{a}_at(p, true));\n    }} else {{\n        coarse[base + {at}u] = vec4<f32>(0.0, 0.0, -1.0, -1.0);\n    }}",
            bit = 1u32 << k
        );
        let reach = atlases
            .get(a)
            .and_then(Option::as_ref)
            .map_or(1.0, |atlas| atlas.params.max_distance);
        let tolerance = super::literal::lit(TOLERANCE * reach);
        let (merged_at, row) = merged.get(&a).copied().unwrap_or((0, 0));
        let _ = write!(
            pixel,
            "// Atlas {a}'s sample where a material of id m reads it at p: rebuilt from the
// multi-scale pass's coarse samples (coarse_rebuild) in a render pixel where they agree,
// walked elsewhere.
fn atlas_{a}_pixel(p: vec3<f32>, m: i32) -> AtlasSample {{
    let r = coarse_rebuild({k}u, p, m, {tolerance}, {merged_at}u, {row}u);
    if (r.status != f32(COARSE_WALK)) {{
        return r;
    }}
    if (coarse_pixel.x >= 0.0) {{
        coarse_walks = coarse_walks + 1u;
    }}
    return atlas_{a}_at(p, true);
}}

"
        );
    }
    let filled = template::fill(
        template::COARSE,
        &[
            ("step", STEP.to_string()),
            ("side", WORKGROUP_SIDE.to_string()),
            ("slots", slots.len().to_string()),
            ("flatness", super::literal::lit(FLATNESS)),
            ("condition", super::literal::lit(CONDITION)),
            ("reads", arms),
            ("samples", samples),
        ],
    )
    .map_err(|e| e.to_string())?;
    Ok(Some(format!("{filled}\n{pixel}")))
}

/// The `coarse` buffer's size in bytes for a `width` × `height` frame of a module with
/// `slots` slots (what `cs_coarse` writes and `coarse_ready` checks).
pub fn buffer_bytes(width: u32, height: u32, slots: usize) -> u64 {
    let (cols, rows) = grid(width, height);
    cols as u64 * rows as u64 * (1 + 4 * slots as u64) * 16
}

/// The pass's contract in the manifest, for a module with `slots` slots (`None`
/// without the pass).
pub fn contract(bindings: &[super::bindings::Binding], slots: usize) -> Option<CoarsePass> {
    let binding = bindings
        .iter()
        .find(|b| b.resource == super::bindings::Resource::Coarse)?;
    (slots > 0).then(|| CoarsePass {
        entry_point: "cs_coarse",
        binding: binding.binding,
        step: STEP,
        slots: slots as u32,
        vec4s_per_sample: 1 + 4 * slots as u32,
        workgroup_size: [WORKGROUP_SIDE, WORKGROUP_SIDE, 1],
        how: COARSE_HOW,
    })
}

/// The side of `cs_coarse`'s square workgroup (`shaders/coarse.wgsl.in`).
pub const WORKGROUP_SIDE: u32 = 8;

/// The workgroups of `cs_coarse` for a `width` × `height` frame.
pub fn workgroups(width: u32, height: u32) -> (u32, u32) {
    let (cols, rows) = grid(width, height);
    (cols.div_ceil(WORKGROUP_SIDE), rows.div_ceil(WORKGROUP_SIDE))
}

/// The coarse grid's columns and rows for a frame (`coarse_columns`, `coarse_rows`).
pub fn grid(width: u32, height: u32) -> (u32, u32) {
    let axis = |n: u32| (n.max(1) + STEP - 2) / STEP + 1;
    (axis(width), axis(height))
}
