//! The CPU reference (f64) of the scene's materials: an interpreter of the material
//! fields ([`FieldExpr`] trees) that mirrors, case by case, the WGSL that
//! `codegen::field::field` writes into `scene_material(id, p, n, footprint)`.
//!
//! What it mirrors:
//! - the material ids of `scene_map` (0 the default material, i + 1 `materials[i]`,
//!   anything else the default, as the generated `switch` does) and the defaults of
//!   attributes a material leaves out (the checked program already holds them);
//! - a `color` given as a float (splat to rgb) or a vec4 (its rgb);
//! - `tangent_u`/`tangent_v` of the generated function, and the texture derivatives of
//!   `sample`: its uv expression again with atlas uv displaced by one footprint along u
//!   (then v) and `position` displaced by one footprint along `tangent_u` (`tangent_v`);
//!   the normal and the other atlas attributes are not displaced;
//! - the atlas attributes of the generated `atlas_K(p)` ([`AtlasValues`]), sampled once
//!   per evaluation at `p`, failed statuses included (uv 0, distance 3e38, identity
//!   transport);
//! - every builtin the emitter accepts in a field, the math builtins and operators by
//!   their one definition in `sema::math` (which the constant folder and the emitter
//!   read too, so folded and run values agree), and textures through
//!   [`texture::MipChain::sample_grad`] (sRGB-decoded in `color` and `emission`, linear
//!   in `roughness` and `metallic`, as the emitter picks the texture format).
//!
//! The GPU computes in f32 with constants rounded to f32. Where a field is
//! discontinuous (`floor`, `fract`, `step`, `checker`, comparisons, …) the two may
//! land on different sides of a jump: [`Evaluated::margin`] says how far the point's
//! arguments were from the nearest jump, so that comparisons can leave such points out.

mod interp;

use interp::{is_field_builtin, Cx, V};

pub use crate::ir::texture::{self, MipChain, Textures, Wrap};

use crate::ir::eval;
use crate::sema::builtins::BuiltinId;
use crate::sema::{AtlasAttr, AtlasId, FieldExpr, MaterialAttrs, Program, SurfaceInput, Ty, Value};
use crate::syntax::ast::{BinaryOp, UnaryOp};
use crate::uv::{Atlas, Sample};
use glam::{DMat3, DVec2, DVec3, DVec4};

/// A material evaluated at a point: the generated `Material` struct, in f64.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialValue {
    pub color: DVec3,
    pub roughness: f64,
    pub metallic: f64,
    pub emission: DVec3,
    /// The unit shading normal: the material's `normal` normalized (the surface normal
    /// where it is zero or not finite), as `fs_main` shades with it.
    pub normal: DVec3,
}

/// A material value with the distance of its discontinuous arguments from their
/// nearest jump (in each argument's own units; `f64::INFINITY` when nothing jumps).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluated {
    pub value: MaterialValue,
    pub margin: f64,
}

/// What the generated `atlas_K(p)` gives a material (the WGSL `AtlasSample`'s
/// attributes), in the shader's conventions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtlasValues {
    /// Alg. 2's blended uv in the atlas's common uv space; 0 where the sample failed.
    pub uv: DVec2,
    /// Geodesic distance; 3e38 (the shader's "infinite") where the sample failed.
    pub distance: f64,
    /// `Status::code` as a float.
    pub status: f64,
    /// Parallel transport as a unit quaternion (x, y, z, w), by the shader's formula.
    pub transport: DVec4,
    /// The chosen seed (on failure the nearest seed that failed), or -1.
    pub seed: f64,
    /// The blended transported seed frame ([`Sample::tangent`], [`Sample::bitangent`]);
    /// zero where the sample failed.
    pub tangent: DVec3,
    pub bitangent: DVec3,
}

/// The shader's "infinite" distance of a failed sample (`uv_failed`).
const FAILED_DISTANCE: f64 = 3.0e38;

impl AtlasValues {
    /// `uv_failed(UV_TOO_FAR, -1.0)`: what a module without the atlas gives.
    pub const FAILED: AtlasValues = AtlasValues {
        uv: DVec2::ZERO,
        distance: FAILED_DISTANCE,
        status: 1.0,
        transport: DVec4::new(0.0, 0.0, 0.0, 1.0),
        seed: -1.0,
        tangent: DVec3::ZERO,
        bitangent: DVec3::ZERO,
    };

    /// The values of a CPU atlas sample ([`Atlas::sample`]).
    pub fn from_sample(s: &Sample) -> AtlasValues {
        let ok = s.status.code() == 0;
        AtlasValues {
            uv: if ok { s.uv } else { DVec2::ZERO },
            distance: if ok && s.distance.is_finite() {
                s.distance
            } else {
                FAILED_DISTANCE
            },
            status: s.status.code() as f64,
            transport: if ok {
                quaternion(&s.transport)
            } else {
                DVec4::new(0.0, 0.0, 0.0, 1.0)
            },
            seed: s.seed.map_or(-1.0, |i| i as f64),
            tangent: if ok { s.tangent } else { DVec3::ZERO },
            bitangent: if ok { s.bitangent } else { DVec3::ZERO },
        }
    }
}

/// `uv_quaternion` of shaders/uv.wgsl (same branches, so the same sign) in f64.
pub fn quaternion(m: &DMat3) -> DVec4 {
    let (c0, c1, c2) = (m.x_axis, m.y_axis, m.z_axis);
    let t = c0.x + c1.y + c2.z;
    let q = if t > 0.0 {
        let s = (t + 1.0).sqrt() * 2.0;
        DVec4::new(
            (c1.z - c2.y) / s,
            (c2.x - c0.z) / s,
            (c0.y - c1.x) / s,
            0.25 * s,
        )
    } else if c0.x > c1.y && c0.x > c2.z {
        let s = (1.0 + c0.x - c1.y - c2.z).sqrt() * 2.0;
        DVec4::new(
            0.25 * s,
            (c1.x + c0.y) / s,
            (c2.x + c0.z) / s,
            (c1.z - c2.y) / s,
        )
    } else if c1.y > c2.z {
        let s = (1.0 + c1.y - c0.x - c2.z).sqrt() * 2.0;
        DVec4::new(
            (c1.x + c0.y) / s,
            0.25 * s,
            (c2.y + c1.z) / s,
            (c2.x - c0.z) / s,
        )
    } else {
        let s = (1.0 + c2.z - c0.x - c1.y).sqrt() * 2.0;
        DVec4::new(
            (c2.x + c0.z) / s,
            (c2.y + c1.z) / s,
            0.25 * s,
            (c0.y - c1.x) / s,
        )
    };
    q.normalize()
}

/// The tangent frame of the generated `scene_material`: (tangent_u, tangent_v).
pub fn tangents(n: DVec3) -> (DVec3, DVec3) {
    let u = if n.z.abs() > 0.9 {
        n.cross(DVec3::X)
    } else {
        n.cross(DVec3::Z)
    }
    .normalize();
    (u, n.cross(u))
}

/// `sdfc_normalize_or` of shaders/render.wgsl: `v` normalized, or `fallback` where
/// `v` is (nearly) zero or not finite.
pub fn sdfc_normalize_or(v: DVec3, fallback: DVec3) -> DVec3 {
    let l = v.length();
    if l > 1e-20 && l.is_finite() {
        v / l
    } else {
        fallback
    }
}

/// The sign of a normal map's green along e2 (+v): sdfc's v runs down the image, so an
/// OpenGL-convention map (green up the image) is negated and a DirectX one is not.
pub fn green_sign(convention: &str) -> f64 {
    if convention == "dx" {
        1.0
    } else {
        -1.0
    }
}

/// `sdfc_normal_map` of shaders/render.wgsl (Eqs. 50 and 52): the texel's rgb decoded
/// to a tangent-space normal (rgb·2 − 1, green times `green` = [`green_sign`]), its
/// tangent part scaled by `strength`, in the transported frame (t, b) re-orthonormalized
/// about the unit normal n. The surface normal where the frame is degenerate.
pub fn normal_map(texel: DVec3, t: DVec3, b: DVec3, n: DVec3, strength: f64, green: f64) -> DVec3 {
    let Some((t, b)) = crate::uv::atlas::tangent_frame(t, b, n) else {
        return n;
    };
    let c = texel * 2.0 - DVec3::ONE;
    let (x, y) = (c.x * strength, c.y * green * strength);
    sdfc_normalize_or(t * x + b * y + n * c.z, n)
}

/// The materials of a checked program, ready to evaluate on the CPU.
pub struct MaterialEval<'a> {
    program: &'a Program,
    atlases: &'a [Option<Atlas>],
    textures: Textures,
    default: MaterialAttrs,
}

impl<'a> MaterialEval<'a> {
    /// The materials of `program` with its prepared atlases (one per atlas of the
    /// program, as `driver::Analysis::atlases` holds them) and its decoded textures.
    /// Fails when a material needs what the WGSL generator would also refuse, or a
    /// texture that `textures` lacks.
    pub fn new(
        program: &'a Program,
        atlases: &'a [Option<Atlas>],
        textures: Textures,
    ) -> Result<MaterialEval<'a>, String> {
        if atlases.len() != program.atlases.len() {
            return Err(format!(
                "{} prepared atlases for {} atlases",
                atlases.len(),
                program.atlases.len()
            ));
        }
        let eval = MaterialEval {
            program,
            atlases,
            textures,
            default: MaterialAttrs::default(),
        };
        for m in &program.materials {
            for v in [
                &m.attrs.color,
                &m.attrs.roughness,
                &m.attrs.metallic,
                &m.attrs.emission,
                &m.attrs.normal,
            ] {
                eval.validate(v)
                    .map_err(|e| format!("material `{}`: {e}", m.name))?;
            }
        }
        Ok(eval)
    }

    /// [`MaterialEval::new`] with the program's textures decoded from the files that
    /// were resolved (inside the allowed folders) when it was checked.
    pub fn load(
        program: &'a Program,
        atlases: &'a [Option<Atlas>],
    ) -> Result<MaterialEval<'a>, String> {
        MaterialEval::new(program, atlases, Textures::load(program)?)
    }

    pub fn textures(&self) -> &Textures {
        &self.textures
    }

    /// The attributes of material `id` as `scene_material` switches on it.
    pub fn attrs(&self, id: u32) -> &MaterialAttrs {
        match (id as usize).checked_sub(1) {
            Some(i) if id <= i32::MAX as u32 && i < self.program.materials.len() => {
                &self.program.materials[i].attrs
            }
            _ => &self.default,
        }
    }

    /// The generated `atlas_K_at(p)` on the CPU: Alg. 2 of the prepared atlas at the
    /// rest point of `p` ([`Atlas::sample_at`]).
    pub fn atlas_values(&self, atlas: AtlasId, p: DVec3) -> AtlasValues {
        match self.atlases.get(atlas.index()) {
            Some(Some(a)) => AtlasValues::from_sample(&a.sample_at(p)),
            _ => AtlasValues::FAILED,
        }
    }

    /// `scene_material(id, p, n, footprint)`: material `id` (as `scene_map` gives it)
    /// at surface point `p` with unit normal `n`, for a pixel `footprint` wide.
    pub fn eval(&self, id: u32, p: DVec3, n: DVec3, footprint: f64) -> MaterialValue {
        self.eval_with(id, p, n, footprint, &mut |k| self.atlas_values(k, p))
            .value
    }

    /// The generated `scene_surface` at surface point `p` of the render target `shape`
    /// (with its heights' environment where it has displacements):
    /// the materials of [`eval::eval_blend`], mixed with b's weight across a smooth
    /// union's band (textured CSG), the normal renormalized.
    pub fn eval_surface<'s>(
        &self,
        shape: impl Into<eval::Field<'s>>,
        p: DVec3,
        n: DVec3,
        footprint: f64,
    ) -> MaterialValue {
        let (_, bl) = eval::eval_blend(shape, p);
        let a = self.eval(bl.a, p, n, footprint);
        if bl.t <= 0.0 {
            return a;
        }
        let b = self.eval(bl.b, p, n, footprint);
        let t = bl.t;
        MaterialValue {
            color: a.color.lerp(b.color, t),
            roughness: a.roughness + (b.roughness - a.roughness) * t,
            metallic: a.metallic + (b.metallic - a.metallic) * t,
            emission: a.emission.lerp(b.emission, t),
            normal: sdfc_normalize_or(a.normal.lerp(b.normal, t), n),
        }
    }

    /// [`MaterialEval::eval`] with the atlas attributes given by `atlas` (called at most
    /// once per atlas), e.g. the GPU's own atlas samples, to compare the material
    /// interpreters alone; with the margin of discontinuities.
    pub fn eval_with(
        &self,
        id: u32,
        p: DVec3,
        n: DVec3,
        footprint: f64,
        atlas: &mut dyn FnMut(AtlasId) -> AtlasValues,
    ) -> Evaluated {
        let (tangent_u, tangent_v) = tangents(n);
        let mut cx = Cx {
            textures: &self.textures,
            atlas,
            samples: vec![None; self.atlases.len()],
            p,
            n,
            footprint,
            tangent_u,
            tangent_v,
            offset: None,
            srgb: false,
            margin: f64::INFINITY,
        };
        let m = self.attrs(id);
        cx.srgb = true;
        let c = cx.value(&m.color);
        let color = match c {
            V::Num(c, 1) => DVec3::splat(c[0]),
            V::Num(c, _) => DVec3::new(c[0], c[1], c[2]),
            V::Bool(_) => DVec3::ZERO,
        };
        cx.srgb = false;
        let roughness = cx.value(&m.roughness).x();
        let metallic = cx.value(&m.metallic).x();
        cx.srgb = true;
        let emission = match cx.value(&m.emission) {
            V::Num(c, 1) => DVec3::splat(c[0]),
            V::Num(c, _) => DVec3::new(c[0], c[1], c[2]),
            V::Bool(_) => DVec3::ZERO,
        };
        // As the emitter: the surface normal as is, anything else normalized.
        let normal = match &m.normal {
            Value::Field(e, _) if **e == FieldExpr::Input(SurfaceInput::Normal) => n,
            v => sdfc_normalize_or(cx.value(v).vec3(), n),
        };
        Evaluated {
            value: MaterialValue {
                color,
                roughness,
                metallic,
                emission,
                normal,
            },
            margin: cx.margin,
        }
    }

    /// Rejects what `codegen::field::field` rejects, and textures without an image.
    fn validate(&self, v: &Value) -> Result<(), String> {
        match v {
            Value::Float(_) | Value::Vec(_) | Value::Bool(_) | Value::Uniform(_) => Ok(()),
            Value::Field(e, _) => match &**e {
                FieldExpr::Param(_) => Err(String::from("a parameter outside a run-time value")),
                FieldExpr::Input(_) => Ok(()),
                FieldExpr::Atlas { atlas, .. } if atlas.index() < self.atlases.len() => Ok(()),
                FieldExpr::Atlas { .. } => Err(String::from("an atlas outside the program")),
                FieldExpr::Unary { operand, .. } => self.validate(operand),
                FieldExpr::Binary { lhs, rhs, .. } => {
                    self.validate(lhs)?;
                    self.validate(rhs)
                }
                FieldExpr::Swizzle { base, .. } => self.validate(base),
                FieldExpr::Vector(args) => args.iter().try_for_each(|a| self.validate(a)),
                FieldExpr::Call {
                    builtin: builtin @ (BuiltinId::Sample | BuiltinId::SampleNormal),
                    args,
                } => {
                    let wrap = if *builtin == BuiltinId::Sample { 2 } else { 4 };
                    let (Some(Value::Texture(node)), Some(Value::Str(_))) =
                        (args.first(), args.get(wrap))
                    else {
                        return Err(String::from(
                            "a texture sample needs an image and a wrap mode",
                        ));
                    };
                    let Some(Value::Str(path)) = node.args.first() else {
                        return Err(String::from("a texture sample needs an image"));
                    };
                    if self.textures.get(path).is_none() {
                        return Err(format!("no decoded image for texture \"{path}\""));
                    }
                    if *builtin == BuiltinId::SampleNormal && args[1].atlases().len() != 1 {
                        return Err(String::from("a normal map's uv must read one atlas"));
                    }
                    // The uv, and a normal map's strength (its other arguments are
                    // constant strings).
                    let fields = if *builtin == BuiltinId::Sample {
                        1..2
                    } else {
                        1..3
                    };
                    args[fields].iter().try_for_each(|a| self.validate(a))
                }
                FieldExpr::Call { builtin, args } => {
                    if !is_field_builtin(*builtin) {
                        return Err(format!("`{}` is not a surface field", builtin.name()));
                    }
                    args.iter().try_for_each(|a| self.validate(a))
                }
            },
            other => Err(format!("a {} cannot be used per point", other.ty())),
        }
    }
}

/// A float surface field at surface point `p` with unit normal `n`, its textures read
/// in level 0 (a zero footprint: `textureSampleGrad` with zero derivatives) and as data
/// (linear): the generated `height_K(p, n)` of a displacement, on the CPU. `atlas` gives
/// the atlas attributes (called at most once per atlas); `atlas_count` is the program's
/// number of atlases.
pub fn eval_scalar(
    value: &Value,
    p: DVec3,
    n: DVec3,
    textures: &Textures,
    atlas_count: usize,
    atlas: &mut dyn FnMut(AtlasId) -> AtlasValues,
) -> f64 {
    eval_data(value, p, n, textures, atlas_count, atlas)[0]
}

/// [`eval_scalar`] for a vec2 field (a shell map's uv): its first two components.
pub fn eval_vec2(
    value: &Value,
    p: DVec3,
    n: DVec3,
    textures: &Textures,
    atlas_count: usize,
    atlas: &mut dyn FnMut(AtlasId) -> AtlasValues,
) -> DVec2 {
    let c = eval_data(value, p, n, textures, atlas_count, atlas);
    DVec2::new(c[0], c[1])
}

/// A surface field's components as data at level 0 (see [`eval_scalar`]); zero for a
/// boolean.
fn eval_data(
    value: &Value,
    p: DVec3,
    n: DVec3,
    textures: &Textures,
    atlas_count: usize,
    atlas: &mut dyn FnMut(AtlasId) -> AtlasValues,
) -> [f64; 4] {
    let (tangent_u, tangent_v) = tangents(n);
    let mut cx = Cx {
        textures,
        atlas,
        samples: vec![None; atlas_count],
        p,
        n,
        footprint: 0.0,
        tangent_u,
        tangent_v,
        offset: None,
        srgb: false,
        margin: f64::INFINITY,
    };
    match cx.value(value) {
        V::Num(c, _) => c,
        V::Bool(_) => [0.0; 4],
    }
}
