//! The CPU reference: the IR evaluated in f64.
//!
//! It is the oracle for the GPU path and the compiler's tool for geometry at
//! compile time (seed projection). Every function here mirrors one in
//! `shaders/sdf.wgsl`.

use super::*;
use glam::DVec3;
use rayon::prelude::*;

pub use super::prim::box_dist;

/// A primitive's distance at a local point ([`Prim::distance`]).
pub fn prim(p: DVec3, prim: &Prim) -> f64 {
    prim.distance(p)
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
