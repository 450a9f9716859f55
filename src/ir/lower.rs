//! Lowering: folded shape values of the checked program → IR nodes with bounds
//! and Lipschitz constants.

use super::dynamic::Dyn;
use super::texture::Textures;
use super::*;
use crate::sema::builtins::BuiltinId as B;
use crate::sema::{DefKind, Program, Ty, Value};
use crate::span::Span;

/// Lowers every named shape and the render target of a checked, error-free program.
/// Displacements whose heights read textures need [`lower_with`] (here those shapes
/// are left out).
pub fn lower(program: &Program) -> Scene {
    lower_with(program, &Textures::default()).0
}

/// What a lowering could not do: the span and why, for each displacement whose height
/// has no bound, and for each run-time value a step bound depends on that has none.
/// The shapes they are in are left out.
#[derive(Debug, Default)]
pub struct Unlowered {
    pub heights: Vec<(Span, String)>,
    pub steps: Vec<(Span, String)>,
}

/// The most run-time numbers one call may have (its bounds are taken over the
/// 2^n corners of their ranges).
pub const MAX_RUN_TIME_COMPONENTS: usize = 12;

/// [`lower`] with the decoded textures that displacement heights read (their texels
/// bound the heights' range and slope), and what could not be lowered.
pub fn lower_with(program: &Program, textures: &Textures) -> (Scene, Unlowered) {
    let mut errors = Unlowered::default();
    let shapes = program
        .defs
        .iter()
        .filter(|d| d.kind == DefKind::Let && d.ty == Ty::Shape)
        .filter_map(|d| {
            Some(NamedShape {
                name: d.name.clone(),
                shape: lower_shape_with(&d.value, textures, &mut errors)?,
            })
        })
        .collect();
    let render = program
        .render
        .as_ref()
        .and_then(|r| lower_shape_with(&r.target, textures, &mut errors));
    for e in [&mut errors.heights, &mut errors.steps] {
        e.sort_by_key(|e: &(Span, String)| (e.0.start, e.0.end));
        e.dedup();
    }
    (Scene { shapes, render }, errors)
}

/// Lowers one shape value; `None` for values that are not (error-free) shapes.
pub fn lower_shape(value: &Value) -> Option<Shape> {
    lower_shape_with(value, &Textures::default(), &mut Unlowered::default())
}

/// [`lower_shape`] with the decoded textures its displacements' heights read.
pub fn lower_shape_textured(value: &Value, textures: &Textures) -> Option<Shape> {
    lower_shape_with(value, textures, &mut Unlowered::default())
}

fn lower_shape_with(value: &Value, textures: &Textures, errors: &mut Unlowered) -> Option<Shape> {
    let mut shape = Shape::default();
    Lowerer {
        out: &mut shape,
        shared: std::collections::HashMap::new(),
        textures,
        errors: &mut errors.heights,
        unbounded: &mut errors.steps,
    }
    .node(value)?;
    Some(shape)
}

struct Lowerer<'a> {
    out: &'a mut Shape,
    /// The node of each shape value already lowered: a `let` used twice is one node with
    /// two parents (the IR is a DAG, its size linear in the checked program).
    shared: std::collections::HashMap<*const crate::sema::Node, NodeId>,
    textures: &'a Textures,
    errors: &'a mut Vec<(Span, String)>,
    unbounded: &'a mut Vec<(Span, String)>,
}

fn f(v: &Value) -> Option<f64> {
    v.as_float()
}

fn v3(v: &Value) -> Option<DVec3> {
    v.as_vec3().map(DVec3::from_array)
}

/// A float or vec3 argument as a vec3.
fn fv3(v: &Value) -> Option<DVec3> {
    f(v).map(DVec3::splat).or_else(|| v3(v))
}

/// A rotation taking `axis` (unit) to `to` (unit).
fn align(axis: DVec3, to: DVec3) -> DMat3 {
    let q = glam::DQuat::from_rotation_arc(axis, to);
    DMat3::from_quat(q)
}

impl Lowerer<'_> {
    fn push(&mut self, op: Op, bounds: Aabb, lipschitz: f64) -> Option<NodeId> {
        self.out.nodes.push(Node {
            op,
            bounds,
            lipschitz,
            dynamic: None,
        });
        Some(NodeId::new(self.out.nodes.len() - 1))
    }

    fn info(&self, id: NodeId) -> (Aabb, f64) {
        let n = &self.out[id];
        (n.bounds, n.lipschitz)
    }

    fn prim(&mut self, p: Prim) -> Option<NodeId> {
        let (bounds, lipschitz) = (p.bounds(), p.lipschitz());
        self.push(Op::Prim(p), bounds, lipschitz)
    }

    /// Lowers a shape value (recursive: on a fresh stack segment when this one runs low).
    fn node(&mut self, value: &Value) -> Option<NodeId> {
        let Value::Shape(n) = value else { return None };
        let key = std::sync::Arc::as_ptr(n);
        if let Some(&id) = self.shared.get(&key) {
            return Some(id);
        }
        let id = stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.node_inner(value))?;
        if n.args.iter().any(|a| a.uniform().is_some()) {
            self.run_time(n, id)?;
        }
        self.shared.insert(key, id);
        Some(id)
    }

    fn node_inner(&mut self, value: &Value) -> Option<NodeId> {
        let Value::Shape(n) = value else { return None };
        match n.builtin {
            B::Sphere
            | B::Box
            | B::RoundBox
            | B::BoxFrame
            | B::Torus
            | B::Capsule
            | B::Cylinder
            | B::Cone
            | B::CappedCone
            | B::Plane
            | B::Ellipsoid
            | B::Octahedron
            | B::HexPrism
            | B::TriPrism
            | B::Pyramid
            | B::Link => self.primitive(n.builtin, &n.args),
            B::Union
            | B::Intersection
            | B::Difference
            | B::SmoothUnion
            | B::SmoothIntersection
            | B::SmoothDifference => self.csg(n.builtin, &n.args),
            B::Translate | B::Rotate | B::RotateX | B::RotateY | B::RotateZ | B::Scale => {
                self.transform(n.builtin, &n.args)
            }
            B::Twist | B::Bend => self.warp(n.builtin, &n.args),
            B::Repeat | B::Mirror | B::Elongate => self.domain(n.builtin, &n.args),
            B::Round | B::Shell | B::Paint => self.surface(n.builtin, &n.args),
            B::Displace => self.displace(n),
            B::ShellMap => self.shell_map(n),
            // Not shapes: they never appear as a shape node.
            B::Image
            | B::Sample
            | B::SampleNormal
            | B::Checker
            | B::Grid
            | B::Orbit
            | B::LookAt
            | B::Sun
            | B::Sin
            | B::Cos
            | B::Tan
            | B::Asin
            | B::Acos
            | B::Atan
            | B::Atan2
            | B::Sqrt
            | B::Abs
            | B::Floor
            | B::Ceil
            | B::Fract
            | B::Sign
            | B::Exp
            | B::Log
            | B::Pow
            | B::Min
            | B::Max
            | B::Clamp
            | B::Mix
            | B::Smoothstep
            | B::Step
            | B::Length
            | B::Distance
            | B::Dot
            | B::Cross
            | B::Normalize
            | B::Radians
            | B::Degrees => None,
        }
    }

    /// A primitive (a cone is a capped cone moved up by half its height).
    /// ([`Self::node_inner`] sends no other builtin here: those are `None`.)
    fn primitive(&mut self, builtin: B, a: &[Value]) -> Option<NodeId> {
        match builtin {
            B::Sphere => self.prim(Prim::Sphere { r: f(&a[0])? }),
            B::Box => self.prim(Prim::Box {
                half: fv3(&a[0])? * 0.5,
            }),
            B::RoundBox => {
                let r = f(&a[1])?;
                let half = fv3(&a[0])? * 0.5;
                let r = r.min(half.min_element());
                self.prim(Prim::RoundBox {
                    half: half - DVec3::splat(r),
                    r,
                })
                .inspect(|&id| {
                    self.out[id].bounds = Aabb::centered(half);
                })
            }
            B::BoxFrame => self.prim(Prim::BoxFrame {
                half: fv3(&a[0])? * 0.5,
                e: f(&a[1])? * 0.5,
            }),
            B::Torus => self.prim(Prim::Torus {
                major: f(&a[0])?,
                minor: f(&a[1])?,
            }),
            B::Capsule => self.prim(Prim::Capsule {
                a: v3(&a[0])?,
                b: v3(&a[1])?,
                r: f(&a[2])?,
            }),
            B::Cylinder => self.prim(Prim::Cylinder {
                r: f(&a[0])?,
                half_h: f(&a[1])? * 0.5,
            }),
            B::Cone => {
                let (r, h) = (f(&a[0])?, f(&a[1])?);
                let cone = self.prim(Prim::CappedCone {
                    half_h: h * 0.5,
                    r1: r,
                    r2: 0.0,
                })?;
                self.translate(DVec3::new(0.0, h * 0.5, 0.0), cone)
            }
            B::CappedCone => self.prim(Prim::CappedCone {
                half_h: f(&a[0])? * 0.5,
                r1: f(&a[1])?,
                r2: f(&a[2])?,
            }),
            B::Plane => self.prim(Prim::Plane {
                n: v3(&a[0])?.normalize(),
                offset: f(&a[1])?,
            }),
            B::Ellipsoid => self.prim(Prim::Ellipsoid { radii: v3(&a[0])? }),
            B::Octahedron => self.prim(Prim::Octahedron { s: f(&a[0])? }),
            B::HexPrism => self.prim(Prim::HexPrism {
                r: f(&a[0])?,
                half_h: f(&a[1])? * 0.5,
            }),
            B::TriPrism => self.prim(Prim::TriPrism {
                r: f(&a[0])?,
                half_h: f(&a[1])? * 0.5,
            }),
            B::Pyramid => self.prim(Prim::Pyramid { h: f(&a[0])? }),
            B::Link => self.prim(Prim::Link {
                le: f(&a[0])?,
                r1: f(&a[1])?,
                r2: f(&a[2])?,
            }),
            _ => None,
        }
    }

    /// A union, intersection or difference, smooth or not.
    fn csg(&mut self, builtin: B, a: &[Value]) -> Option<NodeId> {
        let x = self.node(&a[0])?;
        let y = self.node(&a[1])?;
        let smooth = matches!(
            builtin,
            B::SmoothUnion | B::SmoothIntersection | B::SmoothDifference
        );
        let k = if smooth { f(&a[2])? } else { 0.0 };
        let op = match builtin {
            B::Union | B::SmoothUnion => Csg::Union,
            B::Intersection | B::SmoothIntersection => Csg::Intersection,
            _ => Csg::Difference,
        };
        let ((ba, la), (bb, lb)) = (self.info(x), self.info(y));
        let bounds = match op {
            Csg::Union => ba.union(bb).expand(k * 0.25),
            Csg::Intersection => ba.intersect(bb),
            Csg::Difference => ba,
        };
        self.push(Op::Csg { op, k, a: x, b: y }, bounds, la.max(lb))
    }

    /// A translation, rotation or scale.
    /// ([`Self::node_inner`] sends no other builtin here: those are `None`.)
    fn transform(&mut self, builtin: B, a: &[Value]) -> Option<NodeId> {
        match builtin {
            B::Translate => {
                let child = self.node(&a[0])?;
                self.translate(v3(&a[1])?, child)
            }
            B::Rotate | B::RotateX | B::RotateY | B::RotateZ => {
                let child = self.node(&a[0])?;
                let (axis, angle) = match builtin {
                    B::Rotate => (v3(&a[1])?.normalize(), f(&a[2])?),
                    B::RotateX => (DVec3::X, f(&a[1])?),
                    B::RotateY => (DVec3::Y, f(&a[1])?),
                    _ => (DVec3::Z, f(&a[1])?),
                };
                let forward = DMat3::from_axis_angle(axis, angle);
                let (b, l) = self.info(child);
                self.push(
                    Op::Rotate {
                        inverse: forward.transpose(),
                        child,
                    },
                    b.transform(forward),
                    l,
                )
            }
            B::Scale => {
                let child = self.node(&a[0])?;
                let factor = fv3(&a[1])?;
                let (b, l) = self.info(child);
                let stretch = factor.max_element() / factor.min_element();
                self.push(
                    Op::Scale { factor, child },
                    b.transform(DMat3::from_diagonal(factor)),
                    l * stretch,
                )
            }
            _ => None,
        }
    }

    /// A twist or a bend, bounded by the ball of its child.
    fn warp(&mut self, builtin: B, a: &[Value]) -> Option<NodeId> {
        let child = self.node(&a[0])?;
        let axis = v3(&a[1])?.normalize();
        let rate = f(&a[2])?;
        let (b, l) = self.info(child);
        // A point at distance R from the axis moves sideways by up to |rate|·R per unit
        // along it; the field's gradient grows to at most √(1 + (rate·R)²).
        // Twists and bends rotate points about the origin, so a warped shape lies
        // in the same ball as its child: through a chain of warps the ball's
        // radius stays the innermost one (the box bound's corner would grow it by
        // √3 per warp).
        let bounded = match self.out[child].op {
            Op::Twist { radius, .. } | Op::Bend { radius, .. } if radius.is_finite() => {
                radius.min(b.radius_from_origin())
            }
            _ => b.radius_from_origin(),
        };
        let r = if bounded.is_finite() {
            warp_outer(bounded)
        } else {
            10.0
        };
        let radius = bounded;
        let stretch = (1.0 + (rate * r).powi(2)).sqrt();
        let bounds = Aabb::centered(DVec3::splat(r));
        if builtin == B::Twist {
            self.push(
                Op::Twist {
                    frame: align(axis, DVec3::Y),
                    rate,
                    radius,
                    child,
                },
                bounds,
                l * stretch,
            )
        } else {
            self.push(
                Op::Bend {
                    frame: align(axis, DVec3::X),
                    rate,
                    radius,
                    child,
                },
                bounds,
                l * stretch,
            )
        }
    }

    /// A repetition, mirror or elongation of its child's domain.
    /// ([`Self::node_inner`] sends no other builtin here: those are `None`.)
    fn domain(&mut self, builtin: B, a: &[Value]) -> Option<NodeId> {
        match builtin {
            B::Repeat => {
                let child = self.node(&a[0])?;
                let (_, l) = self.info(child);
                self.push(
                    Op::Repeat {
                        period: fv3(&a[1])?,
                        child,
                    },
                    Aabb::INFINITE,
                    l,
                )
            }
            B::Mirror => {
                let child = self.node(&a[0])?;
                let normal = v3(&a[1])?.normalize();
                let (b, l) = self.info(child);
                let reflect = DMat3::IDENTITY
                    - 2.0
                        * DMat3::from_cols(normal * normal.x, normal * normal.y, normal * normal.z);
                self.push(
                    Op::Mirror { normal, child },
                    b.union(b.transform(reflect)),
                    l,
                )
            }
            B::Elongate => {
                let child = self.node(&a[0])?;
                let h = v3(&a[1])?;
                let (b, l) = self.info(child);
                self.push(
                    Op::Elongate { h, child },
                    Aabb {
                        min: b.min - h,
                        max: b.max + h,
                    },
                    l,
                )
            }
            _ => None,
        }
    }

    /// A rounded, shelled or painted child.
    /// ([`Self::node_inner`] sends no other builtin here: those are `None`.)
    fn surface(&mut self, builtin: B, a: &[Value]) -> Option<NodeId> {
        match builtin {
            B::Round => {
                let child = self.node(&a[0])?;
                let r = f(&a[1])?;
                let (b, l) = self.info(child);
                self.push(Op::Round { r, child }, b.expand(r), l)
            }
            B::Shell => {
                let child = self.node(&a[0])?;
                let t = f(&a[1])?;
                let (b, l) = self.info(child);
                self.push(
                    Op::Shell {
                        thickness: t,
                        child,
                    },
                    b.expand(t * 0.5),
                    l,
                )
            }
            B::Paint => {
                let child = self.node(&a[0])?;
                let Value::Material(m) = a[1] else {
                    return None;
                };
                let (b, l) = self.info(child);
                self.push(
                    Op::Paint {
                        material: m.index() as u32 + 1,
                        child,
                    },
                    b,
                    l,
                )
            }
            _ => None,
        }
    }

    /// A displacement of its child by a height field (Eq. 58); `None`, with the call's
    /// error recorded, when the height has no bound.
    fn displace(&mut self, n: &crate::sema::Node) -> Option<NodeId> {
        let a = &n.args;
        let child = self.node(&a[0])?;
        let (scale, band) = (f(&a[2])?, f(&a[3])?);
        let bound = match displace::analyze(&a[1], self.textures) {
            Ok(b) => b,
            Err(why) => {
                self.errors.push((n.span, why));
                return None;
            }
        };
        let (b, l) = self.info(child);
        let size = if b.is_finite() {
            (b.max - b.min).max_element().max(1e-3)
        } else {
            4.0
        };
        let height = Height::new(a[1].clone(), scale, band, bound, n.span.end, 1e-3 * size);
        let bounds = b.expand(height.epsilon());
        let lipschitz = height.lipschitz(l);
        self.push(
            Op::Displace {
                height: std::sync::Arc::new(height),
                child,
            },
            bounds,
            lipschitz,
        )
    }

    /// A tile copied into the shell of its base (§5.4); `None`, with the call's error
    /// recorded, when the uv field has no slope bound.
    fn shell_map(&mut self, n: &crate::sema::Node) -> Option<NodeId> {
        let a = &n.args;
        let base = self.node(&a[0])?;
        let tile = self.node(&a[1])?;
        let thickness = f(&a[3])?;
        let keep = !matches!(a[4], Value::Bool(false));
        let slope = match displace::analyze_uv(&a[2], self.textures) {
            Ok(s) => s,
            Err(why) => {
                self.errors.push((n.span, why));
                return None;
            }
        };
        let (b, l) = self.info(base);
        let (tb, lt) = self.info(tile);
        let size = if b.is_finite() {
            (b.max - b.min).max_element().max(1e-3)
        } else {
            4.0
        };
        let uv = Height::uv_field(a[2].clone(), slope, n.span.end, 1e-3 * size);
        let map = super::shell::ShellMap::new(uv, thickness, keep, (tb.min.y, tb.max.y));
        let lipschitz = map.lipschitz(l, lt);
        self.push(
            Op::ShellMap {
                map: std::sync::Arc::new(map),
                base,
                tile,
            },
            b.expand(thickness),
            lipschitz,
        )
    }

    /// Node `id`, lowered from `n` at its run-time arguments' current values: its
    /// run-time numbers, and its bounds and Lipschitz constant over every value they may
    /// take. Those come from the node lowered again at each corner of the arguments'
    /// box of intervals (exact for the bounds and constants of primitives, blends,
    /// translations, scales, warps, elongations, roundings and shells, which are
    /// monotone in each number), but for rotations, bounded by the ball that holds
    /// their child at every angle.
    fn run_time(&mut self, n: &crate::sema::Node, id: NodeId) -> Option<()> {
        let slots = match &self.out[id].op {
            Op::Prim(p) => p.kind().slots.len(),
            _ => 0,
        };
        let d = super::dynamic::of(n.builtin, &n.args, slots)?;
        let comps: Vec<(usize, usize, (f64, f64))> = n
            .args
            .iter()
            .enumerate()
            .filter_map(|(i, a)| Some((i, a.uniform()?)))
            .flat_map(|(i, u)| u.range.iter().enumerate().map(move |(c, r)| (i, c, *r)))
            .collect();
        if comps.len() > MAX_RUN_TIME_COMPONENTS {
            self.unbounded.push((
                n.span,
                format!(
                    "`{}` has {} run-time numbers; one call may have at most {MAX_RUN_TIME_COMPONENTS}",
                    n.builtin.name(),
                    comps.len()
                ),
            ));
            return None;
        }
        let (mut bounds, mut lipschitz) = self.info(id);
        let len = self.out.nodes.len();
        for mask in 0u32..1 << comps.len() {
            let mut args: Vec<Value> = n
                .args
                .iter()
                .map(|a| match a {
                    Value::Uniform(u) if u.value.len() == 1 => Value::Float(u.value[0]),
                    Value::Uniform(u) => Value::Vec(u.value.clone()),
                    v => v.clone(),
                })
                .collect();
            for (j, &(i, c, r)) in comps.iter().enumerate() {
                let x = if mask >> j & 1 == 0 { r.0 } else { r.1 };
                match &mut args[i] {
                    Value::Float(v) => *v = x,
                    Value::Vec(v) => v[c] = x,
                    _ => {}
                }
            }
            let corner = Value::Shape(std::sync::Arc::new(crate::sema::Node {
                builtin: n.builtin,
                args,
                span: n.span,
            }));
            match self.node_inner(&corner) {
                Some(c) => {
                    let (b, l) = self.info(c);
                    let nan = b.min.is_nan() || b.max.is_nan();
                    bounds = if nan { Aabb::INFINITE } else { bounds.union(b) };
                    lipschitz = if l.is_nan() {
                        f64::INFINITY
                    } else {
                        lipschitz.max(l)
                    };
                }
                None => lipschitz = f64::INFINITY,
            }
            self.out.nodes.truncate(len);
        }
        if let Op::Rotate { child, .. } = self.out[id].op {
            bounds = Aabb::centered(DVec3::splat(self.out[child].bounds.radius_from_origin()));
        }
        if !lipschitz.is_finite() {
            let culprit = n
                .args
                .iter()
                .filter_map(Value::uniform)
                .find(|u| !u.is_bounded())
                .map_or(n.span, |u| u.span);
            self.unbounded.push((
                culprit,
                format!(
                    "the step bound of `{}` depends on this value, which has no bound over its parameters' ranges",
                    n.builtin.name()
                ),
            ));
            return None;
        }
        let node = &mut self.out[id];
        node.bounds = bounds;
        node.lipschitz = lipschitz;
        // A displacement's range of d scales with its scale: the generated code
        // computes it from the parameters' block (the band follows the value).
        if let (Op::Displace { height: h, .. }, Dyn::One(s)) = (&mut node.op, &d) {
            std::sync::Arc::make_mut(h).run_time_scale = Some(s.value.clone());
        }
        node.dynamic = Some(std::sync::Arc::new(d));
        Some(())
    }

    fn translate(&mut self, offset: DVec3, child: NodeId) -> Option<NodeId> {
        let (b, l) = self.info(child);
        self.push(
            Op::Translate { offset, child },
            Aabb {
                min: b.min + offset,
                max: b.max + offset,
            },
            l,
        )
    }
}
