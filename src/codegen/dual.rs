//! Forward-mode derivatives in WGSL: a shape's distance with its gradient,
//! `vec4<f32>(∇f, f)`, by the chain rule through every operation and warp, from the
//! primitives' gradients by hand (`shaders/dual.wgsl`, named by `ir::prim::Kind::gradient`)
//! or, for the kinds without one, central differences of the primitive alone. Only for
//! shapes `ir::dual::supported` accepts (no texture read, no group); the walk of
//! Implicit UVs then reads exact gradients where it took six evaluations of the whole
//! field (`codegen::atlas`).
//!
//! Each node's value is the gradient with respect to its own input point: a warp
//! evaluates its child at the warped point and pulls the child's gradient back through
//! its Jacobian (Jᵀ g).

use super::emit::{apply, lit, mat3, point_expr, prim_call, vec3};
use crate::ir::dynamic::Dyn;
use crate::ir::{Csg, NodeId, Op, Prim, Shape};
use glam::DMat3;
use std::fmt::Write;

/// Writes the forward derivative of a shape as WGSL statements.
pub struct DualWriter {
    pub out: String,
    /// Module-scope functions the code calls (shared nodes, warps' children).
    pub helpers: String,
    prefix: String,
    next: usize,
    indent: usize,
    done: std::collections::HashMap<(NodeId, String), String>,
    emitted: std::collections::HashSet<NodeId>,
    own: Option<NodeId>,
}

impl DualWriter {
    /// A writer for the body of function `name`, whose helpers are named after it.
    pub fn new(name: &str) -> DualWriter {
        DualWriter {
            out: String::new(),
            helpers: String::new(),
            prefix: name.to_string(),
            next: 0,
            indent: 1,
            done: Default::default(),
            emitted: Default::default(),
            own: None,
        }
    }

    fn sub(&self, name: &str) -> DualWriter {
        let mut w = DualWriter::new(name);
        w.emitted = self.emitted.clone();
        w.prefix = self.prefix.clone();
        w.next = self.next;
        w
    }

    fn absorb(&mut self, w: &mut DualWriter) {
        self.helpers.push_str(&std::mem::take(&mut w.helpers));
        self.emitted = std::mem::take(&mut w.emitted);
        self.next = self.next.max(w.next);
    }

    fn fresh(&mut self, prefix: &str) -> String {
        self.next += 1;
        format!("{prefix}{}", self.next)
    }

    fn line(&mut self, text: &str) {
        let _ = writeln!(self.out, "{}{}", "    ".repeat(self.indent), text);
    }

    /// Node `id` as a helper function `fn NAME(p: vec3<f32>) -> vec4<f32>`; its name.
    fn helper(&mut self, shape: &Shape, id: NodeId, name: String, own: bool) -> String {
        let mut w = self.sub(&name);
        if own {
            w.own = Some(id);
        }
        let d = w.node(shape, id, "p");
        self.absorb(&mut w);
        let _ = writeln!(
            self.helpers,
            "fn {name}(p: vec3<f32>) -> vec4<f32> {{\n{}    return {d};\n}}\n",
            w.out
        );
        name
    }

    /// Emits the derivative of `id` at the point variable `p`; the name of the
    /// `vec4<f32>` holding (∇f, f), the gradient with respect to `p`.
    pub fn node(&mut self, shape: &Shape, id: NodeId, p: &str) -> String {
        let key = (id, p.to_string());
        if let Some(d) = self.done.get(&key) {
            return d.clone();
        }
        let d = if self.own != Some(id) && shape.is_shared(id) {
            // A node with several parents is one helper function, called from each.
            let name = format!("{}_n{}", self.prefix, id.index());
            if self.emitted.insert(id) {
                self.helper(shape, id, name.clone(), true);
            }
            let d = self.fresh("g");
            self.line(&format!("let {d} = {name}({p});"));
            d
        } else {
            stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.inner(shape, id, p))
        };
        self.done.insert(key, d.clone());
        d
    }

    /// Binds the point `expr` and differentiates `child` there.
    fn at(&mut self, shape: &Shape, child: NodeId, expr: &str) -> (String, String) {
        let q = self.fresh("p");
        self.line(&format!("let {q} = {expr};"));
        let d = self.node(shape, child, &q);
        (q, d)
    }

    fn inner(&mut self, shape: &Shape, id: NodeId, p: &str) -> String {
        let node = &shape[id];
        let dynamic = node.dynamic.as_deref();
        let one = |constant: String| match dynamic {
            Some(Dyn::One(s)) => super::params::slot(s, false),
            _ => constant,
        };
        let one3 = |constant: String| match dynamic {
            Some(Dyn::One(s)) => super::params::slot(s, true),
            _ => constant,
        };
        let d = self.fresh("g");
        let value = match &node.op {
            Op::Prim(pr) => self.prim(pr, dynamic, p),
            Op::Csg { op, k, a, b } => {
                let (da, db) = (self.node(shape, *a, p), self.node(shape, *b, p));
                let f = match op {
                    Csg::Union => "dual_union",
                    Csg::Intersection => "dual_intersection",
                    Csg::Difference => "dual_difference",
                };
                format!("{f}({da}, {db}, {})", one(lit(*k)))
            }
            Op::Translate { child, .. } | Op::Repeat { child, .. } | Op::Paint { child, .. } => {
                return match point_expr(node, p) {
                    Some(q) => self.at(shape, *child, &q).1,
                    None => self.node(shape, *child, p),
                };
            }
            Op::Rotate { inverse, child } => {
                let q = point_expr(node, p).unwrap_or_default();
                let (_, dc) = self.at(shape, *child, &q);
                let back = match dynamic {
                    // q = p Rᵀ… as a row vector: q = Rᵀ p, so ∇p = R ∇q.
                    Some(Dyn::Rotate { axis, angle }) => format!(
                        "sdfc_axis_angle({}, {}) * {dc}.xyz",
                        vec3(*axis),
                        super::params::slot(angle, false)
                    ),
                    _ => format!("{} * {dc}.xyz", mat3(inverse.transpose())),
                };
                format!("vec4<f32>({back}, {dc}.w)")
            }
            Op::Scale { factor, child } => {
                let q = point_expr(node, p).unwrap_or_default();
                let (_, dc) = self.at(shape, *child, &q);
                let (m, f) = match dynamic {
                    Some(Dyn::One(s)) => (
                        format!("sdfc_min3({})", super::params::slot(s, true)),
                        super::params::slot(s, true),
                    ),
                    _ => (lit(factor.min_element()), vec3(*factor)),
                };
                format!("vec4<f32>({dc}.xyz / {f} * {m}, {dc}.w * {m})")
            }
            Op::Twist {
                frame,
                rate,
                radius,
                child,
            }
            | Op::Bend {
                frame,
                rate,
                radius,
                child,
            } => {
                let twist = matches!(node.op, Op::Twist { .. });
                return self.warp(shape, id, (*frame, *rate, *radius, *child, twist), p, &d);
            }
            Op::Mirror { normal, child } => {
                let q = point_expr(node, p).unwrap_or_default();
                let (_, dc) = self.at(shape, *child, &q);
                format!(
                    "vec4<f32>(dual_mirror({p}, {}, {dc}.xyz), {dc}.w)",
                    vec3(*normal)
                )
            }
            Op::Elongate { h, child } => {
                let q = point_expr(node, p).unwrap_or_default();
                let (_, dc) = self.at(shape, *child, &q);
                format!(
                    "vec4<f32>(dual_elongate({p}, {}, {dc}.xyz), {dc}.w)",
                    one3(vec3(*h))
                )
            }
            Op::Round { r, child } => {
                let dc = self.node(shape, *child, p);
                format!("{dc} - vec4<f32>(0.0, 0.0, 0.0, {})", one(lit(*r)))
            }
            Op::Shell { thickness, child } => {
                let dc = self.node(shape, *child, p);
                format!("dual_shell({dc}, {})", one(lit(thickness * 0.5)))
            }
            // Not reached: `ir::dual::supported` keeps these shapes on differences.
            Op::Displace { .. } | Op::ShellMap { .. } => {
                String::from("vec4<f32>(0.0, 1.0, 0.0, 3.0e38)")
            }
        };
        self.line(&format!("let {d} = {value};"));
        d
    }

    /// A primitive's (∇f, f) at `p`: its gradient by hand, or central differences of
    /// the primitive alone with a step of 1e-3 of its size (exact to f32's rounding
    /// where it is smooth; the whole field's differences cost six evaluations of every
    /// node).
    fn prim(&mut self, pr: &Prim, dynamic: Option<&Dyn>, p: &str) -> String {
        let call = prim_call(pr, dynamic, p);
        if let Some(name) = pr.kind().gradient {
            return format!("{name}{}", &call[pr.kind().wgsl.len()..]);
        }
        let h = lit(crate::ir::dual::difference_step(pr));
        let taps: Vec<String> = ["1.0, 0.0, 0.0", "0.0, 1.0, 0.0", "0.0, 0.0, 1.0"]
            .iter()
            .map(|e| {
                let plus = prim_call(pr, dynamic, &format!("({p} + vec3<f32>({e}) * {h})"));
                let minus = prim_call(pr, dynamic, &format!("({p} - vec3<f32>({e}) * {h})"));
                format!("{plus} - {minus}")
            })
            .collect();
        format!(
            "vec4<f32>(vec3<f32>({}) / (2.0 * {h}), {call})",
            taps.join(", ")
        )
    }

    /// A twist or bend (in `frame`, the axis its y or x) at `p` into `d`: the child at
    /// the warped point, its gradient pulled back; outside a finite bound, the bounding
    /// sphere's distance (the plain field's bound).
    fn warp(
        &mut self,
        shape: &Shape,
        id: NodeId,
        (frame, rate, radius, child, twist): (DMat3, f64, f64, NodeId, bool),
        p: &str,
        d: &str,
    ) -> String {
        let node = &shape[id];
        let rate = match node.dynamic.as_deref() {
            Some(Dyn::One(s)) => super::params::slot(s, false),
            _ => lit(rate),
        };
        let pull = if twist { "dual_twist" } else { "dual_bend" };
        let u = self.fresh("u");
        self.line(&format!("let {u} = {};", apply(frame, p)));
        let q = point_expr(node, p).unwrap_or_default();
        let body = |dc: &str| {
            let back = format!(
                "{pull}({u}, {rate}, {})",
                apply(frame, &format!("{dc}.xyz"))
            );
            format!("vec4<f32>({}, {dc}.w)", apply(frame.transpose(), &back))
        };
        if !radius.is_finite() {
            let (_, dc) = self.at(shape, child, &q);
            self.line(&format!("let {d} = {};", body(&dc)));
            return d.to_string();
        }
        let l = self.fresh("l");
        self.line(&format!("let {l} = length({p});"));
        self.line(&format!("var {d}: vec4<f32>;"));
        self.line(&format!(
            "if ({l} > {}) {{",
            lit(crate::ir::warp_outer(radius))
        ));
        self.indent += 1;
        self.line(&format!(
            "{d} = vec4<f32>(dual_unit({p}, vec3<f32>(0.0, 1.0, 0.0)), {l} - {});",
            lit(radius)
        ));
        self.indent -= 1;
        self.line("} else {");
        self.indent += 1;
        // The child in a helper function: chains of warps do not nest blocks.
        let name = self.fresh(&format!("{}_w", self.prefix));
        let helper = self.helper(shape, child, name, false);
        let dc = self.fresh("g");
        self.line(&format!("let {dc} = {helper}({q});"));
        self.line(&format!("{d} = {};", body(&dc)));
        self.indent -= 1;
        self.line("}");
        d.to_string()
    }
}
