//! The fragment estimate of a mesh frame: stacked or huge triangles in a `.glb` make
//! the rasterizer's work unbounded by the file's size, so each frame is checked first.

use super::GpuError;
use crate::ir::Aabb;
use crate::view::View;
use glam::DVec3;

/// The most fragments a frame may rasterize, in frames' worth of pixels: a closed
/// mesh covers each pixel about twice (front and back faces), so this is only
/// reached by stacked or huge triangles. On lavapipe the mesh shader shades about
/// 1 M fragments a second: 30,000 copies of one triangle over half of a 32 × 24
/// frame took 13 s, 300,000 took 64 s. The shadow pass may rasterize 8 shadow maps'
/// worth (a closed mesh: about 1.6).
pub const MAX_OVERDRAW: f64 = 32.0;
pub const MAX_SHADOW_OVERDRAW: f64 = 8.0;

/// Refuses a frame whose triangles would rasterize more than [`MAX_OVERDRAW`] frames of
/// fragments from `view`, or more than `MAX_SHADOW_OVERDRAW` shadow maps from the sun
/// (estimated on the CPU: each triangle's projected area, clipped to the frame's; a
/// triangle reaching behind the camera counts as the whole frame).
pub fn check(
    triangles: &[[[f32; 3]; 3]],
    view: &View,
    bounds: &Aabb,
    shadow_size: u32,
) -> Result<(), GpuError> {
    let c = &view.camera;
    let (w, h) = (view.width.max(1) as f64, view.height.max(1) as f64);
    let frame = w * h;
    let scale = 0.5 * h / (c.fov * 0.5).tan().max(1e-9);
    let r = ((bounds.max - bounds.min).length() * 0.5).max(1e-6);
    let shadow_scale = (shadow_size as f64 / (2.0 * r)).powi(2);
    let sun = view.sun.direction.try_normalize().unwrap_or(DVec3::Y);
    let (mut fragments, mut shadow) = (0.0f64, 0.0f64);
    for t in triangles {
        let p = t.map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64));
        let normal = (p[1] - p[0]).cross(p[2] - p[0]);
        shadow += (0.5 * normal.dot(sun).abs() * shadow_scale)
            .min(shadow_size as f64 * shadow_size as f64);
        let screen = p.map(|q| {
            let d = q - c.eye;
            let z = d.dot(c.forward);
            (z > 1e-9).then(|| glam::DVec2::new(d.dot(c.right), d.dot(c.up)) * (scale / z))
        });
        let area = match screen {
            [Some(a), Some(b), Some(cc)] => 0.5 * (b - a).perp_dot(cc - a).abs(),
            [None, None, None] => 0.0,
            _ => frame,
        };
        fragments += area.min(frame);
    }
    if fragments > MAX_OVERDRAW * frame {
        return Err(GpuError::Resource(format!(
            "the mesh would rasterize about {:.0} frames' worth of fragments from this view, over the limit of {MAX_OVERDRAW} (stacked or huge triangles)",
            fragments / frame
        )));
    }
    let map = shadow_size as f64 * shadow_size as f64;
    if shadow > MAX_SHADOW_OVERDRAW * map {
        return Err(GpuError::Resource(format!(
            "the mesh would rasterize about {:.0} shadow maps' worth of fragments, over the limit of {MAX_SHADOW_OVERDRAW} (stacked or huge triangles)",
            shadow / map
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Vec<[[f32; 3]; 3]> {
        // The 12 triangles of the cube [-1, 1]^3.
        let mut out = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let corner = |u: f32, v: f32| {
                    let mut p = [0.0; 3];
                    p[axis] = sign;
                    p[(axis + 1) % 3] = u;
                    p[(axis + 2) % 3] = v;
                    p
                };
                out.push([corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0)]);
                out.push([corner(-1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)]);
            }
        }
        out
    }

    #[test]
    fn a_closed_mesh_passes_and_stacked_triangles_are_refused() {
        let bounds = Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        };
        let mut view = View::framing(bounds);
        view.width = 32;
        view.height = 24;
        assert!(check(&cube(), &view, &bounds, 2048).is_ok());
        // One face of the cube stacked: each copy covers a good part of the frame.
        let face = cube()[0];
        let stacked = vec![face; 30_000];
        let e = check(&stacked, &view, &bounds, 2048).unwrap_err();
        assert!(matches!(e, GpuError::Resource(_)), "{e}");
        // A triangle reaching behind the camera counts as the whole frame.
        let c = &view.camera;
        let back = c.eye - c.forward;
        let ahead = |q: DVec3| [q.x as f32, q.y as f32, q.z as f32];
        let behind = [
            ahead(back),
            ahead(c.eye + c.forward * 2.0),
            ahead(c.eye + c.forward * 2.0 + c.right * 0.01),
        ];
        let e = check(&vec![behind; 40], &view, &bounds, 2048).unwrap_err();
        assert!(e.to_string().contains("frames' worth"), "{e}");
        assert!(check(&vec![behind; 5], &view, &bounds, 2048).is_ok());
    }
}
