//! Run-time parameters in the checker: `param` items, the built-in `time`, and values
//! computed from them ([`Uniform`]): folding stops at a parameter and resumes beyond
//! it, each such value keeping its expression (for the shaders), its value at the
//! parameters' current values (for everything computed at compile time) and its
//! interval over their ranges ([`super::interval`]).

use super::builtins::{self, BuiltinId, Check};
use super::check::Checker;
use super::interval::{self, Iv};
use super::math::Math;
use super::show::fmt_num;
use super::types::{FieldExpr, ParamRef, Uniform, Value};
use super::{DefId, DefKind, ParamDef};
use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::span::Span;
use crate::syntax::ast::{BinaryOp, Expr, Ident, UnaryOp};
use std::sync::Arc;

/// The most run-time parameters one scene may declare (each is a field of the uniform
/// block, 16 bytes at most).
pub const MAX_PARAMS: usize = 256;

/// The arguments a run-time value may set, by builtin and parameter name: the shapes'
/// sizes, offsets, angles, rates and widths whose code the generator writes from the
/// uniform block and whose bounds the lowering takes over the whole range. Anything
/// else a shape takes is fixed at compile time.
pub const RUN_TIME_ARGS: &[(BuiltinId, &[&str])] = &[
    (BuiltinId::Sphere, &["radius"]),
    (BuiltinId::Box, &["size"]),
    (BuiltinId::BoxFrame, &["size", "thickness"]),
    (BuiltinId::Torus, &["major", "minor"]),
    (BuiltinId::Capsule, &["a", "b", "radius"]),
    (BuiltinId::Cylinder, &["radius", "height"]),
    (BuiltinId::CappedCone, &["height", "bottom", "top"]),
    (BuiltinId::Plane, &["offset"]),
    (BuiltinId::Ellipsoid, &["radii"]),
    (BuiltinId::Octahedron, &["radius"]),
    (BuiltinId::HexPrism, &["radius", "height"]),
    (BuiltinId::TriPrism, &["radius", "height"]),
    (BuiltinId::Pyramid, &["height"]),
    (BuiltinId::Link, &["length", "major", "minor"]),
    (BuiltinId::SmoothUnion, &["k"]),
    (BuiltinId::SmoothIntersection, &["k"]),
    (BuiltinId::SmoothDifference, &["k"]),
    (BuiltinId::Translate, &["offset"]),
    (BuiltinId::Rotate, &["angle"]),
    (BuiltinId::RotateX, &["angle"]),
    (BuiltinId::RotateY, &["angle"]),
    (BuiltinId::RotateZ, &["angle"]),
    (BuiltinId::Scale, &["factor"]),
    (BuiltinId::Twist, &["rate"]),
    (BuiltinId::Bend, &["rate"]),
    (BuiltinId::Elongate, &["amount"]),
    (BuiltinId::Round, &["radius"]),
    (BuiltinId::Shell, &["thickness"]),
    (BuiltinId::Repeat, &["period"]),
    (BuiltinId::Displace, &["scale"]),
];

/// Whether argument `param` of shape builtin `b` may be a run-time value.
pub fn run_time_arg(b: BuiltinId, param: &str) -> bool {
    RUN_TIME_ARGS
        .iter()
        .any(|(id, names)| *id == b && names.contains(&param))
}

fn show_range(r: Iv) -> String {
    let end = |x: f64| {
        if x.is_infinite() {
            String::from(if x > 0.0 { "∞" } else { "-∞" })
        } else {
            fmt_num(x)
        }
    };
    format!("[{}, {}]", end(r.0), end(r.1))
}

/// A uniform from its parts.
fn uniform(expr: FieldExpr, value: Value, range: Vec<Iv>, span: Span) -> Value {
    let Some(value) = value.components().map(<[f64]>::to_vec) else {
        return Value::Error;
    };
    Value::Uniform(Arc::new(Uniform {
        expr: Arc::new(expr),
        value,
        range,
        span,
    }))
}

/// The names of the parameters a run-time value reads (none for a constant).
pub fn param_names(v: &Value, out: &mut std::collections::BTreeSet<String>) {
    let Value::Uniform(u) = v else { return };
    stacker::maybe_grow(64 * 1024, 1024 * 1024, || match &*u.expr {
        FieldExpr::Param(p) => {
            out.insert(p.name.to_string());
        }
        FieldExpr::Unary { operand, .. } => param_names(operand, out),
        FieldExpr::Binary { lhs, rhs, .. } => {
            param_names(lhs, out);
            param_names(rhs, out);
        }
        FieldExpr::Vector(items) | FieldExpr::Call { args: items, .. } => {
            items.iter().for_each(|i| param_names(i, out))
        }
        FieldExpr::Swizzle { base, .. } => param_names(base, out),
        FieldExpr::Input(_) | FieldExpr::Atlas { .. } => {}
    })
}

/// The value a run-time value takes at other parameter values: `values` gives a
/// parameter's value by name (`None`: its current value). Constants are themselves;
/// a [`Uniform`]'s expression is folded again by the checker's own rules
/// ([`super::fold`]), so this agrees with a check at those values
/// (`Access::set_param`) where they lie in their ranges (a host keeps them there; a
/// value of the wrong size counts as absent). What is not a number is
/// [`Value::Error`].
pub fn value_at(v: &Value, values: &dyn Fn(&str) -> Option<Vec<f64>>) -> Value {
    let pack = |c: Vec<f64>| {
        if c.len() == 1 {
            Value::Float(c[0])
        } else {
            Value::Vec(c)
        }
    };
    let u = match v {
        Value::Float(_) | Value::Vec(_) => return v.clone(),
        Value::Uniform(u) => u,
        _ => return Value::Error,
    };
    let at = |v: &Value| value_at(v, values);
    stacker::maybe_grow(64 * 1024, 1024 * 1024, || match &*u.expr {
        FieldExpr::Param(p) => pack(
            values(&p.name)
                .filter(|c| c.len() == u.value.len())
                .unwrap_or_else(|| u.value.clone()),
        ),
        FieldExpr::Unary { op, operand } => super::fold::unary(*op, &at(operand)),
        FieldExpr::Binary { op, lhs, rhs } => super::fold::binary(*op, &at(lhs), &at(rhs)),
        FieldExpr::Vector(items) => {
            let mut c = Vec::new();
            for item in items {
                match at(item).components() {
                    Some(x) => c.extend_from_slice(x),
                    None => return Value::Error,
                }
            }
            pack(c)
        }
        FieldExpr::Swizzle { base, components } => match at(base).components() {
            Some(b) => components
                .iter()
                .map(|&i| b.get(i as usize).copied())
                .collect::<Option<Vec<f64>>>()
                .map_or(Value::Error, pack),
            None => Value::Error,
        },
        FieldExpr::Call { builtin, args } => {
            let args: Vec<Value> = args.iter().map(at).collect();
            // The call's vector size: its widest argument (floats widen to it).
            let n = args
                .iter()
                .filter_map(|a| a.components().map(<[f64]>::len))
                .max()
                .unwrap_or(1);
            super::fold::math(*builtin, &args, n)
        }
        FieldExpr::Input(_) | FieldExpr::Atlas { .. } => Value::Error,
    })
}

impl Checker<'_> {
    /// The value of the built-in `time` (its current value from `Access`, else 0).
    pub(crate) fn time(&mut self, span: Span) -> Value {
        if self.prog.params.is_empty() {
            self.prog.params.push(ParamDef::time());
        }
        let t = &mut self.prog.params[0];
        t.used = true;
        if let Some(v) = self
            .access
            .param("time")
            .filter(|v| v.len() == 1 && v[0] >= 0.0)
        {
            t.value = v;
        }
        let value = t.value.clone();
        uniform(
            FieldExpr::Param(ParamRef {
                index: 0,
                name: Arc::from("time"),
            }),
            Value::Float(value[0]),
            vec![t.range],
            span,
        )
    }

    /// `param name = default in [min, max];`
    pub(crate) fn param_item(
        &mut self,
        name: &Ident,
        value: &Expr,
        range: Option<&Expr>,
        item_span: Span,
    ) -> DefId {
        let v = self.param_value(name, value, range);
        self.define(name, DefKind::Param, item_span, v)
    }

    fn param_value(&mut self, name: &Ident, value: &Expr, range: Option<&Expr>) -> Value {
        let default = self.expr(value);
        let r = range.map(|r| (self.expr(r), r.span));
        if default.is_error() || r.as_ref().is_some_and(|r| r.0.is_error()) {
            return Value::Error;
        }
        let not_constant = |v: &Value| !matches!(v, Value::Float(_) | Value::Vec(_));
        if not_constant(&default) {
            self.error(
                Diagnostic::error(
                    codes::E_PARAM_RANGE,
                    format!(
                        "the default of `{}` must be a constant number or vector",
                        name.name
                    ),
                    value.span,
                    format!("this is {}", default.ty()),
                )
                .with_help("write a number such as `0.5`, or a vector such as `[0.8, 0.3, 0.2]`"),
            );
            return Value::Error;
        }
        let size = default.components().map_or(1, <[f64]>::len);
        let bounds = match r {
            Some((Value::Vec(v), _)) if v.len() == 2 && v[0] < v[1] => (v[0], v[1]),
            Some((r, span)) => {
                self.error(
                    Diagnostic::error(
                        codes::E_PARAM_RANGE,
                        "a parameter's range is `[min, max]` with min < max",
                        span,
                        format!("this is {}", r.display()),
                    )
                    .with_help("write two numbers, the smaller first: `in [0.1, 2]`"),
                );
                return Value::Error;
            }
            None if size > 1 => (0.0, 1.0),
            None => {
                self.error(
                    Diagnostic::error(
                        codes::E_PARAM_RANGE,
                        format!("parameter `{}` needs a range", name.name),
                        value.span,
                        "no range after the default",
                    )
                    .with_note(
                        "sphere tracing stays safe only if every step bound holds for every \
                         value the parameter may take: the compiler takes them over its range",
                    )
                    .with_help(format!(
                        "add the values it may take: `param {} = {} in [min, max];`",
                        name.name,
                        default.display()
                    )),
                );
                return Value::Error;
            }
        };
        let d = default.components().unwrap_or(&[]).to_vec();
        if d.iter().any(|x| *x < bounds.0 || *x > bounds.1) {
            self.error(
                Diagnostic::error(
                    codes::E_PARAM_RANGE,
                    format!("the default of `{}` lies outside its range", name.name),
                    value.span,
                    format!("{} is not in {}", default.display(), show_range(bounds)),
                )
                .with_help("widen the range, or choose a default inside it"),
            );
            return Value::Error;
        }
        if self.prog.params.is_empty() {
            self.prog.params.push(ParamDef::time());
        }
        // `time` is the first entry: the ones declared so far are the rest.
        if self.prog.params.len() > MAX_PARAMS {
            self.error(Diagnostic::error(
                codes::E_PARAM_RANGE,
                format!("a scene may declare at most {MAX_PARAMS} parameters"),
                name.span,
                "one too many",
            ));
            return Value::Error;
        }
        let current = self
            .access
            .param(&name.name)
            .filter(|v| v.len() == size && v.iter().all(|x| *x >= bounds.0 && *x <= bounds.1))
            .unwrap_or_else(|| d.clone());
        let index = self.prog.params.len();
        self.prog.params.push(ParamDef {
            name: name.name.clone(),
            size,
            default: d,
            value: current.clone(),
            range: bounds,
            span: name.span,
            used: false,
        });
        let current = if size == 1 {
            Value::Float(current[0])
        } else {
            Value::Vec(current)
        };
        uniform(
            FieldExpr::Param(ParamRef {
                index: index as u32,
                name: Arc::from(name.name.as_str()),
            }),
            current,
            vec![bounds; size],
            name.span,
        )
    }

    /// A run-time value whose current value is not a finite single-precision number
    /// (`1 / (x - 0.5)` at x = 0.5) is an error, as such a constant is.
    fn finite_now(&mut self, v: Value, span: Span) -> Value {
        if super::fold::is_finite(&v) {
            return v;
        }
        self.error(
            Diagnostic::error(
                codes::E_NON_FINITE,
                format!(
                    "at the parameters' current values this is not a finite single-precision number ({})",
                    v.display()
                ),
                span,
                "NaN, infinite, or beyond ±3.4e38",
            )
            .with_help("change the defaults (or the `--param` values), or guard the expression"),
        );
        Value::Error
    }

    /// Marks the parameters a value read from a definition uses.
    pub(crate) fn mark_param_use(&mut self, v: &Value) {
        if let Value::Uniform(u) = v {
            if let FieldExpr::Param(p) = &*u.expr {
                if let Some(def) = self.prog.params.get_mut(p.index as usize) {
                    def.used = true;
                }
            }
        }
    }

    /// `-x` of a run-time value.
    pub(crate) fn uniform_neg(&mut self, v: Value, span: Span) -> Value {
        let Some(range) = v.ranges() else {
            return Value::Error;
        };
        let value = super::fold::unary(UnaryOp::Neg, &v);
        uniform(
            FieldExpr::Unary {
                op: UnaryOp::Neg,
                operand: v,
            },
            value,
            interval::neg(&range),
            span,
        )
    }

    /// An arithmetic operator with a run-time operand; comparisons of run-time values
    /// are refused (a shape's structure is fixed at compile time).
    pub(crate) fn uniform_binary(&mut self, op: BinaryOp, l: Value, r: Value, span: Span) -> Value {
        let (Some(a), Some(b)) = (l.ranges(), r.ranges()) else {
            return Value::Error;
        };
        let Some(range) = interval::binary(op, &a, &b) else {
            self.error(
                Diagnostic::error(
                    codes::E_RUN_TIME,
                    format!("`{}` cannot compare run-time parameters", op.symbol()),
                    span,
                    "this depends on a parameter",
                )
                .with_note("what a comparison decides is fixed at compile time"),
            );
            return Value::Error;
        };
        let value = super::fold::binary(op, &l, &r);
        let v = uniform(FieldExpr::Binary { op, lhs: l, rhs: r }, value, range, span);
        self.finite_now(v, span)
    }

    /// `[a, b, …]` with a run-time component.
    pub(crate) fn uniform_vector(&mut self, values: Vec<Value>, span: Span) -> Value {
        let mut range = Vec::new();
        let mut value = Vec::new();
        for v in &values {
            range.extend(v.ranges().unwrap_or_default());
            value.extend_from_slice(v.components().unwrap_or(&[]));
        }
        uniform(FieldExpr::Vector(values), Value::Vec(value), range, span)
    }

    /// A swizzle of a run-time vector.
    pub(crate) fn uniform_swizzle(
        &mut self,
        base: Value,
        components: Vec<u8>,
        span: Span,
    ) -> Value {
        let (Some(r), Some(v)) = (base.ranges(), base.components().map(<[f64]>::to_vec)) else {
            return Value::Error;
        };
        let range: Vec<Iv> = components.iter().map(|&c| r[c as usize]).collect();
        let value: Vec<f64> = components.iter().map(|&c| v[c as usize]).collect();
        let value = if value.len() == 1 {
            Value::Float(value[0])
        } else {
            Value::Vec(value)
        };
        uniform(FieldExpr::Swizzle { base, components }, value, range, span)
    }

    /// A math builtin with a run-time argument (`n`: the call's vector size).
    pub(crate) fn uniform_math(
        &mut self,
        b: BuiltinId,
        args: Vec<Value>,
        n: usize,
        span: Span,
    ) -> Value {
        let Some(m) = Math::of(b) else {
            return Value::Error;
        };
        let ranges: Vec<Vec<Iv>> = args
            .iter()
            .map(|a| {
                let r = a.ranges().unwrap_or_default();
                if r.len() == 1 && n > 1 && m.widens() {
                    vec![r[0]; n]
                } else {
                    r
                }
            })
            .collect();
        let value = super::fold::math(b, &args, n);
        let range = interval::math(m, &ranges, n);
        let v = uniform(FieldExpr::Call { builtin: b, args }, value, range, span);
        self.finite_now(v, span)
    }

    /// A builtin argument that is a run-time value: allowed where [`RUN_TIME_ARGS`]
    /// says, and its check (a radius is positive) must hold over its whole range.
    pub(crate) fn check_run_time_arg(
        &mut self,
        b: &'static builtins::Builtin,
        param: &builtins::Param,
        u: &Uniform,
        span: Span,
        anywhere: bool,
    ) -> bool {
        if !anywhere && !run_time_arg(b.id, param.name) {
            let allowed: Vec<&str> = RUN_TIME_ARGS
                .iter()
                .find(|(id, _)| *id == b.id)
                .map(|(_, n)| n.to_vec())
                .unwrap_or_default();
            let mut d = Diagnostic::error(
                codes::E_RUN_TIME,
                format!(
                    "`{}` of `{}` is fixed at compile time: a run-time parameter cannot set it",
                    param.name, b.name
                ),
                span,
                "this depends on a parameter",
            );
            d = if allowed.is_empty() {
                d.with_note(format!("every argument of `{}` is a constant", b.name))
            } else {
                d.with_note(format!(
                    "parameters may set {} of `{}`",
                    allowed
                        .iter()
                        .map(|a| format!("`{a}`"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    b.name
                ))
            };
            self.error(d);
            return false;
        }
        let (lo, _) = u.hull();
        let fails = match param.check {
            Check::Positive => lo.is_nan() || lo <= 0.0,
            Check::NonNegative => lo.is_nan() || lo < 0.0,
            _ => false,
        };
        if fails {
            let what = if param.check == Check::Positive {
                "positive"
            } else {
                "non-negative"
            };
            let ranges: Vec<String> = u.range.iter().map(|&r| show_range(r)).collect();
            self.error(
                Diagnostic::error(
                    codes::E_NOT_POSITIVE,
                    format!(
                        "`{}` must be {what} for every value its parameters may take",
                        param.name
                    ),
                    span,
                    format!(
                        "over the parameters' ranges this is in {}",
                        ranges.join(" × ")
                    ),
                )
                .with_help("narrow the parameter's range, or clamp the expression"),
            );
            return false;
        }
        true
    }

    /// A setting (of `render` or `atlas`) or a seed that a run-time value cannot set.
    pub(crate) fn refuse_run_time(&mut self, what: &str, span: Span) {
        self.error(
            Diagnostic::error(
                codes::E_RUN_TIME,
                format!("{what} is fixed at compile time: a run-time parameter cannot set it"),
                span,
                "this depends on a parameter",
            )
            .with_note(
                "parameters may set shapes' sizes, transforms, warps and blend widths, and \
                 materials",
            ),
        );
    }
}
