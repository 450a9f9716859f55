//! Atlases on the CPU: seeds projected onto the surface, the merge graph solved for
//! frames and offsets (all at compile time), and Alg. 2 per point: the search for the
//! geodesic-nearest seed with the exact early-out of Eq. 35, then the blend with the
//! merged neighbours (Eqs. 39–44, with the corrected last line of the notes).

use super::grid::SeedGrid;
use super::logmap::{gradient, log_map_with, LogMap, Params, Seed, Status};
use super::merge::{self, MergeGraph};
use crate::ir::rest::RestQuery;
use crate::ir::{eval, Field, Heights, NoHeights, Shape};
use crate::sema::AtlasDef;
use glam::{DMat3, DVec2, DVec3};
use std::sync::Arc;

/// A seed after projection, with what the user should be told about it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedSeed {
    pub seed: Seed,
    /// How far projection moved the seed from where it was written.
    pub moved: f64,
    /// Whether the frame's e1 came from a default rather than a `tangent`.
    pub default_tangent: bool,
    /// The position as written.
    pub written: DVec3,
    /// f at the written position: how far (and on which side) a true distance field says
    /// the surface is.
    pub written_distance: f64,
    /// The uv offset u_i of Eq. 37 (zero for an unmerged seed).
    pub offset: DVec2,
}

impl PreparedSeed {
    /// Whether projection probably landed on another part of the shape than the one
    /// meant: it moved the seed much farther than |f| at its written position, or not
    /// along the landing point's normal (the written point is not in front of it).
    pub fn jumped(&self, scale: f64) -> bool {
        if self.moved <= 1e-2 * scale {
            return false;
        }
        let along = (self.written - self.seed.p).dot(self.seed.n) * self.written_distance.signum();
        self.moved > 3.0 * self.written_distance.abs() + 1e-2 * scale || along < 0.5 * self.moved
    }
}

/// An atlas ready to evaluate: its shape, projected seeds and parameters.
#[derive(Debug, Clone)]
pub struct Atlas {
    pub name: String,
    /// Seed names, in declaration order.
    pub seed_names: Vec<String>,
    pub shape: Shape,
    pub seeds: Vec<PreparedSeed>,
    pub params: Params,
    /// The solved merge graph.
    pub graph: MergeGraph,
    /// σ, the half-width of the blend band (Eq. 40).
    pub sigma: f64,
    /// Pairs of seeds that project to the same point (within 1e-3 · scale).
    pub coincident: Vec<(usize, usize)>,
    /// The unit normal of the symmetry plane (through the origin) of the `mirror`
    /// setting: points on its negative side are queried at their reflection (§5.1).
    pub mirror: Option<DVec3>,
    /// Where the atlas's shape occurs in the render target: materials query the uv at
    /// the rest pose ([`Atlas::sample_at`]); set by `diagnose::prepare_all`.
    pub rest: RestQuery,
    /// What the shape's heights read (the atlases declared before this one, the
    /// textures): the environment of its field ([`Atlas::field`]).
    pub heights: Arc<dyn Heights>,
}

/// Atlases are equal when their data are: the environment of the field is left out,
/// as it is derived from the atlases before this one and the textures.
impl PartialEq for Atlas {
    fn eq(&self, o: &Atlas) -> bool {
        self.name == o.name
            && self.seed_names == o.seed_names
            && self.shape == o.shape
            && self.seeds == o.seeds
            && self.params == o.params
            && self.graph == o.graph
            && self.sigma == o.sigma
            && self.coincident == o.coincident
            && self.mirror == o.mirror
            && self.rest == o.rest
    }
}

/// Choices for [`Atlas::sample_with`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Search {
    /// Walk every seed with the full D (no early-out): for testing the early-out.
    pub brute_force: bool,
}

/// Why an atlas cannot be prepared.
#[derive(Debug, Clone, PartialEq)]
pub enum PrepareError {
    /// Projection of a seed onto the surface did not converge.
    SeedOffSurface { seed: usize },
}

/// The walk's finite-difference steps in f32 (the generated WGSL): the gradient's and
/// the second difference's as fractions of the step length, and their floor as a
/// fraction of the coordinates' magnitude ([`Params`]).
pub const FD_GRADIENT: f64 = 0.05;
pub const FD_CURVATURE: f64 = 0.25;
pub const FD_FLOOR: f64 = 1e-4;

/// The scale of a shape for finite-difference steps: its framing size.
pub fn scale(shape: &Shape) -> f64 {
    let b = shape.framing_bounds();
    (b.max - b.min).max_element().max(1e-3)
}

/// The frame at a seed: e1 is the tangent projected onto the tangent plane; without
/// one, or with one (nearly) parallel to n, the world x axis projected (or z where x is
/// nearly normal); e2 = n × e1. The flag says the default was used.
pub fn frame(n: DVec3, tangent: Option<DVec3>) -> (DVec3, DVec3, bool) {
    // A tangent within about 0.06° of the normal has no usable direction in the plane.
    let project = |t: DVec3| {
        let along = t - n * n.dot(t);
        (along.length() > 1e-3 * t.length())
            .then_some(along)?
            .try_normalize()
    };
    let (e1, default) = match tangent.and_then(project) {
        Some(e1) => (e1, false),
        None => {
            let axis = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Z };
            (project(axis).unwrap_or(DVec3::X), true)
        }
    };
    (e1, n.cross(e1), default)
}

impl Atlas {
    /// Projects the seeds (Π_f iterated until |f| < 1e-6 · scale) and builds their
    /// frames, on the shape's field with no atlases or textures ([`NoHeights`]).
    pub fn prepare(def: &AtlasDef, shape: &Shape) -> Result<Atlas, PrepareError> {
        Atlas::prepare_in(def, shape, Arc::new(NoHeights))
    }

    /// [`Atlas::prepare`] on the field of `shape` with `heights` (what its
    /// displacements and shell maps read).
    pub fn prepare_in(
        def: &AtlasDef,
        shape: &Shape,
        heights: Arc<dyn Heights>,
    ) -> Result<Atlas, PrepareError> {
        let field = Field::new(shape, &*heights);
        let s = scale(shape);
        let mut seeds = Vec::new();
        for (i, sd) in def.seeds.iter().enumerate() {
            let written = DVec3::from_array(sd.position);
            let p = eval::project(field, written, 1e-6 * s)
                .ok_or(PrepareError::SeedOffSurface { seed: i })?;
            let n = eval::gradient(field, p).normalize_or_zero();
            let (e1, e2, default_tangent) = frame(n, sd.tangent.map(DVec3::from_array));
            seeds.push(PreparedSeed {
                seed: Seed { p, n, e1, e2 },
                moved: (p - written).length(),
                default_tangent,
                written,
                written_distance: eval::distance(field, written),
                offset: DVec2::ZERO,
            });
        }
        let mut coincident = Vec::new();
        for i in 0..seeds.len() {
            for j in i + 1..seeds.len() {
                if (seeds[i].seed.p - seeds[j].seed.p).length() < 1e-3 * s {
                    coincident.push((i, j));
                }
            }
        }
        let a = &def.params;
        let params = Params {
            steps: a.steps,
            refine: a.refine,
            max_distance: a.max_distance,
            heuristic_tolerance: a.heuristic_tolerance,
            sharp_tolerance: a.sharp_tolerance,
            min_reach: a.min_reach,
            reproject: a.reproject,
            h_gradient: 1e-3 * s,
            fd_gradient: FD_GRADIENT,
            fd_curvature: FD_CURVATURE,
            fd_floor: FD_FLOOR,
            exact_gradient: crate::ir::dual::supported(&shape),
        };
        // The merge graph, walked in f64 with the reference's fine difference steps.
        let pairs: Vec<(usize, usize)> = def
            .merges
            .iter()
            .map(|m| (m.a, m.b))
            .filter(|&(a, b)| !coincident.contains(&(a.min(b), a.max(b))))
            .collect();
        let fixed: Vec<bool> = seeds.iter().map(|s| !s.default_tangent).collect();
        let mut plain: Vec<Seed> = seeds.iter().map(|s| s.seed).collect();
        let f = |q: DVec3| eval::distance(field, q);
        let fine = Params {
            h_gradient: 1e-6 * s,
            ..params.reference()
        };
        let (graph, offsets) = merge::solve(&f, &mut plain, &pairs, &fixed, &fine);
        for ((ps, seed), offset) in seeds.iter_mut().zip(plain).zip(offsets) {
            ps.seed = seed;
            ps.offset = offset;
        }
        let shortest = graph
            .edges
            .iter()
            .map(|e| e.length)
            .fold(f64::INFINITY, f64::min);
        let sigma = a.sigma.unwrap_or(if shortest.is_finite() {
            shortest / 3.0
        } else {
            0.0
        });
        Ok(Atlas {
            name: def.name.clone(),
            seed_names: def.seeds.iter().map(|s| s.name.clone()).collect(),
            shape: shape.clone(),
            seeds,
            params,
            graph,
            sigma,
            coincident,
            mirror: a.mirror.map(|n| DVec3::from_array(n).normalize()),
            rest: RestQuery::default(),
            heights: heights.clone(),
        })
    }

    /// The atlas's shape with the environment of its heights.
    pub fn field(&self) -> Field<'_> {
        Field::new(&self.shape, &*self.heights)
    }

    /// The f64 reference uses much finer difference steps than f32 can: the errors left
    /// are then the algorithm's own.
    pub fn with_reference_steps(mut self) -> Atlas {
        let s = scale(&self.shape);
        self.params = Params {
            h_gradient: 1e-6 * s,
            ..self.params.reference()
        };
        self
    }

    /// Alg. 1 around seed `i`, with maximum distance `max_distance`.
    pub fn walk(&self, x: DVec3, i: usize, max_distance: f64) -> LogMap {
        let f = |q: DVec3| eval::distance(self.field(), q);
        let params = Params {
            max_distance,
            ..self.params
        };
        // The shader's forward derivative, where it has one (Params::exact_gradient).
        let dual = |q: DVec3| crate::ir::dual::eval(&self.shape, q);
        let dual: Option<&dyn Fn(DVec3) -> (DVec3, f64)> = if params.exact_gradient {
            Some(&dual)
        } else {
            None
        };
        log_map_with(&f, dual, x, &self.seeds[i].seed, &params)
    }

    /// The geodesic-nearest seed's log map. Seeds are visited by Euclidean distance and
    /// a seed farther (Euclidean) than the best geodesic distance so far is skipped:
    /// Euclidean never exceeds geodesic distance, so this is exact (Eq. 35). The best
    /// distance so far is the next walks' D. With `brute_force`, every seed is walked.
    pub fn nearest(&self, x: DVec3, brute_force: bool) -> Sample {
        let mut order: Vec<(f64, usize)> = self
            .seeds
            .iter()
            .enumerate()
            .map(|(i, s)| ((x - s.seed.p).length(), i))
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.search(x, order.into_iter(), brute_force)
    }

    /// The nearest-seed search over a [`SeedGrid`] cell's list, as the generated shader
    /// runs it: a seed whose lower bound is not below the best distance so far ends it.
    pub fn nearest_in_grid(&self, x: DVec3, grid: &SeedGrid) -> Sample {
        let list = grid
            .entries(grid.list(x))
            .map(|(i, bound)| (bound, i))
            .collect::<Vec<_>>();
        self.search(x, list.into_iter(), false)
    }

    /// The pruning of the field for this atlas's walks ([`super::prune`]), if some
    /// union operand could be pruned for some seed.
    pub fn pruning(&self) -> Option<super::prune::Pruning> {
        let seeds: Vec<DVec3> = self.seeds.iter().map(|s| s.seed.p).collect();
        super::prune::Pruning::new(&self.shape, &seeds)
    }

    /// The seed acceleration grid the generated shader uses for this atlas.
    pub fn seed_grid(&self) -> SeedGrid {
        let b = self.shape.framing_bounds();
        let pad = 1e-3 * scale(&self.shape);
        let points: Vec<DVec3> = self.seeds.iter().map(|s| s.seed.p).collect();
        SeedGrid::build(
            &points,
            b.min - DVec3::splat(pad),
            b.max + DVec3::splat(pad),
            self.params.max_distance,
        )
    }

    /// Walks seeds in the given order of (lower bound of Euclidean distance, seed).
    fn search(
        &self,
        x: DVec3,
        order: impl Iterator<Item = (f64, usize)>,
        brute_force: bool,
    ) -> Sample {
        let mut best: Option<(usize, LogMap)> = None;
        let mut first_failure = None;
        for (euclid, i) in order {
            let bound = best
                .as_ref()
                .map(|(_, m)| m.distance)
                .unwrap_or(self.params.max_distance);
            if !brute_force && best.is_some() && euclid >= bound {
                break;
            }
            let m = self.walk(
                x,
                i,
                if brute_force {
                    self.params.max_distance
                } else {
                    bound
                },
            );
            if m.status == Status::Ok {
                if best.as_ref().is_none_or(|(_, b)| m.distance < b.distance) {
                    best = Some((i, m));
                }
            } else if best.is_none() {
                // Report the Euclidean-nearest failure, whatever the visiting order (as
                // the generated shader does).
                let e = (x - self.seeds[i].seed.p).length();
                if first_failure.is_none_or(|(_, _, f)| e < f) {
                    first_failure = Some((i, m.status, e));
                }
            }
        }
        match best {
            Some((seed, m)) => Sample {
                status: Status::Ok,
                uv: m.uv,
                distance: m.distance,
                transport: m.transport,
                seed: Some(seed),
                weight: 1.0,
                tangent: m.transport * self.seeds[seed].seed.e1,
                bitangent: m.transport * self.seeds[seed].seed.e2,
            },
            None => {
                let (seed, status) = first_failure
                    .map(|(i, s, _)| (Some(i), s))
                    .unwrap_or((None, Status::TooFar));
                Sample {
                    status,
                    uv: DVec2::ZERO,
                    distance: f64::INFINITY,
                    transport: DMat3::IDENTITY,
                    seed,
                    weight: 0.0,
                    tangent: DVec3::ZERO,
                    bitangent: DVec3::ZERO,
                }
            }
        }
    }

    /// Alg. 2: the blended uv at a surface point, from the nearest seed and its merged
    /// neighbours.
    pub fn sample(&self, x: DVec3) -> Sample {
        self.sample_with(x, Search::default())
    }

    /// [`Atlas::sample`] with a choice of search. With a `mirror` plane, a point on its
    /// negative side is sampled at its reflection, and the transported frames and
    /// transport come back reflected (so a mirrored frame is left-handed).
    pub fn sample_with(&self, x: DVec3, search: Search) -> Sample {
        let Some(n) = self.mirror.filter(|n| x.dot(*n) < 0.0) else {
            let nearest = self.nearest(x, search.brute_force);
            return self.blend(x, nearest);
        };
        let r = DMat3::IDENTITY - 2.0 * DMat3::from_cols(n * n.x, n * n.y, n * n.z);
        let y = r * x;
        let mut s = self.blend(y, self.nearest(y, search.brute_force));
        s.tangent = r * s.tangent;
        s.bitangent = r * s.bitangent;
        s.transport = r * s.transport * r;
        s
    }

    /// What a material reads at a point `p` of the render target (the generated
    /// `atlas_K_at`): Alg. 2 at the rest point ω⁻¹(p) of the occurrence of the atlas's
    /// shape that `p` lies on ([`RestQuery`]), moved onto the surface ([`Atlas::onto`]),
    /// with the transported frames carried back by the differential of ω.
    pub fn sample_at(&self, p: DVec3) -> Sample {
        self.sample_at_with(p, true)
    }

    /// [`Atlas::sample_at`], with the rest point moved onto the surface only with
    /// `onto` (the atlas views sample as they are, `atlas_K_at(p, false)`).
    pub fn sample_at_with(&self, p: DVec3, onto: bool) -> Sample {
        let at = |q: DVec3| if onto { self.onto(q) } else { q };
        let Some((i, q)) = self.rest.locate(self.field(), p) else {
            return self.sample(at(p));
        };
        let mut s = self.sample(at(q));
        let occ = &self.rest.occurrences[i];
        if occ.moves_frames() {
            let j = occ.jacobian(p, self.params.h_gradient);
            if let Some(inv) = (j.determinant().abs() > 1e-12).then(|| j.inverse()) {
                s.tangent = inv * s.tangent;
                s.bitangent = inv * s.bitangent;
            }
        }
        s
    }

    /// The blend of Alg. 2 around an already found nearest seed. `uv` comes back in the
    /// atlas's common uv space (the seed's offset added), `weight` is the nearest seed's
    /// normalized weight w_{i*} / (W + w_{i*}).
    pub fn blend(&self, x: DVec3, nearest: Sample) -> Sample {
        let (Status::Ok, Some(i)) = (nearest.status, nearest.seed) else {
            return nearest;
        };
        let mut out = nearest;
        let own = nearest.uv + self.seeds[i].offset;
        let neighbors = &self.graph.neighbors[i];
        if neighbors.is_empty() {
            out.uv = own;
            return out;
        }
        let d = nearest.distance;
        let sigma = self.sigma;
        let (mut sum, mut total, mut w_own) = (DVec2::ZERO, 0.0, 1.0f64);
        // The transported frames R_{p_j→x}·(e1_j, e2_j), blended with the uv's weights.
        let (mut t_sum, mut b_sum) = (DVec3::ZERO, DVec3::ZERO);
        for &(j, d_ij) in neighbors {
            // Eq. 44: when even the Euclidean distance to p_j puts x beyond the band,
            // w_{i*,j} = 1 and p_j does not contribute.
            if d * d + 2.0 * sigma * d_ij < (x - self.seeds[j].seed.p).length_squared() {
                continue;
            }
            let m = self.walk(x, j, d + 2.0 * sigma);
            if m.status != Status::Ok {
                continue;
            }
            let w_ij = blend_weight(frontier_distance(d, m.distance, d_ij), sigma);
            w_own = w_own.min(w_ij); // Eq. 41
            let w_j = 1.0 - w_ij; // Eq. 42
            sum += w_j * (m.uv + self.seeds[j].offset);
            total += w_j;
            t_sum += w_j * (m.transport * self.seeds[j].seed.e1);
            b_sum += w_j * (m.transport * self.seeds[j].seed.e2);
        }
        // The corrected last line of Alg. 2 (notes, item 3).
        out.uv = (sum + w_own * own) / (total + w_own);
        out.weight = w_own / (total + w_own);
        out.tangent = (t_sum + w_own * nearest.tangent) / (total + w_own);
        out.bitangent = (b_sum + w_own * nearest.bitangent) / (total + w_own);
        out
    }

    /// The log map of every seed at x (full D), for `sdfc eval --all-seeds`.
    pub fn all_seeds(&self, x: DVec3) -> Vec<LogMap> {
        (0..self.seeds.len())
            .map(|i| self.walk(x, i, self.params.max_distance))
            .collect()
    }

    /// Whether seeds i and j are merged.
    pub fn merged(&self, i: usize, j: usize) -> bool {
        self.graph.neighbors[i].iter().any(|&(k, _)| k == j)
    }

    /// Below this |f| a material's point is on the surface: 1e-3 of the scale.
    pub fn onto_tolerance(&self) -> f64 {
        1e-3 * scale(&self.shape)
    }

    /// A material's point onto the surface when it lies off it by more than
    /// [`Atlas::onto_tolerance`] (one step of Eq. 57, the generated `atlas_K_onto`), as
    /// on a displaced shape painted with its base's atlas.
    pub fn onto(&self, x: DVec3) -> DVec3 {
        let f = eval::distance(self.field(), x);
        if f.abs() <= self.onto_tolerance() {
            return x;
        }
        let g = eval::gradient(self.field(), x);
        x - g * (f / g.length_squared().max(1e-300))
    }

    /// The surface normal used at a point.
    pub fn normal(&self, x: DVec3) -> DVec3 {
        let f = |q: DVec3| eval::distance(self.field(), q);
        gradient(&f, x, self.params.h_gradient).normalize_or_zero()
    }
}

/// An atlas evaluated at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub status: Status,
    pub uv: DVec2,
    pub distance: f64,
    pub transport: DMat3,
    /// The chosen seed (or, on failure, the nearest seed that failed).
    pub seed: Option<usize>,
    /// The chosen seed's normalized blend weight (1 away from merged frontiers).
    pub weight: f64,
    /// The seeds' frames (e1, e2) carried to x by the walks' parallel transport
    /// (R_{p_i→x}·TBN_i of Eq. 52), blended with the uv's weights: the tangent frame
    /// of normal maps, not yet re-orthonormalized ([`tangent_frame`]). Zero where the
    /// sample failed.
    pub tangent: DVec3,
    pub bitangent: DVec3,
}

/// A blended transported frame (t, b) re-orthonormalized in the tangent plane of the
/// unit normal n: the rotation of the plane nearest to the blend (the polar
/// decomposition of the 2 × 2 frame, symmetric in t and b), as (t', b' = n × t'). `None`
/// where the frame is degenerate (a failed sample). shaders/render.wgsl's
/// `sdfc_tangent_frame` computes the same in f32.
pub fn tangent_frame(t: DVec3, b: DVec3, n: DVec3) -> Option<(DVec3, DVec3)> {
    // For a right-handed frame b = n × t, b × n is t again: their mean is the
    // polar factor's first column. A mirrored frame (§5.1) is left-handed, b = −n × t,
    // and keeps its handedness.
    let hand = if t.cross(b).dot(n) < 0.0 { -1.0 } else { 1.0 };
    let s = t + hand * b.cross(n);
    let s = s - n * n.dot(s);
    let len = s.length();
    if !(len >= 1e-6) {
        return None;
    }
    let t = s / len;
    Some((t, hand * n.cross(t)))
}

/// Eq. 39: the approximate signed distance from x to the Voronoi frontier between seeds
/// i and j (negative on i's side), from the geodesic distances d_i, d_j and d_ij.
pub fn frontier_distance(d_i: f64, d_j: f64, d_ij: f64) -> f64 {
    (d_i * d_i - d_j * d_j) / (2.0 * d_ij)
}

/// Eq. 40 with ω(t) = 3t² − 2t³: 1 deep on i's side, 0 beyond the band on j's side.
pub fn blend_weight(frontier: f64, sigma: f64) -> f64 {
    if frontier < -sigma {
        1.0
    } else if frontier > sigma {
        0.0
    } else {
        let t = 0.5 - frontier / (2.0 * sigma);
        t * t * (3.0 - 2.0 * t)
    }
}
