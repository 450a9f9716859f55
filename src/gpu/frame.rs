//! What a render produces and shows: the views ([`ViewMode`]), a frame with its AOVs
//! ([`Frame`]), its timings, and the statistics read from the evals and walked views.

use std::time::Duration;

crate::choice::choice_enum! {
/// What the fragment shader shows (the `resolution.w` uniform).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewMode {
    Color = "color": "The shaded scene.",
    Normal = "normal": "The surface normal as a colour.",
    Depth = "depth": "The distance along the ray.",
    Steps = "steps": "Sphere-tracing steps.",
    Uv = "uv": "The atlas's uv (fract, red-green).",
    Checker = "checker": "A checkerboard on the atlas's uv.",
    Status = "status": "The walk's status: ok green, too_far blue, heuristic_failed yellow, sharp_feature red, not_reached purple.",
    Distance = "distance": "Isolines of the geodesic distance.",
    Seeds = "seeds": "Geodesic Voronoi cells of the seeds in distinct colours.",
    Blend = "blend": "Blend weights: black inside cells, red to yellow in the bands between merged seeds.",
    Distortion = "distortion": "Distortion: black (isometric) to red and yellow (stretched by 50% or more).",
    Seams = "seams": "Seams: red on frontiers between seeds that are not merged.",
    Albedo = "albedo": "The unlit base colour, tonemapped as the colour view is (to compare a bake with the scene exactly).",
    Level = "level": "Baked meshes only: the flat atlas's level chosen per fragment (Eq. 2 of the seamless-atlas paper), blue (level 0) to red (the last level).",
    Evals = "evals": "SDF evaluations per pixel (the render target's and the atlases' fields) while shading as the colour view does, as a heat map: black (1) through red to yellow (4096 and more), on a log scale. The normal AOV's w holds the count.",
    Walked = "walked": "The multi-scale atlas pass: red where a material's atlas sample was walked, green where every one was rebuilt from the coarse samples, grey where no atlas is read, over the albedo's brightness. The normal AOV's w holds the samples walked and, without the atlas AOV, the atlas AOV's x those rebuilt.",
}
}

impl ViewMode {
    pub(super) fn index(self) -> f32 {
        match self {
            ViewMode::Color => 0.0,
            ViewMode::Normal => 1.0,
            ViewMode::Depth => 2.0,
            ViewMode::Steps => 3.0,
            ViewMode::Uv => 4.0,
            ViewMode::Checker => 5.0,
            ViewMode::Status => 6.0,
            ViewMode::Distance => 7.0,
            ViewMode::Seeds => 8.0,
            ViewMode::Blend => 9.0,
            ViewMode::Distortion => 10.0,
            ViewMode::Seams => 11.0,
            ViewMode::Albedo => 12.0,
            ViewMode::Level => 13.0,
            ViewMode::Evals => 14.0,
            ViewMode::Walked => 15.0,
        }
    }

    /// Whether a baked mesh ([`super::MeshRenderer`]), which has no SDF to trace and no
    /// Implicit UVs, has this view.
    pub fn for_mesh(self) -> bool {
        matches!(
            self,
            ViewMode::Color
                | ViewMode::Albedo
                | ViewMode::Normal
                | ViewMode::Depth
                | ViewMode::Uv
                | ViewMode::Level
        )
    }

    /// Whether an implicit scene has this view (every view but [`ViewMode::Level`]).
    pub fn for_scene(self) -> bool {
        self != ViewMode::Level
    }
}

#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Timings {
    pub pipeline: Duration,
    /// GPU time of the render pass (timestamps), or submit-to-complete wall time.
    pub frame: Duration,
    pub frame_from_timestamps: bool,
    pub readback: Duration,
    /// CPU time of the frame's screen tiles (`gpu::tiles`), zero without them.
    pub tiles: Duration,
    /// Leaves listed over the frame's tiles and groups, and the (tile, group) entries
    /// that walk the whole group instead (`gpu::tiles::Binned`).
    pub tile_leaves: usize,
    pub tiles_whole: usize,
    /// The multi-scale pass's coarse samples (`gpu::coarse`; its time is in `frame`),
    /// zero where it did not run.
    pub coarse_samples: usize,
    /// The build of a pipeline other than the renderer's first (`gpu::Renderer`): for
    /// crowded tiles (`SCENE_CROWDED` true), or another view or atlas AOV switch
    /// (`codegen::views`), where this frame was the first to need it and built it (not
    /// in `pipeline`, nor in `frame`).
    pub pipeline_built: Option<Duration>,
}

/// SDF evaluations per pixel of a frame rendered in [`ViewMode::Evals`]: mean, 95th
/// percentile and maximum (from the normal AOV's w).
pub fn eval_stats(frame: &Frame) -> (f64, f64, f64) {
    let mut v: Vec<f64> = frame.normal.iter().map(|n| n[3] as f64).collect();
    if v.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    v.sort_by(f64::total_cmp);
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let p95 = v[((v.len() - 1) as f64 * 0.95).round() as usize];
    (mean, p95, v[v.len() - 1])
}

/// Pixels of a frame rendered in [`ViewMode::Walked`] (without the atlas AOV) that
/// walked some atlas sample, and that rebuilt every one they read.
pub fn walked_stats(frame: &Frame) -> (usize, usize) {
    let walked = frame.normal.iter().filter(|n| n[3] > 0.0).count();
    let rebuilt = (frame.normal.iter().zip(&frame.atlas))
        .filter(|(n, a)| n[3] == 0.0 && a[0] > 0.0)
        .count();
    (walked, rebuilt)
}

/// A rendered frame: sRGB colour and float AOVs, row-major from the top-left.
#[derive(Debug, Clone)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// RGBA8, sRGB-encoded.
    pub color: Vec<u8>,
    /// World position (xyz) and ray distance t (w; -1 on a miss).
    pub position: Vec<[f32; 4]>,
    /// World normal (xyz) and the sphere-tracing step count (w).
    pub normal: Vec<[f32; 4]>,
    /// The atlas AOV (u, v, geodesic distance, status); filled when `View::atlas_aov`.
    pub atlas: Vec<[f32; 4]>,
    pub timings: Timings,
}
