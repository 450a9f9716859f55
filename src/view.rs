//! What a render sees: the camera, the sun and the tracing limits, resolved
//! from the scene's `render` item (or framed automatically), plus the f64 CPU
//! sphere trace that the GPU renderer is tested against.

use crate::ir::{eval, Aabb, Field, Shape};
use crate::sema::builtins::BuiltinId;
use crate::sema::{self, RenderDef, RenderSettings};
use glam::DVec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    /// Vertical field of view in radians.
    pub fov: f64,
}

impl Camera {
    pub fn look_at(eye: DVec3, target: DVec3, fov: f64) -> Camera {
        let forward = (target - eye).try_normalize().unwrap_or(DVec3::NEG_Z);
        let helper = if forward.cross(DVec3::Y).length() < 1e-6 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let right = forward.cross(helper).normalize();
        let up = right.cross(forward);
        Camera {
            eye,
            forward,
            right,
            up,
            fov,
        }
    }

    /// `orbit(target, distance, yaw, pitch, fov)`: yaw 0 looks along -z from +z.
    pub fn orbit(target: DVec3, distance: f64, yaw: f64, pitch: f64, fov: f64) -> Camera {
        let dir = DVec3::new(
            pitch.cos() * yaw.sin(),
            pitch.sin(),
            pitch.cos() * yaw.cos(),
        );
        Camera::look_at(target + dir * distance, target, fov)
    }

    /// The camera a scene asks for.
    pub fn new(camera: &sema::Camera) -> Camera {
        let v = DVec3::from_array;
        match *camera {
            sema::Camera::Orbit {
                target,
                distance,
                yaw,
                pitch,
                fov,
            } => Camera::orbit(v(target), distance, yaw, pitch, fov),
            sema::Camera::LookAt { eye, target, fov } => Camera::look_at(v(eye), v(target), fov),
        }
    }

    /// Frames a shape's bounds from a three-quarter view, with `orbit`'s default field of view.
    pub fn frame(shape: &Shape) -> Camera {
        Camera::frame_bounds(shape.framing_bounds())
    }

    /// Frames an axis-aligned box (a baked mesh's bounds) as [`Camera::frame`] frames a shape.
    pub fn frame_bounds(b: Aabb) -> Camera {
        let radius = ((b.max - b.min).length() * 0.5).max(1e-3);
        let fov = BuiltinId::Orbit
            .builtin()
            .param("fov")
            .and_then(|(_, p)| sema::Value::from(p.default?).as_float())
            .expect("`orbit` has a default `fov`");
        Camera::orbit(
            b.center(),
            radius / (fov * 0.5).sin() * 1.1,
            30f64.to_radians(),
            20f64.to_radians(),
            fov,
        )
    }

    /// The ray direction through a pixel position (pixel centres at +0.5; y grows downwards),
    /// exactly as `camera_ray` in shaders/render.wgsl computes it.
    pub fn ray(&self, px: f64, py: f64, width: f64, height: f64) -> DVec3 {
        let ndc_x = 2.0 * px / width - 1.0;
        let ndc_y = 1.0 - 2.0 * py / height;
        let t = (self.fov * 0.5).tan();
        (self.forward + ndc_x * (width / height) * t * self.right + ndc_y * t * self.up).normalize()
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Unit direction towards the sun.
    pub direction: DVec3,
    pub color: DVec3,
    pub intensity: f64,
}

impl Sun {
    /// The light a scene asks for.
    pub fn new(light: &sema::Light) -> Sun {
        match *light {
            sema::Light::Sun {
                direction,
                color,
                intensity,
            } => Sun {
                direction: DVec3::from_array(direction).normalize(),
                color: DVec3::from_array(color),
                intensity,
            },
        }
    }
}

/// Everything a render needs besides the shader.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    pub camera: Camera,
    pub sun: Sun,
    pub width: u32,
    pub height: u32,
    pub background: DVec3,
    pub ambient: f64,
    /// Rays stop at this distance.
    pub far: f64,
    /// A hit is |d| < epsilon · max(t, 1).
    pub epsilon: f64,
    pub max_steps: u32,
    /// The size of the scene, for normal and shadow offsets.
    pub scale: f64,
    /// Whether the fragment shader fills the atlas AOV (one more walk per pixel).
    pub atlas_aov: bool,
}

impl View {
    /// The view of a checked document: its `render` item's camera, light and settings
    /// on its target, or, with `shape`, the named `let` shape framed by its bounds.
    pub fn of(analysis: &crate::driver::Analysis, shape: Option<&str>) -> Result<View, String> {
        let scene = analysis
            .scene
            .as_ref()
            .ok_or_else(|| String::from("the scene has errors"))?;
        let target = crate::driver::pick_shape(scene, shape)?;
        let render = match shape {
            Some(_) => None,
            None => analysis.program.render.as_ref(),
        };
        Ok(View::new(render, target))
    }

    /// Resolves the view from the render item (when there is one) for a shape.
    pub fn new(render: Option<&RenderDef>, shape: &Shape) -> View {
        let defaults;
        let settings = match render {
            Some(r) => &r.settings,
            None => {
                defaults = RenderSettings::default();
                &defaults
            }
        };
        let camera = match &settings.camera {
            Some(c) => Camera::new(c),
            None => Camera::frame(shape),
        };
        let b = shape.framing_bounds();
        let scale = (b.max - b.min).max_element().max(1e-3);
        let far = ((camera.eye - b.center()).length() + (b.max - b.min).length()) * 2.0;
        let far = if shape.root_node().bounds.is_finite() {
            far
        } else {
            far.max(100.0 * scale)
        };
        View {
            camera,
            sun: Sun::new(&settings.light),
            width: settings.size[0],
            height: settings.size[1],
            background: DVec3::from_array(settings.background),
            ambient: settings.ambient,
            far,
            // A displacement read from 8-bit texels is a staircase of steps of its range
            // / 255; a hit tolerance below half a step would let a ray oscillate across
            // a step's riser without converging.
            epsilon: (0.6 * shape.height_quantum()).max(1e-4),
            max_steps: 256,
            scale,
            atlas_aov: false,
        }
    }
}

impl View {
    /// The view of a baked mesh with bounds `b` (a `.glb` carries no camera or light):
    /// the framing camera of [`Camera::frame_bounds`] and the `render` item's defaults.
    /// The tracing fields are unused by the mesh renderer, except `far`, its far plane.
    pub fn framing(b: Aabb) -> View {
        let settings = RenderSettings::default();
        let camera = Camera::frame_bounds(b);
        let scale = (b.max - b.min).max_element().max(1e-3);
        let far = ((camera.eye - b.center()).length() + (b.max - b.min).length()) * 2.0;
        View {
            camera,
            sun: Sun::new(&settings.light),
            width: settings.size[0],
            height: settings.size[1],
            background: DVec3::from_array(settings.background),
            ambient: settings.ambient,
            far,
            epsilon: 1e-4,
            max_steps: 256,
            scale,
            atlas_aov: false,
        }
    }
}

/// A CPU sphere-trace hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub position: DVec3,
    pub normal: DVec3,
    pub material: u32,
}

/// Sphere tracing in f64 with the same rule as the shader; `step_scale` ≤ 1 makes it
/// more conservative than the shader (the coverage reference for warps).
pub fn trace_cpu<'s>(
    shape: impl Into<Field<'s>>,
    view: &View,
    dir: DVec3,
    step_scale: f64,
    max_steps: u32,
) -> Option<Hit> {
    let shape: Field = shape.into();
    let l = shape.lipschitz().max(1.0);
    let mut t = 0.0;
    for _ in 0..max_steps {
        let p = view.camera.eye + dir * t;
        let (d, material) = eval::eval(shape, p);
        if d.abs() < view.epsilon * t.max(1.0) {
            return Some(Hit {
                t,
                position: p,
                normal: eval::gradient(shape, p).normalize(),
                material,
            });
        }
        t += d / l * step_scale;
        if t > view.far {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::check;

    fn view(text: &str) -> View {
        let a = check(text, None);
        assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
        let shape = a.scene.as_ref().and_then(|s| s.render.clone()).unwrap();
        View::new(a.program.render.as_ref(), &shape)
    }

    #[test]
    fn the_scene_camera_and_light_reach_the_view() {
        let v = view(
            "render sphere() { camera = look_at([0, 0, 5], fov: 1); light = sun([0, 2, 0], intensity: 2); ambient = 0.5; }",
        );
        assert_eq!(v.camera.eye, DVec3::new(0.0, 0.0, 5.0));
        assert_eq!(v.camera.fov, 1.0);
        assert_eq!(v.sun.direction, DVec3::Y);
        assert_eq!((v.sun.color, v.sun.intensity), (DVec3::ONE, 2.0));
        assert_eq!(v.ambient, 0.5);
    }

    #[test]
    fn without_settings_the_view_takes_the_table_defaults() {
        let v = view("render sphere() { }");
        let d = RenderSettings::default();
        assert_eq!(v.sun, Sun::new(&d.light));
        assert_eq!([v.width, v.height], d.size);
        assert_eq!(v.background, DVec3::from_array(d.background));
        assert_eq!(v.camera.fov, std::f64::consts::FRAC_PI_4);
    }
}
