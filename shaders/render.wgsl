// sdfc's WGSL library for rendering: the uniform block, camera rays, shading
// and procedural patterns. The generated module includes this file after
// sdf.wgsl. This file validates on its own with naga.

// Bind group 0, binding 0 of every generated render module.
struct Globals {
    // xyz: camera position; w: tan(vertical fov / 2).
    camera_pos: vec4<f32>,
    // xyz: unit forward, right and up vectors of the camera.
    camera_forward: vec4<f32>,
    camera_right: vec4<f32>,
    camera_up: vec4<f32>,
    // xyz: unit direction towards the sun; w: intensity.
    light_dir: vec4<f32>,
    // rgb: sun colour (linear); w: ambient strength.
    light_color: vec4<f32>,
    // rgb: background (linear); w: unused.
    background: vec4<f32>,
    // x, y: image size in pixels; z: time in seconds; w: the view (ViewMode::index in src/gpu/render.rs).
    // The mesh renderer (shaders/mesh.wgsl.in) uses the same block.
    resolution: vec4<f32>,
    // x: far distance; y: hit epsilon; z: maximum steps; w: scene scale.
    trace: vec4<f32>,
}

// The world-space direction of the ray through a pixel centre (pixel y grows downwards).
fn camera_ray(g: Globals, pixel: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(2.0 * pixel.x / g.resolution.x - 1.0, 1.0 - 2.0 * pixel.y / g.resolution.y);
    let aspect = g.resolution.x / g.resolution.y;
    let t = g.camera_pos.w;
    return normalize(g.camera_forward.xyz + ndc.x * aspect * t * g.camera_right.xyz + ndc.y * t * g.camera_up.xyz);
}

// A simple physically plausible model: Lambert diffuse plus a normalized
// Blinn-Phong lobe with Schlick Fresnel, one sun and an ambient term.
fn shade(g: Globals, albedo: vec3<f32>, roughness: f32, metallic: f32, emission: vec3<f32>, n: vec3<f32>, v: vec3<f32>, shadow: f32) -> vec3<f32> {
    let l = normalize(g.light_dir.xyz);
    let h = normalize(l + v);
    let ndl = max(dot(n, l), 0.0);
    let ndh = max(dot(n, h), 0.0);
    let r = clamp(roughness, 0.03, 1.0);
    let shininess = 2.0 / (r * r * r * r) - 2.0;
    let f0 = mix(vec3<f32>(0.04), albedo, clamp(metallic, 0.0, 1.0));
    let fresnel = f0 + (vec3<f32>(1.0) - f0) * pow(1.0 - max(dot(h, v), 0.0), 5.0);
    let spec = fresnel * (shininess + 8.0) / 25.132742 * pow(ndh, shininess);
    let diffuse = albedo * (1.0 - clamp(metallic, 0.0, 1.0)) / 3.1415927;
    let sun = g.light_color.rgb * g.light_dir.w * ndl * shadow;
    let ambient = g.light_color.w * albedo * (0.5 + 0.5 * n.y);
    return (diffuse + spec) * sun + ambient + emission;
}

// Filmic-ish tone curve on linear radiance (the target stores sRGB).
fn tonemap(c: vec3<f32>) -> vec3<f32> {
    return c / (vec3<f32>(1.0) + c * 0.15);
}

// A checkerboard of n squares per unit of uv: 0 or 1.
fn sdfc_checker(uv: vec2<f32>, n: f32) -> f32 {
    let c = floor(uv * n);
    return abs(c.x + c.y) % 2.0;
}

// Grid lines, n per unit of uv, of relative width: 1 on a line, 0 elsewhere.
fn sdfc_grid(uv: vec2<f32>, n: f32, width: f32) -> f32 {
    let f = fract(uv * n + vec2<f32>(width * 0.5));
    return select(0.0, 1.0, f.x < width || f.y < width);
}

// v normalized, or fallback where v is (nearly) zero or not finite (src/ir/material.rs
// has the same in f64).
fn sdfc_normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    if (l > 1e-20 && l < 3.0e38) {
        return v / l;
    }
    return fallback;
}

// A normal map (Eqs. 50 and 52). t and b: the atlas's blended transported seed frame,
// re-orthonormalized about the unit normal n by the plane rotation nearest to it (for a
// right-handed frame, b x n is t again; their mean is the polar factor's first column).
// The texel's rgb decodes to a tangent-space normal (rgb * 2 - 1, green times `green`:
// -1 for OpenGL-convention maps, as v runs down the image; 1 for DirectX ones), its
// tangent part scaled by strength. The surface normal where the frame is degenerate
// (a failed atlas sample).
fn sdfc_normal_map(texel: vec4<f32>, t: vec3<f32>, b: vec3<f32>, n: vec3<f32>, strength: f32, green: f32) -> vec3<f32> {
    // A mirrored frame (the atlas's `mirror`) is left-handed and keeps its handedness.
    let hand = select(1.0, -1.0, dot(cross(t, b), n) < 0.0);
    let s = t + hand * cross(b, n);
    let sp = s - n * dot(n, s);
    let len = length(sp);
    if (!(len >= 1e-6)) {
        return n;
    }
    let tt = sp / len;
    let bb = hand * cross(n, tt);
    let c = texel.rgb * 2.0 - vec3<f32>(1.0);
    return sdfc_normalize_or(tt * (c.x * strength) + bb * (c.y * green * strength) + n * c.z, n);
}
