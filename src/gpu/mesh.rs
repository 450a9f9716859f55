//! Rendering a baked mesh (`crate::bake`): its triangles rasterized through wgpu with
//! the generated module of `shaders/mesh.wgsl.in`, whose fragment shader reads the flat
//! seamless atlas as §6 of the paper says (the chart and chart-local (u, v) from the
//! level-0 texture coordinate, the level by Eq. 1–2, two bilinear lookups at the
//! half-texel-inset coordinates of the levels around it, blended). Or, with
//! [`MeshFilter::Standard`], as any glTF viewer reads it: TEXCOORD_0 interpolated over
//! each triangle and sampled with hardware trilinear filtering on a generic mip chain
//! of the glTF's images, level 0 ([`super::generic_mips`]), to see what other tools show.
//!
//! The frame is the implicit renderer's [`Frame`] from the same [`View`], so the two
//! can be compared pixel for pixel: the same projection (`camera_ray` inverted), the
//! same `shade` and `tonemap`. A mesh has no SDF to trace shadow rays in: the colour
//! view's sun shadows come from a 2048² shadow map of the mesh seen from the sun
//! (orthographic over its bounding sphere, 2 × 2 PCF, depth and normal-offset biases),
//! drawn before each frame. Faces are drawn from both sides (culling off) with a depth buffer and no
//! MSAA; a back face is shaded with its normal flipped. The AOVs: position (world, and
//! the distance from the eye, -1 where nothing was drawn), the normal-mapped normal,
//! and in `atlas` the chart-local (u, v), the level i and the chart's index.

use super::atlas_textures::upload_textures;
use super::render::{self, Frame, Targets, Timings, ViewMode};
use super::{Gpu, GpuError};
use crate::asset::{ChartLayout, FlatLayout, MeshData, PackedLayout, Textures};
pub use crate::codegen::mesh::MeshFilter;
use crate::codegen::mesh::{mesh_module, MeshIce};
use crate::ir::Aabb;
use crate::view::View;
use glam::DVec3;
use std::fmt;
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

/// Why a mesh could not be rendered.
#[derive(Debug, Clone, PartialEq)]
pub enum MeshError {
    /// The mesh, its textures or its layout are inconsistent (a bad or foreign file).
    Input(String),
    /// The view is not one a mesh has (see [`ViewMode::for_mesh`]).
    View(ViewMode),
    /// The generated module failed naga's validation: a bug in sdfc.
    Internal(MeshIce),
    Gpu(GpuError),
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            MeshError::Input(e) => write!(f, "the baked mesh cannot be rendered: {e}"),
            MeshError::View(v) => write!(
                f,
                "a baked mesh has no {} view; choose color, albedo, normal, depth, uv or level",
                format!("{v:?}").to_ascii_lowercase()
            ),
            MeshError::Internal(e) => e.fmt(f),
            MeshError::Gpu(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for MeshError {}

impl From<GpuError> for MeshError {
    fn from(e: GpuError) -> Self {
        MeshError::Gpu(e)
    }
}

/// One vertex as the pipeline reads it: position, normal, tangent, texcoord.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex([f32; 16]);

/// A baked mesh on the GPU with its pipeline, ready for any number of frames.
pub struct MeshRenderer {
    pipeline: wgpu::RenderPipeline,
    bind_group_layout: wgpu::BindGroupLayout,
    /// Base colour, metallic-roughness, normal, emission.
    textures: [wgpu::TextureView; 4],
    sampler: wgpu::Sampler,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    formats: [wgpu::TextureFormat; 4],
    bounds: Aabb,
    /// The triangles on the CPU, for the fragment estimate of each frame
    /// ([`super::overdraw::MAX_OVERDRAW`]).
    triangles: Vec<[[f32; 3]; 3]>,
    /// The sun's shadow map: its depth-only pipeline, its group layout (the light), the
    /// map and its comparison sampler.
    shadow_pipeline: wgpu::RenderPipeline,
    shadow_layout: wgpu::BindGroupLayout,
    shadow_view: wgpu::TextureView,
    shadow_sampler: wgpu::Sampler,
    /// The validated module (for `sdfc compile`-style inspection and bug reports).
    pub wgsl: String,
    /// The time the pipeline took to create.
    pub pipeline_time: Duration,
}

/// The bounds of a mesh's positions (a unit box around the origin when it has none).
pub fn mesh_bounds(mesh: &MeshData) -> Aabb {
    let mut min = DVec3::splat(f64::INFINITY);
    let mut max = DVec3::splat(f64::NEG_INFINITY);
    for p in &mesh.positions {
        let p = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        min = min.min(p);
        max = max.max(p);
    }
    if min.is_finite() && max.is_finite() {
        Aabb { min, max }
    } else {
        Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::ONE,
        }
    }
}

/// Checks that a flat layout is well formed: a chart size of at least 2, one origin
/// per level (at most down to 2 texels), every level's grid inside the image. (The
/// shader needs no power of two: level `l`'s charts are `chart_size >> l` texels, as
/// [`FlatLayout::size_at`] says.)
pub fn check_layout(layout: &FlatLayout) -> Result<(), String> {
    let n = layout.chart_size;
    if !(2..=crate::asset::packed::MAX_SIDE).contains(&n) {
        return Err(format!(
            "the chart size {n} is not from 2 to {} texels",
            crate::asset::packed::MAX_SIDE
        ));
    }
    let levels = layout.levels();
    let max_levels = (0..32).take_while(|l| n >> l >= 2).count();
    if levels == 0 || levels > max_levels {
        return Err(format!(
            "{levels} levels for {n}-texel charts (1 to {max_levels})"
        ));
    }
    if layout.columns == 0 || layout.rows == 0 {
        return Err(String::from("the chart grid is empty"));
    }
    if layout.level_origins[0] != [0, 0] {
        return Err(String::from("level 0 does not start at (0, 0)"));
    }
    if layout.gutter > n {
        return Err(format!(
            "a gutter of {} texels around {n}-texel charts",
            layout.gutter
        ));
    }
    for (l, &[x, y]) in layout.level_origins.iter().enumerate() {
        let s = layout.stride(l) as u64;
        let right = x as u64 + layout.columns as u64 * s;
        let bottom = y as u64 + layout.rows as u64 * s;
        if right > layout.width as u64 || bottom > layout.height as u64 {
            return Err(format!(
                "level {l} ({}×{} cells of {s} texels at ({x}, {y})) leaves the {}×{} image",
                layout.columns, layout.rows, layout.width, layout.height
            ));
        }
    }
    Ok(())
}

/// Each vertex's chart in a packed atlas (its block's origin and cells, the shader's
/// `chart` attribute): the chart whose level-0 rectangle holds its TEXCOORD_0, found
/// through a grid of 64-texel tiles. An error when a vertex is on no chart, or a
/// triangle's vertices are on different charts.
fn packed_charts(mesh: &MeshData, layout: &PackedLayout) -> Result<Vec<[f32; 4]>, String> {
    const TILE: u32 = 64;
    let (w, h) = (layout.width, layout.height);
    let (tw, th) = (w.div_ceil(TILE) as usize, h.div_ceil(TILE) as usize);
    let mut tiles: Vec<Vec<u32>> = vec![Vec::new(); tw * th];
    // Each chart's level-0 rectangle, computed once (a rect builds the chart's pyramid).
    let rects: Vec<[u32; 4]> = (0..layout.charts.len())
        .map(|p| layout.rect(p, 0))
        .collect();
    for (p, &[x, y, cw, ch]) in rects.iter().enumerate() {
        for ty in y / TILE..=(y + ch - 1) / TILE {
            for tx in x / TILE..=(x + cw - 1) / TILE {
                tiles[ty as usize * tw + tx as usize].push(p as u32);
            }
        }
    }
    // A texture coordinate lies on its chart's texel centres, within rounding.
    let slack = 1e-2;
    let mut out = Vec::with_capacity(mesh.texcoords.len());
    let mut which = Vec::with_capacity(mesh.texcoords.len());
    for (i, tc) in mesh.texcoords.iter().enumerate() {
        let (tx, ty) = (tc[0] as f64 * w as f64, tc[1] as f64 * h as f64);
        let tile = if tx.is_finite() && ty.is_finite() && tx >= 0.0 && ty >= 0.0 {
            let (a, b) = ((tx as u32 / TILE) as usize, (ty as u32 / TILE) as usize);
            (a < tw && b < th).then(|| &tiles[b * tw + a])
        } else {
            None
        };
        let on = |p: u32| {
            let [x, y, cw, ch] = rects[p as usize].map(f64::from);
            tx >= x + 0.5 - slack
                && tx <= x + cw - 0.5 + slack
                && ty >= y + 0.5 - slack
                && ty <= y + ch - 0.5 + slack
        };
        // A chart's vertices come together: the last vertex's chart first.
        let found = which
            .last()
            .copied()
            .filter(|&p| on(p))
            .or_else(|| tile.into_iter().flatten().copied().find(|&p| on(p)));
        let Some(p) = found else {
            return Err(format!(
                "vertex {i}'s texture coordinate ({}, {}) is on no chart of the packed atlas",
                tc[0], tc[1]
            ));
        };
        let chart = &layout.charts[p as usize];
        which.push(p);
        out.push([
            chart.origin[0] as f32,
            chart.origin[1] as f32,
            chart.cells[0] as f32,
            chart.cells[1] as f32,
        ]);
    }
    if let Some(t) = mesh.indices.chunks(3).position(|t| {
        let k = t.iter().map(|&v| which[v as usize]);
        k.clone().min() != k.max()
    }) {
        return Err(format!("triangle {t} spans two charts of the packed atlas"));
    }
    Ok(out)
}

/// Checks that the attributes, indices and images of a mesh agree with each other and
/// with the layout.
fn check_input(mesh: &MeshData, textures: &Textures, atlas: &ChartLayout) -> Result<(), String> {
    match atlas {
        ChartLayout::Flat(layout) => check_layout(layout)?,
        ChartLayout::Packed(layout) => layout.check()?,
    }
    let layout = atlas;
    let n = mesh.positions.len();
    let lens = [
        ("normals", mesh.normals.len()),
        ("tangents", mesh.tangents.len()),
        ("texture coordinates", mesh.texcoords.len()),
    ];
    for (what, len) in lens {
        if len != n {
            return Err(format!("{len} {what} for {n} vertices"));
        }
    }
    if mesh.indices.len() % 3 != 0 {
        return Err(format!(
            "{} indices are not whole triangles",
            mesh.indices.len()
        ));
    }
    if let Some(i) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {i} past the {n} vertices"));
    }
    let size = (layout.width(), layout.height());
    let images = [
        ("base colour", Some(&textures.base_color)),
        ("metallic-roughness", Some(&textures.metallic_roughness)),
        ("normal", Some(&textures.normal)),
        ("emissive", textures.emissive.as_ref()),
    ];
    for (what, image) in images {
        if let Some(image) = image {
            if image.dimensions() != size {
                let (w, h) = image.dimensions();
                return Err(format!(
                    "the {what} image is {w}×{h}; the layout's atlas is {}×{}",
                    size.0, size.1
                ));
            }
        }
    }
    textures.check_emissive_strength()
}

impl MeshRenderer {
    /// Uploads the mesh and its atlas and creates the pipeline of the mesh module
    /// generated for `layout` (validated by naga first), reading the atlas with sdfc's
    /// own lookup ([`MeshFilter::Atlas`]).
    pub fn new(
        gpu: &Gpu,
        mesh: &MeshData,
        textures: &Textures,
        layout: &ChartLayout,
    ) -> Result<MeshRenderer, MeshError> {
        Self::with_filter(gpu, mesh, textures, layout, MeshFilter::Atlas)
    }

    /// As [`MeshRenderer::new`], reading the atlas with `filter`.
    pub fn with_filter(
        gpu: &Gpu,
        mesh: &MeshData,
        textures: &Textures,
        layout: &ChartLayout,
        filter: MeshFilter,
    ) -> Result<MeshRenderer, MeshError> {
        check_input(mesh, textures, layout).map_err(MeshError::Input)?;
        let side = gpu.device.limits().max_texture_dimension_2d;
        if layout.width() > side || layout.height() > side {
            return Err(MeshError::Gpu(GpuError::Resource(format!(
                "the atlas is {}×{}; this GPU's limit is {side} texels a side",
                layout.width(),
                layout.height()
            ))));
        }
        let charts = match layout {
            ChartLayout::Flat(_) => Vec::new(),
            ChartLayout::Packed(packed) => packed_charts(mesh, packed).map_err(MeshError::Input)?,
        };
        let (wgsl, _) =
            mesh_module(layout, filter, textures.emissive_strength).map_err(MeshError::Internal)?;
        let formats = super::render_pipeline::formats(gpu);
        let d = &gpu.device;
        let vertices: Vec<Vertex> = (0..mesh.positions.len())
            .map(|i| {
                let (p, n, t, c) = (
                    mesh.positions[i],
                    mesh.normals[i],
                    mesh.tangents[i],
                    mesh.texcoords[i],
                );
                let k = charts.get(i).copied().unwrap_or([0.0; 4]);
                Vertex([
                    p[0], p[1], p[2], n[0], n[1], n[2], t[0], t[1], t[2], t[3], c[0], c[1], k[0],
                    k[1], k[2], k[3],
                ])
            })
            .collect();
        let started = Instant::now();
        let made = gpu.scoped(|| {
            let (textures, sampler) = upload_textures(gpu, textures, layout, filter);
            // wgpu rejects empty buffers with a binding; a zero-length draw reads nothing.
            let vertex_bytes: &[u8] = if vertices.is_empty() {
                &[0; 64]
            } else {
                bytemuck::cast_slice(&vertices)
            };
            let index_bytes: &[u8] = if mesh.indices.is_empty() {
                &[0; 4]
            } else {
                bytemuck::cast_slice(&mesh.indices)
            };
            let vertices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("mesh vertices"),
                contents: vertex_bytes,
                usage: wgpu::BufferUsages::VERTEX,
            });
            let indices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("mesh indices"),
                contents: index_bytes,
                usage: wgpu::BufferUsages::INDEX,
            });
            let shadow_pipeline = pipeline(d, &wgsl, None);
            let pipeline = pipeline(d, &wgsl, Some(&formats));
            let layout = pipeline.get_bind_group_layout(0);
            let shadow_layout = shadow_pipeline.get_bind_group_layout(0);
            let shadow_view = d
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some("shadow map"),
                    size: render::extent(SHADOW_SIZE, SHADOW_SIZE),
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: DEPTH_FORMAT,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&Default::default());
            let shadow_sampler = d.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow map"),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            });
            let shadow = (shadow_pipeline, shadow_layout, shadow_view, shadow_sampler);
            (
                textures, sampler, vertices, indices, pipeline, layout, shadow,
            )
        })?;
        gpu.wait()?;
        let (textures, sampler, vertices, indices, pipeline, bind_group_layout, shadow) = made;
        let (shadow_pipeline, shadow_layout, shadow_view, shadow_sampler) = shadow;
        Ok(MeshRenderer {
            pipeline,
            bind_group_layout,
            textures,
            sampler,
            vertices,
            indices,
            index_count: mesh.indices.len() as u32,
            formats,
            bounds: mesh_bounds(mesh),
            triangles: mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]))
                .collect(),
            shadow_pipeline,
            shadow_layout,
            shadow_view,
            shadow_sampler,
            wgsl,
            pipeline_time: started.elapsed(),
        })
    }

    /// The bounds of the mesh's positions, for framing ([`View::framing`]).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Renders one frame of `view` (camera, sun, ambient, background, size; `far` is the
    /// far plane, the tracing fields are unused).
    pub fn render(&self, gpu: &Gpu, view: &View, mode: ViewMode) -> Result<Frame, MeshError> {
        if !mode.for_mesh() {
            return Err(MeshError::View(mode));
        }
        let d = &gpu.device;
        let (w, h) = (view.width.max(1), view.height.max(1));
        gpu.check_size(w, h, render::bytes_per_texel(&self.formats) + 4)?;
        super::overdraw::check(&self.triangles, view, &self.bounds, SHADOW_SIZE)?;
        let uniforms = render::globals(view, mode);
        let background = tonemap(view.background);
        let light = light_uniform(&self.bounds, view.sun.direction);
        let (targets, depth, bind_group, shadow_group, _globals) = gpu.scoped(|| {
            let (bind_group, shadow_group, globals) = self.bind_groups(
                d,
                bytemuck::cast_slice(&uniforms),
                bytemuck::cast_slice(&light),
            );
            let depth = depth_view(d, w, h);
            (
                render::targets(gpu, &self.formats, w, h),
                depth,
                bind_group,
                shadow_group,
                globals,
            )
        })?;
        let submitted = Instant::now();
        gpu.scoped(|| {
            let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("mesh frame"),
            });
            self.shadow_pass(&mut enc, &shadow_group);
            self.color_pass(&mut enc, &targets, &depth, &bind_group, background);
            render::copy_out(&mut enc, &targets);
            gpu.queue.submit([enc.finish()]);
        })?;
        gpu.wait()?;
        let frame_time = submitted.elapsed();
        let mut frame = render::read(gpu, &self.formats, &targets)?;
        frame.timings = Timings {
            pipeline: self.pipeline_time,
            frame: frame_time,
            frame_from_timestamps: false,
            readback: frame.timings.readback,
            ..Default::default()
        };
        Ok(frame)
    }

    /// The frame's bind groups: the mesh's (globals, the atlas's textures and sampler,
    /// the shadow map, the light) and the shadow pass's (the light); and the globals'
    /// buffer, which the frame keeps.
    fn bind_groups(
        &self,
        d: &wgpu::Device,
        uniforms: &[u8],
        light: &[u8],
    ) -> (wgpu::BindGroup, wgpu::BindGroup, wgpu::Buffer) {
        let buffer = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("globals"),
            contents: uniforms,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let light = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("light"),
            contents: light,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let shadow_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow group"),
            layout: &self.shadow_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 8,
                resource: light.as_entire_binding(),
            }],
        });
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }];
        for (k, t) in self.textures.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: k as u32 + 1,
                resource: wgpu::BindingResource::TextureView(t),
            });
        }
        entries.push(wgpu::BindGroupEntry {
            binding: 5,
            resource: wgpu::BindingResource::Sampler(&self.sampler),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 6,
            resource: wgpu::BindingResource::TextureView(&self.shadow_view),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 7,
            resource: wgpu::BindingResource::Sampler(&self.shadow_sampler),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 8,
            resource: light.as_entire_binding(),
        });
        let bind_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mesh group"),
            layout: &self.bind_group_layout,
            entries: &entries,
        });
        (bind_group, shadow_group, buffer)
    }

    /// The shadow map's pass: the mesh's depth seen from the sun.
    fn shadow_pass(&self, enc: &mut wgpu::CommandEncoder, shadow_group: &wgpu::BindGroup) {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow map"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.shadow_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.shadow_pipeline);
        pass.set_bind_group(0, shadow_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }

    /// The mesh's pass into the frame's targets, each cleared first (the colour to
    /// `background`, the others to their "no surface" values).
    fn color_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        targets: &Targets,
        depth: &wgpu::TextureView,
        bind_group: &wgpu::BindGroup,
        background: [f64; 3],
    ) {
        let clears = [
            wgpu::Color {
                r: background[0],
                g: background[1],
                b: background[2],
                a: 1.0,
            },
            wgpu::Color {
                r: 0.0,
                g: 0.0,
                b: 0.0,
                a: -1.0,
            },
            wgpu::Color::TRANSPARENT,
            wgpu::Color {
                r: 0.0,
                g: 0.0,
                b: -1.0,
                a: -1.0,
            },
        ];
        // rgba32uint AOVs (`codegen::aov`) clear to the bits of the same floats.
        let to_bits = |c: f64| f64::from((c as f32).to_bits());
        let bits = self.formats[1] == wgpu::TextureFormat::Rgba32Uint;
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = targets
            .views
            .iter()
            .zip(clears)
            .enumerate()
            .map(|(k, (v, clear))| {
                let clear = match bits && k > 0 {
                    true => wgpu::Color {
                        r: to_bits(clear.r),
                        g: to_bits(clear.g),
                        b: to_bits(clear.b),
                        a: to_bits(clear.a),
                    },
                    false => clear,
                };
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("mesh"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

/// A frame's depth buffer, `w` × `h`.
fn depth_view(d: &wgpu::Device, w: u32, h: u32) -> wgpu::TextureView {
    d.create_texture(&wgpu::TextureDescriptor {
        label: Some("depth"),
        size: render::extent(w, h),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: DEPTH_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    })
    .create_view(&Default::default())
}

const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The shadow map's side in texels.
const SHADOW_SIZE: u32 = 2048;

/// The `Light` uniform of shaders/mesh.wgsl.in: an orthographic view of the mesh's
/// bounding sphere from the sun (`towards_sun`, unit), and the biases: a depth bias of
/// a texel's depth and a normal offset of 1.5 texels, against shadow acne.
fn light_uniform(bounds: &Aabb, towards_sun: DVec3) -> [f32; 20] {
    let centre = bounds.center();
    let r = ((bounds.max - bounds.min).length() * 0.5).max(1e-6);
    let dir = towards_sun.try_normalize().unwrap_or(DVec3::Y);
    let up = if dir.y.abs() > 0.99 {
        DVec3::Z
    } else {
        DVec3::Y
    };
    let eye = centre + dir * (2.0 * r);
    // An orthographic camera at `eye` looking at the centre: x and y over [−r, r], depth
    // over [0, 4r] mapped to [0, 1] (wgpu's clip space).
    let f = (centre - eye).normalize();
    let side = f.cross(up).normalize();
    let u = side.cross(f);
    let row = |a: DVec3, k: f64| glam::DVec4::new(a.x * k, a.y * k, a.z * k, -a.dot(eye) * k);
    let rows = [
        row(side, 1.0 / r),
        row(u, 1.0 / r),
        row(f, 1.0 / (4.0 * r)),
        glam::DVec4::W,
    ];
    let m = glam::DMat4::from_cols(rows[0], rows[1], rows[2], rows[3])
        .transpose()
        .as_mat4()
        .to_cols_array();
    let texel = 2.0 * r / SHADOW_SIZE as f64;
    let mut out = [0.0f32; 20];
    out[..16].copy_from_slice(&m);
    out[16] = (2.0 * texel / (4.0 * r)) as f32;
    out[17] = (1.5 * texel) as f32;
    out
}

/// `tonemap` of shaders/render.wgsl, for the background (the clear colour is linear;
/// the sRGB target encodes it as it encodes the shader's output).
fn tonemap(c: DVec3) -> [f64; 3] {
    let c = c / (DVec3::ONE + c * 0.15);
    [c.x, c.y, c.z]
}

/// The mesh pipeline: one interleaved vertex buffer, a depth test, no culling, no MSAA;
/// vs_main and fs_main (fs_bits with rgba32uint AOVs) into `formats`, or with no
/// formats the shadow map's pipeline:
/// vs_shadow into the depth target alone.
fn pipeline(
    d: &wgpu::Device,
    wgsl: &str,
    formats: Option<&[wgpu::TextureFormat; 4]>,
) -> wgpu::RenderPipeline {
    let label = Some(if formats.is_some() {
        "mesh"
    } else {
        "mesh shadow"
    });
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label,
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    });
    let targets = super::render_pipeline::opaque_targets(formats.into_iter().flatten());
    let attributes = wgpu::vertex_attr_array![
        0 => Float32x3,
        1 => Float32x3,
        2 => Float32x4,
        3 => Float32x2,
        4 => Float32x4,
    ];
    d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label,
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(if formats.is_some() {
                "vs_main"
            } else {
                "vs_shadow"
            }),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attributes,
            })],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: formats.map(|_| wgpu::FragmentState {
            module: &module,
            entry_point: Some(match formats.map(|f| f[1]) {
                Some(wgpu::TextureFormat::Rgba32Uint) => crate::codegen::aov::MESH_ENTRY,
                _ => "fs_main",
            }),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}
