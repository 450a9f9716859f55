//! The wgpu runtime: adapters, headless rendering with readback, and compute
//! queries. Every fallible wgpu call runs inside an error scope, so a device
//! error becomes a [`GpuError`], never a panic.

mod atlas_textures;
pub mod cache;
pub mod coarse;
pub mod compute;
pub mod embed;
pub mod frame;
mod mesh;
pub mod overdraw;
mod render;
mod render_pipeline;
pub mod scene_group;
pub mod texture;
pub mod tiles;

pub use atlas_textures::generic_mips;
pub use compute::{
    eval_atlas, eval_materials, eval_points, eval_points_textured, AtlasValue, MaterialSample,
};
pub use mesh::{check_layout, mesh_bounds, MeshError, MeshFilter, MeshRenderer};
pub use render::{
    eval_stats, globals, render, render_timed, scene_values, walked_stats, Frame, Renderer,
    Targets, Timings, ViewMode,
};

use std::fmt;
use std::sync::Arc;

crate::choice::choice_enum! {
    /// Which graphics API to use.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Backend {
        Auto = "auto": "The best available adapter.",
        Vulkan = "vulkan": "Vulkan (Mesa's lavapipe where there is no GPU).",
        Gl = "gl": "OpenGL through EGL, desktop GL or GL ES (Mesa's llvmpipe where there is no GPU).",
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum GpuError {
    /// No adapter at all.
    NoAdapter(String),
    /// The adapter would not give a device.
    Device(String),
    /// wgpu reported a validation error.
    Validation(String),
    /// Out of memory, or a size over the adapter's or sdfc's limits; the message names
    /// the limit.
    Resource(String),
    /// A texture file could not be read.
    Texture(String),
}

impl fmt::Display for GpuError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            GpuError::NoAdapter(why) => write!(
                f,
                "no GPU adapter is available ({why}).\n  On Debian or Ubuntu, install Mesa's drivers, which include software adapters:\n      apt-get install mesa-vulkan-drivers libgl1-mesa-dri"
            ),
            GpuError::Device(e) => write!(f, "the GPU adapter could not open a device: {e}"),
            GpuError::Validation(e) => write!(f, "the GPU rejected a command: {e}"),
            GpuError::Resource(e) => write!(f, "{e}"),
            GpuError::Texture(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for GpuError {}

/// The most GPU memory one frame's targets and readback may take, in bytes.
pub const MAX_FRAME_BYTES: u64 = 4 << 30;

/// An open device.
pub struct Gpu {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Whether GPU timestamps are available for frame timing.
    pub timestamps: bool,
    /// The pipelines built on this device, by what they were built from.
    pub pipelines: cache::Pipelines,
    /// wgpu's pipeline cache, kept on disk (`SDFC_PIPELINE_CACHE`; Vulkan only).
    pub disk: Option<cache::Disk>,
}

impl Gpu {
    /// Opens the best adapter of the requested kind.
    pub fn new(backend: Backend) -> Result<Gpu, GpuError> {
        let desc = wgpu::InstanceDescriptor::new_without_display_handle();
        let instance = wgpu::Instance::new(Self::descriptor(desc, backend));
        Self::open(&instance, None)
    }

    /// Opens the best adapter of the requested kind that can present to a window, with
    /// the window's surface (`sdfc view`). `display` is the windowing system's
    /// connection (winit's `OwnedDisplayHandle`), which GL needs.
    pub fn with_surface(
        backend: Backend,
        display: Box<dyn wgpu::wgt::WgpuHasDisplayHandle>,
        window: impl Into<wgpu::SurfaceTarget<'static>>,
    ) -> Result<(Gpu, wgpu::Surface<'static>), GpuError> {
        let desc = wgpu::InstanceDescriptor::new_with_display_handle(display);
        let instance = wgpu::Instance::new(Self::descriptor(desc, backend));
        let surface = instance
            .create_surface(window)
            .map_err(|e| GpuError::NoAdapter(format!("no surface for the window: {e}")))?;
        let gpu = Self::open(&instance, Some(&surface))?;
        Ok((gpu, surface))
    }

    fn descriptor(desc: wgpu::InstanceDescriptor, backend: Backend) -> wgpu::InstanceDescriptor {
        let mut desc = desc.with_env();
        match backend {
            Backend::Auto => {}
            Backend::Vulkan => desc.backends = wgpu::Backends::VULKAN,
            Backend::Gl => desc.backends = wgpu::Backends::GL,
        }
        desc
    }

    fn open(instance: &wgpu::Instance, surface: Option<&wgpu::Surface>) -> Result<Gpu, GpuError> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: surface,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut required_features = if timestamps {
            wgpu::Features::TIMESTAMP_QUERY
        } else {
            wgpu::Features::empty()
        };
        // The on-disk pipeline cache, when asked for and the backend has one.
        let disk_cache = std::env::var_os(cache::DISK_VAR).is_some_and(|d| !d.is_empty())
            && adapter.features().contains(wgpu::Features::PIPELINE_CACHE);
        if disk_cache {
            required_features |= wgpu::Features::PIPELINE_CACHE;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sdfc"),
            required_features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        // Errors outside a scope are reported, not turned into panics.
        device.on_uncaptured_error(Arc::new(|e| eprintln!("wgpu: {e}")));
        let info = adapter.get_info();
        let disk = cache::Disk::open(&device, &info, device.features());
        Ok(Gpu {
            adapter,
            device,
            queue,
            info,
            timestamps,
            pipelines: cache::Pipelines::default(),
            disk,
        })
    }

    /// Runs `f` inside validation and out-of-memory error scopes.
    pub fn scoped<T>(&self, f: impl FnOnce() -> T) -> Result<T, GpuError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        if let Some(e) = o {
            return Err(GpuError::Resource(format!(
                "the GPU ran out of memory: {e}"
            )));
        }
        match v {
            Some(e) => Err(GpuError::Validation(e.to_string())),
            None => Ok(out),
        }
    }

    /// Checks that a `width`×`height` image with `bytes_per_texel` bytes of targets and
    /// readback fits this device's limits and [`MAX_FRAME_BYTES`].
    pub fn check_size(
        &self,
        width: u32,
        height: u32,
        bytes_per_texel: u64,
    ) -> Result<(), GpuError> {
        let side = self.device.limits().max_texture_dimension_2d;
        if width > side || height > side {
            return Err(GpuError::Resource(format!(
                "the image is {width}×{height}; this GPU's limit is {side} texels a side"
            )));
        }
        let bytes = width as u64 * height as u64 * bytes_per_texel;
        let limit = MAX_FRAME_BYTES.min(self.device.limits().max_buffer_size.saturating_mul(4));
        if bytes > limit {
            return Err(GpuError::Resource(format!(
                "the image is {width}×{height}, which needs {} MiB of GPU memory; the limit is {} MiB",
                bytes >> 20,
                limit >> 20
            )));
        }
        Ok(())
    }

    /// Waits for all submitted work.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Device(e.to_string()))
    }

    /// Maps a readback buffer and copies its bytes out.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        let (tx, rx) = std::sync::mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| GpuError::Device(e.to_string()))?
            .map_err(|e| GpuError::Device(e.to_string()))?;
        let bytes = buffer
            .get_mapped_range(..)
            .map_err(|e| GpuError::Device(e.to_string()))?
            .to_vec();
        buffer.unmap();
        Ok(bytes)
    }

    /// Whether the adapter runs on the CPU (lavapipe, llvmpipe, SwiftShader, WARP).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The walk form that serves this adapter best, for `--walk auto`: the unrolled walk
    /// (the design's) on a GPU; a loop on a software adapter, where the unrolled form
    /// measured 1.6–3.7× slower a frame and 2–12× slower to build its pipeline
    /// (docs/performance.md, "What each lever gave": the walk form).
    pub fn preferred_walk(&self) -> crate::codegen::WalkForm {
        if self.is_software() {
            crate::codegen::WalkForm::Loop
        } else {
            crate::codegen::WalkForm::Unrolled
        }
    }

    /// A one-line description of the adapter.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }
}

crate::choice::choice_enum! {
/// `render --walk`: a walk form, or the adapter's best ([`Gpu::preferred_walk`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WalkChoice {
    Auto = "auto": "Unrolled on a GPU (the loop where the unrolled module is too large, E0118), a loop on a software adapter (lavapipe, llvmpipe, SwiftShader, WARP), where the unrolled walk is 1.6-3.7x slower a frame and 2-12x slower to build.",
    Unrolled = "unrolled": "N calls of the step, each with its constant N − i.",
    Loop = "loop": "A loop of N iterations.",
}
}

impl WalkChoice {
    /// The form on `gpu`: its [`Gpu::preferred_walk`] for `auto`.
    pub fn on(self, gpu: &Gpu) -> crate::codegen::WalkForm {
        match self {
            WalkChoice::Auto => gpu.preferred_walk(),
            other => other.first(),
        }
    }

    /// The form to compile before the adapter is known (`auto`: the loop, the smaller
    /// module, so that every error of the scene is reported before the adapter opens;
    /// a GPU then generates the unrolled walk again).
    pub fn first(self) -> crate::codegen::WalkForm {
        match self {
            WalkChoice::Loop | WalkChoice::Auto => crate::codegen::WalkForm::Loop,
            WalkChoice::Unrolled => crate::codegen::WalkForm::Unrolled,
        }
    }
}

crate::choice::choice_enum! {
/// `render --multiscale`: whether the render walks every pixel's atlas samples or runs
/// the multi-scale atlas pass (`codegen::coarse`), which walks one pixel in 4 × 4 and
/// rebuilds the others where those agree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MultiScale {
    Auto = "auto": "The pass, on every adapter: it measured 0.69-0.98x the per-pixel walk's frame time on a GPU and 0.54-1.08x on lavapipe (once the view became a pipeline constant), for up to twice the pipeline time.",
    On = "on": "The multi-scale pass.",
    Off = "off": "Every pixel walks its atlas samples.",
}
}

impl MultiScale {
    /// Whether the pass runs on `_gpu`: `auto` runs it on every adapter since it paid on
    /// lavapipe too (docs/performance.md); the adapter stays an argument, as for the
    /// walk's choice, so that a slower kind of adapter can be told apart again.
    pub fn on(self, _gpu: &Gpu) -> bool {
        self.first()
    }

    /// Whether the module compiled before the adapter is known has the pass: where the
    /// choice is `auto`, every adapter runs it.
    pub fn first(self) -> bool {
        self != MultiScale::Off
    }
}

crate::choice::choice_enum! {
/// `render --gradients`, `bench --seed-sweep --gradients`: how the walk takes the
/// field's gradient. `auto` is the forward derivative on every adapter: it measured as
/// fast as differences or faster on lavapipe too (docs/performance.md, "Forward
/// derivatives"), and on a GPU it saves five evaluations a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gradients {
    Auto = "auto": "The forward derivative where the compiler writes one, on every adapter (as fast as differences or faster on lavapipe, measured; five evaluations fewer a step anywhere).",
    Forward = "forward": "The forward derivative the compiler writes (one evaluation a step).",
    Differences = "differences": "Central differences of the field (six evaluations a step).",
}
}

impl Gradients {
    /// Whether the walk takes differences.
    pub fn differences(self) -> bool {
        match self {
            Gradients::Auto | Gradients::Forward => false,
            Gradients::Differences => true,
        }
    }
}

/// For tests: an open GPU, or `None` after saying loudly why the test is skipped.
/// With `SDFC_REQUIRE_GPU=1` a missing adapter is a failure instead.
pub fn gpu_for_tests() -> Option<Gpu> {
    match Gpu::new(Backend::Auto) {
        Ok(g) => Some(g),
        Err(e) => {
            if std::env::var("SDFC_REQUIRE_GPU").is_ok_and(|v| v == "1") {
                panic!("SDFC_REQUIRE_GPU=1 but {e}");
            }
            eprintln!("SKIPPING GPU TEST: {e}");
            None
        }
    }
}
