//! Settings as types. The checker reads a block's settings once, with the defaults of
//! the tables in [`super::builtins`], into these types; later stages read the types and
//! never re-interpret builtin arguments or repeat a default.

use super::builtins::{SettingSpec, ATLAS_SETTINGS, MATERIAL_SETTINGS, RENDER_SETTINGS};
use super::types::{Camera, FieldExpr, Light, SurfaceInput, Ty, Value};
use crate::span::Span;
use std::collections::HashMap;

/// The values of one block's settings: each as written, else its table default.
pub struct Settings<'a> {
    specs: &'static [SettingSpec],
    given: &'a HashMap<&'static str, (Value, Span)>,
}

impl<'a> Settings<'a> {
    /// `given` holds the checked values by setting name; an error value counts as not given.
    pub fn new(
        specs: &'static [SettingSpec],
        given: &'a HashMap<&'static str, (Value, Span)>,
    ) -> Self {
        Settings { specs, given }
    }

    /// The value of a setting: as written, else the table's default (`None` when it has none).
    pub fn get(&self, name: &str) -> Option<Value> {
        match self.given.get(name) {
            Some((v, _)) if !v.is_error() => Some(v.clone()),
            _ => setting_default(self.specs, name),
        }
    }

    fn float(&self, name: &str) -> f64 {
        self.get(name)
            .and_then(|v| v.as_float())
            .unwrap_or_default()
    }

    fn vec3(&self, name: &str) -> [f64; 3] {
        self.get(name).and_then(|v| v.as_vec3()).unwrap_or_default()
    }
}

/// The default of a block's setting as a value; `None` for a setting without one (or
/// no such setting).
pub fn setting_default(specs: &[SettingSpec], name: &str) -> Option<Value> {
    let spec = specs.iter().find(|s| s.name == name)?;
    spec.default.map(Value::from)
}

/// The parameters of Alg. 1 and Alg. 2 for one atlas, with defaults filled in.
#[derive(Debug, Clone, PartialEq)]
pub struct AtlasParams {
    pub steps: u32,
    /// K: Newton corrections of the walk's uv (0: the paper's walk alone).
    pub refine: u32,
    pub max_distance: f64,
    pub heuristic_tolerance: f64,
    pub sharp_tolerance: f64,
    pub min_reach: f64,
    pub reproject: bool,
    pub sigma: Option<f64>,
    /// The normal of the symmetry plane of `mirror` (not normalized; checked non-zero).
    pub mirror: Option<[f64; 3]>,
}

impl AtlasParams {
    /// The parameters from an `atlas` block's settings (already checked).
    pub fn new(s: &Settings) -> AtlasParams {
        AtlasParams {
            steps: s.float("steps") as u32,
            refine: s.float("refine") as u32,
            max_distance: s.float("max_distance"),
            heuristic_tolerance: s.float("heuristic_tolerance"),
            sharp_tolerance: s.float("sharp_tolerance"),
            min_reach: s.float("min_reach"),
            reproject: matches!(s.get("reproject"), Some(Value::Bool(true))),
            sigma: s.get("sigma").and_then(|v| v.as_float()),
            mirror: s.get("mirror").and_then(|v| v.as_vec3()),
        }
    }
}

impl Default for AtlasParams {
    /// Every parameter at its default of [`ATLAS_SETTINGS`].
    fn default() -> Self {
        AtlasParams::new(&Settings::new(ATLAS_SETTINGS, &HashMap::new()))
    }
}

/// The attributes of a material, with defaults filled in; each is constant or a field.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialAttrs {
    /// float, vec3 or vec4 (rgb is used).
    pub color: Value,
    pub roughness: Value,
    pub metallic: Value,
    pub emission: Value,
    /// The shading normal (vec3, world space): the surface normal unless the material
    /// sets one, e.g. a normal map.
    pub normal: Value,
}

impl MaterialAttrs {
    /// The attributes from a `material` block's settings (already checked).
    pub fn new(s: &Settings) -> MaterialAttrs {
        let get = |n: &str| s.get(n).unwrap_or(Value::Error);
        MaterialAttrs {
            color: get("color"),
            roughness: get("roughness"),
            metallic: get("metallic"),
            emission: get("emission"),
            normal: s.get("normal").unwrap_or_else(|| {
                Value::field(FieldExpr::Input(SurfaceInput::Normal), Ty::Vec(3))
            }),
        }
    }
}

impl Default for MaterialAttrs {
    /// The default material: every attribute at its default of [`MATERIAL_SETTINGS`].
    fn default() -> Self {
        MaterialAttrs::new(&Settings::new(MATERIAL_SETTINGS, &HashMap::new()))
    }
}

/// The settings of the `render` item, with defaults filled in.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// `None`: the view frames the shape's bounds.
    pub camera: Option<Camera>,
    pub light: Light,
    pub size: [u32; 2],
    pub background: [f64; 3],
    pub ambient: f64,
}

impl RenderSettings {
    /// The settings from a `render` block's settings (already checked).
    pub fn new(s: &Settings) -> RenderSettings {
        let size = s
            .get("size")
            .and_then(|v| v.components().map(<[f64]>::to_vec));
        RenderSettings {
            camera: match s.get("camera") {
                Some(Value::Camera(c)) => Some(*c),
                _ => None,
            },
            light: match s.get("light") {
                Some(Value::Light(l)) => *l,
                _ => Light::default(),
            },
            size: match size.as_deref() {
                Some(&[w, h]) => [w as u32, h as u32],
                _ => [0, 0],
            },
            background: s.vec3("background"),
            ambient: s.float("ambient"),
        }
    }
}

impl Default for RenderSettings {
    /// Every setting at its default of [`RENDER_SETTINGS`] (a scene without a `render` item).
    fn default() -> Self {
        RenderSettings::new(&Settings::new(RENDER_SETTINGS, &HashMap::new()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sema::builtins::{BuiltinId, Dflt};

    fn table_float(specs: &[SettingSpec], name: &str) -> f64 {
        match specs
            .iter()
            .find(|s| s.name == name)
            .and_then(|s| s.default)
        {
            Some(Dflt::F(x)) => x,
            other => panic!("{name} has no float default: {other:?}"),
        }
    }

    #[test]
    fn atlas_defaults_come_from_the_table() {
        let p = AtlasParams::default();
        assert_eq!(p.steps as f64, table_float(ATLAS_SETTINGS, "steps"));
        assert_eq!(p.max_distance, table_float(ATLAS_SETTINGS, "max_distance"));
        assert_eq!(
            p.heuristic_tolerance,
            table_float(ATLAS_SETTINGS, "heuristic_tolerance")
        );
        assert_eq!(
            p.sharp_tolerance,
            table_float(ATLAS_SETTINGS, "sharp_tolerance")
        );
        assert_eq!(p.min_reach, table_float(ATLAS_SETTINGS, "min_reach"));
        assert!(!p.reproject);
        assert_eq!(p.sigma, None);
        assert_eq!(p.mirror, None);
    }

    #[test]
    fn every_atlas_setting_is_read() {
        // Each setting given a value unlike its default changes the parameters.
        for spec in ATLAS_SETTINGS {
            let value = match spec.name {
                "reproject" => Value::Bool(true),
                "mirror" => Value::Vec(vec![1.0, 0.0, 0.0]),
                _ => Value::Float(7.0),
            };
            let given = HashMap::from([(spec.name, (value, Span::new(0, 0)))]);
            let p = AtlasParams::new(&Settings::new(ATLAS_SETTINGS, &given));
            assert_ne!(p, AtlasParams::default(), "`{}` is not read", spec.name);
        }
    }

    #[test]
    fn render_defaults_come_from_the_table() {
        let r = RenderSettings::default();
        assert_eq!(r.camera, None);
        assert_eq!(r.light, Light::default());
        assert_eq!(r.ambient, table_float(RENDER_SETTINGS, "ambient"));
        let table = |n| setting_default(RENDER_SETTINGS, n);
        assert_eq!(table("size"), Some(Value::Vec(vec![960.0, 540.0])));
        assert_eq!(r.size, [960, 540]);
        assert_eq!(Some(Value::Vec(r.background.to_vec())), table("background"));
        // Material settings have defaults for every attribute.
        let m = MaterialAttrs::default();
        assert_eq!(Some(m.color), setting_default(MATERIAL_SETTINGS, "color"));
        assert_eq!(m.roughness, Value::Float(0.5));
        assert!(![m.metallic, m.emission].iter().any(Value::is_error));
    }

    #[test]
    fn the_default_light_is_sun_with_its_table_defaults() {
        let sun = BuiltinId::Sun.builtin();
        let Light::Sun {
            direction,
            color,
            intensity,
        } = Light::default();
        assert_eq!(
            sun.param("direction").unwrap().1.default,
            Some(Dflt::V(&[0.5, 1.0, 0.3]))
        );
        assert_eq!(direction, [0.5, 1.0, 0.3]);
        assert_eq!(color, [1.0; 3]);
        assert_eq!(intensity, 3.0);
    }

    #[test]
    fn cameras_are_read_by_parameter_name() {
        let args = [
            Value::Vec(vec![1.0, 2.0, 3.0]),
            Value::Vec(vec![0.0; 3]),
            Value::Float(0.5),
        ];
        assert_eq!(
            Camera::from_call(BuiltinId::LookAt, &args),
            Some(Camera::LookAt {
                eye: [1.0, 2.0, 3.0],
                target: [0.0; 3],
                fov: 0.5
            })
        );
        assert_eq!(Camera::from_call(BuiltinId::Sun, &args), None);
    }
}

/// The tables drive the checker and the editor alike: what `check` fills in for an
/// unset setting is what completion shows as its default.
#[cfg(test)]
mod table_tests {
    use crate::driver::analyze;
    use crate::ide::{complete::completions, Document};
    use crate::sema::{AtlasParams, MaterialAttrs, RenderSettings, Value};

    #[test]
    fn unset_settings_take_the_defaults_completion_shows() {
        let text = "let s = sphere();\nmaterial m { }\natlas a on s { seed x = [0, 0, 1]; }\nrender s.paint(m) { }\n";
        let a = analyze(text, None);
        assert!(a
            .diagnostics
            .iter()
            .all(|d| d.severity != crate::Severity::Error));
        let render = a.program.render.as_ref().unwrap();
        assert_eq!(render.settings, RenderSettings::default());
        assert_eq!(a.program.atlases[0].params, AtlasParams::default());
        assert_eq!(a.program.materials[0].attrs, MaterialAttrs::default());

        let doc = Document::new(text, None);
        let offset = text.rfind("{ }").unwrap() + 2;
        let detail = |name: &str| {
            completions(&doc, offset)
                .into_iter()
                .find(|c| c.label == name)
                .and_then(|c| c.detail)
                .unwrap()
        };
        let ambient = Value::Float(render.settings.ambient).display();
        assert_eq!(detail("ambient"), format!("ambient: float = {ambient}"));
        let size = render.settings.size.map(|x| x.to_string()).join(", ");
        assert_eq!(detail("size"), format!("size: vec2 = [{size}]"));
        assert_eq!(detail("camera"), "camera: camera");
        assert_eq!(detail("light"), "light: light");
    }
}
