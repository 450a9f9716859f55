//! Large unions as data: a hard union of many simple leaves (a primitive under
//! translations, rotations and a paint) becomes a table of leaf records and a
//! bounding-volume hierarchy over their boxes, walked without a stack. The CPU
//! reference ([`Group::eval`]) and the generated shader (`codegen::group`) walk the same
//! tree, encoded once ([`Group::words`]), so both skip the same leaves.
//!
//! Skipping is exact for exact distance fields: outside a leaf's box its distance is at
//! least the distance to the box, so a box farther than the best distance so far cannot
//! lower it. For bounds that underestimate (an ellipsoid's), the result stays a lower
//! bound of the true distance, equal to the full union's wherever the nearest leaf is
//! nearer than every skipped box (on and near the surface).

use super::{eval, Aabb, Csg, NodeId, Op, Prim, Shape};
use glam::{DMat3, DVec3};
use std::hash::{Hash, Hasher};

/// The fewest simple leaves for which a union becomes a group: about 150 lines of WGSL
/// as code, one call as a group. (On Mesa's lavapipe, with the render's per-tile
/// culling, `sdfc bench --scale` draws 1,000 and 1,200 spheres faster as a group
/// than as code, 100 slower: a SIMD CPU gathers the table per lane. The groups also
/// gain the pipeline, the compile and the size of the code.)
pub const MIN_LEAVES: usize = 16;

/// No leaf: an inner node of the tree.
pub const INNER: u32 = u32::MAX;

/// Words per tree node: box min (3), skip, box max (3), leaf record offset.
pub const NODE_WORDS: usize = 8;

/// Where an unturned leaf's parameters start in its record: after its head, its
/// material and its translation (`Group::encode`; a turned leaf's matrix comes first).
pub const RECORD_PARAMS: u32 = 5;

/// A primitive with the affine map to its local frame, `q = m p + c`, and its material.
#[derive(Debug, Clone, PartialEq)]
pub struct Leaf {
    pub prim: Prim,
    pub m: DMat3,
    pub c: DVec3,
    pub material: u32,
    pub bounds: Aabb,
}

impl Leaf {
    pub fn eval(&self, p: DVec3) -> f64 {
        eval::prim(self.m * p + self.c, &self.prim)
    }

    /// Whether the leaf's record holds a matrix (it is turned, not only moved).
    pub fn has_matrix(&self) -> bool {
        !self.m.abs_diff_eq(DMat3::IDENTITY, 0.0)
    }
}

/// One node of the flattened tree, in depth-first order: `skip` is the index after its
/// subtree; a leaf node holds one leaf.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeNode {
    pub bounds: Aabb,
    pub skip: u32,
    pub leaf: Option<u32>,
}

/// A union of leaves (as data) and other children (as code), in that order:
/// `union(leaves…, others…)`, ties going to the earlier operand.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    pub leaves: Vec<Leaf>,
    pub others: Vec<NodeId>,
    pub tree: Vec<TreeNode>,
    /// The table the shader reads (`Group::encode`).
    pub words: Vec<u32>,
    /// A name for the group's code and constants, from its table: equal tables share
    /// one function.
    pub key: String,
}

/// The primitive kinds' codes in leaf records (`codegen::group` switches on them):
/// [`Prim::code`].
pub fn kind(p: &Prim) -> u32 {
    p.code()
}

/// A primitive's parameters as a leaf record stores them: [`Prim::params`].
pub fn params(p: &Prim) -> Vec<f64> {
    p.params()
}

/// Node `id` as a leaf: a chain of translations, rotations and paints down to a
/// primitive with a finite box.
fn leaf(shape: &Shape, id: NodeId) -> Option<Leaf> {
    let bounds = shape[id].bounds;
    if !(bounds.min.is_finite() && bounds.max.is_finite()) {
        return None;
    }
    let (mut m, mut c, mut material) = (DMat3::IDENTITY, DVec3::ZERO, None);
    let mut at = id;
    loop {
        // Run-time numbers are generated as code, not as the group's data.
        if shape[at].dynamic.is_some() {
            return None;
        }
        match &shape[at].op {
            Op::Translate { offset, child } => {
                c -= *offset;
                at = *child;
            }
            Op::Rotate { inverse, child } => {
                m = *inverse * m;
                c = *inverse * c;
                at = *child;
            }
            Op::Paint { material: k, child } => {
                // The outermost paint wins.
                material.get_or_insert(*k);
                at = *child;
            }
            Op::Prim(prim) => {
                return Some(Leaf {
                    prim: prim.clone(),
                    m,
                    c,
                    material: material.unwrap_or(0),
                    bounds,
                })
            }
            _ => return None,
        }
    }
}

pub(crate) fn is_hard_union(op: &Op) -> bool {
    matches!(
        op,
        Op::Csg {
            op: Csg::Union,
            k,
            ..
        } if *k == 0.0
    )
}

/// The groups of a shape, by node: each maximal hard union (not itself the unshared
/// operand of a hard union) with at least [`MIN_LEAVES`] simple leaves.
pub fn groups(shape: &Shape) -> Vec<Option<std::sync::Arc<Group>>> {
    let n = shape.nodes.len();
    let mut absorbed = vec![false; n];
    for node in &shape.nodes {
        if is_hard_union(&node.op) {
            for c in node.op.children() {
                if !shape.is_shared(c) {
                    absorbed[c.index()] = true;
                }
            }
        }
    }
    (0..n)
        .map(|i| {
            let id = NodeId::new(i);
            if absorbed[i] || !is_hard_union(&shape[id].op) {
                return None;
            }
            let g = build(shape, id);
            (g.leaves.len() >= MIN_LEAVES).then(|| std::sync::Arc::new(g))
        })
        .collect()
}

/// The operands of the hard union at `root`, left to right, through unshared hard unions.
fn operands(shape: &Shape, root: NodeId) -> Vec<NodeId> {
    let (mut out, mut stack) = (Vec::new(), vec![root]);
    while let Some(id) = stack.pop() {
        match &shape[id].op {
            Op::Csg { a, b, .. }
                if is_hard_union(&shape[id].op) && (id == root || !shape.is_shared(id)) =>
            {
                stack.push(*b);
                stack.push(*a);
            }
            _ => out.push(id),
        }
    }
    out
}

fn build(shape: &Shape, root: NodeId) -> Group {
    let (mut leaves, mut others) = (Vec::new(), Vec::new());
    for id in operands(shape, root) {
        match leaf(shape, id) {
            Some(l) => leaves.push(l),
            None => others.push(id),
        }
    }
    let mut tree = Vec::with_capacity(2 * leaves.len());
    let mut order: Vec<u32> = (0..leaves.len() as u32).collect();
    if !order.is_empty() {
        split(&leaves, &mut order, &mut tree);
    }
    let mut g = Group {
        leaves,
        others,
        tree,
        words: Vec::new(),
        key: String::new(),
    };
    g.words = g.encode();
    let mut h = std::collections::hash_map::DefaultHasher::new();
    g.words.hash(&mut h);
    g.key = format!("{:016x}", h.finish());
    g
}

/// `x` in f32, rounded down (`up == false`) or up: boxes only grow in single precision.
fn outward(x: f64, up: bool) -> u32 {
    let v = x as f32;
    // At least one unit in the last place.
    let ulp = (v.abs() * f32::EPSILON).max(f32::MIN_POSITIVE);
    let v = if up && (v as f64) < x {
        v + ulp
    } else if !up && (v as f64) > x {
        v - ulp
    } else {
        v
    };
    v.to_bits()
}

fn merge(a: Aabb, b: Aabb) -> Aabb {
    Aabb {
        min: a.min.min(b.min),
        max: a.max.max(b.max),
    }
}

/// Appends the subtree over `items` in depth-first order: split at the median of the
/// boxes' centres along the centres' longest axis.
fn split(leaves: &[Leaf], items: &mut [u32], tree: &mut Vec<TreeNode>) {
    let bounds = items
        .iter()
        .map(|&i| leaves[i as usize].bounds)
        .reduce(merge)
        .expect("a subtree has leaves");
    let at = tree.len();
    tree.push(TreeNode {
        bounds,
        skip: 0,
        leaf: None,
    });
    if let [only] = items {
        tree[at].leaf = Some(*only);
    } else {
        let centre = |i: u32| {
            let b = leaves[i as usize].bounds;
            (b.min + b.max) * 0.5
        };
        let (lo, hi) = items.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &i| (lo.min(centre(i)), hi.max(centre(i))),
        );
        let e = hi - lo;
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        // Stable, so equal centres keep the leaves' order (the build is deterministic).
        items.sort_by(|&a, &b| centre(a)[axis].total_cmp(&centre(b)[axis]));
        let mid = items.len() / 2;
        let (left, right) = items.split_at_mut(mid);
        split(leaves, left, tree);
        split(leaves, right, tree);
    }
    tree[at].skip = tree.len() as u32;
}

/// The groups of `shape` whose leaves a ray's trace may restrict to those it can meet
/// (`gpu::tiles`), in the order found: each reached from the root through hard unions
/// and paints alone, no node on the way shared or run-time. Along such a path the
/// shape is `min(group, others)` up to a material, so a leaf the ray never comes near
/// changes neither where the ray first meets the surface nor the distance there.
pub fn traced(shape: &Shape) -> Vec<NodeId> {
    let (mut out, mut stack) = (Vec::new(), vec![shape.root()]);
    while let Some(id) = stack.pop() {
        let node = &shape[id];
        if shape.is_shared(id) || node.dynamic.is_some() {
            continue;
        }
        if shape.group(id).is_some() {
            out.push(id);
            continue;
        }
        match &node.op {
            Op::Csg { a, b, .. } if is_hard_union(&node.op) => {
                stack.push(*b);
                stack.push(*a);
            }
            Op::Paint { child, .. } => stack.push(*child),
            _ => {}
        }
    }
    out
}

/// The distance from `p` to a box: 0 inside.
pub fn box_distance(p: DVec3, b: &Aabb) -> f64 {
    (b.min - p).max(p - b.max).max(DVec3::ZERO).length()
}

impl Group {
    /// The leaf reached by descending from the root into the child whose box is nearer
    /// `p` (the first on ties): a nearby leaf, whose distance starts the search with a
    /// tight bound. A node's children are the next node and the node after the first
    /// child's subtree.
    pub fn descend(&self, p: DVec3) -> u32 {
        let mut i = 0;
        loop {
            if let Some(k) = self.tree[i].leaf {
                return k;
            }
            let (l, r) = (i + 1, self.tree[i + 1].skip as usize);
            let (bl, br) = (
                box_distance(p, &self.tree[l].bounds),
                box_distance(p, &self.tree[r].bounds),
            );
            i = if br < bl { r } else { l };
        }
    }

    /// The union of the leaves at `p`: (distance, material), ties to the earlier leaf.
    /// The leaf [`Group::descend`] finds gives the first bound; then subtrees whose box
    /// is farther than the best distance so far are skipped.
    pub fn eval(&self, p: DVec3) -> (f64, u32) {
        let first = self.descend(p);
        let leaf = &self.leaves[first as usize];
        let (mut best, mut material, mut best_leaf) = (leaf.eval(p), leaf.material, first);
        let mut i = 0;
        while i < self.tree.len() {
            let node = &self.tree[i];
            let b = box_distance(p, &node.bounds);
            if b > 0.0 && b > best {
                i = node.skip as usize;
                continue;
            }
            if let Some(k) = node.leaf {
                let leaf = &self.leaves[k as usize];
                let d = leaf.eval(p);
                if d < best || (d == best && k < best_leaf) {
                    (best, material, best_leaf) = (d, leaf.material, k);
                }
            }
            i += 1;
        }
        (best, material)
    }

    /// The group's table, as the `tables` buffer holds it from the group's offset: the
    /// tree ([`NODE_WORDS`] a node; a leaf node's last word is
    /// its record's offset from the group's start), then the leaf records: `kind | 256 if it has a matrix`, the
    /// material, c (3), m (9, column-major, only with the flag), the parameters.
    fn encode(&self) -> Vec<u32> {
        let f = |x: f64| (x as f32).to_bits();
        let mut records = Vec::new();
        let mut offsets = Vec::with_capacity(self.leaves.len());
        let base = self.tree.len() * NODE_WORDS;
        for l in &self.leaves {
            offsets.push((base + records.len()) as u32);
            let flag = if l.has_matrix() { 256 } else { 0 };
            records.push(kind(&l.prim) | flag);
            records.push(f(l.material as f64));
            records.extend(l.c.to_array().map(f));
            if l.has_matrix() {
                records.extend(l.m.to_cols_array().map(f));
            }
            records.extend(params(&l.prim).into_iter().map(f));
        }
        let mut out = Vec::with_capacity(base + records.len());
        for n in &self.tree {
            out.extend(n.bounds.min.to_array().map(|x| outward(x, false)));
            out.push(n.skip);
            out.extend(n.bounds.max.to_array().map(|x| outward(x, true)));
            out.push(n.leaf.map_or(INNER, |k| offsets[k as usize]));
        }
        out.extend(records);
        out
    }

    /// Each leaf's record: its offset from the group's start in [`Group::words`] (what
    /// a leaf node's last word holds), by leaf index; increasing with the index.
    pub fn records(&self) -> Vec<u32> {
        let mut out = vec![0; self.leaves.len()];
        for (i, n) in self.tree.iter().enumerate() {
            if let Some(k) = n.leaf {
                out[k as usize] = self.words[(i + 1) * NODE_WORDS - 1];
            }
        }
        out
    }

    /// The kinds of primitive among the leaves, sorted.
    pub fn kinds(&self) -> Vec<u32> {
        let mut k: Vec<u32> = self.leaves.iter().map(|l| kind(&l.prim)).collect();
        k.sort_unstable();
        k.dedup();
        k
    }
}
