//! Alg. 1 of the Implicit UVs paper in f64, with the erratum of
//! `shared/notes/implicit-uvs-notes.md`: the point-wise log map around one seed,
//! by a geodesic walk of exactly N steps. `shaders/uv.wgsl` and the generated
//! walk mirror this function step for step.

use glam::{DMat3, DQuat, DVec2, DVec3};

/// Why a walk failed; kept distinct all the way to the user.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Status {
    Ok,
    /// d > D, or r + d > D.
    TooFar,
    /// |v_i| < ε1 · |p − x_i|: the Euclidean heuristic has no tangent direction.
    HeuristicFailed,
    /// n_i · n_{i+1} < 1 − ε2.
    SharpFeature,
    /// d(x_N, p) ≥ r_min after N steps.
    NotReached,
}

impl Status {
    /// The number the shaders and `ATLAS.status` use.
    pub fn code(self) -> u32 {
        match self {
            Status::Ok => 0,
            Status::TooFar => 1,
            Status::HeuristicFailed => 2,
            Status::SharpFeature => 3,
            Status::NotReached => 4,
        }
    }

    pub fn from_code(c: u32) -> Status {
        match c {
            0 => Status::Ok,
            1 => Status::TooFar,
            2 => Status::HeuristicFailed,
            3 => Status::SharpFeature,
            _ => Status::NotReached,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::TooFar => "too_far",
            Status::HeuristicFailed => "heuristic_failed",
            Status::SharpFeature => "sharp_feature",
            Status::NotReached => "not_reached",
        }
    }
}

/// A seed with its projected position, unit normal and frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed {
    pub p: DVec3,
    pub n: DVec3,
    pub e1: DVec3,
    pub e2: DVec3,
}

/// The parameters of Alg. 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// N
    pub steps: u32,
    /// D
    pub max_distance: f64,
    /// ε1
    pub heuristic_tolerance: f64,
    /// ε2
    pub sharp_tolerance: f64,
    /// r_min
    pub min_reach: f64,
    pub reproject: bool,
    /// Finite-difference step for gradients (about 1e-3 · scale in f32).
    pub h_gradient: f64,
    /// Finite-difference step for the second directional difference (Eq. 17).
    pub h_curvature: f64,
}

/// The result of one walk.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogMap {
    pub status: Status,
    pub uv: DVec2,
    /// Geodesic distance r.
    pub distance: f64,
    /// Parallel transport T_pM → T_xM.
    pub transport: DMat3,
    /// Where the walk stopped: the seed on success, else the point where it failed
    /// (for diagnostics such as "sharp feature at (x, y, z)").
    pub at: DVec3,
}

impl LogMap {
    fn fail(status: Status, at: DVec3) -> LogMap {
        LogMap {
            status,
            uv: DVec2::ZERO,
            distance: f64::INFINITY,
            transport: DMat3::IDENTITY,
            at,
        }
    }

    /// The log map as a tangent vector at the seed: u·e1 + v·e2.
    pub fn tangent(&self, seed: &Seed) -> DVec3 {
        seed.e1 * self.uv.x + seed.e2 * self.uv.y
    }

    /// The transport as a unit quaternion (x, y, z, w), as `ATLAS.transport` gives it.
    pub fn transport_quat(&self) -> DQuat {
        DQuat::from_mat3(&self.transport).normalize()
    }
}

/// The gradient of f by central differences.
pub fn gradient(f: &dyn Fn(DVec3) -> f64, x: DVec3, h: f64) -> DVec3 {
    let d = |e: DVec3| f(x + e * h) - f(x - e * h);
    DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z)) / (2.0 * h)
}

/// Eq. 31: the smallest rotation taking unit `a` to unit `b`: I + J + J²/(1 + a·b),
/// J the cross-product matrix of a × b. Near a·b = −1 (which the sharp-feature test
/// normally rejects first) it falls back to the identity.
pub fn rotation_between(a: DVec3, b: DVec3) -> DMat3 {
    let c = a.dot(b);
    if c <= -1.0 + 1e-9 {
        return DMat3::IDENTITY;
    }
    let k = a.cross(b);
    let j = DMat3::from_cols(
        DVec3::new(0.0, k.z, -k.y),
        DVec3::new(-k.z, 0.0, k.x),
        DVec3::new(k.y, -k.x, 0.0),
    );
    DMat3::IDENTITY + j + j * j * (1.0 / (1.0 + c))
}

/// Notes, item 2: the step τ whose parabolic chord has length s, stable as α → 0.
pub fn time_step(s: f64, alpha: f64) -> f64 {
    s * (2.0 / (1.0 + (1.0 + s * s * alpha * alpha).sqrt())).sqrt()
}

/// Notes, item 1: Simpson's rule (1-4-1) for the length of γ(t) = x + t v + t²/2 κ n.
pub fn arc_length(tau: f64, kappa: f64) -> f64 {
    let k2 = kappa * kappa * tau * tau;
    tau / 6.0 * (1.0 + 4.0 * (1.0 + k2 / 4.0).sqrt() + (1.0 + k2).sqrt())
}

/// Π_f (Eq. 18): one Newton projection onto the zero set.
pub fn reproject(f: &dyn Fn(DVec3) -> f64, x: DVec3, h: f64) -> DVec3 {
    let g = gradient(f, x, h);
    let g2 = g.length_squared();
    if g2 > 0.0 {
        x - g * (f(x) / g2)
    } else {
        x
    }
}

/// Alg. 1: the log map of `x` (on the surface of `f`) around `seed`.
pub fn log_map(f: &dyn Fn(DVec3) -> f64, x: DVec3, seed: &Seed, params: &Params) -> LogMap {
    let n_steps = params.steps.max(1);
    let p = seed.p;
    if (x - p).length() > params.max_distance {
        return LogMap::fail(Status::TooFar, x);
    }
    // Within r_min of the seed the walk has nothing left to do: the answer is the
    // tangent projection of x − p itself (the limit of the last step below).
    let d0 = (x - p).length();
    if d0 < params.min_reach {
        let t = (x - p) - seed.n * seed.n.dot(x - p);
        let t = t.normalize_or_zero();
        return LogMap {
            status: Status::Ok,
            uv: DVec2::new(t.dot(seed.e1), t.dot(seed.e2)) * d0,
            distance: d0,
            transport: DMat3::IDENTITY,
            at: p,
        };
    }
    let mut xi = x;
    let mut prev = x;
    let mut r = 0.0;
    let mut rot = DMat3::IDENTITY;
    let mut gi = gradient(f, xi, params.h_gradient);
    let mut ni = gi.normalize_or_zero();
    for i in 0..n_steps {
        let s = (xi - p).length() / (n_steps - i) as f64;
        // Direction: the tangent projection of p − x_i.
        let to_p = p - xi;
        let v = to_p - ni * ni.dot(to_p);
        let vl = v.length();
        // ε1 is relative to the remaining distance: the heuristic fails where p − x_i is
        // (nearly) along the normal. An absolute test would fail every walk that starts
        // within N·ε1 of the seed, whose last steps are shorter than ε1.
        if vl < params.heuristic_tolerance * to_p.length() {
            return LogMap::fail(Status::HeuristicFailed, xi);
        }
        let vh = v / vl;
        // Normal curvature along v̂ by the three-point second difference (Eq. 17).
        let h = params.h_curvature;
        let second = (f(xi - vh * h) - 2.0 * f(xi) + f(xi + vh * h)) / (h * h);
        let kappa = -second / gi.length().max(1e-12);
        let tau = time_step(s, kappa);
        // Second-order exponential-map step (Eq. 16).
        let mut next = xi + vh * tau + ni * (0.5 * tau * tau * kappa);
        if params.reproject {
            next = reproject(f, next, params.h_gradient);
        }
        let g_next = gradient(f, next, params.h_gradient);
        let n_next = g_next.normalize_or_zero();
        if n_next.dot(ni) < 1.0 - params.sharp_tolerance {
            return LogMap::fail(Status::SharpFeature, next);
        }
        rot *= rotation_between(n_next, ni);
        r += arc_length(tau, kappa);
        prev = xi;
        xi = next;
        gi = g_next;
        ni = n_next;
        if r + (xi - p).length() > params.max_distance {
            return LogMap::fail(Status::TooFar, xi);
        }
    }
    let rest = (xi - p).length();
    if rest >= params.min_reach {
        return LogMap::fail(Status::NotReached, xi);
    }
    let r = r + rest;
    // x_{N−1} − p rather than x_{N−1} − x_N, for robustness.
    let d = prev - p;
    let t = d - seed.n * seed.n.dot(d);
    let t = t.normalize_or_zero();
    LogMap {
        status: Status::Ok,
        uv: DVec2::new(t.dot(seed.e1), t.dot(seed.e2)) * r,
        distance: r,
        transport: rot * rotation_between(seed.n, ni),
        at: p,
    }
}
