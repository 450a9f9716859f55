//! `sdfc view`: a live viewer beside the GPU renderer, sharing it. The window shows the
//! generated module's fragment shader through [`crate::gpu::Renderer`] (the one `sdfc
//! render` uses), reloads the scene when its file or textures change, and edits seeds
//! with the mouse as text edits to the scene file.
//!
//! Everything but the window itself is free of windowing and testable headless:
//! [`camera`] (the orbit camera), [`pick`] (the surface point and the seed under a
//! pixel, by f64 sphere tracing on the CPU reference), [`reload`] (the reload state
//! machine) and [`edit`] (seed edits with undo).

pub mod camera;
pub mod edit;
pub mod pick;
pub mod present;
pub mod reload;
pub mod window;

pub use camera::Orbit;
pub use window::{run, Options};

use crate::gpu::ViewMode;

/// The views on the number keys 1 to 9, in order.
pub const VIEWS: [(ViewMode, &str); 10] = [
    (ViewMode::Color, "colour"),
    (ViewMode::Normal, "normal"),
    (ViewMode::Checker, "uv checker"),
    (ViewMode::Seeds, "seeds"),
    (ViewMode::Blend, "blend"),
    (ViewMode::Distortion, "distortion"),
    (ViewMode::Seams, "seams"),
    (ViewMode::Status, "status"),
    (ViewMode::Steps, "steps"),
    (ViewMode::Walked, "walked"),
];

/// The reduction of the resolution while the camera moves: the divisor of each side
/// that brings a frame that took `full_ms` at full resolution near `budget_ms`
/// (frame time grows with the pixel count), between 1 and 8.
pub fn interactive_divisor(full_ms: f64, budget_ms: f64) -> u32 {
    if !(full_ms > budget_ms) {
        return 1;
    }
    ((full_ms / budget_ms).sqrt().ceil() as u32).clamp(1, 8)
}
