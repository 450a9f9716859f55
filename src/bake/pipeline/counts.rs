//! What the report says of the material's samples (the bake's stage 6): counts of what
//! the images cannot hold as the material has it, and the emissive strength; with
//! `--bounds`, of the samples the file shows.

use super::super::images;
use super::super::mips::{Texel, CHANNELS, EMISSION};
use super::super::ChartLayout;
use super::{Report, Samples};
use crate::ir::Aabb;
use glam::DVec3;

/// The emissive strength ([`images::emissive_strength`]): over the atlas's levels, or
/// with `bounds` over level 0's samples in them ([`shown`]: a brighter sample cut away
/// would dim what the file shows).
pub(super) fn emissive_strength(
    levels: &[Samples<Texel<CHANNELS>>],
    atlas: &ChartLayout,
    points: &Samples<[f32; 3]>,
    bounds: Option<Aabb>,
) -> f32 {
    match bounds {
        None => images::emissive_strength(
            levels[..atlas.levels().min(levels.len())]
                .iter()
                .flat_map(|l| l.iter()),
        ),
        bounds => images::emissive_strength(shown(&levels[0], points, bounds)),
    }
}

/// Level 0's samples that the file shows: with `--bounds`, those whose point lies in
/// them (the quads kept reach past the box, and the cut drops the rest).
fn shown<'a>(
    level0: &'a Samples<Texel<CHANNELS>>,
    points: &'a Samples<[f32; 3]>,
    bounds: Option<Aabb>,
) -> impl Iterator<Item = &'a Texel<CHANNELS>> + 'a {
    level0.iter().zip(points.iter()).filter_map(move |(t, p)| {
        let p = DVec3::from_array(p.map(f64::from));
        let inside = bounds.is_none_or(|b| p.cmpge(b.min).all() && p.cmple(b.max).all());
        inside.then_some(t)
    })
}

/// Of level 0's samples the file shows ([`shown`]): how many; where the material is
/// undefined (a channel not finite); where its emission is finite and over 1; and
/// where a finite value is out of what the images hold ([`Report::shown`],
/// [`Report::undefined`], [`Report::emission_over_one`], [`Report::out_of_range`]).
fn material_counts<'a>(shown: impl Iterator<Item = &'a Texel<CHANNELS>>) -> [usize; 4] {
    // Half an 8-bit step: a clamp by less changes no texel.
    let slack = 0.5 / 255.0;
    let out = |t: &Texel<CHANNELS>| {
        let unit = t[..EMISSION.start]
            .iter()
            .any(|&v| v.is_finite() && !(-slack..=1.0 + slack).contains(&v));
        unit || t[EMISSION].iter().any(|&v| v.is_finite() && v < -slack)
    };
    let mut counts = [0; 4];
    for t in shown {
        counts[0] += 1;
        counts[1] += usize::from(t.iter().any(|v| !v.is_finite()));
        counts[2] += usize::from(t[EMISSION].iter().any(|&v| v.is_finite() && v > 1.0));
        counts[3] += usize::from(out(t));
    }
    counts
}

/// Of level 0's samples the file shows ([`shown`]), those that emit, and those of them
/// whose every emitting channel rounds to 0 in the 8-bit texture once divided by
/// `strength` ([`Report::emission_lost`]).
fn emission_lost<'a>(
    shown: impl Iterator<Item = &'a Texel<CHANNELS>>,
    strength: f32,
) -> (usize, usize) {
    let emits = |v: f32| v.is_finite() && v > 0.0;
    let (mut emitting, mut lost) = (0, 0);
    for t in shown {
        let e = &t[EMISSION];
        if e.iter().any(|&v| emits(v)) {
            emitting += 1;
            if e.iter()
                .all(|&v| !emits(v) || images::srgb8(v / strength) == 0)
            {
                lost += 1;
            }
        }
    }
    (emitting, lost)
}

/// The report's counts of level 0's samples the file shows ([`material_counts`]).
pub(super) fn count_material(
    report: &mut Report,
    level0: &Samples<Texel<CHANNELS>>,
    points: &Samples<[f32; 3]>,
    bounds: Option<Aabb>,
) {
    [
        report.shown,
        report.undefined,
        report.emission_over_one,
        report.out_of_range,
    ] = material_counts(shown(level0, points, bounds));
}

/// The report's counts of emitting samples the file shows, and of those the strength
/// dims to 0 ([`emission_lost`]).
pub(super) fn count_emission(
    report: &mut Report,
    level0: &Samples<Texel<CHANNELS>>,
    points: &Samples<[f32; 3]>,
    bounds: Option<Aabb>,
) {
    (report.emitting, report.emission_lost) =
        emission_lost(shown(level0, points, bounds), report.emissive_strength);
}
