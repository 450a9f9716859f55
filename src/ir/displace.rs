//! Displacement (§5.2.2 of the Implicit UVs paper, Eq. 56-58, with the supplement's
//! step bound l_h of the notes, Sec. E).
//!
//! `shape.displace(height, scale, band)` is f_h(ξ) = f(ξ) − d(Π_f(ξ)) with
//! d = scale · height, read at the projection Π_f(ξ) = ξ − f ∇f / |∇f|² (Eq. 57) onto
//! the base surface. Eq. 58's band: with ε = max |d|, the field is exact within
//! |f| ≤ τ·ε (τ = `band` > 1) and, beyond it, the base field shifted by the extreme
//! displacement on that side (f − max d outside, f − min d inside), which never
//! overestimates the distance to the displaced surface.
//!
//! **Step bound.** d ∘ Π_f is constant along the base's normals, so its gradient is
//! tangent to the level sets and |∇f_h| = √(|∇f|² + |∇(d∘Π)|²) ≤ √(L² + (k·g)²), where
//! L is the base's Lipschitz bound, g a bound of d's slope per unit of uv (or of
//! surface length, for `position` and atlas distances), computed from the height's
//! expression and the texels of its textures ([`analyze`]), and k = [`STRETCH`] an
//! allowance for the atlas's metric distortion and Π's stretch inside the band. This
//! is the notes' l_h = max √(1 + |∇h|²) for an exact base.
//!
//! **Normals.** The renderer's normals are the tetrahedral differences of the scene
//! field (4 evaluations), which on a displaced shape are the gradient of f_h itself:
//! the "exact gradient by differencing" of Sec. E (Sec. E uses central differences, 6
//! evaluations; the tetrahedral scheme is the 4-evaluation equivalent).

use super::texture::Textures;
use crate::sema::builtins::BuiltinId;
use crate::sema::math::{Jumps, Math};
use crate::sema::{AtlasAttr, AtlasId, FieldExpr, SurfaceInput, Value};
use crate::syntax::ast::{BinaryOp, UnaryOp};
use glam::{DVec2, DVec3};

/// Allowance for the atlas's metric distortion (the log map's angular stretch
/// (r/R)/sin(r/R) is 1.5 at r/R = 1.5 rad) and for Π's stretch inside the band.
pub const STRETCH: f64 = 1.5;

/// A displacement's height and its derived bounds: plain data. What evaluating it on
/// the CPU needs beyond this (atlases, textures) comes in as a [`Heights`].
#[derive(Debug, Clone, PartialEq)]
pub struct Height {
    /// The height field as the scene gives it (a float surface field or a constant).
    pub value: Value,
    pub scale: f64,
    /// τ of Eq. 58.
    pub band: f64,
    /// The range of the displacement d = scale · height.
    pub lo: f64,
    pub hi: f64,
    /// A bound of |∇d| per unit of uv (or of surface length), from [`analyze`].
    pub slope: f64,
    /// The atlas the height reads (at most one; the checker requires it to be on the
    /// displaced shape).
    pub atlas: Option<AtlasId>,
    /// Names the height's WGSL function `height_ID`: the offset where the call ends,
    /// which no other call has (in a method chain such as
    /// `sphere(1).displace(…).shell_map(…)` every call starts at the same offset).
    pub id: usize,
    /// The difference step of ∇f for Π_f: 1e-3 of the base's scale (f32-safe, notes).
    pub grad_step: f64,
    /// 1 for a displacement's height; 2 for a shell map's uv (`height_ID` then returns
    /// a `vec2<f32>`).
    pub dims: u8,
    /// A run-time scale's value ([`Value::Uniform`]): the generated code computes the
    /// scale, and `lo`, `hi` and the band (each proportional to it) from the
    /// parameters' block; `scale`, `lo`, `hi` and `slope` hold their current values
    /// (the node's bounds and Lipschitz bound hold over the range).
    pub run_time_scale: Option<Value>,
}

impl Height {
    pub fn new(
        value: Value,
        scale: f64,
        band: f64,
        bound: Bound,
        id: usize,
        grad_step: f64,
    ) -> Height {
        let atlas = atlas_of(&value);
        Height {
            value,
            scale,
            band,
            lo: scale * bound.lo,
            hi: scale * bound.hi,
            slope: scale * bound.slope,
            atlas,
            id,
            grad_step,
            dims: 1,
            run_time_scale: None,
        }
    }

    /// A shell map's uv field: a vec2 with slope bound `slope` (per unit of surface).
    pub fn uv_field(value: Value, slope: f64, id: usize, grad_step: f64) -> Height {
        let mut h = Height::new(
            value,
            1.0,
            1.0,
            Bound {
                lo: 0.0,
                hi: 0.0,
                slope,
            },
            id,
            grad_step,
        );
        h.dims = 2;
        h
    }

    /// ε of Eq. 58: the largest displacement.
    pub fn epsilon(&self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    /// |f| up to which the exact displaced field is evaluated.
    pub fn band_width(&self) -> f64 {
        self.epsilon() * self.band
    }

    /// The Lipschitz bound of the displaced field over a base of bound `base`.
    pub fn lipschitz(&self, base: f64) -> f64 {
        (base * base + (STRETCH * self.slope).powi(2)).sqrt()
    }

    /// Whether the height is a constant: then no [`Heights`] is needed to evaluate it.
    pub fn is_constant(&self) -> bool {
        matches!(self.value, Value::Float(_))
    }

    /// d at surface point `q` with unit normal `n` (the generated `height_ID`), from
    /// `heights` unless the height is a constant; `None` where `heights` cannot say.
    pub fn displacement(&self, q: DVec3, n: DVec3, heights: &dyn Heights) -> Option<f64> {
        if let Value::Float(h) = self.value {
            return Some(self.scale * h);
        }
        Some(self.scale * heights.scalar(self, q, n)?)
    }

    /// Eq. 58 given the base's distance `f` at ξ and, inside the band, the projection
    /// and normal (computed only when asked for).
    pub fn field(
        &self,
        f: f64,
        project: impl FnOnce() -> (DVec3, DVec3),
        heights: &dyn Heights,
    ) -> f64 {
        let w = self.band_width();
        if f > w {
            return f - self.hi;
        }
        if f < -w {
            return f - self.lo;
        }
        let (q, n) = project();
        match self.displacement(q, n, heights) {
            Some(d) => f - d,
            // Not given: the conservative shift on either side.
            None if f >= 0.0 => f - self.hi,
            None => f - self.lo,
        }
    }
}

/// What the CPU evaluator needs to evaluate heights and shell-map uv that read
/// textures or atlases: the environment of a shape's field, passed as an argument
/// ([`super::eval::Field`]). The CPU reference layer implements it with the scene's
/// prepared atlases and decoded textures; [`NoHeights`] knows none.
pub trait Heights: Send + Sync + std::fmt::Debug {
    /// The unscaled height `h.value` at surface point `q` with unit normal `n` (the
    /// generated `height_ID` divided by the scale), or `None` when this environment
    /// cannot evaluate it.
    fn scalar(&self, h: &Height, q: DVec3, n: DVec3) -> Option<f64>;
    /// A shell map's uv field `h.value` at `q`, or `None` when it cannot be evaluated.
    fn uv(&self, h: &Height, q: DVec3, n: DVec3) -> Option<DVec2>;
}

/// The environment with no atlases and no textures: constant heights are exact;
/// a displacement that reads a texture or an atlas takes the conservative shift of
/// its band on either side (never an overestimate of the distance), and a shell map
/// whose uv reads one has no tiles.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoHeights;

impl Heights for NoHeights {
    fn scalar(&self, _: &Height, _: DVec3, _: DVec3) -> Option<f64> {
        None
    }
    fn uv(&self, _: &Height, _: DVec3, _: DVec3) -> Option<DVec2> {
        None
    }
}

/// Whether a height samples a texture.
pub fn samples_texture(v: &Value) -> bool {
    let Value::Field(e, _) = v else { return false };
    match &**e {
        FieldExpr::Call {
            builtin: BuiltinId::Sample,
            ..
        } => true,
        FieldExpr::Atlas { .. } | FieldExpr::Input(_) | FieldExpr::Param(_) => false,
        FieldExpr::Unary { operand, .. } => samples_texture(operand),
        FieldExpr::Binary { lhs, rhs, .. } => samples_texture(lhs) || samples_texture(rhs),
        FieldExpr::Swizzle { base, .. } => samples_texture(base),
        FieldExpr::Vector(a) | FieldExpr::Call { args: a, .. } => a.iter().any(samples_texture),
    }
}

/// The one atlas a height reads, if any.
fn atlas_of(v: &Value) -> Option<AtlasId> {
    let Value::Field(e, _) = v else { return None };
    match &**e {
        FieldExpr::Atlas { atlas, .. } => Some(*atlas),
        FieldExpr::Input(_) | FieldExpr::Param(_) => None,
        FieldExpr::Unary { operand, .. } => atlas_of(operand),
        FieldExpr::Binary { lhs, rhs, .. } => atlas_of(lhs).or_else(|| atlas_of(rhs)),
        FieldExpr::Swizzle { base, .. } => atlas_of(base),
        FieldExpr::Vector(a) | FieldExpr::Call { args: a, .. } => a.iter().find_map(atlas_of),
    }
}

/// The range and slope of a float height (unscaled).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    pub lo: f64,
    pub hi: f64,
    pub slope: f64,
}

/// Interval and Lipschitz bounds of a value: per component (lo, hi, slope) and a bound
/// of the whole vector's slope (tighter than the components' for uv, which moves
/// isometrically).
#[derive(Debug, Clone)]
struct B {
    c: Vec<(f64, f64, f64)>,
    joint: f64,
}

impl B {
    fn constant(c: &[f64]) -> B {
        B {
            c: c.iter().map(|&x| (x, x, 0.0)).collect(),
            joint: 0.0,
        }
    }

    fn free(n: usize, lo: f64) -> B {
        B {
            c: vec![(lo, f64::INFINITY, 1.0); n],
            joint: 1.0,
        }
    }

    fn from_comps(c: Vec<(f64, f64, f64)>) -> B {
        let joint = c.iter().map(|x| x.2 * x.2).sum::<f64>().sqrt();
        B { c, joint }
    }

    fn widen(&self, n: usize) -> B {
        if self.c.len() == n {
            return self.clone();
        }
        let x = self.c[0];
        B {
            c: vec![x; n],
            joint: x.2 * (n as f64).sqrt(),
        }
    }

    /// A bound of the value's Euclidean length.
    fn norm(&self) -> f64 {
        self.c
            .iter()
            .map(|x| x.0.abs().max(x.1.abs()).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    fn map(&self, f: impl Fn((f64, f64, f64)) -> (f64, f64, f64)) -> B {
        B::from_comps(self.c.iter().map(|&x| f(x)).collect())
    }
}

/// `x * y` where 0 times anything (infinite included) is 0.
fn m(x: f64, y: f64) -> f64 {
    if x == 0.0 || y == 0.0 {
        0.0
    } else {
        x * y
    }
}

fn mul1(a: (f64, f64, f64), b: (f64, f64, f64)) -> (f64, f64, f64) {
    let ps = [m(a.0, b.0), m(a.0, b.1), m(a.1, b.0), m(a.1, b.1)];
    let lo = ps.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = ps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (ma, mb) = (a.0.abs().max(a.1.abs()), b.0.abs().max(b.1.abs()));
    (lo, hi, m(ma, b.2) + m(mb, a.2))
}

fn zip(a: &B, b: &B, f: impl Fn((f64, f64, f64), (f64, f64, f64)) -> (f64, f64, f64)) -> B {
    let n = a.c.len().max(b.c.len());
    let (a, b) = (a.widen(n), b.widen(n));
    B::from_comps(a.c.iter().zip(&b.c).map(|(&x, &y)| f(x, y)).collect())
}

fn add(a: &B, b: &B, sign: f64) -> B {
    let mut out = zip(a, b, |x, y| {
        let (ylo, yhi) = if sign > 0.0 { (y.0, y.1) } else { (-y.1, -y.0) };
        (x.0 + ylo, x.1 + yhi, x.2 + y.2)
    });
    let n = out.c.len();
    out.joint = out.joint.min(a.widen(n).joint + b.widen(n).joint);
    out
}

fn mul(a: &B, b: &B) -> B {
    let mut out = zip(a, b, mul1);
    // A constant factor (a float, or a vector per component) scales the whole vector's
    // slope by at most its largest component.
    for (x, y) in [(a, b), (b, a)] {
        if x.c.iter().all(|c| c.2 == 0.0) {
            let k =
                x.c.iter()
                    .map(|c| c.0.abs().max(c.1.abs()))
                    .fold(0.0, f64::max);
            out.joint = out.joint.min(m(k, y.widen(out.c.len()).joint));
        }
    }
    out
}

fn recip(b: (f64, f64, f64)) -> Result<(f64, f64, f64), String> {
    if b.0 <= 0.0 && b.1 >= 0.0 {
        return Err(String::from("it divides by a value that may be zero"));
    }
    let min = b.0.abs().min(b.1.abs());
    Ok((1.0 / b.1, 1.0 / b.0, b.2 / (min * min)))
}

fn min_max(a: &B, b: &B, max: bool) -> B {
    zip(a, b, |x, y| {
        if max {
            (x.0.max(y.0), x.1.max(y.1), x.2.max(y.2))
        } else {
            (x.0.min(y.0), x.1.min(y.1), x.2.max(y.2))
        }
    })
}

/// Texel statistics of a texture as data (linear): per channel (min, max, slope per
/// unit of uv) of its bilinear interpolation in level 0.
fn texture_bound(
    textures: &Textures,
    path: &str,
    wrap: &str,
) -> Result<[(f64, f64, f64); 4], String> {
    let chain = textures
        .get(path)
        .ok_or_else(|| format!("texture \"{path}\" is not loaded"))?;
    let img = &chain.levels[0];
    let (w, h) = img.dimensions();
    let wraps = wrap != "clamp";
    let mut out = [(f64::INFINITY, f64::NEG_INFINITY, 0.0); 4];
    let (mut sx, mut sy) = ([0.0f64; 4], [0.0f64; 4]);
    for y in 0..h {
        for x in 0..w {
            let p = img.get_pixel(x, y).0;
            let right = (x + 1 < w || wraps).then(|| img.get_pixel((x + 1) % w, y).0);
            let down = (y + 1 < h || wraps).then(|| img.get_pixel(x, (y + 1) % h).0);
            for c in 0..4 {
                let v = p[c] as f64 / 255.0;
                out[c].0 = out[c].0.min(v);
                out[c].1 = out[c].1.max(v);
                if let Some(r) = right {
                    sx[c] = sx[c].max((r[c] as f64 - p[c] as f64).abs() / 255.0);
                }
                if let Some(d) = down {
                    sy[c] = sy[c].max((d[c] as f64 - p[c] as f64).abs() / 255.0);
                }
            }
        }
    }
    for c in 0..4 {
        out[c].2 = ((sx[c] * w as f64).powi(2) + (sy[c] * h as f64).powi(2)).sqrt();
    }
    Ok(out)
}

/// A bound of a vec2 field's slope (a shell map's uv), or why there is none.
pub fn analyze_uv(v: &Value, textures: &Textures) -> Result<f64, String> {
    let b = bound(v, textures)?;
    if !b.joint.is_finite() {
        return Err(String::from("its slope is unbounded"));
    }
    Ok(b.joint)
}

/// The range and slope bound of a float height, or why there is none.
pub fn analyze(v: &Value, textures: &Textures) -> Result<Bound, String> {
    let b = bound(v, textures)?;
    let (lo, hi, slope) = b.c[0];
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(String::from(
            "its range is unbounded (Eq. 58's band needs the largest displacement); clamp it, \
             for example with `clamp(…, 0, 1)`",
        ));
    }
    if !slope.is_finite() {
        return Err(String::from("its slope is unbounded"));
    }
    Ok(Bound { lo, hi, slope })
}

fn bound(v: &Value, textures: &Textures) -> Result<B, String> {
    stacker::maybe_grow(64 * 1024, 1024 * 1024, || bound_inner(v, textures))
}

fn bound_inner(v: &Value, textures: &Textures) -> Result<B, String> {
    let (e, _) = match v {
        Value::Float(x) => return Ok(B::constant(&[*x])),
        Value::Vec(c) => return Ok(B::constant(c)),
        Value::Field(e, t) => (&**e, t),
        other => return Err(format!("a {} has no bounded slope", other.ty())),
    };
    let r = |v: &Value| bound(v, textures);
    Ok(match e {
        FieldExpr::Param(_) => return Err(String::from("a run-time parameter has no bound here")),
        FieldExpr::Input(SurfaceInput::Position) => B::free(3, f64::NEG_INFINITY),
        FieldExpr::Atlas {
            attr: AtlasAttr::Uv,
            ..
        } => B::free(2, f64::NEG_INFINITY),
        FieldExpr::Atlas {
            attr: AtlasAttr::Distance,
            ..
        } => B::free(1, 0.0),
        FieldExpr::Input(SurfaceInput::Normal) | FieldExpr::Atlas { .. } => {
            return Err(String::from(
                "it reads an input whose slope has no bound (only `position`, an atlas's \
                 `uv` and `distance` have one)",
            ))
        }
        FieldExpr::Unary {
            op: UnaryOp::Neg,
            operand,
        } => {
            let mut b = r(operand)?;
            for x in &mut b.c {
                *x = (-x.1, -x.0, x.2);
            }
            b
        }
        FieldExpr::Binary { op, lhs, rhs } => {
            let (a, b) = (r(lhs)?, r(rhs)?);
            match op {
                BinaryOp::Add => add(&a, &b, 1.0),
                BinaryOp::Sub => add(&a, &b, -1.0),
                BinaryOp::Mul => mul(&a, &b),
                BinaryOp::Div => {
                    let inv =
                        B::from_comps(b.c.iter().map(|&x| recip(x)).collect::<Result<_, _>>()?);
                    mul(&a, &inv)
                }
                _ => return Err(format!("`{}` jumps", op.symbol())),
            }
        }
        FieldExpr::Unary { .. } => return Err(String::from("`!` jumps")),
        FieldExpr::Swizzle { base, components } => {
            let b = r(base)?;
            let c: Vec<_> = components
                .iter()
                .map(|&k| b.c.get(k as usize).copied().unwrap_or((0.0, 0.0, 0.0)))
                .collect();
            let mut out = B::from_comps(c);
            out.joint = out.joint.min(b.joint);
            out
        }
        FieldExpr::Vector(args) => {
            let mut c = Vec::new();
            for a in args {
                c.extend(r(a)?.c);
            }
            B::from_comps(c)
        }
        FieldExpr::Call { builtin, args } => call(*builtin, args, textures)?,
    })
}

fn call(builtin: BuiltinId, args: &[Value], textures: &Textures) -> Result<B, String> {
    use BuiltinId as Bi;
    let mut a = Vec::new();
    if builtin != Bi::Sample {
        for v in args {
            a.push(bound(v, textures)?);
        }
    }
    let name = builtin.name();
    // Where a builtin jumps is a fact of its one definition: no slope bound there.
    if Math::of(builtin).is_some_and(|m| m.row().jumps != Jumps::Never) {
        return Err(format!("`{name}` jumps"));
    }
    Ok(match builtin {
        Bi::Sample => {
            let (Some(Value::Texture(node)), Some(Value::Str(wrap))) = (args.first(), args.get(2))
            else {
                return Err(String::from("a texture sample needs an image"));
            };
            let Some(Value::Str(path)) = node.args.first() else {
                return Err(String::from("a texture sample needs an image"));
            };
            let uv = bound(&args[1], textures)?;
            let t = texture_bound(textures, path, wrap)?;
            let lip = uv.joint;
            let mut out = B::from_comps(t.iter().map(|&(lo, hi, s)| (lo, hi, m(s, lip))).collect());
            out.joint = m(t.iter().map(|x| x.2 * x.2).sum::<f64>().sqrt(), lip);
            out
        }
        Bi::Sin | Bi::Cos => a[0].map(|x| (-1.0, 1.0, x.2)),
        Bi::Atan => a[0].map(|x| (x.0.atan(), x.1.atan(), x.2)),
        Bi::Abs => a[0].map(|x| {
            let lo = if x.0 <= 0.0 && x.1 >= 0.0 {
                0.0
            } else {
                x.0.abs().min(x.1.abs())
            };
            (lo, x.0.abs().max(x.1.abs()), x.2)
        }),
        Bi::Exp => a[0].map(|x| (x.0.exp(), x.1.exp(), m(x.1.exp(), x.2))),
        Bi::Radians | Bi::Degrees => {
            let k = if builtin == Bi::Radians {
                std::f64::consts::PI / 180.0
            } else {
                180.0 / std::f64::consts::PI
            };
            mul(&a[0], &B::constant(&[k]))
        }
        Bi::Min => min_max(&a[0], &a[1], false),
        Bi::Max => min_max(&a[0], &a[1], true),
        Bi::Clamp => min_max(&min_max(&a[0], &a[1], true), &a[2], false),
        Bi::Mix => add(&a[0], &mul(&add(&a[1], &a[0], -1.0), &a[2]), 1.0),
        Bi::Smoothstep => {
            // t = clamp((x − e0) / (e1 − e0), 0, 1); t²(3 − 2t) has slope ≤ 1.5 · t's.
            let t = mul(
                &add(&a[2], &a[0], -1.0),
                &B::from_comps(
                    add(&a[1], &a[0], -1.0)
                        .c
                        .iter()
                        .map(|&x| recip(x))
                        .collect::<Result<_, _>>()?,
                ),
            );
            t.map(|x| (0.0, 1.0, 1.5 * x.2))
        }
        Bi::Length => {
            let b = &a[0];
            B::from_comps(vec![(0.0, b.norm(), b.joint)])
        }
        Bi::Distance => {
            let d = add(&a[0], &a[1], -1.0);
            B::from_comps(vec![(0.0, d.norm(), d.joint)])
        }
        Bi::Dot => {
            let p = zip(&a[0], &a[1], mul1);
            let c =
                p.c.iter()
                    .fold((0.0, 0.0, 0.0), |s, x| (s.0 + x.0, s.1 + x.1, s.2 + x.2));
            B::from_comps(vec![c])
        }
        Bi::Checker | Bi::Grid => return Err(format!("`{name}` jumps")),
        _ => return Err(format!("`{name}` has no slope bound here")),
    })
}
