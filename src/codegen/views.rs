//! The view mode and the atlas AOV's switch as pipeline-overridable constants
//! (`Options::view_constants`): `sdfc render`, the viewer and the benchmarks build one
//! render pipeline per view they draw (`gpu::Renderer`), and the driver compiles only
//! that view's code. A module without them reads both from its globals at every pixel,
//! so that a host can switch views with one pipeline (`compile`, `export-web`).
//!
//! Why: on Mesa's software adapter an `if` runs both sides under lane masks, so the
//! debug views' code, which holds a second call of every atlas, and the atlas AOV's
//! third ran at every pixel of every view; with the constants the driver folds them
//! away (docs/performance.md, "The view as a pipeline constant", has the figures).

/// The constant holding the view mode (`gpu::ViewMode::index`): 0, the colour view,
/// unless a pipeline says otherwise.
pub const VIEW: &str = "SCENE_VIEW";

/// The constant saying whether the atlas AOV is written: false unless a pipeline says
/// otherwise.
pub const ATLAS_AOV: &str = "SCENE_ATLAS_AOV";

/// The values of the entry template's `view_constants`, `view` and `atlas_aov_on`.
pub fn entry_values(constants: bool) -> [(&'static str, String); 3] {
    if constants {
        [
            (
                "view_constants",
                format!(
                    "// The view mode (the globals' resolution.w) and whether the atlas AOV is written
// (camera_forward.w) as pipeline constants: sdfc's runtime builds a pipeline per view
// and the driver compiles that view's code alone (src/codegen/views.rs).
override {VIEW}: i32 = 0;
override {ATLAS_AOV}: bool = false;

"
                ),
            ),
            ("view", VIEW.to_string()),
            ("atlas_aov_on", ATLAS_AOV.to_string()),
        ]
    } else {
        [
            ("view_constants", String::new()),
            ("view", "i32(g.resolution.w) + opaque".to_string()),
            (
                "atlas_aov_on",
                "g.camera_forward.w + f32(opaque) > 0.5".to_string(),
            ),
        ]
    }
}
