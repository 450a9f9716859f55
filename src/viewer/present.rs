//! The window's surface: the renderer's colour target drawn into it by a one-triangle
//! pass (`shaders/blit.wgsl`), and read back from it for screenshots where the surface
//! allows copies.

use crate::gpu::{Gpu, GpuError, Targets};

/// The presentation shader (a library file that naga validates in the tests).
pub const BLIT: &str = include_str!("../../shaders/blit.wgsl");

pub struct Presenter {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The sRGB format the pass writes (the surface's, or its sRGB view).
    view_format: wgpu::TextureFormat,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    nearest: wgpu::Sampler,
    linear: wgpu::Sampler,
    /// Whether the surface's textures can be copied out (screenshots of the window itself).
    copy_src: bool,
}

/// A screenshot: RGBA8, sRGB-encoded, row-major from the top-left.
pub struct Shot {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    /// Whether it was read from the window's surface (else from the renderer's target).
    pub from_surface: bool,
}

impl Presenter {
    pub fn new(
        gpu: &Gpu,
        surface: wgpu::Surface<'static>,
        width: u32,
        height: u32,
    ) -> Result<Presenter, GpuError> {
        let caps = surface.get_capabilities(&gpu.adapter);
        // 8-bit formats whose sRGB view the pass can write; the first the surface lists.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f.remove_srgb_suffix(),
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .ok_or_else(|| {
                GpuError::Device(format!(
                    "the window's surface offers no 8-bit RGBA or BGRA format ({:?})",
                    caps.formats
                ))
            })?;
        let view_format = format.add_srgb_suffix();
        let copy_src = caps.usages.contains(wgpu::TextureUsages::COPY_SRC);
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if copy_src {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        let config = wgpu::SurfaceConfiguration {
            usage,
            format,
            color_space: Default::default(),
            width: width.max(1),
            height: height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 1,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: if view_format == format {
                Vec::new()
            } else {
                vec![view_format]
            },
        };
        let d = &gpu.device;
        let (pipeline, layout, nearest, linear) = gpu.scoped(|| {
            surface.configure(d, &config);
            let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("blit"),
                source: wgpu::ShaderSource::Wgsl(BLIT.into()),
            });
            let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("blit"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: true },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 1,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                        count: None,
                    },
                ],
            });
            let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("blit"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("blit"),
                layout: Some(&pipeline_layout),
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
                    targets: &[Some(wgpu::ColorTargetState {
                        format: view_format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            let sampler = |filter| {
                d.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("blit"),
                    mag_filter: filter,
                    min_filter: filter,
                    ..Default::default()
                })
            };
            (
                pipeline,
                layout,
                sampler(wgpu::FilterMode::Nearest),
                sampler(wgpu::FilterMode::Linear),
            )
        })?;
        Ok(Presenter {
            surface,
            config,
            view_format,
            pipeline,
            layout,
            nearest,
            linear,
            copy_src,
        })
    }

    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Follows the window's size.
    pub fn resize(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<(), GpuError> {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        gpu.scoped(|| self.surface.configure(&gpu.device, &self.config))
    }

    /// The format the picture is drawn in (the surface's sRGB view).
    pub fn view_format(&self) -> wgpu::TextureFormat {
        self.view_format
    }

    /// Shows `targets`' colour (stretched, smoothly when it is at a reduced resolution),
    /// then `overlay` over it (the panel), and, with `capture`, returns what was shown
    /// before the overlay: read from the surface where it allows copies, else from the
    /// colour target (the same pixels at full resolution). `None` when nothing could be
    /// shown this time (the surface was outdated, lost, hidden or busy); `Some(None)`
    /// when shown without a capture.
    pub fn present(
        &mut self,
        gpu: &Gpu,
        renderer: &crate::gpu::Renderer,
        targets: &Targets,
        capture: bool,
        overlay: &mut dyn FnMut(&mut wgpu::CommandEncoder, &wgpu::TextureView, (u32, u32)),
    ) -> Result<Option<Option<Shot>>, GpuError> {
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.resize(gpu, self.config.width, self.config.height)?;
                return Ok(None);
            }
            // Hidden or busy: nothing to show this time.
            _ => return Ok(None),
        };
        let full = targets.size() == self.size();
        let d = &gpu.device;
        let (w, h) = self.size();
        let row = (w * 4).div_ceil(256) * 256;
        let from_surface = capture && full && self.copy_src;
        let readback = gpu.scoped(|| {
            let view = texture.texture.create_view(&wgpu::TextureViewDescriptor {
                format: Some(self.view_format),
                ..Default::default()
            });
            let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("blit"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(targets.color()),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::Sampler(if full {
                            &self.nearest
                        } else {
                            &self.linear
                        }),
                    },
                ],
            });
            let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("present"),
            });
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("present"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.draw(0..3, 0..1);
            }
            let readback = from_surface.then(|| {
                let buffer = d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("screenshot"),
                    size: (row * h) as u64,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                enc.copy_texture_to_buffer(
                    wgpu::TexelCopyTextureInfo {
                        texture: &texture.texture,
                        mip_level: 0,
                        origin: wgpu::Origin3d::ZERO,
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::TexelCopyBufferInfo {
                        buffer: &buffer,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(row),
                            rows_per_image: Some(h),
                        },
                    },
                    wgpu::Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                );
                buffer
            });
            // Drawn after the screenshot's copy: screenshots hold the scene only.
            overlay(&mut enc, &view, (w, h));
            gpu.queue.submit([enc.finish()]);
            readback
        })?;
        gpu.queue.present(texture);
        if !capture {
            return Ok(Some(None));
        }
        let shot = match readback {
            Some(buffer) => {
                let bytes = gpu.read_buffer(&buffer)?;
                let bgra =
                    self.config.format.remove_srgb_suffix() == wgpu::TextureFormat::Bgra8Unorm;
                let mut rgba = Vec::with_capacity((w * h * 4) as usize);
                for y in 0..h as usize {
                    for px in bytes[y * row as usize..][..w as usize * 4].chunks_exact(4) {
                        if bgra {
                            rgba.extend_from_slice(&[px[2], px[1], px[0], 255]);
                        } else {
                            rgba.extend_from_slice(&[px[0], px[1], px[2], 255]);
                        }
                    }
                }
                Shot {
                    width: w,
                    height: h,
                    rgba,
                    from_surface: true,
                }
            }
            None => {
                let frame = renderer.read_back(gpu, targets)?;
                Shot {
                    width: frame.width,
                    height: frame.height,
                    rgba: frame.color,
                    from_surface: false,
                }
            }
        };
        Ok(Some(Some(shot)))
    }
}
