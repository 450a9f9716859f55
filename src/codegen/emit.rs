//! The WGSL emitter: IR shapes → WGSL source, with every constant folded in. With
//! `field` (surface fields), the only code that writes WGSL expressions from Rust; the
//! shared functions it calls live in `shaders/*.wgsl`.

use crate::ir::dynamic::Dyn;
use crate::ir::{Csg, Node, NodeId, Op, Prim, Shape};
use glam::DMat3;
use std::fmt::Write;

pub use super::literal::{arg, lit, vec3};

/// `m * expr`, or just `expr` when `m` is the identity.
pub(super) fn apply(m: DMat3, expr: &str) -> String {
    if m.abs_diff_eq(DMat3::IDENTITY, 1e-12) {
        expr.to_string()
    } else {
        format!("{} * {expr}", mat3(m))
    }
}

pub(super) fn mat3(m: DMat3) -> String {
    format!(
        "mat3x3f({}, {}, {})",
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
    /// Shared nodes already emitted as helper functions, by this writer and the helper
    /// writers of its tree (each has the set so far and hands it back), named after
    /// `shared_prefix`, the top writer's name: a shared node is one function in the
    /// module however many helpers (warps, guards) reach it.
    emitted: std::collections::HashSet<NodeId>,
    shared_prefix: String,
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
    /// The cost from which unions' operands are guarded by their boxes
    /// (`ir::guard`); None for none.
    pub guard_cost: Option<f64>,
    /// The groups this writer evaluates through their screen tile's list, by node, with
    /// their slots (`codegen::tiles`); only the top writer of `scene_trace_map` has
    /// them (its helpers walk whole groups).
    pub tiled: std::collections::HashMap<NodeId, u32>,
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
            shared_prefix: name.to_string(),
            own: None,
            heights: Vec::new(),
            groups: Vec::new(),
            blend: false,
            unions_as_code: false,
            prune: None,
            guard_cost: None,
            tiled: std::collections::HashMap::new(),
        }
    }

    /// A writer for a helper function of this one, in the same mode.
    fn sub(&self, name: &str) -> Writer {
        let mut w = Writer::new(name);
        w.blend = self.blend;
        w.unions_as_code = self.unions_as_code;
        w.guard_cost = self.guard_cost;
        w.emitted = self.emitted.clone();
        w.shared_prefix = self.shared_prefix.clone();
        w
    }

    /// Takes back what a helper writer made for the module: its helper functions, the
    /// shared nodes it emitted, its heights and groups.
    fn absorb(&mut self, w: &mut Writer) {
        self.helpers.push_str(&w.helpers);
        self.emitted.extend(w.emitted.drain());
        self.take_heights(w);
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
            format!("vec4f({e}, {dc}.yzw)")
        } else {
            format!("vec2f({e}, {dc}.y)")
        }
    }

    /// A node's value with distance `e` and the single material `m`.
    fn leaf(&self, e: &str, m: &str) -> String {
        if self.blend {
            format!("vec4f({e}, {m}, {m}, 0.0)")
        } else {
            format!("vec2f({e}, {m})")
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
            let name = format!("{}_n{}", self.shared_prefix, id.index());
            if self.emitted.insert(id) {
                let mut w = self.sub(&name);
                w.own = Some(id);
                let dc = w.shape(shape, id, "p");
                self.absorb(&mut w);
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
            return self.group(shape, (id, g), &d, p);
        }
        let dynamic = shape[id].dynamic.as_deref();
        // A node's one run-time number, or its constant written by `constant`.
        let one = |constant: String| match dynamic {
            Some(Dyn::One(s)) => super::params::slot(s, false),
            _ => constant,
        };
        match &shape[id].op {
            Op::Prim(pr) => {
                let call = prim_call(pr, dynamic, p);
                let v = self.leaf(&call, "0.0");
                self.line(&format!("let {d} = {v};"));
            }
            Op::Csg { op, k, a, b } => {
                let (da, db) = self.csg_operands(shape, id, *a, *b, p);
                let f = match op {
                    Csg::Union => "op_union",
                    Csg::Intersection => "op_intersection",
                    Csg::Difference => "op_difference",
                };
                let mode = if self.blend { "_blend" } else { "" };
                let k = one(lit(*k));
                self.line(&format!("let {d} = {f}{mode}({da}, {db}, {k});"));
            }
            Op::Translate { child, .. } | Op::Rotate { child, .. } => {
                let q = point_expr(&shape[id], p).unwrap_or_default();
                return self.point(shape, *child, &q);
            }
            Op::Scale { factor, child } => {
                let q = point_expr(&shape[id], p).unwrap_or_default();
                let dc = self.point(shape, *child, &q);
                let m = match dynamic {
                    Some(Dyn::One(s)) => format!("sdfc_min3({})", super::params::slot(s, true)),
                    _ => lit(factor.min_element()),
                };
                let v = self.with_d(&dc, &format!("{dc}.x * {m}"));
                self.line(&format!("let {d} = {v};"));
            }
            Op::Twist { radius, child, .. } | Op::Bend { radius, child, .. } => {
                let inner = point_expr(&shape[id], p).unwrap_or_default();
                if radius.is_finite() {
                    self.bounded_warp(shape, *child, *radius, &inner, p, &d);
                } else {
                    return self.point(shape, *child, &inner);
                }
            }
            Op::Repeat { child, .. } | Op::Mirror { child, .. } | Op::Elongate { child, .. } => {
                let q = point_expr(&shape[id], p).unwrap_or_default();
                return self.point(shape, *child, &q);
            }
            Op::Round { r, child } => {
                let dc = self.shape(shape, *child, p);
                let v = self.with_d(&dc, &format!("{dc}.x - {}", one(lit(*r))));
                self.line(&format!("let {d} = {v};"));
            }
            Op::Shell { thickness, child } => {
                let dc = self.shape(shape, *child, p);
                let half = one(lit(thickness * 0.5));
                let v = self.with_d(&dc, &format!("abs({dc}.x) - {half}"));
                self.line(&format!("let {d} = {v};"));
            }
            Op::Displace { height, child } => {
                self.displace(shape, height, *child, p, &d);
            }
            Op::ShellMap { map, base, tile } => {
                self.shell_map(shape, map, *base, *tile, p, &d);
            }
            Op::Paint { material, child } => {
                let dc = self.shape(shape, *child, p);
                let v = self.leaf(&format!("{dc}.x"), &lit(*material as f64));
                self.line(&format!("let {d} = {v};"));
            }
        }
        d
    }

    /// The operands of CSG node `id`: along a chain of unions each as a chain operand,
    /// a guarded union's first operand and the other under its guard, else each
    /// evaluated.
    fn csg_operands(
        &mut self,
        shape: &Shape,
        id: NodeId,
        a: NodeId,
        b: NodeId,
        p: &str,
    ) -> (String, String) {
        let guard = shape
            .guard(id)
            .filter(|g| self.guard_cost.is_some_and(|c| g.cost >= c));
        if self.on_chain(id) {
            (self.operand(shape, a, p), self.operand(shape, b, p))
        } else if let Some(g) = guard {
            let first = self.shape(shape, g.first, p);
            let other = self.guarded(shape, g, &first, p);
            if g.first == a {
                (first, other)
            } else {
                (other, first)
            }
        } else {
            (self.shape(shape, a, p), self.shape(shape, b, p))
        }
    }

    /// A twist or bend with a finite bound into `d`: outside the bounding sphere of
    /// `radius`, its distance; inside, the child at the warped point `inner`.
    fn bounded_warp(
        &mut self,
        shape: &Shape,
        child: NodeId,
        radius: f64,
        inner: &str,
        p: &str,
        d: &str,
    ) {
        let l = self.fresh("l");
        self.line(&format!("let {l} = length({p});"));
        self.line(&format!("var {d}: {};", self.ty()));
        self.line(&format!(
            "if ({l} > {}) {{",
            lit(crate::ir::warp_outer(radius))
        ));
        self.indent += 1;
        let v = self.leaf(&format!("{l} - {}", lit(radius)), "0.0");
        self.line(&format!("{d} = {v};"));
        self.indent -= 1;
        self.line("} else {");
        self.indent += 1;
        // The child goes into a helper function, so chains of warps do not
        // nest blocks (naga limits brace nesting).
        let helper = self.helper_fn(shape, child, "w");
        self.line(&format!("{d} = {helper}({inner});"));
        self.indent -= 1;
        self.line("}");
    }

    /// A displacement into `d` (Eq. 58).
    fn displace(
        &mut self,
        shape: &Shape,
        height: &std::sync::Arc<crate::ir::Height>,
        child: NodeId,
        p: &str,
        d: &str,
    ) {
        // Eq. 58: the child in a helper (evaluated 7 times inside the band for Π_f).
        let helper = self.helper_fn(shape, child, "h");
        if !self.heights.iter().any(|h| h.id == height.id) {
            self.heights.push(height.clone());
        }
        // A number proportional to the scale: from the parameters' block when the
        // scale is a run-time value.
        let scaled = |x: f64| match &height.run_time_scale {
            Some(v) => format!("({} * {})", super::params::expr(v), lit(x / height.scale)),
            None => lit(x),
        };
        let b = self.fresh("b");
        self.line(&format!("let {b} = {helper}({p});"));
        let v = self.with_d(&b, &format!("{b}.x - {}", scaled(height.hi)));
        self.line(&format!("var {d} = {v};"));
        self.line(&format!("if ({b}.x < -{}) {{", scaled(height.band_width())));
        self.indent += 1;
        self.line(&format!("{d}.x = {b}.x - {};", scaled(height.lo)));
        self.indent -= 1;
        self.line(&format!(
            "}} else if ({b}.x <= {}) {{",
            scaled(height.band_width())
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

    /// A shell map into `d` (§5.4).
    fn shell_map(
        &mut self,
        shape: &Shape,
        map: &crate::ir::shell::ShellMap,
        base: NodeId,
        tile: NodeId,
        p: &str,
        d: &str,
    ) {
        // §5.4: the base in a helper (7 evaluations inside the shell), the tile in
        // another, evaluated at the shell coordinates.
        let helper = self.helper_fn(shape, base, "s");
        let tile_fn = self.helper_fn(shape, tile, "t");
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

    /// A union's guarded operand (`ir::guard`): evaluated where its box comes within
    /// reach of the first operand's distance `first` (1e30 elsewhere, which leaves the
    /// union the first operand).
    fn guarded(
        &mut self,
        shape: &Shape,
        g: &crate::ir::guard::Guard,
        first: &str,
        p: &str,
    ) -> String {
        let d = self.fresh("d");
        let far = self.leaf("1e30", "0.0");
        self.line(&format!("var {d} = {far};"));
        self.line(&format!(
            "if (sd_box({p} - {}, {}) <= max({first}.x, 0.0) + {}) {{",
            vec3(g.center),
            vec3(g.half),
            lit(g.slack)
        ));
        self.indent += 1;
        // In a helper function: guards nested in the operand do not nest blocks (naga
        // limits brace nesting).
        let helper = self.helper_fn(shape, g.guarded, "g");
        self.line(&format!("{d} = {helper}({p});"));
        self.indent -= 1;
        self.line("}");
        d
    }

    /// Writes node `child` as a helper function `PREFIX_TAGn(p)` (for nodes evaluated
    /// at several points, or behind a branch: naga limits brace nesting); its name.
    fn helper_fn(&mut self, shape: &Shape, child: NodeId, tag: &str) -> String {
        let helper = self.fresh(&format!("{}_{tag}", self.prefix));
        let mut inner_w = self.sub(&helper);
        let dc = inner_w.shape(shape, child, "p");
        self.absorb(&mut inner_w);
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

/// The WGSL call of a primitive's distance at point `p` ([`Prim::wgsl_call`]), its
/// run-time numbers from the parameters' block.
pub(super) fn prim_call(pr: &Prim, dynamic: Option<&Dyn>, p: &str) -> String {
    let run_time = |i: usize, slot: crate::ir::prim::Slot| match dynamic {
        Some(Dyn::Prim(slots)) => slots
            .get(i)?
            .as_ref()
            .map(|s| super::params::slot(s, slot == crate::ir::prim::Slot::Vec3)),
        _ => None,
    };
    pr.wgsl_call(p, lit, vec3, run_time)
}

/// The WGSL of the point at which a point-mapping node evaluates its child (the
/// `ir::Op::child_point` of the CPU), for the point expression `p`, its run-time
/// numbers from the parameters' block; `None` for ops that are not point maps.
pub fn point_expr(node: &Node, p: &str) -> Option<String> {
    let op = &node.op;
    let run_time = |vec3: bool| match node.dynamic.as_deref() {
        Some(Dyn::One(s)) => Some(super::params::slot(s, vec3)),
        _ => None,
    };
    if let Some(Dyn::Rotate { axis, angle }) = node.dynamic.as_deref() {
        // The inverse rotation: p times the forward matrix.
        return Some(format!(
            "({p} * sdfc_axis_angle({}, {}))",
            vec3(*axis),
            super::params::slot(angle, false)
        ));
    }
    Some(match op {
        Op::Translate { offset, .. } => {
            format!("{p} - {}", run_time(true).unwrap_or_else(|| vec3(*offset)))
        }
        Op::Rotate { inverse, .. } => format!("{} * {p}", mat3(*inverse)),
        Op::Scale { factor, .. } => {
            format!("{p} / {}", run_time(true).unwrap_or_else(|| vec3(*factor)))
        }
        Op::Twist { frame, rate, .. } | Op::Bend { frame, rate, .. } => {
            let warp = if matches!(op, Op::Twist { .. }) {
                "op_twist"
            } else {
                "op_bend"
            };
            apply(
                frame.transpose(),
                &format!(
                    "{warp}({}, {})",
                    apply(*frame, p),
                    run_time(false).unwrap_or_else(|| lit(*rate))
                ),
            )
        }
        Op::Repeat { period, .. } => format!(
            "op_repeat({p}, {})",
            run_time(true).unwrap_or_else(|| vec3(*period))
        ),
        Op::Mirror { normal, .. } => format!("op_mirror({p}, {})", vec3(*normal)),
        Op::Elongate { h, .. } => format!(
            "op_elongate({p}, {})",
            run_time(true).unwrap_or_else(|| vec3(*h))
        ),
        _ => return None,
    })
}
