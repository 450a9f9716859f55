//! The render pipeline of a generated module (`gpu::Renderer`), and the second one a
//! module with per-tile culling needs for frames with a crowded tile
//! (`codegen::tiles::CROWDED`).

use super::render::Renderer;
use super::{Gpu, GpuError};

impl Renderer {
    /// The pipeline with the whole-scene paths of crowded tiles, built the first time a
    /// frame has one (its time is not in `pipeline_time`).
    pub(super) fn crowded_pipeline(&self, gpu: &Gpu) -> Result<wgpu::RenderPipeline, GpuError> {
        let mut built = self.crowded.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = built.as_ref() {
            return Ok(p.clone());
        }
        let key = super::cache::key(
            "render, crowded",
            (&self.bindings, self.formats),
            &self.wgsl,
        );
        let (p, _) = gpu.pipelines.get_or_try(gpu.disk.as_ref(), key, || {
            gpu.scoped(|| {
                let cache = gpu.disk.as_ref().map(|d| &d.cache);
                pipeline(
                    &gpu.device,
                    (&self.wgsl, &[]),
                    &self.layout,
                    &self.formats,
                    cache,
                )
            })
        })?;
        gpu.wait()?;
        *built = Some(p.clone());
        Ok(p)
    }
}

/// The render pipeline of a module's vs_main and fs_aov (the colour and its AOVs) into
/// the targets' formats, with its pipeline-overridable constants.
pub(super) fn pipeline(
    d: &wgpu::Device,
    (wgsl, constants): (&str, &[(&str, f64)]),
    group0: &wgpu::BindGroupLayout,
    formats: &[wgpu::TextureFormat; 4],
    cache: Option<&wgpu::PipelineCache>,
) -> wgpu::RenderPipeline {
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("scene"),
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    });
    let targets: Vec<Option<wgpu::ColorTargetState>> = formats
        .iter()
        .map(|f| {
            Some(wgpu::ColorTargetState {
                format: *f,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        })
        .collect();
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
            entry_point: Some("fs_aov"),
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
