//! Constant folding: operators and math builtins on constant floats and vectors.

use super::builtins::BuiltinId;
use super::math::{self, Math};
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
                Add | Sub | Mul | Div | Rem => {
                    broadcast(a, b, |x, y| math::arithmetic(op, x, y).unwrap_or(f64::NAN))
                }
                Lt | Le | Gt | Ge => Value::Bool(math::compare(op, a[0], b[0]) == Some(true)),
                Eq | Ne => {
                    let n = a.len().max(b.len());
                    let widen =
                        |v: &[f64]| -> Vec<f64> { (0..n).map(|i| v[i.min(v.len() - 1)]).collect() };
                    Value::Bool(math::vectors_equal(op, &widen(a), &widen(b)))
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

fn pack(v: Vec<f64>) -> Value {
    if v.len() == 1 {
        Value::Float(v[0])
    } else {
        Value::Vec(v)
    }
}

/// Folds a math builtin on constant arguments (already type-checked; `T` arguments may be
/// floats that broadcast to the call's vector size `n`), by its one definition
/// ([`super::math`]); anything else is not folded.
pub fn math(builtin: BuiltinId, args: &[Value], n: usize) -> Value {
    let Some(m) = Math::of(builtin) else {
        return Value::Error;
    };
    let comps: Vec<Vec<f64>> = args
        .iter()
        .map(|a| match a.components() {
            Some(c) if c.len() == 1 && n > 1 && m.widens() => vec![c[0]; n],
            Some(c) => c.to_vec(),
            None => Vec::new(),
        })
        .collect();
    if comps.iter().any(|c| c.is_empty()) {
        return Value::Error;
    }
    let refs: Vec<&[f64]> = comps.iter().map(|c| c.as_slice()).collect();
    pack(m.eval(&refs))
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
