//! GPU queries through the generated compute entry points (`cs_points`, `cs_atlas`,
//! `cs_material`).

use super::scene_group::{self, Images, Resources, Stage};
use super::texture::{sampler, upload};
use super::{cache, Gpu, GpuError};
use crate::codegen::bindings::{Resource, COMPUTE_GROUP, RENDER_GROUP};
use crate::codegen::Module;
use crate::ir::texture::Textures;
use glam::DVec3;

/// Distance and gradient at each point, from the generated compute shader:
/// `(distance, gradient.x, gradient.y, gradient.z)` per point.
pub fn eval_points(
    gpu: &Gpu,
    module: &Module,
    points: &[DVec3],
) -> Result<Vec<[f32; 4]>, GpuError> {
    let group0 = Group0 {
        module,
        textures: None,
    };
    run(gpu, &module.wgsl, Some(group0), "cs_points", points, 1)
}

/// The module whose render group a query binds: its tables, and its textures when given.
#[derive(Clone, Copy)]
struct Group0<'a> {
    module: &'a Module,
    textures: Option<&'a Textures>,
}

/// [`eval_points`] for a module whose field samples textures (a displacement's height):
/// its textures (`Textures::load` of the program) are bound as `fs_main` binds them.
pub fn eval_points_textured(
    gpu: &Gpu,
    module: &Module,
    textures: &Textures,
    points: &[DVec3],
) -> Result<Vec<[f32; 4]>, GpuError> {
    let group0 = Group0 {
        module,
        textures: Some(textures),
    };
    run(gpu, &module.wgsl, Some(group0), "cs_points", points, 1)
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
    /// The blended transported seed frame (zero where the sample failed).
    pub tangent: [f32; 3],
    pub bitangent: [f32; 3],
}

/// The scene's atlas (the module's `scene_atlas`) at each point.
pub fn eval_atlas(
    gpu: &Gpu,
    module: &Module,
    points: &[DVec3],
) -> Result<Vec<AtlasValue>, GpuError> {
    let group0 = Group0 {
        module,
        textures: None,
    };
    let raw = run(gpu, &module.wgsl, Some(group0), "cs_atlas", points, 5)?;
    Ok(raw
        .chunks(5)
        .map(|c| AtlasValue {
            uv: [c[0][0], c[0][1]],
            distance: c[0][2],
            status: c[0][3].round() as u32,
            transport: c[1],
            seed: c[2][0].round() as i32,
            weight: c[2][1],
            tangent: [c[3][0], c[3][1], c[3][2]],
            bitangent: [c[4][0], c[4][1], c[4][2]],
        })
        .collect())
}

/// Atlas `k`'s field gradient and value as its walk reads them
/// (`atlas_K_grad_value(p, h)`: forward derivatives where the compiler writes them,
/// else central differences of step `h`) at each point: (∇f, f). Through an entry point
/// appended to the module for the query alone.
pub fn eval_atlas_gradients(
    gpu: &Gpu,
    module: &Module,
    k: usize,
    h: f32,
    points: &[DVec3],
) -> Result<Vec<[f32; 4]>, GpuError> {
    let group0 = Group0 {
        module,
        textures: None,
    };
    let wgsl = format!(
        "{}\n@compute @workgroup_size(64)\nfn cs_atlas_gradient(@builtin(global_invocation_id) id: vec3<u32>) {{\n    let i = id.x;\n    if (i >= arrayLength(&points)) {{\n        return;\n    }}\n    results[i] = atlas_{k}_grad_value(points[i].xyz, {h:e});\n}}\n",
        module.wgsl
    );
    run(gpu, &wgsl, Some(group0), "cs_atlas_gradient", points, 1)
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

fn upload_all(gpu: &Gpu, module: &Module, textures: &Textures) -> Result<Images, GpuError> {
    module
        .manifest
        .textures
        .iter()
        .map(|t| {
            let chain = textures.get(&t.path).ok_or_else(|| {
                GpuError::Texture(format!("no decoded image for texture \"{}\"", t.path))
            })?;
            let image = upload(gpu, chain, &t.path, t.srgb)?;
            Ok((
                image.create_view(&Default::default()),
                sampler(gpu, &t.wrap),
            ))
        })
        .collect()
}

/// What a query binds in the render group: the module's binding table, and the
/// resources of the slots that `stage` binds.
struct Bound<'a> {
    bindings: &'a [crate::codegen::Binding],
    stage: Stage,
    with: Resources<'a>,
}

/// The compute pipeline of `entry_name` over the render group of `group0` and the
/// queries' group, with both layouts.
fn query_pipeline(
    d: &wgpu::Device,
    wgsl: &str,
    group0: &Bound,
    entry_name: &str,
    cache: Option<&wgpu::PipelineCache>,
) -> (
    wgpu::ComputePipeline,
    wgpu::BindGroupLayout,
    wgpu::BindGroupLayout,
) {
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
    let empty = scene_group::layout(d, group0.bindings, group0.stage);
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
        cache,
    });
    (pipeline, empty, layout1)
}

fn create_queries(
    gpu: &Gpu,
    wgsl: &str,
    group0: &Bound,
    entry_name: &str,
    data: &[[f32; 4]],
    size: u64,
) -> Result<Queries, GpuError> {
    use wgpu::util::DeviceExt;
    let d = &gpu.device;
    let key = cache::key(entry_name, (group0.bindings, group0.stage), wgsl);
    let ((pipeline, empty, layout1), _) =
        gpu.pipelines.get_or_try(gpu.disk.as_ref(), key, || {
            gpu.scoped(|| {
                query_pipeline(
                    d,
                    wgsl,
                    group0,
                    entry_name,
                    gpu.disk.as_ref().map(|d| &d.cache),
                )
            })
        })?;
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
    let group0 = scene_group::group(d, group0.bindings, group0.stage, &empty, &group0.with)?;
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
    Ok(Queries {
        pipeline,
        group0,
        group1,
        _input: input,
        output,
        readback,
    })
}

/// Runs a compute entry point over points; it writes `per_point` vec4s per point.
fn run(
    gpu: &Gpu,
    wgsl: &str,
    group0: Option<Group0>,
    entry_name: &str,
    points: &[DVec3],
    per_point: usize,
) -> Result<Vec<[f32; 4]>, GpuError> {
    let data: Vec<[f32; 4]> = points
        .iter()
        .map(|p| [p.x as f32, p.y as f32, p.z as f32, 0.0])
        .collect();
    let params = match group0 {
        Some(g) => scene_group::params(gpu, g.module)?,
        None => None,
    };
    let (images, tables) = match group0 {
        Some(Group0 {
            module,
            textures: Some(t),
        }) => (
            upload_all(gpu, module, t)?,
            scene_group::tables(gpu, module)?,
        ),
        Some(Group0 { module, .. }) => (Vec::new(), scene_group::tables(gpu, module)?),
        None => (Vec::new(), None),
    };
    let bound = Bound {
        bindings: group0.map_or(&[][..], |g| &g.module.manifest.bindings[..]),
        stage: Stage::Compute {
            textured: group0.is_some_and(|g| g.textures.is_some()),
        },
        with: Resources {
            images: &images,
            tables: tables.as_ref(),
            globals: None,
            params: params.as_ref(),
            tiles: None,
            coarse: None,
        },
    };
    run_raw(gpu, wgsl, &bound, entry_name, &data, per_point)
}

/// The most points one dispatch takes (a dispatch has at most 65,535 workgroups of 64).
pub const MAX_POINTS_PER_DISPATCH: usize = 1 << 20;

fn run_raw(
    gpu: &Gpu,
    wgsl: &str,
    group0: &Bound,
    entry_name: &str,
    data: &[[f32; 4]],
    per_point: usize,
) -> Result<Vec<[f32; 4]>, GpuError> {
    if data.is_empty() {
        return Ok(Vec::new());
    }
    let d = &gpu.device;
    let size = (data.len() * 16 * per_point) as u64;
    let q = gpu.scoped(|| create_queries(gpu, wgsl, group0, entry_name, data, size))??;
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

/// A material evaluated on the GPU (`cs_material`): the generated `Material` struct.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialSample {
    pub color: [f32; 3],
    pub roughness: f32,
    pub metallic: f32,
    pub emission: [f32; 3],
    /// The unit shading normal.
    pub normal: [f32; 3],
}

/// The most points one dispatch of [`eval_materials`] takes.
pub const MATERIAL_CHUNK: usize = 1 << 20;

/// The module's `scene_material` at surface points, each `(position, unit normal,
/// footprint)`: the material is `scene_map`'s at the position (as `fs_main` picks it),
/// evaluated with the normal given (not `scene_normal`'s finite difference), so the
/// CPU reference (`reference::material::MaterialEval`) can be fed the same. `textures` holds
/// the images of the module's texture bindings by path (`Textures::load` of the
/// program), uploaded with the same mip levels the CPU samples. Inputs of any size are
/// dispatched in chunks of at most [`MATERIAL_CHUNK`] points; every fallible call runs
/// in an error scope.
pub fn eval_materials(
    gpu: &Gpu,
    module: &Module,
    textures: &Textures,
    points: &[(DVec3, DVec3, f64)],
) -> Result<Vec<MaterialSample>, GpuError> {
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let d = &gpu.device;
    let table = &module.manifest.bindings;
    let images = upload_all(gpu, module, textures)?;
    let slot = |r: Resource| {
        table
            .iter()
            .find(|b| b.resource == r)
            .map(|b| b.binding)
            .ok_or_else(|| GpuError::Validation(format!("the module binds no {r:?}")))
    };
    let (points_at, normals_at, results_at) = (
        slot(Resource::Points)?,
        slot(Resource::Normals)?,
        slot(Resource::Results)?,
    );
    let tables = scene_group::tables(gpu, module)?;
    let params = scene_group::params(gpu, module)?;
    let slots = [points_at, normals_at, results_at];
    let key = cache::key(
        "cs_material",
        (&module.manifest.bindings, slots),
        &module.wgsl,
    );
    let ((pipeline, layout0, layout1), _) =
        gpu.pipelines.get_or_try(gpu.disk.as_ref(), key, || {
            gpu.scoped(|| material_pipeline(d, module, slots, gpu.disk.as_ref().map(|d| &d.cache)))
        })?;
    let with = Resources {
        images: &images,
        tables: tables.as_ref(),
        globals: None,
        params: params.as_ref(),
        tiles: None,
        coarse: None,
    };
    let stage = Stage::Compute { textured: true };
    let bindings = &module.manifest.bindings;
    let group0 = gpu.scoped(|| scene_group::group(d, bindings, stage, &layout0, &with))??;
    // Results take 48 bytes a point: a chunk stays within the binding size limit.
    let max_binding = d.limits().max_storage_buffer_binding_size as usize;
    let chunk = MATERIAL_CHUNK.min(max_binding / 48).max(1);
    let mut out = Vec::with_capacity(points.len());
    for part in points.chunks(chunk) {
        let input: Vec<[f32; 4]> = part
            .iter()
            .map(|(p, _, f)| [p.x as f32, p.y as f32, p.z as f32, *f as f32])
            .collect();
        let normals: Vec<[f32; 4]> = part
            .iter()
            .map(|(_, n, _)| [n.x as f32, n.y as f32, n.z as f32, 0.0])
            .collect();
        let size = (part.len() * 48) as u64;
        let readback = gpu.scoped(|| {
            use wgpu::util::DeviceExt;
            let buffer = |label, data: &[[f32; 4]]| {
                d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytemuck::cast_slice(data),
                    usage: wgpu::BufferUsages::STORAGE,
                })
            };
            let (input, normals) = (buffer("points", &input), buffer("normals", &normals));
            let results = d.create_buffer(&wgpu::BufferDescriptor {
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
            let group1 = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("material points"),
                layout: &layout1,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: points_at,
                        resource: input.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: normals_at,
                        resource: normals.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: results_at,
                        resource: results.as_entire_binding(),
                    },
                ],
            });
            let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("materials"),
            });
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("materials"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(RENDER_GROUP, &group0, &[]);
                pass.set_bind_group(COMPUTE_GROUP, &group1, &[]);
                pass.dispatch_workgroups((part.len() as u32).div_ceil(64), 1, 1);
            }
            enc.copy_buffer_to_buffer(&results, 0, &readback, 0, size);
            gpu.queue.submit([enc.finish()]);
            readback
        })?;
        let bytes = gpu.read_buffer(&readback)?;
        let raw: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        out.extend(raw.chunks(3).map(|c| MaterialSample {
            color: [c[0][0], c[0][1], c[0][2]],
            roughness: c[0][3],
            metallic: c[1][3],
            emission: [c[1][0], c[1][1], c[1][2]],
            normal: [c[2][0], c[2][1], c[2][2]],
        }));
    }
    Ok(out)
}

/// The `cs_material` pipeline with explicit layouts: the module's textures, samplers and
/// tables in the render group, and points, normals and results (at `slots`) in the compute group.
fn material_pipeline(
    d: &wgpu::Device,
    module: &Module,
    slots: [u32; 3],
    cache: Option<&wgpu::PipelineCache>,
) -> (
    wgpu::ComputePipeline,
    wgpu::BindGroupLayout,
    wgpu::BindGroupLayout,
) {
    let shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("scene"),
        source: wgpu::ShaderSource::Wgsl(module.wgsl.as_str().into()),
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
    let layout0 = scene_group::layout(
        d,
        &module.manifest.bindings,
        Stage::Compute { textured: true },
    );
    let layout1 = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("material points"),
        entries: &[
            entry(slots[0], storage(true)),
            entry(slots[1], storage(true)),
            entry(slots[2], storage(false)),
        ],
    });
    let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("materials"),
        bind_group_layouts: &[Some(&layout0), Some(&layout1)],
        immediate_size: 0,
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("cs_material"),
        layout: Some(&layout),
        module: &shader,
        entry_point: Some("cs_material"),
        compilation_options: Default::default(),
        cache,
    });
    (pipeline, layout0, layout1)
}
