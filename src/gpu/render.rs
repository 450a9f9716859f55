//! Headless rendering: the generated fragment shader into an offscreen target,
//! read back with its AOVs (position + depth, normal + steps).

use super::{Gpu, GpuError};
use crate::codegen::Manifest;
use crate::view::View;
use std::path::Path;
use std::time::{Duration, Instant};

/// What the fragment shader shows (the `resolution.w` uniform).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ViewMode {
    Color,
    Normal,
    Depth,
    /// Sphere-tracing steps.
    Steps,
    /// The atlas's uv (fract, red-green).
    Uv,
    /// A checkerboard on the atlas's uv.
    Checker,
    /// The walk's status: ok green, too_far blue, heuristic_failed yellow, sharp_feature red, not_reached purple.
    Status,
    /// Isolines of the geodesic distance.
    Distance,
    /// Geodesic Voronoi cells of the seeds in distinct colours.
    Seeds,
    /// Blend weights: black inside cells, red to yellow in the bands between merged seeds.
    Blend,
    /// Distortion: black (isometric) to red and yellow (stretched by 50% or more).
    Distortion,
    /// Seams: red on frontiers between seeds that are not merged.
    Seams,
}

impl ViewMode {
    fn index(self) -> f32 {
        match self {
            ViewMode::Color => 0.0,
            ViewMode::Normal => 1.0,
            ViewMode::Depth => 2.0,
            ViewMode::Steps => 3.0,
            ViewMode::Uv => 4.0,
            ViewMode::Checker => 5.0,
            ViewMode::Status => 6.0,
            ViewMode::Distance => 7.0,
            ViewMode::Seeds => 8.0,
            ViewMode::Blend => 9.0,
            ViewMode::Distortion => 10.0,
            ViewMode::Seams => 11.0,
        }
    }
}

#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Timings {
    pub pipeline: Duration,
    /// GPU time of the render pass (timestamps), or submit-to-complete wall time.
    pub frame: Duration,
    pub frame_from_timestamps: bool,
    pub readback: Duration,
}

/// A rendered frame: sRGB colour and float AOVs, row-major from the top-left.
#[derive(Debug, Clone)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// RGBA8, sRGB-encoded.
    pub color: Vec<u8>,
    /// World position (xyz) and ray distance t (w; -1 on a miss).
    pub position: Vec<[f32; 4]>,
    /// World normal (xyz) and the sphere-tracing step count (w).
    pub normal: Vec<[f32; 4]>,
    /// The atlas AOV (u, v, geodesic distance, status); filled when `View::atlas_aov`.
    pub atlas: Vec<[f32; 4]>,
    pub timings: Timings,
}

/// The Globals uniform block, laid out as in shaders/render.wgsl.
fn globals(view: &View, mode: ViewMode) -> [[f32; 4]; 9] {
    let c = &view.camera;
    let v3 = |v: glam::DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
    [
        v3(c.eye, (c.fov * 0.5).tan()),
        v3(c.forward, if view.atlas_aov { 1.0 } else { 0.0 }),
        v3(c.right, 0.0),
        v3(c.up, 0.0),
        v3(view.sun.direction, view.sun.intensity),
        v3(view.sun.color, view.ambient),
        v3(view.background, 0.0),
        [view.width as f32, view.height as f32, 0.0, mode.index()],
        [
            view.far as f32,
            view.epsilon as f32,
            view.max_steps as f32,
            view.scale as f32,
        ],
    ]
}

/// Loads an image with an sRGB mip chain.
fn load_texture(gpu: &Gpu, path: &Path, srgb: bool) -> Result<wgpu::Texture, GpuError> {
    let img = image::open(path)
        .map_err(|e| GpuError::Texture(format!("cannot read texture {}: {e}", path.display())))?
        .to_rgba8();
    let (w, h) = img.dimensions();
    let levels = 32 - w.max(h).max(1).leading_zeros();
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("image"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: if srgb {
            wgpu::TextureFormat::Rgba8UnormSrgb
        } else {
            wgpu::TextureFormat::Rgba8Unorm
        },
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let mut level = img;
    for mip in 0..levels {
        let (lw, lh) = level.dimensions();
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: mip,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &level,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * lw),
                rows_per_image: Some(lh),
            },
            wgpu::Extent3d {
                width: lw,
                height: lh,
                depth_or_array_layers: 1,
            },
        );
        level = image::imageops::resize(
            &level,
            (lw / 2).max(1),
            (lh / 2).max(1),
            image::imageops::FilterType::Triangle,
        );
    }
    Ok(texture)
}

fn sampler(gpu: &Gpu, wrap: &str) -> wgpu::Sampler {
    let mode = match wrap {
        "mirror" => wgpu::AddressMode::MirrorRepeat,
        "clamp" => wgpu::AddressMode::ClampToEdge,
        _ => wgpu::AddressMode::Repeat,
    };
    gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(wrap),
        address_mode_u: mode,
        address_mode_v: mode,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    })
}

/// The formats of the colour target and the three AOV targets. AOVs are 32-bit float
/// where the adapter can render to it; otherwise (GL ES, for one) 16-bit float.
fn formats(gpu: &Gpu) -> [wgpu::TextureFormat; 4] {
    let f32_ok = gpu
        .adapter
        .get_texture_format_features(wgpu::TextureFormat::Rgba32Float)
        .allowed_usages
        .contains(wgpu::TextureUsages::RENDER_ATTACHMENT);
    let aov = if f32_ok {
        wgpu::TextureFormat::Rgba32Float
    } else {
        wgpu::TextureFormat::Rgba16Float
    };
    [wgpu::TextureFormat::Rgba8UnormSrgb, aov, aov, aov]
}

/// IEEE half to single precision.
fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h >> 15) as u32) << 31;
    let exp = ((h >> 10) & 0x1f) as u32;
    let man = (h & 0x3ff) as u32;
    let bits = match (exp, man) {
        (0, 0) => sign,
        (0, m) => {
            // Subnormal: normalise.
            let shift = m.leading_zeros() - 21;
            sign | ((113 - shift) << 23) | (((m << shift) & 0x3ff) << 13)
        }
        (31, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 112) << 23) | (m << 13),
    };
    f32::from_bits(bits)
}

/// Renders a generated module. Texture paths in the manifest are relative to `base_dir`.
pub fn render(
    gpu: &Gpu,
    wgsl: &str,
    manifest: &Manifest,
    view: &View,
    mode: ViewMode,
    base_dir: &Path,
) -> Result<Frame, GpuError> {
    render_timed(gpu, wgsl, manifest, view, mode, base_dir, 0)
}

/// [`render`] after `warmup` untimed frames (drivers may compile shaders at first use).
pub fn render_timed(
    gpu: &Gpu,
    wgsl: &str,
    manifest: &Manifest,
    view: &View,
    mode: ViewMode,
    base_dir: &Path,
    warmup: u32,
) -> Result<Frame, GpuError> {
    render_repeated(gpu, wgsl, manifest, view, mode, base_dir, warmup, 1).map(|(f, _)| f)
}

/// [`render_timed`] with `repeats` timed frames on one pipeline: returns the last frame
/// (its `timings.frame` is the median) and every frame time, in order. Only the last
/// frame is read back.
#[allow(clippy::too_many_arguments)]
pub fn render_repeated(
    gpu: &Gpu,
    wgsl: &str,
    manifest: &Manifest,
    view: &View,
    mode: ViewMode,
    base_dir: &Path,
    warmup: u32,
    repeats: u32,
) -> Result<(Frame, Vec<Duration>), GpuError> {
    let d = &gpu.device;
    let (w, h) = (view.width.max(1), view.height.max(1));
    let formats = formats(gpu);
    let textures: Vec<(wgpu::Texture, wgpu::Sampler)> = manifest
        .textures
        .iter()
        .map(|t| {
            Ok((
                load_texture(gpu, &base_dir.join(&t.path), t.srgb)?,
                sampler(gpu, &t.wrap),
            ))
        })
        .collect::<Result<_, GpuError>>()?;
    let started = Instant::now();
    let pipeline = gpu.scoped(|| {
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
        d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("scene"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    })?;
    gpu.wait()?;
    let pipeline_time = started.elapsed();

    let uniforms = globals(view, mode);
    let (targets, views, readbacks, bind_group, queries) = gpu.scoped(|| {
        use wgpu::util::DeviceExt;
        let buffer = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("globals"),
            contents: bytemuck::cast_slice(&uniforms),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let views: Vec<wgpu::TextureView> = textures
            .iter()
            .map(|(t, _)| t.create_view(&Default::default()))
            .collect();
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }];
        for (i, ((_, s), v)) in textures.iter().zip(&views).enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: 1 + 2 * i as u32,
                resource: wgpu::BindingResource::TextureView(v),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: 2 + 2 * i as u32,
                resource: wgpu::BindingResource::Sampler(s),
            });
        }
        let bind_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let targets: Vec<wgpu::Texture> = formats
            .iter()
            .map(|f| {
                d.create_texture(&wgpu::TextureDescriptor {
                    label: Some("target"),
                    size: wgpu::Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: *f,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            })
            .collect();
        let target_views: Vec<wgpu::TextureView> = targets
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let readbacks: Vec<(wgpu::Buffer, u32)> = formats
            .iter()
            .map(|f| {
                let bpp = f.block_copy_size(None).unwrap_or(4);
                let row = (w * bpp).div_ceil(256) * 256;
                (
                    d.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("readback"),
                        size: (row * h) as u64,
                        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                    row,
                )
            })
            .collect();
        let queries = gpu.timestamps.then(|| {
            let set = d.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("frame"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let resolve = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let read = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (set, resolve, read)
        });
        let _keep = buffer;
        (targets, target_views, readbacks, bind_group, queries)
    })?;

    // One full-screen pass into every target; timestamps only for the measured frame.
    let draw = |enc: &mut wgpu::CommandEncoder,
                timestamps: Option<wgpu::RenderPassTimestampWrites>| {
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = views
            .iter()
            .map(|v| {
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("frame"),
            color_attachments: &attachments,
            depth_stencil_attachment: None,
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    };
    for _ in 0..warmup {
        gpu.scoped(|| {
            let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("warm-up"),
            });
            draw(&mut enc, None);
            gpu.queue.submit([enc.finish()]);
        })?;
        gpu.wait()?;
    }
    let repeats = repeats.max(1);
    let mut times = Vec::with_capacity(repeats as usize);
    let mut from_timestamps = true;
    for rep in 0..repeats {
        let last = rep + 1 == repeats;
        let submitted = Instant::now();
        gpu.scoped(|| {
            let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
            draw(
                &mut enc,
                queries
                    .as_ref()
                    .map(|(set, _, _)| wgpu::RenderPassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    }),
            );
            if let Some((set, resolve, read)) = &queries {
                enc.resolve_query_set(set, 0..2, resolve, 0);
                enc.copy_buffer_to_buffer(resolve, 0, read, 0, 16);
            }
            for (t, (b, row)) in targets.iter().zip(&readbacks).filter(|_| last) {
                enc.copy_texture_to_buffer(
                    wgpu::TexelCopyTextureInfo {
                        texture: t,
                        mip_level: 0,
                        origin: wgpu::Origin3d::ZERO,
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::TexelCopyBufferInfo {
                        buffer: b,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(*row),
                            rows_per_image: Some(h),
                        },
                    },
                    wgpu::Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                );
            }
            gpu.queue.submit([enc.finish()]);
        })?;
        gpu.wait()?;
        let wall = submitted.elapsed();
        let frame_time = match &queries {
            Some((_, _, read)) => {
                let bytes = gpu.read_buffer(read)?;
                let t: &[u64] = bytemuck::cast_slice(&bytes);
                let ns = t[1].saturating_sub(t[0]) as f64 * gpu.queue.get_timestamp_period() as f64;
                if ns > 0.0 {
                    Duration::from_nanos(ns as u64)
                } else {
                    from_timestamps = false;
                    wall
                }
            }
            None => {
                from_timestamps = false;
                wall
            }
        };
        times.push(frame_time);
    }
    let frame = {
        let mut sorted = times.clone();
        sorted.sort();
        sorted[sorted.len() / 2]
    };

    let read_start = Instant::now();
    let mut planes = Vec::new();
    for (f, (b, row)) in formats.iter().zip(&readbacks) {
        let bytes = gpu.read_buffer(b)?;
        let bpp = f.block_copy_size(None).unwrap_or(4) as usize;
        let mut out = Vec::with_capacity(w as usize * h as usize * bpp);
        for y in 0..h as usize {
            let start = y * *row as usize;
            out.extend_from_slice(&bytes[start..start + w as usize * bpp]);
        }
        planes.push(out);
    }
    let readback = read_start.elapsed();
    let half = formats[1] == wgpu::TextureFormat::Rgba16Float;
    let floats = |bytes: &[u8]| -> Vec<[f32; 4]> {
        if half {
            bytes
                .chunks_exact(8)
                .map(|c| {
                    std::array::from_fn(|k| {
                        f16_to_f32(u16::from_le_bytes([c[2 * k], c[2 * k + 1]]))
                    })
                })
                .collect()
        } else {
            bytes
                .chunks_exact(16)
                .map(|c| {
                    std::array::from_fn(|k| {
                        f32::from_le_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]])
                    })
                })
                .collect()
        }
    };
    let frame = Frame {
        width: w,
        height: h,
        position: floats(&planes[1]),
        normal: floats(&planes[2]),
        atlas: floats(&planes[3]),
        color: std::mem::take(&mut planes[0]),
        timings: Timings {
            pipeline: pipeline_time,
            frame,
            frame_from_timestamps: from_timestamps,
            readback,
        },
    };
    Ok((frame, times))
}

#[cfg(test)]
mod tests {
    use super::f16_to_f32;

    #[test]
    fn half_floats_convert_exactly() {
        for (bits, value) in [
            (0x3C00u16, 1.0f32),
            (0xC000, -2.0),
            (0x3800, 0.5),
            (0x7BFF, 65504.0),
            (0x0000, 0.0),
            (0x0001, 5.960_464_5e-8),
            (0x0400, 6.103_515_6e-5),
            (0x3555, 0.333_251_95),
        ] {
            assert_eq!(f16_to_f32(bits), value, "{bits:#06x}");
        }
        assert!(f16_to_f32(0x7C00).is_infinite());
        assert!(f16_to_f32(0x7E00).is_nan());
    }
}
