//! Material fields as WGSL expressions: the checked program's surface fields (uv
//! reads, texture samples, builtins on numbers and vectors) with every constant folded
//! in, and the textures and atlases they use.

use super::emit::lit;
use crate::sema::builtins::BuiltinId;
use crate::sema::math::{self, Math};
use crate::sema::{AtlasAttr, AtlasId, FieldExpr, SurfaceInput, Ty, Value};
use crate::syntax::ast::{BinaryOp, UnaryOp};

/// What a surface field needs that the generator cannot give yet.
#[derive(Debug, Clone, PartialEq)]
pub struct Unsupported(pub String);

fn wgsl_ty(t: &Ty) -> String {
    match t {
        Ty::Vec(n) => format!("vec{n}<f32>"),
        Ty::Bool => String::from("bool"),
        _ => String::from("f32"),
    }
}

/// A texture binding the module needs: an image file with a wrap mode.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct TextureUse {
    pub path: String,
    pub wrap: String,
    /// Colour (decoded from sRGB) or data (linear).
    pub srgb: bool,
}

/// What surface fields need from the module: textures in binding order (texture `i`
/// binds at 1 + 2i, its sampler at 2 + 2i) and the atlases they sample.
#[derive(Debug, Default)]
pub struct Uses {
    pub textures: Vec<TextureUse>,
    /// Atlas indices read by the expressions generated since the last reset.
    pub atlases: std::collections::BTreeSet<AtlasId>,
    /// Atlases whose `seed` or `transport` some expression read, ever (not reset): the
    /// multi-scale pass keeps their rebuilt pixels within one seed's region.
    pub discrete: std::collections::BTreeSet<AtlasId>,
    /// While set, atlas uv and position are generated displaced by these WGSL
    /// expressions: the footprint of a pixel, for texture derivatives.
    pub offset: Option<(String, String)>,
    /// Whether textures sampled now hold colour (sRGB) rather than data (linear).
    pub srgb: bool,
    /// `let` statements of the function being generated, which long expressions are
    /// bound to: generated expressions stay shallow (within naga's recursion limit)
    /// however deep the field, and a value shared by `let`s in the scene is computed once.
    pub lets: Vec<String>,
    /// The bound name of each shared field value already generated (by node and offset).
    bound: std::collections::HashMap<BoundKey, String>,
}

/// A field node as generated under one footprint offset.
type BoundKey = (*const FieldExpr, Option<(String, String)>);

/// Expressions longer than this are bound to a `let` (which bounds their nesting).
const MAX_INLINE_EXPRESSION: usize = 160;

impl Uses {
    /// Starts the statements of a new function.
    pub fn start_function(&mut self) {
        self.lets.clear();
        self.bound.clear();
        self.atlases.clear();
    }

    fn index(&mut self, path: &str, wrap: &str) -> usize {
        let u = TextureUse {
            path: path.to_string(),
            wrap: wrap.to_string(),
            srgb: self.srgb,
        };
        if let Some(i) = self.textures.iter().position(|x| *x == u) {
            return i;
        }
        self.textures.push(u);
        self.textures.len() - 1
    }
}

/// A surface field (or constant) as a WGSL expression over `p` (position) and `n`
/// (normal), with the statements it needs in [`Uses::lets`].
pub fn field(v: &Value, tex: &mut Uses) -> Result<String, Unsupported> {
    let Value::Field(expr, _) = v else {
        return field_expr(v, tex);
    };
    let key = (std::sync::Arc::as_ptr(expr), tex.offset.clone());
    if let Some(name) = tex.bound.get(&key) {
        return Ok(name.clone());
    }
    let e = field_expr(v, tex)?;
    let shared = std::sync::Arc::strong_count(expr) > 1;
    if e.len() <= MAX_INLINE_EXPRESSION && !(shared && e.len() > 24) {
        return Ok(e);
    }
    let name = format!("v{}", tex.lets.len());
    tex.lets.push(format!("let {name} = {e};"));
    tex.bound.insert(key, name.clone());
    Ok(name)
}

fn field_expr(v: &Value, tex: &mut Uses) -> Result<String, Unsupported> {
    stacker::maybe_grow(64 * 1024, 1024 * 1024, || field_expr_inner(v, tex))
}

fn field_expr_inner(v: &Value, tex: &mut Uses) -> Result<String, Unsupported> {
    Ok(match v {
        Value::Float(x) => lit(*x),
        Value::Bool(b) => b.to_string(),
        Value::Vec(c) => format!(
            "vec{}<f32>({})",
            c.len(),
            c.iter().map(|x| lit(*x)).collect::<Vec<_>>().join(", ")
        ),
        Value::Uniform(u) => {
            let ty = v.ty();
            field_expr_inner(&Value::Field(u.expr.clone(), ty), tex)?
        }
        Value::Field(expr, ty) => match &**expr {
            FieldExpr::Param(p) => format!("params.{}", super::params::member(&p.name)),
            FieldExpr::Input(SurfaceInput::Position) => match &tex.offset {
                Some((_, dp)) => format!("(p + {dp})"),
                None => String::from("p"),
            },
            FieldExpr::Input(SurfaceInput::Normal) => String::from("n"),
            FieldExpr::Atlas { atlas, attr } => {
                tex.atlases.insert(*atlas);
                if matches!(attr, AtlasAttr::Transport | AtlasAttr::Seed) {
                    tex.discrete.insert(*atlas);
                }
                let name = match attr {
                    AtlasAttr::Uv => "uv",
                    AtlasAttr::Distance => "distance",
                    AtlasAttr::Status => "status",
                    AtlasAttr::Transport => "transport",
                    AtlasAttr::Seed => "seed",
                };
                match (&tex.offset, attr) {
                    (Some((du, _)), AtlasAttr::Uv) => {
                        format!("(atlas_sample_{}.uv + {du})", atlas.index())
                    }
                    _ => format!("atlas_sample_{}.{name}", atlas.index()),
                }
            }
            FieldExpr::Unary { op, operand } => {
                let o = field(operand, tex)?;
                match op {
                    UnaryOp::Neg => format!("(-{o})"),
                    UnaryOp::Not => format!("(!{o})"),
                }
            }
            FieldExpr::Binary { op, lhs, rhs } => binary(*op, lhs, rhs, ty, tex)?,
            FieldExpr::Swizzle { base, components } => {
                let s: String = components
                    .iter()
                    .map(|c| ['x', 'y', 'z', 'w'][*c as usize])
                    .collect();
                format!("({}).{s}", field(base, tex)?)
            }
            FieldExpr::Call { builtin, args } => call(*builtin, args, tex)?,
            FieldExpr::Vector(args) => format!(
                "{}({})",
                wgsl_ty(ty),
                args.iter()
                    .map(|a| field(a, tex))
                    .collect::<Result<Vec<_>, _>>()?
                    .join(", ")
            ),
        },
        other => {
            return Err(Unsupported(format!(
                "a {} cannot be used per point",
                other.ty()
            )))
        }
    })
}

/// Broadcasts a float operand to the vector type of the result where WGSL needs it.
fn widen(v: &Value, to: &Ty, tex: &mut Uses) -> Result<String, Unsupported> {
    let e = field(v, tex)?;
    Ok(match (v.ty().base(), to) {
        (Ty::Float, Ty::Vec(n)) => format!("vec{n}<f32>({e})"),
        _ => e,
    })
}

fn binary(
    op: BinaryOp,
    l: &Value,
    r: &Value,
    ty: &Ty,
    tex: &mut Uses,
) -> Result<String, Unsupported> {
    let numeric = match (l.ty().base(), r.ty().base()) {
        (Ty::Vec(n), _) | (_, Ty::Vec(n)) => Ty::Vec(*n),
        _ => Ty::Float,
    };
    let (a, b) = (widen(l, &numeric, tex)?, widen(r, &numeric, tex)?);
    let vectors = matches!(numeric, Ty::Vec(_)) && *ty == Ty::Bool;
    Ok(math::wgsl_binary(op, &a, &b, vectors))
}

fn call(builtin: BuiltinId, args: &[Value], tex: &mut Uses) -> Result<String, Unsupported> {
    use BuiltinId as B;
    let name = builtin.name();
    let t_ty = args
        .iter()
        .map(|a| a.ty().base().clone())
        .find(|t| matches!(t, Ty::Vec(_)))
        .unwrap_or(Ty::Float);
    if let Some(m) = Math::of(builtin) {
        // The row's WGSL function, on arguments widened to the call's type.
        let written = args
            .iter()
            .map(|a| {
                if m.widens() {
                    widen(a, &t_ty, tex)
                } else {
                    field(a, tex)
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        return Ok(m.wgsl_call(&written, t_ty == Ty::Float));
    }
    let mut f = |v: &Value| field(v, tex);
    Ok(match builtin {
        B::Checker => format!("sdfc_checker({}, {})", f(&args[0])?, f(&args[1])?),
        B::Grid => format!(
            "sdfc_grid({}, {}, {})",
            f(&args[0])?,
            f(&args[1])?,
            f(&args[2])?
        ),
        B::Sample => sample(args, 2, tex)?,
        B::SampleNormal => {
            let [_, uv, strength, Value::Str(convention), _] = args else {
                return Err(Unsupported(String::from(
                    "a normal map needs a texture, uv, strength, convention and wrap mode",
                )));
            };
            let atlases = uv.atlases();
            let (Some(k), 1) = (atlases.first(), atlases.len()) else {
                return Err(Unsupported(String::from(
                    "a normal map's uv must read one atlas",
                )));
            };
            // Normal maps are data: sampled linear whatever field they are used in.
            let saved = std::mem::replace(&mut tex.srgb, false);
            let texel = sample(args, 4, tex);
            tex.srgb = saved;
            let texel = texel?;
            tex.atlases.insert(*k);
            let strength = field(strength, tex)?;
            let green = lit(crate::reference::material::green_sign(convention));
            let a = format!("atlas_sample_{}", k.index());
            format!("sdfc_normal_map({texel}, {a}.tangent, {a}.bitangent, n, {strength}, {green})")
        }
        // Shapes, images and render settings; math builtins are written above.
        _ => return Err(Unsupported(format!("`{name}` is not a surface field"))),
    })
}

/// `textureSampleGrad` of `args[0]` at uv `args[1]` with the wrap mode `args[wrap]`,
/// in the colour space `tex.srgb` says.
fn sample(args: &[Value], wrap: usize, tex: &mut Uses) -> Result<String, Unsupported> {
    let (Some(Value::Texture(node)), Some(Value::Str(wrap))) = (args.first(), args.get(wrap))
    else {
        return Err(Unsupported(String::from(
            "a texture sample needs an image and a wrap mode",
        )));
    };
    let Some(Value::Str(path)) = node.args.first() else {
        return Err(Unsupported(String::from("a texture sample needs an image")));
    };
    // Texture derivatives from the pixel's footprint, analytically: the uv
    // expression at the point and displaced by one footprint along two tangent
    // directions (atlas uv moves isometrically, position along the surface). Unlike
    // screen-space derivatives they cannot explode at uv seams, and they are valid
    // in the non-uniform control flow after sphere tracing.
    let uv = field(&args[1], tex)?;
    let saved = tex.offset.take();
    tex.offset = Some((
        String::from("vec2<f32>(footprint, 0.0)"),
        String::from("tangent_u * footprint"),
    ));
    let ux = field(&args[1], tex)?;
    tex.offset = Some((
        String::from("vec2<f32>(0.0, footprint)"),
        String::from("tangent_v * footprint"),
    ));
    let uy = field(&args[1], tex)?;
    tex.offset = saved;
    let i = tex.index(path, wrap);
    Ok(format!(
        "textureSampleGrad(texture_{i}, sampler_{i}, {uv}, {ux} - {uv}, {uy} - {uv})"
    ))
}
