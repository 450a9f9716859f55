//! Drawing a compiled scene with a host's own wgpu device: sdfc creates no instance,
//! installs no error handler and never waits on the queue. [`SceneRenderer::new`]
//! builds the module's render pipeline (`vs_main` with `fs_main`, one colour target)
//! and its bind group on the caller's device; [`SceneRenderer::set_globals`] queues the
//! `Globals` block ([`super::globals`] packs it from a view, or a host writes the
//! manifest's fields itself); [`SceneRenderer::draw`] records the draw into the
//! caller's render pass. `examples/embed.rs` renders a scene this way, headless.
//!
//! A module with the multi-scale atlas pass (`Options::multiscale`) also needs
//! [`SceneRenderer::prepare`] before each draw: it sizes the frame's `coarse` buffer and
//! records `cs_coarse` into the caller's encoder. A draw without it walks every pixel,
//! which is always right (never stale samples), only slower.

use super::coarse::CoarsePass;
use super::scene_group::{self, Resources, Stage};
use crate::codegen::Module;
use crate::ir::texture::Textures;
use std::sync::atomic::{AtomicBool, Ordering};

/// A compiled scene ready to draw on a host's device.
pub struct SceneRenderer {
    pipeline: wgpu::RenderPipeline,
    /// The bind group without coarse samples (a 16-byte `coarse` buffer where the module
    /// has the pass: every pixel walks).
    bind_group: wgpu::BindGroup,
    globals: wgpu::Buffer,
    params: Option<wgpu::Buffer>,
    tables: Option<wgpu::Buffer>,
    moving: scene_group::MovingTables,
    coarse: Option<Coarse>,
}

/// The multi-scale pass of an embedded module: its pipeline, what its bind group binds,
/// and the frame it was last sized for.
struct Coarse {
    pass: CoarsePass,
    layout: wgpu::BindGroupLayout,
    bindings: Vec<crate::codegen::bindings::Binding>,
    images: Vec<(wgpu::TextureView, wgpu::Sampler)>,
    /// The frame's size and its bind group (with the frame's coarse buffer), once sized.
    frame: Option<((u32, u32), wgpu::BindGroup)>,
    /// Set by `prepare`, taken by `draw`: whether the coarse samples are this frame's.
    fresh: AtomicBool,
}

impl SceneRenderer {
    /// The render pipeline of `module` into targets of `format`, with its textures
    /// (the program's, decoded: `Textures::load`) and tables uploaded through `queue`.
    /// wgpu's validation errors go to the device's own error handler; the `Err` here is
    /// a texture the module binds that `textures` lacks.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        module: &Module,
        textures: &Textures,
        format: wgpu::TextureFormat,
    ) -> Result<SceneRenderer, String> {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sdfc scene"),
            source: wgpu::ShaderSource::Wgsl(module.wgsl.as_str().into()),
        });
        let bindings = &module.manifest.bindings;
        let layout = scene_group::layout(device, bindings, Stage::Render);
        let images = module
            .manifest
            .textures
            .iter()
            .map(|t| {
                let chain = textures
                    .get(&t.path)
                    .ok_or_else(|| format!("no decoded image for texture \"{}\"", t.path))?;
                let texture = super::texture::upload_to(device, queue, chain, t.srgb);
                Ok((
                    texture.create_view(&Default::default()),
                    super::texture::sampler_on(device, &t.wrap),
                ))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let tables = scene_group::tables_on(device, module);
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sdfc globals"),
            size: 9 * 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let params = (!module.manifest.params.fields.is_empty())
            .then(|| super::scene_group::params_on(device, module));
        let pass = CoarsePass::new(device, module, &layout, None);
        // With the pass, the bind group of a draw without `prepare`: every pixel walks.
        let no_samples = pass.as_ref().map(|p| p.buffer(device, 0, 0, false).0);
        let with = Resources {
            images: &images,
            tables: tables.as_ref(),
            globals: Some(&globals),
            params: params.as_ref(),
            tiles: None,
            coarse: no_samples.as_ref(),
        };
        let bind_group = scene_group::group(device, bindings, Stage::Render, &layout, &with)
            .map_err(|e| e.to_string())?;
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("sdfc scene"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("sdfc scene"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let coarse = pass.map(|pass| Coarse {
            pass,
            layout,
            bindings: bindings.clone(),
            images,
            frame: None,
            fresh: AtomicBool::new(false),
        });
        Ok(SceneRenderer {
            pipeline,
            bind_group,
            globals,
            params,
            tables,
            moving: Default::default(),
            coarse,
        })
    }

    /// Whether the module has the multi-scale atlas pass (then call [`Self::prepare`]
    /// before each draw).
    pub fn has_multiscale(&self) -> bool {
        self.coarse.is_some()
    }

    /// For a module with the multi-scale atlas pass: records `cs_coarse` for a `width` ×
    /// `height` frame into `encoder`, which must then record the draw (the pass reads the
    /// globals and parameters queued for that submission). The frame's buffer is made
    /// when the size changes. Returns whether the pass runs: not without the pass, nor
    /// when the frame's samples exceed the device's largest storage binding (then every
    /// pixel walks). The next [`Self::draw`] uses these samples; a draw not preceded by
    /// a `prepare` walks every pixel.
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        (width, height): (u32, u32),
    ) -> Result<bool, String> {
        let Some(c) = &mut self.coarse else {
            return Ok(false);
        };
        if !c.pass.fits(device, width, height) {
            c.fresh.store(false, Ordering::Relaxed);
            return Ok(false);
        }
        if c.frame.as_ref().map(|(size, _)| *size) != Some((width, height)) {
            let (buffer, _) = c.pass.buffer(device, width, height, true);
            let with = Resources {
                images: &c.images,
                tables: self.tables.as_ref(),
                globals: Some(&self.globals),
                params: self.params.as_ref(),
                tiles: None,
                coarse: Some(&buffer),
            };
            let group = scene_group::group(device, &c.bindings, Stage::Render, &c.layout, &with)
                .map_err(|e| e.to_string())?;
            c.frame = Some(((width, height), group));
        }
        if let Some((size, group)) = &c.frame {
            c.pass.dispatch(encoder, group, *size, None);
        }
        c.fresh.store(true, Ordering::Relaxed);
        Ok(true)
    }

    /// Queues the `Globals` block (the manifest's `globals` say what each field holds).
    pub fn set_globals(&self, queue: &wgpu::Queue, globals: &[[f32; 4]; 9]) {
        queue.write_buffer(&self.globals, 0, bytemuck::cast_slice(globals));
    }

    /// Queues the run-time parameters' block (the manifest's `params`: bytes laid out
    /// as `ParamsLayout::bytes` writes them); nothing for a module without parameters.
    pub fn set_params(&self, queue: &wgpu::Queue, bytes: &[u8]) {
        if let Some(b) = &self.params {
            queue.write_buffer(b, 0, bytes);
        }
    }

    /// Queues the run-time parameters at `values` (by name; `None`: the module's
    /// default): their block and, for atlases on moving shapes, their geometry
    /// recomputed on the CPU when the values changed ([`crate::Module::tables_at`]),
    /// written to the `tables` buffer. `module` is the one this renderer was made from.
    /// On an error the block is written and those atlases keep their last geometry.
    pub fn set_param_values(
        &self,
        queue: &wgpu::Queue,
        module: &Module,
        values: crate::ir::dynamic::Values,
    ) -> Result<(), crate::codegen::MovingError> {
        let bytes = module.manifest.params.bytes(values);
        self.set_params(queue, &bytes);
        if let Some((words, _)) = self.moving.update(module, values)? {
            if let Some(t) = &self.tables {
                queue.write_buffer(t, 0, bytemuck::cast_slice(&words));
            }
        }
        Ok(())
    }

    /// Records the full-screen draw into the caller's render pass (whose colour target
    /// has the format given to [`SceneRenderer::new`]).
    /// With the multi-scale pass, the samples of the [`Self::prepare`] before it, else
    /// every pixel walks.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
        let group = match &self.coarse {
            Some(c) if c.fresh.swap(false, Ordering::Relaxed) => c.frame.as_ref().map(|(_, g)| g),
            _ => None,
        };
        pass.set_bind_group(0, group.unwrap_or(&self.bind_group), &[]);
        pass.draw(0..3, 0..1);
    }
}
