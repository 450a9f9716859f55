// sdfc's WGSL library for Implicit UVs (Alg. 1 of the paper, with its erratum).
//
// These are the scene-independent pieces of the geodesic walk; the generator
// emits, per atlas, a step function that evaluates the atlas's field and calls
// these, and a walk that calls the step exactly N times with N - i folded.
// Each function mirrors one in src/uv/logmap.rs. Validates on its own with naga.

// Status codes, as ATLAS.status gives them.
const UV_OK: u32 = 0u;
const UV_TOO_FAR: u32 = 1u;
const UV_HEURISTIC_FAILED: u32 = 2u;
const UV_SHARP_FEATURE: u32 = 3u;
const UV_NOT_REACHED: u32 = 4u;

// One walk's state between steps.
struct WalkState {
    x: vec3<f32>,
    prev: vec3<f32>,
    // Gradient of f at x.
    g: vec3<f32>,
    // Arc length so far.
    r: f32,
    // Accumulated parallel transport.
    rot: mat3x3<f32>,
    status: u32,
    // The last step's turn of the normal, the normal's rate of turn before it and its
    // tau, for the sharp test once the rate after it is known (0: no step yet).
    turn: f32,
    before: f32,
    tau: f32,
    // The normal's rate of turn over the last step (|kappa| of Eq. 17 before the first).
    rate: f32,
    // kappa for the next step: Eq. 17 before the first, then uv_turn_curvature.
    kappa: f32,
    // The last step's direction and chord.
    vh: vec3<f32>,
    s: f32,
    // f at the walk's start: each step ends back on this level set.
    level: f32,
}

// Where a geodesic shot from a seed lands (the refinement, uv/refine.rs).
struct Shot {
    end: vec3<f32>,
    normal: vec3<f32>,
    // Parallel transport along the shot.
    rot: mat3x3<f32>,
}

// A refined walk: the log map as a tangent at the seed, and the transport.
struct Refined {
    t: vec3<f32>,
    rot: mat3x3<f32>,
}

// What an atlas gives a material at a point.
struct AtlasSample {
    uv: vec2<f32>,
    distance: f32,
    status: f32,
    // Parallel transport from the seed as a unit quaternion (x, y, z, w).
    transport: vec4<f32>,
    seed: f32,
    // The nearest seed's normalized blend weight: 1 away from merged frontiers.
    weight: f32,
    // The seeds' frames (e1, e2) carried to the point by the walks' parallel transport
    // (Eq. 52), blended with the uv's weights; zero where the sample failed.
    tangent: vec3<f32>,
    bitangent: vec3<f32>,
}

// Notes, item 2: the step whose parabolic chord is s; stable as alpha -> 0.
fn uv_time_step(s: f32, alpha: f32) -> f32 {
    return s * sqrt(2.0 / (1.0 + sqrt(1.0 + s * s * alpha * alpha)));
}

// The chord of the next step: the remaining arc split evenly, on the osculating
// circle of curvature kappa (uv/logmap.rs: step_chord).
fn uv_step_chord(chord: f32, kappa: f32, remaining: f32) -> f32 {
    let a = min(0.5 * abs(kappa) * chord, 1.0);
    if (a < 1e-4) {
        return chord / remaining;
    }
    return chord / remaining * max(remaining * sin(asin(a) / remaining) / a, 1.0);
}

// The smooth model's allowance for the normal's turn, as a multiple of kappa * tau
// (uv/logmap.rs: TURN_SLACK).
const UV_TURN_SLACK: f32 = 1.5;

// The normal curvature along vh over a step of arc length `arc` that ends at unit normal
// n_next (uv/logmap.rs: turn_curvature).
fn uv_turn_curvature(n_next: vec3<f32>, vh: vec3<f32>, arc: f32) -> f32 {
    if (arc <= 0.0) {
        return 0.0;
    }
    return -asin(clamp(dot(n_next, vh), -1.0, 1.0)) / arc;
}

// Whether a step's normal turned more than the normal's rate of turn on either side of
// it explains (uv/logmap.rs: sharp_turn); theta0 = acos(1 - sharp_tolerance).
fn uv_sharp_turn(turn: f32, kappa: f32, tau: f32, theta0: f32) -> bool {
    return turn > min(theta0 + UV_TURN_SLACK * kappa * tau, 3.0 * theta0);
}

// Notes, item 1: Simpson's rule (1-4-1) for the length of one parabolic step.
fn uv_arc_length(tau: f32, kappa: f32) -> f32 {
    let k2 = kappa * kappa * tau * tau;
    return tau / 6.0 * (1.0 + 4.0 * sqrt(1.0 + k2 * 0.25) + sqrt(1.0 + k2));
}

// Eq. 31: the smallest rotation taking unit a to unit b.
fn uv_rotation_between(a: vec3<f32>, b: vec3<f32>) -> mat3x3<f32> {
    let c = dot(a, b);
    let k = cross(a, b);
    let j = mat3x3<f32>(vec3<f32>(0.0, k.z, -k.y), vec3<f32>(-k.z, 0.0, k.x), vec3<f32>(k.y, -k.x, 0.0));
    // Opposite vectors: the identity. (No early return: naga's pipeline-constant pass
    // rejects a constant matrix used on both sides of one, ExpressionAlreadyInScope.)
    let opposite = c <= -0.999999;
    let s = select(1.0 / (1.0 + c), 0.0, opposite);
    let identity = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
    return identity + j * select(1.0, 0.0, opposite) + (j * j) * s;
}

// A rotation matrix as a unit quaternion (x, y, z, w).
fn uv_quaternion(m: mat3x3<f32>) -> vec4<f32> {
    let t = m[0].x + m[1].y + m[2].z;
    var q: vec4<f32>;
    if (t > 0.0) {
        let s = sqrt(t + 1.0) * 2.0;
        q = vec4<f32>((m[1].z - m[2].y) / s, (m[2].x - m[0].z) / s, (m[0].y - m[1].x) / s, 0.25 * s);
    } else if (m[0].x > m[1].y && m[0].x > m[2].z) {
        let s = sqrt(1.0 + m[0].x - m[1].y - m[2].z) * 2.0;
        q = vec4<f32>(0.25 * s, (m[1].x + m[0].y) / s, (m[2].x + m[0].z) / s, (m[1].z - m[2].y) / s);
    } else if (m[1].y > m[2].z) {
        let s = sqrt(1.0 + m[1].y - m[0].x - m[2].z) * 2.0;
        q = vec4<f32>((m[1].x + m[0].y) / s, 0.25 * s, (m[2].y + m[1].z) / s, (m[2].x - m[0].z) / s);
    } else {
        let s = sqrt(1.0 + m[2].z - m[0].x - m[1].y) * 2.0;
        q = vec4<f32>((m[2].x + m[0].z) / s, (m[2].y + m[1].z) / s, 0.25 * s, (m[0].y - m[1].x) / s);
    }
    return normalize(q);
}

// A failed sample with its status.
fn uv_failed(status: u32, seed: f32) -> AtlasSample {
    return AtlasSample(vec2<f32>(0.0), 3.0e38, f32(status), vec4<f32>(0.0, 0.0, 0.0, 1.0), seed, 0.0, vec3<f32>(0.0), vec3<f32>(0.0));
}

// Eq. 40 with omega(t) = 3t^2 - 2t^3, of the approximate distance to the frontier (Eq. 39):
// 1 deep on the nearest seed's side, 0 beyond the band on the neighbour's.
fn uv_blend_weight(frontier: f32, sigma: f32) -> f32 {
    if (frontier < -sigma) {
        return 1.0;
    }
    if (frontier > sigma) {
        return 0.0;
    }
    let t = 0.5 - frontier / (2.0 * sigma);
    return t * t * (3.0 - 2.0 * t);
}

// The seed grid's list for a point: its cell, or the last list (every seed) outside.
fn uv_grid_list(x: vec3<f32>, grid_min: vec3<f32>, inv_cell: vec3<f32>, dims: vec3<u32>) -> u32 {
    let rel = (x - grid_min) * inv_cell;
    let fd = vec3<f32>(dims);
    if (any(rel < vec3<f32>(0.0)) || any(rel > fd)) {
        return dims.x * dims.y * dims.z;
    }
    let c = min(vec3<u32>(floor(rel)), dims - vec3<u32>(1u));
    return c.x + dims.x * (c.y + dims.y * c.z);
}

// A distinct colour per seed index, for the seed views.
fn uv_seed_color(seed: f32) -> vec3<f32> {
    let h = fract(seed * 0.618034 + 0.13);
    let k = vec3<f32>(0.0, 2.0 / 3.0, 1.0 / 3.0);
    return clamp(abs(fract(vec3<f32>(h) + k) * 6.0 - 3.0) - 1.0, vec3<f32>(0.0), vec3<f32>(1.0)) * 0.7 + 0.2;
}

// Black to red to yellow, for heat maps in [0, 1].
fn uv_heat(x: f32) -> vec3<f32> {
    let t = clamp(x, 0.0, 1.0);
    return vec3<f32>(min(2.0 * t, 1.0), max(2.0 * t - 1.0, 0.0) * 0.8, 0.0);
}

// Debug colours of the statuses: ok, too_far, heuristic_failed, sharp_feature, not_reached.
fn uv_status_color(status: u32) -> vec3<f32> {
    switch status {
        case 0u: {
            return vec3<f32>(0.3, 0.8, 0.35);
        }
        case 1u: {
            return vec3<f32>(0.25, 0.35, 0.9);
        }
        case 2u: {
            return vec3<f32>(0.95, 0.85, 0.2);
        }
        case 3u: {
            return vec3<f32>(0.9, 0.2, 0.2);
        }
        default: {
            return vec3<f32>(0.8, 0.3, 0.85);
        }
    }
}
