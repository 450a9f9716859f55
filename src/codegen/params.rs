//! The run-time parameters' uniform block (`struct Params`, `@group(0)`): its WGSL and
//! its layout, laid out by the compiler from the program's parameters. The manifest
//! describes it (name, offset, type, default, range), hosts fill it, and the generated
//! code reads run-time values from it ([`crate::sema::Uniform`]).

use crate::sema::ParamDef;
use serde::Serialize;

/// The WGSL member of parameter `name` in `struct Params`.
pub fn member(name: &str) -> String {
    format!("p_{name}")
}

/// A parameter's field in the block.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamField {
    /// The parameter's name in the scene (`time` for time).
    pub name: String,
    /// Its member in `struct Params`.
    pub member: String,
    /// Byte offset in the block.
    pub offset: u32,
    /// `f32`, `vec2<f32>`, `vec3<f32>` or `vec4<f32>`.
    #[serde(rename = "type")]
    pub ty: String,
    /// Its value when the host sets nothing (the scene's default, or what `--param` set).
    pub default: Vec<f64>,
    /// Every value a host sets must lie in `[min, max]` (per component); the compiler's
    /// step bounds hold over it. `max` is null when unbounded (`time`).
    pub min: f64,
    pub max: Option<f64>,
}

/// The block's layout: its fields and its size in bytes (a multiple of 16).
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct ParamsLayout {
    pub fields: Vec<ParamField>,
    pub size: u32,
}

impl ParamsLayout {
    /// WGSL's uniform layout of the program's parameters, in order (`time` first): an
    /// `f32` aligns to 4 bytes, a `vec2` to 8, a `vec3` or `vec4` to 16.
    pub fn of(params: &[ParamDef]) -> ParamsLayout {
        let mut offset = 0u32;
        let mut fields = Vec::new();
        for p in params {
            let (align, size) = match p.size {
                1 => (4, 4),
                2 => (8, 8),
                3 => (16, 12),
                _ => (16, 16),
            };
            offset = offset.div_ceil(align) * align;
            fields.push(ParamField {
                name: p.name.clone(),
                member: member(&p.name),
                offset,
                ty: if p.size == 1 {
                    String::from("f32")
                } else {
                    format!("vec{}<f32>", p.size)
                },
                default: p.value.clone(),
                min: p.range.0,
                max: p.range.1.is_finite().then_some(p.range.1),
            });
            offset += size;
        }
        ParamsLayout {
            fields,
            size: offset.div_ceil(16).max(1) * 16,
        }
    }

    /// `struct Params { … }`, or nothing without parameters.
    pub fn wgsl_struct(&self) -> String {
        if self.fields.is_empty() {
            return String::new();
        }
        let mut s = String::from(
            "// The run-time parameters (the manifest's `params`): set by the host per frame.\nstruct Params {\n",
        );
        for f in &self.fields {
            s.push_str(&format!("    {}: {},\n", f.member, f.ty));
        }
        s.push_str("}\n");
        s
    }

    /// The block's bytes with every field at `values` (by name; the defaults for the
    /// others): what a host uploads.
    pub fn bytes(&self, values: &dyn Fn(&str) -> Option<Vec<f64>>) -> Vec<u8> {
        let mut out = vec![0u8; self.size as usize];
        for f in &self.fields {
            let v = values(&f.name).unwrap_or_else(|| f.default.clone());
            for (i, x) in v.iter().enumerate().take(f.default.len()) {
                let at = f.offset as usize + 4 * i;
                out[at..at + 4].copy_from_slice(&(*x as f32).to_le_bytes());
            }
        }
        out
    }
}

/// A run-time value (or a constant) as a WGSL expression over `params`.
pub fn expr(v: &crate::sema::Value) -> String {
    use crate::sema::math::{self, Math};
    use crate::sema::{FieldExpr, Value};
    use crate::syntax::ast::UnaryOp;
    let lit = super::literal::lit;
    let ty_of = |v: &Value| match v.components().map_or(1, <[f64]>::len) {
        1 => String::from("f32"),
        n => format!("vec{n}<f32>"),
    };
    let e = match v {
        Value::Float(x) => return lit(*x),
        Value::Vec(c) => {
            let parts: Vec<String> = c.iter().map(|x| lit(*x)).collect();
            return format!("vec{}<f32>({})", c.len(), parts.join(", "));
        }
        Value::Uniform(u) => &u.expr,
        _ => return String::from("0.0"),
    };
    let widen = |a: &Value, to: &str| {
        let s = expr(a);
        if ty_of(a) == "f32" && to != "f32" {
            format!("{to}({s})")
        } else {
            s
        }
    };
    stacker::maybe_grow(64 * 1024, 1024 * 1024, || match &**e {
        FieldExpr::Param(p) => format!("params.{}", member(&p.name)),
        FieldExpr::Unary { op, operand } => match op {
            UnaryOp::Neg => format!("(-{})", expr(operand)),
            UnaryOp::Not => format!("(!{})", expr(operand)),
        },
        FieldExpr::Binary { op, lhs, rhs } => {
            let to = ty_of(v);
            math::wgsl_binary(*op, &widen(lhs, &to), &widen(rhs, &to), false)
        }
        FieldExpr::Vector(items) => {
            let parts: Vec<String> = items.iter().map(expr).collect();
            format!("{}({})", ty_of(v), parts.join(", "))
        }
        FieldExpr::Swizzle { base, components } => {
            let s: String = components
                .iter()
                .map(|c| ['x', 'y', 'z', 'w'][*c as usize])
                .collect();
            format!("({}).{s}", expr(base))
        }
        FieldExpr::Call { builtin, args } => match Math::of(*builtin) {
            Some(m) => {
                let t = args
                    .iter()
                    .map(ty_of)
                    .find(|t| t != "f32")
                    .unwrap_or_else(|| String::from("f32"));
                let written: Vec<String> = args
                    .iter()
                    .map(|a| if m.widens() { widen(a, &t) } else { expr(a) })
                    .collect();
                m.wgsl_call(&written, t == "f32")
            }
            None => String::from("0.0"),
        },
        FieldExpr::Input(_) | FieldExpr::Atlas { .. } => String::from("0.0"),
    })
}

/// A node's run-time number as WGSL: its value times its scale, as a `vec3<f32>`
/// when `vec3` (a float broadcast).
pub fn slot(s: &crate::ir::dynamic::Slot, vec3: bool) -> String {
    let mut e = expr(&s.value);
    let float = s.value.components().map_or(1, <[f64]>::len) == 1;
    if vec3 && float {
        e = format!("vec3<f32>({e})");
    }
    if s.scale != 1.0 {
        e = format!("({e} * {})", super::literal::lit(s.scale));
    }
    e
}
