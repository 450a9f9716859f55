//! Automatic seed placement and merge graphs (the paper's §7 future work): seeds and
//! merges for an atlas, chosen so that Alg. 2 succeeds at a target share of the surface.
//!
//! The input is a dense, area-weighted sample of the surface (the caller meshes it:
//! `sdfc seeds` uses the bake's dual contouring), with each sample's neighbours.
//!
//! **Placement: farthest-point sampling by coverage.** A sample is *covered* when some
//! seed's walk (Alg. 1, with the atlas's own N, tolerances and D) reaches it with status
//! `ok` within the spacing (D/2 by default, so that neighbouring seeds can reach each
//! other to merge). Each round adds one seed at the uncovered sample farthest
//! (Euclidean) from every seed so far, among the samples where the surface is smooth
//! (a seed on a crease has no well-defined frame and its walks fail on both sides; on an
//! island with no smooth sample, the smoothest), then walks from the new seed to every
//! sample within D. Farthest-point sampling spreads the
//! seeds evenly, and because a walk stops at a sharp feature (the ε2 test), the
//! samples behind one stay uncovered until a seed lands among them: every island the
//! sharp features cut out gets its own seed, largest gaps first. A variational
//! (Lloyd-like) relaxation would need the walk distances from every sample to every
//! candidate, which costs far more walks for a modest saving in seeds.
//!
//! **Merges: a spanning forest of the seeds' neighbourhood graph, then the cycles
//! that close.** Two seeds are neighbours when some sample has both among its two
//! geodesic-nearest covering seeds (their regions touch); the pair is a candidate when
//! each seed's walk reaches the other. Candidates join in order of length (Kruskal):
//! a forest has no cycle and hence no obstruction (holonomy or offset residual); each
//! merge is kept only if the atlas still prepares without a diagnostic. Then the
//! candidates the forest skipped, each of which would close a cycle, are tried
//! shortest first, and each is kept only where the atlas stays free of diagnostics:
//! its cycle's holonomy and offset residual under the obstruction limits. On a flat
//! or developable region (the ring around a hole, Fig. 12) the cycles close, and the
//! chart has no seam where the forest left one; around a sphere's cap they do not. Each merge group has one fixed tangent
//! (its first seed's, the world x axis projected), and the optimal-frame solve (Eq. 45)
//! turns the others.
//!
//! **Coverage** at the end is Alg. 2 itself (`Atlas::sample`) at every sample,
//! weighted by area: what the renderer will do.
//!
//! **Keeping the seeds there** (`PlaceOptions::keep`): the atlas's own seeds (projected)
//! and merges come first, as they are; placement only adds seeds where the surface is
//! still uncovered, and the forest only adds merges that touch a new seed, joining the
//! existing groups (a closing merge also touches a new seed).
//!
//! Everything is deterministic: samples are visited in order and ties go to the lower
//! index.

use super::atlas::Atlas;
use super::logmap::Status;
use crate::ir::Shape;
use crate::sema::{AtlasDef, MergeDef, SeedDef};
use glam::DVec3;
use rayon::prelude::*;

/// A surface sample: position, unit normal, area weight, and how smooth the surface
/// is around it: the smallest cosine between its normal and the normals a short way
/// off in the tangent plane (1 on a flat face, low near a crease).
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceSample {
    pub p: DVec3,
    pub n: DVec3,
    pub area: f64,
    pub smooth: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaceOptions {
    /// The share of the surface (by area) that must end with status `ok`.
    pub target: f64,
    pub max_seeds: usize,
    /// A sample counts as covered while placing when a seed's walk reaches it within
    /// this distance (default D/2): neighbouring seeds are then within reach of each
    /// other, so they can merge.
    pub spacing: Option<f64>,
    /// Keep the atlas's own seeds and merges and add to them (see the module docs).
    pub keep: bool,
}

impl Default for PlaceOptions {
    fn default() -> PlaceOptions {
        PlaceOptions {
            target: 0.995,
            max_seeds: 256,
            spacing: None,
            keep: false,
        }
    }
}

/// The seeds and merges found, and how well they cover. With `keep`, the atlas's own
/// seeds and merges come first ([`Placement::kept`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// How many of `seeds` and of `merges` are the atlas's own.
    pub kept: (usize, usize),
    /// Seed positions (on the surface) and, for the first seed of each merge group and
    /// every unmerged seed, a tangent.
    pub seeds: Vec<(DVec3, Option<DVec3>)>,
    /// Merged pairs (seed indices).
    pub merges: Vec<(usize, usize)>,
    /// Area share with status `ok` under Alg. 2 at the end.
    pub coverage: f64,
    /// The samples still failing, with their status.
    pub failing: Vec<(DVec3, Status)>,
    /// Samples eligible as seeds (their normal agrees with their neighbours').
    pub eligible: usize,
}

/// The cosine of the largest angle between a seed candidate's normal and its
/// neighbours' (20°): sharper samples lie on creases.
const SMOOTH_COS: f64 = 0.94;

/// An atlas definition like `def` with these seeds and merges (for preparing).
pub fn with_seeds(
    def: &AtlasDef,
    seeds: &[(DVec3, Option<DVec3>)],
    merges: &[(usize, usize)],
) -> AtlasDef {
    let mut out = def.clone();
    out.seeds = seeds
        .iter()
        .enumerate()
        .map(|(k, (p, t))| SeedDef {
            name: format!("s{k}"),
            def: def.def,
            span: def.span,
            position: p.to_array(),
            position_span: def.span,
            tangent: t.map(|t| t.to_array()),
            tangent_span: t.map(|_| def.span),
        })
        .collect();
    out.merges = merges
        .iter()
        .map(|&(a, b)| MergeDef {
            a,
            b,
            span: def.span,
        })
        .collect();
    out
}

/// The world x axis in the tangent plane (z where x is nearly normal).
fn tangent(n: DVec3) -> DVec3 {
    super::atlas::frame(n, None).0
}

/// Places seeds and merges on `shape` for the atlas `def` (its parameters; its own
/// seeds and merges are ignored unless `options.keep`): see the module docs.
pub fn place(
    def: &AtlasDef,
    shape: &Shape,
    samples: &[SurfaceSample],
    options: PlaceOptions,
) -> Placement {
    let total: f64 = samples.iter().map(|s| s.area).sum::<f64>().max(1e-300);
    let eligible: Vec<bool> = samples.iter().map(|s| s.smooth >= SMOOTH_COS).collect();
    // With a `mirror` plane, the mirrored side takes the uv of its reflection: a seed
    // there is never used (W0008), so none is placed there.
    let mirror = def
        .params
        .mirror
        .map(|n| DVec3::from_array(n).normalize_or_zero());
    let mirrored = |k: usize| mirror.is_some_and(|n| samples[k].p.dot(n) < 0.0);
    let reach = def.params.max_distance;
    let spacing = options.spacing.unwrap_or(0.5 * reach).min(reach);
    let mut seeds: Vec<(DVec3, Option<DVec3>)> = Vec::new();
    // Per sample: the two nearest seeds whose walks reach it, (distance, seed).
    let mut best: Vec<[(f64, usize); 2]> = vec![[(f64::INFINITY, usize::MAX); 2]; samples.len()];
    // The atlas's own seeds (projected, with their tangents) and merges, kept.
    let mut kept_merges: Vec<(usize, usize)> = Vec::new();
    if options.keep && !def.seeds.is_empty() {
        if let Ok(atlas) = Atlas::prepare(def, shape) {
            seeds = def
                .seeds
                .iter()
                .zip(&atlas.seeds)
                .map(|(sd, ps)| (ps.seed.p, sd.tangent.map(DVec3::from_array)))
                .collect();
            kept_merges = def.merges.iter().map(|m| (m.a, m.b)).collect();
            for i in 0..seeds.len() {
                cover(&atlas, i, samples, reach, &mut best, &mut None);
            }
        }
    }
    let kept = (seeds.len(), kept_merges.len());
    // Seeds to place until coverage is reached, with the final Alg. 2 check between
    // rounds (it can differ from the walks' union where a nearer seed's walk fails).
    let mut covered_by_alg2: Option<Vec<bool>> = None;
    // Samples where a seed could not be prepared: never picked again, so every round
    // either adds a seed or retires a sample (placement always ends).
    // A sample that already has a seed is never given another one: where its own seed
    // does not make Alg. 2 succeed (a mirrored side whose reflection is off the
    // surface), another seed at the same point would not either.
    let mut rejected: Vec<bool> = (0..samples.len()).map(mirrored).collect();
    // The seeds at the end of the last round: a round that adds none ends placement.
    let mut last_round: Option<usize> = None;
    loop {
        fn covered(
            k: usize,
            best: &[[(f64, usize); 2]],
            alg2: &Option<Vec<bool>>,
            spacing: f64,
        ) -> bool {
            best[k][0].0 <= spacing && alg2.as_ref().is_none_or(|c| c[k])
        }
        let share = |best: &[[(f64, usize); 2]], alg2: &Option<Vec<bool>>| {
            (0..samples.len())
                .filter(|&k| covered(k, best, alg2, spacing))
                .map(|k| samples[k].area)
                .sum::<f64>()
                / total
        };
        while seeds.len() < options.max_seeds && share(&best, &covered_by_alg2) < options.target {
            // The uncovered eligible sample farthest from every seed.
            let next = (0..samples.len())
                .filter(|&k| !rejected[k] && !covered(k, &best, &covered_by_alg2, spacing))
                .map(|k| {
                    let d = seeds
                        .iter()
                        .map(|(p, _)| (samples[k].p - *p).length())
                        .fold(f64::INFINITY, f64::min);
                    // Smooth samples first; on an island with none, the smoothest.
                    (
                        eligible[k],
                        if eligible[k] { d } else { samples[k].smooth },
                        k,
                    )
                })
                .max_by(|a, b| {
                    (a.0.cmp(&b.0))
                        .then(a.1.total_cmp(&b.1))
                        .then(b.2.cmp(&a.2))
                })
                .map(|(_, d, k)| (d, k));
            let Some((_, k)) = next else { break };
            let s = &samples[k];
            rejected[k] = true;
            seeds.push((s.p, Some(tangent(s.n))));
            let i = seeds.len() - 1;
            let Ok(atlas) = Atlas::prepare(&with_seeds(def, &seeds, &[]), shape) else {
                // The seed cannot be prepared there (its projection does not converge,
                // as at a pyramid's apex): drop it and never pick that sample again.
                seeds.pop();
                rejected[k] = true;
                continue;
            };
            cover(&atlas, i, samples, reach, &mut best, &mut covered_by_alg2);
            // The new seed's own sample is covered by construction (a walk of length 0).
            if best[k][0].0 > 0.0 {
                best[k][1] = best[k][0];
                best[k][0] = (0.0, i);
            }
            if let Some(c) = covered_by_alg2.as_mut() {
                c[k] = true;
            }
        }
        // Merges, then Alg. 2 over every sample.
        let (placed, merges) = merge_forest(def, shape, &seeds, &best, kept, &kept_merges);
        let atlas = Atlas::prepare(&with_seeds(def, &placed, &merges), shape).ok();
        let statuses: Vec<Status> = match &atlas {
            Some(a) => samples.par_iter().map(|s| a.sample(s.p).status).collect(),
            None => vec![Status::TooFar; samples.len()],
        };
        let ok: Vec<bool> = statuses.iter().map(|s| *s == Status::Ok).collect();
        let coverage = (0..samples.len())
            .filter(|&k| ok[k])
            .map(|k| samples[k].area)
            .sum::<f64>()
            / total;
        let progressed = last_round != Some(seeds.len());
        last_round = Some(seeds.len());
        let more = coverage < options.target
            && progressed
            && seeds.len() < options.max_seeds
            && covered_by_alg2.as_ref() != Some(&ok)
            && (0..samples.len()).any(|k| eligible[k] && !ok[k] && !rejected[k]);
        if !more {
            return Placement {
                kept,
                seeds: placed,
                merges,
                coverage,
                failing: (0..samples.len())
                    .filter(|&k| !ok[k])
                    .map(|k| (samples[k].p, statuses[k]))
                    .collect(),
                eligible: eligible.iter().filter(|&&e| e).count(),
            };
        }
        covered_by_alg2 = Some(ok);
    }
}

/// Walks from seed `i` of `atlas` to every sample within `reach`, and records it among
/// the two nearest covering seeds of the samples it reaches (and, optimistically until
/// the next Alg. 2 check, as covering them).
fn cover(
    atlas: &Atlas,
    i: usize,
    samples: &[SurfaceSample],
    reach: f64,
    best: &mut [[(f64, usize); 2]],
    covered_by_alg2: &mut Option<Vec<bool>>,
) {
    let p = atlas.seeds[i].seed.p;
    let walks: Vec<(usize, f64)> = (0..samples.len())
        .into_par_iter()
        .filter(|&j| (samples[j].p - p).length() < reach)
        .filter_map(|j| {
            let m = atlas.walk(samples[j].p, i, reach);
            (m.status == Status::Ok).then_some((j, m.distance))
        })
        .collect();
    for (j, d) in walks {
        if let Some(c) = covered_by_alg2.as_mut() {
            c[j] = true;
        }
        let b = &mut best[j];
        if d < b[0].0 {
            b[1] = b[0];
            b[0] = (d, i);
        } else if d < b[1].0 {
            b[1] = (d, i);
        }
    }
}

/// The merge forest over the placed seeds (see the module docs), with tangents kept on
/// the first seed of each group only. The first `kept.0` seeds and `kept_merges` are the
/// atlas's own: their merges stay, their tangents stay as written, and only pairs with a
/// new seed are candidates.
fn merge_forest(
    def: &AtlasDef,
    shape: &Shape,
    seeds: &[(DVec3, Option<DVec3>)],
    best: &[[(f64, usize); 2]],
    kept: (usize, usize),
    kept_merges: &[(usize, usize)],
) -> (Vec<(DVec3, Option<DVec3>)>, Vec<(usize, usize)>) {
    let n = seeds.len();
    let fixed = kept.0;
    let mut pairs: Vec<(usize, usize)> = best
        .iter()
        .filter(|b| b[0].1 != usize::MAX && b[1].1 != usize::MAX)
        .map(|b| (b[0].1.min(b[1].1), b[0].1.max(b[1].1)))
        .filter(|&(_, b)| b >= fixed)
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    let Ok(atlas) = Atlas::prepare(&with_seeds(def, seeds, &[]), shape) else {
        return (seeds.to_vec(), kept_merges.to_vec());
    };
    let reach = def.params.max_distance;
    // Both walks must succeed; the length is their mean.
    let mut candidates: Vec<(f64, usize, usize)> = pairs
        .par_iter()
        .filter_map(|&(a, b)| {
            let (pa, pb) = (atlas.seeds[a].seed.p, atlas.seeds[b].seed.p);
            let ab = atlas.walk(pb, a, reach);
            let ba = atlas.walk(pa, b, reach);
            (ab.status == Status::Ok && ba.status == Status::Ok).then_some((
                0.5 * (ab.distance + ba.distance),
                a,
                b,
            ))
        })
        .collect();
    candidates.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));

    // Kruskal, keeping a merge only if the atlas stays free of diagnostics.
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut merges: Vec<(usize, usize)> = kept_merges.to_vec();
    for &(a, b) in kept_merges {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    // One fixed tangent per group: on its root seed (the atlas's own seeds keep theirs).
    let with_tangents = |parent: &mut Vec<usize>| -> Vec<(DVec3, Option<DVec3>)> {
        let mut placed = seeds.to_vec();
        for (k, s) in placed.iter_mut().enumerate().skip(fixed) {
            if root(parent, k) != k {
                s.1 = None;
            }
        }
        placed
    };
    let mut closing = Vec::new();
    for (_, a, b) in candidates {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra == rb {
            // Would close a cycle: tried once the forest is complete.
            closing.push((a, b));
            continue;
        }
        let mut trial_parent = parent.clone();
        trial_parent[ra.max(rb)] = ra.min(rb);
        merges.push((a, b));
        let placed = with_tangents(&mut trial_parent);
        let trial = with_seeds(def, &placed, &merges);
        let clean = Atlas::prepare(&trial, shape)
            .map(|atlas| super::diagnose::diagnostics(&trial, &atlas).is_empty())
            .unwrap_or(false);
        if clean {
            parent = trial_parent;
        } else {
            merges.pop();
        }
    }
    // Cycles, shortest first: each closes only where the atlas stays free of
    // diagnostics, that is where its holonomy and offset residual stay under the
    // obstruction limits (W0005) and the walks still reach. A closed cycle joins the
    // charts along its last edge too (the ring around a hole becomes one chart with no
    // seam, Fig. 12), where the forest left a frontier.
    let placed = with_tangents(&mut parent);
    for (a, b) in closing {
        if root(&mut parent, a) != root(&mut parent, b) {
            continue;
        }
        merges.push((a, b));
        let trial = with_seeds(def, &placed, &merges);
        let clean = Atlas::prepare(&trial, shape)
            .map(|atlas| super::diagnose::diagnostics(&trial, &atlas).is_empty())
            .unwrap_or(false);
        if !clean {
            merges.pop();
        }
    }
    (placed, merges)
}

/// The local stretch of an atlas's uv over surface samples, as `--view distortion`
/// measures it: the uv Jacobian from two tangent offsets of 1e-3 of the shape's size,
/// its singular values s1 ≥ s2, and the stretch max(s1, 1/s2) (1 for an isometry).
/// Samples whose three Alg. 2 queries do not all succeed with the same seed (edges of
/// charts, frontiers) are left out. Returns (mean, 95th percentile, samples measured).
pub fn stretch(atlas: &Atlas, samples: &[SurfaceSample]) -> (f64, f64, usize) {
    let h = 1e-3 * super::atlas::scale(&atlas.shape);
    let mut values: Vec<f64> = samples
        .par_iter()
        .filter_map(|s| {
            let (t1, t2) = (tangent(s.n), s.n.cross(tangent(s.n)));
            let a = atlas.sample(s.p);
            let b = atlas.sample(s.p + t1 * h);
            let c = atlas.sample(s.p + t2 * h);
            let ok = [&a, &b, &c]
                .iter()
                .all(|x| x.status == Status::Ok && x.seed == a.seed);
            if !ok {
                return None;
            }
            let (ju, jv) = ((b.uv - a.uv) / h, (c.uv - a.uv) / h);
            let ss = ju.length_squared() + jv.length_squared();
            let det = (ju.x * jv.y - ju.y * jv.x).abs();
            let root = (ss * ss - 4.0 * det * det).max(0.0).sqrt();
            let s1 = (0.5 * (ss + root)).sqrt();
            let s2 = (0.5 * (ss - root)).max(1e-24).sqrt();
            Some(s1.max(1.0 / s2))
        })
        .collect();
    if values.is_empty() {
        return (f64::NAN, f64::NAN, 0);
    }
    values.sort_by(f64::total_cmp);
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let p95 = values[((values.len() as f64 * 0.95) as usize).min(values.len() - 1)];
    (mean, p95, values.len())
}
