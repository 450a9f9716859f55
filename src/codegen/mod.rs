//! Code generation: the checked program and its IR → one standalone, specialized
//! WGSL module per scene, validated by naga before anyone sees it.
//!
//! The module is the shared library (`shaders/sdf.wgsl`, `shaders/render.wgsl`)
//! followed by the scene: an `sdf_NAME(p) -> f32` per named shape, the render
//! target's `scene_map`, its materials, a full-screen render entry point pair
//! and two compute entry points (points and grids). Its header documents the
//! bind groups; [`Manifest`] describes them as JSON.

mod atlas;
mod emit;
pub mod targets;

pub use atlas::{SeedGridChoice, WalkForm};
pub use emit::{lit, TextureUse};
pub use targets::{translate, validate, NagaError, Target, Validated};

use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::ir::{self, Scene};
use crate::sema::{Program, Value};
use emit::{field, Uses, Writer};
use serde::Serialize;
use std::fmt::Write;

/// The shared WGSL library, included into every module.
pub const SDF_LIBRARY: &str = include_str!("../../shaders/sdf.wgsl");
pub const RENDER_LIBRARY: &str = include_str!("../../shaders/render.wgsl");
pub const UV_LIBRARY: &str = include_str!("../../shaders/uv.wgsl");

/// A generated module with its description.
#[derive(Debug, Clone)]
pub struct Module {
    pub wgsl: String,
    pub manifest: Manifest,
    /// Which scene definition each generated function came from.
    pub source_map: Vec<SourceRegion>,
}

/// A byte range of the generated WGSL and the scene definition that produced it.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceRegion {
    pub wgsl: std::ops::Range<usize>,
    pub span: crate::span::Span,
    /// What the definition is, for messages: "shape `body`", "material `tiled`" …
    pub what: String,
}

impl Module {
    /// For tests of the internal-error path only: inserts an undefined name at the start
    /// of the first material's code (the regions are kept in step).
    #[doc(hidden)]
    pub fn corrupt_first_material(&mut self) {
        let Some(at) = self
            .source_map
            .iter()
            .find(|r| r.what.starts_with("material"))
            .map(|r| r.wgsl.start)
        else {
            return;
        };
        let line_end = self.wgsl[at..].find('\n').map_or(at, |i| at + i + 1);
        let broken = "            let corrupted = undefined_name;\n";
        self.wgsl.insert_str(line_end, broken);
        for r in &mut self.source_map {
            if r.wgsl.start >= line_end {
                r.wgsl.start += broken.len();
            }
            if r.wgsl.end >= line_end {
                r.wgsl.end += broken.len();
            }
        }
    }

    /// The innermost region holding a byte offset of the WGSL.
    pub fn region_at(&self, offset: usize) -> Option<&SourceRegion> {
        self.source_map
            .iter()
            .filter(|r| r.wgsl.contains(&offset))
            .min_by_key(|r| r.wgsl.len())
    }

    /// naga's rejection of this module as an internal-compiler-error diagnostic on the
    /// scene span that produced the offending code (or the file's start, for code of
    /// the shared library).
    pub fn internal_error(&self, e: &NagaError) -> Diagnostic {
        let first = e
            .message
            .lines()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("naga rejected the module")
            .trim()
            .to_string();
        let region = e.offset.and_then(|o| self.region_at(o));
        let (span, label) = match region {
            Some(r) => (
                r.span,
                format!("naga rejected the WGSL generated for {}", r.what),
            ),
            None => (
                crate::span::Span::default(),
                String::from(
                    "naga rejected code sdfc adds to every module, not code from this scene",
                ),
            ),
        };
        let mut d = Diagnostic::error(
            codes::E_INTERNAL,
            "internal compiler error: naga rejected the generated WGSL",
            span,
            label,
        )
        .with_note(format!("naga: {first}"));
        if let Some(o) = e.offset {
            let line = self.wgsl[..o.min(self.wgsl.len())].matches('\n').count() + 1;
            d = d.with_note(format!("at line {line} of the generated WGSL"));
        }
        d.with_help("this is a bug in sdfc, not in the scene: please report it with the generated WGSL (`sdfc compile` saves it)")
    }
}

/// A resource binding of the generated module.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Binding {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    /// `uniform`, `storage-read`, `storage-read-write`, `texture-2d` or `sampler`.
    pub kind: &'static str,
    /// WGSL type, or the image path for textures, or the wrap mode for samplers.
    pub detail: String,
    pub used_by: Vec<&'static str>,
}

/// What an application needs to drive the module: entry points, bindings and the
/// byte layout of the uniform blocks.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Manifest {
    pub entry_points: Vec<(&'static str, &'static str)>,
    pub bindings: Vec<Binding>,
    /// Field names of `Globals`, each a `vec4<f32>` (16 bytes), in order.
    pub globals_layout: Vec<&'static str>,
    /// Lipschitz bound of the render target: sphere-tracing steps are divided by it.
    pub lipschitz: f64,
    /// Names of the shapes with an `sdf_NAME` function.
    pub shapes: Vec<String>,
    pub textures: Vec<TextureUse>,
}

pub const GLOBALS_LAYOUT: &[&str] = &[
    "camera_pos",
    "camera_forward",
    "camera_right",
    "camera_up",
    "light_dir",
    "light_color",
    "background",
    "resolution",
    "trace",
];

/// Generates the module for a checked, error-free program. `shape` picks the render
/// target by name instead of the `render` item's. Problems come back as diagnostics.
pub fn generate(
    program: &Program,
    scene: &Scene,
    shape: Option<&str>,
) -> Result<Module, Vec<Diagnostic>> {
    generate_with(
        program,
        scene,
        &Options {
            shape: shape.map(str::to_string),
            ..Default::default()
        },
    )
}

/// Choices for [`generate_with`].
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Render this named shape instead of the render item's target.
    pub shape: Option<String>,
    pub walk: WalkForm,
    /// The atlas of the atlas views and `cs_atlas` (default: the first).
    pub atlas: Option<String>,
    /// Leave out atlases and materials: the plain sphere-trace baseline of benchmarks.
    pub plain: bool,
    /// Whether the nearest-seed search uses the seed grid.
    pub seed_grid: SeedGridChoice,
}

/// [`generate`] with a choice of walk form.
pub fn generate_with(
    program: &Program,
    scene: &Scene,
    options: &Options,
) -> Result<Module, Vec<Diagnostic>> {
    generate_prepared(program, scene, options, None)
}

/// [`generate_with`] reusing atlases [`crate::driver::check`] prepared already (one per
/// atlas of the program), so the compile-time geometry runs once.
pub fn generate_prepared(
    program: &Program,
    scene: &Scene,
    options: &Options,
    prepared: Option<&[Option<crate::uv::Atlas>]>,
) -> Result<Module, Vec<Diagnostic>> {
    let form = options.walk;
    let mut source_map: Vec<SourceRegion> = Vec::new();
    let let_span = |name: &str| {
        program
            .defs
            .iter()
            .find(|d| d.kind == crate::sema::DefKind::Let && d.name == name)
            .map(|d| d.item_span)
    };
    let target = match options.shape.as_deref() {
        Some(n) => scene.shape(n).cloned().ok_or_else(|| {
            vec![Diagnostic::error(
                codes::E_CODEGEN,
                format!("the scene has no shape `{n}`"),
                Default::default(),
                "",
            )]
        })?,
        None => match (&scene.render, scene.shapes.as_slice()) {
            (Some(r), _) => r.clone(),
            (None, [only]) => only.shape.clone(),
            _ => {
                return Err(vec![Diagnostic::error(
                    codes::E_CODEGEN,
                    "the scene has no render item; choose a shape",
                    Default::default(),
                    "",
                )])
            }
        },
    };
    let mut out = String::new();
    let mut textures = Uses::default();
    let mut problems = Vec::new();

    let _ = writeln!(out, "// ---- scene ----");
    let _ = writeln!(
        out,
        "const SCENE_LIPSCHITZ: f32 = {};",
        lit(target.lipschitz().max(1.0))
    );
    let b = target.framing_bounds();
    let _ = writeln!(
        out,
        "const SCENE_SCALE: f32 = {};\n",
        lit((b.max - b.min).max_element().max(1e-3))
    );
    for named in &scene.shapes {
        let start = out.len();
        map_fn(&mut out, &format!("map_{}", named.name), &named.shape);
        let _ = writeln!(
            out,
            "fn sdf_{0}(p: vec3<f32>) -> f32 {{\n    return map_{0}(p).x;\n}}\n",
            named.name
        );
        if let Some(span) = let_span(&named.name) {
            source_map.push(SourceRegion {
                wgsl: start..out.len(),
                span,
                what: format!("shape `{}`", named.name),
            });
        }
    }
    let start = out.len();
    map_fn(&mut out, "scene_map", &target);
    let target_span = match (options.shape.as_deref(), &program.render) {
        (Some(n), _) => let_span(n),
        (None, Some(r)) => Some(r.target_span),
        (None, None) => scene.shapes.first().and_then(|s| let_span(&s.name)),
    };
    if let Some(span) = target_span {
        source_map.push(SourceRegion {
            wgsl: start..out.len(),
            span,
            what: String::from("the rendered shape"),
        });
    }

    // Atlases: seeds are projected and framed here, at compile time, on the CPU.
    let atlases: &[crate::sema::AtlasDef] = if options.plain { &[] } else { &program.atlases };
    let materials: &[crate::sema::MaterialDef] = if options.plain {
        &[]
    } else {
        &program.materials
    };
    if !atlases.is_empty() {
        let computed;
        let prepared = match prepared {
            Some(p) if p.len() == atlases.len() => p,
            _ => {
                let (p, diags) = crate::uv::diagnose::prepare_all(program);
                // Warnings and notes were reported by the check; errors stop generation.
                problems.extend(diags.into_iter().filter(Diagnostic::is_error));
                computed = p;
                &computed[..]
            }
        };
        for (k, a) in prepared.iter().enumerate() {
            if let Some(a) = a {
                let start = out.len();
                atlas::emit(&mut out, k, a, form, &options.seed_grid.grid(a));
                source_map.push(SourceRegion {
                    wgsl: start..out.len(),
                    span: atlases[k].span,
                    what: format!("atlas `{}`", atlases[k].name),
                });
            }
        }
    }

    // The atlas of the atlas views and of cs_atlas.
    let chosen = match options.atlas.as_deref() {
        Some(name) => match program.atlases.iter().find(|a| a.name == name) {
            Some(a) => Some(a.name.clone()),
            None => {
                return Err(vec![Diagnostic::error(
                    codes::E_CODEGEN,
                    format!("the scene has no atlas `{name}`"),
                    Default::default(),
                    "",
                )])
            }
        },
        None => atlases.first().map(|a| a.name.clone()),
    };
    let _ = match chosen {
        Some(name) => writeln!(out, "fn scene_atlas(p: vec3<f32>) -> AtlasSample {{\n    return atlas_{name}(p);\n}}\n\nfn scene_atlas_merged(i: u32, j: u32) -> bool {{\n    return atlas_{name}_merged(i, j);\n}}\n"),
        None => writeln!(out, "fn scene_atlas(p: vec3<f32>) -> AtlasSample {{\n    return uv_failed(UV_TOO_FAR, -1.0);\n}}\n\nfn scene_atlas_merged(i: u32, j: u32) -> bool {{\n    return false;\n}}\n"),
    };

    // Materials: id 0 is the default; id i + 1 is program.materials[i].
    let _ = writeln!(
        out,
        "// `footprint` is the pixel's size on the surface; tangent_u and tangent_v span the tangent plane.\nfn scene_material(id: i32, p: vec3<f32>, n: vec3<f32>, footprint: f32) -> Material {{\n    let tangent_u = normalize(select(cross(n, vec3<f32>(0.0, 0.0, 1.0)), cross(n, vec3<f32>(1.0, 0.0, 0.0)), abs(n.z) > 0.9));\n    let tangent_v = cross(n, tangent_u);\n    switch id {{"
    );
    for (i, m) in materials.iter().enumerate() {
        let start = out.len();
        textures.atlases.clear();
        let mut attr = |v: &Value, what: &str| {
            textures.srgb = matches!(what, "color" | "emission");
            match field(v, &mut textures) {
                Ok(e) => e,
                Err(e) => {
                    problems.push(Diagnostic::error(
                        codes::E_CODEGEN,
                        format!(
                            "cannot generate the {what} of material `{}`: {}",
                            m.name, e.0
                        ),
                        program.defs[m.def].span,
                        "in this material",
                    ));
                    String::from("0.0")
                }
            }
        };
        let color = match m.color.ty().base() {
            crate::sema::Ty::Vec(4) => format!("({}).rgb", attr(&m.color, "color")),
            crate::sema::Ty::Vec(3) => attr(&m.color, "color"),
            _ => format!("vec3<f32>({})", attr(&m.color, "color")),
        };
        let (r, mt, e) = (
            attr(&m.roughness, "roughness"),
            attr(&m.metallic, "metallic"),
            attr(&m.emission, "emission"),
        );
        let samples: String = textures
            .atlases
            .iter()
            .map(|k| {
                format!(
                    "            let atlas_sample_{k} = atlas_{}(p);\n",
                    program.atlases[*k].name
                )
            })
            .collect();
        let _ = writeln!(out, "        case {}: {{\n{samples}            return Material({color}, {r}, {mt}, {e});\n        }}", i + 1);
        source_map.push(SourceRegion {
            wgsl: start..out.len(),
            span: program.defs[m.def].item_span,
            what: format!("material `{}`", m.name),
        });
    }
    let _ = writeln!(out, "        default: {{\n            return Material(vec3<f32>(0.8), 0.5, 0.0, vec3<f32>(0.0));\n        }}\n    }}\n}}\n");
    if !problems.is_empty() {
        return Err(problems);
    }

    let mut bindings = vec![Binding {
        group: 0,
        binding: 0,
        name: "globals".into(),
        kind: "uniform",
        detail: "Globals".into(),
        used_by: vec!["vs_main", "fs_main"],
    }];
    for (i, t) in textures.textures.iter().enumerate() {
        let _ = writeln!(
            out,
            "@group(0) @binding({}) var texture_{i}: texture_2d<f32>;",
            1 + 2 * i
        );
        let _ = writeln!(
            out,
            "@group(0) @binding({}) var sampler_{i}: sampler;",
            2 + 2 * i
        );
        bindings.push(Binding {
            group: 0,
            binding: 1 + 2 * i as u32,
            name: format!("texture_{i}"),
            kind: "texture-2d",
            detail: t.path.clone(),
            used_by: vec!["fs_main"],
        });
        bindings.push(Binding {
            group: 0,
            binding: 2 + 2 * i as u32,
            name: format!("sampler_{i}"),
            kind: "sampler",
            detail: t.wrap.clone(),
            used_by: vec!["fs_main"],
        });
    }
    bindings.push(Binding {
        group: 1,
        binding: 0,
        name: "grid".into(),
        kind: "uniform",
        detail: "GridParams".into(),
        used_by: vec!["cs_grid"],
    });
    bindings.push(Binding {
        group: 1,
        binding: 1,
        name: "points".into(),
        kind: "storage-read",
        detail: "array<vec4<f32>>".into(),
        used_by: vec!["cs_points", "cs_atlas"],
    });
    bindings.push(Binding {
        group: 1,
        binding: 2,
        name: "results".into(),
        kind: "storage-read-write",
        detail: "array<vec4<f32>>".into(),
        used_by: vec!["cs_points", "cs_grid", "cs_atlas"],
    });
    out.push_str(ENTRY_POINTS);

    let mut header = String::new();
    let _ = writeln!(
        header,
        "// Generated by sdfc {}. Do not edit: regenerate from the scene.",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(header, "//\n// Entry points: vs_main + fs_main (full-screen render), cs_points, cs_grid and cs_atlas (compute, workgroup 64).\n// Bind groups:");
    for b in &bindings {
        let _ = writeln!(
            header,
            "//   @group({}) @binding({}) {} {}: {} (used by {})",
            b.group,
            b.binding,
            b.kind,
            b.name,
            b.detail,
            b.used_by.join(", ")
        );
    }
    let _ = writeln!(
        header,
        "// Globals is {} vec4<f32> fields, in order: {}.",
        GLOBALS_LAYOUT.len(),
        GLOBALS_LAYOUT.join(", ")
    );
    let _ = writeln!(header, "// GridParams: origin.xyz, spacing.xyz (vec4<f32> each), dims.xyz (vec4<u32>); results[i] = (distance, gradient.xyz).\n");
    let wgsl = format!("{header}{SDF_LIBRARY}\n{RENDER_LIBRARY}\n{UV_LIBRARY}\n{out}");
    // The regions were recorded in `out`, which ends the module.
    let shift = wgsl.len() - out.len();
    for r in &mut source_map {
        r.wgsl = r.wgsl.start + shift..r.wgsl.end + shift;
    }
    let manifest = Manifest {
        entry_points: vec![
            ("vs_main", "vertex"),
            ("fs_main", "fragment"),
            ("cs_points", "compute"),
            ("cs_grid", "compute"),
            ("cs_atlas", "compute"),
        ],
        bindings,
        globals_layout: GLOBALS_LAYOUT.to_vec(),
        lipschitz: target.lipschitz(),
        shapes: scene.shapes.iter().map(|s| s.name.clone()).collect(),
        textures: textures.textures,
    };
    Ok(Module {
        wgsl,
        manifest,
        source_map,
    })
}

fn map_fn(out: &mut String, name: &str, shape: &ir::Shape) {
    let mut w = Writer::new();
    let d = w.shape(shape, shape.root(), "p");
    let _ = writeln!(
        out,
        "fn {name}(p: vec3<f32>) -> vec2<f32> {{\n{}    return {d};\n}}\n",
        w.out
    );
}

/// The scene-independent tail of every module: tracing, normals and entry points.
const ENTRY_POINTS: &str = include_str!("entry.wgsl.in");
