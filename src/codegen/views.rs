//! The view mode and the atlas AOV's switch as pipeline-overridable constants, declared
//! by every module: `SCENE_VIEW` and `SCENE_ATLAS_AOV`, both `i32`, default -1. At -1
//! the shader reads them from its globals at every pixel (`resolution.w`,
//! `camera_forward.w`), so a host that sets no constant switches views with one
//! pipeline; at 0 or more the pipeline draws that view (the atlas AOV off at 0, on at
//! 1), and the driver compiles that view's code alone. `sdfc render`, the viewer, the
//! benchmarks (`gpu::Renderer`) and the web page's `sdfc.js` build one pipeline per
//! view they draw; the embedded `SceneRenderer` builds one with the defaults; the
//! manifest's `pipeline_constants` tells other hosts.
//!
//! Why: on a software adapter (Mesa's lavapipe, Chromium's SwiftShader) an `if` runs
//! both sides under lane masks, so the debug views' code, which holds a second call of
//! every atlas, and the atlas AOV's third ran at every pixel of every view; with the
//! constants the driver folds them away (docs/performance.md, "The view as a pipeline
//! constant", has the figures).

/// The constant holding the view mode (`gpu::ViewMode::index`), or -1 (its default):
/// the globals' `resolution.w`.
pub const VIEW: &str = "SCENE_VIEW";

/// The constant saying whether the atlas AOV is written (1) or not (0), or -1 (its
/// default): the globals' `camera_forward.w`.
pub const ATLAS_AOV: &str = "SCENE_ATLAS_AOV";

/// Both constants' default: read the value from the globals.
pub const FROM_GLOBALS: i32 = -1;

/// The values of the entry template's `view_constants`, `view` and `atlas_aov_on`.
pub fn entry_values() -> [(&'static str, String); 3] {
    [
        (
            "view_constants",
            format!(
                "// The view mode and whether the atlas AOV is written, as pipeline constants: at
// -1 (the default) read from the globals (resolution.w, camera_forward.w) at every
// pixel; at 0 or more this pipeline's view, and the driver compiles that view's code
// alone (src/codegen/views.rs; the manifest's pipeline_constants).
override {VIEW}: i32 = {FROM_GLOBALS};
override {ATLAS_AOV}: i32 = {FROM_GLOBALS};

"
            ),
        ),
        (
            "view",
            format!("select(i32(g.resolution.w) + opaque, {VIEW}, {VIEW} >= 0)"),
        ),
        (
            "atlas_aov_on",
            format!(
                "select(g.camera_forward.w + f32(opaque) > 0.5, {ATLAS_AOV} > 0, {ATLAS_AOV} >= 0)"
            ),
        ),
    ]
}

/// The constants' contract in the manifest (`pipeline_constants`).
pub fn contract() -> Vec<super::manifest::PipelineConstant> {
    vec![
        super::manifest::PipelineConstant {
            name: VIEW,
            ty: "i32",
            default: FROM_GLOBALS,
            meaning: "The view this pipeline draws (the globals' resolution.w values: 0 colour, the others as `globals` lists them), folded at pipeline creation so that only that view's code is compiled; -1 (the default): read the view from the globals at every pixel, so that one pipeline draws every view. On a software adapter (SwiftShader, lavapipe) a pipeline per view drawn is faster: every view's code otherwise runs at every pixel.",
        },
        super::manifest::PipelineConstant {
            name: ATLAS_AOV,
            ty: "i32",
            default: FROM_GLOBALS,
            meaning: "Whether fs_aov writes the atlas AOV: 1 yes, 0 no; -1 (the default): as the globals' camera_forward.w says, at every pixel.",
        },
    ]
}
