//! Atlases on the CPU: seeds projected onto the surface with their frames
//! (done at compile time), and the per-point search for the geodesic-nearest
//! seed (Alg. 2's search with the exact early-out of Eq. 35).

use super::logmap::{gradient, log_map, LogMap, Params, Seed, Status};
use crate::ir::{eval, Shape};
use crate::sema::AtlasDef;
use glam::{DMat3, DVec2, DVec3};

/// A seed after projection, with what the user should be told about it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedSeed {
    pub seed: Seed,
    /// How far projection moved the seed from where it was written.
    pub moved: f64,
    /// Whether the frame's e1 came from a default rather than a `tangent`.
    pub default_tangent: bool,
}

/// An atlas ready to evaluate: its shape, projected seeds and parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Atlas {
    pub name: String,
    /// Seed names, in declaration order.
    pub seed_names: Vec<String>,
    pub shape: Shape,
    pub seeds: Vec<PreparedSeed>,
    pub params: Params,
}

/// Why an atlas cannot be prepared.
#[derive(Debug, Clone, PartialEq)]
pub enum PrepareError {
    /// Projection of a seed onto the surface did not converge.
    SeedOffSurface { seed: usize },
}

/// The scale of a shape for finite-difference steps: its framing size.
pub fn scale(shape: &Shape) -> f64 {
    let b = shape.framing_bounds();
    (b.max - b.min).max_element().max(1e-3)
}

/// The frame at a seed: e1 is the tangent projected onto the tangent plane; without
/// one, the world x axis projected (or z where x is nearly normal); e2 = n × e1.
pub fn frame(n: DVec3, tangent: Option<DVec3>) -> (DVec3, DVec3, bool) {
    let project = |t: DVec3| (t - n * n.dot(t)).try_normalize();
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
    /// Projects the seeds (Π_f iterated until |f| < 1e-6 · scale) and builds their frames.
    pub fn prepare(def: &AtlasDef, shape: &Shape) -> Result<Atlas, PrepareError> {
        let s = scale(shape);
        let mut seeds = Vec::new();
        for (i, sd) in def.seeds.iter().enumerate() {
            let written = DVec3::from_array(sd.position);
            let p = eval::project(shape, written, 1e-6 * s)
                .ok_or(PrepareError::SeedOffSurface { seed: i })?;
            let n = eval::gradient(shape, p).normalize_or_zero();
            let (e1, e2, default_tangent) = frame(n, sd.tangent.map(DVec3::from_array));
            seeds.push(PreparedSeed {
                seed: Seed { p, n, e1, e2 },
                moved: (p - written).length(),
                default_tangent,
            });
        }
        let a = &def.params;
        let params = Params {
            steps: a.steps,
            max_distance: a.max_distance,
            heuristic_tolerance: a.heuristic_tolerance,
            sharp_tolerance: a.sharp_tolerance,
            min_reach: a.min_reach,
            reproject: a.reproject,
            h_gradient: 1e-3 * s,
            h_curvature: 1e-2 * s,
        };
        Ok(Atlas {
            name: def.name.clone(),
            seed_names: def.seeds.iter().map(|s| s.name.clone()).collect(),
            shape: shape.clone(),
            seeds,
            params,
        })
    }

    /// The f64 reference uses much finer difference steps than f32 can: the errors left
    /// are then the algorithm's own.
    pub fn with_reference_steps(mut self) -> Atlas {
        let s = scale(&self.shape);
        self.params.h_gradient = 1e-6 * s;
        self.params.h_curvature = 1e-4 * s;
        self
    }

    /// Alg. 1 around seed `i`, with maximum distance `max_distance`.
    pub fn walk(&self, x: DVec3, i: usize, max_distance: f64) -> LogMap {
        let f = |q: DVec3| eval::distance(&self.shape, q);
        let params = Params {
            max_distance,
            ..self.params
        };
        log_map(&f, x, &self.seeds[i].seed, &params)
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
            } else if first_failure.is_none() {
                first_failure = Some((i, m.status));
            }
        }
        match best {
            Some((seed, m)) => Sample {
                status: Status::Ok,
                uv: m.uv,
                distance: m.distance,
                transport: m.transport,
                seed: Some(seed),
            },
            None => {
                let (seed, status) = first_failure
                    .map(|(i, s)| (Some(i), s))
                    .unwrap_or((None, Status::TooFar));
                Sample {
                    status,
                    uv: DVec2::ZERO,
                    distance: f64::INFINITY,
                    transport: DMat3::IDENTITY,
                    seed,
                }
            }
        }
    }

    /// The surface normal used at a point.
    pub fn normal(&self, x: DVec3) -> DVec3 {
        let f = |q: DVec3| eval::distance(&self.shape, q);
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
}
