//! Automatic seed placement and merge graphs (the paper's §7 future work): seeds and
//! merges for an atlas, chosen so that Alg. 2 succeeds at a target share of the surface.
//!
//! The input is a dense, area-weighted sample of the surface (`sdfc seeds` draws it
//! uniformly by area from a thin shell around the surface,
//! [`crate::reference::surface`], so slits, grooves and the insides of holes are in it).
//!
//! **Placement: farthest-point sampling by coverage.** A sample is *covered* when some
//! seed's walk (Alg. 1, with the atlas's own N, tolerances and D) reaches it with status
//! `ok` within the spacing (D/2 by default, so that neighbouring seeds can reach each
//! other to merge). Each round adds one seed at the uncovered sample farthest
//! (Euclidean) from every seed so far, among the samples where the surface is smooth
//! (a seed on a crease has no well-defined frame and its walks fail on both sides; on an
//! island with no smooth sample, the smoothest), then walks from the new seed to every
//! sample within the spacing. Farthest-point sampling spreads the
//! seeds evenly, and because a walk stops at a sharp feature (the ε2 test), the
//! samples behind one stay uncovered until a seed lands among them: every island the
//! sharp features cut out gets its own seed, largest gaps first. A sample picked on a
//! curve (a fillet) first tries seeds on the flat faces beside it instead (`SNAP`): the
//! nearest flat sample, and the nearest on a face across the curve (the picked sample
//! is picked again, as it is, where their walks do not cover it; the flat seeds stay). Each face's edge is then nearer a seed of its own
//! face than one across the fillet, and walks there stay flat; a seed on the fillet
//! would be their nearest, and Alg. 1's walk over a fillet crossed at a slant stretches
//! its map. A variational
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
//! **Stretch** (`PlaceOptions::max_stretch`): a log map stretches with the distance
//! from its seed where the surface curves (on a sphere of radius R by r / (R sin(r/R))
//! across, at distance r), so seeds spaced for coverage alone stretch the texture
//! around curved parts (a seed per flat face of the robot, whose walks reach around the
//! head and arms). With a target S, four things change. A seed covers a sample only
//! where its own map stretches at most 1 + 2(S − 1) there (two more walks a tangent
//! step away, `COVER_SLACK`). Farthest-point sampling prefers flat samples
//! (`FLATNESS`), so seeds go to faces before fillets. A merge is kept only where its
//! blend band does not stretch beyond S. And once the target share is covered, the
//! local stretch of the merged atlas is measured at every sample ([`local_stretch`]);
//! while its 95th percentile exceeds S, the reach of each sample that stretches more
//! (the walk distance within which a seed covers it) shrinks toward what S allows, and
//! farthest-point placement goes on among those samples, for up to
//! `STRETCH_ROUNDS` rounds.
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

mod pick;
mod stretch;

use pick::{farthest, snap};
pub use stretch::{local_stretch, stretch};
use stretch::{stretch_of, tighten};

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
    /// The largest local stretch max(s1, 1/s2) wanted at a sample (see [`stretch`]):
    /// where the placed atlas stretches more, seeds are added nearer (module docs).
    /// `None` places for coverage only.
    pub max_stretch: Option<f64>,
}

impl Default for PlaceOptions {
    fn default() -> PlaceOptions {
        PlaceOptions {
            target: 0.995,
            max_seeds: 256,
            spacing: None,
            keep: false,
            max_stretch: Some(DEFAULT_MAX_STRETCH),
        }
    }
}

impl PlaceOptions {
    /// Whether the options mean something: a target share in (0, 1], between 1 and
    /// [`crate::sema::MAX_SEEDS`] seeds, a positive finite spacing, and a stretch target
    /// above 1 (an isometry stretches by 1, so no placement meets a lower one; `inf` is
    /// none). [`crate::ide::seeds::place_edit`] refuses options that fail this; [`place`]
    /// takes them as given (a target it cannot meet places `max_seeds` seeds).
    pub fn check(&self) -> Result<(), String> {
        if !(self.target > 0.0 && self.target <= 1.0) {
            return Err(format!(
                "the target coverage {} is not in (0, 1]",
                self.target
            ));
        }
        if !(1..=crate::sema::MAX_SEEDS).contains(&self.max_seeds) {
            return Err(format!(
                "{} seeds at most is not between 1 and {}",
                self.max_seeds,
                crate::sema::MAX_SEEDS
            ));
        }
        if let Some(s) = self.spacing.filter(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(format!("the spacing {s} is not a positive distance"));
        }
        if let Some(s) = self.max_stretch.filter(|s| !(*s > 1.0)) {
            return Err(format!(
                "the stretch target {s} is not above 1 (1 is an isometry; infinity turns it off)"
            ));
        }
        Ok(())
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

/// The default stretch target of [`PlaceOptions::max_stretch`].
pub const DEFAULT_MAX_STRETCH: f64 = 1.5;

/// While placing, a seed covers a sample where its own log map stretches no more
/// than 1 + COVER_SLACK · (target − 1): the target itself is for the 95th percentile of
/// the merged atlas ([`tighten`]). Held at the target everywhere, a round box's
/// fillets (a few percent of its area) each needed seeds of their own, and those
/// became the nearest seeds of the flat faces' edges and stretched them.
const COVER_SLACK: f64 = 2.0;

/// How much farthest-point sampling prefers flat samples for seeds: a sample's
/// distance to the seeds counts times smooth^FLATNESS (a fillet whose normal turns 15°
/// within a third of a cell counts half as far as a flat face; a sphere spanning 40
/// cells, 0.997 as far). A seed on a tight curve stretches every walk that leaves it,
/// and Alg. 2 gives each point its nearest seed, good map or not.
const FLATNESS: i32 = 20;

/// A curved sample picked for a seed first gets seeds at the nearest flat sample (smooth
/// ≥ `FLAT_COS`) within SNAP · spacing and at the nearest on a face across the curve,
/// instead of one of its own: a fillet is then covered by seeds on the faces beside it,
/// and a face's edge is served by its own face's seed over a flat walk, where a seed on
/// the fillet would be its nearest and stretch it (Alg. 1's walk over a fillet crossed
/// at a slant). The flat seeds stay; where they do not cover the sample, it is picked
/// again and then gets its own seed.
const SNAP: f64 = 0.1;

/// The smoothness of a flat sample for [`SNAP`] (its neighbours' normals within 0.8°).
const FLAT_COS: f64 = 0.9999;

/// Seeds closer than this, relative to the shape's size, count as one point (the
/// atlas's W0004 limit is 1e-3).
const COINCIDENT: f64 = 2e-3;

/// The most rounds of placement that tighten the reach for stretch.
const STRETCH_ROUNDS: usize = 3;

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

/// A position or tangent rounded to the six decimals the scene text gets
/// ([`crate::ide::seeds`]): placement prepares the atlas the file will have (on a
/// pyramid's base a seed 1e-7 off projected, and its written position did not).
fn as_written(v: DVec3) -> DVec3 {
    (v * 1e6).round() / 1e6
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
    let mirror = def.params.mirror.map(DVec3::from_array);
    let mirrored = |k: usize| mirror.is_some_and(|n| samples[k].p.dot(n) < 0.0);
    let reach = def.params.max_distance;
    let scale = super::atlas::scale(shape);
    let spacing = options.spacing.unwrap_or(0.5 * reach).min(reach);
    let options = finite_target(options);
    // Per sample: the two nearest seeds whose walks reach it, (distance, seed).
    let mut best: Vec<[(f64, usize); 2]> = vec![[(f64::INFINITY, usize::MAX); 2]; samples.len()];
    // The atlas's own seeds (projected, with their tangents) and merges, kept.
    let (mut seeds, kept_merges) = if options.keep {
        own_seeds(
            def,
            shape,
            samples,
            (spacing, options.max_stretch),
            &mut best,
        )
    } else {
        (Vec::new(), Vec::new())
    };
    let kept = (seeds.len(), kept_merges.len());
    // Seeds to place until coverage is reached, with the final Alg. 2 check between
    // rounds (it can differ from the walks' union where a nearer seed's walk fails).
    let mut covered_by_alg2: Option<Vec<bool>> = None;
    // Samples once picked (with or without a seed prepared there) are never picked
    // again, but for a curved sample whose snapped seeds do not cover it, once
    // (`snapped`): so every round adds a seed, retires a sample or spends a snap, and
    // placement ends; where a sample's own seed does not make Alg. 2 succeed, another
    // there would not either.
    let mut rejected: Vec<bool> = (0..samples.len()).map(mirrored).collect();
    // The seeds at the end of the last round: a round that adds none ends placement.
    let mut last_round: Option<usize> = None;
    // Per sample, the walk distance within which a seed covers it: the spacing, less
    // where the placed atlas stretched too much there.
    let mut limit = vec![spacing; samples.len()];
    // Curved samples whose flat neighbour was tried for them (SNAP).
    let mut snapped = vec![false; samples.len()];
    let mut stretch_rounds = 0;
    loop {
        let share = |best: &[[(f64, usize); 2]], alg2: &Option<Vec<bool>>| {
            (0..samples.len())
                .filter(|&k| covered(k, best, alg2, &limit))
                .map(|k| samples[k].area)
                .sum::<f64>()
                / total
        };
        // A sample whose reach was tightened for stretch and is not yet covered within it.
        let wanted =
            |k: usize, best: &[[(f64, usize); 2]], alg2: &Option<Vec<bool>>, rejected: &[bool]| {
                limit[k] < spacing && !rejected[k] && !covered(k, best, alg2, &limit)
            };
        loop {
            let short = share(&best, &covered_by_alg2) < options.target;
            let for_stretch =
                !short && (0..samples.len()).any(|k| wanted(k, &best, &covered_by_alg2, &rejected));
            if seeds.len() >= options.max_seeds || !(short || for_stretch) {
                break;
            }
            // The uncovered sample farthest from every seed (once the share is covered,
            // among the samples whose reach was tightened for stretch).
            let next = farthest(
                samples,
                &seeds,
                &eligible,
                (0..samples.len())
                    .filter(|&k| !rejected[k] && !covered(k, &best, &covered_by_alg2, &limit))
                    .filter(|&k| !for_stretch || wanted(k, &best, &covered_by_alg2, &rejected)),
            );
            let Some((d, k)) = next else { break };
            rejected[k] = true;
            // Samples that project onto an existing seed (a crease's wedge of the
            // shell, two draws at one point) would make coincident seeds (W0004).
            if d < COINCIDENT * scale {
                continue;
            }
            let state = (&mut seeds, &mut best[..], &mut covered_by_alg2);
            let limits = ((spacing, options.max_stretch), options.max_seeds);
            let picked = (&rejected[..], &mut snapped[..]);
            if snap((def, shape, samples), k, limits, picked, state) {
                // Picked again as it is where the flat seeds do not cover it.
                rejected[k] = covered(k, &best, &covered_by_alg2, &limit);
                continue;
            }
            // Where the seed cannot be prepared (its projection does not converge, as
            // at a pyramid's apex), none is added; that sample is never picked again.
            add_seed(
                (def, shape, samples),
                k,
                (spacing, options.max_stretch),
                &mut seeds,
                &mut best,
                &mut covered_by_alg2,
            );
        }
        // Merges, then Alg. 2 over every sample.
        let (placed, merges) = merge_forest(
            def,
            shape,
            (&seeds, &best, samples),
            kept,
            &kept_merges,
            options.max_stretch,
        );
        let atlas = Atlas::prepare(&with_seeds(def, &placed, &merges), shape).ok();
        let (statuses, coverage) = alg2(atlas.as_ref(), samples);
        let ok: Vec<bool> = statuses.iter().map(|s| *s == Status::Ok).collect();
        let progressed = last_round != Some(seeds.len());
        last_round = Some(seeds.len());
        let more = coverage < options.target
            && progressed
            && seeds.len() < options.max_seeds
            && covered_by_alg2.as_ref() != Some(&ok)
            && (0..samples.len()).any(|k| eligible[k] && !ok[k] && !rejected[k]);
        // Covered: where the atlas stretches more than wanted, tighten the reach.
        let tightened = !more
            && progressed
            && seeds.len() < options.max_seeds
            && stretch_rounds < STRETCH_ROUNDS
            && match (options.max_stretch, &atlas) {
                (Some(target), Some(a)) => tighten(a, samples, &best, target, &mut limit),
                _ => false,
            };
        if tightened {
            stretch_rounds += 1;
        }
        if !more && !tightened {
            return finish(
                kept,
                (placed, merges),
                coverage,
                (samples, &statuses),
                &eligible,
            );
        }
        covered_by_alg2 = Some(ok);
    }
}

/// The placement at the end: what was placed, the coverage, the samples where Alg. 2
/// fails with their status, and how many samples could take a seed.
#[allow(clippy::type_complexity)]
fn finish(
    kept: (usize, usize),
    (seeds, merges): (Vec<(DVec3, Option<DVec3>)>, Vec<(usize, usize)>),
    coverage: f64,
    (samples, statuses): (&[SurfaceSample], &[Status]),
    eligible: &[bool],
) -> Placement {
    Placement {
        kept,
        seeds,
        merges,
        coverage,
        failing: (0..samples.len())
            .filter(|&k| statuses[k] != Status::Ok)
            .map(|k| (samples[k].p, statuses[k]))
            .collect(),
        eligible: eligible.iter().filter(|&&e| e).count(),
    }
}

/// Whether sample `k` is covered: a seed's walk reaches it within its reach `limit`,
/// and Alg. 2 succeeds there at the last check (`alg2`, none before the first).
fn covered(k: usize, best: &[[(f64, usize); 2]], alg2: &Option<Vec<bool>>, limit: &[f64]) -> bool {
    best[k][0].0 <= limit[k] && alg2.as_ref().is_none_or(|c| c[k])
}

/// The area share of `samples` where the placed atlas's Alg. 2 succeeds, and the
/// samples where it fails with their status: the coverage of a placement measured on
/// samples it was not placed on (a placement covers its own samples by construction;
/// `sdfc seeds` reports this on a second, independent draw).
pub fn coverage_on(
    def: &AtlasDef,
    shape: &Shape,
    placement: &Placement,
    samples: &[SurfaceSample],
) -> (f64, Vec<(DVec3, Status)>) {
    let atlas = Atlas::prepare(&with_seeds(def, &placement.seeds, &placement.merges), shape).ok();
    let (statuses, coverage) = alg2(atlas.as_ref(), samples);
    let failing = (0..samples.len())
        .filter(|&k| statuses[k] != Status::Ok)
        .map(|k| (samples[k].p, statuses[k]))
        .collect();
    (coverage, failing)
}

/// Adds a seed at sample `k` (as written, with the world x axis as its tangent) and
/// records the samples it covers; leaves `seeds` as it was where the seed cannot be
/// prepared.
#[allow(clippy::type_complexity)]
fn add_seed(
    (def, shape, samples): (&AtlasDef, &Shape, &[SurfaceSample]),
    k: usize,
    reach: (f64, Option<f64>),
    seeds: &mut Vec<(DVec3, Option<DVec3>)>,
    best: &mut [[(f64, usize); 2]],
    covered_by_alg2: &mut Option<Vec<bool>>,
) {
    let s = &samples[k];
    seeds.push((as_written(s.p), Some(as_written(tangent(s.n)))));
    let i = seeds.len() - 1;
    let Ok(atlas) = Atlas::prepare(&with_seeds(def, seeds, &[]), shape) else {
        seeds.pop();
        return;
    };
    cover(&atlas, i, samples, reach, best, covered_by_alg2);
    // The new seed's own sample is covered by construction (a walk of length 0, or
    // nearly: the seed sits at the sample rounded as written).
    let b = &mut best[k];
    if b[0].1 == i {
        b[0].0 = 0.0;
    } else {
        *b = [(0.0, i), b[0]];
    }
    if let Some(c) = covered_by_alg2.as_mut() {
        c[k] = true;
    }
}

/// Alg. 2's status at every sample and the area share where it succeeds (none
/// without an atlas).
fn alg2(atlas: Option<&Atlas>, samples: &[SurfaceSample]) -> (Vec<Status>, f64) {
    let statuses: Vec<Status> = match atlas {
        Some(a) => samples.par_iter().map(|s| a.sample(s.p).status).collect(),
        None => vec![Status::TooFar; samples.len()],
    };
    let total: f64 = samples.iter().map(|s| s.area).sum::<f64>().max(1e-300);
    let ok: f64 = (0..samples.len())
        .filter(|&k| statuses[k] == Status::Ok)
        .map(|k| samples[k].area)
        .sum();
    (statuses, ok / total)
}

/// `options` with a stretch target beyond any stretch (`inf`) taken as none: it would
/// cost the stretch measurements and change nothing.
fn finite_target(options: PlaceOptions) -> PlaceOptions {
    PlaceOptions {
        max_stretch: options.max_stretch.filter(|s| s.is_finite()),
        ..options
    }
}

/// The atlas's own seeds (projected, with their tangents) and merges, for
/// [`PlaceOptions::keep`], with the samples they cover recorded in `best`.
#[allow(clippy::type_complexity)]
fn own_seeds(
    def: &AtlasDef,
    shape: &Shape,
    samples: &[SurfaceSample],
    reach: (f64, Option<f64>),
    best: &mut [[(f64, usize); 2]],
) -> (Vec<(DVec3, Option<DVec3>)>, Vec<(usize, usize)>) {
    let Some(atlas) = (!def.seeds.is_empty())
        .then(|| Atlas::prepare(def, shape).ok())
        .flatten()
    else {
        return (Vec::new(), Vec::new());
    };
    let seeds: Vec<(DVec3, Option<DVec3>)> = def
        .seeds
        .iter()
        .zip(&atlas.seeds)
        .map(|(sd, ps)| (ps.seed.p, sd.tangent.map(DVec3::from_array)))
        .collect();
    for i in 0..seeds.len() {
        cover(&atlas, i, samples, reach, best, &mut None);
    }
    (seeds, def.merges.iter().map(|m| (m.a, m.b)).collect())
}

/// Walks from seed `i` of `atlas` to every sample within `reach` (the spacing: a walk
/// longer than that covers nothing, and regions that touch meet within it) and, with a stretch
/// target, where the seed's own log map stretches no more than that at the sample
/// (two more walks a tangent step away), records it among
/// the two nearest covering seeds of the samples it reaches (and, optimistically until
/// the next Alg. 2 check, as covering them).
fn cover(
    atlas: &Atlas,
    i: usize,
    samples: &[SurfaceSample],
    (reach, max_stretch): (f64, Option<f64>),
    best: &mut [[(f64, usize); 2]],
    covered_by_alg2: &mut Option<Vec<bool>>,
) {
    let p = atlas.seeds[i].seed.p;
    let h = 1e-3 * super::atlas::scale(&atlas.shape);
    let walks: Vec<(usize, f64)> = (0..samples.len())
        .into_par_iter()
        .filter(|&j| (samples[j].p - p).length() < reach)
        .filter_map(|j| {
            let s = &samples[j];
            let m = atlas.walk(s.p, i, reach);
            if m.status != Status::Ok {
                return None;
            }
            if let Some(target) = max_stretch.map(|s| 1.0 + COVER_SLACK * (s - 1.0)) {
                let (t1, t2) = (tangent(s.n), s.n.cross(tangent(s.n)));
                // Within a step of a crease the map is not measured (as in
                // [`local_stretch`]).
                let off = |x: DVec3| crate::ir::eval::distance(atlas.field(), x).abs() > 0.05 * h;
                if off(s.p + t1 * h) || off(s.p + t2 * h) {
                    return Some((j, m.distance));
                }
                let b = atlas.walk(s.p + t1 * h, i, reach);
                let c = atlas.walk(s.p + t2 * h, i, reach);
                if b.status != Status::Ok || c.status != Status::Ok {
                    return None;
                }
                if stretch_of((b.uv - m.uv) / h, (c.uv - m.uv) / h) > target {
                    return None;
                }
            }
            Some((j, m.distance))
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
#[allow(clippy::type_complexity)]
fn merge_forest(
    def: &AtlasDef,
    shape: &Shape,
    (seeds, best, samples): (
        &[(DVec3, Option<DVec3>)],
        &[[(f64, usize); 2]],
        &[SurfaceSample],
    ),
    kept: (usize, usize),
    kept_merges: &[(usize, usize)],
    max_stretch: Option<f64>,
) -> (Vec<(DVec3, Option<DVec3>)>, Vec<(usize, usize)>) {
    // A merge is kept only where the atlas stays free of diagnostics and, with a
    // stretch target, where the blend it brings does not stretch more than that: the
    // samples whose two nearest covering seeds are the pair (its blend band) stretch
    // beyond the target at no more than a tenth of them. Across a fold the two walks'
    // uv disagree a little, and a blend band squeezes the difference into its width.
    let keeps = |trial: &AtlasDef, (a, b): (usize, usize)| {
        let Ok(atlas) = Atlas::prepare(trial, shape) else {
            return false;
        };
        if !super::diagnose::diagnostics(trial, &atlas).is_empty() {
            return false;
        }
        let Some(target) = max_stretch else {
            return true;
        };
        let band: Vec<usize> = (0..samples.len())
            .filter(|&k| {
                let (x, y) = (best[k][0].1, best[k][1].1);
                (x, y) == (a, b) || (x, y) == (b, a)
            })
            .collect();
        let over = band
            .par_iter()
            .filter(|&&k| local_stretch(&atlas, &samples[k]).is_some_and(|s| s > target))
            .count();
        over * 10 <= band.len()
    };
    let n = seeds.len();
    let fixed = kept.0;
    let mut pairs: Vec<(usize, usize)> = best
        .iter()
        .filter(|b| b[0].1 != usize::MAX && b[1].1 != usize::MAX)
        .map(|b| (b[0].1.min(b[1].1), b[0].1.max(b[1].1)))
        .filter(|&(a, b)| b >= fixed && a != b)
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
        if keeps(&trial, (a, b)) {
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
        if !keeps(&trial, (a, b)) {
            merges.pop();
        }
    }
    (placed, merges)
}
