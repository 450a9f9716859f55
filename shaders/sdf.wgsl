// sdfc's WGSL library of signed distance functions.
//
// Every function here mirrors one in src/ir/eval.rs (the f64 CPU reference);
// the generated module includes this file and calls these functions with the
// scene's constants folded in. Distances are in world units; `p` is the point
// in the primitive's local frame. This file validates on its own with naga.

// The SDF evaluations this invocation has made: the render target's (scene_map) and
// the atlases' fields (atlas_K_f), for the evals view.
var<private> sdf_evals: u32 = 0u;

fn sd_box_core(p: vec3<f32>, half: vec3<f32>) -> f32 {
    let q = abs(p) - half;
    return length(max(q, vec3<f32>(0.0))) + min(max(q.x, max(q.y, q.z)), 0.0);
}

fn sd_sphere(p: vec3<f32>, r: f32) -> f32 {
    return length(p) - r;
}

fn sd_box(p: vec3<f32>, half: vec3<f32>) -> f32 {
    return sd_box_core(p, half);
}

fn sd_round_box(p: vec3<f32>, half: vec3<f32>, r: f32) -> f32 {
    return sd_box_core(p, half) - r;
}

fn sd_box_frame_part(v: vec3<f32>) -> f32 {
    return length(max(v, vec3<f32>(0.0))) + min(max(v.x, max(v.y, v.z)), 0.0);
}

fn sd_box_frame(p0: vec3<f32>, half: vec3<f32>, e: f32) -> f32 {
    let p = abs(p0) - half;
    let q = abs(p + vec3<f32>(e)) - vec3<f32>(e);
    return min(min(sd_box_frame_part(vec3<f32>(p.x, q.y, q.z)), sd_box_frame_part(vec3<f32>(q.x, p.y, q.z))), sd_box_frame_part(vec3<f32>(q.x, q.y, p.z)));
}

fn sd_torus(p: vec3<f32>, major: f32, minor: f32) -> f32 {
    return length(vec2<f32>(length(p.xz) - major, p.y)) - minor;
}

fn sd_capsule(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, r: f32) -> f32 {
    let pa = p - a;
    let ba = b - a;
    let bb = dot(ba, ba);
    var h = 0.0;
    if (bb > 0.0) {
        h = clamp(dot(pa, ba) / bb, 0.0, 1.0);
    }
    return length(pa - ba * h) - r;
}

fn sd_cylinder(p: vec3<f32>, r: f32, half_h: f32) -> f32 {
    let d = abs(vec2<f32>(length(p.xz), p.y)) - vec2<f32>(r, half_h);
    return min(max(d.x, d.y), 0.0) + length(max(d, vec2<f32>(0.0)));
}

fn sd_capped_cone(p: vec3<f32>, h: f32, r1: f32, r2: f32) -> f32 {
    let q = vec2<f32>(length(p.xz), p.y);
    let k1 = vec2<f32>(r2, h);
    let k2 = vec2<f32>(r2 - r1, 2.0 * h);
    let ca = vec2<f32>(q.x - min(q.x, select(r2, r1, q.y < 0.0)), abs(q.y) - h);
    let cb = q - k1 + k2 * clamp(dot(k1 - q, k2) / dot(k2, k2), 0.0, 1.0);
    let s = select(1.0, -1.0, cb.x < 0.0 && ca.y < 0.0);
    return s * sqrt(min(dot(ca, ca), dot(cb, cb)));
}

fn sd_plane(p: vec3<f32>, n: vec3<f32>, offset: f32) -> f32 {
    return dot(p, n) - offset;
}

fn sd_ellipsoid(p: vec3<f32>, radii: vec3<f32>) -> f32 {
    let k0 = length(p / radii);
    let k1 = length(p / (radii * radii));
    if (k1 == 0.0) {
        return -min(radii.x, min(radii.y, radii.z));
    }
    return k0 * (k0 - 1.0) / k1;
}

fn sd_octahedron(p0: vec3<f32>, s: f32) -> f32 {
    let p = abs(p0);
    let m = p.x + p.y + p.z - s;
    var q: vec3<f32>;
    if (3.0 * p.x < m) {
        q = p;
    } else if (3.0 * p.y < m) {
        q = p.yzx;
    } else if (3.0 * p.z < m) {
        q = p.zxy;
    } else {
        return m * 0.57735026;
    }
    let k = clamp(0.5 * (q.z - q.y + s), 0.0, s);
    return length(vec3<f32>(q.x, q.y - s + k, q.z - k));
}

fn sd_hex_prism(p0: vec3<f32>, r: f32, half_h: f32) -> f32 {
    let k = vec3<f32>(-0.8660254, 0.5, 0.57735026);
    let pa = abs(p0);
    let pxy = pa.xy - 2.0 * min(dot(k.xy, pa.xy), 0.0) * k.xy;
    let d = vec2<f32>(length(pxy - vec2<f32>(clamp(pxy.x, -k.z * r, k.z * r), r)) * sign(pxy.y - r), pa.z - half_h);
    return min(max(d.x, d.y), 0.0) + length(max(d, vec2<f32>(0.0)));
}

fn sd_tri_prism(p: vec3<f32>, r: f32, half_h: f32) -> f32 {
    let q = abs(p);
    return max(q.z - half_h, max(q.x * 0.8660254 + p.y * 0.5, -p.y) - r * 0.5);
}

fn sd_pyramid(p0: vec3<f32>, h: f32) -> f32 {
    // Below the base the nearest point is on the base square.
    if (p0.y < 0.0) {
        return length(vec3<f32>(max(abs(p0.x) - 0.5, 0.0), p0.y, max(abs(p0.z) - 0.5, 0.0)));
    }
    let m2 = h * h + 0.25;
    var xz = abs(p0.xz);
    if (xz.y > xz.x) {
        xz = xz.yx;
    }
    xz = xz - vec2<f32>(0.5);
    let px = xz.x;
    let pz = xz.y;
    let py = p0.y;
    let q = vec3<f32>(pz, h * py - 0.5 * px, h * px + 0.5 * py);
    let s = max(-q.x, 0.0);
    let t = clamp((q.y - 0.5 * pz) / (m2 + 0.25), 0.0, 1.0);
    let a = m2 * (q.x + s) * (q.x + s) + q.y * q.y;
    let b = m2 * (q.x + 0.5 * t) * (q.x + 0.5 * t) + (q.y - m2 * t) * (q.y - m2 * t);
    let d2 = select(min(a, b), 0.0, min(q.y, -q.x * m2 - q.y * 0.5) > 0.0);
    return sqrt((d2 + q.z * q.z) / m2) * sign(max(q.z, -py));
}

fn sd_link(p: vec3<f32>, le: f32, r1: f32, r2: f32) -> f32 {
    let q = vec3<f32>(p.x, max(abs(p.y) - le, 0.0), p.z);
    return length(vec2<f32>(length(q.xy) - r1, q.z)) - r2;
}

// Quadratic polynomial smooth minimum; k = 0 is the hard minimum.
fn op_smin(a: f32, b: f32, k: f32) -> f32 {
    if (k <= 0.0) {
        return min(a, b);
    }
    let h = max(k - abs(a - b), 0.0) / k;
    return min(a, b) - h * h * k * 0.25;
}

// CSG on (distance, material) pairs: the material of the nearer operand is kept.
fn op_union(a: vec2<f32>, b: vec2<f32>, k: f32) -> vec2<f32> {
    return vec2<f32>(op_smin(a.x, b.x, k), select(b.y, a.y, a.x <= b.x));
}

fn op_intersection(a: vec2<f32>, b: vec2<f32>, k: f32) -> vec2<f32> {
    return vec2<f32>(-op_smin(-a.x, -b.x, k), select(b.y, a.y, a.x >= b.x));
}

fn op_difference(a: vec2<f32>, b: vec2<f32>, k: f32) -> vec2<f32> {
    return vec2<f32>(-op_smin(-a.x, b.x, k), select(b.y, a.y, a.x >= -b.x));
}

// Material blends (`scene_blend`): (distance, material a, material b, b's weight).
// The material that dominates a blend: a up to half b's weight.
fn op_dominant(m: vec4<f32>) -> f32 {
    return select(m.z, m.y, m.w <= 0.5);
}

// A smooth union blends its operands' (dominant) materials with the distance blend's
// own weight: b's is clamp(0.5 - 0.5 (b - a) / k, 0, 1), as in the polynomial smin.
fn op_union_blend(a: vec4<f32>, b: vec4<f32>, k: f32) -> vec4<f32> {
    if (k <= 0.0) {
        return vec4<f32>(min(a.x, b.x), select(b.yzw, a.yzw, a.x <= b.x));
    }
    let ma = op_dominant(a);
    let mb = op_dominant(b);
    let t = clamp(0.5 - 0.5 * (b.x - a.x) / k, 0.0, 1.0);
    if (ma == mb || t <= 0.0) {
        return vec4<f32>(op_smin(a.x, b.x, k), ma, ma, 0.0);
    }
    if (t >= 1.0) {
        return vec4<f32>(op_smin(a.x, b.x, k), mb, mb, 0.0);
    }
    return vec4<f32>(op_smin(a.x, b.x, k), ma, mb, t);
}

// A hard union, intersections and differences keep the materials of the operand that
// bounds the result, blends included.
fn op_intersection_blend(a: vec4<f32>, b: vec4<f32>, k: f32) -> vec4<f32> {
    return vec4<f32>(-op_smin(-a.x, -b.x, k), select(b.yzw, a.yzw, a.x >= b.x));
}

fn op_difference_blend(a: vec4<f32>, b: vec4<f32>, k: f32) -> vec4<f32> {
    return vec4<f32>(-op_smin(-a.x, b.x, k), select(b.yzw, a.yzw, a.x >= -b.x));
}

// Warps, in a frame whose y (twist) or x (bend) is the axis.
fn op_twist(q: vec3<f32>, rate: f32) -> vec3<f32> {
    let c = cos(rate * q.y);
    let s = sin(rate * q.y);
    return vec3<f32>(c * q.x - s * q.z, q.y, s * q.x + c * q.z);
}

fn op_bend(q: vec3<f32>, rate: f32) -> vec3<f32> {
    let c = cos(rate * q.x);
    let s = sin(rate * q.x);
    return vec3<f32>(c * q.x - s * q.y, s * q.x + c * q.y, q.z);
}

fn op_repeat(p: vec3<f32>, period: vec3<f32>) -> vec3<f32> {
    return p - period * round(p / period);
}

fn op_mirror(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return p - 2.0 * min(dot(p, n), 0.0) * n;
}

fn op_elongate(p: vec3<f32>, h: vec3<f32>) -> vec3<f32> {
    return p - clamp(p, -h, h);
}

// The rotation by `angle` radians about the unit `axis` (Rodrigues' formula; the
// lowering's `DMat3::from_axis_angle`): run-time rotations multiply the point by it
// from the left of the row vector, `p * R`, which is the inverse rotation.
fn sdfc_axis_angle(axis: vec3<f32>, angle: f32) -> mat3x3<f32> {
    let s = sin(angle);
    let c = cos(angle);
    let t = 1.0 - c;
    let a = axis;
    return mat3x3<f32>(
        vec3<f32>(t * a.x * a.x + c, t * a.x * a.y + s * a.z, t * a.x * a.z - s * a.y),
        vec3<f32>(t * a.x * a.y - s * a.z, t * a.y * a.y + c, t * a.y * a.z + s * a.x),
        vec3<f32>(t * a.x * a.z + s * a.y, t * a.y * a.z - s * a.x, t * a.z * a.z + c),
    );
}

// The smallest component: a run-time scale's distance factor.
fn sdfc_min3(v: vec3<f32>) -> f32 {
    return min(v.x, min(v.y, v.z));
}
