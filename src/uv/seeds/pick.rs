//! Where the next seed goes: farthest-point sampling, and the snap of a curved
//! sample's seed to the flat faces beside it.

use super::{add_seed, SurfaceSample, COINCIDENT, FLATNESS, FLAT_COS, SNAP};
use crate::ir::Shape;
use crate::sema::AtlasDef;
use glam::DVec3;

/// [`SNAP`]: for a curved sample `k` not tried before (`snapped`), seeds at the flat
/// sample nearest to it and at the nearest on a face across the curve (within
/// `max_seeds`), in place of one at `k`. Returns whether any flat sample was near enough.
#[allow(clippy::type_complexity)]
pub(super) fn snap(
    (def, shape, samples): (&AtlasDef, &Shape, &[SurfaceSample]),
    k: usize,
    (reach, max_seeds): ((f64, Option<f64>), usize),
    (rejected, snapped): (&[bool], &mut [bool]),
    (seeds, best, covered_by_alg2): (
        &mut Vec<(DVec3, Option<DVec3>)>,
        &mut [[(f64, usize); 2]],
        &mut Option<Vec<bool>>,
    ),
) -> bool {
    if snapped[k] || samples[k].smooth >= FLAT_COS {
        return false;
    }
    snapped[k] = true;
    let scale = crate::uv::atlas::scale(shape);
    let radius = SNAP * reach.0;
    let Some(j) = nearest_flat(samples, k, radius, rejected, seeds, scale, None) else {
        return false;
    };
    add_seed(
        (def, shape, samples),
        j,
        reach,
        seeds,
        best,
        covered_by_alg2,
    );
    // And on the face across the curve: each face's edge then has a seed of its own face
    // nearer than the other's.
    let n = samples[j].n;
    let across = nearest_flat(samples, k, radius, rejected, seeds, scale, Some(n));
    if let Some(j) = across.filter(|_| seeds.len() < max_seeds) {
        add_seed(
            (def, shape, samples),
            j,
            reach,
            seeds,
            best,
            covered_by_alg2,
        );
    }
    true
}

/// The flat sample (smooth ≥ [`FLAT_COS`]) nearest to sample `k` within `radius`, not
/// retired and not on an existing seed; with `other`, on a face whose normal is not
/// `other`'s.
#[allow(clippy::too_many_arguments)]
fn nearest_flat(
    samples: &[SurfaceSample],
    k: usize,
    radius: f64,
    rejected: &[bool],
    seeds: &[(DVec3, Option<DVec3>)],
    scale: f64,
    other: Option<DVec3>,
) -> Option<usize> {
    let p = samples[k].p;
    (0..samples.len())
        .filter(|&j| j != k && !rejected[j] && samples[j].smooth >= FLAT_COS)
        .filter(|&j| other.is_none_or(|n| samples[j].n.dot(n) < FLAT_COS))
        .map(|j| ((samples[j].p - p).length(), j))
        .filter(|&(d, _)| d <= radius)
        .filter(|&(_, j)| {
            seeds
                .iter()
                .all(|(q, _)| (samples[j].p - *q).length() >= COINCIDENT * scale)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .map(|(_, j)| j)
}

/// Among `candidates`, the next seed's sample: the eligible one farthest from every
/// seed (Euclidean), with the distance counting less where the surface curves (see
/// [`FLATNESS`]: seeds go to flat faces before fillets); on an island with no eligible
/// sample, the smoothest. Ties go to the lower index. Returns (distance, sample).
pub(super) fn farthest(
    samples: &[SurfaceSample],
    seeds: &[(DVec3, Option<DVec3>)],
    eligible: &[bool],
    candidates: impl Iterator<Item = usize>,
) -> Option<(f64, usize)> {
    candidates
        .map(|k| {
            let d = seeds
                .iter()
                .map(|(p, _)| (samples[k].p - *p).length())
                .fold(f64::INFINITY, f64::min);
            let key = if eligible[k] {
                d * samples[k].smooth.max(0.0).powi(FLATNESS)
            } else {
                samples[k].smooth
            };
            (eligible[k], key, k, d)
        })
        .max_by(|a, b| {
            (a.0.cmp(&b.0))
                .then(a.1.total_cmp(&b.1))
                .then(b.2.cmp(&a.2))
        })
        .map(|(_, _, k, d)| (d, k))
}
