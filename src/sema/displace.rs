//! The checks of `displace` (§5.2.2): what a height may read, and atlases on
//! displaced shapes. The numbers (the height's range and slope, from the texels of its
//! textures) are derived when the shape is lowered (`ir::displace`).

use super::builtins::BuiltinId;
use super::check::Checker;
use super::types::{AtlasAttr, FieldExpr, SurfaceInput, Value};
use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::span::Span;
use crate::syntax::ast::{BinaryOp, UnaryOp};

/// The shape without its `paint`s (a material changes no geometry).
fn geometry(v: &Value) -> &Value {
    match v {
        Value::Shape(n) if n.builtin == BuiltinId::Paint => geometry(&n.args[0]),
        v => v,
    }
}

fn same_shape(a: &Value, b: &Value) -> bool {
    let (a, b) = (geometry(a), geometry(b));
    match (a, b) {
        (Value::Shape(x), Value::Shape(y)) => std::sync::Arc::ptr_eq(x, y) || x == y,
        _ => a == b,
    }
}

/// The `displace` or `shell_map` call inside a shape value, if any (its span).
pub fn displaced(v: &Value) -> Option<Span> {
    let Value::Shape(n) = v else { return None };
    if matches!(n.builtin, BuiltinId::Displace | BuiltinId::ShellMap) {
        return Some(n.span);
    }
    n.args.iter().find_map(displaced)
}

/// Why a height cannot be bounded: the first builtin, operator or input in it that
/// jumps or has no slope bound.
fn unbounded(v: &Value) -> Option<String> {
    if let Value::Uniform(_) = v {
        return Some(String::from(
            "a run-time parameter (a height is bounded at compile time, so parameters cannot set it yet)",
        ));
    }
    let Value::Field(e, _) = v else { return None };
    match &**e {
        FieldExpr::Param(_) => Some(String::from("a run-time parameter")),
        FieldExpr::Input(SurfaceInput::Position) => None,
        FieldExpr::Input(SurfaceInput::Normal) => Some(String::from(
            "`normal` has no slope bound (it turns with the surface's curvature)",
        )),
        FieldExpr::Atlas { attr, .. } => match attr {
            AtlasAttr::Uv | AtlasAttr::Distance => None,
            AtlasAttr::Status | AtlasAttr::Seed => Some(String::from(
                "an atlas's `status` and `seed` jump from one value to the next",
            )),
            AtlasAttr::Transport => Some(String::from("an atlas's `transport` has no slope bound")),
        },
        FieldExpr::Unary { op, operand } => match op {
            UnaryOp::Neg => unbounded(operand),
            UnaryOp::Not => Some(String::from("`!` jumps")),
        },
        FieldExpr::Binary { op, lhs, rhs } => match op {
            BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul => {
                unbounded(lhs).or_else(|| unbounded(rhs))
            }
            BinaryOp::Div if !rhs.ty().is_field() => unbounded(lhs),
            BinaryOp::Div => Some(String::from(
                "dividing by a surface field has no slope bound (it may come near zero)",
            )),
            op => Some(format!("`{}` jumps", op.symbol())),
        },
        FieldExpr::Swizzle { base, .. } => unbounded(base),
        FieldExpr::Vector(args) => args.iter().find_map(unbounded),
        FieldExpr::Call { builtin, args } => {
            use BuiltinId as B;
            match builtin {
                B::Sample => unbounded(&args[1]),
                B::Sin
                | B::Cos
                | B::Atan
                | B::Abs
                | B::Exp
                | B::Min
                | B::Max
                | B::Clamp
                | B::Mix
                | B::Length
                | B::Distance
                | B::Dot
                | B::Radians
                | B::Degrees => args.iter().find_map(unbounded),
                B::Smoothstep if args[..2].iter().any(|a| a.ty().is_field()) => Some(String::from(
                    "`smoothstep` with edges that are surface fields has no slope bound",
                )),
                B::Smoothstep => unbounded(&args[2]),
                B::Checker | B::Grid | B::Floor | B::Ceil | B::Fract | B::Sign | B::Step => {
                    Some(format!("`{}` jumps", builtin.name()))
                }
                b => Some(format!("`{}` has no slope bound in general", b.name())),
            }
        }
    }
}

/// The atlases a height reads.
fn atlases(v: &Value, out: &mut Vec<super::AtlasId>) {
    let Value::Field(e, _) = v else { return };
    match &**e {
        FieldExpr::Atlas { atlas, .. } => {
            if !out.contains(atlas) {
                out.push(*atlas)
            }
        }
        FieldExpr::Input(_) | FieldExpr::Param(_) => {}
        FieldExpr::Unary { operand, .. } => atlases(operand, out),
        FieldExpr::Binary { lhs, rhs, .. } => {
            atlases(lhs, out);
            atlases(rhs, out);
        }
        FieldExpr::Swizzle { base, .. } => atlases(base, out),
        FieldExpr::Vector(a) | FieldExpr::Call { args: a, .. } => {
            a.iter().for_each(|x| atlases(x, out))
        }
    }
}

impl Checker<'_> {
    /// The checks of a `displace` call beyond its parameters' types: `band` above 1, a
    /// height whose slope can be bounded, read from at most one atlas, on the displaced
    /// shape. False after reporting a problem.
    pub(crate) fn check_displace(&mut self, bound: &[(crate::sema::Value, Span)]) -> bool {
        let mut ok = true;
        let (shape, _) = &bound[0];
        let (height, hspan) = &bound[1];
        let (band, bspan) = &bound[3];
        if let Some(t) = band.as_float() {
            if t <= 1.0 {
                self.error(
                    Diagnostic::error(
                        codes::E_OUT_OF_RANGE,
                        "`band` of `displace` must be greater than 1",
                        *bspan,
                        format!("found {}", band.display()),
                    )
                    .with_note(
                        "τ of Eq. 58: the exact displaced field is evaluated within τ times the \
                         largest displacement of the surface, and the displaced surface must lie inside",
                    ),
                );
                ok = false;
            }
        }
        ok &= self.check_read_field(shape, height, *hspan, "the height of `displace`");
        ok
    }

    /// A surface field a shape reads at the projection onto its base (a displacement's
    /// height, a shell map's uv): its slope must be bounded, and it may read one atlas,
    /// on the base shape. False after reporting a problem.
    fn check_read_field(&mut self, shape: &Value, field: &Value, span: Span, what: &str) -> bool {
        let mut ok = true;
        let height = field;
        if let Some(why) = unbounded(height) {
            self.error(
                Diagnostic::error(
                    codes::E_DISPLACE_HEIGHT,
                    format!("{what} must have a bounded slope"),
                    span,
                    why,
                )
                .with_note(
                    "the sphere tracer divides its steps by a bound of the displaced field's \
                     gradient, which comes from the height's slope",
                )
                .with_help("use textures, `position`, an atlas's `uv` or `distance`, and smooth math (sin, mix, clamp, …)"),
            );
            ok = false;
        }
        let mut read = Vec::new();
        atlases(height, &mut read);
        for (i, &k) in read.iter().enumerate() {
            let def = self.prog.atlas(k).clone();
            if i > 0 {
                self.error(
                    Diagnostic::error(
                        codes::E_DISPLACE_ATLAS,
                        format!(
                            "{what} reads two atlases, `{}` and `{}`",
                            self.prog.atlas(read[0]).name,
                            def.name
                        ),
                        span,
                        "one atlas per field",
                    )
                    .with_help("read one atlas"),
                );
                ok = false;
            } else if !same_shape(&def.shape, shape) && !def.shape.is_error() && !shape.is_error() {
                self.error(
                    Diagnostic::error(
                        codes::E_DISPLACE_ATLAS,
                        format!(
                            "{what} reads atlas `{}`, which is on another shape",
                            def.name
                        ),
                        span,
                        format!("reads `{}`", def.name),
                    )
                    .with_label(
                        def.shape_span,
                        format!("atlas `{}` is on this shape", def.name),
                    )
                    .with_note(
                        "it is read at the projection of each point onto the base shape's surface \
                         (Eq. 57), where only an atlas on that surface has coordinates",
                    )
                    .with_help(
                        "declare an atlas on the base shape, or use the atlas's shape as the base",
                    ),
                );
                ok = false;
            }
        }
        ok
    }

    /// The checks of a `shell_map` call beyond its parameters' types: a positive
    /// thickness and a uv read as a displacement's height is.
    pub(crate) fn check_shell_map(&mut self, bound: &[(crate::sema::Value, Span)]) -> bool {
        let (shape, _) = &bound[0];
        let (uv, uspan) = &bound[2];
        let (eps, espan) = &bound[3];
        let mut ok = true;
        if eps.as_float().is_some_and(|e| !(e > 0.0)) {
            self.error(Diagnostic::error(
                codes::E_OUT_OF_RANGE,
                "`thickness` of `shell_map` must be positive",
                *espan,
                format!("found {}", eps.display()),
            ));
            ok = false;
        }
        ok & self.check_read_field(shape, uv, *uspan, "the uv of `shell_map`")
    }

    /// An atlas on a shape with a displacement (or a shell map) works, at a cost worth a
    /// note: its walks differentiate the displaced field, each evaluation of which walks
    /// the height's atlas.
    pub(crate) fn check_atlas_shape(&mut self, shape: &Value, span: Span) {
        if let Some(call) = displaced(shape) {
            self.error(
                Diagnostic::note_diag(
                    codes::N_ATLAS_ON_DISPLACED,
                    "this atlas is on a displaced shape: each step of its walks evaluates the base's atlas",
                    span,
                    "this shape is displaced",
                )
                .with_label(call, "displaced or shell-mapped here")
                .with_note(
                    "the walk of Alg. 1 differentiates the displaced field, whose every \
                     evaluation projects onto the base and walks the height's atlas, so this \
                     atlas costs about that atlas times 7 per step; a material on the displaced \
                     shape can also read the base's atlas, which is cheaper",
                ),
            );
        }
    }
}

/// The shape with every displacement replaced by its base: the plain textured scene a
/// displacement's cost is measured against (`sdfc bench`).
pub fn undisplaced(v: &Value) -> Value {
    let Value::Shape(n) = v else { return v.clone() };
    if matches!(n.builtin, BuiltinId::Displace | BuiltinId::ShellMap) {
        return undisplaced(&n.args[0]);
    }
    if displaced(v).is_none() {
        return v.clone();
    }
    let mut node = (**n).clone();
    node.args = n.args.iter().map(undisplaced).collect();
    Value::Shape(std::sync::Arc::new(node))
}
