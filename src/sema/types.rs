//! Types and folded values of the scene language.

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
/// are read into [`super::Camera`] and [`super::Light`] when they are built.)
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    pub builtin: super::builtins::BuiltinId,
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
    Atlas {
        atlas: AtlasId,
        attr: AtlasAttr,
    },
    /// A builtin applied to arguments, some of them fields (`sin`, `mix`, `sample`, …).
    Call {
        builtin: super::builtins::BuiltinId,
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
    Camera(Arc<super::Camera>),
    Light(Arc<super::Light>),
    Atlas(AtlasId),
    Material(MaterialId),
    /// A surface field with the type of its per-point values.
    Field(Arc<FieldExpr>, Ty),
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
                FieldExpr::Input(_) => {}
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

    pub fn as_float(&self) -> Option<f64> {
        match self {
            Value::Float(x) => Some(*x),
            _ => None,
        }
    }

    pub fn as_vec3(&self) -> Option<[f64; 3]> {
        match self {
            Value::Vec(v) if v.len() == 3 => Some([v[0], v[1], v[2]]),
            _ => None,
        }
    }

    /// Components of a constant float or vector.
    pub fn components(&self) -> Option<&[f64]> {
        match self {
            Value::Float(x) => Some(std::slice::from_ref(x)),
            Value::Vec(v) => Some(v),
            _ => None,
        }
    }

    /// A short rendering of a constant for messages and hovers.
    pub fn display(&self) -> String {
        match self {
            Value::Float(x) => fmt_num(*x),
            Value::Vec(v) => format!(
                "[{}]",
                v.iter().map(|x| fmt_num(*x)).collect::<Vec<_>>().join(", ")
            ),
            Value::Bool(b) => b.to_string(),
            Value::Str(s) => format!("{s:?}"),
            Value::Shape(n) | Value::Texture(n) => format!("{}(…)", n.builtin.name()),
            Value::Camera(c) => format!("{}(…)", c.builtin().name()),
            Value::Light(l) => format!("{}(…)", l.builtin().name()),
            other => other.ty().to_string(),
        }
    }
}

/// Formats a number compactly: integers without a fraction, others with up to 6 significant decimals.
pub fn fmt_num(x: f64) -> String {
    if x.is_finite() && x == x.trunc() && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else if x.is_finite() && (x.abs() >= 1e15 || x.abs() < 1e-6) {
        // Huge and tiny numbers in scientific notation, not 40 digits or "0".
        format!("{x:e}")
    } else {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    }
}
