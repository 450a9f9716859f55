//! The merge graph of an atlas (§4.4 of the paper), solved at compile time on the CPU:
//! Alg. 1 between merged seeds gives each edge its geodesic length d_M, the parallel
//! transport R_{a→b} and the log maps Log_{p_a}(p_b), Log_{p_b}(p_a); then the optimal
//! frames (Eq. 45, the connection Laplacian of Eq. 48, one frame fixed per connected
//! group) and the optimal uv offsets (Eq. 47, one offset fixed). Cycles of the graph are
//! checked for topological obstructions (notes, Sec. C): frame holonomy and offset
//! residual around each cycle of a cycle basis.

use super::logmap::{log_map, LogMap, Params, Seed, Status};
use glam::{DMat3, DVec2, DVec3};
use nalgebra::DMatrix;
use nalgebra_sparse::factorization::CscCholesky;
use nalgebra_sparse::{CooMatrix, CscMatrix};

/// One merge edge with what Alg. 1 measured between its seeds.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    pub a: usize,
    pub b: usize,
    /// Index of the `merge` statement pair in the atlas definition.
    pub merge: usize,
    /// Geodesic length d_M(p_a, p_b) (the mean of the walks that succeeded).
    pub length: f64,
    /// Parallel transport R_{a→b}: T_{p_a}M → T_{p_b}M.
    pub transport: DMat3,
    /// Log_{p_a}(p_b) as a tangent vector at p_a (world coordinates).
    pub log_ab: DVec3,
    /// Log_{p_b}(p_a) as a tangent vector at p_b.
    pub log_ba: DVec3,
    /// Offset residual after the solve, relative to the length:
    /// |u_b − u_a − Log_{p_a}(p_b)| / d_M (in the solved frames).
    pub residual: f64,
}

/// A merge whose seeds cannot reach each other by Alg. 1, in either direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Unreachable {
    pub a: usize,
    pub b: usize,
    pub merge: usize,
    /// The walk from p_b to seed a (the first direction tried).
    pub status: Status,
    pub at: DVec3,
    pub distance_limit: f64,
}

/// A setting under which an unreachable merge's walk succeeds ([`remedy`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Remedy {
    Steps(u32),
    SharpTolerance(f64),
    MaxDistance(f64),
}

/// The first of the settings a user would try that makes seeds `a` and `b` reachable
/// (Alg. 1 succeeds in one direction at least): for a walk that went too far, the
/// `max_distance` it needs (rounded up); otherwise more `steps` (32, 48, 64), then,
/// for a sharp feature, a larger `sharp_tolerance` (0.03, 0.06, 0.1).
pub fn remedy(
    f: &dyn Fn(DVec3) -> f64,
    seeds: &[Seed],
    a: usize,
    b: usize,
    status: Status,
    params: &Params,
) -> Option<Remedy> {
    let walk = |p: &Params| {
        [
            log_map(f, seeds[b].p, &seeds[a], p),
            log_map(f, seeds[a].p, &seeds[b], p),
        ]
        .into_iter()
        .find(|m| m.status == Status::Ok)
    };
    if status == Status::TooFar {
        let m = walk(&Params {
            max_distance: f64::INFINITY,
            ..*params
        })?;
        // Two significant digits, rounded up, with 5 % to spare.
        let d = m.distance * 1.05;
        let unit = 10f64.powf(d.log10().floor() - 1.0);
        return Some(Remedy::MaxDistance((d / unit).ceil() * unit));
    }
    for steps in [32, 48, 64].into_iter().filter(|&n| n > params.steps) {
        if walk(&Params { steps, ..*params }).is_some() {
            return Some(Remedy::Steps(steps));
        }
    }
    if status != Status::SharpFeature {
        return None;
    }
    [0.03, 0.06, 0.1]
        .into_iter()
        .filter(|&t| t > params.sharp_tolerance)
        .find(|&t| {
            walk(&Params {
                sharp_tolerance: t,
                ..*params
            })
            .is_some()
        })
        .map(Remedy::SharpTolerance)
}

/// A cycle of a cycle basis of the merge graph with its obstruction measures.
#[derive(Debug, Clone, PartialEq)]
pub struct Cycle {
    /// The seeds around the cycle, in order.
    pub seeds: Vec<usize>,
    /// Edge indices (into [`MergeGraph::edges`]) around the cycle.
    pub edges: Vec<usize>,
    /// Angle (radians, in (−π, π]) of the composed transport around the cycle about the
    /// normal at its first seed.
    pub holonomy: f64,
    /// The largest relative offset residual among the cycle's edges.
    pub residual: f64,
    /// |Σ transported Log vectors| around the cycle over its length: how far the
    /// offset equations fail to close, independent of the solve.
    pub closure: f64,
}

/// The solved merge graph.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MergeGraph {
    pub edges: Vec<Edge>,
    pub unreachable: Vec<Unreachable>,
    /// Per seed: (neighbour, edge length), in edge order.
    pub neighbors: Vec<Vec<(usize, f64)>>,
    pub cycles: Vec<Cycle>,
    /// Per seed: the seed whose frame and offset were held fixed in its group.
    pub root: Vec<usize>,
    /// Wall time of the two linear solves (frames and offsets), seconds.
    pub solve_seconds: f64,
}

/// Holonomy (degrees) at or above which a cycle is reported as an obstruction.
pub const HOLONOMY_LIMIT_DEG: f64 = 10.0;
/// Relative offset residual at or above which a cycle is reported.
pub const RESIDUAL_LIMIT: f64 = 0.15;

impl Cycle {
    pub fn is_obstruction(&self) -> bool {
        self.holonomy.abs().to_degrees() >= HOLONOMY_LIMIT_DEG || self.residual >= RESIDUAL_LIMIT
    }
}

/// Builds and solves the merge graph. `seeds` get their frames (e1, e2) replaced by the
/// optimal ones; the offsets come back per seed (zero for unmerged seeds).
/// `pairs` are the merge edges (a, b) in statement order; `fixed` says which seeds keep
/// their frame when they are a group's first such seed (seeds with a written tangent).
pub fn solve(
    f: &dyn Fn(DVec3) -> f64,
    seeds: &mut [Seed],
    pairs: &[(usize, usize)],
    fixed: &[bool],
    params: &Params,
) -> (MergeGraph, Vec<DVec2>) {
    let n = seeds.len();
    let mut graph = MergeGraph {
        neighbors: vec![Vec::new(); n],
        root: (0..n).collect(),
        ..Default::default()
    };
    for (merge, &(a, b)) in pairs.iter().enumerate() {
        if a >= n || b >= n || a == b {
            continue;
        }
        // x = p_b walked to seed a: Log_{p_a}(p_b) and the transport T_{p_a} → T_{p_b}.
        let ab = log_map(f, seeds[b].p, &seeds[a], params);
        let ba = log_map(f, seeds[a].p, &seeds[b], params);
        let edge = match (ab.status, ba.status) {
            (Status::Ok, Status::Ok) => Edge {
                a,
                b,
                merge,
                length: 0.5 * (ab.distance + ba.distance),
                transport: mean_rotation(ab.transport, ba.transport.transpose()),
                log_ab: ab.tangent(&seeds[a]),
                log_ba: ba.tangent(&seeds[b]),
                residual: 0.0,
            },
            (Status::Ok, _) => one_way(a, b, merge, &ab, seeds),
            (_, Status::Ok) => {
                let mut e = one_way(b, a, merge, &ba, seeds);
                std::mem::swap(&mut e.a, &mut e.b);
                std::mem::swap(&mut e.log_ab, &mut e.log_ba);
                e.transport = e.transport.transpose();
                e
            }
            _ => {
                graph.unreachable.push(Unreachable {
                    a,
                    b,
                    merge,
                    status: ab.status,
                    at: ab.at,
                    distance_limit: params.max_distance,
                });
                continue;
            }
        };
        if edge.length <= 0.0 || !edge.length.is_finite() {
            continue;
        }
        graph.neighbors[a].push((b, edge.length));
        graph.neighbors[b].push((a, edge.length));
        graph.edges.push(edge);
    }
    let start = std::time::Instant::now();
    let groups = components(n, &graph.edges);
    let mut offsets = vec![DVec2::ZERO; n];
    for group in &groups {
        if group.len() < 2 {
            continue;
        }
        let root = group
            .iter()
            .copied()
            .find(|&i| fixed.get(i).copied().unwrap_or(false))
            .unwrap_or(group[0]);
        for &i in group {
            graph.root[i] = root;
        }
        solve_frames(seeds, &graph.edges, group, root);
        solve_offsets(seeds, &graph.edges, group, root, &mut offsets);
    }
    graph.solve_seconds = start.elapsed().as_secs_f64();
    for e in &mut graph.edges {
        let (sa, sb) = (&seeds[e.a], &seeds[e.b]);
        let log = DVec2::new(e.log_ab.dot(sa.e1), e.log_ab.dot(sa.e2));
        let back = DVec2::new(e.log_ba.dot(sb.e1), e.log_ba.dot(sb.e2));
        // Both directions entered the solve; the worse one is the edge's residual.
        e.residual = (offsets[e.b] - offsets[e.a] - log)
            .length()
            .max((offsets[e.a] - offsets[e.b] - back).length())
            / e.length;
    }
    graph.cycles = cycles(seeds, &graph.edges, n);
    (graph, offsets)
}

/// An edge known from one walk only: the other direction is inferred.
fn one_way(a: usize, b: usize, merge: usize, ab: &LogMap, seeds: &[Seed]) -> Edge {
    let log_ab = ab.tangent(&seeds[a]);
    Edge {
        a,
        b,
        merge,
        length: ab.distance,
        transport: ab.transport,
        log_ab,
        // On a plane Log_{p_b}(p_a) = −R_{a→b} Log_{p_a}(p_b).
        log_ba: -(ab.transport * log_ab),
        residual: 0.0,
    }
}

/// The rotation halfway between two estimates of the same transport.
fn mean_rotation(r1: DMat3, r2: DMat3) -> DMat3 {
    let q1 = glam::DQuat::from_mat3(&r1).normalize();
    let mut q2 = glam::DQuat::from_mat3(&r2).normalize();
    if q1.dot(q2) < 0.0 {
        q2 = -q2;
    }
    DMat3::from_quat(q1.slerp(q2, 0.5))
}

/// Connected components of the merge graph, each sorted by seed index.
fn components(n: usize, edges: &[Edge]) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for e in edges {
        let (ra, rb) = (find(&mut parent, e.a), find(&mut parent, e.b));
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut slot = vec![usize::MAX; n];
    for i in 0..n {
        let r = find(&mut parent, i);
        if slot[r] == usize::MAX {
            slot[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[slot[r]].push(i);
    }
    groups
}

/// The free seeds of a group (all but the root) in breadth-first order from the root,
/// and each seed's index among them, so that assembling the systems is linear in the
/// edges and the sparse factor stays narrow (neighbours get near indices).
fn free_slots(
    n: usize,
    edges: &[Edge],
    group: &[usize],
    root: usize,
) -> (Vec<usize>, Vec<Option<usize>>) {
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for e in edges {
        adj[e.a].push(e.b);
        adj[e.b].push(e.a);
    }
    let mut in_group = vec![false; n];
    for &i in group {
        in_group[i] = true;
    }
    let mut seen = vec![false; n];
    let mut order = vec![root];
    seen[root] = true;
    let mut next = 0;
    while next < order.len() {
        let i = order[next];
        next += 1;
        for &j in &adj[i] {
            if in_group[j] && !seen[j] {
                seen[j] = true;
                order.push(j);
            }
        }
    }
    // A group is connected; any seed not reached still gets a slot.
    order.extend(group.iter().copied().filter(|&i| !seen[i]));
    let free: Vec<usize> = order.into_iter().filter(|&i| i != root).collect();
    let mut slots = vec![None; n];
    for (k, &i) in free.iter().enumerate() {
        slots[i] = Some(k);
    }
    (free, slots)
}

/// Solves the symmetric positive definite system `a x = rhs` (its entries as triplets,
/// duplicates summed) by Cholesky: sparse for large systems, which are graph
/// Laplacians with a few entries per row (a dense factor costs cubic time: a 22 × 22
/// merged grid took 1.7 G instructions, 92 % of its compile, and now 0.03 s in all);
/// dense up to [`DENSE_SOLVE`] unknowns, where it is the cheaper. None when `a` is not
/// positive definite.
fn solve_spd(a: &CooMatrix<f64>, rhs: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if a.nrows() <= DENSE_SOLVE {
        return DMatrix::from(a).cholesky().map(|c| c.solve(rhs));
    }
    let a = CscMatrix::from(a);
    CscCholesky::factor(&a).ok().map(|c| c.solve(rhs))
}

/// The most unknowns solved densely (robot.sdf's merge groups, up to 12: a sparse factor
/// cost 1 % more of its whole compile; plate.sdf's 189: 3 % less).
const DENSE_SOLVE: usize = 64;

/// Eq. 45 with t_root fixed: the connection Laplacian (Eq. 48) restricted to the free
/// seeds of the group, solved by sparse Cholesky; e1 is then t projected onto each
/// tangent plane.
fn solve_frames(seeds: &mut [Seed], edges: &[Edge], group: &[usize], root: usize) {
    let (free, slots) = free_slots(seeds.len(), edges, group, root);
    let index = |i: usize| slots[i];
    let m = 3 * free.len();
    let mut a = CooMatrix::<f64>::new(m, m);
    let mut rhs = DMatrix::<f64>::zeros(m, 1);
    let t_root = seeds[root].e1;
    let block = |a: &mut CooMatrix<f64>, r: usize, c: usize, mat: DMat3, s: f64| {
        for col in 0..3 {
            for row in 0..3 {
                a.push(3 * r + row, 3 * c + col, s * mat.col(col)[row]);
            }
        }
    };
    for e in edges.iter().filter(|e| slots[e.a].is_some() || e.a == root) {
        let w = 1.0 / (e.length * e.length);
        // E = w |R t_a − t_b|²: ∂/∂t_a = w (t_a − Rᵀ t_b), ∂/∂t_b = w (t_b − R t_a).
        let r = e.transport;
        match (index(e.a), index(e.b)) {
            (Some(ia), Some(ib)) => {
                block(&mut a, ia, ia, DMat3::IDENTITY, w);
                block(&mut a, ib, ib, DMat3::IDENTITY, w);
                block(&mut a, ia, ib, r.transpose(), -w);
                block(&mut a, ib, ia, r, -w);
            }
            (Some(ia), None) => {
                block(&mut a, ia, ia, DMat3::IDENTITY, w);
                let v = r.transpose() * t_root * w;
                for k in 0..3 {
                    rhs[3 * ia + k] += v[k];
                }
            }
            (None, Some(ib)) => {
                block(&mut a, ib, ib, DMat3::IDENTITY, w);
                let v = r * t_root * w;
                for k in 0..3 {
                    rhs[3 * ib + k] += v[k];
                }
            }
            (None, None) => {}
        }
    }
    let Some(t) = solve_spd(&a, &rhs) else {
        return;
    };
    for (k, &i) in free.iter().enumerate() {
        let ti = DVec3::new(t[3 * k], t[3 * k + 1], t[3 * k + 2]);
        let s = &mut seeds[i];
        if let Some(e1) = (ti - s.n * s.n.dot(ti)).try_normalize() {
            s.e1 = e1;
            s.e2 = s.n.cross(e1);
        }
    }
}

/// Eq. 47 with u_root = 0: a weighted graph Laplacian with two right-hand sides. Both
/// directions of each edge enter: u_b − u_a ≈ Log_{p_a}(p_b), u_a − u_b ≈ Log_{p_b}(p_a).
fn solve_offsets(
    seeds: &[Seed],
    edges: &[Edge],
    group: &[usize],
    root: usize,
    offsets: &mut [DVec2],
) {
    let (free, slots) = free_slots(seeds.len(), edges, group, root);
    let index = |i: usize| slots[i];
    let m = free.len();
    let mut a = CooMatrix::<f64>::new(m, m);
    let mut rhs = DMatrix::<f64>::zeros(m, 2);
    for e in edges.iter().filter(|e| slots[e.a].is_some() || e.a == root) {
        let w = 1.0 / (e.length * e.length);
        let (sa, sb) = (&seeds[e.a], &seeds[e.b]);
        let l_ab = DVec2::new(e.log_ab.dot(sa.e1), e.log_ab.dot(sa.e2));
        let l_ba = DVec2::new(e.log_ba.dot(sb.e1), e.log_ba.dot(sb.e2));
        // Target for u_b − u_a: the mean of both directions.
        let delta = 0.5 * (l_ab - l_ba);
        let (ia, ib) = (index(e.a), index(e.b));
        if let Some(ia) = ia {
            a.push(ia, ia, w);
            rhs[(ia, 0)] -= w * delta.x;
            rhs[(ia, 1)] -= w * delta.y;
        }
        if let Some(ib) = ib {
            a.push(ib, ib, w);
            rhs[(ib, 0)] += w * delta.x;
            rhs[(ib, 1)] += w * delta.y;
        }
        if let (Some(ia), Some(ib)) = (ia, ib) {
            a.push(ia, ib, -w);
            a.push(ib, ia, -w);
        }
    }
    let Some(u) = solve_spd(&a, &rhs) else {
        return;
    };
    for (k, &i) in free.iter().enumerate() {
        offsets[i] = DVec2::new(u[(k, 0)], u[(k, 1)]);
    }
    offsets[root] = DVec2::ZERO;
}

/// A cycle basis (one fundamental cycle per non-tree edge of a BFS forest) with the
/// holonomy and residuals of each cycle.
fn cycles(seeds: &[Seed], edges: &[Edge], n: usize) -> Vec<Cycle> {
    // BFS forest: parent edge of each seed.
    let mut adj: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
    for (k, e) in edges.iter().enumerate() {
        adj[e.a].push((e.b, k));
        adj[e.b].push((e.a, k));
    }
    let mut parent: Vec<Option<(usize, usize)>> = vec![None; n];
    let mut depth = vec![usize::MAX; n];
    let mut tree = vec![false; edges.len()];
    for s in 0..n {
        if depth[s] != usize::MAX {
            continue;
        }
        depth[s] = 0;
        let mut queue = std::collections::VecDeque::from([s]);
        while let Some(i) = queue.pop_front() {
            for &(j, k) in &adj[i] {
                if depth[j] == usize::MAX {
                    depth[j] = depth[i] + 1;
                    parent[j] = Some((i, k));
                    tree[k] = true;
                    queue.push_back(j);
                }
            }
        }
    }
    let mut out = Vec::new();
    for (k, e) in edges.iter().enumerate() {
        if tree[k] {
            continue;
        }
        // Path a → … → lca ← … ← b, then the edge b → a closes it.
        let (mut x, mut y) = (e.a, e.b);
        let (mut up_a, mut up_b) = (Vec::new(), Vec::new());
        while x != y {
            if depth[x] >= depth[y] {
                let (p, pk) = parent[x].expect("a non-root node has a parent");
                up_a.push((x, p, pk));
                x = p;
            } else {
                let (p, pk) = parent[y].expect("a non-root node has a parent");
                up_b.push((y, p, pk));
                y = p;
            }
        }
        // Oriented steps (from, to, edge): a up to lca, lca down to b, then b → a.
        let mut steps: Vec<(usize, usize, usize)> = up_a.clone();
        steps.extend(up_b.iter().rev().map(|&(c, p, pk)| (p, c, pk)));
        steps.push((e.b, e.a, k));
        let start = e.a;
        let mut rot = DMat3::IDENTITY;
        let mut sum = DVec3::ZERO;
        let mut length = 0.0;
        for &(from, _, ek) in &steps {
            let ed = &edges[ek];
            let (r, log) = if ed.a == from {
                (ed.transport, ed.log_ab)
            } else {
                (ed.transport.transpose(), ed.log_ba)
            };
            // Log at `from`, brought back to the start's tangent plane.
            sum += rot.transpose() * log;
            rot = r * rot;
            length += ed.length;
        }
        let s = &seeds[start];
        let t = rot * s.e1;
        let holonomy = t.dot(s.e2).atan2(t.dot(s.e1));
        let residual = steps
            .iter()
            .map(|&(_, _, ek)| edges[ek].residual)
            .fold(0.0, f64::max);
        out.push(Cycle {
            seeds: steps.iter().map(|&(from, _, _)| from).collect(),
            edges: steps.iter().map(|&(_, _, ek)| ek).collect(),
            holonomy,
            residual,
            closure: sum.length() / length.max(1e-300),
        });
    }
    out
}
