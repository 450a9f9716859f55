//! Code generation: the checked program, its IR and its prepared atlases → one
//! standalone, specialized WGSL module per scene, validated by naga before anyone
//! sees it.
//!
//! The module is the shared library (`shaders/sdf.wgsl`, `shaders/render.wgsl`,
//! `shaders/uv.wgsl`, less the functions the scene does not reach: [`shake`]) followed
//! by the scene: an `sdf_NAME(p) -> f32` per named shape,
//! the render target's `scene_map`, its atlases (from the template
//! `shaders/atlas.wgsl.in`), its materials, the bindings of the one binding table
//! ([`bindings`]) and the entry points (`shaders/entry.wgsl.in`). Its header
//! documents the bind groups; [`Manifest`] describes them as JSON.

pub mod aov;
mod atlas;
mod atlases;
pub mod bindings;
pub mod coarse;
mod dual;
mod emit;
mod field;
mod group;
pub mod inline_cost;
mod literal;
mod manifest;
mod materials;
pub mod mesh;
pub mod moving;
pub mod params;
pub mod shake;
pub mod targets;
pub mod template;
pub mod tiles;
pub mod users;
pub mod views;

pub use manifest::*;

pub use moving::{MovingAtlas, MovingError, SEED_WORDS};

pub use atlas::{SeedData, SeedGridChoice, WalkForm, AUTO_BAKED_SEEDS};
pub use bindings::Binding;
pub use emit::lit;
pub use field::TextureUse;
pub use targets::{compact, translate, validate, NagaError, Target, Validated};

use crate::codes;
use crate::diagnostic::{Diagnostic, Severity};
use crate::ir::{self, Scene};
use crate::sema::Program;
use crate::span::Span;
use crate::uv::Atlas;
use emit::Writer;
use field::{field, Uses};
use std::fmt::Write;

/// The shared WGSL library, included into every module.
pub const SDF_LIBRARY: &str = include_str!("../../shaders/sdf.wgsl");
pub const RENDER_LIBRARY: &str = include_str!("../../shaders/render.wgsl");
pub const UV_LIBRARY: &str = include_str!("../../shaders/uv.wgsl");
/// Forward derivatives of the distance functions (`vec4(∇f, f)`; `codegen::dual`).
pub const DUAL_LIBRARY: &str = include_str!("../../shaders/dual.wgsl");

/// A generated module with its description.
#[derive(Debug, Clone)]
pub struct Module {
    pub wgsl: String,
    /// The comment that opens the module (what it is, its entry points and bindings),
    /// also put before the compacted module `sdfc compile` writes.
    pub header: String,
    pub manifest: Manifest,
    /// Which scene definition each generated function came from.
    pub source_map: Vec<SourceRegion>,
    /// The atlases whose shapes depend on run-time parameters: their records in the
    /// `tables` buffer follow the parameters ([`Module::tables_at`]).
    pub moving: Vec<MovingAtlas>,
    /// The traced groups the runtime bins into screen tiles every frame, when the
    /// module was generated with `Options::tiles` and has some.
    pub tiling: Option<tiles::Tiling>,
    /// The multi-scale atlas pass's slots (atlases read by materials), when the module
    /// was generated with `Options::multiscale` and has some: the runtime runs
    /// `cs_coarse` before every frame (`gpu::coarse`). Zero without the pass.
    pub coarse_slots: usize,
}

/// The scene definition a region of generated code came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Definition {
    /// A named shape (`let NAME = …`), emitted as `sdf_NAME`.
    Shape(String),
    /// The render target, emitted as `scene_map`.
    RenderedShape,
    Atlas(String),
    Material(String),
}

impl std::fmt::Display for Definition {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Definition::Shape(n) => write!(f, "shape `{n}`"),
            Definition::RenderedShape => f.write_str("the rendered shape"),
            Definition::Atlas(n) => write!(f, "atlas `{n}`"),
            Definition::Material(n) => write!(f, "material `{n}`"),
        }
    }
}

/// A byte range of the generated WGSL and the scene definition that produced it.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceRegion {
    pub wgsl: std::ops::Range<usize>,
    pub span: Span,
    pub what: Definition,
}

impl Module {
    /// Sets every binding's `used_by` to the entry points that really reach it in the
    /// validated `naga` module of this WGSL ([`users`]), and the header's list to match
    /// (the source map follows the header's new length).
    pub fn derive_users(&mut self, naga: &naga::Module) {
        let reached = users::entry_bindings(naga);
        let old = bindings::describe(&self.manifest.bindings);
        let entry_points: Vec<&'static str> =
            self.manifest.entry_points.iter().map(|e| e.name).collect();
        for b in &mut self.manifest.bindings {
            b.used_by = entry_points
                .iter()
                .copied()
                .filter(|name| {
                    reached
                        .iter()
                        .any(|(ep, set)| ep == name && set.contains(&(b.group, b.binding)))
                })
                .collect();
        }
        let new = bindings::describe(&self.manifest.bindings);
        if old == new || !self.header.contains(&old) || !self.wgsl.starts_with(&self.header) {
            return;
        }
        let header = self.header.replacen(&old, &new, 1);
        self.wgsl = format!("{header}{}", &self.wgsl[self.header.len()..]);
        // Every region lies after the header, so it moves by the header's change.
        let shift = |o: usize| (o + header.len()).saturating_sub(self.header.len());
        for r in &mut self.source_map {
            r.wgsl = shift(r.wgsl.start)..shift(r.wgsl.end);
        }
        self.header = header;
    }

    /// The innermost region holding a byte offset of the WGSL.
    pub fn region_at(&self, offset: usize) -> Option<&SourceRegion> {
        self.source_map
            .iter()
            .filter(|r| r.wgsl.contains(&offset))
            .min_by_key(|r| r.wgsl.len())
    }

    /// naga's rejection of this module as an internal-compiler-error diagnostic on the
    /// scene span that produced the offending code; unlocated for code of the shared
    /// library, which no scene definition produced.
    pub fn internal_error(&self, e: &NagaError) -> Diagnostic {
        let first = e
            .message
            .lines()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("naga rejected the module")
            .trim()
            .to_string();
        let message = "internal compiler error: naga rejected the generated WGSL";
        let mut d = match e.offset.and_then(|o| self.region_at(o)) {
            Some(r) => Diagnostic::error(
                codes::E_INTERNAL,
                message,
                r.span,
                format!("naga rejected the WGSL generated for {}", r.what),
            ),
            None => Diagnostic::unlocated(Severity::Error, codes::E_INTERNAL, message).with_note(
                "naga rejected code sdfc adds to every module, not code from this scene",
            ),
        }
        .with_note(format!("naga: {first}"));
        if let Some(o) = e.offset {
            let line = self.wgsl[..o.min(self.wgsl.len())].matches('\n').count() + 1;
            d = d.with_note(format!("at line {line} of the generated WGSL"));
        }
        d.with_help("this is a bug in sdfc, not in the scene: please report it with the generated WGSL (`sdfc compile` saves it)")
    }
}

/// Choices for [`generate`].
#[derive(Debug, Clone, Default)]
pub struct Options {
    pub walk: WalkForm,
    /// The atlas of the atlas views and `cs_atlas` (default: the first).
    pub atlas: Option<String>,
    /// Leave out atlases and materials: the plain sphere-trace baseline of benchmarks.
    pub plain: bool,
    /// Whether the nearest-seed search uses the seed grid.
    pub seed_grid: SeedGridChoice,
    /// Leave out the warm start of Alg. 2's search (the previous query's nearest seed
    /// walked first): the baseline `sdfc bench` measures the warm start against.
    pub cold: bool,
    /// Every atlas answers one constant sample (no walk): the same scene, shading,
    /// shadows and texture reads with the uv-dependent inputs constant, the baseline
    /// `sdfc bench` measures the atlases against.
    pub constant_uv: bool,
    /// Large unions as code, one call per operand, instead of data with a bounding-volume
    /// hierarchy (`ir::group`): the baseline `sdfc bench --scale` measures groups against.
    /// The CPU reference always uses the groups.
    pub unions_as_code: bool,
    /// Per-seed pruning of the walks (`uv::prune`): a walk skips the union operands that
    /// cannot change the field within its reach. Exact, but off by default: on the
    /// software adapter its branches cost more than the primitives they skip (1.57×
    /// slower on the robot, `sdfc bench`); a GPU may decide otherwise (`--prune`).
    pub prune: bool,
    /// Where the atlases' seeds and merge graphs live: baked in as `var<private>` arrays
    /// or in the `tables` buffer (auto: baked up to [`AUTO_BAKED_SEEDS`] seeds).
    pub seed_data: SeedData,
    /// Which unions' operands are skipped by their boxes where they cannot change the
    /// union (`ir::guard`).
    pub bounds: Bounds,
    /// The walk differentiates every atlas's field by central differences, even where
    /// the compiler could differentiate it forward (`codegen::dual`): the baseline
    /// `sdfc bench --gradients differences` measures forward derivatives against. The
    /// CPU reference then differs from the shader by the differences' error.
    pub differences: bool,
    /// The render entry points trace the groups reached from the render target through
    /// hard unions and paints over the leaves their pixel's screen tile can meet
    /// (`codegen::tiles`): the module gets a `tiles` binding that the runtime fills
    /// every frame (`gpu::tiles`). Off by default, so that `compile` and `export-web`
    /// write modules any host can drive; `sdfc render`, the viewer and the benchmarks
    /// turn it on. No change to a module without such groups.
    pub tiles: bool,
    /// The multi-scale atlas pass (`codegen::coarse`): materials rebuild a render
    /// pixel's atlas samples from samples walked once per `coarse::STEP`² pixels by
    /// `cs_coarse`, where those agree. The module gets a `coarse` binding and the
    /// `cs_coarse` entry point, which the runtime dispatches before every frame
    /// (`gpu::coarse`). Off by default, like `tiles`: `sdfc render`, the viewer and
    /// the benchmarks turn it on. No change to a module whose materials read no atlas.
    pub multiscale: bool,
}

crate::choice::choice_enum! {
/// Which unions' operands the generated code skips by their bounding boxes
/// (`ir::guard`: exact, the field is unchanged everywhere). Off by default: on Mesa's
/// software adapter an `if` never skips work (gallivm runs both sides under lane masks),
/// so the box tests only add cost there (csg.sdf 1.14×, robot.sdf 1.15× slower plain
/// traces, `sdfc bench`); a GPU, whose warps branch, may decide otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Bounds {
    #[default]
    Off = "off": "None: every operand evaluated everywhere (the default).",
    Costly = "costly": "The operands that cost several primitives (ir::guard::MIN_COST).",
    All = "all": "Every operand that has a box, however cheap.",
}
}

impl Bounds {
    /// The cost from which an operand is guarded; None for none.
    pub fn min_cost(self) -> Option<f64> {
        match self {
            Bounds::Costly => Some(ir::guard::MIN_COST),
            Bounds::Off => None,
            Bounds::All => Some(0.0),
        }
    }
}

/// A material field, for messages and for the colour space of its textures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MaterialField {
    Color,
    Roughness,
    Metallic,
    Emission,
    Normal,
}

impl MaterialField {
    fn name(self) -> &'static str {
        match self {
            MaterialField::Color => "color",
            MaterialField::Roughness => "roughness",
            MaterialField::Metallic => "metallic",
            MaterialField::Emission => "emission",
            MaterialField::Normal => "normal",
        }
    }

    /// Colours are sampled as sRGB; data (roughness, metallic, normals) as linear.
    fn is_color(self) -> bool {
        matches!(self, MaterialField::Color | MaterialField::Emission)
    }
}

/// A problem of sdfc itself while generating (never of the scene).
fn internal(message: String) -> Vec<Diagnostic> {
    vec![
        Diagnostic::unlocated(Severity::Error, codes::E_INTERNAL, message)
            .with_help("this is a bug in sdfc, not in the scene: please report it"),
    ]
}

/// The shape a module renders, as the caller resolved it: the lowered shape, and the
/// name of the `let` it is when it is not the render item's target.
#[derive(Debug, Clone, Copy)]
pub struct Rendered<'a> {
    pub shape: &'a ir::Shape,
    pub name: Option<&'a str>,
}

/// Generates the module for a checked, error-free program, rendering `target` (the
/// driver resolves it once: [`crate::driver::pick_shape`]). `atlases` are the prepared
/// atlases of [`crate::driver::check`], one per atlas of the program; they are never
/// recomputed here. `options.atlas`, which names an atlas, is checked by the driver
/// before; here it is an internal error.
pub fn generate(
    program: &Program,
    scene: &Scene,
    atlases: &[Option<Atlas>],
    target: Rendered<'_>,
    options: &Options,
) -> Result<Module, Vec<Diagnostic>> {
    if atlases.len() != program.atlases.len() {
        return Err(internal(format!(
            "code generation got {} prepared atlases for {} atlases",
            atlases.len(),
            program.atlases.len()
        )));
    }
    let (name, target) = (target.name, target.shape);
    let mut g = Generator {
        program,
        out: String::new(),
        source_map: Vec::new(),
        heights: Vec::new(),
        tables: Vec::new(),
        groups: Vec::new(),
        unions_as_code: options.unions_as_code,
        guard_cost: options.bounds.min_cost(),
        moving: Vec::new(),
        tiled_masks: std::collections::BTreeSet::new(),
        multiscale: options.multiscale,
        reads: coarse::Reads::default(),
    };
    let scale = g.scene_constants(target);
    // Atlases on displaced shapes call their heights in their fields.
    for a in atlases.iter().flatten() {
        g.add_heights(a.shape.heights());
    }
    g.shapes(scene, target);
    g.render_target(scene, target, name);
    let slots = if options.tiles {
        tiles::slots(target, options.unions_as_code)
    } else {
        Default::default()
    };
    let traced = tiles::functions(&mut g.out, target, &slots, (g.unions_as_code, g.guard_cost));
    g.tiled_masks.extend(traced.iter().map(|t| group::mask(t)));
    g.groups.extend(traced);
    let tiling = (!slots.is_empty()).then(|| tiles::tiling(target, &slots, scale));
    let plain = options.plain;
    let mut uses = Uses::default();
    g.heights(&mut uses)?;
    // Displacements read atlases in the field itself, so even the plain baseline has them.
    if !plain || !g.heights.is_empty() {
        g.atlases(atlases, options)
            .map_err(|e| internal(e.to_string()))?;
    }
    g.atlas_choice(options, plain)?;
    let textures = g.materials(if plain { &[] } else { &program.materials }, uses)?;
    let (coarse_slots, aov) = g.multiscale_pass(atlases, options)?;
    let groups = !g.groups.is_empty();
    g.groups();
    if groups {
        g.out.push_str(group::READERS);
    }
    let params = params::ParamsLayout::of(&program.params);
    g.out.push_str(&params.wgsl_struct());
    let table = bindings::table(
        &textures,
        (!g.tables.is_empty(), tiling.is_some(), coarse_slots > 0),
        !params.fields.is_empty(),
    );
    let mut values = vec![
        ("bindings", bindings::declarations(&table)),
        ("atlas_aov", aov),
    ];
    values.extend(views::entry_values());
    let entry = template::fill(template::ENTRY, &values).map_err(|e| internal(e.to_string()))?;
    g.out.push_str(&entry);
    let mut module = g.finish(target, scene, table, textures, params);
    module.tiling = tiling;
    module.coarse_slots = coarse_slots;
    module.manifest.coarse = coarse::contract(&module.manifest.bindings, coarse_slots);
    Ok(module)
}

/// The module being written: the scene's code after the libraries, with its source map.
struct Generator<'a> {
    program: &'a Program,
    out: String,
    source_map: Vec<SourceRegion>,
    /// The displacements' heights the shapes call, once each.
    heights: Vec<std::sync::Arc<ir::Height>>,
    /// The words of the `tables` storage buffer (`Manifest::tables`).
    tables: Vec<u32>,
    /// The groups (large unions as data) the shapes call, once each by key.
    groups: Vec<std::sync::Arc<ir::group::Group>>,
    /// `Options::unions_as_code`.
    unions_as_code: bool,
    /// `Options::bounds`.
    guard_cost: Option<f64>,
    /// The atlases on moving shapes, with their records' offsets in `tables`.
    moving: Vec<MovingAtlas>,
    /// The kinds masks of the groups traced through tiles: their tiled walkers.
    tiled_masks: std::collections::BTreeSet<u32>,
    /// `Options::multiscale`.
    multiscale: bool,
    /// The atlases each material reads (the multi-scale pass's slots).
    reads: coarse::Reads,
}

impl Generator<'_> {
    /// The item span of the shape `let` named `name`.
    fn let_span(&self, name: &str) -> Option<Span> {
        self.program
            .defs
            .iter()
            .find(|d| d.kind == crate::sema::DefKind::Let && d.name == name)
            .map(|d| d.item_span)
    }

    /// Records that the code written since `start` came from `what` at `span`.
    fn region(&mut self, start: usize, span: Option<Span>, what: Definition) {
        if let Some(span) = span {
            self.source_map.push(SourceRegion {
                wgsl: start..self.out.len(),
                span,
                what,
            });
        }
    }

    /// `SCENE_LIPSCHITZ` and `SCENE_SCALE`; returns the scale.
    fn scene_constants(&mut self, target: &ir::Shape) -> f64 {
        let b = target.framing_bounds();
        let scale = (b.max - b.min).max_element().max(1e-3);
        let _ = writeln!(
            self.out,
            "// ---- scene ----\nconst SCENE_LIPSCHITZ: f32 = {};\nconst SCENE_SCALE: f32 = {};\n",
            lit(target.lipschitz().max(1.0)),
            lit(scale)
        );
        scale
    }

    /// `map_NAME` and `sdf_NAME` for every named shape, except those with a
    /// displacement the render target lacks: their heights' textures would be bindings
    /// the entry points never use (and so absent from pipelines' derived layouts).
    /// Such a shape gets its function when it is the target (`--shape NAME`).
    fn shapes(&mut self, scene: &Scene, target: &ir::Shape) {
        let rendered: Vec<usize> = target.heights().iter().map(|h| h.id).collect();
        for named in scene.shapes.iter().filter(|n| emits(n, &rendered)) {
            let start = self.out.len();
            let (h, groups) = map_fn(
                &mut self.out,
                &format!("map_{}", named.name),
                &named.shape,
                (self.unions_as_code, self.guard_cost),
            );
            self.add_heights(h);
            self.groups.extend(groups);
            let _ = writeln!(
                self.out,
                "fn sdf_{0}(p: vec3<f32>) -> f32 {{\n    return map_{0}(p).x;\n}}\n",
                named.name
            );
            let span = self.let_span(&named.name);
            self.region(start, span, Definition::Shape(named.name.clone()));
        }
    }

    /// `scene_map`: the render target.
    fn render_target(&mut self, scene: &Scene, target: &ir::Shape, name: Option<&str>) {
        let start = self.out.len();
        let (h, groups) = map_fn(
            &mut self.out,
            "scene_map",
            target,
            (self.unions_as_code, self.guard_cost),
        );
        self.add_heights(h);
        self.groups.extend(groups);
        self.surface(target);
        let span = match (name, &self.program.render) {
            (Some(n), _) => self.let_span(n),
            (None, Some(r)) => Some(r.target_span),
            (None, None) => scene.shapes.first().and_then(|s| self.let_span(&s.name)),
        };
        self.region(start, span, Definition::RenderedShape);
    }

    /// `scene_surface(id, p, n, footprint)`: the material the entry points shade with.
    /// Where a smooth union has painted operands, `scene_blend` (the target in the
    /// writer's blend mode, `ir::eval::eval_blend` on the CPU) gives two materials and
    /// a weight, and their attributes mix (the normal renormalized); otherwise it is
    /// `scene_material` of scene_map's material `id`.
    fn surface(&mut self, target: &ir::Shape) {
        if !target.blends_materials() {
            self.out.push_str("fn scene_surface(id: i32, p: vec3<f32>, n: vec3<f32>, footprint: f32) -> Material {\n    return scene_material(id, p, n, footprint);\n}\n\n");
            return;
        }
        let mut w = emit::Writer::new("scene_blend");
        w.blend = true;
        w.unions_as_code = self.unions_as_code;
        w.guard_cost = self.guard_cost;
        let d = w.shape(target, target.root(), "p");
        let _ = writeln!(
            self.out,
            "{}// Textured CSG: (distance, material a, material b, b's weight).\nfn scene_blend(p: vec3<f32>) -> vec4<f32> {{\n{}    return {d};\n}}\n",
            w.helpers, w.out
        );
        let heights = std::mem::take(&mut w.heights);
        self.add_heights(heights);
        self.groups.append(&mut w.groups);
        self.out.push_str("fn scene_surface(id: i32, p: vec3<f32>, n: vec3<f32>, footprint: f32) -> Material {\n    let bl = scene_blend(p);\n    var m = scene_material(i32(bl.y + 0.5), p, n, footprint);\n    if (bl.w > 0.0) {\n        let o = scene_material(i32(bl.z + 0.5), p, n, footprint);\n        m.color = mix(m.color, o.color, bl.w);\n        m.roughness = mix(m.roughness, o.roughness, bl.w);\n        m.metallic = mix(m.metallic, o.metallic, bl.w);\n        m.emission = mix(m.emission, o.emission, bl.w);\n        m.normal = sdfc_normalize_or(mix(m.normal, o.normal, bl.w), n);\n    }\n    return m;\n}\n\n");
    }

    /// Every group's table and offset, once each by key, and a walker per set of
    /// primitive kinds (after the code that calls them).
    fn groups(&mut self) {
        let groups = std::mem::take(&mut self.groups);
        if groups.is_empty() {
            return;
        }
        let (mut keys, mut masks) = (
            std::collections::HashSet::new(),
            std::collections::BTreeSet::new(),
        );
        for g in groups.iter().filter(|g| keys.insert(g.key.clone())) {
            let _ = writeln!(
                self.out,
                "const GROUP_{}_AT: u32 = {}u;",
                g.key,
                self.tables.len()
            );
            self.tables.extend_from_slice(&g.words);
            masks.insert(group::mask(g));
        }
        self.out.push('\n');
        for m in masks {
            self.out.push_str(&group::walker(m));
        }
        for &m in &self.tiled_masks {
            self.out.push_str(&group::tiled_walker(m));
        }
    }

    /// `scene_atlas` and `scene_atlas_merged`: the atlas of the atlas views and
    /// `cs_atlas` (the chosen one, or the first).
    fn atlas_choice(&mut self, options: &Options, plain: bool) -> Result<(), Vec<Diagnostic>> {
        let atlases = &self.program.atlases;
        // Generated names are mangled by index, never by the user's names.
        let chosen = match options.atlas.as_deref() {
            _ if plain => None,
            Some(name) => match atlases.iter().position(|a| a.name == name) {
                Some(k) => Some(k),
                None => return Err(internal(format!("code generation: no atlas `{name}`"))),
            },
            None => (!atlases.is_empty()).then_some(0),
        };
        let (sample, merged) = match chosen {
            Some(k) => (
                format!("atlas_{k}_at(p, false)"),
                format!("atlas_{k}_merged(i, j)"),
            ),
            None => (
                String::from("uv_failed(UV_TOO_FAR, -1.0)"),
                String::from("false"),
            ),
        };
        let _ = writeln!(
            self.out,
            "fn scene_atlas(p: vec3<f32>) -> AtlasSample {{\n    return {sample};\n}}\n\nfn scene_atlas_merged(i: u32, j: u32) -> bool {{\n    return {merged};\n}}\n"
        );
        Ok(())
    }

    fn add_heights(&mut self, heights: Vec<std::sync::Arc<ir::Height>>) {
        for h in heights {
            if !self.heights.iter().any(|x| x.id == h.id) {
                self.heights.push(h);
            }
        }
    }

    /// `height_ID(p, n) -> f32` for every displacement: scale times its height at
    /// surface point `p` (normal `n`), textures read in level 0 as data (linear).
    fn heights(&mut self, uses: &mut Uses) -> Result<(), Vec<Diagnostic>> {
        let mut problems = Vec::new();
        for h in self.heights.clone() {
            uses.start_function();
            uses.srgb = false;
            let e = match field(&h.value, uses) {
                Ok(e) => e,
                Err(e) => {
                    problems.push(Diagnostic::error(
                        codes::E_CODEGEN,
                        format!("cannot generate a displacement's height: {}", e.0),
                        Span::new(h.id, h.id),
                        "in this displacement",
                    ));
                    continue;
                }
            };
            let samples: String = uses
                .atlases
                .iter()
                .map(|&k| format!("    let atlas_sample_{0} = atlas_{0}(p);\n", k.index()))
                .collect();
            let (what, ty) = if h.dims == 2 {
                ("A shell map's uv", "vec2<f32>")
            } else {
                ("A displacement's height", "f32")
            };
            let lets: String = uses.lets.iter().map(|l| format!("    {l}\n")).collect();
            let _ = writeln!(
                self.out,
                "// {what} (level-0 texels: a zero footprint).\nfn height_{}(p: vec3<f32>, n: vec3<f32>) -> {ty} {{\n    let footprint = 0.0;\n    let tangent_u = normalize(select(cross(n, vec3<f32>(0.0, 0.0, 1.0)), cross(n, vec3<f32>(1.0, 0.0, 0.0)), abs(n.z) > 0.9));\n    let tangent_v = cross(n, tangent_u);\n{samples}{lets}    return {} * {ty}({e});\n}}\n",
                h.id,
                h.run_time_scale
                    .as_ref()
                    .map_or_else(|| lit(h.scale), |v| format!("({})", params::expr(v)))
            );
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems)
        }
    }

    /// The header, the libraries and the scene's code, with the source map shifted to
    /// the final offsets.
    fn finish(
        self,
        target: &ir::Shape,
        scene: &Scene,
        table: Vec<Binding>,
        textures: Vec<TextureUse>,
        params: params::ParamsLayout,
    ) -> Module {
        let rendered: Vec<usize> = target.heights().iter().map(|h| h.id).collect();
        let mut header = String::new();
        let _ = writeln!(
            header,
            "// Generated by sdfc {}. Do not edit: regenerate from the scene.",
            env!("CARGO_PKG_VERSION")
        );
        let pass = table
            .iter()
            .any(|b| b.resource == bindings::Resource::Coarse);
        let side = coarse::WORKGROUP_SIDE;
        let coarse_entry = if pass {
            format!(" and cs_coarse (the multi-scale atlas pass: compute, workgroup {side} × {side}, dispatched before each frame's render pass over a buffer sized for the frame, as the manifest's `coarse` says)")
        } else {
            String::new()
        };
        let _ = writeln!(header, "//\n// Entry points: vs_main + fs_main (full-screen render, one colour target) or fs_aov (with three rgba32float AOV targets), cs_points, cs_grid, cs_atlas, cs_material and cs_bake (compute, workgroup {WORKGROUP}){coarse_entry}.\n// Bind groups (each with the entry points that use it):");
        header.push_str(&bindings::describe(&table));
        let _ = writeln!(
            header,
            "// Globals is {} vec4<f32> fields, in order: {}.",
            GLOBALS_LAYOUT.len(),
            GLOBALS_LAYOUT.join(", ")
        );
        if !params.fields.is_empty() {
            let fields: Vec<String> = params
                .fields
                .iter()
                .map(|f| {
                    let max = f.max.map_or(String::from("inf"), |m| format!("{m}"));
                    format!(
                        "{} {} at {} in [{}, {max}]",
                        f.member, f.ty, f.offset, f.min
                    )
                })
                .collect();
            let _ = writeln!(
                header,
                "// Params ({} bytes, set by the host per frame; values outside a range void the step bounds): {}.",
                params.size,
                fields.join(", ")
            );
        }
        let _ = writeln!(header, "// GridParams: origin.xyz, spacing.xyz (vec4<f32> each), dims.xyz (vec4<u32>); results[i] = (distance, gradient.xyz).\n");
        // Only the library functions the scene's code reaches (shake.rs): naga parses
        // every byte of the module, and what it validates is what `compile` writes.
        let wgsl = format!("{header}{}{}", shake::library_for(&self.out), self.out);
        // The regions were recorded in `out`, which ends the module.
        let shift = wgsl.len() - self.out.len();
        let mut source_map = self.source_map;
        for r in &mut source_map {
            r.wgsl = r.wgsl.start + shift..r.wgsl.end + shift;
        }
        let manifest = Manifest {
            version: MANIFEST_VERSION,
            entry_points: ENTRY_POINTS
                .iter()
                .map(|&(name, stage)| EntryPoint {
                    name,
                    stage,
                    workgroup_size: if stage == "compute" {
                        [WORKGROUP, 1, 1]
                    } else {
                        [0; 3]
                    },
                })
                .chain(pass.then_some(EntryPoint {
                    name: "cs_coarse",
                    stage: "compute",
                    workgroup_size: [coarse::WORKGROUP_SIDE, coarse::WORKGROUP_SIDE, 1],
                }))
                .collect(),
            render_targets: render_targets(),
            bindings: table,
            globals_layout: GLOBALS_LAYOUT.to_vec(),
            globals: GLOBALS_LAYOUT
                .iter()
                .zip(GLOBALS_MEANING)
                .enumerate()
                .map(|(i, (&name, &meaning))| GlobalField {
                    name,
                    offset: 16 * i as u32,
                    meaning,
                })
                .collect(),
            scene: None,
            lipschitz: target.lipschitz(),
            shapes: scene
                .shapes
                .iter()
                .filter(|n| emits(n, &rendered))
                .map(|s| s.name.clone())
                .collect(),
            textures,
            tables: self.tables,
            params,
            coarse: None,
            pipeline_constants: views::contract(),
        };
        Module {
            wgsl,
            header,
            manifest,
            source_map,
            moving: self.moving,
            tiling: None,
            coarse_slots: 0,
        }
    }
}

/// Whether a named shape gets its `sdf_NAME`: its displacements are all the target's.
fn emits(named: &ir::NamedShape, rendered: &[usize]) -> bool {
    named
        .shape
        .heights()
        .iter()
        .all(|h| rendered.contains(&h.id))
}

/// The heights and groups a function calls.
type Calls = (
    Vec<std::sync::Arc<ir::Height>>,
    Vec<std::sync::Arc<ir::group::Group>>,
);

/// Writes `fn NAME(p) -> vec2<f32>` (distance, material); returns the heights and
/// groups it calls.
/// `mode`: unions as code, and the cost from which operands are guarded.
fn map_fn(
    out: &mut String,
    name: &str,
    shape: &ir::Shape,
    (unions_as_code, guard_cost): (bool, Option<f64>),
) -> Calls {
    let mut w = Writer::new(name);
    w.unions_as_code = unions_as_code;
    w.guard_cost = guard_cost;
    let d = w.shape(shape, shape.root(), "p");
    // The evals view counts the render target's evaluations.
    let count = if name == "scene_map" {
        "    sdf_evals = sdf_evals + 1u;\n"
    } else {
        ""
    };
    let _ = writeln!(
        out,
        "{}fn {name}(p: vec3<f32>) -> vec2<f32> {{\n{count}{}    return {d};\n}}\n",
        w.helpers, w.out
    );
    (w.heights, w.groups)
}
