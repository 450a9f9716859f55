//! The viewer's orbit camera: a target, a distance and two angles, moved by the mouse
//! and turned into the renderer's [`Camera`] for each frame.

use crate::ir::Aabb;
use crate::view::Camera;
use glam::DVec3;

/// Pitch stays this far from the poles, where the orbit's frame would flip.
const MAX_PITCH: f64 = 1.55;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    pub target: DVec3,
    pub distance: f64,
    /// Around +y; 0 looks along -z from +z (as the scene language's `orbit`).
    pub yaw: f64,
    pub pitch: f64,
    /// Vertical field of view in radians.
    pub fov: f64,
}

impl Orbit {
    /// The orbit that gives `camera`, turning about the point `focus` projects to on its
    /// line of sight (the bounds' centre, for a scene's `look_at` camera).
    pub fn from_camera(camera: &Camera, focus: DVec3) -> Orbit {
        let distance = (focus - camera.eye).dot(camera.forward).max(1e-3);
        let target = camera.eye + camera.forward * distance;
        let back = -camera.forward;
        Orbit {
            target,
            distance,
            yaw: back.x.atan2(back.z),
            pitch: back.y.clamp(-1.0, 1.0).asin(),
            fov: camera.fov,
        }
    }

    pub fn camera(&self) -> Camera {
        Camera::orbit(self.target, self.distance, self.yaw, self.pitch, self.fov)
    }

    /// Turns by a mouse drag of `dx`, `dy` pixels (a full window width is about a turn).
    pub fn rotate(&mut self, dx: f64, dy: f64, width: f64) {
        let k = std::f64::consts::TAU / width.max(1.0);
        self.yaw -= dx * k;
        self.pitch = (self.pitch + dy * k).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target with a drag of `dx`, `dy` pixels, so that the point under the
    /// cursor at the target's depth follows it.
    pub fn pan(&mut self, dx: f64, dy: f64, height: f64) {
        let c = self.camera();
        let per_pixel = 2.0 * self.distance * (self.fov * 0.5).tan() / height.max(1.0);
        self.target += (-dx * c.right + dy * c.up) * per_pixel;
    }

    /// Zooms by `steps` wheel notches (positive: closer).
    pub fn zoom(&mut self, steps: f64) {
        self.distance = (self.distance * 0.85f64.powf(steps)).clamp(1e-4, 1e7);
    }

    /// Frames `bounds` from the current direction: the box's bounding sphere fits the
    /// view of aspect `aspect` (width / height), across its narrower angle.
    pub fn frame(&mut self, bounds: Aabb, aspect: f64) {
        let radius = ((bounds.max - bounds.min).length() * 0.5).max(1e-3);
        let half = (self.fov * 0.5).tan();
        let narrower = half.min(half * aspect.max(1e-3)).atan();
        self.target = bounds.center();
        self.distance = radius / narrower.sin() * 1.1;
    }
}
