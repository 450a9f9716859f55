//! Types and folded values of the scene language.

use super::builtins::{Builtin, BuiltinId, Dflt, PTy};
use super::show::{fmt_num, fmt_vec};
use crate::span::Span;
use crate::syntax::ast::{BinaryOp, UnaryOp};
use std::fmt;
use std::sync::Arc;

/// The type of an expression.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Ty {
    Float,
    /// `vec2`, `vec3` or `vec4`.
    Vec(u8),
    Bool,
    Str,
    /// A signed distance field.
    Shape,
    /// An image binding.
    Texture,
    Atlas,
    Material,
    Camera,
    Light,
    /// A per-point value on the surface (`skin.uv`, `position`, …) of a float, vector or bool type.
    Field(Box<Ty>),
    /// The type of an expression that already has an error; it matches everything
    /// so that one mistake is reported once.
    Error,
}

impl Ty {
    pub fn is_numeric(&self) -> bool {
        matches!(self, Ty::Float | Ty::Vec(_))
    }

    /// The type with any surface-field wrapper removed.
    pub fn base(&self) -> &Ty {
        match self {
            Ty::Field(t) => t,
            t => t,
        }
    }

    pub fn is_field(&self) -> bool {
        matches!(self, Ty::Field(_))
    }

    /// The type as a surface field, when `field` is true.
    pub fn lift(self, field: bool) -> Ty {
        if field && !matches!(self, Ty::Error | Ty::Field(_)) {
            Ty::Field(Box::new(self))
        } else {
            self
        }
    }

    /// Whether a value of this type (for a surface field, of its values' type) fits a
    /// parameter of type `p`: the checker's rule for arguments.
    pub fn fits(&self, p: PTy) -> bool {
        match p {
            PTy::Float => *self == Ty::Float,
            PTy::Vec2 => *self == Ty::Vec(2),
            PTy::Vec3 => *self == Ty::Vec(3),
            PTy::Bool => *self == Ty::Bool,
            PTy::Str => *self == Ty::Str,
            PTy::Shape => *self == Ty::Shape,
            PTy::Texture => *self == Ty::Texture,
            PTy::Material => *self == Ty::Material,
            PTy::FloatOrVec3 => matches!(self, Ty::Float | Ty::Vec(3)),
            PTy::Color => matches!(self, Ty::Float | Ty::Vec(3) | Ty::Vec(4)),
            PTy::Camera => *self == Ty::Camera,
            PTy::Light => *self == Ty::Light,
            PTy::T => self.is_numeric(),
        }
    }
}

impl fmt::Display for Ty {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Ty::Float => f.write_str("float"),
            Ty::Vec(n) => write!(f, "vec{n}"),
            Ty::Bool => f.write_str("bool"),
            Ty::Str => f.write_str("string"),
            Ty::Shape => f.write_str("shape"),
            Ty::Texture => f.write_str("texture"),
            Ty::Atlas => f.write_str("atlas"),
            Ty::Material => f.write_str("material"),
            Ty::Camera => f.write_str("camera"),
            Ty::Light => f.write_str("light"),
            Ty::Field(t) => write!(f, "field<{t}>"),
            Ty::Error => f.write_str("{error}"),
        }
    }
}

crate::id::define_id!(
    /// Index of an atlas in [`super::Program::atlases`].
    AtlasId
);
crate::id::define_id!(
    /// Index of a material in [`super::Program::materials`].
    MaterialId
);

/// A call of a builtin with its arguments bound, in parameter order, defaults filled in.
/// Shapes and textures are trees of these; the IR lowers them. (Cameras and lights
/// are read into [`Camera`] and [`Light`] when they are built.)
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    pub builtin: BuiltinId,
    pub args: Vec<Value>,
    /// The source that produced this node (the call or the operator).
    pub span: Span,
}

/// Built-in surface inputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SurfaceInput {
    Position,
    Normal,
}

/// Per-point attributes an atlas provides (`skin.uv`, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AtlasAttr {
    Uv,
    Distance,
    Status,
    Transport,
    Seed,
}

impl AtlasAttr {
    /// Each attribute with its name, type and documentation.
    pub const ALL: &'static [(AtlasAttr, &'static str, Ty, &'static str)] = &[
        (
            AtlasAttr::Uv,
            "uv",
            Ty::Vec(2),
            "texture coordinates: the log map (Alg. 1) of the geodesic-nearest seed",
        ),
        (
            AtlasAttr::Distance,
            "distance",
            Ty::Float,
            "geodesic distance to the nearest seed",
        ),
        (
            AtlasAttr::Status,
            "status",
            Ty::Float,
            "0 ok, 1 too_far, 2 heuristic_failed, 3 sharp_feature, 4 not_reached",
        ),
        (
            AtlasAttr::Transport,
            "transport",
            Ty::Vec(4),
            "parallel transport from the seed as a unit quaternion (x, y, z, w)",
        ),
        (
            AtlasAttr::Seed,
            "seed",
            Ty::Float,
            "index of the geodesic-nearest seed",
        ),
    ];
}

/// A symbolic per-point expression. It is evaluated per pixel (GPU) or per query (CPU).
#[derive(Debug, Clone, PartialEq)]
pub enum FieldExpr {
    Input(SurfaceInput),
    /// A run-time parameter (`param` item, or `time`): the same at every point, set by
    /// the host. It appears only inside a [`Uniform`].
    Param(ParamRef),
    Atlas {
        atlas: AtlasId,
        attr: AtlasAttr,
    },
    /// A builtin applied to arguments, some of them fields (`sin`, `mix`, `sample`, …).
    Call {
        builtin: BuiltinId,
        args: Vec<Value>,
    },
    /// A vector built from its components (`[x, y, z]` with a field among them).
    Vector(Vec<Value>),
    Unary {
        op: UnaryOp,
        operand: Value,
    },
    Binary {
        op: BinaryOp,
        lhs: Value,
        rhs: Value,
    },
    /// Component selection, 0 = x … 3 = w.
    Swizzle {
        base: Value,
        components: Vec<u8>,
    },
}

/// A run-time parameter as a leaf of an expression: its index in
/// [`super::Program::params`] and its name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamRef {
    pub index: u32,
    pub name: Arc<str>,
}

/// A value computed from run-time parameters: the same at every point of space, set by
/// the host per frame (sliders, `time`). Its expression is generated into the shaders;
/// every compile-time consumer reads `value`, the value at the parameters' current
/// values (their defaults, or what `--param` set), and what must hold for every value
/// reads `range`, an interval per component that holds over the parameters' ranges.
#[derive(Debug, Clone, PartialEq)]
pub struct Uniform {
    /// Over [`FieldExpr::Param`] leaves, constants and math.
    pub expr: Arc<FieldExpr>,
    pub value: Vec<f64>,
    pub range: Vec<(f64, f64)>,
    /// The expression in the source.
    pub span: Span,
}

impl Uniform {
    /// The interval of the whole value (the hull of its components').
    pub fn hull(&self) -> (f64, f64) {
        self.range
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                (a.min(r.0), b.max(r.1))
            })
    }

    /// Whether every component's range is finite.
    pub fn is_bounded(&self) -> bool {
        self.range
            .iter()
            .all(|r| r.0.is_finite() && r.1.is_finite())
    }
}

/// The folded value of an expression. Constants are folded completely; surface
/// fields stay symbolic; scene objects are trees of [`Node`]s.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Float(f64),
    Vec(Vec<f64>),
    Bool(bool),
    Str(String),
    Shape(Arc<Node>),
    Texture(Arc<Node>),
    Camera(Arc<Camera>),
    Light(Arc<Light>),
    Atlas(AtlasId),
    Material(MaterialId),
    /// A surface field with the type of its per-point values.
    Field(Arc<FieldExpr>, Ty),
    /// A float or vector computed from run-time parameters.
    Uniform(Arc<Uniform>),
    Error,
}

impl Value {
    pub fn ty(&self) -> Ty {
        match self {
            Value::Float(_) => Ty::Float,
            Value::Vec(v) => Ty::Vec(v.len() as u8),
            Value::Bool(_) => Ty::Bool,
            Value::Str(_) => Ty::Str,
            Value::Shape(_) => Ty::Shape,
            Value::Texture(_) => Ty::Texture,
            Value::Camera(_) => Ty::Camera,
            Value::Light(_) => Ty::Light,
            Value::Atlas(_) => Ty::Atlas,
            Value::Material(_) => Ty::Material,
            Value::Field(_, t) => Ty::Field(Box::new(t.clone())),
            Value::Uniform(u) if u.value.len() == 1 => Ty::Float,
            Value::Uniform(u) => Ty::Vec(u.value.len() as u8),
            Value::Error => Ty::Error,
        }
    }

    pub fn is_error(&self) -> bool {
        matches!(self, Value::Error)
    }

    /// The atlases a surface field reads (`skin.uv`, …), in index order; empty for a
    /// constant. A normal map takes its tangent frame from its uv's one atlas.
    pub fn atlases(&self) -> std::collections::BTreeSet<AtlasId> {
        fn walk(v: &Value, out: &mut std::collections::BTreeSet<AtlasId>) {
            let Value::Field(e, _) = v else { return };
            stacker::maybe_grow(64 * 1024, 1024 * 1024, || match &**e {
                FieldExpr::Input(_) | FieldExpr::Param(_) => {}
                FieldExpr::Atlas { atlas, .. } => {
                    out.insert(*atlas);
                }
                FieldExpr::Call { args, .. } | FieldExpr::Vector(args) => {
                    args.iter().for_each(|a| walk(a, out))
                }
                FieldExpr::Unary { operand, .. } => walk(operand, out),
                FieldExpr::Binary { lhs, rhs, .. } => {
                    walk(lhs, out);
                    walk(rhs, out);
                }
                FieldExpr::Swizzle { base, .. } => walk(base, out),
            })
        }
        let mut out = std::collections::BTreeSet::new();
        walk(self, &mut out);
        out
    }

    pub fn field(expr: FieldExpr, ty: Ty) -> Value {
        Value::Field(Arc::new(expr), ty)
    }

    /// A float, or a run-time float at its current value.
    pub fn as_float(&self) -> Option<f64> {
        match self {
            Value::Float(x) => Some(*x),
            Value::Uniform(u) if u.value.len() == 1 => Some(u.value[0]),
            _ => None,
        }
    }

    /// A vec3, or a run-time vec3 at its current value.
    pub fn as_vec3(&self) -> Option<[f64; 3]> {
        match self.components() {
            Some(v) if v.len() == 3 && !matches!(self, Value::Float(_)) => Some([v[0], v[1], v[2]]),
            _ => None,
        }
    }

    /// Components of a float or vector: a constant's, or a run-time value's at the
    /// parameters' current values.
    pub fn components(&self) -> Option<&[f64]> {
        match self {
            Value::Float(x) => Some(std::slice::from_ref(x)),
            Value::Vec(v) => Some(v),
            Value::Uniform(u) => Some(&u.value),
            _ => None,
        }
    }

    /// The interval of each component over the parameters' ranges (a point for a
    /// constant).
    pub fn ranges(&self) -> Option<Vec<(f64, f64)>> {
        match self {
            Value::Uniform(u) => Some(u.range.clone()),
            _ => Some(self.components()?.iter().map(|&x| (x, x)).collect()),
        }
    }

    /// The run-time value, if this is one.
    pub fn uniform(&self) -> Option<&Uniform> {
        match self {
            Value::Uniform(u) => Some(u),
            _ => None,
        }
    }

    /// A short rendering of a constant for messages and hovers.
    pub fn display(&self) -> String {
        match self {
            Value::Float(x) => fmt_num(*x),
            Value::Vec(v) => fmt_vec(v),
            Value::Uniform(u) if u.value.len() == 1 => {
                format!("{} (run time)", fmt_num(u.value[0]))
            }
            Value::Uniform(u) => format!("{} (run time)", fmt_vec(&u.value)),
            Value::Bool(b) => b.to_string(),
            Value::Str(s) => format!("{s:?}"),
            Value::Shape(n) | Value::Texture(n) => format!("{}(…)", n.builtin.name()),
            Value::Camera(c) => format!("{}(…)", c.builtin().name()),
            Value::Light(l) => format!("{}(…)", l.builtin().name()),
            other => other.ty().to_string(),
        }
    }
}

impl From<Dflt> for Value {
    /// A table's default as a folded value: the one conversion, used by the checker for
    /// missing arguments and unset settings.
    fn from(d: Dflt) -> Value {
        match d {
            Dflt::F(x) => Value::Float(x),
            Dflt::V(v) => Value::Vec(v.to_vec()),
            Dflt::B(b) => Value::Bool(b),
            Dflt::S(s) => Value::Str(s.to_string()),
        }
    }
}

/// Every parameter's default of a builtin, in order; `None` when some parameter has none.
pub fn default_args(b: &Builtin) -> Option<Vec<Value>> {
    b.params
        .iter()
        .map(|p| p.default.map(Value::from))
        .collect()
}

/// A camera as the scene gives it; [`crate::view::Camera`] resolves it into a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Camera {
    /// `orbit(target, distance, yaw, pitch, fov)`.
    Orbit {
        target: [f64; 3],
        distance: f64,
        yaw: f64,
        pitch: f64,
        fov: f64,
    },
    /// `look_at(eye, target, fov)`.
    LookAt {
        eye: [f64; 3],
        target: [f64; 3],
        fov: f64,
    },
}

/// A light as the scene gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// `sun(direction, color, intensity)`; `direction` points towards the sun, as written.
    Sun {
        direction: [f64; 3],
        color: [f64; 3],
        intensity: f64,
    },
}

/// The bound arguments of a call (in parameter order, checked), read by parameter name.
struct Args<'a> {
    builtin: BuiltinId,
    args: &'a [Value],
}

impl Args<'_> {
    fn get(&self, name: &str) -> Option<&Value> {
        let (i, _) = self.builtin.builtin().param(name)?;
        self.args.get(i)
    }

    fn float(&self, name: &str) -> Option<f64> {
        self.get(name)?.as_float()
    }

    fn vec3(&self, name: &str) -> Option<[f64; 3]> {
        self.get(name)?.as_vec3()
    }
}

impl Camera {
    /// The camera of a checked call of a camera builtin; `None` for any other builtin.
    pub fn from_call(builtin: BuiltinId, args: &[Value]) -> Option<Camera> {
        let a = Args { builtin, args };
        match builtin {
            BuiltinId::Orbit => Some(Camera::Orbit {
                target: a.vec3("target")?,
                distance: a.float("distance")?,
                yaw: a.float("yaw")?,
                pitch: a.float("pitch")?,
                fov: a.float("fov")?,
            }),
            BuiltinId::LookAt => Some(Camera::LookAt {
                eye: a.vec3("eye")?,
                target: a.vec3("target")?,
                fov: a.float("fov")?,
            }),
            _ => None,
        }
    }

    /// The builtin that makes this camera.
    pub fn builtin(&self) -> BuiltinId {
        match self {
            Camera::Orbit { .. } => BuiltinId::Orbit,
            Camera::LookAt { .. } => BuiltinId::LookAt,
        }
    }
}

impl Light {
    /// The light of a checked call of a light builtin; `None` for any other builtin.
    pub fn from_call(builtin: BuiltinId, args: &[Value]) -> Option<Light> {
        let a = Args { builtin, args };
        match builtin {
            BuiltinId::Sun => Some(Light::Sun {
                direction: a.vec3("direction")?,
                color: a.vec3("color")?,
                intensity: a.float("intensity")?,
            }),
            _ => None,
        }
    }

    /// The builtin that makes this light.
    pub fn builtin(&self) -> BuiltinId {
        match self {
            Light::Sun { .. } => BuiltinId::Sun,
        }
    }
}

impl Default for Light {
    /// `sun()`: the sun with the defaults of its parameters in the builtins table.
    fn default() -> Self {
        default_args(BuiltinId::Sun.builtin())
            .and_then(|args| Light::from_call(BuiltinId::Sun, &args))
            .expect("every parameter of `sun` has a default")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sema::builtins::{ATLAS_SETTINGS, BUILTINS, MATERIAL_SETTINGS, RENDER_SETTINGS};

    /// One format for constants: a table's default shows as its folded value does.
    #[test]
    fn a_default_shows_as_its_value_shows() {
        let params = BUILTINS.iter().flat_map(|b| b.params.iter());
        let settings = [ATLAS_SETTINGS, MATERIAL_SETTINGS, RENDER_SETTINGS]
            .into_iter()
            .flatten();
        let defaults: Vec<Dflt> = params
            .filter_map(|p| p.default)
            .chain(settings.filter_map(|s| s.default))
            .collect();
        assert!(defaults.len() > 20);
        for d in defaults {
            assert_eq!(d.display(), Value::from(d).display(), "{d:?}");
        }
    }
}
