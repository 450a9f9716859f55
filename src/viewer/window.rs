//! The viewer's window (winit) and its event loop: camera, views, progressive
//! resolution, hot reload from a file watcher (notify), seed edits by mouse,
//! screenshots.

mod input;
mod panel;
mod params;

use super::edit::SeedEditor;

use super::present::{Presenter, Shot};
use super::reload::{Outcome, Reloader};
use super::{interactive_divisor, Orbit, VIEWS};
use crate::codegen;
use crate::gpu::{Backend, Gpu, Renderer, Targets, ViewMode};
use crate::view::View;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::ModifiersState;
use winit::window::{Window, WindowId};

/// What `sdfc view` was asked for.
#[derive(Debug, Clone)]
pub struct Options {
    pub scene: PathBuf,
    pub shape: Option<String>,
    pub backend: Backend,
    pub size: Option<(u32, u32)>,
    pub walk: codegen::WalkForm,
    /// The multi-scale atlas pass (`auto`: on a GPU).
    pub multiscale: crate::gpu::MultiScale,
    pub mode: ViewMode,
    /// Render this many frames, save the screenshot and quit (tests and scripts).
    pub frames: Option<u32>,
    pub screenshot: Option<PathBuf>,
    /// With `frames`: turn the camera by this many degrees a frame, as a drag would (a
    /// scripted orbit, to measure the frame times while the camera moves).
    pub spin: Option<f64>,
    /// The file access rules of the scene (its folder, and `--allow` ones).
    pub access: crate::access::Access,
}

/// Why the viewer could not run (the CLI turns it into an exit status).
#[derive(Debug)]
pub enum ViewError {
    /// No window could be opened (no display).
    Display(String),
    Gpu(crate::gpu::GpuError),
    /// The scene never built (its report was printed).
    Scene,
    Io(String),
}

impl std::fmt::Display for ViewError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            ViewError::Display(m) | ViewError::Io(m) => f.write_str(m),
            ViewError::Gpu(e) => write!(f, "{e}"),
            ViewError::Scene => f.write_str("the scene has errors"),
        }
    }
}

/// A change on disk, from the watcher thread.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Changed {
    Scene,
    Texture,
}

/// The window's time budget for a frame while the camera moves.
const INTERACTIVE_MS: f64 = 40.0;
/// The camera counts as still this long after the last wheel notch.
const SETTLE: Duration = Duration::from_millis(200);
/// File events closer than this are one change (an editor's save is several).
const DEBOUNCE: Duration = Duration::from_millis(60);
/// A click moves the cursor less than this (else it is a drag), in pixels.
const CLICK: f64 = 3.0;

/// The state of a mouse press.
#[derive(Debug, Clone)]
enum Drag {
    Orbit,
    Pan,
    /// Moving a seed: its atlas and name.
    Seed(String, String),
    /// Sweeping the selected run-time parameter (right button).
    Param,
}

struct App {
    options: Options,
    name: String,
    base_dir: PathBuf,
    reloader: Reloader<Renderer>,
    editor: SeedEditor,
    proxy: EventLoopProxy<Changed>,
    /// The watched files: the scene and its textures (canonical paths).
    watched: Vec<PathBuf>,
    watcher: Option<notify::RecommendedWatcher>,
    window: Option<Arc<Window>>,
    gpu: Option<Gpu>,
    presenter: Option<Presenter>,
    targets: Option<Targets>,
    orbit: Option<Orbit>,
    mode: usize,
    modifiers: ModifiersState,
    cursor: (f64, f64),
    pressed: Option<(MouseButton, (f64, f64), Drag)>,
    /// The camera is moving until then: frames are drawn at a reduced resolution.
    moving_until: Option<Instant>,
    /// The estimated time of a full-resolution frame, in milliseconds.
    full_ms: f64,
    last_frame_ms: f64,
    divisor: u32,
    /// The next frame is the first of a new pipeline.
    fresh: bool,
    /// The largest divisor used while moving (for the report).
    divisor_used: u32,
    pending: Option<(Instant, bool)>,
    /// A seed shift-clicked first, waiting for the second of a merge.
    merge_first: Option<(String, String)>,
    frames_drawn: u32,
    /// Frame times in milliseconds: at full resolution, and reduced while moving.
    times: (Vec<f64>, Vec<f64>),
    screenshot_next: bool,
    error: Option<ViewError>,
    /// The run-time parameters' values and `time` ([`params`]).
    params: params::Params,
    /// The panel of sliders drawn over the picture ([`panel`]).
    panel: Option<panel::Panel>,
}

/// Opens the window and runs until it is closed (or `frames` were drawn).
pub fn run(options: Options) -> Result<(), ViewError> {
    let event_loop = EventLoop::<Changed>::with_user_event()
        .build()
        .map_err(|e| ViewError::Display(format!("cannot open a window: {e}")))?;
    let name = options.scene.display().to_string();
    let base_dir = match options.scene.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let codegen_options = codegen::Options {
        walk: options.walk,
        tiles: true,
        // Decided with the adapter (`resumed`).
        multiscale: false,
        ..Default::default()
    };
    let mut app = App {
        reloader: Reloader::new(
            name.clone(),
            options.access.clone(),
            options.shape.clone(),
            codegen_options,
        ),
        editor: SeedEditor::new(&options.scene, options.access.clone()),
        proxy: event_loop.create_proxy(),
        mode: VIEWS
            .iter()
            .position(|(m, _)| *m == options.mode)
            .unwrap_or(0),
        options,
        name,
        base_dir,
        watched: Vec::new(),
        watcher: None,
        window: None,
        gpu: None,
        presenter: None,
        targets: None,
        orbit: None,
        modifiers: ModifiersState::empty(),
        cursor: (0.0, 0.0),
        pressed: None,
        moving_until: None,
        full_ms: 0.0,
        last_frame_ms: 0.0,
        divisor: 1,
        divisor_used: 1,
        fresh: true,
        pending: None,
        merge_first: None,
        frames_drawn: 0,
        times: (Vec::new(), Vec::new()),
        screenshot_next: false,
        params: params::Params::default(),
        panel: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewError::Display(format!("the window's event loop failed: {e}")))?;
    app.report_times();
    match app.error.take() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The median of some milliseconds.
fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

impl App {
    /// Prints the frame times the window measured (submit to complete, per frame).
    fn report_times(&self) {
        let (full, reduced) = &self.times;
        if full.is_empty() && reduced.is_empty() {
            return;
        }
        let size = self.presenter.as_ref().map_or((0, 0), |p| p.size());
        let mut line = format!(
            "frames: {} at {}x{}, median {:.1} ms",
            full.len(),
            size.0,
            size.1,
            median(full)
        );
        if !reduced.is_empty() {
            line.push_str(&format!(
                "; {} while moving, at reduced resolution (1/{} a side), median {:.1} ms",
                reduced.len(),
                self.divisor_used,
                median(reduced)
            ));
        }
        eprintln!("{line}");
    }

    fn say(&self, message: &str) {
        eprintln!("{message}");
    }

    /// The shape on screen with the environment of its heights (for picking).
    fn shape(&self) -> Option<crate::ir::Field<'_>> {
        let loaded = self.reloader.good.as_ref()?;
        let analysis = &loaded.doc.analysis;
        let scene = analysis.scene.as_ref()?;
        let shape = crate::driver::pick_shape(scene, self.options.shape.as_deref()).ok()?;
        Some(analysis.field(shape))
    }

    /// The view the loaded scene asks for (its `render` item; framed with `--shape`), as
    /// `sdfc render` resolves it.
    fn scene_view(&self) -> Option<View> {
        let loaded = self.reloader.good.as_ref()?;
        let render = match self.options.shape {
            Some(_) => None,
            None => loaded.doc.analysis.program.render.as_ref(),
        };
        Some(View::new(render, self.shape()?.shape))
    }

    /// The view of the loaded scene at the window's size, with the viewer's camera.
    fn view(&self) -> Option<View> {
        let shape = self.shape()?;
        let mut view = self.scene_view()?;
        let (w, h) = self.presenter.as_ref()?.size();
        view.width = w;
        view.height = h;
        if let Some(orbit) = &self.orbit {
            view.camera = orbit.camera();
            let b = shape.framing_bounds();
            let reach = (view.camera.eye - b.center()).length() + (b.max - b.min).length();
            view.far = view.far.max(reach * 2.0);
        }
        Some(view)
    }

    /// The scene's own camera as an orbit (what `R` returns to).
    fn scene_orbit(&self) -> Option<Orbit> {
        let shape = self.shape()?;
        let view = self.scene_view()?;
        Some(Orbit::from_camera(
            &view.camera,
            shape.framing_bounds().center(),
        ))
    }

    /// Reads the scene and reloads it; prints the outcome.
    fn reload(&mut self, force: bool) {
        let text = match std::fs::read(&self.options.scene) {
            Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
            Err(e) => {
                self.say(&format!("error: cannot read {}: {e}", self.name));
                return;
            }
        };
        self.reload_text(&text, force);
    }

    fn reload_text(&mut self, text: &str, force: bool) {
        let Some(gpu) = self.gpu.as_ref() else {
            return;
        };
        let base = self.base_dir.clone();
        let mut built = 0;
        // The pipeline of the view on screen (another view builds its own when shown).
        let first = (VIEWS[self.mode].0, false);
        let outcome = self.reloader.reload(text, force, |c| {
            built += 1;
            Renderer::new_for(gpu, &c.module, &base, first).map_err(|e| e.to_string())
        });
        self.params.pipelines += built;
        match outcome {
            Outcome::Unchanged => return,
            Outcome::Swapped => {
                let loaded = self.reloader.good.as_ref().expect("swapped in");
                let warnings = &loaded.doc.analysis.diagnostics;
                if !warnings.is_empty() {
                    eprint!(
                        "{}",
                        crate::diagnostic::render(&self.name, text, warnings, false)
                    );
                }
                eprintln!(
                    "loaded {}: compile {:.1} ms, pipeline {:.1} ms{}",
                    self.name,
                    loaded.compile_time.as_secs_f64() * 1e3,
                    loaded.pipeline.pipeline_time.as_secs_f64() * 1e3,
                    if loaded.pipeline.pipeline_cached {
                        " (cached)"
                    } else {
                        ""
                    }
                );
                if self.orbit.is_none() {
                    self.orbit = self.scene_orbit();
                }
                self.watch_textures();
                self.params_reloaded();
                self.fresh = true;
                self.merge_first = None;
            }
            Outcome::Failed(report) => {
                eprint!("{report}");
                eprintln!(
                    "{}: not reloaded; showing the last good version until the file is fixed",
                    self.name
                );
            }
        }
        self.update_title();
        self.request_redraw();
    }

    /// Watches the scene's folder and its textures' folders.
    fn watch_textures(&mut self) {
        // The scene is watched even before it first builds (the viewer waits for a fix).
        let Ok(scene) = std::fs::canonicalize(&self.options.scene) else {
            return;
        };
        let mut files = vec![scene.clone()];
        if let Some(loaded) = self.reloader.good.as_ref() {
            files.extend(
                loaded
                    .compiled
                    .module
                    .manifest
                    .textures
                    .iter()
                    .filter_map(|t| std::fs::canonicalize(self.base_dir.join(&t.path)).ok()),
            );
        }
        if files == self.watched && self.watcher.is_some() {
            return;
        }
        let proxy = self.proxy.clone();
        let scene = Some(scene);
        let textures: Vec<PathBuf> = files.iter().skip(1).cloned().collect();
        let handler = move |event: notify::Result<notify::Event>| {
            let Ok(event) = event else { return };
            if matches!(event.kind, notify::EventKind::Access(_)) {
                return;
            }
            for p in &event.paths {
                if Some(p) == scene.as_ref() {
                    let _ = proxy.send_event(Changed::Scene);
                } else if textures.contains(p) {
                    let _ = proxy.send_event(Changed::Texture);
                }
            }
        };
        use notify::Watcher;
        match notify::recommended_watcher(handler) {
            Ok(mut watcher) => {
                let mut dirs: Vec<&Path> = files.iter().filter_map(|f| f.parent()).collect();
                dirs.sort();
                dirs.dedup();
                for dir in dirs {
                    if let Err(e) = watcher.watch(dir, notify::RecursiveMode::NonRecursive) {
                        self.say(&format!("warning: cannot watch {}: {e}", dir.display()));
                    }
                }
                self.watcher = Some(watcher);
                self.watched = files;
            }
            Err(e) => self.say(&format!("warning: no hot reload: {e}")),
        }
    }

    fn request_redraw(&self) {
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }

    fn update_title(&self) {
        let Some(window) = &self.window else { return };
        let mut title = format!("sdfc view: {} [{}]", self.name, VIEWS[self.mode].1);
        if let Some(loaded) = &self.reloader.good {
            title.push_str(&format!(
                " frame {:.0} ms{} | compile {:.1} ms",
                self.last_frame_ms,
                if self.divisor > 1 {
                    format!(" (1/{} res)", self.divisor)
                } else {
                    String::new()
                },
                loaded.compile_time.as_secs_f64() * 1e3
            ));
        }
        if let Some(gpu) = &self.gpu {
            title.push_str(&format!(" | {}", gpu.info.name));
        }
        if self.reloader.stale.is_some() {
            title.push_str(" | STALE: the file has errors (see the terminal)");
        }
        window.set_title(&title);
    }

    fn moving(&self) -> bool {
        self.pressed
            .as_ref()
            .is_some_and(|(_, _, d)| !matches!(d, Drag::Seed(..)))
            || self.moving_until.is_some_and(|t| Instant::now() < t)
    }

    fn draw(&mut self) -> Result<(), ViewError> {
        let Some(full) = self.view() else {
            return Ok(());
        };
        self.run_panel();
        let scripted = self.options.frames.is_some();
        let moving =
            self.moving() && (!scripted || self.options.spin.is_some()) && !self.screenshot_next;
        self.divisor = if moving {
            interactive_divisor(self.full_ms, INTERACTIVE_MS)
        } else {
            1
        };
        let mut view = full.clone();
        view.width = (full.width / self.divisor).max(1);
        view.height = (full.height / self.divisor).max(1);
        let (gpu, loaded) = match (self.gpu.as_ref(), self.reloader.good.as_ref()) {
            (Some(g), Some(l)) => (g, l),
            _ => return Ok(()),
        };
        let renderer = &loaded.pipeline;
        if self.targets.as_ref().map(|t| t.size()) != Some((view.width, view.height)) {
            self.targets = Some(
                renderer
                    .new_targets(gpu, view.width, view.height)
                    .map_err(ViewError::Gpu)?,
            );
        }
        let targets = self.targets.as_ref().expect("made above");
        let module = &loaded.compiled.module;
        match renderer.set_param_values(gpu, module, &|n| self.params.value(n)) {
            Ok(Some(took)) => self.params.recomputed = Some(Ok(took)),
            Ok(None) => {}
            Err(e) => {
                if self.params.recomputed.as_ref().is_none_or(|r| r.is_ok()) {
                    self.say(&format!("warning: {e}; it keeps its last geometry"));
                }
                self.params.recomputed = Some(Err(e.to_string()));
            }
        }
        let (took, built) = renderer
            .draw_into(gpu, &view, VIEWS[self.mode].0, targets)
            .map_err(ViewError::Gpu)?;
        // A view's first frame builds its pipeline (`codegen::views`): counted with
        // the reloads', and its driver compile kept out of the estimate below.
        if built.is_some() {
            self.params.pipelines += 1;
            self.fresh = true;
        }
        self.last_frame_ms = took.as_secs_f64() * 1e3;
        // The cost of a full-resolution frame, estimated from this one (frame time
        // grows with the pixels); not from the first frame of a new pipeline, which
        // includes the driver's own shader compilation.
        if !std::mem::take(&mut self.fresh) {
            self.full_ms = self.last_frame_ms * (self.divisor * self.divisor) as f64;
        }
        if self.divisor == 1 {
            self.times.0.push(self.last_frame_ms);
        } else {
            self.divisor_used = self.divisor_used.max(self.divisor);
            self.times.1.push(self.last_frame_ms);
        }
        let capture = self.screenshot_next && self.divisor == 1;
        let presenter = self.presenter.as_mut().expect("a window");
        let panel = &mut self.panel;
        let mut overlay = |enc: &mut wgpu::CommandEncoder, view: &wgpu::TextureView, size| {
            if let Some(p) = panel.as_mut() {
                p.paint(&gpu.device, &gpu.queue, enc, view, size);
            }
        };
        let Some(shot) = presenter
            .present(gpu, renderer, targets, capture, &mut overlay)
            .map_err(ViewError::Gpu)?
        else {
            // Not shown (the surface was outdated, hidden or busy): try again shortly.
            std::thread::sleep(Duration::from_millis(10));
            self.request_redraw();
            return Ok(());
        };
        self.frames_drawn += 1;
        if self.params.playing() {
            self.request_redraw();
        }
        if let Some(shot) = shot {
            self.screenshot_next = false;
            self.save(&shot)?;
        }
        self.update_title();
        Ok(())
    }

    /// Saves a screenshot: to `--screenshot`, or next to the scene as `STEM-view-N.png`.
    fn save(&self, shot: &Shot) -> Result<(), ViewError> {
        let path = match &self.options.screenshot {
            Some(p) => p.clone(),
            None => {
                let stem = self
                    .options
                    .scene
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "scene".into());
                (1..)
                    .map(|k| self.base_dir.join(format!("{stem}-view-{k}.png")))
                    .find(|p| !p.exists())
                    .expect("a free name")
            }
        };
        let img = image::RgbaImage::from_raw(shot.width, shot.height, shot.rgba.clone())
            .ok_or_else(|| ViewError::Io("the screenshot has the wrong size".into()))?;
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| ViewError::Io(format!("cannot encode the screenshot: {e}")))?;
        crate::fsutil::write_output(&path, &bytes)
            .map_err(|e| ViewError::Io(format!("cannot write {}: {e}", path.display())))?;
        eprintln!(
            "saved {} ({}x{}, from the {})",
            path.display(),
            shot.width,
            shot.height,
            if shot.from_surface {
                "window"
            } else {
                "renderer's target"
            }
        );
        Ok(())
    }
}

impl ApplicationHandler<Changed> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        // The first build decides the window's size (the scene's `render` size).
        let mut size = self.options.size;
        if size.is_none() {
            let text = std::fs::read_to_string(&self.options.scene).unwrap_or_default();
            let analysis = crate::driver::analyze_with(&text, &self.options.access);
            let s = analysis
                .program
                .render
                .as_ref()
                .map(|r| r.settings.size)
                .unwrap_or(crate::sema::RenderSettings::default().size);
            size = Some((s[0], s[1]));
        }
        let (w, h) = size.expect("set above");
        let attributes = Window::default_attributes()
            .with_title(format!("sdfc view: {}", self.name))
            .with_inner_size(PhysicalSize::new(w, h));
        let window = match event_loop.create_window(attributes) {
            Ok(w) => Arc::new(w),
            Err(e) => {
                self.error = Some(ViewError::Display(format!("cannot open a window: {e}")));
                event_loop.exit();
                return;
            }
        };
        let display = Box::new(event_loop.owned_display_handle());
        let (gpu, surface) = match Gpu::with_surface(self.options.backend, display, window.clone())
        {
            Ok(x) => x,
            Err(e) => {
                self.error = Some(ViewError::Gpu(e));
                event_loop.exit();
                return;
            }
        };
        let inner = window.inner_size();
        match Presenter::new(&gpu, surface, inner.width, inner.height) {
            Ok(p) => {
                self.panel = Some(panel::Panel::new(&window, &gpu.device, p.view_format()));
                self.presenter = Some(p);
            }
            Err(e) => {
                self.error = Some(ViewError::Gpu(e));
                event_loop.exit();
                return;
            }
        }
        eprintln!("adapter: {}", gpu.describe());
        self.reloader.options.multiscale = self.options.multiscale.on(&gpu);
        if self.reloader.options.multiscale {
            eprintln!("multi-scale atlas pass: on");
        }
        self.gpu = Some(gpu);
        self.window = Some(window);
        self.reload(false);
        self.watch_textures();
        if self.reloader.good.is_none() {
            // Nothing to show: the report is printed; the viewer waits for a fix unless
            // it was asked for a fixed number of frames.
            if self.options.frames.is_some() {
                self.error = Some(ViewError::Scene);
                event_loop.exit();
                return;
            }
        }
    }

    fn user_event(&mut self, _: &ActiveEventLoop, changed: Changed) {
        let force = changed == Changed::Texture || self.pending.is_some_and(|(_, f)| f);
        self.pending = Some((Instant::now() + DEBOUNCE, force));
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some((at, force)) = self.pending {
            if Instant::now() >= at {
                self.pending = None;
                self.reload(force);
            }
        }
        let mut wake = self.pending.map(|(at, _)| at);
        if let Some(until) = self.moving_until {
            if Instant::now() >= until {
                // The camera stopped: refine to full resolution.
                self.moving_until = None;
                self.request_redraw();
            } else {
                wake = Some(wake.map_or(until, |w| w.min(until)));
            }
        }
        event_loop.set_control_flow(match wake {
            Some(at) => ControlFlow::WaitUntil(at),
            None => ControlFlow::Wait,
        });
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        if let (Some(panel), Some(window)) = (self.panel.as_mut(), self.window.as_ref()) {
            let (consumed, repaint) = panel.on_event(window, &event);
            if repaint {
                window.request_redraw();
            }
            if consumed {
                return;
            }
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let (Some(p), Some(gpu)) = (self.presenter.as_mut(), self.gpu.as_ref()) {
                    if let Err(e) = p.resize(gpu, size.width, size.height) {
                        self.say(&format!("warning: {e}"));
                    }
                }
                self.request_redraw();
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            // A release the window will not see: the drag ends here, and the camera
            // refines.
            WindowEvent::Focused(false) | WindowEvent::CursorLeft { .. } => {
                if self.pressed.take().is_some() {
                    self.request_redraw();
                }
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.key(event_loop, &event.logical_key)
            }
            WindowEvent::CursorMoved {
                position: PhysicalPosition { x, y },
                ..
            } => {
                let (dx, dy) = (x - self.cursor.0, y - self.cursor.1);
                self.cursor = (x, y);
                let width = self.presenter.as_ref().map_or(1, |p| p.size().0) as f64;
                let height = self.presenter.as_ref().map_or(1, |p| p.size().1) as f64;
                if matches!(self.pressed, Some((_, _, Drag::Param))) {
                    self.drag_param(dx, width);
                    return;
                }
                if let (Some((_, _, drag)), Some(orbit)) = (&self.pressed, self.orbit.as_mut()) {
                    match drag {
                        Drag::Orbit => orbit.rotate(dx, dy, width),
                        Drag::Pan => orbit.pan(dx, dy, height),
                        Drag::Seed(..) | Drag::Param => return,
                    }
                    self.request_redraw();
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                if let Some(orbit) = self.orbit.as_mut() {
                    orbit.zoom(steps);
                }
                self.moving_until = Some(Instant::now() + SETTLE);
                self.request_redraw();
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.mouse(state, button);
            }
            WindowEvent::RedrawRequested => {
                if let (Some(deg), Some(orbit)) = (self.options.spin, self.orbit.as_mut()) {
                    // A scripted drag: the first frame still, then turning.
                    if self.frames_drawn > 0 {
                        orbit.yaw += deg.to_radians();
                        self.moving_until = Some(Instant::now() + SETTLE);
                    }
                }
                if let Some(k) = self.options.frames {
                    // The last of the scripted frames is the screenshot.
                    self.screenshot_next |=
                        self.frames_drawn + 1 >= k && self.options.screenshot.is_some();
                }
                if let Err(e) = self.draw() {
                    // A frame that fails never closes the viewer (unless scripted).
                    self.say(&format!("error: {e}"));
                    if self.options.frames.is_some() {
                        self.error = Some(e);
                        event_loop.exit();
                        return;
                    }
                }
                if let Some(k) = self.options.frames {
                    if self.frames_drawn >= k && !self.screenshot_next {
                        event_loop.exit();
                        return;
                    }
                    self.request_redraw();
                }
            }
            _ => {}
        }
    }
}
