//! The CPU reference (f64) of the scene's materials: an interpreter of the material
//! fields ([`FieldExpr`] trees) that mirrors, case by case, the WGSL that
//! `codegen::emit::field` writes into `scene_material(id, p, n, footprint)`.
//!
//! What it mirrors:
//! - the material ids of `scene_map` (0 the default material, i + 1 `materials[i]`,
//!   anything else the default, as the generated `switch` does) and the defaults of
//!   attributes a material leaves out (the checked program already holds them);
//! - a `color` given as a float (splat to rgb) or a vec4 (its rgb);
//! - `tangent_u`/`tangent_v` of the generated function, and the texture derivatives of
//!   `sample`: its uv expression again with atlas uv displaced by one footprint along u
//!   (then v) and `position` displaced by one footprint along `tangent_u` (`tangent_v`);
//!   the normal and the other atlas attributes are not displaced;
//! - the atlas attributes of the generated `atlas_K(p)` ([`AtlasValues`]), sampled once
//!   per evaluation at `p`, failed statuses included (uv 0, distance 3e38, identity
//!   transport);
//! - every builtin the emitter accepts in a field, with WGSL's conventions where they
//!   differ from the constant folder's (`normalize` of a float is its sign, `==`/`!=`
//!   of vectors are `all(a op b)`, `%` is `a - b * floor(a / b)`), and textures through
//!   [`texture::MipChain::sample_grad`] (sRGB-decoded in `color` and `emission`, linear
//!   in `roughness` and `metallic`, as the emitter picks the texture format).
//!
//! The GPU computes in f32 with constants rounded to f32. Where a field is
//! discontinuous (`floor`, `fract`, `step`, `checker`, comparisons, …) the two may
//! land on different sides of a jump: [`Evaluated::margin`] says how far the point's
//! arguments were from the nearest jump, so that comparisons can leave such points out.

pub mod texture;

pub use texture::{MipChain, Textures, Wrap};

use crate::sema::builtins::BuiltinId;
use crate::sema::{AtlasAttr, AtlasId, FieldExpr, MaterialAttrs, Program, SurfaceInput, Ty, Value};
use crate::syntax::ast::{BinaryOp, UnaryOp};
use crate::uv::{Atlas, Sample};
use glam::{DMat3, DVec2, DVec3, DVec4};

/// A material evaluated at a point: the generated `Material` struct, in f64.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialValue {
    pub color: DVec3,
    pub roughness: f64,
    pub metallic: f64,
    pub emission: DVec3,
}

/// A material value with the distance of its discontinuous arguments from their
/// nearest jump (in each argument's own units; `f64::INFINITY` when nothing jumps).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluated {
    pub value: MaterialValue,
    pub margin: f64,
}

/// What the generated `atlas_K(p)` gives a material (the WGSL `AtlasSample`'s
/// attributes), in the shader's conventions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtlasValues {
    /// Alg. 2's blended uv in the atlas's common uv space; 0 where the sample failed.
    pub uv: DVec2,
    /// Geodesic distance; 3e38 (the shader's "infinite") where the sample failed.
    pub distance: f64,
    /// `Status::code` as a float.
    pub status: f64,
    /// Parallel transport as a unit quaternion (x, y, z, w), by the shader's formula.
    pub transport: DVec4,
    /// The chosen seed (on failure the nearest seed that failed), or -1.
    pub seed: f64,
}

/// The shader's "infinite" distance of a failed sample (`uv_failed`).
const FAILED_DISTANCE: f64 = 3.0e38;

impl AtlasValues {
    /// `uv_failed(UV_TOO_FAR, -1.0)`: what a module without the atlas gives.
    pub const FAILED: AtlasValues = AtlasValues {
        uv: DVec2::ZERO,
        distance: FAILED_DISTANCE,
        status: 1.0,
        transport: DVec4::new(0.0, 0.0, 0.0, 1.0),
        seed: -1.0,
    };

    /// The values of a CPU atlas sample ([`Atlas::sample`]).
    pub fn from_sample(s: &Sample) -> AtlasValues {
        let ok = s.status.code() == 0;
        AtlasValues {
            uv: if ok { s.uv } else { DVec2::ZERO },
            distance: if ok && s.distance.is_finite() {
                s.distance
            } else {
                FAILED_DISTANCE
            },
            status: s.status.code() as f64,
            transport: if ok {
                quaternion(&s.transport)
            } else {
                DVec4::new(0.0, 0.0, 0.0, 1.0)
            },
            seed: s.seed.map_or(-1.0, |i| i as f64),
        }
    }
}

/// `uv_quaternion` of shaders/uv.wgsl (same branches, so the same sign) in f64.
pub fn quaternion(m: &DMat3) -> DVec4 {
    let (c0, c1, c2) = (m.x_axis, m.y_axis, m.z_axis);
    let t = c0.x + c1.y + c2.z;
    let q = if t > 0.0 {
        let s = (t + 1.0).sqrt() * 2.0;
        DVec4::new(
            (c1.z - c2.y) / s,
            (c2.x - c0.z) / s,
            (c0.y - c1.x) / s,
            0.25 * s,
        )
    } else if c0.x > c1.y && c0.x > c2.z {
        let s = (1.0 + c0.x - c1.y - c2.z).sqrt() * 2.0;
        DVec4::new(
            0.25 * s,
            (c1.x + c0.y) / s,
            (c2.x + c0.z) / s,
            (c1.z - c2.y) / s,
        )
    } else if c1.y > c2.z {
        let s = (1.0 + c1.y - c0.x - c2.z).sqrt() * 2.0;
        DVec4::new(
            (c1.x + c0.y) / s,
            0.25 * s,
            (c2.y + c1.z) / s,
            (c2.x - c0.z) / s,
        )
    } else {
        let s = (1.0 + c2.z - c0.x - c1.y).sqrt() * 2.0;
        DVec4::new(
            (c2.x + c0.z) / s,
            (c2.y + c1.z) / s,
            0.25 * s,
            (c0.y - c1.x) / s,
        )
    };
    q.normalize()
}

/// The tangent frame of the generated `scene_material`: (tangent_u, tangent_v).
pub fn tangents(n: DVec3) -> (DVec3, DVec3) {
    let u = if n.z.abs() > 0.9 {
        n.cross(DVec3::X)
    } else {
        n.cross(DVec3::Z)
    }
    .normalize();
    (u, n.cross(u))
}

/// The materials of a checked program, ready to evaluate on the CPU.
pub struct MaterialEval<'a> {
    program: &'a Program,
    atlases: &'a [Option<Atlas>],
    textures: Textures,
    default: MaterialAttrs,
}

impl<'a> MaterialEval<'a> {
    /// The materials of `program` with its prepared atlases (one per atlas of the
    /// program, as `driver::Analysis::atlases` holds them) and its decoded textures.
    /// Fails when a material needs what the WGSL generator would also refuse, or a
    /// texture that `textures` lacks.
    pub fn new(
        program: &'a Program,
        atlases: &'a [Option<Atlas>],
        textures: Textures,
    ) -> Result<MaterialEval<'a>, String> {
        if atlases.len() != program.atlases.len() {
            return Err(format!(
                "{} prepared atlases for {} atlases",
                atlases.len(),
                program.atlases.len()
            ));
        }
        let eval = MaterialEval {
            program,
            atlases,
            textures,
            default: MaterialAttrs::default(),
        };
        for m in &program.materials {
            for v in [
                &m.attrs.color,
                &m.attrs.roughness,
                &m.attrs.metallic,
                &m.attrs.emission,
            ] {
                eval.validate(v)
                    .map_err(|e| format!("material `{}`: {e}", m.name))?;
            }
        }
        Ok(eval)
    }

    /// [`MaterialEval::new`] with the program's textures decoded from the files that
    /// were resolved (inside the allowed folders) when it was checked.
    pub fn load(
        program: &'a Program,
        atlases: &'a [Option<Atlas>],
    ) -> Result<MaterialEval<'a>, String> {
        MaterialEval::new(program, atlases, Textures::load(program)?)
    }

    pub fn textures(&self) -> &Textures {
        &self.textures
    }

    /// The attributes of material `id` as `scene_material` switches on it.
    pub fn attrs(&self, id: u32) -> &MaterialAttrs {
        match (id as usize).checked_sub(1) {
            Some(i) if id <= i32::MAX as u32 && i < self.program.materials.len() => {
                &self.program.materials[i].attrs
            }
            _ => &self.default,
        }
    }

    /// The generated `atlas_K(p)` on the CPU: Alg. 2 of the prepared atlas.
    pub fn atlas_values(&self, atlas: AtlasId, p: DVec3) -> AtlasValues {
        match self.atlases.get(atlas.index()) {
            Some(Some(a)) => AtlasValues::from_sample(&a.sample(p)),
            _ => AtlasValues::FAILED,
        }
    }

    /// `scene_material(id, p, n, footprint)`: material `id` (as `scene_map` gives it)
    /// at surface point `p` with unit normal `n`, for a pixel `footprint` wide.
    pub fn eval(&self, id: u32, p: DVec3, n: DVec3, footprint: f64) -> MaterialValue {
        self.eval_with(id, p, n, footprint, &mut |k| self.atlas_values(k, p))
            .value
    }

    /// [`MaterialEval::eval`] with the atlas attributes given by `atlas` (called at most
    /// once per atlas), e.g. the GPU's own atlas samples, to compare the material
    /// interpreters alone; with the margin of discontinuities.
    pub fn eval_with(
        &self,
        id: u32,
        p: DVec3,
        n: DVec3,
        footprint: f64,
        atlas: &mut dyn FnMut(AtlasId) -> AtlasValues,
    ) -> Evaluated {
        let (tangent_u, tangent_v) = tangents(n);
        let mut cx = Cx {
            textures: &self.textures,
            atlas,
            samples: vec![None; self.atlases.len()],
            p,
            n,
            footprint,
            tangent_u,
            tangent_v,
            offset: None,
            srgb: false,
            margin: f64::INFINITY,
        };
        let m = self.attrs(id);
        cx.srgb = true;
        let c = cx.value(&m.color);
        let color = match c {
            V::Num(c, 1) => DVec3::splat(c[0]),
            V::Num(c, _) => DVec3::new(c[0], c[1], c[2]),
            V::Bool(_) => DVec3::ZERO,
        };
        cx.srgb = false;
        let roughness = cx.value(&m.roughness).x();
        let metallic = cx.value(&m.metallic).x();
        cx.srgb = true;
        let emission = match cx.value(&m.emission) {
            V::Num(c, 1) => DVec3::splat(c[0]),
            V::Num(c, _) => DVec3::new(c[0], c[1], c[2]),
            V::Bool(_) => DVec3::ZERO,
        };
        Evaluated {
            value: MaterialValue {
                color,
                roughness,
                metallic,
                emission,
            },
            margin: cx.margin,
        }
    }

    /// Rejects what `codegen::emit::field` rejects, and textures without an image.
    fn validate(&self, v: &Value) -> Result<(), String> {
        match v {
            Value::Float(_) | Value::Vec(_) | Value::Bool(_) => Ok(()),
            Value::Field(e, _) => match &**e {
                FieldExpr::Input(_) => Ok(()),
                FieldExpr::Atlas { atlas, .. } if atlas.index() < self.atlases.len() => Ok(()),
                FieldExpr::Atlas { .. } => Err(String::from("an atlas outside the program")),
                FieldExpr::Unary { operand, .. } => self.validate(operand),
                FieldExpr::Binary { lhs, rhs, .. } => {
                    self.validate(lhs)?;
                    self.validate(rhs)
                }
                FieldExpr::Swizzle { base, .. } => self.validate(base),
                FieldExpr::Vector(args) => args.iter().try_for_each(|a| self.validate(a)),
                FieldExpr::Call {
                    builtin: BuiltinId::Sample,
                    args,
                } => {
                    let (Some(Value::Texture(node)), Some(Value::Str(_))) =
                        (args.first(), args.get(2))
                    else {
                        return Err(String::from(
                            "a texture sample needs an image and a wrap mode",
                        ));
                    };
                    let Some(Value::Str(path)) = node.args.first() else {
                        return Err(String::from("a texture sample needs an image"));
                    };
                    if self.textures.get(path).is_none() {
                        return Err(format!("no decoded image for texture \"{path}\""));
                    }
                    self.validate(&args[1])
                }
                FieldExpr::Call { builtin, args } => {
                    if !is_field_builtin(*builtin) {
                        return Err(format!("`{}` is not a surface field", builtin.name()));
                    }
                    args.iter().try_for_each(|a| self.validate(a))
                }
            },
            other => Err(format!("a {} cannot be used per point", other.ty())),
        }
    }
}

/// A per-point value: up to four components, or a bool.
#[derive(Debug, Clone, Copy, PartialEq)]
enum V {
    Num([f64; 4], usize),
    Bool(bool),
}

impl V {
    fn float(x: f64) -> V {
        V::Num([x, 0.0, 0.0, 0.0], 1)
    }

    fn from_slice(c: &[f64]) -> V {
        let mut a = [0.0; 4];
        for (d, s) in a.iter_mut().zip(c) {
            *d = *s;
        }
        V::Num(a, c.len().min(4))
    }

    fn comps(&self) -> &[f64] {
        match self {
            V::Num(c, n) => &c[..*n],
            V::Bool(_) => &[],
        }
    }

    fn x(&self) -> f64 {
        self.comps().first().copied().unwrap_or(0.0)
    }

    fn bool(&self) -> bool {
        matches!(self, V::Bool(true))
    }

    fn vec2(&self) -> DVec2 {
        let c = self.widen(2);
        DVec2::new(c.comps()[0], c.comps()[1])
    }

    fn vec3(&self) -> DVec3 {
        let c = self.widen(3);
        DVec3::new(c.comps()[0], c.comps()[1], c.comps()[2])
    }

    /// A float broadcast to `n` components (WGSL's `vecN<f32>(x)`); others unchanged.
    fn widen(self, n: usize) -> V {
        match self {
            V::Num(c, 1) if n > 1 => V::Num([c[0]; 4], n),
            other => other,
        }
    }

    fn map(self, f: impl Fn(f64) -> f64) -> V {
        match self {
            V::Num(mut c, n) => {
                for x in &mut c[..n] {
                    *x = f(*x);
                }
                V::Num(c, n)
            }
            b => b,
        }
    }

    fn zip(self, o: V, f: impl Fn(f64, f64) -> f64) -> V {
        match (self, o) {
            (V::Num(mut a, n), V::Num(b, _)) => {
                for i in 0..n {
                    a[i] = f(a[i], b[i]);
                }
                V::Num(a, n)
            }
            (a, _) => a,
        }
    }
}

fn vec3v(v: DVec3) -> V {
    V::Num([v.x, v.y, v.z, 0.0], 3)
}

/// The state of one evaluation.
struct Cx<'e> {
    textures: &'e Textures,
    atlas: &'e mut dyn FnMut(AtlasId) -> AtlasValues,
    samples: Vec<Option<AtlasValues>>,
    p: DVec3,
    n: DVec3,
    footprint: f64,
    tangent_u: DVec3,
    tangent_v: DVec3,
    /// While a texture's derivatives are evaluated: the displacement of atlas uv and of
    /// `position` (the emitter's `Uses::offset`).
    offset: Option<(DVec2, DVec3)>,
    /// Whether textures sampled now hold colour (the field is `color` or `emission`).
    srgb: bool,
    margin: f64,
}

/// Distance of x from the nearest integer.
fn to_integer(x: f64) -> f64 {
    (x - x.round()).abs()
}

impl Cx<'_> {
    fn jump(&mut self, distance: f64) {
        if !distance.is_nan() {
            self.margin = self.margin.min(distance);
        }
    }

    fn atlas_sample(&mut self, k: AtlasId) -> AtlasValues {
        if let Some(s) = self.samples.get(k.index()).copied().flatten() {
            return s;
        }
        let s = (self.atlas)(k);
        if let Some(slot) = self.samples.get_mut(k.index()) {
            *slot = Some(s);
        }
        s
    }

    fn value(&mut self, v: &Value) -> V {
        stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.value_inner(v))
    }

    fn value_inner(&mut self, v: &Value) -> V {
        let (expr, ty) = match v {
            Value::Float(x) => return V::float(*x),
            Value::Vec(c) => return V::from_slice(c),
            Value::Bool(b) => return V::Bool(*b),
            Value::Field(e, ty) => (&**e, ty),
            // Rejected by `MaterialEval::new`.
            _ => return V::float(0.0),
        };
        match expr {
            FieldExpr::Input(SurfaceInput::Position) => {
                vec3v(self.p + self.offset.map_or(DVec3::ZERO, |o| o.1))
            }
            FieldExpr::Input(SurfaceInput::Normal) => vec3v(self.n),
            FieldExpr::Atlas { atlas, attr } => {
                let s = self.atlas_sample(*atlas);
                match attr {
                    AtlasAttr::Uv => {
                        let uv = s.uv + self.offset.map_or(DVec2::ZERO, |o| o.0);
                        V::from_slice(&[uv.x, uv.y])
                    }
                    AtlasAttr::Distance => V::float(s.distance),
                    AtlasAttr::Status => V::float(s.status),
                    AtlasAttr::Transport => V::from_slice(&s.transport.to_array()),
                    AtlasAttr::Seed => V::float(s.seed),
                }
            }
            FieldExpr::Unary { op, operand } => {
                let o = self.value(operand);
                match (op, o) {
                    (UnaryOp::Neg, o) => o.map(|x| -x),
                    (UnaryOp::Not, V::Bool(b)) => V::Bool(!b),
                    (UnaryOp::Not, o) => o,
                }
            }
            FieldExpr::Binary { op, lhs, rhs } => {
                let (l, r) = (self.value(lhs), self.value(rhs));
                self.binary(*op, l, r)
            }
            FieldExpr::Swizzle { base, components } => {
                let b = self.value(base);
                let c: Vec<f64> = components
                    .iter()
                    .map(|&k| b.comps().get(k as usize).copied().unwrap_or(0.0))
                    .collect();
                V::from_slice(&c)
            }
            FieldExpr::Vector(args) => {
                let mut c = Vec::with_capacity(4);
                for a in args {
                    c.extend_from_slice(self.value(a).comps());
                }
                match ty {
                    Ty::Vec(n) if c.len() == 1 => V::float(c[0]).widen(*n as usize),
                    _ => V::from_slice(&c),
                }
            }
            FieldExpr::Call { builtin, args } => self.call(*builtin, args),
        }
    }

    /// `binary` of the emitter: floats widened to the vector operand's size.
    fn binary(&mut self, op: BinaryOp, l: V, r: V) -> V {
        use BinaryOp::*;
        let n = l.comps().len().max(r.comps().len());
        let (a, b) = (l.widen(n), r.widen(n));
        match op {
            Or => V::Bool(a.bool() || b.bool()),
            And => V::Bool(a.bool() && b.bool()),
            Add => a.zip(b, |x, y| x + y),
            Sub => a.zip(b, |x, y| x - y),
            Mul => a.zip(b, |x, y| x * y),
            Div => a.zip(b, |x, y| x / y),
            Rem => {
                for (x, y) in a.comps().iter().zip(b.comps()) {
                    self.jump(to_integer(x / y));
                }
                a.zip(b, |x, y| x - y * (x / y).floor())
            }
            Eq | Ne => {
                if let (V::Bool(x), V::Bool(y)) = (a, b) {
                    return V::Bool((x == y) == (op == Eq));
                }
                for (x, y) in a.comps().iter().zip(b.comps()) {
                    self.jump((x - y).abs());
                }
                // `all(a == b)` / `all(a != b)` for vectors, as the emitter writes it.
                V::Bool(
                    a.comps()
                        .iter()
                        .zip(b.comps())
                        .all(|(x, y)| (x == y) == (op == Eq)),
                )
            }
            Lt | Le | Gt | Ge => {
                let (x, y) = (a.x(), b.x());
                self.jump((x - y).abs());
                V::Bool(match op {
                    Lt => x < y,
                    Le => x <= y,
                    Gt => x > y,
                    _ => x >= y,
                })
            }
        }
    }

    fn call(&mut self, builtin: BuiltinId, args: &[Value]) -> V {
        use BuiltinId as B;
        if builtin == B::Sample {
            return self.sample(args);
        }
        let vals: Vec<V> = args.iter().map(|a| self.value(a)).collect();
        // The call's type: the first vector argument's (the emitter's `t_ty`).
        let n = args
            .iter()
            .find_map(|a| match a.ty().base() {
                Ty::Vec(k) => Some(*k as usize),
                _ => None,
            })
            .unwrap_or(1);
        let arg = |i: usize| vals.get(i).copied().unwrap_or(V::float(0.0));
        match builtin {
            B::Checker => {
                let q = arg(0).vec2() * arg(1).x();
                self.jump(to_integer(q.x).min(to_integer(q.y)));
                let c = q.floor();
                V::float((c.x + c.y).abs() % 2.0)
            }
            B::Grid => {
                let width = arg(2).x();
                let q = arg(0).vec2() * arg(1).x() + DVec2::splat(width * 0.5);
                let f = q - q.floor();
                for (qi, fi) in [(q.x, f.x), (q.y, f.y)] {
                    self.jump(to_integer(qi).min((fi - width).abs()));
                }
                V::float(if f.x < width || f.y < width { 1.0 } else { 0.0 })
            }
            B::Cross => vec3v(arg(0).vec3().cross(arg(1).vec3())),
            B::Normalize if n == 1 => {
                let x = arg(0).x();
                self.jump(x.abs());
                V::float(wgsl_sign(x))
            }
            B::Normalize => {
                let len = arg(0).comps().iter().map(|x| x * x).sum::<f64>().sqrt();
                arg(0).map(|x| x / len)
            }
            B::Length => V::float(arg(0).comps().iter().map(|x| x * x).sum::<f64>().sqrt()),
            B::Dot if n == 1 => V::float(arg(0).x() * arg(1).x()),
            _ => {
                let widened: Vec<V> = vals.iter().map(|v| v.widen(n)).collect();
                self.math(builtin, &widened)
            }
        }
    }

    /// The builtins the emitter writes as the WGSL builtin of the same name, on
    /// arguments widened to the call's type.
    fn math(&mut self, builtin: BuiltinId, a: &[V]) -> V {
        use BuiltinId as B;
        let arg = |i: usize| a.get(i).copied().unwrap_or(V::float(0.0));
        let x = arg(0);
        match builtin {
            B::Sin => x.map(f64::sin),
            B::Cos => x.map(f64::cos),
            B::Tan => x.map(f64::tan),
            B::Asin => x.map(f64::asin),
            B::Acos => x.map(f64::acos),
            B::Atan => x.map(f64::atan),
            B::Atan2 => x.zip(arg(1), f64::atan2),
            B::Sqrt => x.map(f64::sqrt),
            B::Abs => x.map(f64::abs),
            B::Floor | B::Ceil | B::Fract => {
                for c in x.comps() {
                    self.jump(to_integer(*c));
                }
                x.map(match builtin {
                    B::Floor => f64::floor,
                    B::Ceil => f64::ceil,
                    _ => |v: f64| v - v.floor(),
                })
            }
            B::Sign => {
                for c in x.comps() {
                    self.jump(c.abs());
                }
                x.map(wgsl_sign)
            }
            B::Exp => x.map(f64::exp),
            B::Log => x.map(f64::ln),
            B::Pow => x.zip(arg(1), f64::powf),
            B::Min => x.zip(arg(1), f64::min),
            B::Max => x.zip(arg(1), f64::max),
            B::Clamp => x.zip(arg(1), f64::max).zip(arg(2), f64::min),
            B::Mix => {
                let t = arg(2);
                let one_minus = t.map(|t| 1.0 - t);
                x.zip(one_minus, |a, w| a * w)
                    .zip(arg(1).zip(t, |b, t| b * t), |p, q| p + q)
            }
            B::Smoothstep => {
                let (lo, hi) = (x, arg(1));
                let mut out = arg(2);
                if let V::Num(c, k) = &mut out {
                    for ((v, l), h) in c[..*k].iter_mut().zip(lo.comps()).zip(hi.comps()) {
                        let t = ((*v - l) / (h - l)).clamp(0.0, 1.0);
                        *v = t * t * (3.0 - 2.0 * t);
                    }
                }
                out
            }
            B::Step => {
                for (e, v) in x.comps().iter().zip(arg(1).comps()) {
                    self.jump((v - e).abs());
                }
                x.zip(arg(1), |e, v| if e <= v { 1.0 } else { 0.0 })
            }
            B::Distance => V::float(
                x.comps()
                    .iter()
                    .zip(arg(1).comps())
                    .map(|(p, q)| (p - q) * (p - q))
                    .sum::<f64>()
                    .sqrt(),
            ),
            B::Dot => V::float(
                x.comps()
                    .iter()
                    .zip(arg(1).comps())
                    .map(|(p, q)| p * q)
                    .sum(),
            ),
            B::Radians => x.map(f64::to_radians),
            B::Degrees => x.map(f64::to_degrees),
            // Handled by `call`, or not surface fields (rejected by `MaterialEval::new`,
            // as by the emitter).
            B::Checker
            | B::Grid
            | B::Sample
            | B::Cross
            | B::Normalize
            | B::Length
            | B::Sphere
            | B::Box
            | B::RoundBox
            | B::BoxFrame
            | B::Torus
            | B::Capsule
            | B::Cylinder
            | B::Cone
            | B::CappedCone
            | B::Plane
            | B::Ellipsoid
            | B::Octahedron
            | B::HexPrism
            | B::TriPrism
            | B::Pyramid
            | B::Link
            | B::Union
            | B::Intersection
            | B::Difference
            | B::SmoothUnion
            | B::SmoothIntersection
            | B::SmoothDifference
            | B::Translate
            | B::Rotate
            | B::RotateX
            | B::RotateY
            | B::RotateZ
            | B::Scale
            | B::Paint
            | B::Twist
            | B::Bend
            | B::Repeat
            | B::Mirror
            | B::Elongate
            | B::Round
            | B::Shell
            | B::Image
            | B::Orbit
            | B::LookAt
            | B::Sun => V::float(0.0),
        }
    }

    /// `sample(texture, uv, wrap)`: `textureSampleGrad` with the emitter's analytic
    /// derivatives (the uv expression displaced by one footprint along each tangent).
    fn sample(&mut self, args: &[Value]) -> V {
        let zero = V::Num([0.0; 4], 4);
        let (Some(Value::Texture(node)), Some(Value::Str(wrap))) = (args.first(), args.get(2))
        else {
            return zero;
        };
        let Some(Value::Str(path)) = node.args.first() else {
            return zero;
        };
        let uv = self.value(&args[1]).vec2();
        let saved = self.offset.take();
        let f = self.footprint;
        self.offset = Some((DVec2::new(f, 0.0), self.tangent_u * f));
        let ux = self.value(&args[1]).vec2();
        self.offset = Some((DVec2::new(0.0, f), self.tangent_v * f));
        let uy = self.value(&args[1]).vec2();
        self.offset = saved;
        let Some(chain) = self.textures.get(path) else {
            return zero;
        };
        let c = chain.sample_grad(uv, ux - uv, uy - uv, Wrap::parse(wrap), self.srgb);
        V::from_slice(&c.to_array())
    }
}

/// WGSL's `sign`: 0 at 0.
fn wgsl_sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Whether the emitter accepts `builtin` in a surface field. Exhaustive: a new builtin
/// must be sorted here (and in [`Cx::math`]) before this compiles.
fn is_field_builtin(builtin: BuiltinId) -> bool {
    use BuiltinId as B;
    match builtin {
        B::Checker
        | B::Grid
        | B::Sample
        | B::Cross
        | B::Normalize
        | B::Length
        | B::Dot
        | B::Sin
        | B::Cos
        | B::Tan
        | B::Asin
        | B::Acos
        | B::Atan
        | B::Atan2
        | B::Sqrt
        | B::Abs
        | B::Floor
        | B::Ceil
        | B::Fract
        | B::Sign
        | B::Exp
        | B::Log
        | B::Pow
        | B::Min
        | B::Max
        | B::Clamp
        | B::Mix
        | B::Smoothstep
        | B::Step
        | B::Distance
        | B::Radians
        | B::Degrees => true,
        B::Sphere
        | B::Box
        | B::RoundBox
        | B::BoxFrame
        | B::Torus
        | B::Capsule
        | B::Cylinder
        | B::Cone
        | B::CappedCone
        | B::Plane
        | B::Ellipsoid
        | B::Octahedron
        | B::HexPrism
        | B::TriPrism
        | B::Pyramid
        | B::Link
        | B::Union
        | B::Intersection
        | B::Difference
        | B::SmoothUnion
        | B::SmoothIntersection
        | B::SmoothDifference
        | B::Translate
        | B::Rotate
        | B::RotateX
        | B::RotateY
        | B::RotateZ
        | B::Scale
        | B::Paint
        | B::Twist
        | B::Bend
        | B::Repeat
        | B::Mirror
        | B::Elongate
        | B::Round
        | B::Shell
        | B::Image
        | B::Orbit
        | B::LookAt
        | B::Sun => false,
    }
}
