//! The CPU reference: the IR evaluated in f64.
//!
//! It is the oracle for the GPU path and the compiler's tool for geometry at
//! compile time (seed projection). Every function here mirrors one in
//! `shaders/sdf.wgsl`.

use super::*;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// The signed distance to a centred box of half size `half` (`sd_box` in the shaders).
pub fn box_dist(p: DVec3, half: DVec3) -> f64 {
    let q = p.abs() - half;
    q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
}

/// A primitive's distance at a local point.
pub fn prim(p: DVec3, prim: &Prim) -> f64 {
    match *prim {
        Prim::Sphere { r } => p.length() - r,
        Prim::Box { half } => box_dist(p, half),
        Prim::RoundBox { half, r } => box_dist(p, half) - r,
        Prim::BoxFrame { half, e } => {
            let p = p.abs() - half;
            let q = (p + DVec3::splat(e)).abs() - DVec3::splat(e);
            let a = DVec3::new(p.x, q.y, q.z);
            let b = DVec3::new(q.x, p.y, q.z);
            let c = DVec3::new(q.x, q.y, p.z);
            let part = |v: DVec3| v.max(DVec3::ZERO).length() + v.max_element().min(0.0);
            part(a).min(part(b)).min(part(c))
        }
        Prim::Torus { major, minor } => {
            DVec2::new(DVec2::new(p.x, p.z).length() - major, p.y).length() - minor
        }
        Prim::Capsule { a, b, r } => {
            let (pa, ba) = (p - a, b - a);
            let bb = ba.dot(ba);
            let h = if bb > 0.0 {
                (pa.dot(ba) / bb).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (pa - ba * h).length() - r
        }
        Prim::Cylinder { r, half_h } => {
            let d = DVec2::new(DVec2::new(p.x, p.z).length(), p.y).abs() - DVec2::new(r, half_h);
            d.x.max(d.y).min(0.0) + d.max(DVec2::ZERO).length()
        }
        Prim::CappedCone { half_h: h, r1, r2 } => {
            let q = DVec2::new(DVec2::new(p.x, p.z).length(), p.y);
            let k1 = DVec2::new(r2, h);
            let k2 = DVec2::new(r2 - r1, 2.0 * h);
            let ca = DVec2::new(
                q.x - q.x.min(if q.y < 0.0 { r1 } else { r2 }),
                q.y.abs() - h,
            );
            let cb = q - k1 + k2 * ((k1 - q).dot(k2) / k2.dot(k2)).clamp(0.0, 1.0);
            let s = if cb.x < 0.0 && ca.y < 0.0 { -1.0 } else { 1.0 };
            s * ca.dot(ca).min(cb.dot(cb)).sqrt()
        }
        Prim::Plane { n, offset } => p.dot(n) - offset,
        Prim::Ellipsoid { radii } => {
            let k0 = (p / radii).length();
            let k1 = (p / (radii * radii)).length();
            if k1 == 0.0 {
                -radii.min_element()
            } else {
                k0 * (k0 - 1.0) / k1
            }
        }
        Prim::Octahedron { s } => {
            let p = p.abs();
            let m = p.x + p.y + p.z - s;
            let q = if 3.0 * p.x < m {
                p
            } else if 3.0 * p.y < m {
                DVec3::new(p.y, p.z, p.x)
            } else if 3.0 * p.z < m {
                DVec3::new(p.z, p.x, p.y)
            } else {
                return m * 0.577_350_269_189_625_8;
            };
            let k = (0.5 * (q.z - q.y + s)).clamp(0.0, s);
            DVec3::new(q.x, q.y - s + k, q.z - k).length()
        }
        Prim::HexPrism { r, half_h } => {
            let k = DVec3::new(-0.866_025_403_784_438_6, 0.5, 0.577_350_269_189_625_8);
            let mut p = p.abs();
            let kxy = DVec2::new(k.x, k.y);
            let pxy = DVec2::new(p.x, p.y) - 2.0 * kxy.dot(DVec2::new(p.x, p.y)).min(0.0) * kxy;
            p.x = pxy.x;
            p.y = pxy.y;
            let d = DVec2::new(
                (DVec2::new(p.x, p.y) - DVec2::new(p.x.clamp(-k.z * r, k.z * r), r)).length()
                    * (p.y - r).signum(),
                p.z - half_h,
            );
            d.x.max(d.y).min(0.0) + d.max(DVec2::ZERO).length()
        }
        Prim::TriPrism { r, half_h } => {
            let q = p.abs();
            (q.z - half_h).max((q.x * 0.866_025_403_784_438_6 + p.y * 0.5).max(-p.y) - r * 0.5)
        }
        Prim::Pyramid { h } => {
            // Below the base the nearest point is on the base square; IQ's formula
            // overestimates there.
            if p.y < 0.0 {
                return DVec3::new((p.x.abs() - 0.5).max(0.0), p.y, (p.z.abs() - 0.5).max(0.0))
                    .length();
            }
            let m2 = h * h + 0.25;
            let (mut px, py, mut pz) = (p.x.abs(), p.y, p.z.abs());
            if pz > px {
                std::mem::swap(&mut px, &mut pz);
            }
            px -= 0.5;
            pz -= 0.5;
            let q = DVec3::new(pz, h * py - 0.5 * px, h * px + 0.5 * py);
            let s = (-q.x).max(0.0);
            let t = ((q.y - 0.5 * pz) / (m2 + 0.25)).clamp(0.0, 1.0);
            let a = m2 * (q.x + s) * (q.x + s) + q.y * q.y;
            let b = m2 * (q.x + 0.5 * t) * (q.x + 0.5 * t) + (q.y - m2 * t) * (q.y - m2 * t);
            let d2 = if q.y.min(-q.x * m2 - q.y * 0.5) > 0.0 {
                0.0
            } else {
                a.min(b)
            };
            ((d2 + q.z * q.z) / m2).sqrt() * q.z.max(-py).signum()
        }
        Prim::Link { le, r1, r2 } => {
            let q = DVec3::new(p.x, (p.y.abs() - le).max(0.0), p.z);
            DVec2::new(DVec2::new(q.x, q.y).length() - r1, q.z).length() - r2
        }
    }
}

/// Quadratic polynomial smooth minimum (IQ), with the blend factor for materials.
pub fn smin(a: f64, b: f64, k: f64) -> f64 {
    if k <= 0.0 {
        return a.min(b);
    }
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// A shape's field with what evaluating it needs: the shape (plain IR) and the
/// environment its heights and shell-map uv read ([`Heights`]: the prepared atlases and
/// decoded textures). A `&Shape` converts into a field with [`NoHeights`], so the free
/// functions below take either; a shape whose displacements read textures or atlases
/// then evaluates them conservatively (the band's shift), the same on every call.
#[derive(Debug, Clone, Copy)]
pub struct Field<'a> {
    pub shape: &'a Shape,
    pub heights: &'a dyn Heights,
}

impl<'a> From<&'a Shape> for Field<'a> {
    fn from(shape: &'a Shape) -> Field<'a> {
        Field::plain(shape)
    }
}

impl<'a> Field<'a> {
    pub fn new(shape: &'a Shape, heights: &'a dyn Heights) -> Field<'a> {
        Field { shape, heights }
    }

    /// The shape with [`NoHeights`].
    pub fn plain(shape: &'a Shape) -> Field<'a> {
        Field {
            shape,
            heights: &NoHeights,
        }
    }
}

impl<'a> From<&Field<'a>> for Field<'a> {
    fn from(f: &Field<'a>) -> Field<'a> {
        *f
    }
}

/// A field reads as its shape (bounds, Lipschitz bound, nodes).
impl std::ops::Deref for Field<'_> {
    type Target = Shape;

    fn deref(&self) -> &Shape {
        self.shape
    }
}

/// Distance and material id (0 = default) of a shape at `p`: the material that
/// dominates there ([`Blend::dominant`]).
pub fn eval<'a>(field: impl Into<Field<'a>>, p: DVec3) -> (f64, u32) {
    let f = field.into();
    let (d, m) = eval_node(&f, f.shape.root(), p, true);
    (d, m.dominant())
}

/// The materials at a point (textured CSG, §5.1): material `a`, or `a` and `b` mixed
/// with `b`'s weight `t` across a smooth union's blend band. Blends of blends keep
/// each operand's dominant material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blend {
    pub a: u32,
    pub b: u32,
    pub t: f64,
}

impl Blend {
    pub fn single(m: u32) -> Blend {
        Blend { a: m, b: m, t: 0.0 }
    }

    /// `a` up to half `b`'s weight (shaders/sdf.wgsl's `op_dominant`).
    pub fn dominant(self) -> u32 {
        if self.t <= 0.5 {
            self.a
        } else {
            self.b
        }
    }

    /// `op_union_blend`: b's weight is the polynomial smin's, clamp(0.5 − 0.5 (db − da)
    /// / k, 0, 1); a hard union takes the nearer operand's blend as it is.
    fn union(da: f64, ma: Blend, db: f64, mb: Blend, k: f64) -> Blend {
        if k <= 0.0 {
            return if da <= db { ma } else { mb };
        }
        let (a, b) = (ma.dominant(), mb.dominant());
        let t = (0.5 - 0.5 * (db - da) / k).clamp(0.0, 1.0);
        if a == b || t <= 0.0 {
            Blend::single(a)
        } else if t >= 1.0 {
            Blend::single(b)
        } else {
            Blend { a, b, t }
        }
    }
}

/// Distance and materials of a shape at `p` (the generated `scene_blend`).
pub fn eval_blend<'a>(field: impl Into<Field<'a>>, p: DVec3) -> (f64, Blend) {
    let f = field.into();
    eval_node(&f, f.shape.root(), p, true)
}

/// Just the distance.
pub fn distance<'a>(field: impl Into<Field<'a>>, p: DVec3) -> f64 {
    eval(field, p).0
}

/// The distance of node `id` (a subtree of the shape) at `p`.
pub fn node_distance<'a>(field: impl Into<Field<'a>>, id: NodeId, p: DVec3) -> f64 {
    eval_node(&field.into(), id, p, true).0
}

/// Distance and materials with every union operand evaluated, none skipped by its
/// box ([`super::guard`]): the baseline the guards are proven equal to.
pub fn eval_unguarded<'a>(field: impl Into<Field<'a>>, p: DVec3) -> (f64, Blend) {
    let f = field.into();
    eval_node(&f, f.shape.root(), p, false)
}

fn eval_node(f: &Field, id: NodeId, p: DVec3, g: bool) -> (f64, Blend) {
    stacker::maybe_grow(64 * 1024, 1024 * 1024, || eval_node_inner(f, id, p, g))
}

fn eval_node_inner(f: &Field, id: NodeId, p: DVec3, g: bool) -> (f64, Blend) {
    let shape = f.shape;
    if let Some(group) = shape.group(id) {
        // union(leaves…, others…) with a hard union's blends: the nearer, ties first.
        let (mut d, m) = group.eval(p);
        let mut blend = Blend::single(m);
        for &o in &group.others {
            let (dd, mm) = eval_node(f, o, p, g);
            if dd < d {
                (d, blend) = (dd, mm);
            }
        }
        return (d, blend);
    }
    match &shape[id].op {
        Op::Prim(pr) => (prim(p, pr), Blend::single(0)),
        Op::Csg { op, k, a, b } => {
            let far = (f64::INFINITY, Blend::single(0));
            let ((da, ma), (db, mb)) = match shape.guard(id).filter(|_| g) {
                // The first operand, then the other where its box comes near enough.
                Some(guard) => {
                    let first = eval_node(f, guard.first, p, g);
                    let other = if guard.needed(p, first.0) {
                        eval_node(f, guard.guarded, p, g)
                    } else {
                        far
                    };
                    if guard.first == *a {
                        (first, other)
                    } else {
                        (other, first)
                    }
                }
                None => (eval_node(f, *a, p, g), eval_node(f, *b, p, g)),
            };
            match op {
                Csg::Union => (smin(da, db, *k), Blend::union(da, ma, db, mb, *k)),
                Csg::Intersection => (-smin(-da, -db, *k), if da >= db { ma } else { mb }),
                Csg::Difference => (-smin(-da, db, *k), if da >= -db { ma } else { mb }),
            }
        }
        Op::Scale { factor, child } => {
            let (d, m) = eval_node(f, *child, p / *factor, g);
            (d * factor.min_element(), m)
        }
        Op::Twist { radius, .. } | Op::Bend { radius, .. } if p.length() > warp_outer(*radius) => {
            (p.length() - radius, Blend::single(0))
        }
        Op::Translate { child, .. }
        | Op::Rotate { child, .. }
        | Op::Twist { child, .. }
        | Op::Bend { child, .. }
        | Op::Repeat { child, .. }
        | Op::Mirror { child, .. }
        | Op::Elongate { child, .. } => {
            let op = &shape[id].op;
            eval_node(f, *child, op.child_point(p), g)
        }
        Op::Round { r, child } => {
            let (d, m) = eval_node(f, *child, p, g);
            (d - r, m)
        }
        Op::Shell { thickness, child } => {
            let (d, m) = eval_node(f, *child, p, g);
            (d.abs() - thickness * 0.5, m)
        }
        Op::Paint { material, child } => (eval_node(f, *child, p, g).0, Blend::single(*material)),
        Op::Displace { height, child } => {
            let (fd, m) = eval_node(f, *child, p, g);
            let d = height.field(fd, || project_onto(f, *child, p, fd, g), f.heights);
            (d, m)
        }
        Op::ShellMap { map, base, tile } => {
            let fb = eval_node(f, *base, p, g);
            map.field(
                fb,
                || project_onto(f, *base, p, fb.0, g),
                |s| eval_node(f, *tile, s, g),
                f.heights,
            )
        }
    }
}

/// Π_f (Eq. 57) onto node `child`'s surface from p, where its distance is `fp`, with
/// the gradient by central differences: the point and the unit normal.
fn project_onto(f: &Field, child: NodeId, p: DVec3, fp: f64, g: bool) -> (DVec3, DVec3) {
    let h = GRADIENT_STEP;
    let diff = |o: DVec3| eval_node(f, child, p + o, g).0 - eval_node(f, child, p - o, g).0;
    let grad = DVec3::new(diff(DVec3::X * h), diff(DVec3::Y * h), diff(DVec3::Z * h)) / (2.0 * h);
    let q = p - grad * (fp / grad.length_squared().max(1e-300));
    (q, grad.normalize_or_zero())
}

/// Step for central differences, relative to the scene's scale.
pub const GRADIENT_STEP: f64 = 1e-6;

/// The gradient by central differences in f64.
pub fn gradient<'a>(field: impl Into<Field<'a>>, p: DVec3) -> DVec3 {
    let f = field.into();
    let h = GRADIENT_STEP;
    let d = |o: DVec3| distance(f, p + o) - distance(f, p - o);
    DVec3::new(d(DVec3::X * h), d(DVec3::Y * h), d(DVec3::Z * h)) / (2.0 * h)
}

/// Projects a point onto the zero set with Newton steps along the gradient
/// (Π_f, Eq. 18 of the Implicit UVs paper), iterated until |f| < `tolerance`.
/// `None` when it does not converge (a flat gradient, or no surface nearby).
pub fn project<'a>(field: impl Into<Field<'a>>, p: DVec3, tolerance: f64) -> Option<DVec3> {
    let f = field.into();
    let mut x = p;
    for _ in 0..200 {
        let d = distance(f, x);
        if d.abs() < tolerance {
            return Some(x);
        }
        let g = gradient(f, x);
        let g2 = g.length_squared();
        // Written so that a NaN gradient also stops the projection.
        if g2.is_nan() || g2 <= 1e-12 || !d.is_finite() {
            return None;
        }
        x -= g * (d / g2);
    }
    None
}

/// One `sdfc eval` answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Query {
    pub point: DVec3,
    pub distance: f64,
    pub gradient: DVec3,
    pub surface: Option<DVec3>,
}

/// Evaluates many points in parallel.
pub fn query_all<'a>(field: impl Into<Field<'a>>, points: &[DVec3]) -> Vec<Query> {
    let f = field.into();
    points
        .par_iter()
        .map(|&p| Query {
            point: p,
            distance: distance(f, p),
            gradient: gradient(f, p),
            surface: project(f, p, 1e-10),
        })
        .collect()
}
