//! The IR: a scene's signed distance fields as a flat, typed tree.
//!
//! Lowering turns the checked program's folded shape values into [`Op`] nodes
//! with every constant resolved to the form the evaluators need (half sizes,
//! inverse rotations, normalized axes). Each node carries an axis-aligned bound
//! and a **Lipschitz bound**: warps and non-uniform scales stretch distances, and
//! the sphere tracer divides its steps by the root's bound so it never
//! oversteps the surface. The WGSL generator and the CPU reference
//! ([`eval`]) both walk this IR.

pub mod displace;
pub mod dual;
pub mod dynamic;
pub mod eval;
pub mod group;
pub mod guard;
mod lower;
pub mod prim;
pub mod rest;
pub mod shell;
pub mod texture;

pub use displace::{Height, Heights, NoHeights};
pub use eval::Field;
pub use lower::{lower, lower_shape, lower_shape_textured, lower_with, Unlowered};
pub use prim::Prim;

use glam::{DMat3, DVec3};

crate::id::define_id!(
    /// Index of a node in [`Shape::nodes`].
    NodeId
);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Csg {
    Union,
    Intersection,
    Difference,
}

/// A node of the SDF tree.
#[derive(Debug, Clone, PartialEq)]
pub enum Op {
    Prim(Prim),
    /// Hard (`k == 0`) or smooth CSG. The material of the nearer operand is kept.
    Csg {
        op: Csg,
        k: f64,
        a: NodeId,
        b: NodeId,
    },
    /// Child evaluated at `p - offset`.
    Translate {
        offset: DVec3,
        child: NodeId,
    },
    /// Child evaluated at `inverse * p`.
    Rotate {
        inverse: DMat3,
        child: NodeId,
    },
    /// Child evaluated at `p / factor`, distance times `min(factor)`.
    Scale {
        factor: DVec3,
        child: NodeId,
    },
    /// Twist about `axis` (through the origin) by `rate` radians per unit length.
    /// `frame` maps world to a frame whose y is the axis. Warps are rotations about the
    /// origin, so the result lies within `radius` (the child's bound) of the origin.
    /// Beyond [`warp_outer`]`(radius)` the distance is the lower bound `|p| - radius`,
    /// which keeps the Lipschitz bound valid everywhere without stopping rays on the
    /// bounding sphere itself.
    Twist {
        frame: DMat3,
        rate: f64,
        radius: f64,
        child: NodeId,
    },
    /// Bend: p turns about the frame's z by `rate * (p · axis)`; `frame` maps axis to x.
    Bend {
        frame: DMat3,
        rate: f64,
        radius: f64,
        child: NodeId,
    },
    Repeat {
        period: DVec3,
        child: NodeId,
    },
    /// Points on the negative side of the plane through the origin are reflected.
    Mirror {
        normal: DVec3,
        child: NodeId,
    },
    Elongate {
        h: DVec3,
        child: NodeId,
    },
    /// Distance minus `r`.
    Round {
        r: f64,
        child: NodeId,
    },
    /// `|d| - thickness / 2`.
    Shell {
        thickness: f64,
        child: NodeId,
    },
    /// Gives the subtree a material (1-based; 0 is the default material).
    Paint {
        material: u32,
        child: NodeId,
    },
    /// The child displaced along its normal by a height field (Eq. 56-58; see
    /// [`displace`]).
    Displace {
        height: std::sync::Arc<Height>,
        child: NodeId,
    },
    /// The tile copied into the base's shell (§5.4; see [`shell`]).
    ShellMap {
        map: std::sync::Arc<shell::ShellMap>,
        base: NodeId,
        tile: NodeId,
    },
}

impl Op {
    /// The nodes this one evaluates (compile-time passes; the evaluators match on
    /// the ops themselves).
    pub fn children(&self) -> Vec<NodeId> {
        self.clone()
            .children_mut()
            .into_iter()
            .map(|c| *c)
            .collect()
    }

    /// The child slots of this node, to rewrite them.
    pub fn children_mut(&mut self) -> Vec<&mut NodeId> {
        match self {
            Op::Prim(_) => Vec::new(),
            Op::Csg { a, b, .. } => vec![a, b],
            Op::ShellMap { base, tile, .. } => vec![base, tile],
            Op::Translate { child, .. }
            | Op::Rotate { child, .. }
            | Op::Scale { child, .. }
            | Op::Twist { child, .. }
            | Op::Bend { child, .. }
            | Op::Repeat { child, .. }
            | Op::Mirror { child, .. }
            | Op::Elongate { child, .. }
            | Op::Round { child, .. }
            | Op::Shell { child, .. }
            | Op::Paint { child, .. }
            | Op::Displace { child, .. } => vec![child],
        }
    }

    /// Whether an op evaluates its child at a moved point.
    pub fn is_point_map(&self) -> bool {
        matches!(
            self,
            Op::Translate { .. }
                | Op::Rotate { .. }
                | Op::Scale { .. }
                | Op::Twist { .. }
                | Op::Bend { .. }
                | Op::Repeat { .. }
                | Op::Mirror { .. }
                | Op::Elongate { .. }
        )
    }

    /// The point at which this op evaluates its child, for the ops of
    /// [`Op::is_point_map`] (p itself for the others). Twists and bends outside their
    /// bound use the bounding sphere instead of the child ([`eval`]); that region holds
    /// no surface. The rest-pose queries ([`rest`]) compose these maps.
    pub fn child_point(&self, p: DVec3) -> DVec3 {
        match self {
            Op::Translate { offset, .. } => p - *offset,
            Op::Rotate { inverse, .. } => *inverse * p,
            Op::Scale { factor, .. } => p / *factor,
            Op::Twist { frame, rate, .. } => {
                let q = *frame * p;
                let (s, c) = (rate * q.y).sin_cos();
                frame.transpose() * DVec3::new(c * q.x - s * q.z, q.y, s * q.x + c * q.z)
            }
            Op::Bend { frame, rate, .. } => {
                let q = *frame * p;
                let (s, c) = (rate * q.x).sin_cos();
                frame.transpose() * DVec3::new(c * q.x - s * q.y, s * q.x + c * q.y, q.z)
            }
            Op::Repeat { period, .. } => p - *period * (p / *period).round(),
            Op::Mirror { normal, .. } => p - 2.0 * p.dot(*normal).min(0.0) * *normal,
            Op::Elongate { h, .. } => p - p.clamp(-*h, *h),
            _ => p,
        }
    }
}

impl Shape {
    /// Every displacement's height, once each (by call site).
    pub fn heights(&self) -> Vec<std::sync::Arc<Height>> {
        let mut out: Vec<std::sync::Arc<Height>> = Vec::new();
        for n in &self.nodes {
            let h = match &n.op {
                Op::Displace { height, .. } => height.clone(),
                Op::ShellMap { map, .. } => std::sync::Arc::new(map.uv.clone()),
                _ => continue,
            };
            if !out.iter().any(|x| x.id == h.id) {
                out.push(h);
            }
        }
        out
    }

    /// The largest step of a displacement read from 8-bit texels: its range / 255
    /// (textures are sampled as 8-bit data); 0 without such a displacement.
    pub fn height_quantum(&self) -> f64 {
        self.heights()
            .iter()
            .filter(|h| displace::samples_texture(&h.value))
            .map(|h| (h.hi - h.lo) / 255.0)
            .fold(0.0, f64::max)
    }

    /// Whether some smooth union has a painted operand: its materials then blend across
    /// the band (textured CSG, [`eval::Blend`]), and the generator emits `scene_blend`.
    pub fn blends_materials(&self) -> bool {
        // Children come before parents: one pass (the nodes form a DAG).
        let mut painted = vec![false; self.nodes.len()];
        for (i, n) in self.nodes.iter().enumerate() {
            painted[i] = matches!(n.op, Op::Paint { .. })
                || n.op.children().iter().any(|c| painted[c.index()]);
        }
        self.nodes.iter().any(|n| match n.op {
            Op::Csg {
                op: Csg::Union,
                k,
                a,
                b,
            } => k > 0.0 && (painted[a.index()] || painted[b.index()]),
            _ => false,
        })
    }

    /// The group (a large hard union as data) rooted at node `id`, if any.
    pub fn group(&self, id: NodeId) -> Option<&std::sync::Arc<group::Group>> {
        self.groups
            .get_or_init(|| group::groups(self))
            .get(id.index())?
            .as_ref()
    }

    /// The guard of union node `id` (its operand skipped by its box), if any.
    pub fn guard(&self, id: NodeId) -> Option<&guard::Guard> {
        self.guards
            .get_or_init(|| guard::guards(self))
            .get(id.index())?
            .as_ref()
    }

    /// Whether a node has more than one parent (a `let` used twice).
    pub fn is_shared(&self, id: NodeId) -> bool {
        self.shared
            .get_or_init(|| {
                let mut parents = vec![0u32; self.nodes.len()];
                for n in &self.nodes {
                    for c in n.op.children() {
                        parents[c.index()] += 1;
                    }
                }
                parents.into_iter().map(|p| p > 1).collect()
            })
            .get(id.index())
            .copied()
            .unwrap_or(false)
    }
}

/// Where a twist or bend switches to the bounding-sphere distance: a margin
/// beyond its bound, so that a ray stepping onto the bound lands inside the warp.
pub fn warp_outer(radius: f64) -> f64 {
    radius * 1.05 + 1e-3
}

/// An axis-aligned bound; infinite for unbounded shapes (planes, repetition).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const INFINITE: Aabb = Aabb {
        min: DVec3::splat(f64::NEG_INFINITY),
        max: DVec3::splat(f64::INFINITY),
    };

    pub fn centered(half: DVec3) -> Aabb {
        Aabb {
            min: -half,
            max: half,
        }
    }

    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn intersect(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    pub fn expand(self, r: f64) -> Aabb {
        Aabb {
            min: self.min - DVec3::splat(r),
            max: self.max + DVec3::splat(r),
        }
    }

    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// The largest distance from the origin to the box.
    pub fn radius_from_origin(&self) -> f64 {
        self.min.abs().max(self.max.abs()).length()
    }

    /// The bound of the box after a linear map.
    pub fn transform(self, m: DMat3) -> Aabb {
        if !self.is_finite() {
            return Aabb::INFINITE;
        }
        let mut out = Aabb {
            min: DVec3::splat(f64::INFINITY),
            max: DVec3::splat(f64::NEG_INFINITY),
        };
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            let q = m * c;
            out.min = out.min.min(q);
            out.max = out.max.max(q);
        }
        out
    }
}

/// How often a displacement or a shell map evaluates its base at a point near the
/// surface: once for the distance and six times for Π_f's gradient (Eq. 57).
pub const PROJECTION_EVALS: f64 = 7.0;

/// The largest derived constant a shape may have (bounds, Lipschitz bound, warp
/// radii): well inside single precision, so sums and products in the shader stay finite.
pub const MAX_DERIVED: f64 = 1e30;

/// A node with its bound and Lipschitz constant.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    pub op: Op,
    pub bounds: Aabb,
    /// An upper bound of |∇f|: sphere-tracing steps are divided by it.
    pub lipschitz: f64,
    /// The node's numbers that the host sets at run time, if any: the op holds their
    /// current values, `bounds` and `lipschitz` hold over their whole ranges.
    pub dynamic: Option<std::sync::Arc<dynamic::Dyn>>,
}

/// A lowered shape: nodes in child-before-parent order, the last one the root. A node
/// may have several parents (a `let` used twice): the nodes form a DAG.
#[derive(Debug, Clone, Default)]
pub struct Shape {
    pub nodes: Vec<Node>,
    /// Which nodes have several parents, computed on first use.
    shared: std::sync::OnceLock<Vec<bool>>,
    /// The large unions evaluated as data ([`group`]), by node, built on first use.
    groups: std::sync::OnceLock<Vec<Option<std::sync::Arc<group::Group>>>>,
    /// The unions' guards by their operands' boxes ([`guard`]), built on first use.
    guards: std::sync::OnceLock<Vec<Option<guard::Guard>>>,
}

impl PartialEq for Shape {
    fn eq(&self, other: &Shape) -> bool {
        self.nodes == other.nodes
    }
}

impl std::ops::Index<NodeId> for Shape {
    type Output = Node;

    fn index(&self, id: NodeId) -> &Node {
        &self.nodes[id.index()]
    }
}

impl std::ops::IndexMut<NodeId> for Shape {
    fn index_mut(&mut self, id: NodeId) -> &mut Node {
        &mut self.nodes[id.index()]
    }
}

impl Shape {
    pub fn root(&self) -> NodeId {
        NodeId::new(self.nodes.len() - 1)
    }

    pub fn root_node(&self) -> &Node {
        &self[self.root()]
    }

    pub fn lipschitz(&self) -> f64 {
        self.root_node().lipschitz
    }

    /// About how many primitive evaluations one evaluation of the shape's field costs
    /// near its surface, each use of a shared node counted: a displacement or a shell
    /// map evaluates its base [`PROJECTION_EVALS`] times (Π_f of Eq. 57), and a height
    /// or uv that reads atlas `k` walks it, at `walk(k)` evaluations.
    pub fn eval_cost(&self, walk: impl Fn(crate::sema::AtlasId) -> f64) -> f64 {
        let mut cost: Vec<f64> = Vec::with_capacity(self.nodes.len());
        for n in &self.nodes {
            let c = |id: NodeId| cost[id.index()];
            let read = |h: &Height| h.atlas.map_or(1.0, &walk);
            let total = match &n.op {
                Op::Displace { height, child } => PROJECTION_EVALS * c(*child) + read(height),
                Op::ShellMap { map, base, tile } => {
                    PROJECTION_EVALS * c(*base) + c(*tile) + read(&map.uv)
                }
                op => 1.0 + op.children().iter().map(|&k| c(k)).sum::<f64>(),
            };
            cost.push(total);
        }
        cost.last().copied().unwrap_or(0.0)
    }

    /// Why the shape's derived constants (bounds, Lipschitz bound, warp radii) do not fit
    /// the shaders' single precision, or None. Every constant the code generator writes
    /// must be finite in f32; these are derived, so the checker cannot see them.
    pub fn overflow(&self) -> Option<String> {
        let big = |x: f64| x.is_finite() && x.abs() > MAX_DERIVED;
        for n in &self.nodes {
            if !n.lipschitz.is_finite() || n.lipschitz > MAX_DERIVED {
                return Some(format!(
                    "its warps stretch distances by more than {MAX_DERIVED:e} (the Lipschitz bound is {:e})",
                    n.lipschitz
                ));
            }
            let b = n.bounds;
            if b.min
                .to_array()
                .into_iter()
                .chain(b.max.to_array())
                .any(big)
            {
                return Some(format!(
                    "its bounds reach beyond {MAX_DERIVED:e} from the origin"
                ));
            }
            if let Op::Twist { radius, .. } | Op::Bend { radius, .. } = n.op {
                if big(radius) {
                    return Some(format!(
                        "a warp's radius of {radius:e} is beyond {MAX_DERIVED:e}"
                    ));
                }
            }
            // The band tests and offsets the displacement and shell-map code writes
            // (an unbounded base has infinite bounds, so the box test above misses them).
            let over = |x: f64| !x.is_finite() || x.abs() > MAX_DERIVED;
            match &n.op {
                Op::Displace { height, .. }
                    if [height.lo, height.hi, height.band_width(), height.slope]
                        .into_iter()
                        .any(over) =>
                {
                    return Some(format!(
                        "its displacement reaches {:e} (scale times the height's range, and the band around it), beyond {MAX_DERIVED:e}",
                        height.band_width()
                    ));
                }
                Op::ShellMap { map, .. } => {
                    let band = shell::BAND * map.thickness;
                    let consts = [
                        map.thickness * map.lo - band,
                        map.thickness * map.hi + band,
                        map.scale,
                        map.uv.slope,
                    ];
                    if consts.into_iter().any(over) {
                        return Some(format!(
                            "its shell map's constants (thickness {:e}, uv slope {:e}) reach beyond {MAX_DERIVED:e}",
                            map.thickness, map.uv.slope
                        ));
                    }
                }
                _ => {}
            }
        }
        None
    }

    /// A finite bound for framing a camera: the shape's bound, or a 4-unit cube when unbounded.
    pub fn framing_bounds(&self) -> Aabb {
        let b = self.root_node().bounds;
        let fallback = Aabb::centered(DVec3::splat(2.0));
        if b.is_finite() {
            b
        } else {
            Aabb {
                min: b.min.max(fallback.min),
                max: b.max.min(fallback.max),
            }
        }
    }
}

/// A named shape of the program, lowered.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedShape {
    pub name: String,
    pub shape: Shape,
}

/// The lowered scene: every named shape and the render target.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Scene {
    pub shapes: Vec<NamedShape>,
    pub render: Option<Shape>,
}

impl Scene {
    pub fn shape(&self, name: &str) -> Option<&Shape> {
        self.shapes
            .iter()
            .find(|s| s.name == name)
            .map(|s| &s.shape)
    }
}
