//! The exported mesh cut at the faces of `--bounds`.
//!
//! The mesher keeps the quads that reach into the box ([`QuadMesh::retain_reaching`]);
//! here every triangle of the exported mesh is clipped against the box's six planes
//! (Sutherland and Hodgman), and a vertex made where an edge crosses a plane takes the
//! edge's attributes interpolated linearly, as a rasterizer interpolates them. The
//! texture map on what is kept is the triangle's own, so the texels, placed through the
//! same linear map, need no change: the cut mesh shows exactly what the whole one showed
//! inside the box, and ends on its faces.
//!
//! A vertex outside a face by a thousandth of a cell or less ([`CUT_SLACK_CELLS`]) lies on
//! it, so that a surface lying along a face is kept whole, and is moved onto the face.
//!
//! A crossing is computed from the edge's ends taken in the order of their positions,
//! so both triangles of an edge, and both charts of a border (whose vertices are split
//! for their texture coordinates), make the same point bit for bit: the cut mesh stays
//! watertight. Within a chart, the two triangles of an edge share the vertex made on it.
//!
//! [`QuadMesh::retain_reaching`]: crate::reference::mesh::QuadMesh::retain_reaching

use crate::asset::MeshData;
use crate::ir::Aabb;
use glam::DVec3;
use std::cmp::Ordering;
use std::collections::HashMap;

/// How near outside a face of the box a vertex lies on it, in mesh cells ([`to_box`]'s
/// `slack`):
/// a flat face or a plane along a face of `--bounds` has its vertices a rounding error
/// off it (1e-13 on a plane at 0), and is kept whole, not at random.
pub const CUT_SLACK_CELLS: f64 = 1e-3;

/// One of the box's six planes: the coordinate `axis` at `at`, the inside below it
/// (`upper`) or above it; a point within `slack` of it lies on it.
#[derive(Debug, Clone, Copy)]
struct Plane {
    axis: usize,
    at: f64,
    upper: bool,
    slack: f64,
}

impl Plane {
    fn of(b: Aabb, slack: f64) -> [Plane; 6] {
        let p = |axis: usize, upper: bool| Plane {
            axis,
            at: if upper { b.max[axis] } else { b.min[axis] },
            upper,
            slack,
        };
        [
            p(0, false),
            p(0, true),
            p(1, false),
            p(1, true),
            p(2, false),
            p(2, true),
        ]
    }

    /// How far `p` lies inside (negative outside).
    fn distance(&self, p: DVec3) -> f64 {
        if self.upper {
            self.at - p[self.axis]
        } else {
            p[self.axis] - self.at
        }
    }

    /// How far `p` lies inside, 0 where it lies outside by the slack or less: a surface
    /// that lies on a face of the box (a flat face or a plane, whose mesh vertices sit a
    /// rounding error off it) is kept whole, and moved onto the face ([`clamp`]). A
    /// point just inside stays as it is, so that the sliver between it and the face is
    /// cut as any other (counted on the face, it was dropped: a hole).
    fn inside(&self, p: DVec3) -> f64 {
        let d = self.distance(p);
        if d < 0.0 && d >= -self.slack {
            0.0
        } else {
            d
        }
    }
}

/// `p` moved into the box: a kept point lies at most the slack outside it.
fn clamp(p: DVec3, b: &Aabb) -> DVec3 {
    p.clamp(b.min, b.max)
}

/// Orders two points by their coordinates, x first.
fn by_position(a: DVec3, b: DVec3) -> Ordering {
    a.to_array()
        .partial_cmp(&b.to_array())
        .unwrap_or(Ordering::Equal)
}

/// Clips the convex polygon `poly` against `plane` into `out`. Where an edge crosses
/// it, `cut(first, second, t)` makes the vertex at `t` from `first` to `second`, the
/// edge's ends in [`by_position`] order; a vertex on the plane counts as inside, and
/// no crossing is made at a vertex that lies on it.
fn clip_polygon<V: Copy>(
    poly: &[V],
    out: &mut Vec<V>,
    plane: &Plane,
    pos: &impl Fn(&V) -> DVec3,
    cut: &mut impl FnMut(&V, &V, f64) -> V,
) {
    out.clear();
    let Some(&last) = poly.last() else {
        return;
    };
    let mut s = last;
    let mut ds = plane.inside(pos(&s));
    for &e in poly {
        let de = plane.inside(pos(&e));
        if (ds > 0.0 && de < 0.0) || (ds < 0.0 && de > 0.0) {
            let (a, da, b, db) = if by_position(pos(&s), pos(&e)) == Ordering::Greater {
                (e, de, s, ds)
            } else {
                (s, ds, e, de)
            };
            out.push(cut(&a, &b, da / (da - db)));
        }
        if de >= 0.0 {
            out.push(e);
        }
        (s, ds) = (e, de);
    }
}

/// The point at `t` from `a` to `b`, on `plane` exactly.
fn crossing(a: DVec3, b: DVec3, t: f64, plane: &Plane) -> DVec3 {
    let mut p = a + (b - a) * t;
    p[plane.axis] = plane.at;
    p
}

/// Whether the triangle has a part of non-zero area inside the box (its corners as the
/// exported mesh holds them, in f32).
fn triangle_reaches(tri: [DVec3; 3], planes: &[Plane; 6], b: &Aabb) -> bool {
    if planes
        .iter()
        .any(|pl| tri.iter().all(|&p| pl.inside(p) < 0.0))
    {
        return false;
    }
    let (mut poly, mut next) = (tri.to_vec(), Vec::with_capacity(9));
    for plane in planes {
        clip_polygon(&poly, &mut next, plane, &|p: &DVec3| *p, &mut |a, b, t| {
            crossing(*a, *b, t, plane)
        });
        std::mem::swap(&mut poly, &mut next);
    }
    let poly: Vec<DVec3> = poly.iter().map(|&p| clamp(p, b)).collect();
    (2..poly.len()).any(|i| area2(poly[0], poly[i - 1], poly[i]) > 0.0)
}

/// Twice the area of a triangle whose corners are rounded to f32, as the file holds them.
fn area2(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let r = |p: DVec3| p.as_vec3().as_dvec3();
    (r(b) - r(a)).cross(r(c) - r(a)).length()
}

/// Whether any of `triangles` has a part of non-zero area inside `bounds` (a point
/// outside a face by `slack` or less lying on it): whether [`to_box`] keeps anything of
/// a mesh of them.
pub fn reaches(triangles: impl IntoIterator<Item = [DVec3; 3]>, bounds: Aabb, slack: f64) -> bool {
    let planes = Plane::of(bounds, slack);
    triangles
        .into_iter()
        .any(|t| triangle_reaches(t, &planes, &bounds))
}

/// A vertex's attributes in f64.
#[derive(Debug, Clone, Copy)]
struct Attributes {
    position: DVec3,
    normal: DVec3,
    tangent: [f64; 4],
    uv: [f64; 2],
}

impl Attributes {
    fn of(mesh: &MeshData, k: usize) -> Attributes {
        let t = mesh.tangents[k].map(f64::from);
        Attributes {
            position: DVec3::from_array(mesh.positions[k].map(f64::from)),
            normal: DVec3::from_array(mesh.normals[k].map(f64::from)),
            tangent: t,
            uv: mesh.texcoords[k].map(f64::from),
        }
    }

    /// The attributes at `t` from `a` to `b`, the position on `plane`: linear, as a
    /// rasterizer interpolates them; the normal made unit again and the tangent made
    /// unit and perpendicular to it (as a shader does with the interpolated pair: the
    /// two can be far from perpendicular across a crease), the tangent's handedness
    /// `a`'s (a chart's vertices share it).
    fn between(a: &Attributes, b: &Attributes, t: f64, plane: &Plane) -> Attributes {
        let n = a
            .normal
            .lerp(b.normal, t)
            .try_normalize()
            .unwrap_or(a.normal);
        let ta = DVec3::new(a.tangent[0], a.tangent[1], a.tangent[2]);
        let tb = DVec3::new(b.tangent[0], b.tangent[1], b.tangent[2]);
        let across = |v: DVec3| (v - n * n.dot(v)).try_normalize();
        let tt = across(ta.lerp(tb, t))
            .or_else(|| across(ta))
            .unwrap_or_else(|| n.any_orthonormal_vector());
        let lerp = |x: f64, y: f64| x + (y - x) * t;
        Attributes {
            position: crossing(a.position, b.position, t, plane),
            normal: n,
            tangent: [tt.x, tt.y, tt.z, a.tangent[3]],
            uv: [lerp(a.uv[0], b.uv[0]), lerp(a.uv[1], b.uv[1])],
        }
    }
}

/// A polygon's vertex while it is clipped: an index of the mesh's vertices, or past
/// them of the vertices made on crossings; and its position.
#[derive(Debug, Clone, Copy)]
struct Corner {
    id: u32,
    position: DVec3,
}

/// The clip's state: the vertices made on crossings (by edge and plane, so that the
/// triangles of an edge share them), and the output's index of each vertex, given
/// when a kept triangle first uses it.
struct Cutter<'m> {
    mesh: &'m MeshData,
    bounds: Aabb,
    made: Vec<Attributes>,
    made_at: HashMap<(u32, u32, u8), u32>,
    emitted: Vec<u32>,
    out: MeshData,
}

impl Cutter<'_> {
    fn attributes(&self, id: u32) -> Attributes {
        let n = self.mesh.positions.len();
        match (id as usize).checked_sub(n) {
            Some(k) => self.made[k],
            None => Attributes::of(self.mesh, id as usize),
        }
    }

    fn cut(&mut self, a: &Corner, b: &Corner, t: f64, plane: (u8, &Plane)) -> Corner {
        let key = (a.id.min(b.id), a.id.max(b.id), plane.0);
        if let Some(&id) = self.made_at.get(&key) {
            return Corner {
                id,
                position: self.attributes(id).position,
            };
        }
        let at = Attributes::between(&self.attributes(a.id), &self.attributes(b.id), t, plane.1);
        let id = (self.mesh.positions.len() + self.made.len()) as u32;
        self.made.push(at);
        self.emitted.push(u32::MAX);
        self.made_at.insert(key, id);
        Corner {
            id,
            position: at.position,
        }
    }

    /// The output's index of vertex `id`, pushed there at its first use.
    fn emit(&mut self, id: u32) -> u32 {
        if self.emitted[id as usize] == u32::MAX {
            let k = self.out.positions.len() as u32;
            let n = self.mesh.positions.len();
            let out = &mut self.out;
            if (id as usize) < n {
                let i = id as usize;
                let p = DVec3::from_array(self.mesh.positions[i].map(f64::from));
                let q = clamp(p, &self.bounds);
                out.positions.push(if q == p {
                    self.mesh.positions[i]
                } else {
                    q.as_vec3().to_array()
                });
                out.normals.push(self.mesh.normals[i]);
                out.tangents.push(self.mesh.tangents[i]);
                out.texcoords.push(self.mesh.texcoords[i]);
            } else {
                let a = self.made[id as usize - n];
                out.positions
                    .push(clamp(a.position, &self.bounds).as_vec3().to_array());
                out.normals.push(a.normal.as_vec3().to_array());
                out.tangents.push(a.tangent.map(|x| x as f32));
                out.texcoords.push([a.uv[0] as f32, a.uv[1] as f32]);
            }
            self.emitted[id as usize] = k;
        }
        self.emitted[id as usize]
    }
}

/// `mesh` cut at the faces of `bounds`: the triangles inside them whole, those across
/// a face clipped to it (fanned from the clipped polygon's first corner, dropping a
/// triangle of no area), those outside dropped; a vertex outside a face by `slack` or
/// less lies on it (moved onto it); vertices renumbered in the order the
/// kept triangles use them, and none left unused (a mesh wholly inside is returned as
/// it is, without a copy). The made vertices are held in a table of the crossed edges
/// only, and the output is at most as large as `mesh` plus those: while it is made, the
/// bake holds three meshes' worth (its own, `mesh`, the output), as while the glb
/// encoder, which follows, fills its buffer (`bake::memory::VERTEX_BYTES`).
pub fn to_box(mesh: MeshData, bounds: Aabb, slack: f64) -> MeshData {
    let planes = Plane::of(bounds, slack);
    // Nothing to cut: the mesh as it is, in its own order.
    if mesh.positions.iter().all(|p| {
        let p = DVec3::from_array(p.map(f64::from));
        planes.iter().all(|pl| pl.distance(p) >= 0.0)
    }) {
        return mesh;
    }
    let mut c = Cutter {
        mesh: &mesh,
        bounds,
        made: Vec::new(),
        made_at: HashMap::new(),
        emitted: vec![u32::MAX; mesh.positions.len()],
        out: MeshData::default(),
    };
    let (mut poly, mut next) = (Vec::with_capacity(9), Vec::with_capacity(9));
    for tri in mesh.indices.chunks_exact(3) {
        let corners = [0, 1, 2].map(|k| Corner {
            id: tri[k],
            position: DVec3::from_array(mesh.positions[tri[k] as usize].map(f64::from)),
        });
        if planes
            .iter()
            .any(|pl| corners.iter().all(|v| pl.inside(v.position) < 0.0))
        {
            continue;
        }
        if planes
            .iter()
            .all(|pl| corners.iter().all(|v| pl.inside(v.position) >= 0.0))
        {
            for v in corners {
                let k = c.emit(v.id);
                c.out.indices.push(k);
            }
            continue;
        }
        poly.clear();
        poly.extend(corners);
        for (k, plane) in planes.iter().enumerate() {
            clip_polygon(
                &poly,
                &mut next,
                plane,
                &|v: &Corner| v.position,
                &mut |a, b, t| c.cut(a, b, t, (k as u8, plane)),
            );
            std::mem::swap(&mut poly, &mut next);
        }
        for i in 2..poly.len() {
            let (a, b, d) = (poly[0], poly[i - 1], poly[i]);
            let at = |v: Corner| clamp(v.position, &bounds);
            if area2(at(a), at(b), at(d)) > 0.0 {
                for v in [a, b, d] {
                    let k = c.emit(v.id);
                    c.out.indices.push(k);
                }
            }
        }
    }
    c.out
}
