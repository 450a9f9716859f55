//! Run-time values in the IR: which of a node's numbers the generated code computes
//! from the parameters' uniform block ([`Dyn`]), and how the lowering writes each
//! run-time argument ([`TARGETS`], agreeing with the checker's
//! `sema::params::RUN_TIME_ARGS`). The node's own numbers hold the parameters'
//! current values, which the CPU reference evaluates; its bounds and Lipschitz
//! constant hold over the parameters' whole ranges.

use crate::sema::builtins::BuiltinId as B;
use crate::sema::Value;
use glam::DVec3;

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
