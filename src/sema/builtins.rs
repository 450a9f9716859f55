//! The builtins table: every builtin function and constant with its signature,
//! defaults and documentation. The checker, hover, completion and signature
//! help all read this one table.

use super::show::{fmt_num, fmt_vec};

/// The type a parameter accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PTy {
    Float,
    Vec2,
    Vec3,
    Bool,
    Str,
    Shape,
    Texture,
    Material,
    /// A float or a vector; all `T` parameters of a call agree, and floats broadcast.
    T,
    /// A float (uniform) or a vec3 (per axis).
    FloatOrVec3,
    /// A colour: a float (grey), a vec3, or a vec4 whose rgb is used.
    Color,
    Camera,
    Light,
}

impl PTy {
    pub fn describe(self) -> &'static str {
        match self {
            PTy::Float => "float",
            PTy::Vec2 => "vec2",
            PTy::Vec3 => "vec3",
            PTy::Bool => "bool",
            PTy::Str => "string",
            PTy::Shape => "shape",
            PTy::Texture => "texture",
            PTy::Material => "material",
            PTy::T => "float or vector",
            PTy::FloatOrVec3 => "float or vec3",
            PTy::Color => "float, vec3 or vec4",
            PTy::Camera => "camera",
            PTy::Light => "light",
        }
    }
}

/// A default value, as the tables write it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dflt {
    F(f64),
    V(&'static [f64]),
    B(bool),
    S(&'static str),
}

impl Dflt {
    /// The default as hover, completion and signatures show it: as its folded value
    /// shows (`Value::from(d).display()`, a test keeps the two the same).
    pub fn display(self) -> String {
        match self {
            Dflt::F(x) => fmt_num(x),
            Dflt::V(v) => fmt_vec(v),
            Dflt::B(b) => b.to_string(),
            Dflt::S(s) => format!("{s:?}"),
        }
    }
}

/// `name: type = default`, or `name: type` without a default: a parameter or setting
/// as signatures, completion and signature help show it.
fn describe_slot(name: &str, ty: PTy, default: Option<Dflt>) -> String {
    match default {
        Some(d) => format!("{name}: {} = {}", ty.describe(), d.display()),
        None => format!("{name}: {}", ty.describe()),
    }
}

/// A check on a constant argument.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Check {
    None,
    /// Every component > 0.
    Positive,
    /// Every component ≥ 0.
    NonNegative,
    /// Not the zero vector (a direction or axis).
    NonZero,
    /// One of the listed strings.
    OneOf(&'static [&'static str]),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Param {
    pub name: &'static str,
    pub ty: PTy,
    pub default: Option<Dflt>,
    pub check: Check,
}

impl Param {
    /// `name: type = default`, for signatures and completion.
    pub fn describe(&self) -> String {
        describe_slot(self.name, self.ty, self.default)
    }
}

const fn p(name: &'static str, ty: PTy) -> Param {
    Param {
        name,
        ty,
        default: None,
        check: Check::None,
    }
}
const fn pos(name: &'static str, ty: PTy) -> Param {
    Param {
        name,
        ty,
        default: None,
        check: Check::Positive,
    }
}
const fn posd(name: &'static str, ty: PTy, d: Dflt) -> Param {
    Param {
        name,
        ty,
        default: Some(d),
        check: Check::Positive,
    }
}
const fn d(name: &'static str, ty: PTy, d: Dflt) -> Param {
    Param {
        name,
        ty,
        default: Some(d),
        check: Check::None,
    }
}
const fn dir(name: &'static str, v: &'static [f64]) -> Param {
    Param {
        name,
        ty: PTy::Vec3,
        default: Some(Dflt::V(v)),
        check: Check::NonZero,
    }
}

/// What a builtin returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ret {
    Shape,
    Texture,
    Camera,
    Light,
    Float,
    Vec3,
    Vec4,
    /// The unified type of the `T` parameters.
    T,
}

/// What family a builtin belongs to (for documentation, completion and lowering).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Primitive,
    Csg,
    Transform,
    Warp,
    Texture,
    Render,
    Math,
}

impl Kind {
    pub fn title(self) -> &'static str {
        match self {
            Kind::Primitive => "primitive",
            Kind::Csg => "CSG",
            Kind::Transform => "transform",
            Kind::Warp => "warp",
            Kind::Texture => "texture",
            Kind::Render => "render setting",
            Kind::Math => "math",
        }
    }

    /// Whether the builtin accepts surface fields and then returns one.
    pub fn lifts_fields(self) -> bool {
        matches!(self, Kind::Math | Kind::Texture)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Builtin {
    pub id: BuiltinId,
    pub name: &'static str,
    pub params: &'static [Param],
    pub ret: Ret,
    pub kind: Kind,
    pub doc: &'static str,
}

impl Builtin {
    pub fn param(&self, name: &str) -> Option<(usize, &Param)> {
        self.params.iter().enumerate().find(|(_, p)| p.name == name)
    }

    /// `name(param: type = default, …) -> ret`, for hover and signature help.
    pub fn signature(&self) -> String {
        let params: Vec<String> = self.params.iter().map(Param::describe).collect();
        let ret = match self.ret {
            Ret::Shape => "shape",
            Ret::Texture => "texture",
            Ret::Camera => "camera",
            Ret::Light => "light",
            Ret::Float => "float",
            Ret::Vec3 => "vec3",
            Ret::Vec4 => "vec4",
            Ret::T => "T",
        };
        format!("{}({}) -> {}", self.name, params.join(", "), ret)
    }
}

use Dflt::{F, V};
use PTy::*;

const S: Param = p("shape", Shape);
const A: Param = p("a", Shape);
const B: Param = p("b", Shape);
const K: Param = pos("k", Float);
const TX: Param = p("x", T);

/// The table: each row names its [`BuiltinId`] variant, so the enum and the table are
/// one list and cannot drift apart.
macro_rules! builtins {
    ($($(#[$attr:meta])* $id:ident: $name:literal, [$($param:expr),*], $ret:ident, $kind:ident, $doc:literal;)*) => {
        /// Every builtin function by ID, generated from the one table ([`BUILTINS`]).
        /// Lowering, folding and WGSL emission match on it exhaustively, so a new builtin
        /// that some stage does not handle fails to compile.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum BuiltinId {
            $($id,)*
        }

        /// Every builtin function, in [`BuiltinId`] order.
        pub static BUILTINS: &[Builtin] = &[
            $(Builtin { id: BuiltinId::$id, name: $name, params: &[$($param),*], ret: Ret::$ret, kind: Kind::$kind, doc: $doc },)*
        ];
    };
}

impl BuiltinId {
    /// The builtin's row of the table.
    pub fn builtin(self) -> &'static Builtin {
        &BUILTINS[self as usize]
    }

    /// The name as written in scenes.
    pub fn name(self) -> &'static str {
        self.builtin().name
    }
}

builtins! {
    // Primitives, centred at the origin.
    Sphere: "sphere", [posd("radius", Float, F(1.0))], Shape, Primitive, "A sphere of `radius` centred at the origin.";
    Box: "box", [posd("size", FloatOrVec3, F(1.0))], Shape, Primitive, "An axis-aligned box with full edge lengths `size` (a float for a cube).";
    RoundBox: "round_box", [posd("size", FloatOrVec3, F(1.0)), posd("radius", Float, F(0.1))], Shape, Primitive, "A box with edges rounded by `radius`; `size` is the outer size.";
    BoxFrame: "box_frame", [posd("size", FloatOrVec3, F(1.0)), posd("thickness", Float, F(0.05))], Shape, Primitive, "The edges of a box, as bars of `thickness`.";
    Torus: "torus", [posd("major", Float, F(1.0)), posd("minor", Float, F(0.25))], Shape, Primitive, "A torus in the xz-plane: ring radius `major`, tube radius `minor`.";
    Capsule: "capsule", [d("a", Vec3, V(&[0.0, -0.5, 0.0])), d("b", Vec3, V(&[0.0, 0.5, 0.0])), posd("radius", Float, F(0.25))], Shape, Primitive, "A capsule: all points within `radius` of the segment from `a` to `b`.";
    Cylinder: "cylinder", [posd("radius", Float, F(0.5)), posd("height", Float, F(1.0))], Shape, Primitive, "A capped cylinder along y of `radius` and total `height`.";
    Cone: "cone", [posd("radius", Float, F(0.5)), posd("height", Float, F(1.0))], Shape, Primitive, "A capped cone along y: base of `radius` at y = 0, apex at y = `height`.";
    CappedCone: "capped_cone", [posd("height", Float, F(1.0)), Param { name: "bottom", ty: Float, default: Some(F(0.5)), check: Check::NonNegative }, Param { name: "top", ty: Float, default: Some(F(0.25)), check: Check::NonNegative }], Shape, Primitive, "A truncated cone along y of total `height`, with radii `bottom` and `top`.";
    Plane: "plane", [dir("normal", &[0.0, 1.0, 0.0]), d("offset", Float, F(0.0))], Shape, Primitive, "The half-space below the plane `dot(p, normal) = offset`.";
    Ellipsoid: "ellipsoid", [posd("radii", Vec3, V(&[1.0, 0.5, 0.5]))], Shape, Primitive, "An ellipsoid with semi-axes `radii` (a bound, not an exact distance).";
    Octahedron: "octahedron", [posd("radius", Float, F(1.0))], Shape, Primitive, "A regular octahedron with vertices at distance `radius`.";
    HexPrism: "hex_prism", [posd("radius", Float, F(0.5)), posd("height", Float, F(1.0))], Shape, Primitive, "A hexagonal prism along z: inradius `radius`, total `height`.";
    TriPrism: "tri_prism", [posd("radius", Float, F(0.5)), posd("height", Float, F(1.0))], Shape, Primitive, "A triangular prism along z: inradius `radius`, total `height`.";
    Pyramid: "pyramid", [posd("height", Float, F(1.0))], Shape, Primitive, "A square pyramid with a unit base in the xz-plane and apex at y = `height`.";
    Link: "link", [posd("length", Float, F(0.5)), posd("major", Float, F(0.4)), posd("minor", Float, F(0.1))], Shape, Primitive, "A chain link: a torus stretched along y by `length`.";
    // CSG.
    Union: "union", [A, B], Shape, Csg, "Everything in `a` or `b` (also `a | b`). Each hit keeps the material of the nearer operand.";
    Intersection: "intersection", [A, B], Shape, Csg, "Everything in both `a` and `b` (also `a & b`).";
    Difference: "difference", [A, B], Shape, Csg, "`a` with `b` carved out (also `a - b`).";
    SmoothUnion: "smooth_union", [A, B, K], Shape, Csg, "Union blended over a fillet of size `k` (polynomial smooth minimum).";
    SmoothIntersection: "smooth_intersection", [A, B, K], Shape, Csg, "Intersection blended over a fillet of size `k`.";
    SmoothDifference: "smooth_difference", [A, B, K], Shape, Csg, "Difference blended over a fillet of size `k`.";
    // Transforms.
    Translate: "translate", [S, p("offset", Vec3)], Shape, Transform, "Moves the shape by `offset`.";
    Rotate: "rotate", [S, dir("axis", &[0.0, 1.0, 0.0]), p("angle", Float)], Shape, Transform, "Rotates the shape by `angle` about `axis` through the origin.";
    RotateX: "rotate_x", [S, p("angle", Float)], Shape, Transform, "Rotates the shape by `angle` about the x axis.";
    RotateY: "rotate_y", [S, p("angle", Float)], Shape, Transform, "Rotates the shape by `angle` about the y axis.";
    RotateZ: "rotate_z", [S, p("angle", Float)], Shape, Transform, "Rotates the shape by `angle` about the z axis.";
    Scale: "scale", [S, pos("factor", FloatOrVec3)], Shape, Transform, "Scales the shape about the origin; a vec3 scales per axis (the sphere tracer compensates for the stretched distance).";
    // Warps.
    Twist: "twist", [S, dir("axis", &[0.0, 1.0, 0.0]), p("rate", Float)], Shape, Warp, "Twists the shape about `axis` by `rate` radians per unit length.";
    Bend: "bend", [S, dir("axis", &[1.0, 0.0, 0.0]), p("rate", Float)], Shape, Warp, "Bends the shape in the xy-plane: each point turns about z by `rate` times its coordinate along `axis`.";
    Repeat: "repeat", [S, posd("period", FloatOrVec3, F(2.0))], Shape, Warp, "Repeats the shape forever on a grid with cell size `period`.";
    Mirror: "mirror", [S, dir("normal", &[1.0, 0.0, 0.0])], Shape, Warp, "Mirrors the half on the positive side of the plane through the origin with `normal` onto the other side.";
    Elongate: "elongate", [S, Param { name: "amount", ty: Vec3, default: None, check: Check::NonNegative }], Shape, Warp, "Stretches the shape by inserting `amount` of straight extrusion along each axis.";
    Round: "round", [S, Param { name: "radius", ty: Float, default: None, check: Check::NonNegative }], Shape, Warp, "Rounds the shape by offsetting its surface outwards by `radius`.";
    Shell: "shell", [S, pos("thickness", Float)], Shape, Warp, "Hollows the shape into a shell of `thickness` around its surface.";
    Paint: "paint", [S, p("material", Material)], Shape, Transform, "Gives the shape a material. Unions keep each operand's material.";
    ShellMap: "shell_map", [S, p("tile", Shape), p("uv", Vec2), posd("thickness", Float, F(0.1)), posd("base", Bool, Dflt::B(true))], Shape, Warp, "Copies a tile shape into the shell |f| ≤ `thickness` around the surface (§5.4, Eq. 60-62): shell coordinates S(x) = (fract(u) − 0.5, f(x) / thickness, fract(v) − 0.5), with (u, v) = `uv` read at the projection of x onto the surface (usually an atlas's uv on this shape, scaled: `skin.uv * 4` gives 4 tiles per unit), map one tile cell to x, z in [−0.5, 0.5] and the shell's height to y in [−1, 1]. The tile must stay inside its cell and the shell. With `base`, the result keeps the surface (min(f, tile), Eq. 62); without, only the tiles.";
    Displace: "displace", [S, p("height", Float), posd("scale", Float, F(1.0)), posd("band", Float, F(2.0))], Shape, Warp, "Displaces the surface along its normal by `scale * height` (§5.2.2, Eq. 56-58): `height` is a float surface field, usually a texture channel at an atlas's uv on this shape (`tex.sample(skin.uv).r`), read at the projection of each point onto the surface. Within `band` (τ > 1) times the largest displacement of the surface the field is f − scale·h; beyond it, the base field shifted by that largest displacement. Steps are divided by the bound √(L² + (1.5·scale·|∇h|)²).";
    // Textures and procedural patterns.
    Image: "image", [p("path", Str)], Texture, Texture, "Loads a PNG or JPEG image; the path is relative to the scene file.";
    Sample: "sample", [p("texture", Texture), p("uv", Vec2), Param { name: "wrap", ty: Str, default: Some(Dflt::S("repeat")), check: Check::OneOf(&["repeat", "mirror", "clamp"]) }], Vec4, Texture, "Samples `texture` at `uv` (rgba, linear), with mip-mapping and the `wrap` mode `repeat`, `mirror` or `clamp`.";
    SampleNormal: "sample_normal", [p("texture", Texture), p("uv", Vec2), Param { name: "strength", ty: Float, default: Some(F(1.0)), check: Check::NonNegative }, Param { name: "convention", ty: Str, default: Some(Dflt::S("gl")), check: Check::OneOf(&["gl", "dx"]) }, Param { name: "wrap", ty: Str, default: Some(Dflt::S("repeat")), check: Check::OneOf(&["repeat", "mirror", "clamp"]) }], Vec3, Texture, "A normal map (§5.2.1): samples `texture` at `uv` as linear data and decodes the tangent-space normal rgb·2 − 1 in the frame (e1, e2, n) of the seeds of `uv`'s atlas, carried to the point by the walk's parallel transport (Eq. 52) and blended like the uv across merged seeds; returns the world-space shading normal, for a material's `normal`. sdfc's v runs down the image (v = 0 is the top row), so `convention` \"gl\" (OpenGL: green points up the image) reads green along −e2 and \"dx\" (DirectX) along +e2. `strength` scales the tangent part (0: the surface normal).";
    Checker: "checker", [p("uv", Vec2), posd("n", Float, F(8.0))], Float, Texture, "A checkerboard of `n` squares per unit of uv: 0 or 1.";
    Grid: "grid", [p("uv", Vec2), posd("n", Float, F(8.0)), posd("width", Float, F(0.05))], Float, Texture, "Grid lines, `n` per unit of uv, of relative `width`: 1 on a line, 0 elsewhere.";
    // Render settings.
    Orbit: "orbit", [d("target", Vec3, V(&[0.0, 0.0, 0.0])), posd("distance", Float, F(5.0)), d("yaw", Float, F(0.0)), d("pitch", Float, F(0.0)), posd("fov", Float, F(std::f64::consts::FRAC_PI_4))], Camera, Render, "A camera looking at `target` from `distance`, turned by `yaw` about y and raised by `pitch`; `fov` is the vertical field of view.";
    LookAt: "look_at", [p("eye", Vec3), d("target", Vec3, V(&[0.0, 0.0, 0.0])), posd("fov", Float, F(std::f64::consts::FRAC_PI_4))], Camera, Render, "A camera at `eye` looking at `target`; `fov` is the vertical field of view.";
    Sun: "sun", [dir("direction", &[0.5, 1.0, 0.3]), Param { name: "color", ty: Vec3, default: Some(V(&[1.0, 1.0, 1.0])), check: Check::NonNegative }, Param { name: "intensity", ty: Float, default: Some(F(3.0)), check: Check::NonNegative }], Light, Render, "A directional light; `direction` points from the surface towards the sun.";
    // Math; all of these also work on surface fields.
    Sin: "sin", [TX], T, Math, "Sine, per component.";
    Cos: "cos", [TX], T, Math, "Cosine, per component.";
    Tan: "tan", [TX], T, Math, "Tangent, per component.";
    Asin: "asin", [TX], T, Math, "Arc sine, per component.";
    Acos: "acos", [TX], T, Math, "Arc cosine, per component.";
    Atan: "atan", [TX], T, Math, "Arc tangent, per component.";
    Atan2: "atan2", [p("y", T), TX], T, Math, "Arc tangent of y/x using both signs, per component.";
    Sqrt: "sqrt", [TX], T, Math, "Square root, per component.";
    Abs: "abs", [TX], T, Math, "Absolute value, per component.";
    Floor: "floor", [TX], T, Math, "Rounds down, per component.";
    Ceil: "ceil", [TX], T, Math, "Rounds up, per component.";
    Fract: "fract", [TX], T, Math, "`x - floor(x)`, per component.";
    Sign: "sign", [TX], T, Math, "-1, 0 or 1, per component.";
    Exp: "exp", [TX], T, Math, "e to the power x, per component.";
    Log: "log", [TX], T, Math, "Natural logarithm, per component.";
    Pow: "pow", [TX, p("y", T)], T, Math, "x to the power y, per component.";
    Min: "min", [p("a", T), p("b", T)], T, Math, "The smaller value, per component.";
    Max: "max", [p("a", T), p("b", T)], T, Math, "The larger value, per component.";
    Clamp: "clamp", [TX, p("lo", T), p("hi", T)], T, Math, "`x` limited to `[lo, hi]`, per component.";
    Mix: "mix", [p("a", T), p("b", T), p("t", T)], T, Math, "Linear interpolation `a + (b - a) * t`.";
    Smoothstep: "smoothstep", [p("edge0", T), p("edge1", T), TX], T, Math, "Hermite step from 0 at `edge0` to 1 at `edge1`.";
    Step: "step", [p("edge", T), TX], T, Math, "0 where `x < edge`, else 1.";
    Length: "length", [TX], Float, Math, "Euclidean length of a vector.";
    Distance: "distance", [p("a", T), p("b", T)], Float, Math, "Euclidean distance between two points.";
    Dot: "dot", [p("a", T), p("b", T)], Float, Math, "Dot product.";
    Cross: "cross", [p("a", Vec3), p("b", Vec3)], Vec3, Math, "Cross product of two vec3.";
    Normalize: "normalize", [TX], T, Math, "The vector scaled to unit length.";
    Radians: "radians", [TX], T, Math, "Degrees to radians (or write `90deg`).";
    Degrees: "degrees", [TX], T, Math, "Radians to degrees.";
}

/// A builtin constant or surface input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Constant {
    pub name: &'static str,
    pub doc: &'static str,
}

/// Every builtin name that is not a function.
pub static CONSTANTS: &[Constant] = &[
    Constant {
        name: "pi",
        doc: "π = 3.14159…",
    },
    Constant {
        name: "tau",
        doc: "τ = 2π = 6.28318…",
    },
    Constant {
        name: "time",
        doc: "Seconds since the start, from 0: a run-time parameter the host sets each frame (`sdfc render --time T`, `--animate`). It may reach a shape only through expressions the compiler can bound (`sin(time)`, `fract(time / 4)`, `clamp(time, 0, 10)`), or where the step bound does not depend on it (a translation).",
    },
    Constant {
        name: "position",
        doc: "The surface point being shaded (field<vec3>).",
    },
    Constant {
        name: "normal",
        doc: "The unit surface normal at the point being shaded (field<vec3>).",
    },
];

pub fn lookup(name: &str) -> Option<&'static Builtin> {
    BUILTINS.iter().find(|b| b.name == name)
}

/// A setting of a block (`atlas`, `material` or `render`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SettingSpec {
    pub name: &'static str,
    pub ty: PTy,
    pub default: Option<Dflt>,
    pub check: Check,
    /// Whether a surface field is allowed (material attributes).
    pub field: bool,
    pub doc: &'static str,
}

const fn set(
    name: &'static str,
    ty: PTy,
    default: Option<Dflt>,
    check: Check,
    field: bool,
    doc: &'static str,
) -> SettingSpec {
    SettingSpec {
        name,
        ty,
        default,
        check,
        field,
        doc,
    }
}

/// Settings of an `atlas` block (the parameters of Alg. 1 and Alg. 2).
pub static ATLAS_SETTINGS: &[SettingSpec] = &[
    set("steps", Float, Some(F(20.0)), Check::None, false, "N: the number of steps of every geodesic walk, a whole number in 1..=64."),
    set("max_distance", Float, Some(F(3.0)), Check::Positive, false, "D: points farther than this (Euclidean, then geodesic) from a seed get status too_far."),
    set("heuristic_tolerance", Float, Some(F(1e-3)), Check::Positive, false, "ε1: the walk fails (heuristic_failed) when the tangent part of the direction to the seed is shorter than ε1 times its length."),
    set("sharp_tolerance", Float, Some(F(0.015)), Check::Positive, false, "ε2: the walk stops at a sharp feature when a step turns the normal by more than acos(1 - ε2) beyond what the surface's curvature at the step's ends explains (1.5·κ·τ), or by more than 3·acos(1 - ε2) in any case."),
    set("min_reach", Float, Some(F(0.01)), Check::Positive, false, "r_min: the walk fails (not_reached) when it ends farther than this from the seed."),
    set("refine", Float, Some(F(0.0)), Check::None, false, "K: Newton corrections of each walk's uv towards the exact log map, a whole number in 0..=8: shoot the exponential map from the seed along the uv, transport the miss back to the seed, correct; each costs about one more walk."),
    set("reproject", Bool, Some(Dflt::B(false)), Check::None, false, "Project every step back onto the surface (Eq. 18)."),
    set("sigma", Float, None, Check::Positive, false, "σ: half-width of the blend band between merged seeds (default: the shortest merge edge / 3)."),
    set("mirror", Vec3, None, Check::NonZero, false, "The normal of a symmetry plane through the shape's origin (§5.1): a point on its negative side takes the uv of its reflection, e.g. `mirror = [1, 0, 0]` queries (|x|, y, z). Seeds are needed on the positive side only."),
];

/// Settings of a `material` block. Each may be a surface field.
pub static MATERIAL_SETTINGS: &[SettingSpec] = &[
    set(
        "color",
        Color,
        Some(V(&[0.8, 0.8, 0.8])),
        Check::NonNegative,
        true,
        "Base colour (linear RGB). A vec4, such as a texture sample, gives its rgb.",
    ),
    set(
        "roughness",
        Float,
        Some(F(0.5)),
        Check::NonNegative,
        true,
        "Perceptual roughness in [0, 1].",
    ),
    set(
        "metallic",
        Float,
        Some(F(0.0)),
        Check::NonNegative,
        true,
        "Metalness in [0, 1].",
    ),
    set(
        "emission",
        Vec3,
        Some(V(&[0.0, 0.0, 0.0])),
        Check::NonNegative,
        true,
        "Emitted radiance (linear RGB).",
    ),
    set(
        "normal",
        Vec3,
        None,
        Check::NonZero,
        true,
        "The shading normal (world space; normalized before shading), e.g. a normal map `tex.sample_normal(skin.uv)` (default: the surface normal `normal`).",
    ),
];

/// Settings of a `render` block.
pub static RENDER_SETTINGS: &[SettingSpec] = &[
    set(
        "camera",
        PTy::Camera,
        None,
        Check::None,
        false,
        "The camera: `orbit(…)` or `look_at(…)` (default: framed on the shape's bounds).",
    ),
    set(
        "size",
        Vec2,
        Some(V(&[960.0, 540.0])),
        Check::Positive,
        false,
        "Image size in pixels, [width, height]: whole numbers.",
    ),
    set(
        "light",
        PTy::Light,
        None,
        Check::None,
        false,
        "The light: `sun(…)` (default: `sun()`).",
    ),
    set(
        "background",
        Vec3,
        Some(V(&[0.05, 0.06, 0.08])),
        Check::NonNegative,
        false,
        "Background colour (linear RGB).",
    ),
    set(
        "ambient",
        Float,
        Some(F(0.15)),
        Check::NonNegative,
        false,
        "Strength of the ambient term.",
    ),
];

impl SettingSpec {
    /// `name: type = default`, for completion.
    pub fn describe(&self) -> String {
        describe_slot(self.name, self.ty, self.default)
    }
}
