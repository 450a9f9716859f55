//! The render group (`@group(0)`) of a generated module, built from its binding table
//! for every pipeline that uses the module: the render pipeline (`fs_main`), the compute
//! queries (`cs_atlas`, `cs_points`, `cs_material`) and the bake pass (`cs_bake`). The
//! layouts are explicit, from the manifest, so a binding an entry point does not reach
//! (the `tables` of an atlas that only `cs_atlas` reads) is never an error.

use super::{Gpu, GpuError};
use crate::codegen::bindings::{Binding, Resource, RENDER_GROUP};
use crate::codegen::Module;

/// The textures and samplers of a module's texture bindings, in `Manifest::textures`
/// order.
pub type Images = Vec<(wgpu::TextureView, wgpu::Sampler)>;

/// Which pipeline the group is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// `vs_main` and `fs_main`: the globals, the textures and the tables.
    Render,
    /// A compute entry point, with the module's textures (`textured`) or without them
    /// (the entry points that sample none: `cs_points` and `cs_atlas` of most scenes).
    Compute { textured: bool },
}

/// The bindings of group 0 (of a module's `Manifest::bindings`) a pipeline of `stage`
/// binds.
fn slots(bindings: &[Binding], stage: Stage) -> impl Iterator<Item = &Binding> {
    bindings
        .iter()
        .filter(|b| b.group == RENDER_GROUP)
        .filter(move |b| match (b.resource, stage) {
            (Resource::Globals, Stage::Render) => true,
            (Resource::Texture(_) | Resource::Sampler(_), Stage::Render) => true,
            (Resource::Texture(_) | Resource::Sampler(_), Stage::Compute { textured }) => textured,
            (Resource::Tables | Resource::Params, _) => true,
            (Resource::Tiles | Resource::Coarse, Stage::Render) => true,
            _ => false,
        })
}

/// The layout of group 0 for `stage`.
/// With the multi-scale pass (a `coarse` binding), the render group is also the group of
/// its compute entry point `cs_coarse`, so every binding is visible to compute too.
pub fn layout(d: &wgpu::Device, bindings: &[Binding], stage: Stage) -> wgpu::BindGroupLayout {
    let shaders = match stage {
        Stage::Render => wgpu::ShaderStages::FRAGMENT,
        Stage::Compute { .. } => wgpu::ShaderStages::COMPUTE,
    };
    let also = match stage {
        Stage::Render if bindings.iter().any(|b| b.resource == Resource::Coarse) => {
            wgpu::ShaderStages::COMPUTE
        }
        _ => wgpu::ShaderStages::NONE,
    };
    let entries: Vec<wgpu::BindGroupLayoutEntry> = slots(bindings, stage)
        .map(|b| {
            let (visibility, ty) = match b.resource {
                Resource::Globals => (
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
                Resource::Params => (
                    match stage {
                        Stage::Render => wgpu::ShaderStages::VERTEX_FRAGMENT,
                        Stage::Compute { .. } => wgpu::ShaderStages::COMPUTE,
                    },
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
                Resource::Sampler(_) => (
                    shaders,
                    wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                ),
                Resource::Tables | Resource::Tiles => (
                    shaders,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
                Resource::Coarse => (
                    shaders,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: false },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
                _ => (
                    shaders,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                ),
            };
            wgpu::BindGroupLayoutEntry {
                binding: b.binding,
                visibility: visibility | also,
                ty,
                count: None,
            }
        })
        .collect();
    d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("render group"),
        entries: &entries,
    })
}

/// The `tables` storage buffer of a module, with its words; `None` when it has none.
/// Writable: an atlas on a moving shape rewrites its records ([`MovingTables`]).
pub fn tables(gpu: &Gpu, module: &Module) -> Result<Option<wgpu::Buffer>, GpuError> {
    gpu.scoped(|| tables_on(&gpu.device, module))
}

/// [`tables`] on any device (no error scope).
pub fn tables_on(d: &wgpu::Device, module: &Module) -> Option<wgpu::Buffer> {
    use wgpu::util::DeviceExt;
    (!module.manifest.tables.is_empty()).then(|| {
        d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("tables"),
            contents: bytemuck::cast_slice(&module.manifest.tables),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        })
    })
}

/// The `tables` words of a module with atlases on moving shapes, as last uploaded,
/// and the key of the values they were computed at ([`Module::moving_key`]): new
/// values recompute the atlases' geometry once ([`Module::write_tables_at`]), equal
/// values nothing.
#[derive(Debug, Default)]
pub struct MovingTables {
    last: std::sync::Mutex<Option<(Vec<u8>, Vec<u32>)>>,
}

impl MovingTables {
    /// The words to upload for the parameters at `values`, with the time the
    /// recomputation took; `None` when the module has no moving atlas or the values
    /// their shapes read are the last ones ([`Module::moving_key`]). On an error the
    /// last words stay.
    pub fn update(
        &self,
        module: &Module,
        values: crate::ir::dynamic::Values,
    ) -> Result<Option<(Vec<u32>, std::time::Duration)>, crate::codegen::MovingError> {
        if !module.has_moving_atlases() {
            return Ok(None);
        }
        let key = module.moving_key(values);
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        if last.as_ref().is_some_and(|(k, _)| *k == key) {
            return Ok(None);
        }
        let started = std::time::Instant::now();
        let mut words = match last.take() {
            Some((_, w)) => w,
            None => module.manifest.tables.clone(),
        };
        let result = module.write_tables_at(values, &mut words);
        let took = started.elapsed();
        *last = Some((key, words.clone()));
        result.map(|()| Some((words, took)))
    }
}

/// The run-time parameters' uniform block of a module at its defaults (the values
/// the scene was checked with), writable for later values; `None` when it has none.
pub fn params(gpu: &Gpu, module: &Module) -> Result<Option<wgpu::Buffer>, GpuError> {
    if module.manifest.params.fields.is_empty() {
        return Ok(None);
    }
    gpu.scoped(|| Some(params_on(&gpu.device, module)))
}

/// [`params`] on any device (no error scope).
pub fn params_on(d: &wgpu::Device, module: &Module) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("params"),
        contents: &module.manifest.params.bytes(&|_| None),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    })
}

/// What group 0 binds: the module's images, its tables buffer and, for rendering, the
/// globals.
pub struct Resources<'a> {
    pub images: &'a [(wgpu::TextureView, wgpu::Sampler)],
    pub tables: Option<&'a wgpu::Buffer>,
    pub globals: Option<&'a wgpu::Buffer>,
    /// The run-time parameters' block ([`params`]).
    pub params: Option<&'a wgpu::Buffer>,
    /// The frame's screen tiles (`gpu::tiles`), for a module generated with them.
    pub tiles: Option<&'a wgpu::Buffer>,
    /// The frame's coarse samples (`gpu::coarse`), for a module with the multi-scale pass.
    pub coarse: Option<&'a wgpu::Buffer>,
}

/// The bind group of `layout` (made by [`layout`] for the same `stage`); an error when a
/// resource the table names is missing.
pub fn group(
    d: &wgpu::Device,
    bindings: &[Binding],
    stage: Stage,
    layout: &wgpu::BindGroupLayout,
    with: &Resources,
) -> Result<wgpu::BindGroup, GpuError> {
    let missing = |what: &str| GpuError::Validation(format!("no {what} to bind for the module"));
    let entries = slots(bindings, stage)
        .map(|b| {
            let resource = match b.resource {
                Resource::Globals => with
                    .globals
                    .ok_or_else(|| missing("globals"))?
                    .as_entire_binding(),
                Resource::Texture(i) => wgpu::BindingResource::TextureView(
                    &with.images.get(i).ok_or_else(|| missing("texture"))?.0,
                ),
                Resource::Sampler(i) => wgpu::BindingResource::Sampler(
                    &with.images.get(i).ok_or_else(|| missing("sampler"))?.1,
                ),
                Resource::Tables => with
                    .tables
                    .ok_or_else(|| missing("tables"))?
                    .as_entire_binding(),
                Resource::Params => with
                    .params
                    .ok_or_else(|| missing("parameters block"))?
                    .as_entire_binding(),
                Resource::Tiles => with
                    .tiles
                    .ok_or_else(|| {
                        missing("screen tiles (a module generated with Options::tiles is for sdfc's own renderer)")
                    })?
                    .as_entire_binding(),
                Resource::Coarse => with
                    .coarse
                    .ok_or_else(|| {
                        missing("coarse samples (a module generated with Options::multiscale is for sdfc's own renderer)")
                    })?
                    .as_entire_binding(),
                _ => return Err(missing("compute buffer in the render group")),
            };
            Ok(wgpu::BindGroupEntry {
                binding: b.binding,
                resource,
            })
        })
        .collect::<Result<Vec<_>, GpuError>>()?;
    Ok(d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("render group"),
        layout,
        entries: &entries,
    }))
}
