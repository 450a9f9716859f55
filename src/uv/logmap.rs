//! Alg. 1 of the Implicit UVs paper (Genest, Gueth, Levallois and Wang, "Implicit UVs:
//! Real-time semi-global parameterization of implicit surfaces", Computer Graphics Forum,
//! Eurographics 2025) in f64, with its authors' erratum (docs/papers.md, "The erratum"):
//! the point-wise log map around one seed, by a geodesic walk of exactly N steps.
//! `shaders/uv.wgsl` and the generated walk mirror this function step for step.

pub use super::geodesic::{
    gradient, gradient_value, normal_curvature, rotation_between, FdSteps, LogMap, Params, Seed,
    Status,
};
use glam::{DMat3, DVec2, DVec3};

/// Notes, item 2: the step τ whose parabolic chord has length s, stable as α → 0.
pub fn time_step(s: f64, alpha: f64) -> f64 {
    s * (2.0 / (1.0 + (1.0 + s * s * alpha * alpha).sqrt())).sqrt()
}

/// The chord of the next step: the remaining arc split evenly. Where the path ahead
/// curves like the osculating circle of curvature κ, the remaining chord c spans the
/// angle 2·asin(κc/2), and each of the `remaining` steps should span an equal part of
/// it: (2/κ)·sin(asin(κc/2)/remaining). The paper's c/remaining splits the chord
/// evenly instead, which leaves the longest steps (and the largest turns of the
/// normal) for last on a curved tube. The two agree as κ → 0 and on the last step; it
/// is never shorter than c/remaining.
pub fn step_chord(chord: f64, kappa: f64, remaining: u32) -> f64 {
    let m = remaining as f64;
    let a = (0.5 * kappa.abs() * chord).min(1.0);
    if a < 1e-4 {
        return chord / m;
    }
    (chord / m) * (m * (a.asin() / m).sin() / a).max(1.0)
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

/// The smooth model's allowance for the normal's turn over a step, as a multiple of
/// κ·τ (the turn of a normal section of curvature κ over a step τ): the excess covers
/// the geodesic torsion of directions off the principal ones (at most κτ/6 beyond 1.5κτ
/// on a cylinder) and the change of curvature along the step.
pub const TURN_SLACK: f64 = 1.5;

/// ε2 as an angle: acos(1 − ε2), the turn per step that no smooth model has to explain.
pub fn sharp_angle(sharp_tolerance: f64) -> f64 {
    (1.0 - sharp_tolerance).clamp(-1.0, 1.0).acos()
}

/// Whether a step's normal turned more than a smooth surface explains: more than
/// θ0 = acos(1 − ε2) plus [`TURN_SLACK`]·κ·τ, κ the smaller rate of turn of the normal
/// on the two sides of the step (the steps before and after it; |κ| of Eq. 17 before
/// the first step and after the last), or more than 3·θ0 whatever the rate. A crease
/// turns the normal over one step while the faces on either side are flat (a rate ≈ 0
/// on one side at least); a smooth tube turns it by κτ, however long the step.
pub fn sharp_turn(turn: f64, kappa: f64, tau: f64, theta0: f64) -> bool {
    turn > (theta0 + TURN_SLACK * kappa * tau).min(3.0 * theta0)
}

/// The normal curvature along unit tangent `vh` over a step of arc length `arc` whose
/// end has the unit normal `n_next` (`vh` is tangent at its start): the normal's turn in
/// the plane of `vh` and the normal, by the Weingarten equation dn/ds = −S(v), whose
/// component along v is the normal curvature. The sign is Eq. 17's (−f''/|∇f|: negative
/// where the surface bends away from its normal, as on a sphere).
pub fn turn_curvature(n_next: DVec3, vh: DVec3, arc: f64) -> f64 {
    if arc <= 0.0 {
        return 0.0;
    }
    -n_next.dot(vh).clamp(-1.0, 1.0).asin() / arc
}

/// Alg. 1: the log map of `x` (on the surface of `f`) around `seed`.
///
/// Departures from the paper (docs/papers.md, "Our departures from Alg. 1"):
/// - each step spans an equal part of the remaining arc ([`step_chord`]);
/// - the sharp-feature test compares the normal's turn with the normal's rate of turn
///   over the steps before and after it ([`sharp_turn`]), so a step's test waits for
///   the next step (after the last step, one more second difference gives the rate);
/// - κ comes from Eq. 17 for the first step only; every later step takes it from the
///   normal's turn over the step before ([`turn_curvature`]), and each step ends with a
///   Newton step back onto the level set of f through x (the surface, for x on it),
///   whose f is the mean of the gradient's six taps ([`gradient_value`]), or f itself
///   with the forward derivative ([`Params::exact_gradient`]). A step costs 6
///   evaluations instead of 9 (one of the derivative where the compiler writes it), and the walk does not drift off its level set (the
///   sphere's distance error drops from 3.5e-5 to 2.7e-7);
/// - the start looks only where the walk goes: Eq. 17's first second difference is
///   centred a tap ahead of x along the first direction, and the gradient at x is
///   narrower than a step's ([`Params::fd_start`]), so that neither reaches across a
///   crease beside x that the walk never meets.
pub fn log_map(f: &dyn Fn(DVec3) -> f64, x: DVec3, seed: &Seed, params: &Params) -> LogMap {
    log_map_with(f, None, x, seed, params)
}

/// [`log_map`] with the field's forward derivative `dual` ((∇f, f), `ir::dual::eval`),
/// which the walk reads where [`Params::exact_gradient`] says the shader does.
pub fn log_map_with(
    f: &dyn Fn(DVec3) -> f64,
    dual: Option<&dyn Fn(DVec3) -> (DVec3, f64)>,
    x: DVec3,
    seed: &Seed,
    params: &Params,
) -> LogMap {
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
    let mut fd = FdSteps::new(params, p, x);
    if let Some(d) = dual {
        fd = fd.with_dual(d);
    }
    let theta0 = sharp_angle(params.sharp_tolerance);
    let mut xi = x;
    let mut prev = x;
    let mut r = 0.0;
    let mut rot = DMat3::IDENTITY;
    let mut s = d0 / n_steps as f64;
    // f at x: the walk keeps to its level set (the surface, for a point on it). The
    // difference is narrower at x than along the walk (Params::fd_start).
    let (mut gi, level) = fd.grad_value(f, xi, fd.start(s));
    let mut ni = gi.normalize_or_zero();
    // κ for the next step: Eq. 17 before the first step, then the normal's turn over
    // the step just taken (no evaluations: the gradients at its ends are known).
    let mut kappa_next: Option<f64> = None;
    // The normal's rate of turn over the last step (|κ| of Eq. 17 before the first).
    let mut rate_before = 0.0;
    // The last step's turn, the rate before it, its τ and end, until the rate after it
    // is known.
    let mut pending: Option<(f64, f64, f64, DVec3)> = None;
    let mut vh = DVec3::ZERO;
    for i in 0..n_steps {
        let remaining = n_steps - i;
        let chord = (xi - p).length();
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
        vh = v / vl;
        let kappa = match kappa_next {
            Some(k) => k,
            None => {
                // Centred a difference step ahead (taps x, x + h·v̂, x + 2h·v̂): the
                // walk goes that way, and a tap behind x would cross a crease that x
                // lies next to but the walk never meets.
                let h = fd.curvature(chord / remaining as f64);
                let k = normal_curvature(f, xi + vh * h, vh, gi, h);
                rate_before = k.abs();
                k
            }
        };
        s = step_chord(chord, kappa, remaining);
        let tau = time_step(s, kappa);
        // Second-order exponential-map step (Eq. 16).
        let mut next = xi + vh * tau + ni * (0.5 * tau * tau * kappa);
        if params.reproject {
            let g = fd.grad(f, next, fd.gradient(s));
            if g.length_squared() > 0.0 {
                next -= g * (f(next) / g.length_squared());
            }
        }
        let (g_next, f_next) = fd.grad_value(f, next, fd.gradient(s));
        // Back onto the level set of x along the gradient (Eq. 18 with what the
        // gradient's taps already tell; on a distance field the gradient is the same at
        // the foot), so that the errors of κ's estimates do not add up into a drift.
        if !params.reproject {
            next -= g_next * ((f_next - level) / g_next.length_squared().max(1e-300));
        }
        let n_next = g_next.normalize_or_zero();
        let turn = n_next.dot(ni).clamp(-1.0, 1.0).acos();
        // Beyond 3·θ0 no curvature at the far end can excuse the turn.
        if turn > 3.0 * theta0 {
            return LogMap::fail(Status::SharpFeature, next);
        }
        let arc = arc_length(tau, kappa);
        // The normal's rate of turn over this step (normal curvature and geodesic
        // torsion together): what a smooth surface's next and previous steps share and
        // a crease's step does not.
        let rate = if arc > 0.0 { turn / arc } else { 0.0 };
        // The previous step's turn, now that the rate after it is known.
        if let Some((t0, k0, tau0, at)) = pending.take() {
            if sharp_turn(t0, k0.min(rate), tau0, theta0) {
                return LogMap::fail(Status::SharpFeature, at);
            }
        }
        pending = Some((turn, rate_before, tau, next));
        rate_before = rate;
        kappa_next = Some(turn_curvature(n_next, vh, arc));
        rot *= rotation_between(n_next, ni);
        r += arc;
        prev = xi;
        xi = next;
        gi = g_next;
        ni = n_next;
        if r + (xi - p).length() > params.max_distance {
            return LogMap::fail(Status::TooFar, xi);
        }
    }
    if let Some((turn, k0, tau, at)) = pending {
        let vh = (vh - ni * ni.dot(vh)).normalize_or_zero();
        let kappa = normal_curvature(f, xi, vh, gi, fd.curvature(s));
        if sharp_turn(turn, k0.min(kappa.abs()), tau, theta0) {
            return LogMap::fail(Status::SharpFeature, at);
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
    let mut m = LogMap {
        status: Status::Ok,
        uv: DVec2::new(t.dot(seed.e1), t.dot(seed.e2)) * r,
        distance: r,
        transport: rot * rotation_between(seed.n, ni),
        at: p,
    };
    if params.refine > 0 {
        super::refine::correct(f, x, seed, &mut m, params.refine, n_steps, &fd);
    }
    m
}
