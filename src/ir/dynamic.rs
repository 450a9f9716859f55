//! Run-time values in the IR: which of a node's numbers the generated code computes
//! from the parameters' uniform block ([`Dyn`]), and how the lowering writes each
//! run-time argument ([`TARGETS`], agreeing with the checker's
//! `sema::params::RUN_TIME_ARGS`). The node's own numbers hold the parameters'
//! current values, which the CPU reference evaluates; its bounds and Lipschitz
//! constant hold over the parameters' whole ranges.

use super::prim::Slot as PrimSlot;
use super::Op;
use crate::sema::builtins::BuiltinId as B;
use crate::sema::Value;
use glam::{DMat3, DVec3};

/// A run-time number of a node: the generated code computes `value · scale`.
#[derive(Debug, Clone, PartialEq)]
pub struct Slot {
    /// A [`Value::Uniform`] (or a constant, for the other numbers of a primitive).
    pub value: Value,
    pub scale: f64,
}

/// The run-time numbers of a node.
#[derive(Debug, Clone, PartialEq)]
pub enum Dyn {
    /// A primitive's call arguments after the point, by the slot of its kind
    /// ([`super::prim::Kind::slots`]); `None` where the number is a constant.
    Prim(Vec<Option<Slot>>),
    /// The op's one number: a smooth blend's `k`, a translation's offset, a scale's
    /// factor, a warp's rate, an elongation, a rounding radius, a shell's half
    /// thickness.
    One(Slot),
    /// A rotation by a run-time angle about a constant unit axis.
    Rotate { axis: DVec3, angle: Slot },
}

/// Where a run-time argument goes in the lowered node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// Slot `i` of the primitive's call, times the scale.
    Prim(usize, f64),
    /// The op's one number, times the scale.
    One(f64),
    /// A rotation's angle.
    Angle,
}

/// Every run-time argument: builtin, parameter name, and where the lowering writes it.
pub const TARGETS: &[(B, &str, Target)] = &[
    (B::Sphere, "radius", Target::Prim(0, 1.0)),
    (B::Box, "size", Target::Prim(0, 0.5)),
    (B::BoxFrame, "size", Target::Prim(0, 0.5)),
    (B::BoxFrame, "thickness", Target::Prim(1, 0.5)),
    (B::Torus, "major", Target::Prim(0, 1.0)),
    (B::Torus, "minor", Target::Prim(1, 1.0)),
    (B::Capsule, "a", Target::Prim(0, 1.0)),
    (B::Capsule, "b", Target::Prim(1, 1.0)),
    (B::Capsule, "radius", Target::Prim(2, 1.0)),
    (B::Cylinder, "radius", Target::Prim(0, 1.0)),
    (B::Cylinder, "height", Target::Prim(1, 0.5)),
    (B::CappedCone, "height", Target::Prim(0, 0.5)),
    (B::CappedCone, "bottom", Target::Prim(1, 1.0)),
    (B::CappedCone, "top", Target::Prim(2, 1.0)),
    (B::Plane, "offset", Target::Prim(1, 1.0)),
    (B::Ellipsoid, "radii", Target::Prim(0, 1.0)),
    (B::Octahedron, "radius", Target::Prim(0, 1.0)),
    (B::HexPrism, "radius", Target::Prim(0, 1.0)),
    (B::HexPrism, "height", Target::Prim(1, 0.5)),
    (B::TriPrism, "radius", Target::Prim(0, 1.0)),
    (B::TriPrism, "height", Target::Prim(1, 0.5)),
    (B::Pyramid, "height", Target::Prim(0, 1.0)),
    (B::Link, "length", Target::Prim(0, 1.0)),
    (B::Link, "major", Target::Prim(1, 1.0)),
    (B::Link, "minor", Target::Prim(2, 1.0)),
    (B::SmoothUnion, "k", Target::One(1.0)),
    (B::SmoothIntersection, "k", Target::One(1.0)),
    (B::SmoothDifference, "k", Target::One(1.0)),
    (B::Translate, "offset", Target::One(1.0)),
    (B::Rotate, "angle", Target::Angle),
    (B::RotateX, "angle", Target::Angle),
    (B::RotateY, "angle", Target::Angle),
    (B::RotateZ, "angle", Target::Angle),
    (B::Scale, "factor", Target::One(1.0)),
    (B::Twist, "rate", Target::One(1.0)),
    (B::Bend, "rate", Target::One(1.0)),
    (B::Elongate, "amount", Target::One(1.0)),
    (B::Round, "radius", Target::One(1.0)),
    (B::Shell, "thickness", Target::One(0.5)),
    (B::Repeat, "period", Target::One(1.0)),
    (B::Displace, "scale", Target::One(1.0)),
];

/// The run-time numbers of a call of shape builtin `builtin` with `args` (some of them
/// [`Value::Uniform`]), for a node whose primitive has `slots` call arguments; `None`
/// when an argument the table does not list is a run-time value (the checker refuses
/// those first).
pub fn of(builtin: B, args: &[Value], slots: usize) -> Option<Dyn> {
    let b = builtin.builtin();
    let mut prim: Vec<Option<Slot>> = vec![None; slots];
    let mut one = None;
    for (param, value) in b.params.iter().zip(args) {
        if value.uniform().is_none() {
            continue;
        }
        let (_, _, target) = TARGETS
            .iter()
            .find(|(id, name, _)| *id == builtin && *name == param.name)?;
        let slot = |scale| Slot {
            value: value.clone(),
            scale,
        };
        match *target {
            Target::Prim(i, scale) => *prim.get_mut(i)? = Some(slot(scale)),
            Target::One(scale) => one = Some(Dyn::One(slot(scale))),
            Target::Angle => {
                let axis = match builtin {
                    B::RotateX => DVec3::X,
                    B::RotateY => DVec3::Y,
                    B::RotateZ => DVec3::Z,
                    _ => DVec3::from_slice(args.get(1)?.components()?).normalize(),
                };
                one = Some(Dyn::Rotate {
                    axis,
                    angle: slot(1.0),
                })
            }
        }
    }
    one.or_else(|| prim.iter().any(Option::is_some).then_some(Dyn::Prim(prim)))
}

/// A parameter's value by name (`None`: its current value).
pub type Values<'a> = &'a dyn Fn(&str) -> Option<Vec<f64>>;

/// A slot's number at `values`: its value times its scale, by component; `None`
/// when it is not a number.
fn number(s: &Slot, values: Values) -> Option<Vec<f64>> {
    let v = crate::sema::params::value_at(&s.value, values);
    let c = v.components()?;
    Some(c.iter().map(|x| x * s.scale).collect())
}

/// A vector slot's three components (a float broadcast, as the generated code does).
fn three(c: &[f64]) -> Option<DVec3> {
    match c.len() {
        1 => Some(DVec3::splat(c[0])),
        3 => Some(DVec3::from_slice(c)),
        _ => None,
    }
}

/// Writes the node's run-time numbers at `values` into `op`, as the generated code
/// computes them from the parameters' block: what the CPU reference then evaluates.
/// `None` when a number cannot be computed or does not fit the op.
pub fn apply(d: &Dyn, op: &mut Op, values: Values) -> Option<()> {
    match (d, op) {
        (Dyn::Prim(slots), Op::Prim(p)) => {
            let mut params = p.params();
            let mut at = 0;
            for (i, kind) in p.kind().slots.iter().enumerate() {
                let width = kind.words();
                if let Some(s) = slots.get(i).and_then(Option::as_ref) {
                    let c = number(s, values)?;
                    match kind {
                        PrimSlot::Float => params[at] = *c.first()?,
                        PrimSlot::Vec3 => {
                            params[at..at + 3].copy_from_slice(&three(&c)?.to_array())
                        }
                    }
                }
                at += width;
            }
            *p = p.with_params(&params)?;
        }
        (Dyn::Rotate { axis, angle }, Op::Rotate { inverse, .. }) => {
            let a = *number(angle, values)?.first()?;
            *inverse = DMat3::from_axis_angle(*axis, a).transpose();
        }
        (Dyn::One(s), op) => {
            let c = number(s, values)?;
            let x = *c.first()?;
            match op {
                Op::Csg { k, .. } => *k = x,
                Op::Translate { offset, .. } => *offset = three(&c)?,
                Op::Scale { factor, .. } => *factor = three(&c)?,
                Op::Twist { rate, .. } | Op::Bend { rate, .. } => *rate = x,
                Op::Elongate { h, .. } => *h = three(&c)?,
                Op::Round { r, .. } => *r = x,
                // The generated code's number is the half thickness.
                Op::Shell { thickness, .. } => *thickness = 2.0 * x,
                Op::Repeat { period, .. } => *period = three(&c)?,
                // d = scale · height: its range and slope scale with it (the checker
                // keeps the scale positive over its range).
                Op::Displace { height, .. } => {
                    let h = std::sync::Arc::make_mut(height);
                    let r = x / h.scale;
                    (h.lo, h.hi, h.slope, h.scale) = (h.lo * r, h.hi * r, h.slope * r, x);
                }
                _ => return None,
            }
        }
        _ => return None,
    }
    Some(())
}

impl super::Shape {
    /// The shape at other parameter values: each node's run-time numbers written at
    /// `values` ([`apply`]); bounds and Lipschitz constants, which hold over the
    /// parameters' whole ranges, stay. `None` when a number cannot be computed.
    pub fn at_params(&self, values: Values) -> Option<super::Shape> {
        let mut out = self.clone();
        for node in &mut out.nodes {
            if let Some(d) = node.dynamic.clone() {
                apply(&d, &mut node.op, values)?;
            }
        }
        Some(out)
    }

    /// The names of the parameters the shape's run-time numbers read.
    pub fn param_names(&self) -> std::collections::BTreeSet<String> {
        let mut out = std::collections::BTreeSet::new();
        for d in self.nodes.iter().filter_map(|n| n.dynamic.as_deref()) {
            let slots: Vec<&Slot> = match d {
                Dyn::Prim(slots) => slots.iter().flatten().collect(),
                Dyn::One(s) => vec![s],
                Dyn::Rotate { angle, .. } => vec![angle],
            };
            for s in slots {
                crate::sema::params::param_names(&s.value, &mut out);
            }
        }
        out
    }

    /// Whether some node's numbers are set at run time.
    pub fn is_dynamic(&self) -> bool {
        self.nodes.iter().any(|n| n.dynamic.is_some())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_lowering_writes_every_argument_the_checker_allows() {
        let mut ir: Vec<(String, String)> = super::TARGETS
            .iter()
            .map(|(b, n, _)| (b.name().to_string(), n.to_string()))
            .collect();
        let mut sema: Vec<(String, String)> = crate::sema::params::RUN_TIME_ARGS
            .iter()
            .flat_map(|(b, names)| names.iter().map(|n| (b.name().to_string(), n.to_string())))
            .collect();
        ir.sort();
        sema.sort();
        assert_eq!(ir, sema);
        // Every name is a parameter of its builtin.
        for (b, n, _) in super::TARGETS {
            assert!(b.builtin().params.iter().any(|p| p.name == *n), "{b:?} {n}");
        }
    }
}
