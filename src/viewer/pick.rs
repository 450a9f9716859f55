//! Picking for the viewer's mouse: the surface point under a pixel, found by sphere
//! tracing the CPU reference in f64 along the camera ray (the same ray the shader
//! casts), then refined by Newton steps along the ray to |f| below 1e-9 of the scene's
//! scale (where the ray grazes the surface and Newton would leave the hit, the trace's
//! own point stays: within its hit tolerance, 1e-4 · max(t, 1) at the default); and
//! the seed under a pixel.

use crate::driver::Analysis;
use crate::ir::{eval, Field};
use crate::view::{trace_cpu, View};
use glam::DVec3;

/// A surface point under the cursor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePick {
    pub t: f64,
    pub position: DVec3,
    pub normal: DVec3,
}

/// The surface point seen through pixel position (`px`, `py`) (pixel centres at +0.5,
/// y down) of `view`, or `None` on a miss.
pub fn surface<'s>(
    shape: impl Into<Field<'s>>,
    view: &View,
    px: f64,
    py: f64,
) -> Option<SurfacePick> {
    let shape: Field = shape.into();
    let c = &view.camera;
    let dir = c.ray(px, py, view.width as f64, view.height as f64);
    // A conservative trace (half steps) to the first hit, then Newton along the ray.
    let hit = trace_cpu(shape, view, dir, 0.5, view.max_steps.max(512) * 2)?;
    let mut t = hit.t;
    let tolerance = 1e-9 * view.scale;
    for _ in 0..32 {
        let p = c.eye + dir * t;
        let d = eval::distance(shape, p);
        if d.abs() <= tolerance {
            break;
        }
        let slope = eval::gradient(shape, p).dot(dir);
        // Grazing rays: the line barely leaves the surface; stop at the trace's point.
        if slope.abs() < 1e-6 {
            break;
        }
        let step = -d / slope;
        // Newton stays near the first hit; a jump means the ray only grazes here.
        if step.abs() > 0.05 * view.scale {
            break;
        }
        t += step;
    }
    let position = c.eye + dir * t;
    Some(SurfacePick {
        t,
        position,
        normal: eval::gradient(shape, position).normalize_or_zero(),
    })
}

/// A seed of the scene's atlases as drawn on screen.
#[derive(Debug, Clone, PartialEq)]
pub struct SeedPick {
    pub atlas: String,
    pub seed: String,
    /// The seed's projected position.
    pub position: DVec3,
    /// Its distance from the cursor in pixels.
    pub pixels: f64,
}

/// Where a point lands on screen (pixel position, and the depth along the view
/// direction), or `None` behind the camera.
pub fn project(view: &View, p: DVec3) -> Option<(f64, f64, f64)> {
    let c = &view.camera;
    let v = p - c.eye;
    let depth = v.dot(c.forward);
    if depth <= 1e-9 {
        return None;
    }
    let t = (c.fov * 0.5).tan();
    let aspect = view.width as f64 / view.height as f64;
    let ndc_x = v.dot(c.right) / depth / (t * aspect);
    let ndc_y = v.dot(c.up) / depth / t;
    Some((
        (ndc_x + 1.0) * 0.5 * view.width as f64,
        (1.0 - ndc_y) * 0.5 * view.height as f64,
        depth,
    ))
}

/// The visible seed nearest the cursor within `radius` pixels: its projected position
/// lands within the radius, and the surface hit through its own pixel is the seed (not
/// something in front of it).
pub fn seed(
    analysis: &Analysis,
    shape: Field<'_>,
    view: &View,
    px: f64,
    py: f64,
    radius: f64,
) -> Option<SeedPick> {
    let mut best: Option<SeedPick> = None;
    for atlas in analysis.atlases.iter().flatten() {
        for (k, s) in atlas.seeds.iter().enumerate() {
            let p = s.seed.p;
            let Some((sx, sy, _)) = project(view, p) else {
                continue;
            };
            let pixels = ((sx - px).powi(2) + (sy - py).powi(2)).sqrt();
            if pixels > radius || best.as_ref().is_some_and(|b| b.pixels <= pixels) {
                continue;
            }
            let visible = surface(shape, view, sx, sy)
                .is_some_and(|hit| (hit.position - p).length() < 0.02 * view.scale);
            if visible {
                best = Some(SeedPick {
                    atlas: atlas.name.clone(),
                    seed: atlas.seed_names[k].clone(),
                    position: p,
                    pixels,
                });
            }
        }
    }
    best
}

/// The atlas a new seed at `p` goes to: the only one, or among those whose shape's
/// surface passes through `p` (|f| within 1e-3 of the scale), the one with a seed
/// nearest to it.
pub fn atlas_at(analysis: &Analysis, p: DVec3, scale: f64) -> Option<String> {
    let prepared: Vec<_> = analysis.atlases.iter().flatten().collect();
    if let [only] = prepared.as_slice() {
        return Some(only.name.clone());
    }
    prepared
        .iter()
        .filter(|a| eval::distance(a.field(), p).abs() < 1e-3 * scale)
        .min_by(|a, b| {
            let near = |a: &crate::uv::Atlas| {
                a.seeds
                    .iter()
                    .map(|s| (s.seed.p - p).length())
                    .fold(f64::INFINITY, f64::min)
            };
            near(a).total_cmp(&near(b))
        })
        .map(|a| a.name.clone())
}
