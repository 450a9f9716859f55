//! The viewer's run-time parameters: `P` selects the next parameter, a right-button
//! drag across the window sweeps it over its whole range (`time`: scrubs four
//! seconds, paused), the space bar plays and pauses `time`, and `W` writes the
//! current values back into the scene file as the new defaults (through the seed edits' machinery: checked, atomic, every other byte
//! kept). Moving a value only rewrites the parameters' block: no pipeline is built,
//! and the viewer says how many it has built so far.

use super::App;
use crate::codegen::params::ParamsLayout;
use crate::diagnostic::Edit;
use crate::syntax::ast::ItemKind;
use std::collections::BTreeMap;
use std::time::Instant;

/// The seconds of `time` a right-drag across the whole window scrubs.
const SCRUB_SECONDS: f64 = 4.0;

/// The parameters' state of the viewer.
#[derive(Debug, Default)]
pub(crate) struct Params {
    /// The current values, by name (`time` included).
    values: BTreeMap<String, Vec<f64>>,
    /// The parameter `P` selected (its name), which a right-drag moves.
    selected: Option<String>,
    /// `time` runs from `started`, plus what ran before a pause.
    playing: Option<Instant>,
    time: f64,
    /// Pipelines built since the viewer started (one per good reload, and one per
    /// view at its first frame: `gpu::Renderer`).
    pub(crate) pipelines: usize,
    /// The last recomputation of the atlases on moving shapes: its time, or why it
    /// failed.
    pub(crate) recomputed: Option<Result<std::time::Duration, String>>,
}

impl Params {
    /// A parameter's current value (`time`'s from the clock).
    pub(crate) fn value(&self, name: &str) -> Option<Vec<f64>> {
        if name == "time" {
            Some(vec![self.now()])
        } else {
            self.values.get(name).cloned()
        }
    }

    fn now(&self) -> f64 {
        self.time + self.playing.map_or(0.0, |t| t.elapsed().as_secs_f64())
    }

    /// Sets a parameter (the panel's sliders keep values within range).
    pub(crate) fn set(&mut self, name: &str, value: Vec<f64>) {
        if let Some(v) = self.values.get_mut(name) {
            *v = value;
        }
    }

    /// Scrubs `time` to `t` seconds, paused.
    pub(crate) fn scrub_to(&mut self, t: f64) {
        self.playing = None;
        self.time = t.max(0.0);
    }

    /// Whether `time` runs (frames follow one another).
    pub(crate) fn playing(&self) -> bool {
        self.playing.is_some()
    }
}

impl App {
    fn layout(&self) -> Option<&ParamsLayout> {
        let loaded = self.reloader.good.as_ref()?;
        Some(&loaded.compiled.module.manifest.params)
    }

    /// After a reload: the values of parameters still declared stay (clamped into
    /// their new ranges); new ones start at their defaults.
    pub(super) fn params_reloaded(&mut self) {
        let Some(layout) = self.layout().cloned() else {
            return;
        };
        let mut values = BTreeMap::new();
        for f in layout.fields.iter().filter(|f| f.name != "time") {
            let max = f.max.unwrap_or(f64::INFINITY);
            let v = match self.params.values.get(&f.name) {
                Some(v) if v.len() == f.default.len() => {
                    v.iter().map(|x| x.clamp(f.min, max)).collect()
                }
                _ => f.default.clone(),
            };
            values.insert(f.name.clone(), v);
        }
        self.params.values = values;
        // A new build has not recomputed anything yet.
        self.params.recomputed = None;
        let reads_time = self.reads_time();
        if self
            .params
            .selected
            .as_ref()
            .is_some_and(|s| !self.params.values.contains_key(s) && !(s == "time" && reads_time))
        {
            self.params.selected = None;
        }
    }

    /// Whether a parameter is selected (a right-drag then moves it).
    pub(super) fn params_selected(&self) -> bool {
        self.params.selected.is_some()
    }

    /// `P`: the next parameter, then `time` (when the scene reads it).
    pub(super) fn select_next_param(&mut self) {
        let mut names: Vec<String> = self.params.values.keys().cloned().collect();
        if self.reads_time() {
            names.push(String::from("time"));
        }
        if names.is_empty() {
            self.say("the scene has no parameters (declare one: `param r = 0.5 in [0.1, 1];`)");
            return;
        }
        let next = match &self.params.selected {
            Some(s) => names
                .iter()
                .position(|n| n == s)
                .map_or(0, |i| (i + 1) % names.len()),
            None => 0,
        };
        self.params.selected = Some(names[next].clone());
        self.say_param("selected; right-drag across the window to move it, W writes it back");
    }

    fn say_param(&self, what: &str) {
        if let Some(name) = &self.params.selected {
            self.say_param_named(name, what);
        }
    }

    /// Says parameter `name`'s value, its range and `what` happened to it.
    pub(super) fn say_param_named(&self, name: &str, what: &str) {
        let Some(layout) = self.layout() else {
            return;
        };
        let Some(f) = layout.fields.iter().find(|f| f.name == name) else {
            return;
        };
        let v = self.params.value(name).unwrap_or_default();
        let shown: Vec<String> = v.iter().map(|x| format!("{x:.4}")).collect();
        let atlases = match &self.params.recomputed {
            Some(Ok(t)) => format!(
                "; moving atlases last recomputed in {:.2} ms",
                t.as_secs_f64() * 1e3
            ),
            _ => String::new(),
        };
        self.say(&format!(
            "parameter `{name}` = {} in [{}, {}]: {what} ({} pipelines built{atlases})",
            shown.join(", "),
            f.min,
            f.max.map_or(String::from("∞"), |m| m.to_string()),
            self.params.pipelines
        ));
    }

    /// A right-drag of `dx` pixels in a window `width` wide: the selected parameter
    /// moves by that share of its range (every component of a vector together).
    pub(super) fn drag_param(&mut self, dx: f64, width: f64) {
        let Some(name) = self.params.selected.clone() else {
            return;
        };
        if name == "time" {
            // Scrubbing pauses the clock and moves it.
            if let Some(t) = self.params.playing.take() {
                self.params.time += t.elapsed().as_secs_f64();
            }
            let step = dx / width.max(1.0) * SCRUB_SECONDS;
            self.params.time = (self.params.time + step).max(0.0);
            self.request_redraw();
            return;
        }
        let Some(f) = self
            .layout()
            .and_then(|l| l.fields.iter().find(|f| f.name == name))
            .cloned()
        else {
            return;
        };
        let max = f.max.unwrap_or(f.min + 1.0);
        let step = dx / width.max(1.0) * (max - f.min);
        if let Some(v) = self.params.values.get_mut(&name) {
            for x in v.iter_mut() {
                *x = (*x + step).clamp(f.min, max);
            }
        }
        self.request_redraw();
    }

    /// The end of a right-drag: says where the parameter is.
    pub(super) fn param_dropped(&self) {
        self.say_param("moved, with no new pipeline");
    }

    fn reads_time(&self) -> bool {
        self.layout()
            .is_some_and(|l| l.fields.iter().any(|f| f.name == "time"))
    }

    /// Space: plays or pauses `time`.
    pub(super) fn toggle_time(&mut self) {
        if !self.reads_time() {
            self.say("the scene does not read `time`");
            return;
        }
        match self.params.playing.take() {
            Some(t) => {
                self.params.time += t.elapsed().as_secs_f64();
                self.say(&format!("time paused at {:.2} s", self.params.time));
            }
            None => {
                self.params.playing = Some(Instant::now());
                self.say(&format!("time playing from {:.2} s", self.params.time));
            }
        }
        self.request_redraw();
    }

    /// `W`: the current values become the `param` items' defaults in the file.
    pub(super) fn write_params(&mut self) {
        let Some(loaded) = self.reloader.good.as_ref() else {
            return;
        };
        let doc = &loaded.doc;
        let mut edits = Vec::new();
        for item in &doc.analysis.parsed.file.items {
            let ItemKind::Param { name, value, .. } = &item.kind else {
                continue;
            };
            let Some(v) = self.params.values.get(&name.name) else {
                continue;
            };
            let text = match v.as_slice() {
                [x] => crate::sema::Value::Float(*x).display(),
                v => crate::sema::Value::Vec(v.to_vec()).display(),
            };
            if doc.text.get(value.span.start..value.span.end) != Some(text.as_str()) {
                edits.push(Edit {
                    span: value.span,
                    text,
                });
            }
        }
        if edits.is_empty() {
            self.say("the parameters' defaults already are their current values");
            return;
        }
        let doc = doc.clone();
        let result = self
            .editor
            .apply("set the parameters' defaults", &doc, Ok(edits), false)
            .map(|t| (t, String::from("set the parameters' defaults")));
        self.edited(result);
    }
}
