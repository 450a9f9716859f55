// Forward-mode derivatives of sdfc's distance functions: a distance with its gradient,
// `vec4<f32>(∇f, f)`, in the frame of the point given (Implicit UVs' walk reads the
// gradient at every step; src/codegen/dual.rs writes the chain rule through a scene's
// operations and warps, src/ir/dual.rs says which scenes it covers).
//
// `dsd_K` is the gradient of `sd_K` of sdf.wgsl, by hand: exact wherever `sd_K` is
// differentiable, and one of the one-sided gradients on its creases. The kinds without
// one here (box frame, capped cone, octahedron, hexagonal prism, pyramid) are
// differentiated by central differences of the primitive alone (src/codegen/dual.rs).
// This file validates on its own with naga.

// The sign of x, 1 at 0 (a gradient never vanishes on a mirror plane).
fn dual_sign(x: f32) -> f32 {
    return select(1.0, -1.0, x < 0.0);
}

fn dual_sign3(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dual_sign(v.x), dual_sign(v.y), dual_sign(v.z));
}

// A unit vector along v, or `fallback` where v vanishes.
fn dual_unit(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    return select(fallback, v / l, l > 0.0);
}

fn dsd_sphere(p: vec3<f32>, r: f32) -> vec4<f32> {
    return vec4<f32>(dual_unit(p, vec3<f32>(0.0, 1.0, 0.0)), length(p) - r);
}

// A box of half size `half`: outside, along the point's offset from the nearest point;
// inside, the normal of the nearest face. Branch-free, as every function here: a SIMD
// CPU (Mesa's lavapipe) runs both sides of a branch.
fn dsd_box_core(p: vec3<f32>, half: vec3<f32>) -> vec4<f32> {
    let s = dual_sign3(p);
    let q = abs(p) - half;
    let outside = max(q, vec3<f32>(0.0));
    let l = length(outside);
    let inner = max(q.x, max(q.y, q.z));
    let axis = select(select(vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, 1.0, 0.0), q.y >= q.z), vec3<f32>(1.0, 0.0, 0.0), q.x >= q.y && q.x >= q.z);
    let g = select(axis, outside / max(l, 1e-30), l > 0.0);
    return vec4<f32>(g * s, l + min(inner, 0.0));
}

fn dsd_box(p: vec3<f32>, half: vec3<f32>) -> vec4<f32> {
    return dsd_box_core(p, half);
}

fn dsd_round_box(p: vec3<f32>, half: vec3<f32>, r: f32) -> vec4<f32> {
    return dsd_box_core(p, half) - vec4<f32>(0.0, 0.0, 0.0, r);
}

fn dsd_torus(p: vec3<f32>, major: f32, minor: f32) -> vec4<f32> {
    let l = length(p.xz);
    let radial = select(vec2<f32>(1.0, 0.0), p.xz / l, l > 0.0);
    let v = vec2<f32>(l - major, p.y);
    let lv = length(v);
    let dv = select(vec2<f32>(0.0, 1.0), v / lv, lv > 0.0);
    return vec4<f32>(dv.x * radial.x, dv.y, dv.x * radial.y, lv - minor);
}

fn dsd_capsule(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, r: f32) -> vec4<f32> {
    let pa = p - a;
    let ba = b - a;
    let bb = dot(ba, ba);
    let h = select(0.0, clamp(dot(pa, ba) / max(bb, 1e-30), 0.0, 1.0), bb > 0.0);
    let w = pa - ba * h;
    return vec4<f32>(dual_unit(w, vec3<f32>(0.0, 1.0, 0.0)), length(w) - r);
}

// The gradient of min(max(d.x, d.y), 0) + length(max(d, 0)) with respect to d.
fn dual_rect(d: vec2<f32>) -> vec3<f32> {
    let outside = max(d, vec2<f32>(0.0));
    let l = length(outside);
    let inner = select(vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), d.x >= d.y);
    let g = select(inner, outside / max(l, 1e-30), l > 0.0);
    return vec3<f32>(g, l + min(max(d.x, d.y), 0.0));
}

fn dsd_cylinder(p: vec3<f32>, r: f32, half_h: f32) -> vec4<f32> {
    let l = length(p.xz);
    let radial = select(vec2<f32>(1.0, 0.0), p.xz / l, l > 0.0);
    let g = dual_rect(vec2<f32>(l - r, abs(p.y) - half_h));
    return vec4<f32>(g.x * radial.x, g.y * dual_sign(p.y), g.x * radial.y, g.z);
}

fn dsd_plane(p: vec3<f32>, n: vec3<f32>, offset: f32) -> vec4<f32> {
    return vec4<f32>(n, dot(p, n) - offset);
}

// f = k0 (k0 − 1) / k1 with k0 = |p / r|, k1 = |p / r²|.
fn dsd_ellipsoid(p: vec3<f32>, radii: vec3<f32>) -> vec4<f32> {
    let r2 = radii * radii;
    let k0 = length(p / radii);
    let k1 = length(p / r2);
    let centre = vec4<f32>(0.0, 1.0, 0.0, -min(radii.x, min(radii.y, radii.z)));
    let k0s = max(k0, 1e-30);
    let k1s = max(k1, 1e-30);
    let dk0 = p / r2 / k0s;
    let dk1 = p / (r2 * r2) / k1s;
    let f = k0 * (k0 - 1.0) / k1s;
    return select(centre, vec4<f32>(((2.0 * k0 - 1.0) * dk0 - f * dk1) / k1s, f), k1 != 0.0);
}

fn dsd_tri_prism(p: vec3<f32>, r: f32, half_h: f32) -> vec4<f32> {
    let q = abs(p);
    let cap = vec4<f32>(0.0, 0.0, dual_sign(p.z), q.z - half_h);
    let slanted = vec4<f32>(0.8660254 * dual_sign(p.x), 0.5, 0.0, q.x * 0.8660254 + p.y * 0.5 - r * 0.5);
    let base = vec4<f32>(0.0, -1.0, 0.0, -p.y - r * 0.5);
    let side = select(base, slanted, slanted.w >= base.w);
    return select(cap, side, side.w >= cap.w);
}

fn dsd_link(p: vec3<f32>, le: f32, r1: f32, r2: f32) -> vec4<f32> {
    let over = abs(p.y) - le;
    let q = vec3<f32>(p.x, max(over, 0.0), p.z);
    let u = length(q.xy);
    let du = select(vec2<f32>(1.0, 0.0), q.xy / u, u > 0.0);
    let v = vec2<f32>(u - r1, q.z);
    let lv = length(v);
    let dv = select(vec2<f32>(1.0, 0.0), v / lv, lv > 0.0);
    let dy = select(0.0, dual_sign(p.y), over > 0.0);
    return vec4<f32>(dv.x * du.x, dv.x * du.y * dy, dv.y, lv - r2);
}

// The quadratic polynomial smooth minimum of op_smin on (∇, f) pairs: its gradient is
// the blend h/2 of the operands' (exact: the terms in ∇h cancel).
fn dual_smin(a: vec4<f32>, b: vec4<f32>, k: f32) -> vec4<f32> {
    let m = select(b, a, a.w <= b.w);
    let other = select(a, b, a.w <= b.w);
    // h = 0 for the hard minimum (k = 0): m itself.
    let h = select(0.0, max(k - abs(a.w - b.w), 0.0) / max(k, 1e-30), k > 0.0);
    let g = m.xyz + (other.xyz - m.xyz) * (0.5 * h);
    return vec4<f32>(g, m.w - h * h * k * 0.25);
}

fn dual_union(a: vec4<f32>, b: vec4<f32>, k: f32) -> vec4<f32> {
    return dual_smin(a, b, k);
}

fn dual_intersection(a: vec4<f32>, b: vec4<f32>, k: f32) -> vec4<f32> {
    return -dual_smin(-a, -b, k);
}

fn dual_difference(a: vec4<f32>, b: vec4<f32>, k: f32) -> vec4<f32> {
    return -dual_smin(-a, b, k);
}

// Pull-backs of warps: the gradient at the warp's input point u from the gradient g at
// its output, Jᵀ g.
fn dual_twist(u: vec3<f32>, rate: f32, g: vec3<f32>) -> vec3<f32> {
    let c = cos(rate * u.y);
    let s = sin(rate * u.y);
    let t0 = c * u.x - s * u.z;
    let t2 = s * u.x + c * u.z;
    return vec3<f32>(c * g.x + s * g.z, -rate * t2 * g.x + g.y + rate * t0 * g.z, -s * g.x + c * g.z);
}

fn dual_bend(u: vec3<f32>, rate: f32, g: vec3<f32>) -> vec3<f32> {
    let c = cos(rate * u.x);
    let s = sin(rate * u.x);
    let t0 = c * u.x - s * u.y;
    let t1 = s * u.x + c * u.y;
    return vec3<f32>((c - rate * t1) * g.x + (s + rate * t0) * g.y, -s * g.x + c * g.y, g.z);
}

fn dual_mirror(p: vec3<f32>, n: vec3<f32>, g: vec3<f32>) -> vec3<f32> {
    return select(g, g - 2.0 * dot(g, n) * n, dot(p, n) < 0.0);
}

fn dual_elongate(p: vec3<f32>, h: vec3<f32>, g: vec3<f32>) -> vec3<f32> {
    return g * select(vec3<f32>(0.0), vec3<f32>(1.0), abs(p) > h);
}

// A shell |f| − t: the gradient flips inside.
fn dual_shell(d: vec4<f32>, half: f32) -> vec4<f32> {
    return vec4<f32>(d.xyz * dual_sign(d.w), abs(d.w) - half);
}
