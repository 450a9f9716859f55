//! Rest-pose queries (§5.1 of the Implicit UVs paper, Fig. 13 row A).
//!
//! An atlas is declared on a shape `body`; the render target may use `body` under
//! transforms and warps ω (`body.twist(…).translate(…)`). A point x on the rendered
//! surface ω(M) satisfies f(ω⁻¹(x)) = 0, so its uv is Alg. 2 on f queried at ω⁻¹(x): the
//! walk runs on the rest pose and the texture follows the deformation at no extra cost.
//!
//! Every IR transform already evaluates its child at ω⁻¹(p) (translations, rotations,
//! scales, twists, bends, and the folds of `repeat` and `mirror`), so ω⁻¹ is the
//! composition of the point maps on the path from the target's root to the atlas's
//! shape. [`RestQuery::find`] finds every place where the atlas's shape occurs in the
//! target (structurally: the same subtree); where it occurs several times (a rest-pose
//! copy beside a deformed one), a point takes the occurrence whose rest point lies
//! nearest the atlas's surface (smallest |f(ω_i⁻¹(x))|).
//!
//! The transported seed frames (the tangent frame of normal maps) live in the rest
//! pose; they are carried to the deformed surface by the differential of ω, which is
//! the inverse of the Jacobian of ω⁻¹ (by central differences).
//!
//! `elongate` has no inverse (it collapses its middle), so uv through it are constant
//! across the stretched part; [`RestQuery::stretched`] says so, for a warning.

use super::{eval, NodeId, Op, Shape};
use glam::{DMat3, DVec3};

/// Most occurrences followed; beyond it the rest are left out (and said so).
pub const MAX_OCCURRENCES: usize = 16;

/// One place the atlas's shape occurs in the target: the point maps from the target's
/// root down to it (each op's own child point, see [`Op::child_point`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Occurrence {
    /// The point-mapping nodes (with their run-time numbers, if any).
    pub steps: Vec<super::Node>,
}

impl Occurrence {
    /// ω⁻¹(p).
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.steps.iter().fold(p, |q, n| n.op.child_point(q))
    }

    /// Whether tangent vectors change on the way (anything but translations).
    pub fn moves_frames(&self) -> bool {
        self.steps
            .iter()
            .any(|n| !matches!(n.op, Op::Translate { .. }))
    }

    /// The Jacobian of ω⁻¹ at `p` (columns ∂ω⁻¹/∂x, ∂/∂y, ∂/∂z) by central differences
    /// of step `h`.
    pub fn jacobian(&self, p: DVec3, h: f64) -> DMat3 {
        let c = |e: DVec3| (self.apply(p + e * h) - self.apply(p - e * h)) / (2.0 * h);
        DMat3::from_cols(c(DVec3::X), c(DVec3::Y), c(DVec3::Z))
    }
}

/// Where an atlas's shape occurs in a render target.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RestQuery {
    /// Empty when the target does not contain the atlas's shape: the uv are then queried
    /// at the point itself (the projection onto the atlas's surface).
    pub occurrences: Vec<Occurrence>,
    /// Some path goes through `elongate`, which has no inverse.
    pub stretched: bool,
    /// More than [`MAX_OCCURRENCES`] occurrences: the rest were left out.
    pub truncated: bool,
}

impl RestQuery {
    /// Every occurrence of `atlas_shape` in `target`.
    pub fn find(target: &Shape, atlas_shape: &Shape) -> RestQuery {
        let mut q = RestQuery::default();
        if target.nodes.is_empty() || atlas_shape.nodes.is_empty() {
            return q;
        }
        // Which nodes are the atlas's shape, and which contain it: one pass over the
        // DAG (children come before parents), so the paths below only go where an
        // occurrence is, and shared nodes are compared once.
        let mut memo = Memo::default();
        let n = target.nodes.len();
        let mut is = vec![false; n];
        let mut contains = vec![false; n];
        for i in 0..n {
            let id = NodeId::new(i);
            is[i] = same_memo(target, id, atlas_shape, atlas_shape.root(), &mut memo);
            contains[i] = is[i] || target[id].op.children().iter().any(|c| contains[c.index()]);
        }
        let mut steps = Vec::new();
        let mut stretched = false;
        let found = Found {
            is: &is,
            contains: &contains,
        };
        q.visit(target, target.root(), &found, &mut steps, &mut stretched);
        q
    }

    fn visit(
        &mut self,
        target: &Shape,
        id: NodeId,
        found: &Found,
        steps: &mut Vec<super::Node>,
        stretched: &mut bool,
    ) {
        if !found.contains[id.index()] || self.truncated {
            return;
        }
        if found.is[id.index()] {
            if self.occurrences.len() == MAX_OCCURRENCES {
                self.truncated = true;
            } else {
                self.occurrences.push(Occurrence {
                    steps: steps.clone(),
                });
                self.stretched |= *stretched;
            }
            return;
        }
        let op = &target[id].op;
        let maps = op.is_point_map();
        let was = *stretched;
        if maps {
            steps.push(target[id].clone());
            *stretched |= matches!(op, Op::Elongate { .. });
        }
        // A shell map's tile is evaluated at shell coordinates, not at a moved point:
        // only its base is followed.
        let children = match op {
            Op::ShellMap { base, .. } => vec![*base],
            _ => op.children(),
        };
        for c in children {
            stacker::maybe_grow(64 * 1024, 1024 * 1024, || {
                self.visit(target, c, found, steps, stretched)
            });
        }
        if maps {
            steps.pop();
        }
        *stretched = was;
    }

    /// Whether the query is the point itself.
    pub fn is_identity(&self) -> bool {
        self.occurrences.len() <= 1 && self.occurrences.iter().all(|o| o.steps.is_empty())
    }

    /// The occurrence a point belongs to (the one whose rest point is nearest the
    /// atlas's surface; the first on ties) and its rest point; `None` without any.
    pub fn locate<'a>(
        &self,
        atlas_shape: impl Into<eval::Field<'a>>,
        p: DVec3,
    ) -> Option<(usize, DVec3)> {
        let atlas_shape = atlas_shape.into();
        let mut best: Option<(usize, DVec3, f64)> = None;
        for (i, o) in self.occurrences.iter().enumerate() {
            let q = o.apply(p);
            if self.occurrences.len() == 1 {
                return Some((0, q));
            }
            let f = eval::distance(atlas_shape, q).abs();
            if best.is_none_or(|b| f < b.2) {
                best = Some((i, q, f));
            }
        }
        best.map(|(i, q, _)| (i, q))
    }
}

/// Which target nodes are the atlas's shape, and which contain it.
struct Found<'a> {
    is: &'a [bool],
    contains: &'a [bool],
}

/// Comparisons already made, by node pair: shapes are DAGs (a `let` used twice), and
/// comparing them as trees can take exponential time.
type Memo = std::collections::HashMap<(NodeId, NodeId), bool>;

/// Whether subtree `x` of `a` and subtree `y` of `b` are the same shape.
fn same_memo(a: &Shape, x: NodeId, b: &Shape, y: NodeId, memo: &mut Memo) -> bool {
    if let Some(&r) = memo.get(&(x, y)) {
        return r;
    }
    let (oa, ob) = (&a[x].op, &b[y].op);
    let r = std::mem::discriminant(oa) == std::mem::discriminant(ob) && {
        let (ca, cb) = (oa.children(), ob.children());
        ca.len() == cb.len()
            && strip(oa) == strip(ob)
            && ca.iter().zip(&cb).all(|(&i, &j)| {
                stacker::maybe_grow(64 * 1024, 1024 * 1024, || same_memo(a, i, b, j, memo))
            })
    };
    memo.insert((x, y), r);
    r
}

/// The op with its children's ids zeroed, to compare the op's own parameters.
fn strip(op: &Op) -> Op {
    let mut o = op.clone();
    for c in o.children_mut() {
        *c = NodeId::new(0);
    }
    o
}
