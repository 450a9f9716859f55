//! The render pipeline of a generated module (`gpu::Renderer`), with its
//! pipeline-overridable constants (`codegen::tiles::CROWDED`, `codegen::views`).

use super::{Gpu, GpuError};

/// The render pipeline of a module's vs_main and fs_aov (the colour and its AOVs; with
/// rgba32uint AOV targets, `codegen::aov`'s fs_aov_bits appended to the module) into
/// the targets' formats, with its pipeline-overridable constants.
pub(super) fn pipeline(
    d: &wgpu::Device,
    (wgsl, constants): (&str, &[(&str, f64)]),
    group0: &wgpu::BindGroupLayout,
    formats: &[wgpu::TextureFormat; 4],
    cache: Option<&wgpu::PipelineCache>,
) -> wgpu::RenderPipeline {
    // Where the AOVs are rgba32uint, the module gets the entry point that writes them
    // as bits (`codegen::aov`).
    let bits = formats[1] == wgpu::TextureFormat::Rgba32Uint;
    let source = match bits {
        true => crate::codegen::aov::with_scene_bits(wgsl),
        false => wgsl.to_string(),
    };
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("scene"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let targets = opaque_targets(formats);
    let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("scene"),
        bind_group_layouts: &[Some(group0)],
        immediate_size: 0,
    });
    d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("scene"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(match bits {
                true => crate::codegen::aov::SCENE_ENTRY,
                false => "fs_aov",
            }),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            targets: &targets,
        }),
        multiview_mask: None,
        cache,
    })
}

/// Colour targets of these formats, written whole without blending (the scene's
/// render pipeline and the baked mesh's).
pub(super) fn opaque_targets<'f>(
    formats: impl IntoIterator<Item = &'f wgpu::TextureFormat>,
) -> Vec<Option<wgpu::ColorTargetState>> {
    formats
        .into_iter()
        .map(|f| {
            Some(wgpu::ColorTargetState {
                format: *f,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        })
        .collect()
}

/// The formats of the colour target and the three AOV targets. AOVs are 32-bit float
/// where the adapter can render to it; otherwise the bits of 32-bit floats in
/// `rgba32uint` (wgpu's GL backend on a desktop GL core profile, llvmpipe's among them,
/// does not report float colour buffers: `codegen::aov`), and 16-bit float only where
/// neither is renderable, or where the adapter's `max_color_attachment_bytes_per_sample`
/// is below the 56 bytes a sample of 32-bit AOVs takes (the manifest's
/// `bytes_per_sample`; 16-bit ones take 32). `read` takes the first two back exactly.
pub(super) fn formats(gpu: &Gpu) -> [wgpu::TextureFormat; 4] {
    let needed = crate::codegen::render_targets()
        .iter()
        .find(|t| t.entry == "fs_aov")
        .expect("the codegen's render targets list fs_aov")
        .bytes_per_sample;
    let room = gpu.device.limits().max_color_attachment_bytes_per_sample >= needed;
    let renderable = |f| {
        room && gpu
            .adapter
            .get_texture_format_features(f)
            .allowed_usages
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
    };
    let aov = [
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Rgba32Uint,
    ]
    .into_iter()
    .find(|&f| renderable(f))
    .unwrap_or(wgpu::TextureFormat::Rgba16Float);
    [wgpu::TextureFormat::Rgba8UnormSrgb, aov, aov, aov]
}

/// Which of a module's render pipelines a frame draws with: the values of its
/// pipeline-overridable constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) struct Variant {
    /// The view mode's index (`codegen::views::VIEW`), or -1: read from the globals.
    pub(super) view: i32,
    /// Whether the atlas AOV is written (`codegen::views::ATLAS_AOV`): 1 or 0, or -1:
    /// as the globals say.
    pub(super) atlas_aov: i32,
    /// Whether a tile's list was too long (`codegen::tiles::CROWDED`), in a module with
    /// per-tile culling.
    pub(super) crowded: bool,
}

impl Variant {
    /// The pipeline constants of this variant: the view's (every module declares them)
    /// and, in a module with per-tile culling (`tiled`), the crowded tiles'.
    pub(super) fn constants(self, tiled: bool) -> Vec<(&'static str, f64)> {
        let mut out = Vec::new();
        if tiled {
            out.push((
                crate::codegen::tiles::CROWDED,
                f64::from(u8::from(self.crowded)),
            ));
        }
        out.push((crate::codegen::views::VIEW, f64::from(self.view)));
        out.push((crate::codegen::views::ATLAS_AOV, f64::from(self.atlas_aov)));
        out
    }
}

/// The pipeline of a variant other than a renderer's first, from the device's cache
/// where an earlier renderer of the same module built it.
pub(super) fn built_variant(
    gpu: &Gpu,
    (wgsl, constants): (&str, &[(&str, f64)]),
    (bindings, layout): (&[crate::codegen::Binding], &wgpu::BindGroupLayout),
    formats: &[wgpu::TextureFormat; 4],
) -> Result<wgpu::RenderPipeline, GpuError> {
    // Its own kind: a first pipeline's entry holds it with its layout and pass.
    let key = super::cache::key(
        "render, another variant",
        (bindings, formats, constants),
        wgsl,
    );
    let (p, _) = gpu.pipelines.get_or_try(gpu.disk.as_ref(), key, || {
        gpu.scoped(|| {
            let cache = gpu.disk.as_ref().map(|d| &d.cache);
            pipeline(&gpu.device, (wgsl, constants), layout, formats, cache)
        })
    })?;
    gpu.wait()?;
    Ok(p)
}
