//! GPU queries through the generated `cs_points` entry point.

use super::{Gpu, GpuError};
use glam::DVec3;

/// Distance and gradient at each point, from the generated compute shader:
/// `(distance, gradient.x, gradient.y, gradient.z)` per point.
pub fn eval_points(gpu: &Gpu, wgsl: &str, points: &[DVec3]) -> Result<Vec<[f32; 4]>, GpuError> {
    run(gpu, wgsl, "cs_points", points, 1)
}

/// An atlas evaluated on the GPU (`cs_atlas`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtlasValue {
    pub uv: [f32; 2],
    pub distance: f32,
    pub status: u32,
    /// Unit quaternion (x, y, z, w).
    pub transport: [f32; 4],
    /// The chosen seed, or -1.
    pub seed: i32,
    /// The chosen seed's normalized blend weight.
    pub weight: f32,
}

/// The scene's atlas (the module's `scene_atlas`) at each point.
pub fn eval_atlas(gpu: &Gpu, wgsl: &str, points: &[DVec3]) -> Result<Vec<AtlasValue>, GpuError> {
    let raw = run(gpu, wgsl, "cs_atlas", points, 3)?;
    Ok(raw
        .chunks(3)
        .map(|c| AtlasValue {
            uv: [c[0][0], c[0][1]],
            distance: c[0][2],
            status: c[0][3].round() as u32,
            transport: c[1],
            seed: c[2][0].round() as i32,
            weight: c[2][1],
        })
        .collect())
}

/// The query pipeline and its buffers: `points` in, `size` bytes of results out.
struct Queries {
    pipeline: wgpu::ComputePipeline,
    group0: wgpu::BindGroup,
    group1: wgpu::BindGroup,
    /// Bound in `group1`; kept alive until the dispatch.
    _input: wgpu::Buffer,
    output: wgpu::Buffer,
    readback: wgpu::Buffer,
}

fn create_queries(
    d: &wgpu::Device,
    wgsl: &str,
    entry_name: &str,
    data: &[[f32; 4]],
    size: u64,
) -> Queries {
    use wgpu::util::DeviceExt;
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("scene"),
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    });
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    };
    let storage = |read_only| wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let uniform = wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Uniform,
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let empty = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("empty"),
        entries: &[],
    });
    let layout1 = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("queries"),
        entries: &[
            entry(0, uniform),
            entry(1, storage(true)),
            entry(2, storage(false)),
        ],
    });
    let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("queries"),
        bind_group_layouts: &[Some(&empty), Some(&layout1)],
        immediate_size: 0,
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry_name),
        layout: Some(&layout),
        module: &module,
        entry_point: Some(entry_name),
        compilation_options: Default::default(),
        cache: None,
    });
    let grid = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("grid"),
        contents: &[0u8; 48],
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let input = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("points"),
        contents: bytemuck::cast_slice(data),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let output = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let group0 = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("empty"),
        layout: &empty,
        entries: &[],
    });
    let group1 = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("queries"),
        layout: &layout1,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: grid.as_entire_binding(),
            },
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
    Queries {
        pipeline,
        group0,
        group1,
        _input: input,
        output,
        readback,
    }
}

/// Runs a compute entry point over points; it writes `per_point` vec4s per point.
fn run(
    gpu: &Gpu,
    wgsl: &str,
    entry_name: &str,
    points: &[DVec3],
    per_point: usize,
) -> Result<Vec<[f32; 4]>, GpuError> {
    let data: Vec<[f32; 4]> = points
        .iter()
        .map(|p| [p.x as f32, p.y as f32, p.z as f32, 0.0])
        .collect();
    run_raw(gpu, wgsl, entry_name, &data, per_point)
}

/// The most points one dispatch takes (a dispatch has at most 65,535 workgroups of 64).
pub const MAX_POINTS_PER_DISPATCH: usize = 1 << 20;

fn run_raw(
    gpu: &Gpu,
    wgsl: &str,
    entry_name: &str,
    data: &[[f32; 4]],
    per_point: usize,
) -> Result<Vec<[f32; 4]>, GpuError> {
    if data.is_empty() {
        return Ok(Vec::new());
    }
    let d = &gpu.device;
    let size = (data.len() * 16 * per_point) as u64;
    let q = gpu.scoped(|| create_queries(d, wgsl, entry_name, data, size))?;
    gpu.scoped(|| {
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("queries"),
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("queries"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&q.pipeline);
            pass.set_bind_group(0, &q.group0, &[]);
            pass.set_bind_group(1, &q.group1, &[]);
            pass.dispatch_workgroups((data.len() as u32).div_ceil(64), 1, 1);
        }
        enc.copy_buffer_to_buffer(&q.output, 0, &q.readback, 0, size);
        gpu.queue.submit([enc.finish()]);
    })?;
    let bytes = gpu.read_buffer(&q.readback)?;
    Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec())
}
