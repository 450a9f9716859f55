//! The viewer's input: keys, mouse buttons and the seed edits they make.

use super::{App, Drag, CLICK};
use crate::viewer::pick;
use winit::event::{ElementState, MouseButton};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, ModifiersState, NamedKey};

impl App {
    /// The seed edits of a mouse click at the cursor; prints what happened.
    fn seed_click(&mut self, button_mods: ModifiersState) {
        let Some(view) = self.view() else { return };
        let Some(loaded) = self.reloader.current() else {
            self.say("seed edits wait until the file has no errors");
            return;
        };
        let Some(shape) = self.shape() else { return };
        let (px, py) = self.cursor;
        let doc = &loaded.doc;
        let result = if button_mods.control_key() {
            let Some(hit) = pick::surface(shape, &view, px, py) else {
                self.say("add seed: no surface under the cursor");
                return;
            };
            let Some(atlas) = pick::atlas_at(&doc.analysis, hit.position, view.scale) else {
                self.say("add seed: no atlas on the surface under the cursor");
                return;
            };
            let edits = crate::ide::seed_edit::add_seed(doc, &atlas, hit.position);
            let what = match &edits {
                Ok((_, name)) => format!("add seed `{name}` to atlas `{atlas}`"),
                Err(_) => String::from("add seed"),
            };
            self.editor
                .apply(&what, doc, edits.map(|(e, _)| e), false)
                .map(|t| (t, what))
        } else {
            let Some(seed) = pick::seed(&doc.analysis, shape, &view, px, py, 12.0) else {
                return;
            };
            if button_mods.alt_key() {
                let edits = crate::ide::seed_edit::remove_seed(doc, &seed.atlas, &seed.seed);
                let what = format!("remove seed `{}`", seed.seed);
                self.editor
                    .apply(&what, doc, edits, false)
                    .map(|t| (t, what))
            } else if button_mods.shift_key() {
                match self.merge_first.take() {
                    Some((atlas, first)) if atlas == seed.atlas && first != seed.seed => {
                        let edits = crate::ide::seed_edit::merge(doc, &atlas, &first, &seed.seed);
                        let what = format!("merge `{first}` and `{}`", seed.seed);
                        self.editor
                            .apply(&what, doc, edits, true)
                            .map(|t| (t, what))
                    }
                    _ => {
                        self.say(&format!(
                            "merge: `{}` chosen; shift-click a second seed of atlas `{}`",
                            seed.seed, seed.atlas
                        ));
                        self.merge_first = Some((seed.atlas, seed.seed));
                        return;
                    }
                }
            } else {
                return;
            }
        };
        self.edited(result);
    }

    /// After an edit: reload what was written at once (the watcher's echo is then the
    /// same text), or print why it was refused.
    pub(super) fn edited(&mut self, result: Result<(String, String), String>) {
        match result {
            Ok((text, what)) => {
                eprintln!("{what}: written to {}", self.name);
                self.reload_text(&text, false);
            }
            Err(report) => eprint!("{}", report.trim_end_matches('\n').to_string() + "\n"),
        }
    }

    fn drop_seed(&mut self, atlas: &str, seed: &str) {
        let Some(view) = self.view() else { return };
        let Some(loaded) = self.reloader.current() else {
            return;
        };
        let Some(shape) = self.shape() else { return };
        let Some(hit) = pick::surface(shape, &view, self.cursor.0, self.cursor.1) else {
            self.say(&format!("move seed `{seed}`: no surface under the cursor"));
            return;
        };
        let doc = &loaded.doc;
        let edits = crate::ide::seed_edit::move_seed(doc, atlas, seed, hit.position);
        let what = format!("move seed `{seed}`");
        let result = self
            .editor
            .apply(&what, doc, edits, false)
            .map(|t| (t, what));
        self.edited(result);
    }

    pub(super) fn key(&mut self, event_loop: &ActiveEventLoop, key: &Key) {
        let ctrl = self.modifiers.control_key();
        match key {
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::Space) => self.toggle_time(),
            Key::Character(c) => match c.as_str() {
                "z" | "Z" if ctrl => {
                    let result = self
                        .editor
                        .undo()
                        .map(|(t, what)| (t, format!("undo `{what}`")));
                    self.edited(result);
                }
                "p" | "P" => self.select_next_param(),
                "w" | "W" => self.write_params(),
                "f" | "F" => {
                    let bounds = self.shape().map(|s| s.framing_bounds());
                    let (w, h) = self.presenter.as_ref().map_or((1, 1), |p| p.size());
                    if let (Some(orbit), Some(b)) = (self.orbit.as_mut(), bounds) {
                        orbit.frame(b, w as f64 / h.max(1) as f64);
                    }
                    self.request_redraw();
                }
                "r" | "R" => {
                    self.orbit = self.scene_orbit();
                    self.request_redraw();
                }
                "s" | "S" => {
                    self.screenshot_next = true;
                    self.request_redraw();
                }
                d if d.len() == 1 && ("1"..="9").contains(&d) => {
                    self.mode = d.parse::<usize>().expect("a digit") - 1;
                    self.request_redraw();
                }
                _ => {}
            },
            _ => {}
        }
    }

    pub(super) fn mouse(&mut self, state: ElementState, button: MouseButton) {
        let mods = self.modifiers;
        match state {
            ElementState::Pressed => {
                // A second button during a drag does not start another.
                if self.pressed.is_some() {
                    return;
                }
                let drag = match button {
                    MouseButton::Middle => Drag::Pan,
                    MouseButton::Right if self.params_selected() => Drag::Param,
                    MouseButton::Left if mods.control_key() || mods.alt_key() => Drag::Orbit,
                    MouseButton::Left => {
                        let on_seed = self.view().and_then(|view| {
                            let loaded = self.reloader.current()?;
                            let shape = self.shape()?;
                            let (px, py) = self.cursor;
                            pick::seed(&loaded.doc.analysis, shape, &view, px, py, 12.0)
                        });
                        match on_seed {
                            Some(s) if !mods.shift_key() => Drag::Seed(s.atlas, s.seed),
                            None if mods.shift_key() => Drag::Pan,
                            _ => Drag::Orbit,
                        }
                    }
                    _ => return,
                };
                self.pressed = Some((button, self.cursor, drag));
            }
            ElementState::Released => {
                // Only the release of the button that started the drag ends it.
                if !self.pressed.as_ref().is_some_and(|(b, _, _)| *b == button) {
                    return;
                }
                let Some((_, at, drag)) = self.pressed.take() else {
                    return;
                };
                let moved =
                    ((self.cursor.0 - at.0).powi(2) + (self.cursor.1 - at.1).powi(2)).sqrt();
                match drag {
                    Drag::Seed(atlas, seed) if moved >= CLICK => self.drop_seed(&atlas, &seed),
                    Drag::Param => self.param_dropped(),
                    _ if moved < CLICK && button == MouseButton::Left => self.seed_click(mods),
                    _ => {}
                }
                // The camera stopped: refine.
                self.request_redraw();
            }
        }
    }
}
