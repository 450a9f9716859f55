// sdfc's WGSL library for Implicit UVs (Alg. 1 of the paper, with its erratum).
//
// These are the scene-independent pieces of the geodesic walk; the generator
// emits, per atlas, a step function that evaluates the atlas's field and calls
// these, and a walk that calls the step exactly N times with 1/(N - i) folded.
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
}

// What an atlas gives a material at a point.
struct AtlasSample {
    uv: vec2<f32>,
    distance: f32,
    status: f32,
    // Parallel transport from the seed as a unit quaternion (x, y, z, w).
    transport: vec4<f32>,
    seed: f32,
}

// Notes, item 2: the step whose parabolic chord is s; stable as alpha -> 0.
fn uv_time_step(s: f32, alpha: f32) -> f32 {
    return s * sqrt(2.0 / (1.0 + sqrt(1.0 + s * s * alpha * alpha)));
}

// Notes, item 1: Simpson's rule (1-4-1) for the length of one parabolic step.
fn uv_arc_length(tau: f32, kappa: f32) -> f32 {
    let k2 = kappa * kappa * tau * tau;
    return tau / 6.0 * (1.0 + 4.0 * sqrt(1.0 + k2 * 0.25) + sqrt(1.0 + k2));
}

// Eq. 31: the smallest rotation taking unit a to unit b.
fn uv_rotation_between(a: vec3<f32>, b: vec3<f32>) -> mat3x3<f32> {
    let c = dot(a, b);
    let identity = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
    if (c <= -0.999999) {
        return identity;
    }
    let k = cross(a, b);
    let j = mat3x3<f32>(vec3<f32>(0.0, k.z, -k.y), vec3<f32>(-k.z, 0.0, k.x), vec3<f32>(k.y, -k.x, 0.0));
    let j2 = j * j;
    let s = 1.0 / (1.0 + c);
    return mat3x3<f32>(identity[0] + j[0] + j2[0] * s, identity[1] + j[1] + j2[1] * s, identity[2] + j[2] + j2[2] * s);
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
    return AtlasSample(vec2<f32>(0.0), 3.0e38, f32(status), vec4<f32>(0.0, 0.0, 0.0, 1.0), seed);
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
