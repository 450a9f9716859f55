//! Stage 4 on the GPU: the generated module's `cs_bake` entry point projects each
//! sample point onto the surface and shades it with the scene's material, the same
//! `scene_material` code as `fs_main`, validated by naga with the rest of the module.

use crate::codegen::bindings::{COMPUTE_GROUP, RENDER_GROUP};
use crate::codegen::Module;
use crate::gpu::compute::MAX_POINTS_PER_DISPATCH;
use crate::gpu::scene_group::{self, Resources, Stage};
use crate::gpu::texture::{load_texture, sampler};
use crate::gpu::{Gpu, GpuError};
use std::path::Path;

/// One baked sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shaded {
    /// The projected point, and |f| there.
    pub position: [f32; 3],
    pub residual: f32,
    pub color: [f32; 3],
    pub roughness: f32,
    pub metallic: f32,
    pub emission: [f32; 3],
    /// The unit shading normal (object space): the material's, normal maps included
    /// (the surface normal where the material sets none).
    pub normal: [f32; 3],
    /// The material id (0 is the default material).
    pub material: u32,
}

/// The `cs_bake` pipeline with the scene's textures and tables bound.
pub struct BakePass {
    pipeline: wgpu::ComputePipeline,
    textures: wgpu::BindGroup,
    /// Bound in `textures`.
    _tables: Option<wgpu::Buffer>,
    _params: Option<wgpu::Buffer>,
}

impl BakePass {
    pub fn new(gpu: &Gpu, module: &Module, base_dir: &Path) -> Result<BakePass, GpuError> {
        let d = &gpu.device;
        let loaded = module
            .manifest
            .textures
            .iter()
            .map(|t| {
                let image = load_texture(gpu, &base_dir.join(&t.path), t.srgb)?;
                Ok((
                    image.create_view(&Default::default()),
                    sampler(gpu, &t.wrap),
                ))
            })
            .collect::<Result<Vec<_>, GpuError>>()?;
        let tables = scene_group::tables(gpu, module)?;
        let params = scene_group::params(gpu, module)?;
        let bindings = &module.manifest.bindings;
        let stage = Stage::Compute { textured: true };
        let (pipeline, layout0) = gpu.scoped(|| {
            let shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("scene"),
                source: wgpu::ShaderSource::Wgsl(module.wgsl.as_str().into()),
            });
            let layout0 = scene_group::layout(d, bindings, stage);
            let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            };
            // cs_bake reads `points` (binding 1) and writes `results` (binding 2).
            let layout1 = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("bake queries"),
                entries: &[storage(1, true), storage(2, false)],
            });
            let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("bake"),
                bind_group_layouts: &[Some(&layout0), Some(&layout1)],
                immediate_size: 0,
            });
            let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("cs_bake"),
                layout: Some(&layout),
                module: &shader,
                entry_point: Some("cs_bake"),
                compilation_options: Default::default(),
                cache: None,
            });
            (pipeline, layout0)
        })?;
        let with = Resources {
            images: &loaded,
            tables: tables.as_ref(),
            globals: None,
            params: params.as_ref(),
            tiles: None,
            coarse: None,
        };
        let textures = gpu.scoped(|| scene_group::group(d, bindings, stage, &layout0, &with))??;
        Ok(BakePass {
            pipeline,
            textures,
            _tables: tables,
            _params: params,
        })
    }

    /// Shades points `(x, y, z, footprint)`, in dispatches of bounded size; `progress`
    /// hears how many points each finished dispatch had.
    pub fn run(
        &self,
        gpu: &Gpu,
        inputs: &[[f32; 4]],
        progress: &dyn Fn(usize),
    ) -> Result<Vec<Shaded>, GpuError> {
        let mut out = Vec::with_capacity(inputs.len());
        for chunk in inputs.chunks(MAX_POINTS_PER_DISPATCH) {
            let raw = self.dispatch(gpu, chunk)?;
            out.extend(raw.chunks_exact(4).map(|r| Shaded {
                position: [r[0][0], r[0][1], r[0][2]],
                residual: r[0][3],
                color: [r[1][0], r[1][1], r[1][2]],
                roughness: r[1][3],
                emission: [r[2][0], r[2][1], r[2][2]],
                metallic: r[2][3],
                normal: [r[3][0], r[3][1], r[3][2]],
                material: r[3][3].max(0.0).round() as u32,
            }));
            progress(chunk.len());
        }
        Ok(out)
    }

    fn dispatch(&self, gpu: &Gpu, data: &[[f32; 4]]) -> Result<Vec<[f32; 4]>, GpuError> {
        use wgpu::util::DeviceExt;
        if data.is_empty() {
            return Ok(Vec::new());
        }
        let d = &gpu.device;
        let size = (data.len() * 64) as u64;
        let (group, output, readback) = gpu.scoped(|| {
            let input = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("bake points"),
                contents: bytemuck::cast_slice(data),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let output = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("bake results"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let readback = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("bake readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            // cs_bake reads `points` (binding 1) and writes `results` (binding 2).
            let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("bake queries"),
                layout: &self.pipeline.get_bind_group_layout(COMPUTE_GROUP),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: input.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: output.as_entire_binding(),
                    },
                ],
            });
            (group, output, readback)
        })?;
        gpu.scoped(|| {
            let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bake"),
            });
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("bake"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(RENDER_GROUP, &self.textures, &[]);
                pass.set_bind_group(COMPUTE_GROUP, &group, &[]);
                pass.dispatch_workgroups((data.len() as u32).div_ceil(64), 1, 1);
            }
            enc.copy_buffer_to_buffer(&output, 0, &readback, 0, size);
            gpu.queue.submit([enc.finish()]);
        })?;
        let bytes = gpu.read_buffer(&readback)?;
        Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec())
    }
}
