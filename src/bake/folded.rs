//! Folded triangles out of the exported mesh.
//!
//! Where several cells' vertices lie on one point, a quad between them has two or more
//! corners at the same position: the mesher gives vertices joined by a quad side under
//! a tenth of a cell one position, so that creases grow no fins (`MERGE_CELLS`; the
//! quads keep their four corners), and a box's corner or a sphere's pole on a grid
//! line gathers several. A triangle with two equal corners has no area and two of its
//! edges lie on each other. It draws nothing, but it makes the mesh non-manifold (its
//! third edge is then held by three or four triangles) and shows in a modeller's checks
//! (degenerate faces, non-manifold edges). Removing it leaves the triangles around it
//! sharing their edges directly, so the mesh is as watertight as before, and the
//! texels, placed through each remaining triangle's own map, need no change.
//!
//! A triangle is folded when two of its corners have equal positions (the f32s the
//! file holds, compared as numbers: 0 and -0 are one point). Triangles of zero area
//! with three distinct corners (on one line) are kept: removing one would leave a
//! vertex in the middle of its neighbours' edge.

use crate::asset::MeshData;

/// `mesh` without its folded triangles and without the vertices no triangle uses any
/// more (the others keep their order; returned as it is when it has none), and how
/// many triangles were left out.
pub fn drop_folded(mut mesh: MeshData) -> (MeshData, usize) {
    let folded = |t: &[u32]| is_folded([0, 1, 2].map(|k| mesh.positions[t[k] as usize]));
    if !mesh.indices.chunks_exact(3).any(folded) {
        return (mesh, 0);
    }
    let before = mesh.indices.len() / 3;
    let kept: Vec<u32> = mesh
        .indices
        .chunks_exact(3)
        .filter(|t| !folded(t))
        .flatten()
        .copied()
        .collect();
    mesh.indices = kept;
    // The vertices still used, renumbered in their order.
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    for &i in &mesh.indices {
        remap[i as usize] = 0;
    }
    let mut next = 0u32;
    for r in remap.iter_mut().filter(|r| **r == 0) {
        *r = next;
        next += 1;
    }
    let keep = |k: &usize| remap[*k] != u32::MAX;
    compact(&mut mesh.positions, keep);
    compact(&mut mesh.normals, keep);
    compact(&mut mesh.tangents, keep);
    compact(&mut mesh.texcoords, keep);
    for i in &mut mesh.indices {
        *i = remap[*i as usize];
    }
    let left_out = before - mesh.indices.len() / 3;
    (mesh, left_out)
}

/// Whether a triangle with these corners is folded: two of them equal (compared as
/// numbers, so 0 and -0 are one point). The bake checks its mesh with it before the
/// GPU's work (`pipeline::check_reaches`), as the export then drops such triangles.
pub fn is_folded<P: PartialEq>(corners: [P; 3]) -> bool {
    let [a, b, c] = corners;
    a == b || b == c || a == c
}

/// `values` with only the entries whose index `keep` holds, in order.
fn compact<T: Copy>(values: &mut Vec<T>, keep: impl Fn(&usize) -> bool) {
    let mut at = 0;
    for k in 0..values.len() {
        if keep(&k) {
            values[at] = values[k];
            at += 1;
        }
    }
    values.truncate(at);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mesh of `positions` with attributes that tell the vertices apart.
    fn mesh(positions: &[[f32; 3]], indices: &[u32]) -> MeshData {
        let n = positions.len();
        MeshData {
            positions: positions.to_vec(),
            normals: (0..n).map(|k| [0.0, 0.0, k as f32]).collect(),
            tangents: (0..n).map(|k| [k as f32, 0.0, 0.0, 1.0]).collect(),
            texcoords: (0..n).map(|k| [k as f32 / 8.0, 0.5]).collect(),
            indices: indices.to_vec(),
        }
    }

    #[test]
    fn a_quad_with_two_corners_on_one_point_keeps_its_other_triangle() {
        // Corners 1 and 2 at one point (split vertices, as a quad collapsed at a pole
        // has), and a vertex (4) that only the folded triangle used.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
        ];
        let (m, left_out) = drop_folded(mesh(&p, &[0, 1, 3, 1, 2, 3, 4, 2, 1]));
        assert_eq!((m.indices, left_out), (vec![0, 1, 2], 2));
        assert_eq!(m.positions, vec![p[0], p[1], p[3]]);
        // Every attribute follows its vertex.
        assert_eq!(m.normals[2], [0.0, 0.0, 3.0]);
        assert_eq!(m.tangents[2], [3.0, 0.0, 0.0, 1.0]);
        assert_eq!(m.texcoords[2], [3.0 / 8.0, 0.5]);
    }

    #[test]
    fn a_mesh_without_folds_is_returned_as_it_is_slivers_stay_and_signed_zeros_meet() {
        // A sliver of zero area with three distinct corners stays.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let m = mesh(&p, &[0, 1, 2, 0, 2, 3]);
        assert_eq!(drop_folded(m.clone()), (m, 0));
        // Positions are compared as numbers: 0 and -0 are one point.
        let q = [[0.0, 0.0, 0.0], [-0.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert_eq!(drop_folded(mesh(&q, &[0, 1, 2])).1, 1);
    }

    #[test]
    fn a_quad_collapsed_to_a_point_goes_whole() {
        let p = [[0.5, 0.5, 0.5]; 4];
        let (m, left_out) = drop_folded(mesh(&p, &[0, 1, 3, 0, 3, 2]));
        assert!(m.indices.is_empty() && m.positions.is_empty() && m.texcoords.is_empty());
        assert_eq!(left_out, 2);
    }
}
