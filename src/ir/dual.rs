//! Which shapes the compiler differentiates forward (`codegen::dual`): every node's
//! gradient by the chain rule, from primitives' gradients by hand (`prim::Kind::gradient`,
//! `shaders/dual.wgsl`) or differences of the primitive alone. A displacement or a shell
//! map reads a texture and a group is a data union walked in a loop: a shape with one of
//! them keeps differences of the whole field. The CPU reference reads the same answer
//! (`uv::geodesic::Params::exact_gradient`), so both sides of a walk use exact gradients
//! or both use the same differences.

use super::{eval, warp_outer, Csg, NodeId, Op, Prim, Shape};
use glam::{DMat3, DVec2, DVec3};

/// Whether every node reachable from the root of `shape` has a forward derivative.
pub fn supported(shape: &Shape) -> bool {
    let mut seen = vec![false; shape.nodes.len()];
    let mut stack = vec![shape.root()];
    while let Some(id) = stack.pop() {
        if std::mem::replace(&mut seen[id.index()], true) {
            continue;
        }
        if !node_supported(shape, id) {
            return false;
        }
        stack.extend(shape[id].op.children());
    }
    true
}

fn node_supported(shape: &Shape, id: NodeId) -> bool {
    if shape.group(id).is_some() {
        return false;
    }
    !matches!(shape[id].op, Op::Displace { .. } | Op::ShellMap { .. })
}

/// A distance with its gradient, (∇f, f): the f64 mirror of `vec4<f32>(∇f, f)`.
pub type Dual = (DVec3, f64);

/// The sign of `x`, 1 at 0 (`dual_sign` of the shaders).
fn sign(x: f64) -> f64 {
    if x < 0.0 {
        -1.0
    } else {
        1.0
    }
}

fn unit(v: DVec3, fallback: DVec3) -> DVec3 {
    let l = v.length();
    if l > 0.0 {
        v / l
    } else {
        fallback
    }
}

fn unit2(v: DVec2, fallback: DVec2) -> DVec2 {
    let l = v.length();
    if l > 0.0 {
        v / l
    } else {
        fallback
    }
}

/// The f64 mirror of `shaders/dual.wgsl`'s `dsd_box_core`.
fn box_core(p: DVec3, half: DVec3) -> Dual {
    let s = DVec3::new(sign(p.x), sign(p.y), sign(p.z));
    let q = p.abs() - half;
    let outside = q.max(DVec3::ZERO);
    let l = outside.length();
    let inner = q.max_element();
    if l > 0.0 {
        return (outside / l * s, l + inner.min(0.0));
    }
    let axis = if q.x >= q.y && q.x >= q.z {
        DVec3::X
    } else if q.y >= q.z {
        DVec3::Y
    } else {
        DVec3::Z
    };
    (axis * s, inner)
}

/// The gradient of min(max(d.x, d.y), 0) + |max(d, 0)| with respect to d, and the value.
fn rect(d: DVec2) -> (DVec2, f64) {
    let outside = d.max(DVec2::ZERO);
    let l = outside.length();
    if l > 0.0 {
        return (outside / l, l + d.x.max(d.y).min(0.0));
    }
    let g = if d.x >= d.y { DVec2::X } else { DVec2::Y };
    (g, d.x.max(d.y))
}

/// A primitive's (∇f, f) at `p` in its frame, as the generated WGSL computes it: by
/// hand (`dsd_K`) or by central differences of the primitive alone with a step of 1e-3
/// of its size.
pub fn prim(p: DVec3, pr: &Prim) -> Dual {
    match *pr {
        Prim::Sphere { r } => (unit(p, DVec3::Y), p.length() - r),
        Prim::Box { half } => box_core(p, half),
        Prim::RoundBox { half, r } => {
            let (g, d) = box_core(p, half);
            (g, d - r)
        }
        Prim::Torus { major, minor } => {
            let l = DVec2::new(p.x, p.z).length();
            let radial = unit2(DVec2::new(p.x, p.z), DVec2::X);
            let v = DVec2::new(l - major, p.y);
            let dv = unit2(v, DVec2::Y);
            (
                DVec3::new(dv.x * radial.x, dv.y, dv.x * radial.y),
                v.length() - minor,
            )
        }
        Prim::Capsule { a, b, r } => {
            let w = super::prim::capsule_offset(p, a, b);
            (unit(w, DVec3::Y), w.length() - r)
        }
        Prim::Cylinder { r, half_h } => {
            let l = DVec2::new(p.x, p.z).length();
            let radial = unit2(DVec2::new(p.x, p.z), DVec2::X);
            let (g, d) = rect(DVec2::new(l - r, p.y.abs() - half_h));
            (
                DVec3::new(g.x * radial.x, g.y * sign(p.y), g.x * radial.y),
                d,
            )
        }
        Prim::Plane { n, offset } => (n, p.dot(n) - offset),
        Prim::Ellipsoid { radii } => {
            let r2 = radii * radii;
            let (k0, k1) = ((p / radii).length(), (p / r2).length());
            if k1 == 0.0 {
                return (DVec3::Y, -radii.min_element());
            }
            let (dk0, dk1) = (p / r2 / k0, p / (r2 * r2) / k1);
            let f = k0 * (k0 - 1.0) / k1;
            (((2.0 * k0 - 1.0) * dk0 - f * dk1) / k1, f)
        }
        Prim::TriPrism { r, half_h } => {
            let q = p.abs();
            let cap = (DVec3::new(0.0, 0.0, sign(p.z)), q.z - half_h);
            let slanted = (
                DVec3::new(0.866_025_4 * sign(p.x), 0.5, 0.0),
                q.x * 0.866_025_4 + p.y * 0.5 - r * 0.5,
            );
            let base = (DVec3::new(0.0, -1.0, 0.0), -p.y - r * 0.5);
            let side = if slanted.1 >= base.1 { slanted } else { base };
            if side.1 >= cap.1 {
                side
            } else {
                cap
            }
        }
        Prim::Link { le, r1, r2 } => {
            let over = p.y.abs() - le;
            let q = DVec3::new(p.x, over.max(0.0), p.z);
            let u = DVec2::new(q.x, q.y).length();
            let du = unit2(DVec2::new(q.x, q.y), DVec2::X);
            let v = DVec2::new(u - r1, q.z);
            let dv = unit2(v, DVec2::X);
            let dy = if over > 0.0 { sign(p.y) } else { 0.0 };
            (
                DVec3::new(dv.x * du.x, dv.x * du.y * dy, dv.y),
                v.length() - r2,
            )
        }
        Prim::BoxFrame { .. }
        | Prim::CappedCone { .. }
        | Prim::Octahedron { .. }
        | Prim::HexPrism { .. }
        | Prim::Pyramid { .. } => {
            let h = difference_step(pr);
            let d = |e: DVec3| eval::prim(p + e * h, pr) - eval::prim(p - e * h, pr);
            (
                DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z)) / (2.0 * h),
                eval::prim(p, pr),
            )
        }
    }
}

/// The step of a primitive's own central differences (the kinds without a gradient by
/// hand): 1e-3 of the largest side of its bounds.
pub fn difference_step(pr: &Prim) -> f64 {
    let b = pr.bounds();
    let size = (b.max - b.min).max_element();
    let size = if size.is_finite() { size } else { 1.0 };
    1e-3 * size.max(1e-6)
}

/// The polynomial smooth minimum on (∇, f) pairs (`dual_smin`).
fn smin(a: Dual, b: Dual, k: f64) -> Dual {
    let (m, other) = if a.1 <= b.1 { (a, b) } else { (b, a) };
    if k <= 0.0 {
        return m;
    }
    let h = (k - (a.1 - b.1).abs()).max(0.0) / k;
    (m.0 + (other.0 - m.0) * (0.5 * h), m.1 - h * h * k * 0.25)
}

fn neg(a: Dual) -> Dual {
    (-a.0, -a.1)
}

/// Jᵀ g of a twist (`dual_twist`) at its input point `u` (in its frame).
fn twist_back(u: DVec3, rate: f64, g: DVec3) -> DVec3 {
    let (s, c) = (rate * u.y).sin_cos();
    let (t0, t2) = (c * u.x - s * u.z, s * u.x + c * u.z);
    DVec3::new(
        c * g.x + s * g.z,
        -rate * t2 * g.x + g.y + rate * t0 * g.z,
        -s * g.x + c * g.z,
    )
}

/// Jᵀ g of a bend (`dual_bend`) at its input point `u` (in its frame).
fn bend_back(u: DVec3, rate: f64, g: DVec3) -> DVec3 {
    let (s, c) = (rate * u.x).sin_cos();
    let (t0, t1) = (c * u.x - s * u.y, s * u.x + c * u.y);
    DVec3::new(
        (c - rate * t1) * g.x + (s + rate * t0) * g.y,
        -s * g.x + c * g.y,
        g.z,
    )
}

/// The shape's (∇f, f) at `p` by forward derivatives, the f64 mirror of the generated
/// `atlas_K_dual` (`codegen::dual`): the same branches, hand gradients and primitive
/// differences, so that the CPU reference and the shader agree on creases too, where
/// a gradient is one-sided. Only for shapes [`supported`] accepts; elsewhere (a group,
/// a displacement, a shell map) the value with the gradient of central differences.
pub fn eval(shape: &Shape, p: DVec3) -> Dual {
    node(shape, shape.root(), p)
}

fn node(shape: &Shape, id: NodeId, p: DVec3) -> Dual {
    stacker::maybe_grow(64 * 1024, 1024 * 1024, || node_inner(shape, id, p))
}

fn node_inner(shape: &Shape, id: NodeId, p: DVec3) -> Dual {
    let op = &shape[id].op;
    if !node_supported(shape, id) {
        let f = super::eval::Field::plain(shape);
        return (eval::gradient(f, p), eval::node_distance(f, id, p));
    }
    match op {
        Op::Prim(pr) => prim(p, pr),
        Op::Csg { op, k, a, b } => {
            let (da, db) = (node(shape, *a, p), node(shape, *b, p));
            match op {
                Csg::Union => smin(da, db, *k),
                Csg::Intersection => neg(smin(neg(da), neg(db), *k)),
                Csg::Difference => neg(smin(neg(da), db, *k)),
            }
        }
        Op::Translate { child, .. } | Op::Repeat { child, .. } => {
            node(shape, *child, op.child_point(p))
        }
        Op::Paint { child, .. } => node(shape, *child, p),
        Op::Rotate { inverse, child } => {
            let (g, d) = node(shape, *child, op.child_point(p));
            (inverse.transpose() * g, d)
        }
        Op::Scale { factor, child } => {
            let (g, d) = node(shape, *child, op.child_point(p));
            let m = factor.min_element();
            (g / *factor * m, d * m)
        }
        Op::Twist { radius, .. } | Op::Bend { radius, .. } if p.length() > warp_outer(*radius) => {
            (unit(p, DVec3::Y), p.length() - radius)
        }
        Op::Twist {
            frame, rate, child, ..
        }
        | Op::Bend {
            frame, rate, child, ..
        } => {
            let (g, d) = node(shape, *child, op.child_point(p));
            let (f, u): (DMat3, DVec3) = (*frame, *frame * p);
            let back = if matches!(op, Op::Twist { .. }) {
                twist_back(u, *rate, f * g)
            } else {
                bend_back(u, *rate, f * g)
            };
            (f.transpose() * back, d)
        }
        Op::Mirror { normal, child } => {
            let (g, d) = node(shape, *child, op.child_point(p));
            if p.dot(*normal) < 0.0 {
                (g - 2.0 * g.dot(*normal) * *normal, d)
            } else {
                (g, d)
            }
        }
        Op::Elongate { h, child } => {
            let (g, d) = node(shape, *child, op.child_point(p));
            let keep = |x: f64, h: f64| if x.abs() > h { 1.0 } else { 0.0 };
            (
                g * DVec3::new(keep(p.x, h.x), keep(p.y, h.y), keep(p.z, h.z)),
                d,
            )
        }
        Op::Round { r, child } => {
            let (g, d) = node(shape, *child, p);
            (g, d - r)
        }
        Op::Shell { thickness, child } => {
            let (g, d) = node(shape, *child, p);
            (g * sign(d), d.abs() - thickness * 0.5)
        }
        // Not reached: node_supported sends these to differences above.
        Op::Displace { .. } | Op::ShellMap { .. } => unreachable_dual(shape, id, p),
    }
}

fn unreachable_dual(shape: &Shape, id: NodeId, p: DVec3) -> Dual {
    let f = super::eval::Field::plain(shape);
    (eval::gradient(f, p), eval::node_distance(f, id, p))
}
