//! Per-node bounds for the tracer: a union's costly operand is evaluated only when
//! its bounding box comes near enough to change the union.
//!
//! For `union(a, b)` with blend radius `k`, where `b`'s field is at least the distance
//! to its box `B` outside it (its field is *exact outside*, [`exact_outside`]): once
//! `a` is known, wherever `dist(p, B) > max(f_a, 0) + k + margin`, `f_b > f_a + k`,
//! and the (smooth) union is `f_a` itself, material and all. So `b` is skipped
//! there with no change to the field at all, near the surface or far from it. The
//! generated shader (`codegen::emit`) and the CPU reference ([`super::eval`]) test the
//! same boxes; `tests` prove the equality on every example.
//!
//! The CPU reference always skips (a scalar branch is real). The generated code does
//! so on request (`--bounds`): on a SIMD machine the branch saves work only where a
//! whole group of lanes skips, and the box test is paid everywhere; on Mesa's software
//! adapter an `if` never skips at all (gallivm runs it under lane masks), so there the
//! tests are pure cost, and the default emits none.

use super::{Csg, NodeId, Op, Prim, Shape};
use glam::DVec3;

/// The estimated cost (in primitive evaluations) from which `--bounds costly` guards an
/// operand; the box test itself costs about one.
pub const MIN_COST: f64 = 6.0;

/// The guard of one union node.
#[derive(Debug, Clone, PartialEq)]
pub struct Guard {
    /// The operand evaluated first, always.
    pub first: NodeId,
    /// The operand evaluated behind the test.
    pub guarded: NodeId,
    /// The guarded operand's box, as centre and half size.
    pub center: DVec3,
    pub half: DVec3,
    /// Skip where `dist(p, box) > max(f_first, 0) + slack`: the blend radius and a
    /// margin for single precision.
    pub slack: f64,
    /// The guarded operand's estimated cost (primitive evaluations).
    pub cost: f64,
}

impl Guard {
    /// Whether the guarded operand can change the union at `p`, where the first
    /// operand's distance is `first`.
    pub fn needed(&self, p: DVec3, first: f64) -> bool {
        // A NaN first operand: the union is the other (Rust's min ignores NaN).
        if first.is_nan() {
            return true;
        }
        // As the shaders' guard: sd_box(p - centre, half).
        let outside = super::eval::box_dist(p - self.center, self.half);
        // A NaN box distance evaluates the operand.
        outside.partial_cmp(&(first.max(0.0) + self.slack)) != Some(std::cmp::Ordering::Greater)
    }
}

/// Every node's estimated cost, in primitive evaluations.
pub fn costs(shape: &Shape) -> Vec<f64> {
    let mut cost = vec![0.0; shape.nodes.len()];
    for (i, n) in shape.nodes.iter().enumerate() {
        let c = |id: &NodeId| cost[id.index()];
        cost[i] = match &n.op {
            Op::Prim(p) => p.kind().cost,
            Op::Csg { a, b, .. } => c(a) + c(b) + 0.5,
            Op::Translate { child, .. } | Op::Round { child, .. } | Op::Paint { child, .. } => {
                c(child) + 0.25
            }
            Op::Shell { child, .. } => c(child) + 0.25,
            Op::Rotate { child, .. }
            | Op::Scale { child, .. }
            | Op::Repeat { child, .. }
            | Op::Mirror { child, .. }
            | Op::Elongate { child, .. } => c(child) + 0.5,
            Op::Twist { child, .. } | Op::Bend { child, .. } => c(child) + 2.0,
            // The base again for the projection's gradient (7 in the band), and the height.
            Op::Displace { child, .. } => 8.0 * c(child) + 4.0,
            Op::ShellMap { base, tile, .. } => 8.0 * c(base) + c(tile) + 4.0,
        };
    }
    cost
}

/// Which nodes' fields are at least the distance to their bounds outside them, as
/// their operations guarantee: exact distances, and the operations that keep such a
/// lower bound with the bounds `lower` gives them.
pub fn exact_outside(shape: &Shape) -> Vec<bool> {
    let mut exact = vec![false; shape.nodes.len()];
    for (i, n) in shape.nodes.iter().enumerate() {
        let e = |id: &NodeId| exact[id.index()];
        // A node with run-time numbers keeps none of these guarantees over its range.
        exact[i] = n.dynamic.is_none()
            && match &n.op {
                // IQ's ellipsoid and triangular prism are bounds that underestimate.
                Op::Prim(Prim::Ellipsoid { .. } | Prim::TriPrism { .. }) => false,
                Op::Prim(_) => true,
                // min(a, b) minus at most k/4 (the bounds grow by k/4).
                Op::Csg {
                    op: Csg::Union,
                    a,
                    b,
                    ..
                } => e(a) && e(b),
                // max(a, b) plus a non-negative blend term: at least an operand whose box is
                // the intersection's.
                Op::Csg {
                    op: Csg::Intersection,
                    a,
                    b,
                    ..
                } => [a, b].iter().any(|o| e(o) && shape[**o].bounds == n.bounds),
                // At least max(a, -b) ≥ a, and the bounds are a's.
                Op::Csg {
                    op: Csg::Difference,
                    a,
                    ..
                } => e(a),
                // Rigid maps and uniform scales carry the bound; a non-uniform scale
                // underestimates by min(factor).
                Op::Translate { child, .. }
                | Op::Rotate { child, .. }
                | Op::Paint { child, .. } => e(child),
                Op::Scale { factor, child } => {
                    e(child) && factor.min_element() == factor.max_element()
                }
                // Warps rotate points about the origin within the child's ball (radius R):
                // the field is at least |p| − R, and the box holds the ball. An unbounded
                // child has no ball (its warp's box is only a framing guess).
                Op::Twist { child, radius, .. } | Op::Bend { child, radius, .. } => {
                    e(child) && radius.is_finite()
                }
                // The child's box grows by what the operation can subtract.
                Op::Mirror { child, .. }
                | Op::Elongate { child, .. }
                | Op::Round { child, .. }
                | Op::Shell { child, .. }
                | Op::Displace { child, .. } => e(child),
                Op::Repeat { .. } | Op::ShellMap { .. } => false,
            };
    }
    exact
}

/// The guard of each union node whose operand can be skipped by its box, with the
/// operand's cost.
pub fn guards(shape: &Shape) -> Vec<Option<Guard>> {
    let cost = costs(shape);
    let exact = exact_outside(shape);
    shape
        .nodes
        .iter()
        .map(|n| {
            let Op::Csg {
                op: Csg::Union,
                k,
                a,
                b,
            } = n.op
            else {
                return None;
            };
            if n.dynamic.is_some() {
                return None;
            }
            let can = |o: NodeId| exact[o.index()] && shape[o].bounds.is_finite();
            // Both: the smaller box, which more points are far from (in a chain of
            // unions, the new operand against the running union), or the costlier.
            let size = |o: NodeId| {
                let b = shape[o].bounds;
                ((b.max - b.min).length(), -cost[o.index()])
            };
            let (first, guarded) = match (can(a), can(b)) {
                (true, true) if size(a) < size(b) => (b, a),
                (_, true) => (a, b),
                (true, false) => (b, a),
                (false, false) => return None,
            };
            let bounds = shape[guarded].bounds;
            let (center, half) = (
                (bounds.min + bounds.max) * 0.5,
                (bounds.max - bounds.min) * 0.5,
            );
            // Single precision's rounding of the box test and of the operand's own field.
            let margin = 1e-4 * (1.0 + center.abs().max_element() + half.max_element());
            Some(Guard {
                first,
                guarded,
                center,
                half,
                slack: k + margin,
                cost: cost[guarded.index()],
            })
        })
        .collect()
}
