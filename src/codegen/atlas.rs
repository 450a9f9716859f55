//! Atlas code: per atlas, its field, gradient, one Alg. 1 step, the walk (unrolled
//! to exactly N steps with 1/(N − i) folded, or a rolled loop), and the search for
//! the geodesic-nearest seed with the seeds' projected positions and frames as
//! constants. The scene-independent pieces are in `shaders/uv.wgsl`.

use super::emit::{lit, vec3, Writer};
use crate::uv::Atlas;
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
pub fn emit(out: &mut String, k: usize, atlas: &Atlas, form: WalkForm) {
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
    let _ = writeln!(
        out,
        "// Alg. 1 around one seed: exactly N = {n} steps.
fn atlas_{k}_walk(x: vec3<f32>, p: vec3<f32>, np: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, dmax: f32, seed: f32) -> AtlasSample {{
    let d0 = length(x - p);
    if (d0 > dmax) {{
        return uv_failed(UV_TOO_FAR, seed);
    }}
    if (d0 < {rmin}) {{
        let t0 = (x - p) - np * dot(np, x - p);
        let t0l = max(length(t0), 1e-30);
        return AtlasSample(vec2<f32>(dot(t0, e1), dot(t0, e2)) / t0l * d0, d0, 0.0, vec4<f32>(0.0, 0.0, 0.0, 1.0), seed);
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
    return AtlasSample(vec2<f32>(dot(t, e1), dot(t, e2)) / tl * r, r, 0.0, uv_quaternion(rot), seed);
}}
"
    );
    // The nearest seed: a seed farther (Euclidean) than the best geodesic distance so far
    // cannot win (Eq. 35); the best so far is the next walk's D.
    let _ = writeln!(out, "fn atlas_{}(x: vec3<f32>) -> AtlasSample {{\n    var best = uv_failed(UV_TOO_FAR, -1.0);\n    var found = false;\n    var fail_e = 3.0e38;", atlas.name);
    for (j, s) in atlas.seeds.iter().enumerate() {
        let s = &s.seed;
        let _ = writeln!(
            out,
            "    {{
        let bound = select({dmax}, best.distance, found);
        let e = length(x - {p});
        if (e < bound) {{
            let m = atlas_{k}_walk(x, {p}, {n}, {e1}, {e2}, bound, {j}.0);
            if (m.status == 0.0) {{
                if (!found || m.distance < best.distance) {{
                    best = m;
                    found = true;
                }}
            }} else if (!found && e < fail_e) {{
                best = m;
                fail_e = e;
            }}
        }}
    }}",
            dmax = lit(p.max_distance),
            p = vec3(s.p),
            n = vec3(s.n),
            e1 = vec3(s.e1),
            e2 = vec3(s.e2),
        );
    }
    let _ = writeln!(out, "    return best;\n}}\n");
}
