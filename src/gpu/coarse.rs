//! The multi-scale atlas pass at run time (`codegen::coarse`): before each frame of a
//! module generated with `Options::multiscale`, `cs_coarse` walks the atlases at one
//! pixel in `STEP²` into the frame's `coarse` buffer, which the render pass then reads.
//!
//! Limit, checked before the work: the buffer must fit the device's largest storage
//! binding (`max_storage_buffer_binding_size`; 128 MiB by default: 5 bytes a pixel with
//! one atlas read and 4 more for each other, so a 3840 × 2160 frame with up to three). A larger frame, or one drawn with the pass turned off
//! ([`super::Renderer::set_multiscale`]), binds a 16-byte buffer instead, which the
//! shader's `coarse_ready` refuses: every sample walks, as without the pass.

use crate::codegen::coarse::{buffer_bytes, grid, workgroups};
use crate::codegen::Module;

/// The pass's pipeline; cloned out of the device's pipeline cache with the render
/// pipeline it belongs to.
#[derive(Clone)]
pub struct CoarsePass {
    pipeline: wgpu::ComputePipeline,
    slots: usize,
}

impl CoarsePass {
    /// The pass of `module` on the render group's layout `group0` (visible to compute:
    /// `scene_group::layout`); `None` for a module without it.
    pub fn new(
        d: &wgpu::Device,
        module: &Module,
        group0: &wgpu::BindGroupLayout,
        cache: Option<&wgpu::PipelineCache>,
    ) -> Option<CoarsePass> {
        if module.coarse_slots == 0 {
            return None;
        }
        let shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("coarse"),
            source: wgpu::ShaderSource::Wgsl(module.wgsl.as_str().into()),
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("coarse"),
            bind_group_layouts: &[Some(group0)],
            immediate_size: 0,
        });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("coarse"),
            layout: Some(&layout),
            module: &shader,
            entry_point: Some("cs_coarse"),
            compilation_options: Default::default(),
            cache,
        });
        Some(CoarsePass {
            pipeline,
            slots: module.coarse_slots,
        })
    }

    /// Whether a `width` × `height` frame's samples fit the device's limit.
    pub fn fits(&self, d: &wgpu::Device, width: u32, height: u32) -> bool {
        let limits = d.limits();
        let bytes = buffer_bytes(width, height, self.slots);
        bytes <= limits.max_storage_buffer_binding_size && bytes <= limits.max_buffer_size
    }

    /// The `coarse` buffer of a frame: its samples' size when `on` and they fit, else 16
    /// bytes (every sample walks). Returns whether the pass runs.
    pub fn buffer(
        &self,
        d: &wgpu::Device,
        width: u32,
        height: u32,
        on: bool,
    ) -> (wgpu::Buffer, bool) {
        let run = on && self.fits(d, width, height);
        let size = if run {
            buffer_bytes(width, height, self.slots)
        } else {
            16
        };
        let buffer = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("coarse"),
            size,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        (buffer, run)
    }

    /// Records the pass for a `width` × `height` frame into `enc` (before the render
    /// pass that reads it), with `timestamps` when the frame is timed.
    pub fn dispatch(
        &self,
        enc: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        (width, height): (u32, u32),
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let (x, y) = workgroups(width, height);
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("coarse"),
            timestamp_writes: timestamps,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(crate::codegen::bindings::RENDER_GROUP, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// The coarse samples of a `width` × `height` frame (the pass's walks, before the
/// pixels that walk because their samples disagree).
pub fn samples(width: u32, height: u32) -> usize {
    let (cols, rows) = grid(width, height);
    cols as usize * rows as usize
}
