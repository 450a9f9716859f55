//! The WGSL emitter: IR shapes and surface fields → WGSL source, with every
//! constant folded in. Only this file writes WGSL text from Rust; the shared
//! functions it calls live in `shaders/*.wgsl`.

use crate::ir::{Csg, NodeId, Op, Prim, Shape};
use crate::sema::builtins::BuiltinId;
use crate::sema::{AtlasAttr, AtlasId, FieldExpr, SurfaceInput, Ty, Value};
use crate::syntax::ast::{BinaryOp, UnaryOp};
use glam::{DMat3, DVec3};
use std::fmt::Write;

/// A WGSL float literal for a constant (always with a decimal point or exponent).
pub fn lit(x: f64) -> String {
    let x = x as f32;
    let s = format!("{x:?}");
    let s = if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    };
    if x < 0.0 {
        format!("({s})")
    } else {
        s
    }
}

pub fn vec3(v: DVec3) -> String {
    format!("vec3<f32>({}, {}, {})", lit(v.x), lit(v.y), lit(v.z))
}

/// `m * expr`, or just `expr` when `m` is the identity.
fn apply(m: DMat3, expr: &str) -> String {
    if m.abs_diff_eq(DMat3::IDENTITY, 1e-12) {
        expr.to_string()
    } else {
        format!("{} * {expr}", mat3(m))
    }
}

fn mat3(m: DMat3) -> String {
    format!(
        "mat3x3<f32>({}, {}, {})",
        vec3(m.x_axis),
        vec3(m.y_axis),
        vec3(m.z_axis)
    )
}

/// Writes indented WGSL statements with fresh temporary names.
pub struct Writer {
    pub out: String,
    indent: usize,
    next: usize,
    /// The prefix of the helper functions this writer defines (unique in the module).
    prefix: String,
    /// Helper functions the code in `out` calls: module-scope WGSL to emit beside it.
    pub helpers: String,
    /// The variable holding each node already evaluated at a point variable (every
    /// `let` is at function scope): a node shared by two parents at the same point is
    /// evaluated once.
    done: std::collections::HashMap<(NodeId, String), String>,
    /// Shared nodes already emitted as helper functions by this writer.
    emitted: std::collections::HashSet<NodeId>,
    /// The node whose helper function this writer is writing (not a helper again).
    own: Option<NodeId>,
    /// The displacements' heights the code calls (`height_ID`), once each.
    pub heights: Vec<std::sync::Arc<crate::ir::Height>>,
    /// The groups the code calls (`group_KEY`), once each: their functions and tables
    /// are the module's (`codegen::group`).
    pub groups: Vec<std::sync::Arc<crate::ir::group::Group>>,
    /// Material blend mode (`scene_blend`): every node is a `vec4<f32>` (distance,
    /// material a, material b, b's weight) instead of (distance, material), and smooth
    /// unions blend their operands' materials with the distance blend's weight.
    pub blend: bool,
    /// Large unions as code, not as groups (`Options::unions_as_code`).
    pub unions_as_code: bool,
    /// An atlas field's pruning (`uv::prune`): the private variable holding the walk's
    /// mask, and which union operands its bits guard. Only the top writer has it: the
    /// union chain is never inside a helper.
    pub prune: Option<(String, std::sync::Arc<crate::uv::prune::Pruning>)>,
}

impl Writer {
    /// A writer for the body of function `name`, whose helpers are named after it.
    pub fn new(name: &str) -> Self {
        Writer {
            out: String::new(),
            indent: 1,
            next: 0,
            prefix: name.to_string(),
            helpers: String::new(),
            done: std::collections::HashMap::new(),
            emitted: std::collections::HashSet::new(),
            own: None,
            heights: Vec::new(),
            groups: Vec::new(),
            blend: false,
            unions_as_code: false,
            prune: None,
        }
    }

    /// A writer for a helper function of this one, in the same mode.
    fn sub(&self, name: &str) -> Writer {
        let mut w = Writer::new(name);
        w.blend = self.blend;
        w.unions_as_code = self.unions_as_code;
        w
    }

    /// The WGSL type of a node's value.
    pub fn ty(&self) -> &'static str {
        if self.blend {
            "vec4<f32>"
        } else {
            "vec2<f32>"
        }
    }

    /// A node's value with distance `e` and the material of `dc`.
    fn with_d(&self, dc: &str, e: &str) -> String {
        if self.blend {
            format!("vec4<f32>({e}, {dc}.yzw)")
        } else {
            format!("vec2<f32>({e}, {dc}.y)")
        }
    }

    /// A node's value with distance `e` and the single material `m`.
    fn leaf(&self, e: &str, m: &str) -> String {
        if self.blend {
            format!("vec4<f32>({e}, {m}, {m}, 0.0)")
        } else {
            format!("vec2<f32>({e}, {m})")
        }
    }

    pub(super) fn fresh(&mut self, prefix: &str) -> String {
        self.next += 1;
        format!("{prefix}{}", self.next)
    }

    /// Writes the following lines `levels` deeper.
    pub fn indent(&mut self, levels: usize) {
        self.indent += levels;
    }

    pub fn line(&mut self, text: &str) {
        let _ = writeln!(self.out, "{}{}", "    ".repeat(self.indent), text);
    }

    /// Emits the evaluation of `id` at the point variable `p`; returns the name of the
    /// `vec2<f32>` holding (distance, material).
    pub fn shape(&mut self, shape: &Shape, id: NodeId, p: &str) -> String {
        let key = (id, p.to_string());
        if let Some(d) = self.done.get(&key) {
            return d.clone();
        }
        let d = if self.own != Some(id) && shape.is_shared(id) {
            // A node with several parents (a `let` used twice) is one helper function,
            // called from each: the WGSL stays linear in the scene.
            let name = format!("{}_n{}", self.prefix, id.index());
            if self.emitted.insert(id) {
                let mut w = self.sub(&name);
                w.own = Some(id);
                let dc = w.shape(shape, id, "p");
                self.helpers.push_str(&w.helpers);
                self.take_heights(&mut w);
                let _ = writeln!(
                    self.helpers,
                    "fn {name}(p: vec3<f32>) -> {} {{\n{}    return {dc};\n}}\n",
                    self.ty(),
                    w.out
                );
            }
            let d = self.fresh("d");
            self.line(&format!("let {d} = {name}({p});"));
            d
        } else {
            stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.shape_inner(shape, id, p))
        };
        self.done.insert(key, d.clone());
        d
    }

    fn shape_inner(&mut self, shape: &Shape, id: NodeId, p: &str) -> String {
        let d = self.fresh("d");
        if let Some(g) = shape.group(id).filter(|_| !self.unions_as_code) {
            return self.group(shape, g, &d, p);
        }
        match &shape[id].op {
            Op::Prim(pr) => {
                let call = match pr {
                    Prim::Sphere { r } => format!("sd_sphere({p}, {})", lit(*r)),
                    Prim::Box { half } => format!("sd_box({p}, {})", vec3(*half)),
                    Prim::RoundBox { half, r } => {
                        format!("sd_round_box({p}, {}, {})", vec3(*half), lit(*r))
                    }
                    Prim::BoxFrame { half, e } => {
                        format!("sd_box_frame({p}, {}, {})", vec3(*half), lit(*e))
                    }
                    Prim::Torus { major, minor } => {
                        format!("sd_torus({p}, {}, {})", lit(*major), lit(*minor))
                    }
                    Prim::Capsule { a, b, r } => {
                        format!("sd_capsule({p}, {}, {}, {})", vec3(*a), vec3(*b), lit(*r))
                    }
                    Prim::Cylinder { r, half_h } => {
                        format!("sd_cylinder({p}, {}, {})", lit(*r), lit(*half_h))
                    }
                    Prim::CappedCone { half_h, r1, r2 } => format!(
                        "sd_capped_cone({p}, {}, {}, {})",
                        lit(*half_h),
                        lit(*r1),
                        lit(*r2)
                    ),
                    Prim::Plane { n, offset } => {
                        format!("sd_plane({p}, {}, {})", vec3(*n), lit(*offset))
                    }
                    Prim::Ellipsoid { radii } => format!("sd_ellipsoid({p}, {})", vec3(*radii)),
                    Prim::Octahedron { s } => format!("sd_octahedron({p}, {})", lit(*s)),
                    Prim::HexPrism { r, half_h } => {
                        format!("sd_hex_prism({p}, {}, {})", lit(*r), lit(*half_h))
                    }
                    Prim::TriPrism { r, half_h } => {
                        format!("sd_tri_prism({p}, {}, {})", lit(*r), lit(*half_h))
                    }
                    Prim::Pyramid { h } => format!("sd_pyramid({p}, {})", lit(*h)),
                    Prim::Link { le, r1, r2 } => {
                        format!("sd_link({p}, {}, {}, {})", lit(*le), lit(*r1), lit(*r2))
                    }
                };
                let v = self.leaf(&call, "0.0");
                self.line(&format!("let {d} = {v};"));
            }
            Op::Csg { op, k, a, b } => {
                let (da, db) = if self.on_chain(id) {
                    (self.operand(shape, *a, p), self.operand(shape, *b, p))
                } else {
                    (self.shape(shape, *a, p), self.shape(shape, *b, p))
                };
                let f = match op {
                    Csg::Union => "op_union",
                    Csg::Intersection => "op_intersection",
                    Csg::Difference => "op_difference",
                };
                let mode = if self.blend { "_blend" } else { "" };
                self.line(&format!("let {d} = {f}{mode}({da}, {db}, {});", lit(*k)));
            }
            Op::Translate { child, .. } | Op::Rotate { child, .. } => {
                let q = point_expr(&shape[id].op, p).unwrap_or_default();
                return self.point(shape, *child, &q);
            }
            Op::Scale { factor, child } => {
                let q = point_expr(&shape[id].op, p).unwrap_or_default();
                let dc = self.point(shape, *child, &q);
                let v = self.with_d(&dc, &format!("{dc}.x * {}", lit(factor.min_element())));
                self.line(&format!("let {d} = {v};"));
            }
            Op::Twist { radius, child, .. } | Op::Bend { radius, child, .. } => {
                let inner = point_expr(&shape[id].op, p).unwrap_or_default();
                if radius.is_finite() {
                    let l = self.fresh("l");
                    self.line(&format!("let {l} = length({p});"));
                    self.line(&format!("var {d}: {};", self.ty()));
                    self.line(&format!(
                        "if ({l} > {}) {{",
                        lit(crate::ir::warp_outer(*radius))
                    ));
                    self.indent += 1;
                    let v = self.leaf(&format!("{l} - {}", lit(*radius)), "0.0");
                    self.line(&format!("{d} = {v};"));
                    self.indent -= 1;
                    self.line("} else {");
                    self.indent += 1;
                    // The child goes into a helper function, so chains of warps do not
                    // nest blocks (naga limits brace nesting).
                    let helper = self.helper_fn(shape, *child, "w");
                    self.line(&format!("{d} = {helper}({inner});"));
                    self.indent -= 1;
                    self.line("}");
                } else {
                    return self.point(shape, *child, &inner);
                }
            }
            Op::Repeat { child, .. } | Op::Mirror { child, .. } | Op::Elongate { child, .. } => {
                let q = point_expr(&shape[id].op, p).unwrap_or_default();
                return self.point(shape, *child, &q);
            }
            Op::Round { r, child } => {
                let dc = self.shape(shape, *child, p);
                let v = self.with_d(&dc, &format!("{dc}.x - {}", lit(*r)));
                self.line(&format!("let {d} = {v};"));
            }
            Op::Shell { thickness, child } => {
                let dc = self.shape(shape, *child, p);
                let v = self.with_d(&dc, &format!("abs({dc}.x) - {}", lit(thickness * 0.5)));
                self.line(&format!("let {d} = {v};"));
            }
            Op::Displace { height, child } => {
                // Eq. 58: the child in a helper (evaluated 7 times inside the band for Π_f).
                let helper = self.helper_fn(shape, *child, "h");
                if !self.heights.iter().any(|h| h.id == height.id) {
                    self.heights.push(height.clone());
                }
                let b = self.fresh("b");
                self.line(&format!("let {b} = {helper}({p});"));
                let v = self.with_d(&b, &format!("{b}.x - {}", lit(height.hi)));
                self.line(&format!("var {d} = {v};"));
                self.line(&format!("if ({b}.x < -{}) {{", lit(height.band_width())));
                self.indent += 1;
                self.line(&format!("{d}.x = {b}.x - {};", lit(height.lo)));
                self.indent -= 1;
                self.line(&format!(
                    "}} else if ({b}.x <= {}) {{",
                    lit(height.band_width())
                ));
                self.indent += 1;
                let (q, g) = self.projection(&helper, p, &b, height.grad_step);
                self.line(&format!(
                    "{d}.x = {b}.x - height_{}({q}, normalize({g}));",
                    height.id
                ));
                self.indent -= 1;
                self.line("}");
            }
            Op::ShellMap { map, base, tile } => {
                // §5.4: the base in a helper (7 evaluations inside the shell), the tile in
                // another, evaluated at the shell coordinates.
                let helper = self.helper_fn(shape, *base, "s");
                let tile_fn = self.helper_fn(shape, *tile, "t");
                if !self.heights.iter().any(|h| h.id == map.uv.id) {
                    self.heights.push(std::sync::Arc::new(map.uv.clone()));
                }
                let eps = lit(map.thickness);
                let b = self.fresh("b");
                self.line(&format!("let {b} = {helper}({p});"));
                let (lo, hi) = (map.thickness * map.lo, map.thickness * map.hi);
                let lower = format!("max({b}.x - {}, {} - {b}.x)", lit(hi), lit(lo));
                let outside = if map.keep_base {
                    format!("min({b}.x, {lower})")
                } else {
                    lower.clone()
                };
                let v = self.with_d(&b, &outside);
                self.line(&format!("var {d} = {v};"));
                let band = crate::ir::shell::BAND * map.thickness;
                self.line(&format!(
                    "if ({b}.x < {} && {b}.x > {}) {{",
                    lit(hi + band),
                    lit(lo - band)
                ));
                self.indent += 1;
                let (q, g) = self.projection(&helper, p, &b, map.uv.grad_step);
                let uv = self.fresh("uv");
                self.line(&format!(
                    "let {uv} = height_{}({q}, normalize({g}));",
                    map.uv.id
                ));
                let t = self.fresh("t");
                self.line(&format!(
                    "let {t} = {tile_fn}(vec3<f32>(fract({uv}.x) - 0.5, {b}.x / {eps}, fract({uv}.y) - 0.5));"
                ));
                let v = self.with_d(&t, &format!("max({} * {t}.x, {lower})", lit(map.scale)));
                if map.keep_base {
                    let tv = self.fresh("tv");
                    self.line(&format!("let {tv} = {v};"));
                    self.line(&format!("{d} = select({b}, {tv}, {tv}.x < {b}.x);"));
                } else {
                    self.line(&format!("{d} = {v};"));
                }
                self.indent -= 1;
                self.line("}");
            }
            Op::Paint { material, child } => {
                let dc = self.shape(shape, *child, p);
                let v = self.leaf(&format!("{dc}.x"), &lit(*material as f64));
                self.line(&format!("let {d} = {v};"));
            }
        }
        d
    }

    /// Writes node `child` as a helper function `PREFIX_TAGn(p)` (for nodes evaluated
    /// at several points, or behind a branch: naga limits brace nesting); its name.
    /// Whether `id` is on the pruned union chain of this writer's atlas field.
    fn on_chain(&self, id: NodeId) -> bool {
        self.prune
            .as_ref()
            .is_some_and(|(_, pr)| pr.on_chain.get(id.index()).copied().unwrap_or(false))
    }

    /// An operand of a union on the chain: evaluated only when its bit of the pruning mask is set, where it
    /// is a pruning candidate (1e30 otherwise, which leaves the union the other operand).
    fn operand(&mut self, shape: &Shape, c: NodeId, p: &str) -> String {
        let Some((mask, bit)) = self
            .prune
            .as_ref()
            .and_then(|(mask, pr)| Some((mask.clone(), pr.bit(c)?)))
        else {
            return self.shape(shape, c, p);
        };
        if let Some(d) = self.done.get(&(c, p.to_string())) {
            return d.clone();
        }
        let d = self.fresh("d");
        let far = self.leaf("1e30", "0.0");
        self.line(&format!("var {d} = {far};"));
        self.line(&format!("if (({mask} & {}u) != 0u) {{", 1u32 << bit));
        self.indent += 1;
        // What is evaluated inside the block is not in scope after it.
        let before = self.done.clone();
        let dc = self.shape(shape, c, p);
        self.line(&format!("{d} = {dc};"));
        self.done = before;
        self.indent -= 1;
        self.line("}");
        d
    }

    fn helper_fn(&mut self, shape: &Shape, child: NodeId, tag: &str) -> String {
        let helper = self.fresh(&format!("{}_{tag}", self.prefix));
        let mut inner_w = self.sub(&helper);
        let dc = inner_w.shape(shape, child, "p");
        self.helpers.push_str(&inner_w.helpers);
        self.take_heights(&mut inner_w);
        let _ = writeln!(
            self.helpers,
            "fn {helper}(p: vec3<f32>) -> {} {{\n{}    return {dc};\n}}\n",
            self.ty(),
            inner_w.out
        );
        helper
    }

    /// Π_f (Eq. 57) from point `p`, where helper `f` has the value `b`: the gradient by
    /// central differences of step `h` and the projected point; their names.
    fn projection(&mut self, f: &str, p: &str, b: &str, h: f64) -> (String, String) {
        let h = lit(h);
        let g = self.fresh("g");
        self.line(&format!(
            "let {g} = vec3<f32>({f}({p} + vec3<f32>({h}, 0.0, 0.0)).x - {f}({p} - vec3<f32>({h}, 0.0, 0.0)).x, {f}({p} + vec3<f32>(0.0, {h}, 0.0)).x - {f}({p} - vec3<f32>(0.0, {h}, 0.0)).x, {f}({p} + vec3<f32>(0.0, 0.0, {h})).x - {f}({p} - vec3<f32>(0.0, 0.0, {h})).x) / (2.0 * {h});"
        ));
        let q = self.fresh("q");
        self.line(&format!(
            "let {q} = {p} - {g} * ({b}.x / max(dot({g}, {g}), 1e-20));"
        ));
        (q, g)
    }

    /// Takes the heights and groups a helper's writer calls.
    fn take_heights(&mut self, w: &mut Writer) {
        for h in std::mem::take(&mut w.heights) {
            if !self.heights.iter().any(|x| x.id == h.id) {
                self.heights.push(h);
            }
        }
        for g in std::mem::take(&mut w.groups) {
            if !self.groups.iter().any(|x| x.key == g.key) {
                self.groups.push(g);
            }
        }
    }

    /// Binds a transformed point and evaluates a child there.
    fn point(&mut self, shape: &Shape, child: NodeId, expr: &str) -> String {
        let q = self.fresh("p");
        self.line(&format!("let {q} = {expr};"));
        self.shape(shape, child, &q)
    }
}

/// The WGSL of the point at which a point-mapping op evaluates its child (the
/// `ir::rest::child_point` of the CPU), for the point expression `p`; `None` for ops
/// that are not point maps.
pub fn point_expr(op: &Op, p: &str) -> Option<String> {
    Some(match op {
        Op::Translate { offset, .. } => format!("{p} - {}", vec3(*offset)),
        Op::Rotate { inverse, .. } => format!("{} * {p}", mat3(*inverse)),
        Op::Scale { factor, .. } => format!("{p} / {}", vec3(*factor)),
        Op::Twist { frame, rate, .. } | Op::Bend { frame, rate, .. } => {
            let warp = if matches!(op, Op::Twist { .. }) {
                "op_twist"
            } else {
                "op_bend"
            };
            apply(
                frame.transpose(),
                &format!("{warp}({}, {})", apply(*frame, p), lit(*rate)),
            )
        }
        Op::Repeat { period, .. } => format!("op_repeat({p}, {})", vec3(*period)),
        Op::Mirror { normal, .. } => format!("op_mirror({p}, {})", vec3(*normal)),
        Op::Elongate { h, .. } => format!("op_elongate({p}, {})", vec3(*h)),
        _ => return None,
    })
}

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
        Value::Field(expr, ty) => match &**expr {
            FieldExpr::Input(SurfaceInput::Position) => match &tex.offset {
                Some((_, dp)) => format!("(p + {dp})"),
                None => String::from("p"),
            },
            FieldExpr::Input(SurfaceInput::Normal) => String::from("n"),
            FieldExpr::Atlas { atlas, attr } => {
                tex.atlases.insert(*atlas);
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
    Ok(match op {
        BinaryOp::Or => format!("({a} || {b})"),
        BinaryOp::And => format!("({a} && {b})"),
        BinaryOp::Rem => format!("({a} - {b} * floor({a} / {b}))"),
        BinaryOp::Eq | BinaryOp::Ne if matches!(numeric, Ty::Vec(_)) && *ty == Ty::Bool => {
            format!("all({a} {} {b})", op.symbol())
        }
        _ => format!("({a} {} {b})", op.symbol()),
    })
}

fn call(builtin: BuiltinId, args: &[Value], tex: &mut Uses) -> Result<String, Unsupported> {
    use BuiltinId as B;
    let name = builtin.name();
    let t_ty = args
        .iter()
        .map(|a| a.ty().base().clone())
        .find(|t| matches!(t, Ty::Vec(_)))
        .unwrap_or(Ty::Float);
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
            let green = lit(crate::ir::material::green_sign(convention));
            let a = format!("atlas_sample_{}", k.index());
            format!("sdfc_normal_map({texel}, {a}.tangent, {a}.bitangent, n, {strength}, {green})")
        }
        B::Cross => format!("cross({}, {})", f(&args[0])?, f(&args[1])?),
        // WGSL's normalize takes only vectors; a float's is its sign.
        B::Normalize if args[0].ty().base() == &Ty::Float => format!("sign({})", f(&args[0])?),
        B::Length | B::Normalize => format!("{name}({})", f(&args[0])?),
        // WGSL's dot takes only vectors; two floats' is their product.
        B::Dot if t_ty == Ty::Float => format!("({} * {})", f(&args[0])?, f(&args[1])?),
        // The WGSL builtin of the same name, on arguments widened to the call's type.
        B::Sin
        | B::Cos
        | B::Tan
        | B::Asin
        | B::Acos
        | B::Atan
        | B::Atan2
        | B::Sqrt
        | B::Abs
        | B::Floor
        | B::Ceil
        | B::Fract
        | B::Sign
        | B::Exp
        | B::Log
        | B::Pow
        | B::Min
        | B::Max
        | B::Clamp
        | B::Mix
        | B::Smoothstep
        | B::Step
        | B::Distance
        | B::Dot
        | B::Radians
        | B::Degrees => format!(
            "{name}({})",
            args.iter()
                .map(|a| widen(a, &t_ty, tex))
                .collect::<Result<Vec<_>, _>>()?
                .join(", ")
        ),
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
        | B::Orbit
        | B::LookAt
        | B::Sun => return Err(Unsupported(format!("`{name}` is not a surface field"))),
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
