//! The render pipeline of a generated module (`gpu::Renderer`), with its
//! pipeline-overridable constants (`codegen::tiles::CROWDED`).

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
