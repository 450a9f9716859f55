//! The viewer's panel of run-time parameters (egui, drawn with egui-wgpu over the
//! picture, fed by egui-winit): a slider per parameter (each component of a vector)
//! over its range, play/pause and a scrub slider for `time`, and a button that writes
//! the values back into the scene as its defaults. Moving a slider rewrites the
//! parameters' block, and recomputes the atlases on moving shapes: no pipeline is
//! built. The keys (`P`, right-drag, space, `W`) do the same from the keyboard.
//!
//! The panel is drawn after the screenshot's copy: screenshots hold the scene only.

use super::App;
use crate::codegen::params::ParamsLayout;
use winit::event::WindowEvent;
use winit::window::Window;

/// The seconds the `time` slider spans at least (more once time runs past it).
const TIME_SPAN: f64 = 20.0;

/// The egui state of the panel.
pub(crate) struct Panel {
    ctx: egui::Context,
    state: egui_winit::State,
    renderer: egui_wgpu::Renderer,
    /// This frame's triangles and textures, painted over the picture by [`Panel::paint`].
    frame: Option<(Vec<egui::ClippedPrimitive>, egui::TexturesDelta, f32)>,
    /// Whether the sliders' places were said (tests drive them with real input).
    said: bool,
    /// Whether the last frame showed the panel (a scene without parameters has none:
    /// then egui takes no events).
    shown: bool,
}

/// What the panel was used for in one frame.
#[derive(Debug, Default)]
struct Actions {
    /// New values, by parameter name.
    set: Vec<(String, Vec<f64>)>,
    /// `time` scrubbed to this value (paused).
    time: Option<f64>,
    toggle_time: bool,
    write: bool,
    /// Parameters whose slider was let go (or clicked) this frame: said in the terminal.
    released: Vec<String>,
}

/// What the panel shows: the layout, the current values, the clock and the counts.
struct Shown<'a> {
    layout: &'a ParamsLayout,
    values: &'a dyn Fn(&str) -> Option<Vec<f64>>,
    time: f64,
    playing: bool,
    status: String,
}

impl Panel {
    pub(crate) fn new(
        window: &Window,
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
    ) -> Panel {
        let ctx = egui::Context::default();
        let state = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        let renderer = egui_wgpu::Renderer::new(device, format, Default::default());
        Panel {
            ctx,
            state,
            renderer,
            frame: None,
            said: false,
            shown: false,
        }
    }

    /// Gives egui the event: whether the viewer should ignore it (a pointer event over
    /// the panel; keys always reach the viewer's shortcuts too), and whether to redraw.
    pub(crate) fn on_event(&mut self, window: &Window, event: &WindowEvent) -> (bool, bool) {
        if !self.shown {
            return (false, false);
        }
        let r = self.state.on_window_event(window, event);
        let pointer = matches!(
            event,
            WindowEvent::MouseInput { .. }
                | WindowEvent::CursorMoved { .. }
                | WindowEvent::MouseWheel { .. }
        );
        (r.consumed && pointer, r.repaint)
    }

    /// Records this frame's panel and returns what was done with it.
    fn run(&mut self, window: &Window, shown: &Shown) -> Actions {
        let input = self.state.take_egui_input(window);
        let mut actions = Actions::default();
        let mut places = Vec::new();
        let output = self.ctx.run_ui(input, |ui| {
            egui::Window::new("Parameters")
                .default_pos([8.0, 8.0])
                .resizable(false)
                .show(ui.ctx(), |ui| {
                    contents(ui, shown, &mut actions, &mut places);
                });
        });
        self.state
            .handle_platform_output(window, output.platform_output);
        let jobs = self.ctx.tessellate(output.shapes, output.pixels_per_point);
        // Texture changes of a frame that was never painted (the surface was lost)
        // still have to reach the renderer: the font atlas is uploaded once.
        let mut textures = match self.frame.take() {
            Some((_, unpainted, _)) => unpainted,
            None => Default::default(),
        };
        textures.append(output.textures_delta);
        self.frame = Some((jobs, textures, output.pixels_per_point));
        if !self.said && !places.is_empty() {
            self.said = true;
            // Where each slider's rail lies, in window pixels (its left end, its right
            // end, its row): the viewer's test drags them with real input.
            let scale = output.pixels_per_point;
            for (name, r) in places {
                eprintln!(
                    "panel: slider `{name}` from {:.0} to {:.0} at y {:.0}",
                    r.left() * scale,
                    r.right() * scale,
                    r.center().y * scale
                );
            }
        }
        actions
    }

    /// Paints the frame recorded by [`Panel::run`] over `view` (the window's surface).
    pub(crate) fn paint(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        enc: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        size: (u32, u32),
    ) {
        let Some((jobs, textures, pixels_per_point)) = self.frame.take() else {
            return;
        };
        for (id, deltas) in &textures.set {
            for delta in deltas {
                self.renderer.update_texture(device, queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.0, size.1],
            pixels_per_point,
        };
        let extra = self
            .renderer
            .update_buffers(device, queue, enc, &jobs, &screen);
        if !extra.is_empty() {
            queue.submit(extra);
        }
        let pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("panel"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.renderer
            .render(&mut pass.forget_lifetime(), &jobs, &screen);
        for id in &textures.free {
            self.renderer.free_texture(id);
        }
    }
}

/// A slider's rail: the left part of its widget, `slider_width` wide (the value and
/// the label follow it).
fn rail(ui: &egui::Ui, widget: egui::Rect) -> egui::Rect {
    let width = ui.spacing().slider_width.min(widget.width());
    egui::Rect::from_min_size(widget.min, egui::vec2(width, widget.height()))
}

/// The panel's widgets.
fn contents(
    ui: &mut egui::Ui,
    shown: &Shown,
    actions: &mut Actions,
    places: &mut Vec<(String, egui::Rect)>,
) {
    for f in shown.layout.fields.iter().filter(|f| f.name != "time") {
        let Some(mut value) = (shown.values)(&f.name) else {
            continue;
        };
        let max = f.max.unwrap_or(f.min + 1.0);
        let mut changed = false;
        for i in 0..value.len() {
            let label = if value.len() > 1 {
                format!("{}[{i}]", f.name)
            } else {
                f.name.clone()
            };
            let r = ui.add(egui::Slider::new(&mut value[i], f.min..=max).text(&label));
            places.push((label, rail(ui, r.rect)));
            changed |= r.changed();
            if r.drag_stopped() || (r.changed() && !r.dragged()) {
                actions.released.push(f.name.clone());
            }
        }
        if changed {
            actions.set.push((f.name.clone(), value));
        }
    }
    if shown.layout.fields.iter().any(|f| f.name == "time") {
        ui.horizontal(|ui| {
            let label = if shown.playing { "pause" } else { "play" };
            actions.toggle_time = ui.button(label).clicked();
            let mut t = shown.time;
            let span = TIME_SPAN.max(shown.time.ceil());
            let r = ui.add(egui::Slider::new(&mut t, 0.0..=span).text("time (s)"));
            places.push((String::from("time"), rail(ui, r.rect)));
            if r.changed() {
                actions.time = Some(t);
            }
            if r.drag_stopped() || (r.changed() && !r.dragged()) {
                actions.released.push(String::from("time"));
            }
        });
    }
    actions.write = ui
        .button("write the values into the scene as defaults")
        .clicked();
    ui.label(&shown.status);
}

impl App {
    /// Runs the panel for this frame (when the scene has parameters or reads `time`)
    /// and applies what was done with it, before the frame is rendered.
    pub(super) fn run_panel(&mut self) {
        let (Some(window), Some(loaded)) = (self.window.clone(), self.reloader.good.as_ref())
        else {
            return;
        };
        let layout = loaded.compiled.module.manifest.params.clone();
        let Some(panel) = self.panel.as_mut() else {
            return;
        };
        panel.shown = !layout.fields.is_empty();
        if !panel.shown {
            return;
        }
        let atlases = match &self.params.recomputed {
            Some(Ok(t)) => format!(
                "; moving atlases recomputed in {:.2} ms",
                t.as_secs_f64() * 1e3
            ),
            Some(Err(e)) => format!("; {e}"),
            None => String::new(),
        };
        let shown = Shown {
            layout: &layout,
            values: &|n| self.params.value(n),
            time: self.params.value("time").map_or(0.0, |t| t[0]),
            playing: self.params.playing(),
            status: format!("{} pipelines built{atlases}", self.params.pipelines),
        };
        let actions = panel.run(&window, &shown);
        for (name, value) in actions.set {
            self.params.set(&name, value);
        }
        if let Some(t) = actions.time {
            self.params.scrub_to(t);
        }
        if actions.toggle_time {
            self.toggle_time();
        }
        for name in actions.released {
            self.say_param_named(&name, "moved in the panel, with no new pipeline");
        }
        if actions.write {
            self.write_params();
        }
    }
}
