//! Headless rendering: the generated fragment shader into an offscreen target,
//! read back with its AOVs (position + depth, normal + steps).

use super::render_pipeline::{built_variant, formats, pipeline, Variant};
use super::scene_group::{self, Stage};
use super::texture::{load_texture, sampler};
use super::{Gpu, GpuError};
use crate::codegen::bindings::RENDER_GROUP;
use crate::codegen::views::FROM_GLOBALS;
use crate::codegen::Module;
use crate::view::View;
use std::path::Path;
use std::time::{Duration, Instant};

pub use super::frame::{eval_stats, walked_stats, Frame, Timings, ViewMode};

/// The values a document's scene gives its module (the manifest's `scene`): the
/// `Globals` block of its view in the colour view, and the rendered shape's bounds;
/// `None` when the scene has errors or names no such shape.
pub fn scene_values(
    analysis: &crate::driver::Analysis,
    shape: Option<&str>,
) -> Option<crate::codegen::SceneValues> {
    let view = View::of(analysis, shape).ok()?;
    let target = crate::driver::pick_shape(analysis.scene.as_ref()?, shape).ok()?;
    let b = target.framing_bounds();
    let finite = |v: glam::DVec3| {
        v.clamp(glam::DVec3::splat(-1e30), glam::DVec3::splat(1e30))
            .to_array()
    };
    Some(crate::codegen::SceneValues {
        globals: globals(&view, ViewMode::Color).to_vec(),
        bounds: [finite(b.min), finite(b.max)],
    })
}

/// The `Globals` uniform block of `view` in view `mode`, laid out as in
/// `shaders/render.wgsl` (the manifest's `globals` say what each field holds): what a
/// host uploads to binding 0 to draw the module as `sdfc render` does.
pub fn globals(view: &View, mode: ViewMode) -> [[f32; 4]; 9] {
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
    module: &Module,
    view: &View,
    mode: ViewMode,
    base_dir: &Path,
) -> Result<Frame, GpuError> {
    render_timed(gpu, module, view, mode, base_dir, 0)
}

/// [`render`] after `warmup` untimed frames (drivers may compile shaders at first use).
pub fn render_timed(
    gpu: &Gpu,
    module: &Module,
    view: &View,
    mode: ViewMode,
    base_dir: &Path,
    warmup: u32,
) -> Result<Frame, GpuError> {
    let renderer = Renderer::new_for(gpu, module, base_dir, (mode, view.atlas_aov))?;
    renderer.frames(gpu, view, mode, warmup, 1).map(|(f, _)| f)
}

/// A generated module's render pipeline with its textures, built once and used for
/// any number of frames, views and sizes (`sdfc render`, `sdfc bench`, the tests).
pub struct Renderer {
    /// The pipeline of the variant [`Renderer::new_for`] was asked for (with per-tile
    /// culling, for frames where no tile's list is too long: `codegen::tiles::CROWDED`
    /// false), built with the renderer; `others` holds the variants built since, each
    /// at the first frame that needed it.
    pipeline: wgpu::RenderPipeline,
    first: Variant,
    others: std::sync::Mutex<std::collections::HashMap<Variant, wgpu::RenderPipeline>>,
    /// The module's WGSL, for the pipelines built after the first.
    wgsl: String,
    /// What the binding table of the manifest binds, slot by slot.
    bindings: Vec<crate::codegen::Binding>,
    /// The render group's layout, from the binding table.
    layout: wgpu::BindGroupLayout,
    textures: Vec<(wgpu::TextureView, wgpu::Sampler)>,
    /// The module's `tables` storage buffer, when it has one.
    tables: Option<wgpu::Buffer>,
    /// The run-time parameters' block, when the module has one ([`Renderer::set_params`]).
    params: Option<wgpu::Buffer>,
    /// The moving atlases' last tables ([`Renderer::set_param_values`]).
    moving: scene_group::MovingTables,
    /// The traced groups binned into screen tiles every frame (`gpu::tiles`), for a
    /// module generated with `Options::tiles` that has some.
    tiling: Option<crate::codegen::tiles::Tiling>,
    /// The multi-scale atlas pass, for a module generated with `Options::multiscale`
    /// that has one, and whether frames run it ([`Renderer::set_multiscale`]).
    coarse: Option<super::coarse::CoarsePass>,
    multiscale: std::sync::atomic::AtomicBool,
    /// `set_views_from_globals`: one pipeline, the view read from the globals.
    views_from_globals: std::sync::atomic::AtomicBool,
    formats: [wgpu::TextureFormat; 4],
    /// The time the pipeline took to create (or to find in the device's cache).
    pub pipeline_time: Duration,
    /// Whether the pipeline came from the device's cache (`gpu::cache`).
    pub pipeline_cached: bool,
}

/// The offscreen targets of one frame size and their readback buffers.
pub struct Targets {
    width: u32,
    height: u32,
    textures: Vec<wgpu::Texture>,
    pub(super) views: Vec<wgpu::TextureView>,
    /// Each target's buffer and its padded row length in bytes.
    readbacks: Vec<(wgpu::Buffer, u32)>,
}

/// What one frame binds ([`Renderer::prepare`]).
struct Prepared {
    group: wgpu::BindGroup,
    /// The frame's pipeline where it is not the renderer's first (another view, or a
    /// tile's list too long).
    pipeline: Option<wgpu::RenderPipeline>,
    /// The screen tiles' timings and the coarse samples.
    timings: Timings,
    /// The frame's size where the multi-scale pass runs.
    coarse: Option<(u32, u32)>,
    /// Kept alive until the frame is drawn.
    _buffers: wgpu::Buffer,
}

/// The timestamp queries of the measured frames.
struct Queries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
}

impl Renderer {
    /// Loads the textures and creates the pipeline of the colour view without the atlas
    /// AOV (timed: `pipeline_time`).
    pub fn new(gpu: &Gpu, module: &Module, base_dir: &Path) -> Result<Renderer, GpuError> {
        Renderer::new_for(gpu, module, base_dir, (ViewMode::Color, false))
    }

    /// [`Renderer::new`] with the pipeline of view `first.0`, with the atlas AOV where
    /// `first.1` (pipeline constants: `codegen::views`); other views get their pipelines
    /// at their first frame.
    pub fn new_for(
        gpu: &Gpu,
        module: &Module,
        base_dir: &Path,
        first: (ViewMode, bool),
    ) -> Result<Renderer, GpuError> {
        let formats = formats(gpu);
        let textures = module
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
            .collect::<Result<_, GpuError>>()?;
        let tables = scene_group::tables(gpu, module)?;
        let params = scene_group::params(gpu, module)?;
        let bindings = module.manifest.bindings.clone();
        let started = Instant::now();
        // With tiles, frames without a crowded tile compile the whole-scene paths away.
        let first = Variant {
            view: first.0.index() as i32,
            atlas_aov: i32::from(first.1),
            crowded: false,
        };
        let constants = first.constants(module.tiling.is_some());
        let key = super::cache::key("render", (&bindings, formats, &constants), &module.wgsl);
        let ((pipeline, layout, coarse), pipeline_cached) =
            gpu.pipelines.get_or_try(gpu.disk.as_ref(), key, || {
                gpu.scoped(|| {
                    let layout = scene_group::layout(&gpu.device, &bindings, Stage::Render);
                    let cache = gpu.disk.as_ref().map(|d| &d.cache);
                    let pipeline = pipeline(
                        &gpu.device,
                        (&module.wgsl, &constants),
                        &layout,
                        &formats,
                        cache,
                    );
                    let coarse =
                        super::coarse::CoarsePass::new(&gpu.device, module, &layout, cache);
                    (pipeline, layout, coarse)
                })
            })?;
        gpu.wait()?;
        Ok(Renderer {
            pipeline,
            first,
            others: Default::default(),
            wgsl: module.wgsl.clone(),
            bindings,
            layout,
            textures,
            tables,
            params,
            moving: Default::default(),
            tiling: module.tiling.clone(),
            coarse,
            multiscale: std::sync::atomic::AtomicBool::new(true),
            views_from_globals: std::sync::atomic::AtomicBool::new(false),
            formats,
            pipeline_time: started.elapsed(),
            pipeline_cached,
        })
    }

    /// Queues new values of the run-time parameters (the bytes of the manifest's
    /// `params` block, `ParamsLayout::bytes`) for the frames rendered after it: no new
    /// pipeline. Nothing to do for a module without parameters.
    pub fn set_params(&self, gpu: &Gpu, bytes: &[u8]) {
        if let Some(b) = &self.params {
            gpu.queue.write_buffer(b, 0, bytes);
        }
    }

    /// Queues the run-time parameters at `values` (by name; `None`: the module's
    /// default): their block and, when `module` (the one this renderer was made from)
    /// has atlases on moving shapes and the values changed, those atlases' geometry
    /// recomputed on the CPU reference and uploaded to the `tables` buffer. Returns the
    /// recomputation's time, if one ran. On an error the block is written and the
    /// atlases keep their last geometry.
    pub fn set_param_values(
        &self,
        gpu: &Gpu,
        module: &Module,
        values: crate::ir::dynamic::Values,
    ) -> Result<Option<Duration>, crate::codegen::MovingError> {
        let bytes = module.manifest.params.bytes(values);
        self.set_params(gpu, &bytes);
        let Some((words, took)) = self.moving.update(module, values)? else {
            return Ok(None);
        };
        if let Some(t) = &self.tables {
            gpu.queue.write_buffer(t, 0, bytemuck::cast_slice(&words));
        }
        Ok(Some(took))
    }

    /// Whether the frames drawn after this run the multi-scale atlas pass (on by
    /// default, for a module that has it): off, every atlas sample walks, with the same
    /// pipeline (the baseline the tests and `sdfc bench` compare the pass with).
    pub fn set_multiscale(&self, on: bool) {
        self.multiscale
            .store(on, std::sync::atomic::Ordering::Relaxed);
    }

    /// Whether the frames drawn after this use one pipeline for every view, built with
    /// the view constants' defaults (the view and the atlas AOV switch read from the
    /// globals, as a host that sets no constant draws: `codegen::views`) instead of a
    /// pipeline per view (the default). For tests and comparisons.
    pub fn set_views_from_globals(&self, on: bool) {
        self.views_from_globals
            .store(on, std::sync::atomic::Ordering::Relaxed);
    }

    /// Whether the module has the multi-scale atlas pass.
    pub fn has_multiscale(&self) -> bool {
        self.coarse.is_some()
    }

    /// A frame's globals, screen tiles and coarse samples, and the bind group of them:
    /// with the tiles' timings and whether the multi-scale pass runs.
    fn prepare(&self, gpu: &Gpu, view: &View, mode: ViewMode) -> Result<Prepared, GpuError> {
        use wgpu::util::DeviceExt;
        let d = &gpu.device;
        let uniforms = globals(view, mode);
        let globals = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("globals"),
            contents: bytemuck::cast_slice(&uniforms),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let tiles = self.tiles(gpu, view);
        let size = (view.width.max(1), view.height.max(1));
        let on = self.multiscale.load(std::sync::atomic::Ordering::Relaxed);
        let coarse = self
            .coarse
            .as_ref()
            .map(|c| c.buffer(d, size.0, size.1, on));
        let with = scene_group::Resources {
            images: &self.textures,
            tables: self.tables.as_ref(),
            globals: Some(&globals),
            params: self.params.as_ref(),
            tiles: tiles.as_ref().map(|t| &t.0),
            coarse: coarse.as_ref().map(|c| &c.0),
        };
        let group = scene_group::group(d, &self.bindings, Stage::Render, &self.layout, &with)?;
        let mut timings = tiles.map(|t| t.1).unwrap_or_default();
        let from_globals = self
            .views_from_globals
            .load(std::sync::atomic::Ordering::Relaxed);
        let variant = Variant {
            view: if from_globals {
                FROM_GLOBALS
            } else {
                mode.index() as i32
            },
            atlas_aov: if from_globals {
                FROM_GLOBALS
            } else {
                i32::from(view.atlas_aov)
            },
            crowded: timings.tiles_whole > 0,
        };
        let pipeline = if variant == self.first {
            None
        } else {
            let started = Instant::now();
            let (pipeline, built) = self.variant_pipeline(gpu, variant)?;
            timings.pipeline_built = built.then(|| started.elapsed());
            Some(pipeline)
        };
        let coarse = coarse.is_some_and(|c| c.1);
        if coarse {
            timings.coarse_samples = super::coarse::samples(size.0, size.1);
        }
        Ok(Prepared {
            group,
            pipeline,
            timings,
            coarse: coarse.then_some(size),
            _buffers: globals,
        })
    }

    /// The pipeline of `variant` (another view, or the whole-scene paths of crowded
    /// tiles), built the first time a frame needs it (its time is not in
    /// `pipeline_time`: the frame's timings have it), and whether this call built it.
    fn variant_pipeline(
        &self,
        gpu: &Gpu,
        variant: Variant,
    ) -> Result<(wgpu::RenderPipeline, bool), GpuError> {
        let mut built = self.others.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = built.get(&variant) {
            return Ok((p.clone(), false));
        }
        let constants = variant.constants(self.tiling.is_some());
        let p = built_variant(
            gpu,
            (&self.wgsl, &constants),
            (&self.bindings, &self.layout),
            &self.formats,
        )?;
        gpu.wait()?;
        built.insert(variant, p.clone());
        Ok((p, true))
    }

    /// The screen tiles of a frame of `view` (`gpu::tiles`) in a new buffer, with the
    /// time the binning took and what it holds; `None` for a module without tiles.
    fn tiles(&self, gpu: &Gpu, view: &View) -> Option<(wgpu::Buffer, Timings)> {
        use wgpu::util::DeviceExt;
        let tiling = self.tiling.as_ref()?;
        let started = Instant::now();
        let binned = super::tiles::bin(tiling, view);
        let took = started.elapsed();
        let buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("tiles"),
                contents: bytemuck::cast_slice(&binned.words),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let timings = Timings {
            tiles: took,
            tile_leaves: binned.leaves,
            tiles_whole: binned.whole,
            ..Default::default()
        };
        Some((buffer, timings))
    }

    fn targets(&self, gpu: &Gpu, width: u32, height: u32) -> Targets {
        targets(gpu, &self.formats, width, height)
    }

    /// The multi-scale pass where the frame runs it, then one full-screen pass into
    /// every target; timed from the first pass's start to the last's end.
    fn draw(
        &self,
        enc: &mut wgpu::CommandEncoder,
        targets: &Targets,
        frame: &Prepared,
        queries: Option<&wgpu::QuerySet>,
    ) {
        let mut timestamps = queries.map(|q| wgpu::RenderPassTimestampWrites {
            query_set: q,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        });
        if let (Some(pass), Some(size)) = (&self.coarse, frame.coarse) {
            let writes = queries.map(|q| wgpu::ComputePassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(0),
                end_of_pass_write_index: None,
            });
            pass.dispatch(enc, &frame.group, size, writes);
            if let Some(t) = &mut timestamps {
                t.beginning_of_pass_write_index = None;
            }
        }
        let bind_group = &frame.group;
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = targets
            .views
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
        pass.set_pipeline(frame.pipeline.as_ref().unwrap_or(&self.pipeline));
        pass.set_bind_group(RENDER_GROUP, bind_group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// `warmup` untimed frames, then `repeats` timed ones on this pipeline: returns the
    /// last frame (its `timings.frame` is the median) and every frame time, in order.
    /// Only the last frame is read back.
    pub fn frames(
        &self,
        gpu: &Gpu,
        view: &View,
        mode: ViewMode,
        warmup: u32,
        repeats: u32,
    ) -> Result<(Frame, Vec<Duration>), GpuError> {
        let d = &gpu.device;
        let (w, h) = (view.width.max(1), view.height.max(1));
        // Targets and their readback on the GPU, and the frame on the CPU.
        gpu.check_size(w, h, bytes_per_texel(&self.formats))?;
        let (targets, prepared, queries) = gpu.scoped(|| {
            (
                self.targets(gpu, w, h),
                self.prepare(gpu, view, mode),
                queries(gpu),
            )
        })?;
        let prepared = prepared?;
        for _ in 0..warmup {
            gpu.scoped(|| {
                let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("warm-up"),
                });
                self.draw(&mut enc, &targets, &prepared, None);
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
                self.draw(
                    &mut enc,
                    &targets,
                    &prepared,
                    queries.as_ref().map(|q| &q.set),
                );
                if let Some(q) = &queries {
                    enc.resolve_query_set(&q.set, 0..2, &q.resolve, 0);
                    enc.copy_buffer_to_buffer(&q.resolve, 0, &q.read, 0, 16);
                }
                if last {
                    copy_out(&mut enc, &targets);
                }
                gpu.queue.submit([enc.finish()]);
            })?;
            gpu.wait()?;
            let wall = submitted.elapsed();
            let measured = match &queries {
                Some(q) => gpu_time(gpu, &q.read)?,
                None => None,
            };
            from_timestamps &= measured.is_some();
            times.push(measured.unwrap_or(wall));
        }
        let mut sorted = times.clone();
        sorted.sort();
        let median = sorted[sorted.len() / 2];
        let mut frame = self.read(gpu, &targets)?;
        // The preparation's timings (tiles, coarse samples, another pipeline's build),
        // with the pipeline's, the frame's and the readback's.
        frame.timings = Timings {
            pipeline: self.pipeline_time,
            frame: median,
            frame_from_timestamps: from_timestamps,
            readback: frame.timings.readback,
            ..prepared.timings
        };
        Ok((frame, times))
    }

    /// Reads the targets back into a frame (timed: `timings.readback`).
    fn read(&self, gpu: &Gpu, targets: &Targets) -> Result<Frame, GpuError> {
        read(gpu, &self.formats, targets)
    }

    /// Copies the targets of the last [`Renderer::draw_into`] out and reads them back.
    pub fn read_back(&self, gpu: &Gpu, targets: &Targets) -> Result<Frame, GpuError> {
        gpu.scoped(|| {
            let mut enc = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("read back"),
                });
            copy_out(&mut enc, targets);
            gpu.queue.submit([enc.finish()]);
        })?;
        self.read(gpu, targets)
    }

    /// Targets of one frame size for [`Renderer::draw_into`] (the viewer's: drawn, then
    /// shown in a window).
    pub fn new_targets(&self, gpu: &Gpu, width: u32, height: u32) -> Result<Targets, GpuError> {
        gpu.check_size(width, height, bytes_per_texel(&self.formats))?;
        gpu.scoped(|| self.targets(gpu, width, height))
    }

    /// Draws one frame of `view` into `targets` (of `view`'s size) and waits for it:
    /// returns the submit-to-complete time, which includes binning the screen tiles
    /// (`gpu::tiles`) but not the build of a pipeline this frame was the first to need
    /// (another view, crowded tiles), and that build's time. Nothing is read back.
    pub fn draw_into(
        &self,
        gpu: &Gpu,
        view: &View,
        mode: ViewMode,
        targets: &Targets,
    ) -> Result<(Duration, Option<Duration>), GpuError> {
        let started = Instant::now();
        let mut built = None;
        gpu.scoped(|| {
            let prepared = self.prepare(gpu, view, mode)?;
            built = prepared.timings.pipeline_built;
            let mut enc = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("frame"),
                });
            self.draw(&mut enc, targets, &prepared, None);
            gpu.queue.submit([enc.finish()]);
            Ok::<_, GpuError>(())
        })??;
        gpu.wait()?;
        Ok((
            started.elapsed().saturating_sub(built.unwrap_or_default()),
            built,
        ))
    }
}

impl Targets {
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The sRGB colour target.
    pub fn color(&self) -> &wgpu::TextureView {
        &self.views[0]
    }
}

pub(super) fn extent(width: u32, height: u32) -> wgpu::Extent3d {
    wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    }
}

/// The bytes per texel of targets of `formats` with their readback, and of the frame
/// on the CPU.
pub(super) fn bytes_per_texel(formats: &[wgpu::TextureFormat; 4]) -> u64 {
    formats
        .iter()
        .map(|f| 2 * f.block_copy_size(None).unwrap_or(16) as u64)
        .sum::<u64>()
        + 52
}

/// Offscreen targets of `formats` and their readback buffers.
pub(super) fn targets(
    gpu: &Gpu,
    formats: &[wgpu::TextureFormat; 4],
    width: u32,
    height: u32,
) -> Targets {
    let d = &gpu.device;
    let textures: Vec<wgpu::Texture> = formats
        .iter()
        .map(|f| {
            d.create_texture(&wgpu::TextureDescriptor {
                label: Some("target"),
                size: extent(width, height),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: *f,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        })
        .collect();
    let views = textures
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let readbacks = formats
        .iter()
        .map(|f| {
            let row = (width * f.block_copy_size(None).unwrap_or(4)).div_ceil(256) * 256;
            let buffer = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: (row * height) as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (buffer, row)
        })
        .collect();
    Targets {
        width,
        height,
        textures,
        views,
        readbacks,
    }
}

/// Reads the targets back into a frame (timed: `timings.readback`).
pub(super) fn read(
    gpu: &Gpu,
    formats: &[wgpu::TextureFormat; 4],
    targets: &Targets,
) -> Result<Frame, GpuError> {
    let (w, h) = (targets.width, targets.height);
    let read_start = Instant::now();
    let mut planes = Vec::new();
    for (f, (b, row)) in formats.iter().zip(&targets.readbacks) {
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
    Ok(Frame {
        width: w,
        height: h,
        position: floats(&planes[1], half),
        normal: floats(&planes[2], half),
        atlas: floats(&planes[3], half),
        color: std::mem::take(&mut planes[0]),
        timings: Timings {
            readback,
            ..Default::default()
        },
    })
}

/// Timestamp queries, where the adapter has them.
fn queries(gpu: &Gpu) -> Option<Queries> {
    let d = &gpu.device;
    gpu.timestamps.then(|| {
        let buffer = |usage| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage,
                mapped_at_creation: false,
            })
        };
        Queries {
            set: d.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("frame"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolve: buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
            read: buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST),
        }
    })
}

/// The GPU time between the two timestamps, when the adapter measured one.
fn gpu_time(gpu: &Gpu, read: &wgpu::Buffer) -> Result<Option<Duration>, GpuError> {
    let bytes = gpu.read_buffer(read)?;
    let t: &[u64] = bytemuck::cast_slice(&bytes);
    let ns = t[1].saturating_sub(t[0]) as f64 * gpu.queue.get_timestamp_period() as f64;
    Ok((ns > 0.0).then(|| Duration::from_nanos(ns as u64)))
}

/// Copies every target into its readback buffer.
pub(super) fn copy_out(enc: &mut wgpu::CommandEncoder, targets: &Targets) {
    for (t, (b, row)) in targets.textures.iter().zip(&targets.readbacks) {
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
                    rows_per_image: Some(targets.height),
                },
            },
            extent(targets.width, targets.height),
        );
    }
}

/// RGBA texels of 32-bit floats (or their bits, `rgba32uint`) or (`half`) 16-bit floats.
fn floats(bytes: &[u8], half: bool) -> Vec<[f32; 4]> {
    if half {
        bytes
            .chunks_exact(8)
            .map(|c| {
                std::array::from_fn(|k| f16_to_f32(u16::from_le_bytes([c[2 * k], c[2 * k + 1]])))
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
