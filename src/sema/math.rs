//! The meaning of the math builtins and of the arithmetic operators, once: one table
//! ([`MATH`]) that gives each math builtin its f64 implementation, its WGSL function
//! and where it jumps. The constant folder ([`super::fold`]), the f64 interpreter of
//! surface fields (`reference::material`) and the WGSL writer (`codegen::field`) all
//! read it, so a folded constant and the same expression run on the GPU mean the same
//! thing; `tests/agreement.rs` checks the three against each other for every row.
//!
//! The semantics are WGSL's, in f64: `sign(0) = 0`; `normalize` of a float is its sign
//! (WGSL's `normalize` takes vectors only); `mix(a, b, t) = a·(1 − t) + b·t`;
//! `step(edge, x)` is 1 where `edge ≤ x`; `%` is `a − b·floor(a / b)`; `==` on vectors
//! holds when every component is equal and `!=` when any differs.

use super::builtins::BuiltinId;
use crate::syntax::ast::BinaryOp;

/// A math builtin (the `Kind::Math` rows of [`super::builtins::BUILTINS`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Math {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Atan2,
    Sqrt,
    Abs,
    Floor,
    Ceil,
    Fract,
    Sign,
    Exp,
    Log,
    Pow,
    Min,
    Max,
    Clamp,
    Mix,
    Smoothstep,
    Step,
    Length,
    Distance,
    Dot,
    Cross,
    Normalize,
    Radians,
    Degrees,
}

/// How a builtin combines its arguments' components.
#[derive(Debug, Clone, Copy)]
pub enum Form {
    /// Per component, one argument.
    Map(fn(f64) -> f64),
    /// Per component, two arguments.
    Zip(fn(f64, f64) -> f64),
    /// Per component, three arguments.
    Zip3(fn(f64, f64, f64) -> f64),
    /// A float from whole vectors (`length`, `distance`, `dot`), a vec3 (`cross`) or a
    /// vector of the argument's size (`normalize`).
    Whole(fn(&[&[f64]]) -> Vec<f64>),
}

/// Where a discontinuous builtin jumps: how far its arguments lie from the nearest
/// jump (in their own units), for comparisons in f32 to leave such points out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Jumps {
    /// Continuous.
    Never,
    /// At integer values of every component of the first argument.
    AtIntegers,
    /// Where a component of the first argument is zero.
    AtZero,
    /// Where a component of the second argument equals the first's (`step`).
    AtEdge,
}

/// One math builtin: its front-end id, its WGSL function and its f64 meaning.
#[derive(Debug, Clone, Copy)]
pub struct MathRow {
    pub op: Math,
    pub id: BuiltinId,
    /// The WGSL builtin function the generated code calls (on arguments widened to the
    /// call's type), but for the special forms of [`Math::wgsl_call`].
    pub wgsl: &'static str,
    pub form: Form,
    pub jumps: Jumps,
}

/// Every math builtin, in [`Math`] order.
pub static MATH: &[MathRow] = &[
    row(
        Math::Sin,
        BuiltinId::Sin,
        "sin",
        Form::Map(f64::sin),
        Jumps::Never,
    ),
    row(
        Math::Cos,
        BuiltinId::Cos,
        "cos",
        Form::Map(f64::cos),
        Jumps::Never,
    ),
    row(
        Math::Tan,
        BuiltinId::Tan,
        "tan",
        Form::Map(f64::tan),
        Jumps::Never,
    ),
    row(
        Math::Asin,
        BuiltinId::Asin,
        "asin",
        Form::Map(f64::asin),
        Jumps::Never,
    ),
    row(
        Math::Acos,
        BuiltinId::Acos,
        "acos",
        Form::Map(f64::acos),
        Jumps::Never,
    ),
    row(
        Math::Atan,
        BuiltinId::Atan,
        "atan",
        Form::Map(f64::atan),
        Jumps::Never,
    ),
    row(
        Math::Atan2,
        BuiltinId::Atan2,
        "atan2",
        Form::Zip(f64::atan2),
        Jumps::Never,
    ),
    row(
        Math::Sqrt,
        BuiltinId::Sqrt,
        "sqrt",
        Form::Map(f64::sqrt),
        Jumps::Never,
    ),
    row(
        Math::Abs,
        BuiltinId::Abs,
        "abs",
        Form::Map(f64::abs),
        Jumps::Never,
    ),
    row(
        Math::Floor,
        BuiltinId::Floor,
        "floor",
        Form::Map(f64::floor),
        Jumps::AtIntegers,
    ),
    row(
        Math::Ceil,
        BuiltinId::Ceil,
        "ceil",
        Form::Map(f64::ceil),
        Jumps::AtIntegers,
    ),
    row(
        Math::Fract,
        BuiltinId::Fract,
        "fract",
        Form::Map(fract),
        Jumps::AtIntegers,
    ),
    row(
        Math::Sign,
        BuiltinId::Sign,
        "sign",
        Form::Map(sign),
        Jumps::AtZero,
    ),
    row(
        Math::Exp,
        BuiltinId::Exp,
        "exp",
        Form::Map(f64::exp),
        Jumps::Never,
    ),
    row(
        Math::Log,
        BuiltinId::Log,
        "log",
        Form::Map(f64::ln),
        Jumps::Never,
    ),
    row(
        Math::Pow,
        BuiltinId::Pow,
        "pow",
        Form::Zip(f64::powf),
        Jumps::Never,
    ),
    row(
        Math::Min,
        BuiltinId::Min,
        "min",
        Form::Zip(f64::min),
        Jumps::Never,
    ),
    row(
        Math::Max,
        BuiltinId::Max,
        "max",
        Form::Zip(f64::max),
        Jumps::Never,
    ),
    row(
        Math::Clamp,
        BuiltinId::Clamp,
        "clamp",
        Form::Zip3(clamp),
        Jumps::Never,
    ),
    row(
        Math::Mix,
        BuiltinId::Mix,
        "mix",
        Form::Zip3(mix),
        Jumps::Never,
    ),
    row(
        Math::Smoothstep,
        BuiltinId::Smoothstep,
        "smoothstep",
        Form::Zip3(smoothstep),
        Jumps::Never,
    ),
    row(
        Math::Step,
        BuiltinId::Step,
        "step",
        Form::Zip(step),
        Jumps::AtEdge,
    ),
    row(
        Math::Length,
        BuiltinId::Length,
        "length",
        Form::Whole(length),
        Jumps::Never,
    ),
    row(
        Math::Distance,
        BuiltinId::Distance,
        "distance",
        Form::Whole(distance),
        Jumps::Never,
    ),
    row(
        Math::Dot,
        BuiltinId::Dot,
        "dot",
        Form::Whole(dot),
        Jumps::Never,
    ),
    row(
        Math::Cross,
        BuiltinId::Cross,
        "cross",
        Form::Whole(cross),
        Jumps::Never,
    ),
    row(
        Math::Normalize,
        BuiltinId::Normalize,
        "normalize",
        Form::Whole(normalize),
        Jumps::AtZero,
    ),
    row(
        Math::Radians,
        BuiltinId::Radians,
        "radians",
        Form::Map(f64::to_radians),
        Jumps::Never,
    ),
    row(
        Math::Degrees,
        BuiltinId::Degrees,
        "degrees",
        Form::Map(f64::to_degrees),
        Jumps::Never,
    ),
];

const fn row(op: Math, id: BuiltinId, wgsl: &'static str, form: Form, jumps: Jumps) -> MathRow {
    MathRow {
        op,
        id,
        wgsl,
        form,
        jumps,
    }
}

/// `x − floor(x)`.
pub fn fract(x: f64) -> f64 {
    x - x.floor()
}

/// WGSL's `sign`: −1, 0 or 1 (0 for ±0; NaN stays NaN).
pub fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        x * 0.0
    }
}

fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    x.max(lo).min(hi)
}

/// WGSL's `mix`: `a·(1 − t) + b·t`.
fn mix(a: f64, b: f64, t: f64) -> f64 {
    a * (1.0 - t) + b * t
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn step(edge: f64, x: f64) -> f64 {
    if edge <= x {
        1.0
    } else {
        0.0
    }
}

fn length(a: &[&[f64]]) -> Vec<f64> {
    vec![a[0].iter().map(|x| x * x).sum::<f64>().sqrt()]
}

fn distance(a: &[&[f64]]) -> Vec<f64> {
    let d: Vec<f64> = a[0].iter().zip(a[1]).map(|(x, y)| x - y).collect();
    length(&[&d])
}

fn dot(a: &[&[f64]]) -> Vec<f64> {
    vec![a[0].iter().zip(a[1]).map(|(x, y)| x * y).sum()]
}

fn cross(a: &[&[f64]]) -> Vec<f64> {
    let (p, q) = (a[0], a[1]);
    vec![
        p[1] * q[2] - p[2] * q[1],
        p[2] * q[0] - p[0] * q[2],
        p[0] * q[1] - p[1] * q[0],
    ]
}

/// A vector over its length; a float's sign (what the generated code writes for it).
fn normalize(a: &[&[f64]]) -> Vec<f64> {
    if a[0].len() == 1 {
        return vec![sign(a[0][0])];
    }
    let len = length(a)[0];
    a[0].iter().map(|x| x / len).collect()
}

impl Math {
    /// The math builtin behind a front-end builtin, if it is one.
    pub fn of(id: BuiltinId) -> Option<Math> {
        MATH.iter().find(|r| r.id == id).map(|r| r.op)
    }

    /// The builtin's row.
    pub fn row(self) -> &'static MathRow {
        &MATH[self as usize]
    }

    pub fn id(self) -> BuiltinId {
        self.row().id
    }

    /// Whether float arguments are widened to the call's vector type first (every
    /// builtin whose parameters share the type `T`), as WGSL needs; `length`,
    /// `normalize` and `cross` take their vectors as they are.
    pub fn widens(self) -> bool {
        !matches!(self, Math::Length | Math::Normalize | Math::Cross)
    }

    /// The value on arguments widened to the call's size (every argument has the
    /// call's number of components, but `cross`'s two vec3 and the whole-vector forms'
    /// own vectors): the result's components.
    pub fn eval(self, args: &[&[f64]]) -> Vec<f64> {
        let x = args[0];
        match self.row().form {
            Form::Map(f) => x.iter().map(|&v| f(v)).collect(),
            Form::Zip(f) => x.iter().zip(args[1]).map(|(&a, &b)| f(a, b)).collect(),
            Form::Zip3(f) => (0..x.len())
                .map(|i| f(x[i], args[1][i], args[2][i]))
                .collect(),
            Form::Whole(f) => f(args),
        }
    }

    /// How far the arguments lie from the nearest jump ([`Jumps`]); infinite for a
    /// continuous builtin.
    pub fn jump(self, args: &[&[f64]]) -> f64 {
        let to_integer = |x: f64| (x - x.round()).abs();
        match self.row().jumps {
            Jumps::Never => f64::INFINITY,
            Jumps::AtIntegers => args[0]
                .iter()
                .map(|&x| to_integer(x))
                .fold(f64::INFINITY, f64::min),
            Jumps::AtZero if self == Math::Normalize && args[0].len() > 1 => f64::INFINITY,
            Jumps::AtZero => args[0]
                .iter()
                .map(|x| x.abs())
                .fold(f64::INFINITY, f64::min),
            Jumps::AtEdge => args[0]
                .iter()
                .zip(args[1])
                .map(|(e, x)| (x - e).abs())
                .fold(f64::INFINITY, f64::min),
        }
    }

    /// The WGSL expression of a call on the already written arguments `args`, whose
    /// type (the call's, after widening) is a float when `float` holds: the row's
    /// function, but `normalize` of a float (its `sign`) and `dot` of floats (a product).
    pub fn wgsl_call(self, args: &[String], float: bool) -> String {
        match self {
            Math::Normalize if float => format!("sign({})", args[0]),
            Math::Dot if float => format!("({} * {})", args[0], args[1]),
            _ => format!("{}({})", self.row().wgsl, args.join(", ")),
        }
    }
}

/// An arithmetic operator on one pair of components (`+ - * / %`); `None` for the
/// others.
pub fn arithmetic(op: BinaryOp, x: f64, y: f64) -> Option<f64> {
    Some(match op {
        BinaryOp::Add => x + y,
        BinaryOp::Sub => x - y,
        BinaryOp::Mul => x * y,
        BinaryOp::Div => x / y,
        BinaryOp::Rem => x - y * (x / y).floor(),
        _ => return None,
    })
}

/// A comparison of two floats (`< <= > >= == !=`); `None` for the others.
pub fn compare(op: BinaryOp, x: f64, y: f64) -> Option<bool> {
    Some(match op {
        BinaryOp::Lt => x < y,
        BinaryOp::Le => x <= y,
        BinaryOp::Gt => x > y,
        BinaryOp::Ge => x >= y,
        BinaryOp::Eq => x == y,
        BinaryOp::Ne => x != y,
        _ => return None,
    })
}

/// `==` and `!=` of two vectors of the same size: every component equal, any differing.
pub fn vectors_equal(op: BinaryOp, a: &[f64], b: &[f64]) -> bool {
    let eq = a.iter().zip(b).all(|(x, y)| x == y);
    if op == BinaryOp::Ne {
        !eq
    } else {
        eq
    }
}

/// The WGSL of a binary operator on the written operands `a` and `b`; `vectors` when
/// `==`/`!=` compares two vectors (WGSL's comparison gives a vector of bools).
pub fn wgsl_binary(op: BinaryOp, a: &str, b: &str, vectors: bool) -> String {
    match op {
        BinaryOp::Rem => format!("({a} - {b} * floor({a} / {b}))"),
        BinaryOp::Eq if vectors => format!("all({a} == {b})"),
        BinaryOp::Ne if vectors => format!("any({a} != {b})"),
        _ => format!("({a} {} {b})", op.symbol()),
    }
}
