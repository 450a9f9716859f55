//! Constant folding: operators and math builtins on constant floats and vectors.

use super::builtins::BuiltinId;
use super::types::{Ty, Value};
use crate::syntax::ast::{BinaryOp, UnaryOp};

/// The result type of a binary operator on two (non-field) types, or why it does not apply.
pub fn binary_type(op: BinaryOp, l: &Ty, r: &Ty) -> Result<Ty, String> {
    use BinaryOp::*;
    let what = || format!("`{}` cannot be applied to {l} and {r}", op.symbol());
    match (op, l, r) {
        (_, Ty::Error, _) | (_, _, Ty::Error) => Ok(Ty::Error),
        (Or | And | Sub, Ty::Shape, Ty::Shape) => Ok(Ty::Shape),
        (Or | And, Ty::Bool, Ty::Bool) => Ok(Ty::Bool),
        (Eq | Ne, Ty::Bool, Ty::Bool) => Ok(Ty::Bool),
        (Lt | Le | Gt | Ge, Ty::Float, Ty::Float) => Ok(Ty::Bool),
        (Eq | Ne | Add | Sub | Mul | Div | Rem, a, b) if a.is_numeric() && b.is_numeric() => {
            let ty = match (a, b) {
                (Ty::Vec(n), Ty::Vec(m)) if n != m => {
                    return Err(format!(
                        "`{}` needs vectors of the same size, found {l} and {r}",
                        op.symbol()
                    ))
                }
                (Ty::Vec(n), _) | (_, Ty::Vec(n)) => Ty::Vec(*n),
                _ => Ty::Float,
            };
            Ok(if matches!(op, Eq | Ne) { Ty::Bool } else { ty })
        }
        _ => Err(what()),
    }
}

fn broadcast(a: &[f64], b: &[f64], f: impl Fn(f64, f64) -> f64) -> Value {
    let n = a.len().max(b.len());
    let get = |v: &[f64], i: usize| if v.len() == 1 { v[0] } else { v[i] };
    let out: Vec<f64> = (0..n).map(|i| f(get(a, i), get(b, i))).collect();
    if n == 1 {
        Value::Float(out[0])
    } else {
        Value::Vec(out)
    }
}

/// Folds a binary operator on constants whose types [`binary_type`] accepted.
pub fn binary(op: BinaryOp, l: &Value, r: &Value) -> Value {
    use BinaryOp::*;
    match (l, r) {
        (Value::Bool(a), Value::Bool(b)) => match op {
            Or => Value::Bool(*a || *b),
            And => Value::Bool(*a && *b),
            Eq => Value::Bool(a == b),
            Ne => Value::Bool(a != b),
            _ => Value::Error,
        },
        _ => match (l.components(), r.components()) {
            (Some(a), Some(b)) => match op {
                Add => broadcast(a, b, |x, y| x + y),
                Sub => broadcast(a, b, |x, y| x - y),
                Mul => broadcast(a, b, |x, y| x * y),
                Div => broadcast(a, b, |x, y| x / y),
                Rem => broadcast(a, b, |x, y| x - y * (x / y).floor()),
                Lt => Value::Bool(a[0] < b[0]),
                Le => Value::Bool(a[0] <= b[0]),
                Gt => Value::Bool(a[0] > b[0]),
                Ge => Value::Bool(a[0] >= b[0]),
                Eq | Ne => {
                    let n = a.len().max(b.len());
                    let get = |v: &[f64], i: usize| if v.len() == 1 { v[0] } else { v[i] };
                    let eq = (0..n).all(|i| get(a, i) == get(b, i));
                    Value::Bool(if op == Eq { eq } else { !eq })
                }
                Or | And => Value::Error,
            },
            _ => Value::Error,
        },
    }
}

pub fn unary(op: UnaryOp, v: &Value) -> Value {
    match (op, v) {
        (UnaryOp::Not, Value::Bool(b)) => Value::Bool(!b),
        (UnaryOp::Neg, Value::Float(x)) => Value::Float(-x),
        (UnaryOp::Neg, Value::Vec(v)) => Value::Vec(v.iter().map(|x| -x).collect()),
        _ => Value::Error,
    }
}

fn map1(x: &[f64], f: impl Fn(f64) -> f64) -> Vec<f64> {
    x.iter().map(|v| f(*v)).collect()
}

fn pack(v: Vec<f64>) -> Value {
    if v.len() == 1 {
        Value::Float(v[0])
    } else {
        Value::Vec(v)
    }
}

/// Folds a math builtin on constant arguments (already type-checked; `T` arguments may be
/// floats that broadcast to the call's vector size `n`).
pub fn math(builtin: BuiltinId, args: &[Value], n: usize) -> Value {
    use BuiltinId as B;
    let comps: Vec<Vec<f64>> = args
        .iter()
        .map(|a| match a.components() {
            Some(c) if c.len() == 1 && n > 1 => vec![c[0]; n],
            Some(c) => c.to_vec(),
            None => Vec::new(),
        })
        .collect();
    if comps.iter().any(|c| c.is_empty()) {
        return Value::Error;
    }
    let zip2 = |f: fn(f64, f64) -> f64| {
        pack(
            comps[0]
                .iter()
                .zip(&comps[1])
                .map(|(a, b)| f(*a, *b))
                .collect(),
        )
    };
    let x = &comps[0];
    match builtin {
        B::Sin => pack(map1(x, f64::sin)),
        B::Cos => pack(map1(x, f64::cos)),
        B::Tan => pack(map1(x, f64::tan)),
        B::Asin => pack(map1(x, f64::asin)),
        B::Acos => pack(map1(x, f64::acos)),
        B::Atan => pack(map1(x, f64::atan)),
        B::Atan2 => zip2(f64::atan2),
        B::Sqrt => pack(map1(x, f64::sqrt)),
        B::Abs => pack(map1(x, f64::abs)),
        B::Floor => pack(map1(x, f64::floor)),
        B::Ceil => pack(map1(x, f64::ceil)),
        B::Fract => pack(map1(x, |v| v - v.floor())),
        B::Sign => pack(map1(x, |v| {
            if v > 0.0 {
                1.0
            } else if v < 0.0 {
                -1.0
            } else {
                0.0
            }
        })),
        B::Exp => pack(map1(x, f64::exp)),
        B::Log => pack(map1(x, f64::ln)),
        B::Pow => zip2(f64::powf),
        B::Min => zip2(f64::min),
        B::Max => zip2(f64::max),
        B::Step => zip2(|e, v| if v < e { 0.0 } else { 1.0 }),
        B::Radians => pack(map1(x, f64::to_radians)),
        B::Degrees => pack(map1(x, f64::to_degrees)),
        B::Clamp => pack(
            (0..x.len())
                .map(|i| x[i].max(comps[1][i]).min(comps[2][i]))
                .collect(),
        ),
        B::Mix => pack(
            (0..x.len())
                .map(|i| x[i] + (comps[1][i] - x[i]) * comps[2][i])
                .collect(),
        ),
        B::Smoothstep => pack(
            (0..comps[2].len())
                .map(|i| {
                    let t = ((comps[2][i] - x[i]) / (comps[1][i] - x[i])).clamp(0.0, 1.0);
                    t * t * (3.0 - 2.0 * t)
                })
                .collect(),
        ),
        B::Length => Value::Float(x.iter().map(|v| v * v).sum::<f64>().sqrt()),
        B::Distance => Value::Float(
            x.iter()
                .zip(&comps[1])
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt(),
        ),
        B::Dot => Value::Float(x.iter().zip(&comps[1]).map(|(a, b)| a * b).sum()),
        B::Normalize => {
            let len = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            pack(map1(x, |v| v / len))
        }
        B::Cross => {
            let (a, b) = (x, &comps[1]);
            Value::Vec(vec![
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ])
        }
        // Not math: shapes, textures and render settings are never folded.
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
        | B::Displace
        | B::ShellMap
        | B::Twist
        | B::Bend
        | B::Repeat
        | B::Mirror
        | B::Elongate
        | B::Round
        | B::Shell
        | B::Image
        | B::Sample
        | B::SampleNormal
        | B::Checker
        | B::Grid
        | B::Orbit
        | B::LookAt
        | B::Sun => Value::Error,
    }
}

/// Whether every component of a constant is finite (non-constants count as finite).
/// Whether every component is a finite number that single precision can hold (the
/// generated shaders are f32: a constant beyond ±3.4e38 would become infinite there).
pub fn is_finite(v: &Value) -> bool {
    v.components().is_none_or(|c| {
        c.iter()
            .all(|x| x.is_finite() && x.abs() <= f32::MAX as f64)
    })
}
