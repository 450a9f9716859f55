//! What the geodesic walk of Alg. 1 ([`super::logmap`]) and its Newton corrections
//! ([`super::refine`]) share: the seed's frame, the walk's parameters and answer, and
//! the geometry of f by finite differences (gradient, normal curvature, the smallest
//! rotation between two normals). [`super::logmap`] re-exports all of it.

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
    /// K: Newton corrections towards the exact log map ([`super::refine`]).
    pub refine: u32,
    /// D
    pub max_distance: f64,
    /// ε1
    pub heuristic_tolerance: f64,
    /// ε2
    pub sharp_tolerance: f64,
    /// r_min
    pub min_reach: f64,
    pub reproject: bool,
    /// Finite-difference step for gradients off the walk (normals, projection onto the
    /// surface): about 1e-3 · scale in f32.
    pub h_gradient: f64,
    /// The walk's gradient step, as a fraction of the step length.
    pub fd_gradient: f64,
    /// The walk's step for the second directional difference (Eq. 17), as a fraction of
    /// the step length.
    pub fd_curvature: f64,
    /// The floor of these and of the start's gradient step ([`Params::fd_start`]), as a
    /// fraction of |p|∞ + |x − p| (the coordinates' magnitude,
    /// which sets the rounding error).
    pub fd_floor: f64,
    /// The field's gradient is exact: the generated WGSL differentiates it forward
    /// (`ir::dual::supported`, `codegen::dual`), and the walk here reads it to f64's
    /// precision ([`exact_gradient`]) where it took differences of the step's width.
    pub exact_gradient: bool,
}

/// How much narrower than a step's gradient difference the one at the walk's start is
/// ([`Params::fd_start`]).
pub const START_NARROWING: f64 = 4.0;

impl Params {
    /// The gradient's step at the walk's start, as a fraction of the first step's
    /// length: [`Params::fd_gradient`] narrowed by [`START_NARROWING`]. The query point
    /// may lie next to a crease that its walk never crosses (a face's point by the
    /// face's edge, walking inwards); a difference as wide as a step's would straddle
    /// that crease and tilt the start's normal into a false sharp feature. Narrower
    /// still (the floor alone) and f32's rounding shows in the uv where the log map is
    /// sensitive to the first direction (near a cylinder's cut locus).
    pub fn fd_start(&self) -> f64 {
        self.fd_gradient / START_NARROWING
    }

    /// The same walk with the f64 reference's fine difference steps (far below what f32
    /// allows): the errors left are then the algorithm's own.
    pub fn reference(self) -> Params {
        Params {
            fd_gradient: 1e-4,
            fd_curvature: 1e-2,
            fd_floor: 1e-10,
            ..self
        }
    }
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
    pub(super) fn fail(status: Status, at: DVec3) -> LogMap {
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

/// The gradient by central differences, with the mean of its six taps: f(x) plus
/// (h²/6)·Δf, an estimate of f(x) that costs no evaluation (for the walk's h, a few
/// 1e-4 of the step length squared times the mean curvature).
pub fn gradient_value(f: &dyn Fn(DVec3) -> f64, x: DVec3, h: f64) -> (DVec3, f64) {
    let mut g = DVec3::ZERO;
    let mut sum = 0.0;
    for e in [DVec3::X, DVec3::Y, DVec3::Z] {
        let (a, b) = (f(x + e * h), f(x - e * h));
        g += e * (a - b);
        sum += a + b;
    }
    (g / (2.0 * h), sum / 6.0)
}

/// The gradient to f64's precision where the field is smooth, the CPU side of the
/// generated WGSL's forward derivatives: fourth-order central differences (Richardson's
/// five-point stencil) of step 1e-4 of the coordinates' magnitude `scale`, whose
/// truncation (h⁴/30 of the fifth derivative) and rounding (1e-16 of f over h) are both
/// far below f32's.
pub fn exact_gradient(f: &dyn Fn(DVec3) -> f64, x: DVec3, scale: f64) -> DVec3 {
    let h = 1e-4 * scale.max(1e-12);
    let d = |e: DVec3| {
        (8.0 * (f(x + e * h) - f(x - e * h)) - (f(x + e * (2.0 * h)) - f(x - e * (2.0 * h))))
            / (12.0 * h)
    };
    DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z))
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

/// The finite-difference steps of a walk: fractions of the step length, so that they
/// follow the geometry the walk crosses and not the size of the scene, floored at
/// `fd_floor` of the magnitude of the coordinates (where rounding sets the limit).
#[derive(Clone, Copy)]
pub struct FdSteps<'a> {
    /// The field's forward derivative (`ir::dual::eval`) where the walk has one.
    dual: Option<&'a dyn Fn(DVec3) -> (DVec3, f64)>,
    start: f64,
    gradient: f64,
    curvature: f64,
    floor: f64,
    /// The coordinates' magnitude, |p|∞ + |x − p|.
    scale: f64,
    exact: bool,
}

impl<'a> FdSteps<'a> {
    /// The steps of a walk from `x` to seed `p` under `params`.
    pub fn new(params: &Params, p: DVec3, x: DVec3) -> FdSteps<'a> {
        let scale = p.abs().max_element() + (x - p).length();
        FdSteps {
            dual: None,
            start: params.fd_start(),
            gradient: params.fd_gradient,
            curvature: params.fd_curvature,
            floor: params.fd_floor * scale,
            scale,
            exact: params.exact_gradient,
        }
    }
    /// These steps with the field's forward derivative, read where the gradient is
    /// exact ([`Params::exact_gradient`]).
    pub fn with_dual(self, dual: &'a dyn Fn(DVec3) -> (DVec3, f64)) -> FdSteps<'a> {
        FdSteps {
            dual: Some(dual),
            ..self
        }
    }
    /// The gradient at `x`: exact ([`Params::exact_gradient`]: the forward derivative,
    /// or [`exact_gradient`] of `f` without one), else central differences of step `h`.
    pub fn grad(&self, f: &dyn Fn(DVec3) -> f64, x: DVec3, h: f64) -> DVec3 {
        self.grad_value_or(f, x, h, false).0
    }
    /// The gradient at `x` and f there: exact, else central differences of step `h`
    /// with the mean of their six taps (`logmap::gradient_value`).
    pub fn grad_value(&self, f: &dyn Fn(DVec3) -> f64, x: DVec3, h: f64) -> (DVec3, f64) {
        self.grad_value_or(f, x, h, true)
    }
    fn grad_value_or(
        &self,
        f: &dyn Fn(DVec3) -> f64,
        x: DVec3,
        h: f64,
        value: bool,
    ) -> (DVec3, f64) {
        match (self.exact, self.dual) {
            (true, Some(dual)) => dual(x),
            (true, None) => (
                exact_gradient(f, x, self.scale),
                if value { f(x) } else { 0.0 },
            ),
            (false, _) if value => gradient_value(f, x, h),
            (false, _) => (gradient(f, x, h), 0.0),
        }
    }
    /// The gradient's step for a step of length `s`.
    pub fn gradient(&self, s: f64) -> f64 {
        (self.gradient * s).max(self.floor)
    }
    /// The gradient's step at the walk's start, for a first step of length `s`
    /// ([`Params::fd_start`]).
    pub fn start(&self, s: f64) -> f64 {
        (self.start * s).max(self.floor)
    }
    /// The second difference's step for a step of length `s`.
    pub fn curvature(&self, s: f64) -> f64 {
        (self.curvature * s).max(self.floor)
    }
}

/// The normal curvature along unit tangent `vh` at `x` by the three-point second
/// difference (Eq. 17).
pub fn normal_curvature(f: &dyn Fn(DVec3) -> f64, x: DVec3, vh: DVec3, g: DVec3, h: f64) -> f64 {
    let second = (f(x - vh * h) - 2.0 * f(x) + f(x + vh * h)) / (h * h);
    -second / g.length().max(1e-12)
}
