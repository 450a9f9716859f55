//! Atlas code: per atlas, its field, gradient, one Alg. 1 step, the walk (unrolled
//! to exactly N steps with 1/(N − i) folded, or a rolled loop), the search for the
//! geodesic-nearest seed over the seed grid, and Alg. 2's blend with the merged
//! neighbours. Seeds (projected positions, solved frames and offsets), the merge
//! graph, σ and the grid are constants. The scene-independent pieces are in
//! `shaders/uv.wgsl`.

/// Whether the nearest-seed search uses the seed grid ([`SeedGrid`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum SeedGridChoice {
    /// The grid for atlases of more than 4 seeds (the default).
    #[default]
    Auto,
    On,
    /// A plain scan of every seed.
    Off,
}

impl SeedGridChoice {
    pub fn grid(self, atlas: &Atlas) -> SeedGrid {
        let n = atlas.seeds.len();
        match self {
            SeedGridChoice::Off => SeedGrid::single(n),
            SeedGridChoice::Auto if n <= 4 => SeedGrid::single(n),
            _ => atlas.seed_grid(),
        }
    }
}

use super::emit::{lit, vec3, Writer};
use crate::uv::grid::SeedGrid;
use crate::uv::Atlas;
use glam::DVec3;
use std::fmt::Write;

/// How the walk's N steps are emitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum WalkForm {
    /// N calls of the step, each with its constant 1/(N − i) (the default).
    #[default]
    Unrolled,
    /// A loop of N iterations.
    Loop,
}

/// Emits the WGSL of atlas `k`; `atlas_NAME(p) -> AtlasSample` is its entry.
pub fn emit(out: &mut String, k: usize, atlas: &Atlas, form: WalkForm, grid: &SeedGrid) {
    let p = &atlas.params;
    let mut w = Writer::new();
    let d = w.shape(&atlas.shape, atlas.shape.root(), "p");
    let _ = writeln!(
        out,
        "// ---- atlas `{}`: {} seeds, N = {} ----",
        atlas.name,
        atlas.seeds.len(),
        p.steps
    );
    let _ = writeln!(
        out,
        "fn atlas_{k}_f(p: vec3<f32>) -> f32 {{\n{}    return {d}.x;\n}}\n",
        w.out
    );
    let hg = lit(p.h_gradient);
    let _ = writeln!(
        out,
        "fn atlas_{k}_grad(x: vec3<f32>) -> vec3<f32> {{
    let h = {hg};
    let dx = vec3<f32>(h, 0.0, 0.0);
    let dy = vec3<f32>(0.0, h, 0.0);
    let dz = vec3<f32>(0.0, 0.0, h);
    return vec3<f32>(atlas_{k}_f(x + dx) - atlas_{k}_f(x - dx), atlas_{k}_f(x + dy) - atlas_{k}_f(x - dy), atlas_{k}_f(x + dz) - atlas_{k}_f(x - dz)) / (2.0 * h);
}}
"
    );
    let reproject = if p.reproject {
        format!("    let gr = atlas_{k}_grad(next);\n    next = next - gr * (atlas_{k}_f(next) / max(dot(gr, gr), 1e-20));\n")
    } else {
        String::new()
    };
    let _ = writeln!(
        out,
        "// One step of Alg. 1 towards p.
fn atlas_{k}_step(st: WalkState, p: vec3<f32>, dmax: f32, inv_remaining: f32) -> WalkState {{
    if (st.status != UV_OK) {{
        return st;
    }}
    var out = st;
    let n = normalize(st.g);
    let to_p = p - st.x;
    let s = length(to_p) * inv_remaining;
    let v = to_p - n * dot(n, to_p);
    let vl = length(v);
    if (vl < {eps1} * length(to_p)) {{
        out.status = UV_HEURISTIC_FAILED;
        return out;
    }}
    let vh = v / vl;
    let h = {hc};
    let second = (atlas_{k}_f(st.x - vh * h) - 2.0 * atlas_{k}_f(st.x) + atlas_{k}_f(st.x + vh * h)) / (h * h);
    let kappa = -second / max(length(st.g), 1e-12);
    let tau = uv_time_step(s, kappa);
    var next = st.x + vh * tau + n * (0.5 * tau * tau * kappa);
{reproject}    let g_next = atlas_{k}_grad(next);
    let n_next = normalize(g_next);
    if (dot(n_next, n) < {one_minus_eps2}) {{
        out.status = UV_SHARP_FEATURE;
        return out;
    }}
    out.rot = st.rot * uv_rotation_between(n_next, n);
    out.r = st.r + uv_arc_length(tau, kappa);
    out.prev = st.x;
    out.x = next;
    out.g = g_next;
    if (out.r + length(next - p) > dmax) {{
        out.status = UV_TOO_FAR;
    }}
    return out;
}}
",
        eps1 = lit(p.heuristic_tolerance),
        hc = lit(p.h_curvature),
        one_minus_eps2 = lit(1.0 - p.sharp_tolerance),
    );
    let n = p.steps.max(1);
    let steps = match form {
        WalkForm::Unrolled => (0..n).map(|i| format!("    st = atlas_{k}_step(st, p, dmax, {});\n", lit(1.0 / (n - i) as f64))).collect::<String>(),
        WalkForm::Loop => format!("    for (var i = 0u; i < {n}u; i = i + 1u) {{\n        st = atlas_{k}_step(st, p, dmax, 1.0 / f32({n}u - i));\n    }}\n"),
    };
    let rmin = lit(p.min_reach);
    emit_tables(out, k, atlas, grid);
    let _ = writeln!(
        out,
        "// Alg. 1 around seed j (the constants above): exactly N = {n} steps.
fn atlas_{k}_walk(x: vec3<f32>, j: u32, dmax: f32) -> AtlasSample {{
    let p = ATLAS_{k}_P[j];
    let np = ATLAS_{k}_N[j];
    let e1 = ATLAS_{k}_E1[j];
    let e2 = cross(np, e1);
    let seed = f32(j);
    let d0 = length(x - p);
    if (d0 > dmax) {{
        return uv_failed(UV_TOO_FAR, seed);
    }}
    if (d0 < {rmin}) {{
        let t0 = (x - p) - np * dot(np, x - p);
        let t0l = max(length(t0), 1e-30);
        return AtlasSample(vec2<f32>(dot(t0, e1), dot(t0, e2)) / t0l * d0, d0, 0.0, vec4<f32>(0.0, 0.0, 0.0, 1.0), seed, 1.0);
    }}
    let identity = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
    var st = WalkState(x, x, atlas_{k}_grad(x), 0.0, identity, UV_OK);
{steps}    if (st.status != UV_OK) {{
        return uv_failed(st.status, seed);
    }}
    let rest = length(st.x - p);
    if (rest >= {rmin}) {{
        return uv_failed(UV_NOT_REACHED, seed);
    }}
    let r = st.r + rest;
    let dd = st.prev - p;
    let t = dd - np * dot(np, dd);
    let tl = max(length(t), 1e-30);
    let rot = st.rot * uv_rotation_between(np, normalize(st.g));
    return AtlasSample(vec2<f32>(dot(t, e1), dot(t, e2)) / tl * r, r, 0.0, uv_quaternion(rot), seed, 1.0);
}}
"
    );
    let dmax = lit(p.max_distance);
    let cells = grid.cells();
    let list = if cells == 0 {
        String::from("0u")
    } else {
        let [dx, dy, dz] = grid.dims;
        format!(
            "uv_grid_list(x, {min}, {inv}, vec3<u32>({dx}u, {dy}u, {dz}u))",
            min = vec3(grid.min),
            inv = vec3(DVec3::ONE / grid.cell),
        )
    };
    // Alg. 2 as one loop with a single call site of the walk (so that drivers inline
    // the unrolled walk once): phase 0 searches the nearest seed over the seed grid's
    // list; a seed whose Euclidean lower bound is not below the best geodesic distance
    // so far cannot win (Eq. 35), nor can any after it, and the best so far is the next
    // walk's D. Phase 1 blends with the nearest seed's merged neighbours.
    let sigma = lit(atlas.sigma);
    let _ = writeln!(
        out,
        "// Alg. 2: the nearest seed, then the blend with its merged neighbours (Eqs. 39-44;
// the last line as corrected by the notes). sigma = {sigma}.
fn atlas_{name}(x: vec3<f32>) -> AtlasSample {{
    var best = uv_failed(UV_TOO_FAR, -1.0);
    var found = false;
    var fail_e = 3.0e38;
    let list = {list};
    var t = ATLAS_{k}_START[list];
    var end = ATLAS_{k}_START[list + 1u];
    var phase = 0u;
    let sigma = {sigma};
    var own = vec2<f32>(0.0);
    var d = 0.0;
    var sum = vec2<f32>(0.0);
    var total = 0.0;
    var w_own = 1.0;
    loop {{
        if (t >= end) {{
            if (phase == 1u || !found) {{
                break;
            }}
            let i = u32(best.seed);
            own = best.uv + ATLAS_{k}_OFFSET[i];
            d = best.distance;
            t = ATLAS_{k}_ADJ_START[i];
            end = ATLAS_{k}_ADJ_START[i + 1u];
            phase = 1u;
            continue;
        }}
        var j = 0u;
        var dmax = 0.0;
        var walk = false;
        if (phase == 0u) {{
            dmax = select({dmax}, best.distance, found);
            if (found && ATLAS_{k}_BOUND[t] >= dmax) {{
                t = end;
                continue;
            }}
            j = ATLAS_{k}_ITEMS[t];
            walk = length(x - ATLAS_{k}_P[j]) < dmax;
        }} else {{
            j = ATLAS_{k}_ADJ[t];
            let to_j = x - ATLAS_{k}_P[j];
            dmax = d + 2.0 * sigma;
            // Eq. 44: beyond the band even in Euclidean distance, p_j does not contribute.
            walk = d * d + 2.0 * sigma * ATLAS_{k}_ADJ_D[t] >= dot(to_j, to_j);
        }}
        if (walk) {{
            let m = atlas_{k}_walk(x, j, dmax);
            if (phase == 0u) {{
                if (m.status == 0.0) {{
                    if (!found || m.distance < best.distance) {{
                        best = m;
                        found = true;
                    }}
                }} else if (!found) {{
                    let e = length(x - ATLAS_{k}_P[j]);
                    if (e < fail_e) {{
                        best = m;
                        fail_e = e;
                    }}
                }}
            }} else if (m.status == 0.0) {{
                let w_ij = uv_blend_weight((d * d - m.distance * m.distance) / (2.0 * ATLAS_{k}_ADJ_D[t]), sigma);
                w_own = min(w_own, w_ij);
                let w_j = 1.0 - w_ij;
                sum = sum + w_j * (m.uv + ATLAS_{k}_OFFSET[j]);
                total = total + w_j;
            }}
        }}
        t = t + 1u;
    }}
    if (found) {{
        best.uv = (sum + w_own * own) / (total + w_own);
        best.weight = w_own / (total + w_own);
    }}
    return best;
}}

// Whether seeds i and j of atlas `{name}` are merged.
fn atlas_{name}_merged(i: u32, j: u32) -> bool {{
    for (var t = ATLAS_{k}_ADJ_START[i]; t < ATLAS_{k}_ADJ_START[i + 1u]; t = t + 1u) {{
        if (ATLAS_{k}_ADJ[t] == j) {{
            return true;
        }}
    }}
    return false;
}}
",
        name = atlas.name
    );
}

/// The atlas's constants: seeds (position, normal, e1, offset), the merge graph's
/// adjacency (CSR, with edge lengths) and the seed grid's lists.
fn emit_tables(out: &mut String, k: usize, atlas: &Atlas, grid: &SeedGrid) {
    let n = atlas.seeds.len();
    let arr = |name: &str, ty: &str, items: Vec<String>| {
        // WGSL has no empty arrays: pad with one unused element.
        let items = if items.is_empty() {
            vec![match ty {
                "u32" => "0u".to_string(),
                "f32" => "0.0".to_string(),
                _ => format!("{ty}()"),
            }]
        } else {
            items
        };
        format!(
            "var<private> {name}: array<{ty}, {}> = array<{ty}, {}>({});\n",
            items.len(),
            items.len(),
            items.join(", ")
        )
    };
    let seeds = &atlas.seeds;
    let mut text = String::new();
    text += &arr(
        &format!("ATLAS_{k}_P"),
        "vec3<f32>",
        seeds.iter().map(|s| vec3(s.seed.p)).collect(),
    );
    text += &arr(
        &format!("ATLAS_{k}_N"),
        "vec3<f32>",
        seeds.iter().map(|s| vec3(s.seed.n)).collect(),
    );
    text += &arr(
        &format!("ATLAS_{k}_E1"),
        "vec3<f32>",
        seeds.iter().map(|s| vec3(s.seed.e1)).collect(),
    );
    text += &arr(
        &format!("ATLAS_{k}_OFFSET"),
        "vec2<f32>",
        seeds
            .iter()
            .map(|s| format!("vec2<f32>({}, {})", lit(s.offset.x), lit(s.offset.y)))
            .collect(),
    );
    let mut adj_start = vec![0u32];
    let (mut adj, mut adj_d) = (Vec::new(), Vec::new());
    for i in 0..n {
        for &(j, d) in &atlas.graph.neighbors[i] {
            adj.push(format!("{j}u"));
            adj_d.push(lit(d));
        }
        adj_start.push(adj.len() as u32);
    }
    text += &arr(
        &format!("ATLAS_{k}_ADJ_START"),
        "u32",
        adj_start.iter().map(|v| format!("{v}u")).collect(),
    );
    text += &arr(&format!("ATLAS_{k}_ADJ"), "u32", adj);
    text += &arr(&format!("ATLAS_{k}_ADJ_D"), "f32", adj_d);
    text += &arr(
        &format!("ATLAS_{k}_START"),
        "u32",
        grid.start.iter().map(|v| format!("{v}u")).collect(),
    );
    text += &arr(
        &format!("ATLAS_{k}_ITEMS"),
        "u32",
        grid.items.iter().map(|v| format!("{v}u")).collect(),
    );
    text += &arr(
        &format!("ATLAS_{k}_BOUND"),
        "f32",
        grid.bound.iter().map(|&v| lit(v)).collect(),
    );
    let _ = writeln!(
        out,
        "// Seeds (projected, with solved frames and offsets), merge graph and seed grid ({} cells).\n{text}",
        grid.cells()
    );
}
