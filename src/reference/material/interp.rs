//! The interpreter of [`super::MaterialEval`]: per-point values ([`V`]) and one
//! evaluation's state ([`Cx`]), with every operator and builtin the WGSL emitter
//! accepts in a field.

use super::*;
use crate::sema::math::{self, Math};

/// A per-point value: up to four components, or a bool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum V {
    Num([f64; 4], usize),
    Bool(bool),
}

impl V {
    pub(super) fn float(x: f64) -> V {
        V::Num([x, 0.0, 0.0, 0.0], 1)
    }

    pub(super) fn from_slice(c: &[f64]) -> V {
        let mut a = [0.0; 4];
        for (d, s) in a.iter_mut().zip(c) {
            *d = *s;
        }
        V::Num(a, c.len().min(4))
    }

    pub(super) fn comps(&self) -> &[f64] {
        match self {
            V::Num(c, n) => &c[..*n],
            V::Bool(_) => &[],
        }
    }

    pub(super) fn x(&self) -> f64 {
        self.comps().first().copied().unwrap_or(0.0)
    }

    pub(super) fn bool(&self) -> bool {
        matches!(self, V::Bool(true))
    }

    pub(super) fn vec2(&self) -> DVec2 {
        let c = self.widen(2);
        DVec2::new(c.comps()[0], c.comps()[1])
    }

    pub(super) fn vec3(&self) -> DVec3 {
        let c = self.widen(3);
        DVec3::new(c.comps()[0], c.comps()[1], c.comps()[2])
    }

    /// A float broadcast to `n` components (WGSL's `vecN<f32>(x)`); others unchanged.
    pub(super) fn widen(self, n: usize) -> V {
        match self {
            V::Num(c, 1) if n > 1 => V::Num([c[0]; 4], n),
            other => other,
        }
    }

    pub(super) fn map(self, f: impl Fn(f64) -> f64) -> V {
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

    pub(super) fn zip(self, o: V, f: impl Fn(f64, f64) -> f64) -> V {
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

pub(super) fn vec3v(v: DVec3) -> V {
    V::Num([v.x, v.y, v.z, 0.0], 3)
}

/// The state of one evaluation.
pub(super) struct Cx<'e> {
    pub(super) textures: &'e Textures,
    pub(super) atlas: &'e mut dyn FnMut(AtlasId) -> AtlasValues,
    pub(super) samples: Vec<Option<AtlasValues>>,
    pub(super) p: DVec3,
    pub(super) n: DVec3,
    pub(super) footprint: f64,
    pub(super) tangent_u: DVec3,
    pub(super) tangent_v: DVec3,
    /// While a texture's derivatives are evaluated: the displacement of atlas uv and of
    /// `position` (the emitter's `Uses::offset`).
    pub(super) offset: Option<(DVec2, DVec3)>,
    /// Whether textures sampled now hold colour (the field is `color` or `emission`).
    pub(super) srgb: bool,
    pub(super) margin: f64,
}

/// Distance of x from the nearest integer.
pub(super) fn to_integer(x: f64) -> f64 {
    (x - x.round()).abs()
}

impl Cx<'_> {
    pub(super) fn jump(&mut self, distance: f64) {
        if !distance.is_nan() {
            self.margin = self.margin.min(distance);
        }
    }

    pub(super) fn atlas_sample(&mut self, k: AtlasId) -> AtlasValues {
        if let Some(s) = self.samples.get(k.index()).copied().flatten() {
            return s;
        }
        let s = (self.atlas)(k);
        if let Some(slot) = self.samples.get_mut(k.index()) {
            *slot = Some(s);
        }
        s
    }

    pub(super) fn value(&mut self, v: &Value) -> V {
        stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.value_inner(v))
    }

    pub(super) fn value_inner(&mut self, v: &Value) -> V {
        let (expr, ty) = match v {
            Value::Float(x) => return V::float(*x),
            Value::Vec(c) => return V::from_slice(c),
            // A run-time value at the parameters' current values.
            Value::Uniform(u) if u.value.len() == 1 => return V::float(u.value[0]),
            Value::Uniform(u) => return V::from_slice(&u.value),
            Value::Bool(b) => return V::Bool(*b),
            Value::Field(e, ty) => (&**e, ty),
            // Rejected by `MaterialEval::new`.
            _ => return V::float(0.0),
        };
        match expr {
            // Only inside a `Value::Uniform`, whose value is read above.
            FieldExpr::Param(_) => V::float(0.0),
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
    pub(super) fn binary(&mut self, op: BinaryOp, l: V, r: V) -> V {
        use BinaryOp::*;
        let n = l.comps().len().max(r.comps().len());
        let (a, b) = (l.widen(n), r.widen(n));
        match op {
            Or => V::Bool(a.bool() || b.bool()),
            And => V::Bool(a.bool() && b.bool()),
            Add | Sub | Mul | Div => {
                a.zip(b, |x, y| math::arithmetic(op, x, y).unwrap_or(f64::NAN))
            }
            Rem => {
                for (x, y) in a.comps().iter().zip(b.comps()) {
                    self.jump(to_integer(x / y));
                }
                a.zip(b, |x, y| math::arithmetic(op, x, y).unwrap_or(f64::NAN))
            }
            Eq | Ne => {
                if let (V::Bool(x), V::Bool(y)) = (a, b) {
                    return V::Bool((x == y) == (op == Eq));
                }
                for (x, y) in a.comps().iter().zip(b.comps()) {
                    self.jump((x - y).abs());
                }
                // `all(a == b)` / `any(a != b)` for vectors, as the emitter writes it.
                V::Bool(math::vectors_equal(op, a.comps(), b.comps()))
            }
            Lt | Le | Gt | Ge => {
                let (x, y) = (a.x(), b.x());
                self.jump((x - y).abs());
                V::Bool(math::compare(op, x, y) == Some(true))
            }
        }
    }

    pub(super) fn call(&mut self, builtin: BuiltinId, args: &[Value]) -> V {
        use BuiltinId as B;
        if builtin == B::Sample {
            return self.sample(args, 2);
        }
        if builtin == B::SampleNormal {
            return self.sample_normal(args);
        }
        let vals: Vec<V> = args.iter().map(|a| self.value(a)).collect();
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
            _ => match Math::of(builtin) {
                Some(m) => self.math(m, args, &vals),
                // Not surface fields (rejected by `MaterialEval::new`, as by the emitter).
                None => V::float(0.0),
            },
        }
    }

    /// A math builtin by its one definition ([`Math`]), on arguments widened to the
    /// call's type (the first vector argument's, the emitter's `t_ty`), noting how near
    /// its jumps the arguments are.
    pub(super) fn math(&mut self, m: Math, args: &[Value], vals: &[V]) -> V {
        let n = args
            .iter()
            .find_map(|a| match a.ty().base() {
                Ty::Vec(k) => Some(*k as usize),
                _ => None,
            })
            .unwrap_or(1);
        let widened: Vec<V> = vals
            .iter()
            .map(|v| if m.widens() { v.widen(n) } else { *v })
            .collect();
        let comps: Vec<&[f64]> = widened.iter().map(|v| v.comps()).collect();
        self.jump(m.jump(&comps));
        V::from_slice(&m.eval(&comps))
    }

    /// `sample_normal(texture, uv, strength, convention, wrap)`: the texel sampled as
    /// data, in the blended transported frame of the uv's atlas ([`normal_map`]).
    pub(super) fn sample_normal(&mut self, args: &[Value]) -> V {
        let saved = self.srgb;
        self.srgb = false;
        let texel = self.sample(args, 4).vec3();
        self.srgb = saved;
        let strength = args.get(2).map_or(1.0, |s| self.value(s).x());
        let green = match args.get(3) {
            Some(Value::Str(c)) => green_sign(c),
            _ => green_sign("gl"),
        };
        let frame = match args.get(1).map(Value::atlases) {
            Some(a) if a.len() == 1 => a.first().map(|&k| self.atlas_sample(k)),
            _ => None,
        };
        let (t, b) = frame.map_or((DVec3::ZERO, DVec3::ZERO), |s| (s.tangent, s.bitangent));
        vec3v(normal_map(texel, t, b, self.n, strength, green))
    }

    /// `sample(texture, uv, wrap)` (the wrap mode is argument `wrap`): `textureSampleGrad`
    /// with the emitter's analytic derivatives (the uv expression displaced by one
    /// footprint along each tangent).
    pub(super) fn sample(&mut self, args: &[Value], wrap: usize) -> V {
        let zero = V::Num([0.0; 4], 4);
        let (Some(Value::Texture(node)), Some(Value::Str(wrap))) = (args.first(), args.get(wrap))
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

/// Whether the emitter accepts `builtin` in a surface field: the patterns, texture
/// samples and every math builtin ([`Math`]).
pub(super) fn is_field_builtin(builtin: BuiltinId) -> bool {
    use BuiltinId as B;
    matches!(builtin, B::Checker | B::Grid | B::Sample | B::SampleNormal)
        || Math::of(builtin).is_some()
}
