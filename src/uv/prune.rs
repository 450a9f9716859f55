//! Per-seed pruned fields (issue #15): a walk from seed j stays near seed j, so the
//! operands of the shape's unions whose bounds lie far from it cannot change f where
//! the walk queries it. The generated field skips them there.
//!
//! **Where.** The *union chain* is the root and, below it, every union (hard or smooth)
//! and paint reached through unions and paints only; a union's operands are the
//! *candidates* (at most [`MAX_CANDIDATES`], the costliest first). Shared nodes (a
//! `let` used twice) and groups are not entered: their code is evaluated at other
//! points too.
//!
//! **When.** A walk from seed j with reach ρ (its D, or twice its chord when that is
//! less: a geodesic path from x to p_j rarely strays farther) clears the bit of
//! candidate c when `ρ < limit[j][c]`, and evaluates inside the *guard*: points within
//! `GUARD·ρ + ε` of p_j, whose pruned value v has `|v| < WINDOW·ρ + ε`. Anywhere else
//! the full field is evaluated again, so the pruned field is exact everywhere the
//! proof below holds and merely slower where its heuristics miss.
//!
//! **Why it is exact.** Let B = M + 1.25·K, with M the window and K the sum of the
//! chain's smooth-union radii k. A pruned operand has F ≥ B everywhere in the guard:
//! its box lies at least L·B beyond the guard (the limit's condition), and outside its
//! box a field is at least the box distance divided by its Lipschitz bound L (an exact
//! field, L = 1, is the distance itself). Bottom up through the
//! chain, every node either has its full value F equal to its pruned value P, or has
//! both F and P at least B − 1.25·(the k below it): an smin with one operand ≥ β
//! either equals the other (which is then below β − k) or is at least β − 1.25·k.
//! At the root that threshold is above M, so `|P| < M` gives F = P. Operands pruned
//! are replaced by 1e30, which leaves smin(a, 1e30, k) = a exactly, in f32 as in f64.

use crate::ir::group::box_distance;
use crate::ir::{Csg, Field, NodeId, Op, Shape};
use glam::DVec3;

/// Bits of the pruning mask (one `u32`).
pub const MAX_CANDIDATES: usize = 32;
/// The guard's radius, in reaches.
pub const GUARD: f64 = 1.25;
/// The window of |f| in which the pruned value is used, in reaches.
pub const WINDOW: f64 = 0.1;
/// A walk's reach: at most this many times the chord from its seed.
pub const CHORD_REACH: f64 = 2.0;

/// The pruning of one atlas's field for its seeds.
#[derive(Debug, Clone, PartialEq)]
pub struct Pruning {
    /// Candidate c is bit c of the mask.
    pub candidates: Vec<NodeId>,
    /// Whether a node is on the union chain (its operands' bits apply).
    pub on_chain: Vec<bool>,
    /// Per seed, per candidate: the reach below which the candidate is pruned.
    pub limit: Vec<f64>,
    /// The absolute slack of the guard and the window (1e-3 of the shape's size).
    pub eps: f64,
}

/// A walk's pruning: its mask, seed and reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkMask {
    pub mask: u32,
    pub centre: DVec3,
    pub reach: f64,
}

impl WalkMask {
    /// The full field (outside walks).
    pub const FULL: WalkMask = WalkMask {
        mask: u32::MAX,
        centre: DVec3::ZERO,
        reach: 0.0,
    };
}

impl Pruning {
    /// The pruning of `shape` for seeds at `seeds`, or None when no seed could ever skip
    /// a union operand.
    pub fn new(shape: &Shape, seeds: &[DVec3]) -> Option<Pruning> {
        if shape.nodes.is_empty() || seeds.is_empty() {
            return None;
        }
        let mut on_chain = vec![false; shape.nodes.len()];
        let mut found: Vec<NodeId> = Vec::new();
        let mut smoothing = 0.0;
        let mut stack = vec![shape.root()];
        while let Some(id) = stack.pop() {
            if (id != shape.root() && shape.is_shared(id)) || shape.group(id).is_some() {
                continue;
            }
            match shape[id].op {
                Op::Csg {
                    op: Csg::Union,
                    k,
                    a,
                    b,
                } => {
                    on_chain[id.index()] = true;
                    smoothing += k.max(0.0);
                    for c in [a, b] {
                        if shape[c].bounds.is_finite() && !found.contains(&c) {
                            found.push(c);
                        }
                        stack.push(c);
                    }
                }
                Op::Paint { child, .. } => {
                    on_chain[id.index()] = true;
                    stack.push(child);
                }
                _ => {}
            }
        }
        let size = shape.framing_bounds();
        let eps = 1e-3 * (size.max - size.min).max_element().max(1e-6);
        // Per seed, the reach below which candidate c is pruned:
        // ρ < limit ⟺ d − ε − L(ε + 1.25K) > ρ (GUARD + L·WINDOW), d the distance from the
        // seed to c's box and L c's Lipschitz bound (at least 1).
        let limits = |c: NodeId| -> Vec<f64> {
            let node = &shape[c];
            let l = node.lipschitz.max(1.0);
            seeds
                .iter()
                .map(|p| {
                    let d = box_distance(*p, &node.bounds);
                    (d - eps - l * (eps + 1.25 * smoothing)) / (GUARD + l * WINDOW)
                })
                .collect()
        };
        // Operands no seed could ever skip (the unions that hold most of the shape) take
        // no bit; the costliest of the others first (nodes in their subtrees).
        let mut found: Vec<(NodeId, Vec<f64>)> = found
            .into_iter()
            .map(|c| (c, limits(c)))
            .filter(|(_, l)| l.iter().any(|&l| l > 0.0))
            .collect();
        if found.is_empty() {
            return None;
        }
        let cost = subtree_sizes(shape);
        found.sort_by_key(|(c, _)| std::cmp::Reverse(cost[c.index()]));
        found.truncate(MAX_CANDIDATES);
        let mut limit = Vec::with_capacity(seeds.len() * found.len());
        for j in 0..seeds.len() {
            limit.extend(found.iter().map(|(_, l)| l[j]));
        }
        let found: Vec<NodeId> = found.into_iter().map(|(c, _)| c).collect();
        Some(Pruning {
            candidates: found,
            on_chain,
            limit,
            eps,
        })
    }

    /// The mask of a walk from seed `j` with reach `reach`: the bits of the candidates
    /// it must evaluate.
    pub fn mask(&self, j: usize, reach: f64) -> u32 {
        let n = self.candidates.len();
        let mut mask = u32::MAX;
        for c in 0..n {
            if reach < self.limit[j * n + c] {
                mask &= !(1u32 << c);
            }
        }
        mask
    }

    /// The walk's pruning from seed `j` at `p_j` towards a point `x`, with D `dmax`.
    pub fn walk(&self, j: usize, centre: DVec3, x: DVec3, dmax: f64) -> WalkMask {
        let reach = dmax.min(CHORD_REACH * (x - centre).length());
        WalkMask {
            mask: self.mask(j, reach),
            centre,
            reach,
        }
    }

    /// The bit of candidate `id`, if it is one.
    pub fn bit(&self, id: NodeId) -> Option<u32> {
        self.candidates
            .iter()
            .position(|&c| c == id)
            .map(|c| c as u32)
    }

    /// The field as the generated code evaluates it in a walk: the pruned value inside
    /// the guard and the window, the full one elsewhere.
    pub fn field<'a>(&self, field: impl Into<Field<'a>>, p: DVec3, walk: WalkMask) -> f64 {
        let field = field.into();
        if walk.mask != u32::MAX && (p - walk.centre).length() <= GUARD * walk.reach + self.eps {
            let v = self.pruned(field, p, walk.mask);
            if v.abs() < WINDOW * walk.reach + self.eps {
                return v;
            }
        }
        crate::ir::eval::distance(field, p)
    }

    /// The field with the candidates whose bits are clear replaced by 1e30 (no guard).
    pub fn pruned<'a>(&self, field: impl Into<Field<'a>>, p: DVec3, mask: u32) -> f64 {
        let field = field.into();
        self.node(field, field.shape.root(), p, mask)
    }

    fn node(&self, field: Field, id: NodeId, p: DVec3, mask: u32) -> f64 {
        let shape = field.shape;
        if !self.on_chain[id.index()] {
            return crate::ir::eval::node_distance(field, id, p);
        }
        match shape[id].op {
            Op::Csg { k, a, b, .. } => {
                let value = |c: NodeId| match self.bit(c) {
                    Some(bit) if mask & (1 << bit) == 0 => 1e30,
                    _ => self.node(field, c, p, mask),
                };
                crate::ir::eval::smin(value(a), value(b), k)
            }
            Op::Paint { child, .. } => self.node(field, child, p, mask),
            _ => crate::ir::eval::node_distance(field, id, p),
        }
    }
}

/// Nodes in each node's subtree (shared nodes counted once per use).
fn subtree_sizes(shape: &Shape) -> Vec<u64> {
    let mut size = vec![0u64; shape.nodes.len()];
    for (i, n) in shape.nodes.iter().enumerate() {
        let own = match shape.group(NodeId::new(i)) {
            Some(g) => g.leaves.len() as u64,
            None => 1,
        };
        size[i] =
            n.op.children()
                .iter()
                .fold(own, |s, c| s.saturating_add(size[c.index()]));
    }
    size
}
