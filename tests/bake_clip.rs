//! The exported mesh cut at `--bounds`' faces (src/bake/clip.rs), on meshes whose every
//! attribute has a closed form: a tilted plane in two charts, its texture coordinates
//! linear in the position on each.

use crate::common;
use glam::DVec3;
use sdfc::bake::clip::{reaches, to_box};
use sdfc::bake::MeshData;
use sdfc::ir::Aabb;

/// The plane z = 0.3 x + 0.2 y.
fn height(x: f64, y: f64) -> f64 {
    0.3 * x + 0.2 * y
}

/// Chart `c`'s texture coordinates at (x, y): linear, each chart its own.
fn uv_of(c: usize, x: f64, y: f64) -> [f64; 2] {
    [
        0.1 + 0.5 * c as f64 + 0.2 * (x + 1.0),
        0.3 + 0.2 * (y + 1.0),
    ]
}

/// The plane over [-1, 1]² as a grid of `k × k` quads a chart, two charts (x < 0 and
/// x > 0) whose vertices on x = 0 are split (their texture coordinates differ), as the
/// welded bake's; the tangent along +x, the normals tilted by a linear field (made unit)
/// so that interpolating them is seen.
fn two_charts(k: usize) -> MeshData {
    let mut m = MeshData::default();
    let up = DVec3::new(-0.3, -0.2, 1.0).normalize();
    let tangent = DVec3::new(1.0, 0.0, 0.3).normalize();
    for c in 0..2 {
        let base = m.positions.len() as u32;
        for j in 0..=k {
            for i in 0..=k {
                let x = -1.0 + c as f64 + i as f64 / k as f64;
                let y = -1.0 + 2.0 * j as f64 / k as f64;
                m.positions.push([x as f32, y as f32, height(x, y) as f32]);
                let n = (up + DVec3::new(0.1 * x, 0.05 * y, 0.0)).normalize();
                m.normals.push(n.as_vec3().to_array());
                let t = (tangent - n * n.dot(tangent)).normalize();
                m.tangents.push([t.x as f32, t.y as f32, t.z as f32, 1.0]);
                m.texcoords.push(uv_of(c, x, y).map(|u| u as f32));
            }
        }
        let at = |i: usize, j: usize| base + (j * (k + 1) + i) as u32;
        for j in 0..k {
            for i in 0..k {
                let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                m.indices.extend([q[0], q[1], q[2], q[0], q[2], q[3]]);
            }
        }
    }
    m
}

fn p(m: &MeshData, i: u32) -> DVec3 {
    DVec3::from_array(m.positions[i as usize].map(f64::from))
}

#[test]
fn a_mesh_cut_at_the_box_ends_on_its_faces_with_its_texture_unchanged() {
    let mesh = two_charts(12);
    let b = Aabb {
        min: DVec3::new(-0.63, -2.0, -0.2),
        max: DVec3::new(0.71, 0.37, 5.0),
    };
    let cut = to_box(mesh.clone(), b, 0.0);
    assert!(!cut.indices.is_empty() && cut.indices.len() % 3 == 0);
    let n = cut.positions.len();
    assert!(cut.indices.iter().all(|&i| (i as usize) < n));
    let mut used = vec![false; n];
    cut.indices.iter().for_each(|&i| used[i as usize] = true);
    assert!(used.iter().all(|&u| u), "unused vertices were kept");
    // Inside the box (to the f32 rounding of its faces), on the plane.
    let f32_of = |x: f64| x as f32 as f64;
    for i in 0..n as u32 {
        let q = p(&cut, i);
        for a in 0..3 {
            assert!(
                q[a] >= f32_of(b.min[a]) && q[a] <= f32_of(b.max[a]),
                "{q} lies outside the box"
            );
        }
        assert!(
            (q.z - height(q.x, q.y)).abs() < 1e-6,
            "{q} is off the plane"
        );
    }
    // Every vertex's texture coordinate is its chart's linear function of its position:
    // the cut kept the map the texels were placed through.
    for i in 0..n {
        let q = p(&cut, i as u32);
        let c = usize::from(cut.texcoords[i][0] > 0.5);
        let want = uv_of(c, q.x, q.y);
        for a in 0..2 {
            assert!(
                (cut.texcoords[i][a] as f64 - want[a]).abs() < 1e-6,
                "{q}: uv {:?}, chart {c}'s map gives {want:?}",
                cut.texcoords[i]
            );
        }
        let nrm = DVec3::from_array(cut.normals[i].map(f64::from));
        assert!((nrm.length() - 1.0).abs() < 1e-6, "{nrm}");
        let t = cut.tangents[i];
        let tv = DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64);
        assert!((tv.length() - 1.0).abs() < 1e-6 && t[3] == 1.0, "{t:?}");
        assert!(
            tv.dot(nrm).abs() < 1e-6,
            "a tangent {tv} off the normal {nrm}'s plane"
        );
    }
    // The area: the rectangle [-0.63, 0.71] × [-1, 0.37] less the corner where the plane
    // dips under z = -0.2 (the triangle (-0.63, -1), (0, -1), (-0.63, -0.055)), on a
    // plane tilted by √1.13.
    let flat = 1.34 * 1.37 - 0.5 * 0.63 * 0.945;
    let want = flat * 1.13f64.sqrt();
    let mut area = 0.0;
    let up = DVec3::new(-0.3, -0.2, 1.0);
    for t in cut.indices.chunks_exact(3) {
        let cr = (p(&cut, t[1]) - p(&cut, t[0])).cross(p(&cut, t[2]) - p(&cut, t[0]));
        assert!(cr.length() > 0.0, "a triangle of no area");
        assert!(cr.dot(up) > 0.0, "a triangle turned over");
        area += 0.5 * cr.length();
    }
    assert!(
        (area - want).abs() < 1e-5 * want,
        "area {area}, the region's {want}"
    );
    // Watertight: an edge held once (by its ends' bits) lies on a face of the box or on
    // the plane's own rim; the charts' border x = 0 is held twice, by split vertices
    // made bit for bit alike.
    let held = common::edges_by_position(&cut);
    let on_face = |q: DVec3| {
        (0..3).any(|a| q[a] == f32_of(b.min[a]) || q[a] == f32_of(b.max[a])) || q.y == -1.0
    };
    let mut rim = 0;
    for (e, &count) in &held {
        assert!(count <= 2, "an edge held {count} times");
        if count == 1 {
            let [a, c] = e.map(|v| DVec3::from_array(v.map(|x| f32::from_bits(x) as f64)));
            assert!(
                on_face(a) && on_face(c),
                "an open edge {a} – {c} inside the box"
            );
            rim += 1;
        }
    }
    assert!(rim > 20, "{rim}");
    // Inside each chart the triangles share their vertices, those made on the cut too:
    // two pieces, one a chart.
    assert_eq!(common::mesh_pieces(&cut), 2);
}

#[test]
fn a_box_around_the_mesh_keeps_it_as_it_is_and_one_past_it_keeps_nothing() {
    let mesh = two_charts(5);
    let all = Aabb {
        min: DVec3::splat(-1.0),
        max: DVec3::splat(1.0),
    };
    assert!(
        to_box(mesh.clone(), all, 0.0) == mesh,
        "a box around the mesh changed it"
    );
    let tris = |m: &MeshData| -> Vec<[DVec3; 3]> {
        m.indices
            .chunks_exact(3)
            .map(|t| [p(m, t[0]), p(m, t[1]), p(m, t[2])])
            .collect()
    };
    assert!(reaches(tris(&mesh), all, 0.0));
    // Above the plane everywhere (its highest point is z = 0.5), and touching it at one
    // corner only: nothing of non-zero area.
    for past in [
        Aabb {
            min: DVec3::new(-1.0, -1.0, 0.51),
            max: DVec3::splat(1.0),
        },
        Aabb {
            min: DVec3::new(1.0, 1.0, -1.0),
            max: DVec3::splat(2.0),
        },
    ] {
        let cut = to_box(mesh.clone(), past, 0.0);
        assert!(
            cut.indices.is_empty() && cut.positions.is_empty(),
            "{past:?}"
        );
        assert!(!reaches(tris(&mesh), past, 0.0), "{past:?}");
    }
    // A sliver of it: kept, and `reaches` says so.
    let sliver = Aabb {
        min: DVec3::new(0.99, 0.99, -1.0),
        max: DVec3::splat(2.0),
    };
    assert!(reaches(tris(&mesh), sliver, 0.0));
    let cut = to_box(mesh.clone(), sliver, 0.0);
    let area: f64 = cut
        .indices
        .chunks_exact(3)
        .map(|t| {
            0.5 * (p(&cut, t[1]) - p(&cut, t[0]))
                .cross(p(&cut, t[2]) - p(&cut, t[0]))
                .length()
        })
        .sum();
    let want = 0.01f64 * 0.01 * 1.13f64.sqrt();
    assert!((area - want).abs() < 1e-3 * want, "{area} against {want}");
}

/// A closed cube of side 1 turned by a rotation, six charts of `k × k` quads, their
/// vertices split along the cube's edges (each face's texture coordinates its own,
/// linear in the face's position); each vertex's chart is its uv's sixth of [0, 1].
fn turned_cube(k: usize, turn: glam::DQuat) -> MeshData {
    let mut m = MeshData::default();
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for f in 0..6 {
        let (a, sign) = (f / 2, if f % 2 == 0 { 1.0 } else { -1.0 });
        let n = axes[a] * sign;
        let t = axes[(a + 1) % 3] * sign;
        let b = n.cross(t);
        let base = m.positions.len() as u32;
        for j in 0..=k {
            for i in 0..=k {
                let (u, v) = (i as f64 / k as f64, j as f64 / k as f64);
                let p = 0.5 * n + (u - 0.5) * t + (v - 0.5) * b;
                m.positions.push((turn * p).as_vec3().to_array());
                m.normals.push((turn * n).as_vec3().to_array());
                let tt = turn * t;
                m.tangents
                    .push([tt.x as f32, tt.y as f32, tt.z as f32, 1.0]);
                m.texcoords.push([
                    ((f as f64 + 0.1 + 0.8 * u) / 6.0) as f32,
                    (0.1 + 0.8 * v) as f32,
                ]);
            }
        }
        let at = |i: usize, j: usize| base + (j * (k + 1) + i) as u32;
        for j in 0..k {
            for i in 0..k {
                m.indices.extend([
                    at(i, j),
                    at(i + 1, j),
                    at(i + 1, j + 1),
                    at(i, j),
                    at(i + 1, j + 1),
                    at(i, j + 1),
                ]);
            }
        }
    }
    m
}

fn area(m: &MeshData) -> f64 {
    m.indices
        .chunks_exact(3)
        .map(|t| {
            0.5 * (p(m, t[1]) - p(m, t[0]))
                .cross(p(m, t[2]) - p(m, t[0]))
                .length()
        })
        .sum()
}

/// Random boxes across a turned cube (every cut oblique to its triangles): the cut lies
/// in the box, is closed but on the box's faces (bit for bit across the cube's chart
/// borders), keeps every face's linear texture map, and its area adds up: the cuts of
/// the two halves of a box, split by a plane, are the cut of the box.
#[test]
fn random_boxes_cut_a_turned_cube_into_closed_pieces_whose_areas_add_up() {
    let turn = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.5, -0.7, 0.3);
    let cube = turned_cube(3, turn);
    let whole = Aabb {
        min: DVec3::splat(-1.0),
        max: DVec3::splat(1.0),
    };
    assert!((area(&to_box(cube.clone(), whole, 0.0)) - 6.0).abs() < 1e-5);
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut cut_some = 0;
    for _ in 0..150 {
        let (c, h) = (
            DVec3::new(next(), next(), next()) * 1.2 - 0.6,
            DVec3::new(next(), next(), next()) * 0.6 + 0.05,
        );
        let b = Aabb {
            min: c - h,
            max: c + h,
        };
        let cut = to_box(cube.clone(), b, 0.0);
        let f32_of = |x: f64| x as f32 as f64;
        let on_face =
            |q: DVec3| (0..3).any(|a| q[a] == f32_of(b.min[a]) || q[a] == f32_of(b.max[a]));
        let held = common::edges_by_position(&cut);
        for (e, &count) in &held {
            let [a, c] = e.map(|v| DVec3::from_array(v.map(|x| f32::from_bits(x) as f64)));
            assert!(count <= 2, "{b:?}: an edge held {count} times");
            assert!(
                count == 2 || (on_face(a) && on_face(c)),
                "{b:?}: a hole at {a} – {c}"
            );
        }
        for i in 0..cut.positions.len() {
            let q = p(&cut, i as u32);
            for a in 0..3 {
                assert!(
                    q[a] >= f32_of(b.min[a]) && q[a] <= f32_of(b.max[a]),
                    "{b:?}: {q}"
                );
            }
            // The face's own coordinates: its uv, back through the face's map.
            let [s, t] = cut.texcoords[i].map(f64::from);
            let f = (s * 6.0).floor() as usize;
            let (u, v) = ((s * 6.0 - f as f64 - 0.1) / 0.8, (t - 0.1) / 0.8);
            let axes = [DVec3::X, DVec3::Y, DVec3::Z];
            let (a, sign) = (f / 2, if f % 2 == 0 { 1.0 } else { -1.0 });
            let (n, tt) = (axes[a] * sign, axes[(a + 1) % 3] * sign);
            let want = turn * (0.5 * n + (u - 0.5) * tt + (v - 0.5) * n.cross(tt));
            assert!(
                (want - q).length() < 1e-5,
                "{b:?}: {q} has the uv of {want}"
            );
        }
        // Split along a random axis at a random point inside: the halves add up.
        let axis = (next() * 3.0) as usize % 3;
        let at = b.min[axis] + (0.2 + 0.6 * next()) * (b.max[axis] - b.min[axis]);
        let (mut lo, mut hi) = (b, b);
        lo.max[axis] = at;
        hi.min[axis] = at;
        let (whole, parts) = (
            area(&cut),
            area(&to_box(cube.clone(), lo, 0.0)) + area(&to_box(cube.clone(), hi, 0.0)),
        );
        assert!(
            (whole - parts).abs() < 1e-5,
            "{b:?}: {whole} against {parts} in two halves"
        );
        cut_some += usize::from(whole > 0.0 && whole < 6.0 - 1e-6);
    }
    assert!(cut_some > 50, "{cut_some} of the boxes cut the cube");
}

/// A surface lying along a face of the box, a rounding error off it (the mesher puts a
/// plane at 0 at -1.25e-13), is kept whole within the slack and moved onto the face;
/// without slack it is dropped whole (it was kept or dropped at random).
#[test]
fn a_surface_along_a_face_is_kept_whole_within_the_slack() {
    let mut flat = two_charts(4);
    for p in &mut flat.positions {
        p[2] = -1.25e-13;
    }
    let b = Aabb {
        min: DVec3::new(-2.0, -2.0, 0.0),
        max: DVec3::splat(2.0),
    };
    let tris = |m: &MeshData| -> Vec<[DVec3; 3]> {
        m.indices
            .chunks_exact(3)
            .map(|t| [p(m, t[0]), p(m, t[1]), p(m, t[2])])
            .collect()
    };
    assert!(!reaches(tris(&flat), b, 0.0));
    assert!(to_box(flat.clone(), b, 0.0).indices.is_empty());
    assert!(reaches(tris(&flat), b, 1e-6));
    let kept = to_box(flat.clone(), b, 1e-6);
    assert_eq!(kept.indices.len(), flat.indices.len());
    assert!(kept.positions.iter().all(|p| p[2] == 0.0));
    // The same vertices, renumbered.
    let sorted = |m: &MeshData| {
        let mut v: Vec<[u32; 2]> = m.texcoords.iter().map(|t| t.map(f32::to_bits)).collect();
        v.sort();
        v
    };
    assert_eq!(sorted(&kept), sorted(&flat));
    assert!((area(&kept) - 4.0).abs() < 1e-6);
    // Past the slack, it is outside.
    assert!(!reaches(tris(&flat), b, 1e-14));
}

/// A vertex just inside a face (within the slack) stays where it is, and the sliver
/// between it and the face is cut as any other: counted on the face, it was dropped,
/// leaving a hole along the cut (the red team's `--chart-quads 2` bakes).
#[test]
fn a_vertex_just_inside_a_face_keeps_the_sliver_beyond_it() {
    let mesh = two_charts(12);
    // Chart 0's column of vertices at x = -0.5 lies 1e-7 inside the face.
    let b = Aabb {
        min: DVec3::new(-0.5 - 1e-7, -2.0, -5.0),
        max: DVec3::splat(5.0),
    };
    let cut = to_box(mesh, b, 1e-6);
    let face = (b.min.x as f32) as f64;
    for (e, &count) in &common::edges_by_position(&cut) {
        let [a, c] = e.map(|v| DVec3::from_array(v.map(|x| f32::from_bits(x) as f64)));
        let on_rim = |q: DVec3| q.x == face || q.x == 1.0 || q.y.abs() == 1.0;
        assert!(
            count == 2 || (on_rim(a) && on_rim(c)),
            "a hole at {a} – {c}"
        );
    }
    let lowest = cut.positions.iter().map(|p| p[0]).fold(f32::MAX, f32::min);
    assert_eq!(lowest as f64, face, "the cut ends on the face");
}
