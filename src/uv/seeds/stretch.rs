//! Stretch: the local stretch of an atlas's uv at a surface sample (`--view
//! distortion`'s measure), and the tightening of placement's reach where it is high.

use super::{tangent, SurfaceSample};
use crate::uv::atlas::Atlas;
use crate::uv::logmap::Status;
use glam::DVec3;
use rayon::prelude::*;

/// While the 95th percentile of `atlas`'s local stretch ([`local_stretch`]) over the
/// samples exceeds `target`: at every sample that stretches more than `target`, the
/// walk distance within which a seed covers it shrinks toward what the target allows
/// (on a surface of curvature K a log map stretches by about 1 + K r²/6 at distance r,
/// so the reach scales by √((target − 1)/(stretch − 1)), kept within 0.6 and 0.85 a
/// round). Returns whether any sample's reach shrank.
pub(super) fn tighten(
    atlas: &Atlas,
    samples: &[SurfaceSample],
    best: &[[(f64, usize); 2]],
    target: f64,
    limit: &mut [f64],
) -> bool {
    let stretch: Vec<Option<f64>> = samples
        .par_iter()
        .map(|s| local_stretch(atlas, s))
        .collect();
    let mut measured: Vec<f64> = stretch.iter().flatten().copied().collect();
    if measured.is_empty() {
        return false;
    }
    measured.sort_by(f64::total_cmp);
    if measured[((measured.len() as f64 * 0.95) as usize).min(measured.len() - 1)] <= target {
        return false;
    }
    let mut any = false;
    for (k, s) in stretch.iter().enumerate() {
        let Some(s) = *s else { continue };
        let d = best[k][0].0;
        if s <= target || !d.is_finite() || d <= 0.0 {
            continue;
        }
        let shrink = ((target - 1.0) / (s - 1.0)).sqrt().clamp(0.6, 0.85);
        let reach = (d * shrink).min(limit[k]);
        if reach < limit[k] {
            limit[k] = reach;
            any = true;
        }
    }
    any
}

/// The local stretch of an atlas's uv over surface samples, as `--view distortion`
/// measures it: the uv Jacobian from two tangent offsets of 1e-3 of the shape's size,
/// its singular values s1 ≥ s2, and the stretch max(s1, 1/s2) (1 for an isometry).
/// Samples whose three Alg. 2 queries do not all succeed with the same seed (edges of
/// charts, frontiers), or whose offsets leave the surface (within a step of a crease),
/// are left out. Returns (mean, 95th percentile, samples measured).
pub fn stretch(atlas: &Atlas, samples: &[SurfaceSample]) -> (f64, f64, usize) {
    let mut values: Vec<f64> = samples
        .par_iter()
        .filter_map(|s| local_stretch(atlas, s))
        .collect();
    if values.is_empty() {
        return (f64::NAN, f64::NAN, 0);
    }
    values.sort_by(f64::total_cmp);
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let p95 = values[((values.len() as f64 * 0.95) as usize).min(values.len() - 1)];
    (mean, p95, values.len())
}

/// The local stretch at one sample (see [`stretch`]); `None` where it is not measured.
pub fn local_stretch(atlas: &Atlas, s: &SurfaceSample) -> Option<f64> {
    let h = 1e-3 * crate::uv::atlas::scale(&atlas.shape);
    let (t1, t2) = (tangent(s.n), s.n.cross(tangent(s.n)));
    // Both offsets stay on the surface (within a twentieth of the step): within a step
    // of a crease one lies off it, Alg. 2 sees its projection, and the Jacobian would
    // measure the crease rather than the map.
    let off = |x: DVec3| crate::ir::eval::distance(atlas.field(), x).abs() > 0.05 * h;
    if off(s.p + t1 * h) || off(s.p + t2 * h) {
        return None;
    }
    let a = atlas.sample(s.p);
    let b = atlas.sample(s.p + t1 * h);
    let c = atlas.sample(s.p + t2 * h);
    let ok = [&a, &b, &c]
        .iter()
        .all(|x| x.status == Status::Ok && x.seed == a.seed);
    if !ok {
        return None;
    }
    Some(stretch_of((b.uv - a.uv) / h, (c.uv - a.uv) / h))
}

/// max(s1, 1/s2) of the 2 × 2 Jacobian with columns `ju` and `jv` (singular values
/// s1 ≥ s2).
pub(super) fn stretch_of(ju: glam::DVec2, jv: glam::DVec2) -> f64 {
    let ss = ju.length_squared() + jv.length_squared();
    let det = (ju.x * jv.y - ju.y * jv.x).abs();
    let root = (ss * ss - 4.0 * det * det).max(0.0).sqrt();
    let s1 = (0.5 * (ss + root)).sqrt();
    let s2 = (0.5 * (ss - root)).max(1e-24).sqrt();
    s1.max(1.0 / s2)
}
