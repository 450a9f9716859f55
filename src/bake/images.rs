//! Stage 6: the atlas images (flat §3.3, packed §3.4) and the exported mesh.

use super::charts::{bilinear, side_texel, ChartTable, Samples};
pub use super::mesh::split_along_02;
use super::mesh::QuadMesh;
use super::mips::{Texel, CHANNELS, EMISSION};
use super::{ChartLayout, FlatLayout, MeshData, Patches, Textures};
use glam::DVec3;
use image::{Rgba, RgbaImage};

pub use crate::asset::{srgb8, unorm8};

/// Each cell's tangents along +u at its four corners: at every vertex of a chart's
/// grid, the mean of the u-edges (bottom or top side) of the chart's cells there. For a
/// one-cell chart they are the cell's own sides, and their bilinear blend is the
/// patch's ∂/∂u; in a grown chart they agree between neighbouring cells, so the
/// tangent frame is continuous across the cells inside a chart.
pub fn corner_tangents(mesh: &QuadMesh, patches: &Patches) -> Vec<[DVec3; 4]> {
    let v = &mesh.vertices;
    let mut out = vec![[DVec3::ZERO; 4]; mesh.quads.len()];
    for p in 0..patches.len() {
        let [a, b] = patches.dims[p].map(|d| d as usize);
        let mut sum = vec![(DVec3::ZERO, 0.0); (a + 1) * (b + 1)];
        let cells = &patches.cells[p];
        for j in 0..b {
            for i in 0..a {
                let q = mesh.quads[cells[j * a + i] as usize].map(|k| v[k as usize]);
                let (bottom, top) = (q[1] - q[0], q[2] - q[3]);
                // A side the mesher collapsed (two corners joined) has no direction:
                // the other side's is the limit of ∂/∂u there.
                let (bottom, top) = match (bottom == DVec3::ZERO, top == DVec3::ZERO) {
                    (true, false) => (top, top),
                    (false, true) => (bottom, bottom),
                    _ => (bottom, top),
                };
                for (di, dj, e) in [(0, 0, bottom), (1, 0, bottom), (1, 1, top), (0, 1, top)] {
                    let s = &mut sum[(j + dj) * (a + 1) + i + di];
                    s.0 += e;
                    s.1 += 1.0;
                }
            }
        }
        for j in 0..b {
            for i in 0..a {
                let at = |di: usize, dj: usize| {
                    let (t, k) = sum[(j + dj) * (a + 1) + i + di];
                    t / k
                };
                out[cells[j * a + i] as usize] = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)];
            }
        }
    }
    out
}

/// Each cell's bitangent sign (glTF's TANGENT w), one for its whole chart: the sign of
/// the sum, over the chart's cells at their centres, of cross(N, T) · (−∂/∂v)
/// ([`frame`]'s handedness). glTF gives a triangle's vertices one sign between them
/// (a rasterizer interpolates w, and a w between −1 and 1 shrinks the bitangent). Taken
/// vertex by vertex, the sign flipped where a vertex's normal stood across the chart's
/// own plane (a crease's corner): a twisted box at `--grid 12` mixed signs in 96 of its
/// 364 triangles, `warps.sdf` at its default grid, unrefined, in 486 of 2,876, and the normal map
/// drew dark wedges from the creases there (`tests/bake.rs`).
pub fn chart_signs(mesh: &QuadMesh, patches: &Patches, tangents: &[[DVec3; 4]]) -> Vec<f64> {
    let mut out = vec![1.0; mesh.quads.len()];
    for cells in &patches.cells {
        let sum: f64 = cells
            .iter()
            .map(|&c| frame(mesh, mesh.quads[c as usize], tangents[c as usize], 0.5, 0.5).2)
            .sum();
        let sign = if sum >= 0.0 { 1.0 } else { -1.0 };
        for &c in cells {
            out[c as usize] = sign;
        }
    }
    out
}

/// The tangent frame the mesh carries at chart-local (u, v): the tangent along +u
/// (bilinear in the corner tangents of [`corner_tangents`], orthogonal to the normal),
/// the normal (bilinear in the corners' normals), and the handedness there,
/// cross(N, T) · (−∂/∂v), whose sign over the chart ([`chart_signs`]) is glTF's
/// bitangent sign w: cross(N, T) · w points toward −v (glTF's normal maps have +Y up,
/// and glTF's texture coordinates grow downward).
pub fn frame(
    mesh: &QuadMesh,
    corners: [u32; 4],
    tangents: [DVec3; 4],
    u: f64,
    v: f64,
) -> (DVec3, DVec3, f64) {
    let p = corners.map(|i| mesh.vertices[i as usize]);
    let nrm = corners.map(|i| mesh.normals[i as usize]);
    let n = bilinear(nrm, u, v).normalize_or(DVec3::Y);
    let du = bilinear(tangents, u, v);
    let dv = (p[3] - p[0]) * (1.0 - u) + (p[2] - p[1]) * u;
    let t = (du - n * n.dot(du))
        .try_normalize()
        .unwrap_or_else(|| n.any_orthonormal_vector());
    (t, n, n.cross(t).dot(-dv))
}

/// The tangent frame a rasterizer rebuilds at chart-local (u, v) of chart `c` of the
/// exported mesh (`m × m` quads per chart, as [`mesh_data`] writes them): the
/// vertices' normals and tangents interpolated barycentrically over the triangle that
/// holds (u, v), then N = normalize(n), T = normalize(t − N (N · t)), and the
/// bitangent sign. The tangent-space normal map is encoded against exactly this
/// frame, so the mesh renderer (and any glTF viewer) decodes the baked normal.
pub fn render_frame(
    exported: &MeshData,
    m: usize,
    c: usize,
    u: f64,
    v: f64,
) -> (DVec3, DVec3, f64) {
    let n = m + 1;
    let (a, b) = (
        ((u * m as f64).floor() as usize).min(m - 1),
        ((v * m as f64).floor() as usize).min(m - 1),
    );
    let (s, t) = (u * m as f64 - a as f64, v * m as f64 - b as f64);
    let base = c * n * n;
    let k = [
        b * n + a,
        b * n + a + 1,
        (b + 1) * n + a + 1,
        (b + 1) * n + a,
    ]
    .map(|k| base + k);
    // The split mesh_data chose, read from its triangles (the quad's first triangle
    // ends at corner 2 when split along 0–2; deciding again from the f32 positions
    // could flip a choice made on the f64 grid), and the barycentric weights of
    // (s, t) in its triangle.
    let first = 6 * (c * m * m + b * m + a);
    let along_02 = exported.indices.get(first + 2) == Some(&(k[2] as u32));
    let weights = weights_in_split(along_02, s, t);
    let mut nrm = DVec3::ZERO;
    let mut tan = DVec3::ZERO;
    let mut sign = 0.0;
    for (w, &k) in weights.iter().zip(&k) {
        nrm += DVec3::from_array(exported.normals[k].map(f64::from)) * *w;
        let t4 = exported.tangents[k];
        tan += DVec3::new(t4[0] as f64, t4[1] as f64, t4[2] as f64) * *w;
        sign += t4[3] as f64 * *w;
    }
    let nrm = nrm.normalize_or(DVec3::Y);
    let tan = (tan - nrm * nrm.dot(tan))
        .try_normalize()
        .unwrap_or_else(|| nrm.any_orthonormal_vector());
    (tan, nrm, if sign >= 0.0 { 1.0 } else { -1.0 })
}

/// The texel of a tangent-space normal map for the baked (object-space) normal in
/// `t[8..11]`, against the frame `(T, N, bitangent sign)` a rasterizer rebuilds there
/// ([`render_frame`]): `(n · T, n · B, n · N) · 0.5 + 0.5` in 8 bits.
///
/// A normal map's normals point out of the surface (z ≥ 0): engines that store two
/// channels rebuild z as `√(1 − x² − y²)`, and a normal that points into the mesh
/// shades its texel black in the others. The baked normal can point into the mesh
/// where the mesh's interpolated normal is far from the field's gradient (a crease's
/// triangle, such as the capsule's drilled rim: 232 of its 130,560 level-0 texels at
/// 512², the default grid, before this clamp), so such a normal is replaced by the
/// nearest one on the hemisphere: its tangent-plane direction at z = 0 (a grazing
/// normal; straight out if it had none).
pub fn tangent_space_texel((tan, nrm, sign): (DVec3, DVec3, f64), t: &Texel<CHANNELS>) -> Rgba<u8> {
    let bit = nrm.cross(tan) * sign;
    let o = DVec3::new(t[8] as f64, t[9] as f64, t[10] as f64).normalize_or(nrm);
    let mut ts = DVec3::new(o.dot(tan), o.dot(bit), o.dot(nrm));
    if ts.z < 0.0 {
        ts = DVec3::new(ts.x, ts.y, 0.0)
            .try_normalize()
            .unwrap_or(DVec3::Z);
    }
    let enc = |x: f64| unorm8((x * 0.5 + 0.5) as f32);
    Rgba([enc(ts.x), enc(ts.y), enc(ts.z), 255])
}

/// Writes every level of every cell into the atlas: base colour (sRGB),
/// metallic-roughness, tangent-space normals and emission (when any). In a packed
/// atlas the cells of a chart share their common rows and columns of texels (the same
/// samples, and the same tangent frame there).
pub fn atlas_images(
    exported: &MeshData,
    m: usize,
    table: &ChartTable,
    atlas: &ChartLayout,
    patches: &Patches,
    levels: &[Samples<Texel<CHANNELS>>],
    strength: f32,
) -> Textures {
    let (w, h) = (atlas.width(), atlas.height());
    let blank = || RgbaImage::from_pixel(w, h, Rgba([0, 0, 0, 255]));
    let mut color = blank();
    let mut mr = blank();
    let mut normal = RgbaImage::from_pixel(w, h, Rgba([128, 128, 255, 255]));
    let mut emission = blank();
    let mut emits = false;
    // Emission over 1 is carried by the strength (`emissive_strength`): the image
    // holds emission ÷ it.
    let emitted = |e: &[f32]| {
        let [r, g, b] = [e[0], e[1], e[2]].map(|v| srgb8(v / strength));
        Rgba([r, g, b, 255])
    };
    for (l, level) in levels.iter().enumerate().take(atlas.levels()) {
        let n = level.n;
        for c in 0..table.len() {
            let [x0, y0] = patches.cell_origin(atlas, c, l);
            let grid = level.grid(table, c);
            for j in 0..n {
                for i in 0..n {
                    let t = &grid[j * n + i];
                    let (x, y) = (x0 + i as u32, y0 + j as u32);
                    color.put_pixel(x, y, Rgba([srgb8(t[0]), srgb8(t[1]), srgb8(t[2]), 255]));
                    mr.put_pixel(x, y, Rgba([0, unorm8(t[3]), unorm8(t[4]), 255]));
                    let e = &t[EMISSION];
                    emits |= e.iter().any(|&v| v > 0.0);
                    emission.put_pixel(x, y, emitted(e));
                    let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                    let frame = render_frame(exported, m, c, u, v);
                    normal.put_pixel(x, y, tangent_space_texel(frame, t));
                }
            }
        }
    }
    if let ChartLayout::Flat(layout @ FlatLayout { gutter: 1.., .. }) = atlas {
        let g = layout.gutter as i64;
        let level = &levels[0];
        let n = level.n as i64;
        let grids: Vec<Vec<Texel<CHANNELS>>> =
            (0..table.len()).map(|c| level.grid(table, c)).collect();
        for c in 0..table.len() {
            let [x0, y0] = layout.chart_origin(c, 0);
            for j in -g..n + g {
                for i in -g..n + g {
                    if (0..n).contains(&i) && (0..n).contains(&j) {
                        continue;
                    }
                    // Past a corner, continue the side along u (clamp v into the chart).
                    let jc = j.clamp(0, n - 1);
                    let (side, k, depth) = if i < 0 {
                        (3, n - 1 - jc, -i)
                    } else if i >= n {
                        (1, jc, i - (n - 1))
                    } else if j < 0 {
                        (0, i, -j)
                    } else {
                        (2, n - 1 - i, j - (n - 1))
                    };
                    let t = match table.neighbours(c, side as usize).first() {
                        Some(&(c2, s2, reversed)) => {
                            let kk = if reversed { n - 1 - k } else { k };
                            let (a, b) = side_texel(
                                n as usize,
                                s2 as usize,
                                kk as usize,
                                depth.min(n - 1) as usize,
                            );
                            grids[c2 as usize][b * n as usize + a]
                        }
                        // A mesh boundary: the chart's own border texel.
                        None => {
                            let (a, b) = side_texel(n as usize, side as usize, k as usize, 0);
                            grids[c][b * n as usize + a]
                        }
                    };
                    let (x, y) = ((x0 as i64 + i) as u32, (y0 as i64 + j) as u32);
                    color.put_pixel(x, y, Rgba([srgb8(t[0]), srgb8(t[1]), srgb8(t[2]), 255]));
                    mr.put_pixel(x, y, Rgba([0, unorm8(t[3]), unorm8(t[4]), 255]));
                    let e = &t[EMISSION];
                    emission.put_pixel(x, y, emitted(e));
                    // The neighbour's normal in this chart's frame at the nearest border point.
                    let (u, v) = (
                        i.clamp(0, n - 1) as f64 / (n - 1) as f64,
                        jc as f64 / (n - 1) as f64,
                    );
                    let frame = render_frame(exported, m, c, u, v);
                    normal.put_pixel(x, y, tangent_space_texel(frame, &t));
                }
            }
        }
    }
    Textures {
        base_color: color,
        metallic_roughness: mr,
        normal,
        emissive: emits.then_some(emission),
        emissive_strength: strength,
    }
}

/// The emissive texture's strength for `texels` (glTF's `emissiveStrength`): the
/// largest finite emission of any channel of any of them, or 1 where that is at most 1.
/// The bake takes it over every level, or with `--bounds` over level 0's samples inside
/// them (a brighter sample cut away would dim what the file shows).
pub fn emissive_strength<'a>(texels: impl Iterator<Item = &'a Texel<CHANNELS>>) -> f32 {
    texels
        .flat_map(|t| t[EMISSION].iter().copied())
        .filter(|v| v.is_finite())
        .fold(1.0f32, f32::max)
}

/// One chart's level-`l` grid as a stacked-style image (§3.2): the chart grid of that
/// level alone, `columns · n × rows · n` texels, for the KTX2 mip chain.
pub fn stacked_level(
    table: &ChartTable,
    layout: &FlatLayout,
    level: &Samples<Texel<CHANNELS>>,
    l: usize,
) -> RgbaImage {
    let n = level.n as u32;
    let mut img = RgbaImage::from_pixel(layout.columns * n, layout.rows * n, Rgba([0, 0, 0, 255]));
    for c in 0..table.len() {
        let [cx, cy] = layout.cell(c);
        let grid = level.grid(table, c);
        for (k, t) in grid.iter().enumerate() {
            let (i, j) = (k as u32 % n, k as u32 / n);
            img.put_pixel(
                cx * n + i,
                cy * n + j,
                Rgba([srgb8(t[0]), srgb8(t[1]), srgb8(t[2]), 255]),
            );
        }
    }
    let _ = l;
    img
}

/// The exported mesh's vertices: each chart split into `m × m` quads at the
/// parameters (i/m, j/m), projected onto the surface (`project`); the points on a
/// chart's sides are computed once per mesh edge, so neighbouring charts' vertices
/// coincide and the mesh is watertight. The texels are placed through these vertices
/// ([`on_triangles`]), as a rasterizer interpolates them.
pub fn vertex_grid(
    mesh: &QuadMesh,
    table: &ChartTable,
    m: usize,
    project: &(dyn Fn(DVec3) -> DVec3 + Sync),
) -> Samples<[f64; 3]> {
    let v = &mesh.vertices;
    Samples::build(
        table,
        v.len(),
        m + 1,
        |i| v[i].to_array(),
        |e, t| {
            let edge = &table.edges[e];
            project(v[edge.a as usize].lerp(v[edge.b as usize], t)).to_array()
        },
        |c, s, t| project(bilinear(table.corners[c].map(|i| v[i as usize]), s, t)).to_array(),
    )
}

/// The barycentric weights of `(s, t)` in the triangle that holds it, of a quad with
/// corners `p` (in (0,0), (1,0), (1,1), (0,1) order) split as [`split_along_02`] says,
/// as [`mesh_data`] splits it.
fn split_weights(p: [DVec3; 4], s: f64, t: f64) -> [f64; 4] {
    weights_in_split(split_along_02(p), s, t)
}

/// The barycentric weights of `(s, t)` in the triangle that holds it, of a quad split
/// along 0–2 (`along_02`) or 1–3.
fn weights_in_split(along_02: bool, s: f64, t: f64) -> [f64; 4] {
    if along_02 {
        if s >= t {
            [1.0 - s, s - t, t, 0.0]
        } else {
            [1.0 - t, 0.0, s, t - s]
        }
    } else if s + t <= 1.0 {
        [1.0 - s - t, s, 0.0, t]
    } else {
        [0.0, 1.0 - t, s + t - 1.0, 1.0 - s]
    }
}

/// The point of the exported mesh at chart-local `(u, v)` of chart `c`: linear over the
/// triangle of the `m × m` vertex grid that holds it, exactly as any rasterizer
/// interpolates a position from TEXCOORD_0 (the texel at `(u, v)` then shades the
/// surface point nearest that one).
pub fn on_triangles(
    grid: &Samples<[f64; 3]>,
    table: &ChartTable,
    c: usize,
    u: f64,
    v: f64,
) -> DVec3 {
    let m = grid.n - 1;
    let (a, b) = (
        ((u * m as f64).floor() as usize).min(m - 1),
        ((v * m as f64).floor() as usize).min(m - 1),
    );
    let (s, t) = (u * m as f64 - a as f64, v * m as f64 - b as f64);
    let at = |i: usize, j: usize| DVec3::from_array(grid.get(table, c, i, j));
    let p = [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)];
    let w = split_weights(p, s, t);
    p[0] * w[0] + p[1] * w[1] + p[2] * w[2] + p[3] * w[3]
}

/// A bake's sample of chart `c` at chart-local `(u, v)`: the exported mesh's point
/// there ([`on_triangles`]), with the footprint of a sample `spacing` apart (in chart
/// units) as the fourth value, the longer of the chart's mean side lengths times it.
pub fn interior_point(
    mesh: &QuadMesh,
    table: &ChartTable,
    grid: &Samples<[f64; 3]>,
    c: usize,
    (u, v): (f64, f64),
    spacing: f64,
) -> [f32; 4] {
    let q = table.corners[c].map(|i| mesh.vertices[i as usize]);
    let p = on_triangles(grid, table, c, u, v);
    let size = ((q[1] - q[0]).length() + (q[2] - q[3]).length()) * 0.5;
    let size = size.max(((q[3] - q[0]).length() + (q[2] - q[1]).length()) * 0.5);
    let f = size * spacing;
    [p.x as f32, p.y as f32, p.z as f32, f as f32]
}

/// The point of the exported mesh on edge `e` at `t` (from `a` to `b`): linear between
/// the edge's consecutive vertices, which both charts of the edge share.
pub fn on_edge(grid: &Samples<[f64; 3]>, table: &ChartTable, e: usize, t: f64) -> DVec3 {
    let m = grid.n - 1;
    let k = ((t * m as f64).floor() as usize).min(m - 1);
    let s = t * m as f64 - k as f64;
    let at = |k: usize| DVec3::from_array(grid.on_edge(table, e, k));
    at(k).lerp(at(k + 1), s)
}

/// The exported mesh over the vertex grid of [`vertex_grid`] (`m × m` quads per
/// chart). Vertices are not shared between charts (their texture coordinates
/// differ); each small quad is split as [`split_along_02`] says.
pub fn mesh_data(
    mesh: &QuadMesh,
    table: &ChartTable,
    atlas: &ChartLayout,
    patches: &Patches,
    points: &Samples<[f64; 3]>,
) -> MeshData {
    let m = points.n - 1;
    let n = m + 1;
    let tangents = corner_tangents(mesh, patches);
    let signs = chart_signs(mesh, patches, &tangents);
    let mut out = MeshData::default();
    for (c, q) in table.corners.iter().enumerate() {
        let base = out.positions.len() as u32;
        let grid = points.grid(table, c);
        for j in 0..n {
            for i in 0..n {
                let (u, w) = (i as f64 / m as f64, j as f64 / m as f64);
                let p = DVec3::from_array(grid[j * n + i]);
                let (t, nrm, _) = frame(mesh, *q, tangents[c], u, w);
                let sign = signs[c];
                out.positions.push(p.as_vec3().to_array());
                out.normals.push(nrm.as_vec3().to_array());
                out.tangents
                    .push([t.x as f32, t.y as f32, t.z as f32, sign as f32]);
                out.texcoords.push(patches.texcoord(atlas, c, u, w));
            }
        }
        for j in 0..m {
            for i in 0..m {
                let k = [
                    j * n + i,
                    j * n + i + 1,
                    (j + 1) * n + i + 1,
                    (j + 1) * n + i,
                ];
                let p = k.map(|k| DVec3::from_array(grid[k]));
                let tris = if split_along_02(p) {
                    [0, 1, 2, 0, 2, 3]
                } else {
                    [0, 1, 3, 1, 2, 3]
                };
                out.indices.extend(tris.iter().map(|&t| base + k[t] as u32));
            }
        }
    }
    out
}

/// The exported mesh's triangles as [`mesh_data`] makes them (its positions rounded to
/// f32, as the file holds them), chart after chart.
pub fn grid_triangles<'a>(
    points: &'a Samples<[f64; 3]>,
    table: &'a ChartTable,
) -> impl Iterator<Item = [DVec3; 3]> + 'a {
    let m = points.n - 1;
    let n = m + 1;
    (0..table.len()).flat_map(move |c| {
        let grid = points.grid(table, c);
        let mut out = Vec::with_capacity(2 * m * m);
        for q in 0..m * m {
            let (i, j) = (q % m, q / m);
            let k = [
                j * n + i,
                j * n + i + 1,
                (j + 1) * n + i + 1,
                (j + 1) * n + i,
            ];
            // Split as mesh_data splits, on the f64 points.
            let along_02 = split_along_02(k.map(|k| DVec3::from_array(grid[k])));
            let p = k.map(|k| DVec3::from_array(grid[k]).as_vec3().as_dvec3());
            out.extend(if along_02 {
                [[p[0], p[1], p[2]], [p[0], p[2], p[3]]]
            } else {
                [[p[0], p[1], p[3]], [p[1], p[2], p[3]]]
            });
        }
        out
    })
}

/// Shares the vertices whose every attribute is bitwise the same (position, normal,
/// tangent and texture coordinates): inside a chart the cells' vertices on their common
/// sides become one, so a chart is one connected piece; across a chart border the
/// texture coordinates differ and the vertices stay split, as glTF needs. `mesh` is
/// [`mesh_data`]'s: cell after cell, `n × n` vertices each (`n` = `--chart-quads` + 1),
/// whose inner vertices belong to their cell alone, so only the `4 (n − 1)` on each
/// cell's sides are looked up (a fifth of the vertices at n = 17, where a table of every
/// vertex would double the export's memory).
pub fn weld(mesh: &MeshData, n: usize) -> MeshData {
    let mut out = MeshData::default();
    let count = mesh.positions.len();
    let per_cell = n * n;
    // Every vertex is looked up unless the mesh is whole cells of n × n with inner ones.
    let cells = n >= 3 && count % per_cell == 0;
    let on_side = |k: usize| {
        let (i, j) = ((k % per_cell) % n, (k % per_cell) / n);
        i == 0 || j == 0 || i == n - 1 || j == n - 1
    };
    out.positions.reserve(count);
    out.normals.reserve(count);
    out.tangents.reserve(count);
    out.texcoords.reserve(count);
    let mut index: std::collections::HashMap<[u32; 12], u32> = std::collections::HashMap::new();
    let mut remap = Vec::with_capacity(count);
    for k in 0..count {
        let (p, nrm, t, uv) = (
            mesh.positions[k],
            mesh.normals[k],
            mesh.tangents[k],
            mesh.texcoords[k],
        );
        let next = out.positions.len() as u32;
        let mut push = || {
            out.positions.push(p);
            out.normals.push(nrm);
            out.tangents.push(t);
            out.texcoords.push(uv);
            next
        };
        let at = if !cells || on_side(k) {
            let key = [
                p[0], p[1], p[2], nrm[0], nrm[1], nrm[2], t[0], t[1], t[2], t[3], uv[0], uv[1],
            ]
            .map(f32::to_bits);
            *index.entry(key).or_insert_with(push)
        } else {
            push()
        };
        remap.push(at);
    }
    out.indices = mesh.indices.iter().map(|&i| remap[i as usize]).collect();
    out
}

/// The object-space normals of every level in the flat atlas, encoded `n · 0.5 + 0.5`.
/// Unlike the tangent-space map these are the filtered samples themselves, so their
/// border texels are identical between charts, like the colours'.
pub fn object_normals(
    table: &ChartTable,
    atlas: &ChartLayout,
    patches: &Patches,
    levels: &[Samples<Texel<CHANNELS>>],
) -> RgbaImage {
    let mut img = RgbaImage::from_pixel(atlas.width(), atlas.height(), Rgba([128, 128, 128, 255]));
    for (l, level) in levels.iter().enumerate().take(atlas.levels()) {
        let n = level.n;
        for c in 0..table.len() {
            let [x0, y0] = patches.cell_origin(atlas, c, l);
            for (k, t) in level.grid(table, c).iter().enumerate() {
                let o = DVec3::new(t[8] as f64, t[9] as f64, t[10] as f64).normalize_or_zero();
                let enc = |x: f64| unorm8((x * 0.5 + 0.5) as f32);
                img.put_pixel(
                    x0 + (k % n) as u32,
                    y0 + (k / n) as u32,
                    Rgba([enc(o.x), enc(o.y), enc(o.z), 255]),
                );
            }
        }
    }
    img
}
