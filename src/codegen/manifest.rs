//! The manifest of a generated module (`sdfc compile --manifest`): the contract a
//! host drives the module by, versioned and described by `schemas/manifest.v1.json`.

use super::bindings::Binding;
use super::field::TextureUse;
use serde::Serialize;

/// What an application needs to drive the module: entry points, bindings and the
/// byte layout of the uniform blocks.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Manifest {
    /// The manifest's format version ([`MANIFEST_VERSION`]; `schemas/manifest.v1.json`
    /// describes version 1).
    pub version: u32,
    /// Every entry point, with its stage and (compute) workgroup size.
    pub entry_points: Vec<EntryPoint>,
    /// The colour targets of each fragment entry point, in location order, by WebGPU
    /// format name: `fs_main` one sRGB colour target (WebGPU's default limits), `fs_aov`
    /// the colour and three float AOVs (position and depth, normal and steps, atlas).
    pub render_targets: Vec<RenderTargets>,
    pub bindings: Vec<Binding>,
    /// Field names of `Globals`, each a `vec4<f32>` (16 bytes), in order.
    pub globals_layout: Vec<&'static str>,
    /// Each `Globals` field with its offset and meaning.
    pub globals: Vec<GlobalField>,
    /// The scene's own values (set by `sdfc compile --manifest`; absent where a module
    /// is generated without a view).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneValues>,
    /// Lipschitz bound of the render target: sphere-tracing steps are divided by it.
    pub lipschitz: f64,
    /// Names of the shapes with an `sdf_NAME` function.
    pub shapes: Vec<String>,
    /// Each texture binding's image, colour space, wrap mode, filter and mip chain.
    #[serde(serialize_with = "textures_json")]
    pub textures: Vec<TextureUse>,
    /// The contents of the `tables` storage buffer (the atlases' seed-grid lists, the
    /// multi-scale pass's tables of merged seeds, and the groups' trees and leaf records;
    /// f32 values as their bits), which the runtime
    /// uploads as they are; empty, with no binding, when the module has neither.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub tables: Vec<u32>,
    /// The run-time parameters' uniform block (`params`, binding `params` of group 0):
    /// each parameter's member, offset, type, default and range, and the block's size.
    /// Empty (size 0) for a scene without parameters or `time`.
    pub params: super::params::ParamsLayout,
    /// The multi-scale atlas pass (`codegen::coarse`): present only in a module
    /// generated with it (`sdfc compile --multiscale`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coarse: Option<CoarsePass>,
    /// The module's pipeline-overridable constants that a host may set when it builds a
    /// render pipeline (`codegen::views`: the view, and whether the atlas AOV is
    /// written); a host that sets none gets each one's default.
    pub pipeline_constants: Vec<PipelineConstant>,
}

/// A pipeline-overridable constant of the module (WGSL's `override`), set through the
/// pipeline's `constants` (WebGPU's `GPUProgrammableStage.constants`, wgpu's
/// `PipelineCompilationOptions::constants`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PipelineConstant {
    pub name: &'static str,
    /// Its WGSL type.
    #[serde(rename = "type")]
    pub ty: &'static str,
    pub default: i32,
    /// What it does, and what its default means.
    pub meaning: &'static str,
}

/// How a host runs the multi-scale atlas pass of a module generated with it. Before
/// each frame's render pass, for a frame of `width` × `height` pixels:
///
/// 1. `columns = floor((max(width, 1) + step - 2) / step) + 1`, `rows` likewise from
///    `height` (one coarse sample every `step` pixels, and the last row and column);
/// 2. bind a storage buffer of `columns × rows × vec4s_per_sample × 16` bytes as
///    `binding` of group 0 (the render group, visible to compute too);
/// 3. dispatch `entry_point` with `ceil(columns / workgroup_size[0]) × ceil(rows /
///    workgroup_size[1]) × 1` workgroups,
///    the render group bound, in the same submission before the render pass.
///
/// A buffer of 16 bytes turns the pass off: the shader sees it is too small for the
/// frame and every pixel walks, as in a module without the pass. The buffer must fit
/// the device's `maxStorageBufferBindingSize` (128 MiB by default: a 3840 × 2160 frame
/// with up to three atlases read).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct CoarsePass {
    /// The compute entry point that walks the coarse samples: `cs_coarse`.
    pub entry_point: &'static str,
    /// The `coarse` buffer's binding in group 0.
    pub binding: u32,
    /// Pixels between coarse samples, along each axis.
    pub step: u32,
    /// The atlases materials read, each a slot of the coarse samples.
    pub slots: u32,
    /// `vec4<f32>` values per coarse sample: one for the surface point and four per slot.
    pub vec4s_per_sample: u32,
    /// The entry point's workgroup size.
    pub workgroup_size: [u32; 3],
    /// The steps above, in words.
    pub how: &'static str,
}

/// [`CoarsePass::how`].
pub const COARSE_HOW: &str = "Before each frame's render pass: columns = floor((max(width, 1) + step - 2) / step) + 1 and rows likewise from height; bind a storage buffer of columns * rows * vec4s_per_sample * 16 bytes as `binding` of group 0; dispatch `entry_point` with ceil(columns / workgroup_size[0]) x ceil(rows / workgroup_size[1]) x 1 workgroups, group 0 bound, before the render pass. A 16-byte buffer turns the pass off (every pixel walks).";

pub const GLOBALS_LAYOUT: &[&str] = &[
    "camera_pos",
    "camera_forward",
    "camera_right",
    "camera_up",
    "light_dir",
    "light_color",
    "background",
    "resolution",
    "trace",
];

/// What each `Globals` field holds (`shaders/render.wgsl`), in [`GLOBALS_LAYOUT`] order.
pub const GLOBALS_MEANING: &[&str] = &[
    "xyz: the camera position; w: tan(vertical field of view / 2)",
    "xyz: the camera's unit forward vector; w: 1 to fill fs_aov's atlas AOV, else 0 (read where the pipeline constant SCENE_ATLAS_AOV is -1, its default)",
    "xyz: the camera's unit right vector; w: unused",
    "xyz: the camera's unit up vector; w: unused",
    "xyz: the unit direction towards the sun; w: its intensity",
    "rgb: the sun's colour (linear); w: the ambient strength",
    "rgb: the background colour (linear); w: unused",
    "x, y: the image size in pixels; z: time in seconds; w: the view (0 colour, 1 normal, 2 depth, 3 steps, 4 uv, 5 checker, 6 status, 7 distance, 8 seeds, 9 blend, 10 distortion, 11 seams, 12 albedo, 14 evals, 15 walked: the multi-scale pass's rebuilt and walked pixels; read where the pipeline constant SCENE_VIEW is -1, its default)",
    "x: the far distance (rays stop beyond it: the distance across the shape's bounds from the camera); y: the hit epsilon (relative to the ray's length); z: the most sphere-tracing steps; w: the scene's scale (offsets of normals and shadows)",
];

/// A `Globals` field, for the manifest.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct GlobalField {
    /// Its name in `struct Globals`.
    pub name: &'static str,
    /// Its byte offset (each field is a `vec4<f32>`).
    pub offset: u32,
    /// What its components hold.
    pub meaning: &'static str,
}

/// The values a scene gives its module: what `sdfc render` uploads, for a host to
/// start from.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SceneValues {
    /// The `Globals` block as the scene's `render` item sets it, at its size and in the
    /// colour view, field by field.
    pub globals: Vec<[f32; 4]>,
    /// The rendered shape's bounds (`min`, `max`; infinite components as ±1e30).
    pub bounds: [[f64; 3]; 2],
}

/// An entry point of the module.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EntryPoint {
    /// Its WGSL name.
    pub name: &'static str,
    /// `vertex`, `fragment` or `compute`.
    pub stage: &'static str,
    /// The workgroup size of a compute entry point; `[0, 0, 0]` for the others.
    pub workgroup_size: [u32; 3],
}

/// The version of the manifest's format.
pub const MANIFEST_VERSION: u32 = 1;

/// How a texture's mip chain is made (`ir::texture::MipChain`, which the runtime
/// uploads and the CPU reference samples).
pub const MIP_CHAIN: &str = "every level down to 1x1, each the previous resized to half its size (at least 1 texel) with a triangle (bilinear) filter on the stored 8-bit values";

/// The manifest's textures: each binding's file and how to upload and sample it.
fn textures_json<S: serde::Serializer>(textures: &[TextureUse], s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeSeq;
    let mut seq = s.serialize_seq(Some(textures.len()))?;
    for (i, t) in textures.iter().enumerate() {
        seq.serialize_element(&serde_json::json!({
            "path": t.path,
            "texture_binding": 1 + 2 * i,
            "sampler_binding": 2 + 2 * i,
            "srgb": t.srgb,
            "format": if t.srgb { "rgba8unorm-srgb" } else { "rgba8unorm" },
            "wrap": t.wrap,
            "address_mode": match t.wrap.as_str() {
                "mirror" => "mirror-repeat",
                "clamp" => "clamp-to-edge",
                _ => "repeat",
            },
            "filter": { "mag": "linear", "min": "linear", "mipmap": "linear" },
            "mips": MIP_CHAIN,
        }))?;
    }
    seq.end()
}

/// A fragment entry point's colour targets.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RenderTargets {
    /// The fragment entry point.
    pub entry: &'static str,
    /// Its targets' formats, location 0 first (WebGPU's names).
    pub formats: Vec<&'static str>,
    /// Bytes per sample of those targets by WebGPU's rule (render target pixel byte
    /// cost: 8 for `rgba8unorm-srgb`, 16 for `rgba32float`): the device's
    /// `maxColorAttachmentBytesPerSample` must be at least this (its default is 32).
    pub bytes_per_sample: u32,
}

/// The render targets of every module: `fs_main` into one `rgba8unorm-srgb` target,
/// `fs_aov` into it and three `rgba32float` AOVs. (Where an adapter cannot render
/// 32-bit floats, sdfc's runtime appends `codegen::aov`'s entry point, which writes
/// their bits to `rgba32uint` targets; a module as exported does not carry it.)
pub fn render_targets() -> Vec<RenderTargets> {
    vec![
        RenderTargets {
            entry: "fs_main",
            formats: vec!["rgba8unorm-srgb"],
            bytes_per_sample: 8,
        },
        RenderTargets {
            entry: "fs_aov",
            formats: vec![
                "rgba8unorm-srgb",
                "rgba32float",
                "rgba32float",
                "rgba32float",
            ],
            bytes_per_sample: 8 + 3 * 16,
        },
    ]
}

/// The workgroup size of every compute entry point (`shaders/entry.wgsl.in`).
pub const WORKGROUP: u32 = 64;

/// The entry points of every module, with their stages.
pub const ENTRY_POINTS: &[(&str, &str)] = &[
    ("vs_main", "vertex"),
    ("fs_main", "fragment"),
    ("fs_aov", "fragment"),
    ("cs_points", "compute"),
    ("cs_grid", "compute"),
    ("cs_atlas", "compute"),
    ("cs_material", "compute"),
    ("cs_bake", "compute"),
];
