//! The checker's expression level: names, operators, vectors, fields and calls.

use super::builtins::{self, Builtin, BuiltinId, Kind, PTy, Ret, BUILTINS, CONSTANTS};
use super::check::{suggest, Checker};
use super::fold;
use super::types::{AtlasAttr, FieldExpr, Node, SurfaceInput, Ty, Value};
use super::{Camera, Light, Reference, TextureRef};
use crate::access::Refusal;
use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::span::Span;
use crate::syntax::ast::{Arg, BinaryOp, Expr, ExprKind, Ident, Unit};
use std::path::Path;
use std::sync::Arc;

impl Checker<'_> {
    /// Checks an expression and folds it to a value.
    pub(crate) fn expr(&mut self, e: &Expr) -> Value {
        stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.expr_inner(e))
    }

    fn expr_inner(&mut self, e: &Expr) -> Value {
        match &e.kind {
            ExprKind::Number { value, unit } => {
                let v = match unit {
                    Some(Unit::Deg) => value.to_radians(),
                    _ => *value,
                };
                self.finite(Value::Float(v), e.span)
            }
            ExprKind::Bool(b) => Value::Bool(*b),
            ExprKind::Str(s) => Value::Str(s.clone()),
            ExprKind::Name(n) => self.name(n, e.span),
            ExprKind::Paren(inner) => self.expr(inner),
            ExprKind::Vector(items) => self.vector(items, e.span),
            ExprKind::Unary { op, expr } => {
                let v = self.expr(expr);
                let ty = v.ty();
                let ok = match op {
                    crate::syntax::ast::UnaryOp::Neg => ty.base().is_numeric(),
                    crate::syntax::ast::UnaryOp::Not => *ty.base() == Ty::Bool,
                };
                if v.is_error() {
                    Value::Error
                } else if !ok {
                    let sym = if *op == crate::syntax::ast::UnaryOp::Neg {
                        "-"
                    } else {
                        "!"
                    };
                    self.error(Diagnostic::error(
                        codes::E_BAD_OPERANDS,
                        format!("`{sym}` cannot be applied to {ty}"),
                        e.span,
                        format!("this is {ty}"),
                    ));
                    Value::Error
                } else if let Value::Uniform(_) = &v {
                    self.uniform_neg(v, e.span)
                } else if let Value::Field(_, t) = &v {
                    let t = t.clone();
                    Value::field(
                        FieldExpr::Unary {
                            op: *op,
                            operand: v,
                        },
                        t,
                    )
                } else {
                    fold::unary(*op, &v)
                }
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let l = self.expr(lhs);
                let r = self.expr(rhs);
                self.binary(*op, l, r, lhs.span, rhs.span, e.span)
            }
            ExprKind::Call { callee, args } => self.call(callee, None, args, e.span),
            ExprKind::Method {
                receiver,
                method,
                args,
            } => {
                let r = self.expr(receiver);
                self.call(method, Some((r, receiver.span)), args, e.span)
            }
            ExprKind::Field { receiver, field } => {
                let r = self.expr(receiver);
                self.field(r, receiver.span, field)
            }
            ExprKind::Error => Value::Error,
        }
    }

    /// Reports a constant that is NaN or infinite; it becomes an error value.
    fn finite(&mut self, v: Value, span: Span) -> Value {
        if fold::is_finite(&v) {
            v
        } else {
            self.error(
                Diagnostic::error(
                    codes::E_NON_FINITE,
                    format!(
                        "this constant is not a finite single-precision number ({})",
                        v.display()
                    ),
                    span,
                    "NaN, infinite, or beyond ±3.4e38",
                )
                .with_note(
                    "constants are folded at compile time in double precision, and the \
                     shaders hold them in single precision (f32), whose largest value is \
                     about 3.4e38",
                ),
            );
            Value::Error
        }
    }

    fn name(&mut self, n: &str, span: Span) -> Value {
        if let Some(&id) = self.scope.get(n) {
            self.prog.references.push(Reference { span, def: id });
            self.used.insert(id);
            let v = self.prog.def(id).value.clone();
            self.mark_param_use(&v);
            return v;
        }
        match n {
            "pi" => return Value::Float(std::f64::consts::PI),
            "time" => return self.time(span),
            "tau" => return Value::Float(std::f64::consts::TAU),
            "position" => {
                return Value::field(FieldExpr::Input(SurfaceInput::Position), Ty::Vec(3))
            }
            "normal" => return Value::field(FieldExpr::Input(SurfaceInput::Normal), Ty::Vec(3)),
            _ => {}
        }
        if let Some(def_span) = self.items.get(n) {
            let def_span = *def_span;
            self.used_early.insert(n.to_string());
            self.error(
                Diagnostic::error(
                    codes::E_USED_BEFORE_DEF,
                    format!("`{n}` is used before its definition"),
                    span,
                    "used here",
                )
                .with_label(def_span, "defined later here")
                .with_help("move the definition above its first use"),
            );
            return Value::Error;
        }
        let mut d = Diagnostic::error(
            codes::E_UNKNOWN_NAME,
            format!("cannot find `{n}` in this scene"),
            span,
            "not defined",
        );
        if let Some(b) = builtins::lookup(n) {
            d = d.with_help(format!(
                "`{n}` is a function: call it as `{}`",
                b.signature()
            ));
        } else {
            // Did-you-mean compares against every name in scope: a budget per file keeps
            // a file of many unknown names linear.
            let cost = self.scope.len() + CONSTANTS.len();
            if cost <= self.suggestion_budget {
                self.suggestion_budget -= cost;
                let best = suggest(
                    n,
                    self.scope
                        .keys()
                        .map(|s| s.as_str())
                        .chain(CONSTANTS.iter().map(|c| c.name)),
                )
                .map(str::to_string);
                if let Some(best) = best {
                    d = d.with_suggestion(&best);
                }
            }
        }
        self.error(d);
        Value::Error
    }

    /// `[a, b, …]`: components are floats or vectors (flattened, as in `[uv, 0]`), 2 to 4 in all.
    fn vector(&mut self, items: &[Expr], span: Span) -> Value {
        let values: Vec<Value> = items.iter().map(|i| self.expr(i)).collect();
        let mut bad = false;
        let mut count = 0usize;
        for (v, e) in values.iter().zip(items) {
            match v.ty().base() {
                Ty::Float => count += 1,
                Ty::Vec(n) => count += *n as usize,
                Ty::Error => bad = true,
                other => {
                    self.error(Diagnostic::error(
                        codes::E_TYPE_MISMATCH,
                        format!("vector components must be floats or vectors, found {other}"),
                        e.span,
                        "expected float",
                    ));
                    bad = true;
                }
            }
        }
        if bad {
            return Value::Error;
        }
        if !(2..=4).contains(&count) {
            self.error(Diagnostic::error(
                codes::E_VECTOR_SIZE,
                format!("vectors have 2, 3 or 4 components, this one has {count}"),
                span,
                "wrong number of components",
            ));
            return Value::Error;
        }
        if values.iter().any(|v| v.ty().is_field()) {
            return Value::field(FieldExpr::Vector(values), Ty::Vec(count as u8));
        }
        if values.iter().any(|v| v.uniform().is_some()) {
            return self.uniform_vector(values, span);
        }
        Value::Vec(
            values
                .iter()
                .filter_map(Value::components)
                .flatten()
                .copied()
                .collect(),
        )
    }

    fn binary(
        &mut self,
        op: BinaryOp,
        l: Value,
        r: Value,
        ls: Span,
        rs: Span,
        span: Span,
    ) -> Value {
        if l.is_error() || r.is_error() {
            return Value::Error;
        }
        let (lt, rt) = (l.ty(), r.ty());
        let field = lt.is_field() || rt.is_field();
        match fold::binary_type(op, lt.base(), rt.base()) {
            Err(msg) => {
                let code = if msg.contains("same size") {
                    codes::E_VECTOR_SIZE
                } else {
                    codes::E_BAD_OPERANDS
                };
                let mut d = Diagnostic::error(code, msg, span, "in this expression")
                    .with_label(ls, format!("this is {lt}"))
                    .with_label(rs, format!("this is {rt}"));
                if (lt == Ty::Shape) != (rt == Ty::Shape) {
                    d = d.with_note("on shapes, `|` is union, `&` intersection and `-` difference; both sides must be shapes");
                }
                self.error(d);
                Value::Error
            }
            Ok(Ty::Shape) => {
                let builtin = match op {
                    BinaryOp::Or => builtins::BuiltinId::Union,
                    BinaryOp::And => builtins::BuiltinId::Intersection,
                    _ => builtins::BuiltinId::Difference,
                };
                Value::Shape(Arc::new(Node {
                    builtin,
                    args: vec![l, r],
                    span,
                }))
            }
            Ok(ty) if field => Value::field(FieldExpr::Binary { op, lhs: l, rhs: r }, ty),
            Ok(_) if l.uniform().is_some() || r.uniform().is_some() => {
                self.uniform_binary(op, l, r, span)
            }
            Ok(_) => {
                let v = fold::binary(op, &l, &r);
                self.finite(v, span)
            }
        }
    }

    fn field(&mut self, r: Value, rspan: Span, field: &Ident) -> Value {
        let name = field.name.as_str();
        match &r {
            Value::Error => Value::Error,
            Value::Atlas(id) => {
                let id = *id;
                match AtlasAttr::ALL.iter().find(|(_, n, _, _)| *n == name) {
                    Some((attr, _, ty, _)) => Value::field(
                        FieldExpr::Atlas {
                            atlas: id,
                            attr: *attr,
                        },
                        ty.clone(),
                    ),
                    None => {
                        let mut d = Diagnostic::error(
                            codes::E_UNKNOWN_FIELD,
                            format!("atlases have no field `{name}`"),
                            field.span,
                            "unknown field",
                        );
                        if let Some(best) = suggest(name, AtlasAttr::ALL.iter().map(|a| a.1)) {
                            d = d.with_suggestion(best);
                        }
                        let all: Vec<&str> = AtlasAttr::ALL.iter().map(|a| a.1).collect();
                        self.error(d.with_note(format!("an atlas provides: {}", all.join(", "))));
                        Value::Error
                    }
                }
            }
            _ if matches!(r.ty().base(), Ty::Vec(_)) => {
                let Ty::Vec(n) = *r.ty().base() else {
                    unreachable!()
                };
                match swizzle(name, n) {
                    Ok(components) => match &r {
                        Value::Vec(v) => {
                            let out: Vec<f64> = components.iter().map(|&c| v[c as usize]).collect();
                            if out.len() == 1 {
                                Value::Float(out[0])
                            } else {
                                Value::Vec(out)
                            }
                        }
                        Value::Uniform(_) => {
                            self.uniform_swizzle(r.clone(), components, field.span)
                        }
                        _ => {
                            let ty = if components.len() == 1 {
                                Ty::Float
                            } else {
                                Ty::Vec(components.len() as u8)
                            };
                            Value::field(
                                FieldExpr::Swizzle {
                                    base: r.clone(),
                                    components,
                                },
                                ty,
                            )
                        }
                    },
                    Err(why) => {
                        self.error(
                            Diagnostic::error(codes::E_UNKNOWN_FIELD, format!("`{name}` is not a swizzle of a vec{n}"), field.span, why)
                                .with_label(rspan, format!("this is {}", r.ty()))
                                .with_note("swizzles use up to four of `xyzw` or of `rgba`, e.g. `.xy` or `.rgb`"),
                        );
                        Value::Error
                    }
                }
            }
            _ => {
                let ty = r.ty();
                let mut d = Diagnostic::error(
                    codes::E_UNKNOWN_FIELD,
                    format!("{ty} has no field `{name}`"),
                    field.span,
                    "unknown field",
                )
                .with_label(rspan, format!("this is {ty}"));
                if builtins::lookup(name).is_some() {
                    d = d.with_help(format!("to call `{name}`, add arguments: `.{name}(…)`"));
                }
                self.error(d);
                Value::Error
            }
        }
    }

    pub(crate) fn call(
        &mut self,
        callee: &Ident,
        receiver: Option<(Value, Span)>,
        args: &[Arg],
        span: Span,
    ) -> Value {
        // Arguments are checked first so that their own errors are reported in any case.
        let mut given: Vec<(Option<&Ident>, Value, Span)> = Vec::new();
        if let Some((v, s)) = receiver {
            given.push((None, v, s));
        }
        for a in args {
            let v = self.expr(&a.value);
            given.push((a.name.as_ref(), v, a.value.span));
        }
        let Some(b) = builtins::lookup(&callee.name) else {
            let what = if given.len() > args.len() {
                "method"
            } else {
                "function"
            };
            let mut d = Diagnostic::error(
                codes::E_UNKNOWN_FUNCTION,
                format!("cannot find {what} `{}`", callee.name),
                callee.span,
                format!("unknown {what}"),
            );
            if let Some(&id) = self.scope.get(&callee.name) {
                self.used.insert(id);
                self.prog.references.push(Reference {
                    span: callee.span,
                    def: id,
                });
                d = d.with_note(format!("`{}` is a value, not a function", callee.name));
            } else if let Some(best) = suggest(&callee.name, BUILTINS.iter().map(|b| b.name)) {
                d = d.with_suggestion(best);
            }
            self.error(d);
            return Value::Error;
        };
        let (bound, ok) = self.bind(b, callee, given, span);
        let value = self.apply(b, bound, span);
        if ok {
            value
        } else {
            Value::Error
        }
    }

    /// Matches arguments to parameters; fills defaults; reports count and name problems.
    /// A missing argument is bound to an error value; the flag says whether binding succeeded.
    fn bind(
        &mut self,
        b: &'static Builtin,
        callee: &Ident,
        given: Vec<(Option<&Ident>, Value, Span)>,
        span: Span,
    ) -> (Vec<(Value, Span)>, bool) {
        let mut slots: Vec<Option<(Value, Span)>> = vec![None; b.params.len()];
        let mut next = 0;
        let mut ok = true;
        let mut seen_named = false;
        for (name, value, vspan) in given {
            let index = match name {
                None => {
                    if seen_named {
                        self.error(
                            Diagnostic::error(
                                codes::E_ARG_ORDER,
                                "positional argument after a named argument",
                                vspan,
                                "positional argument",
                            )
                            .with_help("put positional arguments first, or name this one too"),
                        );
                        ok = false;
                        continue;
                    }
                    if next >= b.params.len() {
                        self.error(
                            Diagnostic::error(
                                codes::E_TOO_MANY_ARGS,
                                format!(
                                    "`{}` takes {} argument{}",
                                    b.name,
                                    b.params.len(),
                                    if b.params.len() == 1 { "" } else { "s" }
                                ),
                                vspan,
                                "extra argument",
                            )
                            .with_label(
                                callee.span,
                                format!("`{}` declared as `{}`", b.name, b.signature()),
                            ),
                        );
                        ok = false;
                        continue;
                    }
                    next += 1;
                    next - 1
                }
                Some(n) => {
                    seen_named = true;
                    match b.param(&n.name) {
                        Some((i, _)) => i,
                        None => {
                            let mut d = Diagnostic::error(
                                codes::E_UNKNOWN_ARG,
                                format!("`{}` has no parameter `{}`", b.name, n.name),
                                n.span,
                                "unknown parameter",
                            )
                            .with_note(format!("the signature is `{}`", b.signature()));
                            if let Some(best) = suggest(&n.name, b.params.iter().map(|p| p.name)) {
                                d = d.with_suggestion(best);
                            }
                            self.error(d);
                            ok = false;
                            continue;
                        }
                    }
                }
            };
            if let Some((_, first)) = &slots[index] {
                let first = *first;
                self.error(
                    Diagnostic::error(
                        codes::E_DUPLICATE_ARG,
                        format!("argument `{}` is given twice", b.params[index].name),
                        vspan,
                        "given again here",
                    )
                    .with_label(first, "first given here"),
                );
                ok = false;
                continue;
            }
            slots[index] = Some((value, vspan));
        }
        let mut bound = Vec::with_capacity(slots.len());
        for (p, slot) in b.params.iter().zip(slots) {
            match (slot, p.default) {
                (Some(v), _) => bound.push(v),
                (None, Some(d)) => bound.push((Value::from(d), span)),
                (None, None) => {
                    self.error(
                        Diagnostic::error(
                            codes::E_MISSING_ARG,
                            format!("`{}` needs the argument `{}`", b.name, p.name),
                            span,
                            format!("`{}` is missing", p.name),
                        )
                        .with_note(format!("the signature is `{}`", b.signature())),
                    );
                    bound.push((Value::Error, span));
                    ok = false;
                }
            }
        }
        (bound, ok)
    }

    /// Type-checks bound arguments and applies the parameters' checks; returns the
    /// size of the `T` arguments (1 for floats), or `None` after reporting a problem.
    fn check_args(&mut self, b: &'static Builtin, bound: &[(Value, Span)]) -> Option<u8> {
        let lifts = b.kind.lifts_fields();
        let mut ok = true;
        let mut t_size: Option<(u8, Span)> = None;
        for (p, (v, vspan)) in b.params.iter().zip(bound) {
            if v.is_error() {
                ok = false;
                continue;
            }
            let ty = v.ty();
            // A displacement's height is the one surface field a shape takes.
            let field_ok = lifts
                || (b.id == builtins::BuiltinId::Displace && p.name == "height")
                || (b.id == builtins::BuiltinId::ShellMap && p.name == "uv");
            if ty.is_field() && !field_ok {
                self.error(
                    Diagnostic::error(
                        codes::E_NOT_CONSTANT,
                        format!("`{}` of `{}` must be a constant", p.name, b.name),
                        *vspan,
                        format!("this is a surface field ({ty})"),
                    )
                    .with_note("shapes, cameras and lights are built at compile time"),
                );
                ok = false;
                continue;
            }
            let base = ty.base();
            let accepted = base.fits(p.ty);
            if !accepted {
                let mut d = Diagnostic::error(
                    codes::E_TYPE_MISMATCH,
                    format!(
                        "`{}` of `{}` expects {}, found {ty}",
                        p.name,
                        b.name,
                        p.ty.describe()
                    ),
                    *vspan,
                    format!("expected {}", p.ty.describe()),
                )
                .with_note(format!("the signature is `{}`", b.signature()));
                if p.ty == PTy::Vec3 && *base == Ty::Float {
                    d = d.with_help("write a vector such as `[x, y, z]`");
                }
                self.error(d);
                ok = false;
                continue;
            }
            if p.ty == PTy::T {
                if let Ty::Vec(n) = base {
                    match t_size {
                        Some((m, first)) if m != *n => {
                            self.error(
                                Diagnostic::error(
                                    codes::E_VECTOR_SIZE,
                                    format!(
                                        "`{}` needs arguments of one size, found vec{m} and vec{n}",
                                        b.name
                                    ),
                                    *vspan,
                                    format!("this is vec{n}"),
                                )
                                .with_label(first, format!("this is vec{m}")),
                            );
                            ok = false;
                        }
                        None => t_size = Some((*n, *vspan)),
                        _ => {}
                    }
                }
            }
            if let Value::Uniform(u) = v {
                let lifts = lifts || b.ret == Ret::Float || b.ret == Ret::T;
                let refused = matches!(b.ret, Ret::Camera | Ret::Light | Ret::Texture);
                if refused {
                    self.refuse_run_time(&format!("`{}` of `{}`", p.name, b.name), *vspan);
                    ok = false;
                } else if !self.check_run_time_arg(b, p, u, *vspan, lifts) {
                    ok = false;
                }
                continue;
            }
            if !ty.is_field() && !self.check_constant(p.name, p.check, v, *vspan) {
                ok = false;
            }
        }
        ok.then(|| t_size.map(|(n, _)| n).unwrap_or(1))
    }

    /// Type-checks bound arguments and builds the call's value.
    fn apply(&mut self, b: &'static Builtin, bound: Vec<(Value, Span)>, span: Span) -> Value {
        let Some(n) = self.check_args(b, &bound) else {
            return Value::Error;
        };
        if b.id == builtins::BuiltinId::Displace && !self.check_displace(&bound) {
            return Value::Error;
        }
        if b.id == builtins::BuiltinId::ShellMap && !self.check_shell_map(&bound) {
            return Value::Error;
        }
        let args: Vec<Value> = bound.iter().map(|(v, _)| v.clone()).collect();
        if b.id == BuiltinId::SampleNormal && !self.normal_map_atlas(&bound[1]) {
            return Value::Error;
        }
        if b.name == "image" {
            if let (Value::Str(path), pspan) = (&args[0], bound[0].1) {
                self.texture_file(path, pspan);
            }
        }
        let t_ty = if n == 1 { Ty::Float } else { Ty::Vec(n) };
        let ret_ty = match b.ret {
            Ret::Float => Ty::Float,
            Ret::Vec3 => Ty::Vec(3),
            Ret::Vec4 => Ty::Vec(4),
            Ret::T => t_ty,
            Ret::Shape => Ty::Shape,
            Ret::Texture => Ty::Texture,
            Ret::Camera => Ty::Camera,
            Ret::Light => Ty::Light,
        };
        let node = || {
            Arc::new(Node {
                builtin: b.id,
                args: args.clone(),
                span,
            })
        };
        match b.ret {
            Ret::Shape => Value::Shape(node()),
            Ret::Texture => Value::Texture(node()),
            Ret::Camera => {
                Camera::from_call(b.id, &args).map_or(Value::Error, |c| Value::Camera(Arc::new(c)))
            }
            Ret::Light => {
                Light::from_call(b.id, &args).map_or(Value::Error, |l| Value::Light(Arc::new(l)))
            }
            _ if b.kind == Kind::Texture || args.iter().any(|a| a.ty().is_field()) => Value::field(
                FieldExpr::Call {
                    builtin: b.id,
                    args,
                },
                ret_ty,
            ),
            _ if args.iter().any(|a| a.uniform().is_some()) => {
                self.uniform_math(b.id, args, n as usize, span)
            }
            _ => {
                let v = fold::math(b.id, &args, n as usize);
                self.finite(v, span)
            }
        }
    }

    /// A normal map's uv must read exactly one atlas: its seeds' frames, carried to the
    /// point by the walk's parallel transport, are the tangent frame (Eq. 52).
    fn normal_map_atlas(&mut self, (uv, span): &(Value, Span)) -> bool {
        let atlases = uv.atlases();
        if atlases.len() == 1 {
            return true;
        }
        let names: Vec<String> = atlases
            .iter()
            .filter_map(|k| self.prog.atlases.get(k.index()))
            .map(|a| format!("`{}`", a.name))
            .collect();
        let (message, label) = if atlases.is_empty() {
            (
                String::from("the uv of `sample_normal` must come from an atlas"),
                String::from("this uv reads no atlas"),
            )
        } else {
            (
                String::from("the uv of `sample_normal` must come from one atlas"),
                format!("this uv reads the atlases {}", names.join(" and ")),
            )
        };
        self.error(
            Diagnostic::error(codes::E_NORMAL_MAP_ATLAS, message, *span, label)
                .with_note(
                    "a normal map's tangent frame is the frame of its atlas's seeds, carried to \
                     the point by the geodesic walk's parallel transport",
                )
                .with_help("sample it at an atlas's uv, e.g. `tex.sample_normal(skin.uv)`"),
        );
        false
    }

    fn texture_file(&mut self, path: &str, span: Span) {
        let lower = path.to_ascii_lowercase();
        let mut texture = TextureRef {
            path: path.to_string(),
            resolved: None,
            span,
        };
        if !(lower.ends_with(".png") || lower.ends_with(".jpg") || lower.ends_with(".jpeg")) {
            self.prog.textures.push(texture);
            self.error(
                Diagnostic::error(
                    codes::E_IMAGE_FORMAT,
                    format!("cannot read {}: textures must be PNG or JPEG", quote(path)),
                    span,
                    "unsupported image format",
                )
                .with_note("the file name must end in .png, .jpg or .jpeg"),
            );
            return;
        }
        match self.access.resolve(path) {
            None => {}
            Some(Ok(full)) => match crate::access::image_header(&full) {
                Ok(_) => texture.resolved = Some(full),
                Err(why) => self.error(Diagnostic::error(
                    codes::E_IMAGE_FORMAT,
                    format!("cannot read texture {}: {why}", quote(path)),
                    span,
                    "not a usable image",
                )),
            },
            Some(Err(Refusal::NotFound)) => {
                let base = self.access.base.as_deref().unwrap_or(Path::new("."));
                self.error(
                    Diagnostic::error(
                        codes::E_MISSING_FILE,
                        format!("texture file {} not found", quote(path)),
                        span,
                        "no such file",
                    )
                    .with_note(format!("looked for {}", base.join(path).display()))
                    .with_note("texture paths are relative to the scene file's folder"),
                )
            }
            Some(Err(Refusal::Outside)) => self.error(
                Diagnostic::error(
                    codes::E_FILE_REFUSED,
                    format!("cannot read texture {}: {}", quote(path), Refusal::Outside),
                    span,
                    "outside the allowed folders",
                )
                .with_note(
                    "a scene reads files only in its own folder and its subfolders, after \
                     following symbolic links",
                )
                .with_help("to allow another folder, pass `--allow-path DIR`"),
            ),
            Some(Err(why)) => self.error(Diagnostic::error(
                codes::E_FILE_REFUSED,
                format!("cannot read texture {}: {why}", quote(path)),
                span,
                "not a readable image file",
            )),
        }
        self.prog.textures.push(texture);
    }
}

/// A user's string in a message: quoted, and cut short when long.
fn quote(text: &str) -> String {
    crate::diagnostic::quote(text)
}

/// Component indices of a swizzle on a vector of `n` components.
fn swizzle(name: &str, n: u8) -> Result<Vec<u8>, String> {
    if name.is_empty() || name.len() > 4 {
        return Err(String::from("a swizzle has 1 to 4 components"));
    }
    let set = if name.chars().all(|c| "xyzw".contains(c)) {
        "xyzw"
    } else if name.chars().all(|c| "rgba".contains(c)) {
        "rgba"
    } else {
        return Err(String::from("not a swizzle"));
    };
    name.chars()
        .map(|c| {
            let i = set.find(c).unwrap_or(0) as u8;
            if i < n {
                Ok(i)
            } else {
                Err(format!("vec{n} has no component `{c}`"))
            }
        })
        .collect()
}
