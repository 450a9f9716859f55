//! The whole pipeline, owned here, run once per document, in one direction:
//!
//! ```text
//! text → tokens → AST → checked program ─┬─ prepared atlases (compile-time geometry)
//!                                        └─ IR scene ──▶ WGSL ──▶ naga-validated module
//! ```
//!
//! [`check`] runs the front end, the atlas geometry and lowering; [`compile`] turns an
//! [`Analysis`] into a validated module for a set of [`codegen::Options`], reusing its
//! IR scene and prepared atlases (code generation never recomputes them); [`check_all`]
//! is both with the default options, as `sdfc check` and the language server run them,
//! and keeps the validated module. Every command goes through these three.

use crate::access::Access;
use crate::codegen::{self, Module, Validated};
use crate::diagnostic::{self, Diagnostic};
use crate::ir::{self, Scene};
use crate::sema::{self, Program};
use crate::syntax::{self, Parsed};
use crate::uv::Atlas;
use std::collections::HashSet;
use std::path::Path;
use std::sync::Arc;

/// Everything the compiler knows about one document.
#[derive(Debug, Clone)]
pub struct Analysis {
    pub parsed: Parsed,
    pub program: Program,
    /// Every diagnostic, sorted by position.
    pub diagnostics: Vec<Diagnostic>,
    /// The prepared atlases (projected seeds, solved merge graphs), one per atlas of the
    /// program (None where one failed), once [`check`] ran the geometry; else empty.
    pub atlases: Vec<Option<Atlas>>,
    /// The lowered scene, once [`check`] found no errors.
    pub scene: Option<Scene>,
    /// What the scene's displacements and shell maps read on the CPU (its prepared
    /// atlases and decoded textures; [`ir::NoHeights`] for a scene without them): the
    /// environment of its fields ([`Analysis::field`]).
    pub heights: Arc<dyn ir::Heights>,
    /// The validated module for the default options, once [`check_all`] built it.
    pub compiled: Option<Arc<Compiled>>,
}

/// The language server analyses documents on a worker thread.
const _: () = {
    const fn send<T: Send>() {}
    send::<Analysis>();
};

impl Analysis {
    /// A shape of this document's scene with the environment of its heights: what the
    /// CPU reference evaluates ([`ir::eval`]).
    pub fn field<'a>(&'a self, shape: &'a ir::Shape) -> ir::Field<'a> {
        ir::Field::new(shape, &*self.heights)
    }

    /// Adds the diagnostics of decoding the file's bytes ([`syntax::decode`]). An invalid
    /// sequence is reported once, by its byte offset, and not again as an unexpected
    /// character.
    pub fn add_decoding(&mut self, decoding: Vec<Diagnostic>) {
        if decoding.is_empty() {
            return;
        }
        // A run of unexpected characters made only of replaced sequences starts at one
        // and ends at one.
        let starts: HashSet<usize> = decoding
            .iter()
            .filter_map(|d| d.span())
            .map(|s| s.start)
            .collect();
        let ends: HashSet<usize> = decoding
            .iter()
            .filter_map(|d| d.span())
            .map(|s| s.end)
            .collect();
        let covered = |d: &Diagnostic| {
            d.code == crate::codes::E_UNEXPECTED_CHAR
                && d.span()
                    .is_some_and(|s| starts.contains(&s.start) && ends.contains(&s.end))
        };
        self.diagnostics.retain(|d| !covered(d));
        self.diagnostics.extend(decoding);
        diagnostic::sort(&mut self.diagnostics);
    }

    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }

    /// The prepared atlas of the program's atlas `name`.
    pub fn atlas(&self, name: &str) -> Option<&Atlas> {
        let k = self.program.atlases.iter().position(|a| a.name == name)?;
        self.atlases.get(k)?.as_ref()
    }
}

/// A module that naga accepted, with naga's own form of it.
pub struct Compiled {
    pub module: Module,
    /// Shared with the analyses of later texts that differ only in trivia
    /// ([`crate::incremental`]).
    pub validated: Arc<Validated>,
}

impl std::fmt::Debug for Compiled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Compiled")
            .field("wgsl_bytes", &self.module.wgsl.len())
            .finish()
    }
}

/// Why [`compile`] produced no module. Each maps to one exit status of the CLI.
#[derive(Debug)]
pub enum CompileError {
    /// The scene has errors (exit 1): the diagnostics to show.
    Scene(Vec<Diagnostic>),
    /// A choice made outside the scene names nothing in it (exit 2): `--shape`,
    /// `--atlas`. The message ends with a did-you-mean or the list of choices.
    Usage(String),
    /// naga rejected the generated module (exit 3): an internal compiler error, on the
    /// scene definition that produced the rejected code, with the module for the report.
    Internal {
        diagnostic: Box<Diagnostic>,
        naga: codegen::NagaError,
        module: Box<Module>,
    },
}

/// One line: the first error's message (and how many more), the usage message, or the
/// internal error's.
impl std::fmt::Display for CompileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CompileError::Scene(d) => match d.first() {
                Some(first) if d.len() > 1 => {
                    write!(f, "{} ({} more errors)", first.message, d.len() - 1)
                }
                Some(first) => f.write_str(&first.message),
                None => f.write_str("the scene has errors"),
            },
            CompileError::Usage(m) => f.write_str(m),
            CompileError::Internal { diagnostic, .. } => f.write_str(&diagnostic.message),
        }
    }
}

impl std::error::Error for CompileError {}

/// Parses and checks a scene: the front end only. `base_dir` is the folder of the
/// scene file: texture paths are relative to it, and confined to it.
pub fn analyze(source: &str, base_dir: Option<&Path>) -> Analysis {
    analyze_with(source, &Access::new(base_dir))
}

/// [`analyze`] with the folders the scene may read given explicitly.
pub fn analyze_with(source: &str, access: &Access) -> Analysis {
    analyze_reusing(source, access, None)
}

/// [`analyze_with`], reusing the unchanged items of the document's last parse
/// ([`syntax::ItemCache`]; the language server keeps one per document).
pub fn analyze_reusing(
    source: &str,
    access: &Access,
    cache: Option<&mut syntax::ItemCache>,
) -> Analysis {
    let mut diagnostics = Vec::new();
    if let Some(d) = syntax::source::too_large(source) {
        diagnostics.push(d);
        return Analysis {
            parsed: syntax::parse("", &mut Vec::new()),
            program: Program::default(),
            diagnostics,
            atlases: Vec::new(),
            scene: None,
            heights: Arc::new(ir::NoHeights),
            compiled: None,
        };
    }
    let parsed = syntax::parse_reusing(source, &mut diagnostics, cache);
    let program = sema::check(&parsed.file, access, &mut diagnostics);
    diagnostic::sort(&mut diagnostics);
    Analysis {
        parsed,
        program,
        diagnostics,
        atlases: Vec::new(),
        scene: None,
        heights: Arc::new(ir::NoHeights),
        compiled: None,
    }
}

/// The whole check: the front end and, when it finds no errors, the compile-time
/// geometry of the atlases (seed projection, merge walks, frame and offset solves,
/// obstruction tests) with its diagnostics, and the lowered scene.
pub fn check(source: &str, base_dir: Option<&Path>) -> Analysis {
    check_with(source, &Access::new(base_dir))
}

/// [`check`] with the folders the scene may read given explicitly.
pub fn check_with(source: &str, access: &Access) -> Analysis {
    check_reusing(source, access, None)
}

/// [`check_with`], reusing the unchanged items of the document's last parse.
pub fn check_reusing(
    source: &str,
    access: &Access,
    cache: Option<&mut syntax::ItemCache>,
) -> Analysis {
    let mut analysis = analyze_reusing(source, access, cache);
    if !analysis.has_errors() {
        let (atlases, diags) =
            crate::uv::diagnose::prepare_all(&analysis.program, &crate::reference::Env::shared);
        analysis.atlases = atlases;
        analysis.diagnostics.extend(diags);
        diagnostic::sort(&mut analysis.diagnostics);
    }
    if !analysis.has_errors() {
        let (scene, heights, problems) = lower_displaced(&analysis.program, &analysis.atlases);
        analysis.heights = heights;
        if !problems.is_empty() {
            analysis.diagnostics.extend(problems);
            diagnostic::sort(&mut analysis.diagnostics);
            return analysis;
        }
        let overflows = derived_overflows(&analysis.program, &scene);
        if overflows.is_empty() {
            analysis.scene = Some(scene);
        } else {
            analysis.diagnostics.extend(overflows);
            diagnostic::sort(&mut analysis.diagnostics);
        }
    }
    analysis
}

/// Lowers the scene with the textures its displacements read (decoded only when it has
/// displacements), makes the environment its heights are evaluated in on the CPU (the
/// prepared atlases and the textures), and reports heights whose range or slope has no
/// bound.
fn lower_displaced(
    program: &Program,
    atlases: &[Option<crate::uv::Atlas>],
) -> (Scene, Arc<dyn ir::Heights>, Vec<Diagnostic>) {
    let displaced = program
        .defs
        .iter()
        .map(|d| &d.value)
        .chain(program.render.as_ref().map(|r| &r.target))
        .any(|v| sema::displaced(v).is_some());
    let textures = match displaced.then(|| ir::texture::Textures::load(program)) {
        None => ir::texture::Textures::default(),
        Some(Ok(t)) => t,
        Some(Err(why)) => {
            let span = program.textures.first().map(|t| t.span).unwrap_or_default();
            let d = Diagnostic::error(
                crate::codes::E_IMAGE_FORMAT,
                why,
                span,
                "a displacement reads this texture",
            );
            return (Scene::default(), Arc::new(ir::NoHeights), vec![d]);
        }
    };
    let (scene, errors) = ir::lower_with(program, &textures);
    let heights: Arc<dyn ir::Heights> = if displaced {
        crate::reference::Env::shared(atlases, &textures)
    } else {
        Arc::new(ir::NoHeights)
    };
    let steps = errors.steps.into_iter().map(|(span, why)| {
        Diagnostic::error(
            crate::codes::E_UNBOUNDED_STEP,
            "this shape's step bound has no bound over its parameters' ranges",
            span,
            why,
        )
        .with_note(
            "sphere tracing divides each step by the shape's Lipschitz bound, taken over every \
             value the parameters may take; `time` grows without bound",
        )
        .with_help(
            "bound the expression: `sin(time)`, `fract(time / 4)`, `clamp(time, 0, 10)`, or a \
             `param` with a range",
        )
    });
    let diags = errors
        .heights
        .into_iter()
        .map(|(span, why)| {
            Diagnostic::error(
                crate::codes::E_DISPLACE_HEIGHT,
                "the height of this displacement has no bound",
                span,
                why,
            )
            .with_note(
                "Eq. 58 needs the largest displacement and the sphere tracer a bound of the \
                 height's slope; both come from the height's expression and its textures' texels",
            )
        })
        .chain(steps)
        .collect();
    (scene, heights, diags)
}

/// Errors for shapes whose derived constants do not fit single precision
/// ([`ir::Shape::overflow`]), on their `let` or the render item.
fn derived_overflows(program: &Program, scene: &Scene) -> Vec<Diagnostic> {
    let named = scene.shapes.iter().filter_map(|s| {
        let why = s.shape.overflow()?;
        let span = program.lookup(&s.name)?.item_span;
        Some((format!("shape `{}`", s.name), why, span))
    });
    let render = scene.render.as_ref().and_then(|r| {
        let why = r.overflow()?;
        Some((
            String::from("the rendered shape"),
            why,
            program.render.as_ref()?.target_span,
        ))
    });
    let named: Vec<_> = named.collect();
    // The rendered shape is usually one of the named ones: one error is enough.
    let render = if named.is_empty() { render } else { None };
    named
        .into_iter()
        .chain(render)
        .map(|(what, why, span)| {
            Diagnostic::error(
                crate::codes::E_DERIVED_OVERFLOW,
                format!("{what} cannot be compiled: {why}"),
                span,
                "derived constants beyond single precision",
            )
            .with_note(
                "each twist or bend multiplies the bound of the distance's stretch, and a \
                 displacement's scale widens its band; long chains of warps or huge scales \
                 overflow the shaders' 32-bit floats",
            )
            .with_help("use fewer chained warps, smaller rates or smaller scales")
        })
        .collect()
}

/// [`check`] and, when it finds no errors, code generation and naga validation with the
/// default options: everything the compiler would report. The module is kept in
/// [`Analysis::compiled`]; a library file (shapes, no `render`) is built for its first
/// shape.
pub fn check_all(source: &str, base_dir: Option<&Path>) -> Analysis {
    check_all_with(source, &Access::new(base_dir))
}

/// [`check_all`] with the folders the scene may read given explicitly.
pub fn check_all_with(source: &str, access: &Access) -> Analysis {
    check_all_reusing(source, access, None)
}

/// [`check_all_with`], reusing the unchanged items of the document's last parse.
pub fn check_all_reusing(
    source: &str,
    access: &Access,
    cache: Option<&mut syntax::ItemCache>,
) -> Analysis {
    let mut analysis = check_reusing(source, access, cache);
    let Some(scene) = &analysis.scene else {
        return analysis;
    };
    let shape = match (&analysis.program.render, scene.shapes.first()) {
        (Some(_), _) => None,
        (None, Some(first)) => Some(first.name.clone()),
        (None, None) => return analysis,
    };
    match compile_shape(&analysis, shape.as_deref(), &codegen::Options::default()) {
        Ok(c) => analysis.compiled = Some(Arc::new(c)),
        Err(CompileError::Scene(d)) => analysis.diagnostics.extend(d),
        Err(CompileError::Internal { diagnostic, .. }) => analysis.diagnostics.push(*diagnostic),
        // The default options name nothing, so they cannot be a usage error.
        Err(CompileError::Usage(_)) => {}
    }
    diagnostic::sort(&mut analysis.diagnostics);
    analysis
}

/// Code generation and naga validation of a checked scene, reusing its IR scene and
/// prepared atlases.
pub fn compile(analysis: &Analysis, options: &codegen::Options) -> Result<Compiled, CompileError> {
    compile_shape(analysis, None, options)
}

/// [`compile`] with the named `let` shape rendered instead of the render item's target
/// (`--shape NAME`; `None`: the target).
pub fn compile_shape(
    analysis: &Analysis,
    shape: Option<&str>,
    options: &codegen::Options,
) -> Result<Compiled, CompileError> {
    let module = generate_shape(analysis, shape, options)?;
    let module = test_hooks::corrupt(module);
    match codegen::validate(&module.wgsl) {
        Ok(validated) => {
            if let Some(d) = inlined_too_large(analysis, shape, options, &validated.module) {
                return Err(CompileError::Scene(vec![d]));
            }
            let mut module = module;
            module.derive_users(&validated.module);
            Ok(Compiled {
                module,
                validated: Arc::new(validated),
            })
        }
        Err(naga) => Err(CompileError::Internal {
            diagnostic: Box::new(module.internal_error(&naga)),
            naga,
            module: Box::new(module),
        }),
    }
}

/// E0118 when an entry point of `module`, with every call inlined, is over
/// [`codegen::inline_cost::MAX_INLINED`]: on the compiled shape, with a label on each
/// atlas on a displaced shape (walks nested in walks are what multiplies).
fn inlined_too_large(
    analysis: &Analysis,
    shape: Option<&str>,
    options: &codegen::Options,
    module: &naga::Module,
) -> Option<Diagnostic> {
    use codegen::inline_cost::{inlined_sizes, MAX_INLINED};
    let (entry, size) = inlined_sizes(module).into_iter().next()?;
    if size <= MAX_INLINED {
        return None;
    }
    let program = &analysis.program;
    let span = match shape {
        Some(name) => program.defs.iter().find(|d| d.name == name).map(|d| d.span),
        None => program.render.as_ref().map(|r| r.target_span),
    }
    .unwrap_or_default();
    let mut d = Diagnostic::error(
        crate::codes::E_INLINED_SIZE,
        format!(
            "this shape's code is too large for a driver to build: `{entry}` has a \
             loop-weighted inlined size of {size}, over the limit of {MAX_INLINED}"
        ),
        span,
        "compiled here",
    );
    for a in program.atlases.iter() {
        if let Some(call) = sema::displaced(&a.shape) {
            d = d.with_label(
                a.shape_span,
                format!(
                    "the walks of atlas `{}` evaluate this displaced shape",
                    a.name
                ),
            );
            d = d.with_label(call, "each evaluation walks the height's atlas");
        }
    }
    d = d.with_note(
        "drivers inline every function: each displacement or shell map evaluates its \
         base 7 times, a height that reads an atlas holds a copy of its walk, and a walk \
         holds a copy of its shape per evaluation, so stacked displacements and walks \
         nested in walks multiply; the size counts each expression once per inlined \
         copy, 4 times more for each loop around it",
    );
    let help = if options.walk == codegen::WalkForm::Unrolled {
        "compile with `--walk loop` (one copy of each walk's step), stack fewer \
         displacements and shell maps, or read the base shape's atlas instead of an \
         atlas on a displaced shape"
    } else {
        "stack fewer displacements and shell maps, or read the base shape's atlas \
         instead of an atlas on a displaced shape"
    };
    Some(d.with_help(help))
}

/// The generated (not yet validated) module of a checked scene.
pub fn generate(analysis: &Analysis, options: &codegen::Options) -> Result<Module, CompileError> {
    generate_shape(analysis, None, options)
}

/// [`generate`] for the named `let` shape (`None`: the render item's target).
pub fn generate_shape(
    analysis: &Analysis,
    name: Option<&str>,
    options: &codegen::Options,
) -> Result<Module, CompileError> {
    let scene = match &analysis.scene {
        Some(s) if !analysis.has_errors() => s,
        _ => {
            let errors = analysis.diagnostics.iter().filter(|d| d.is_error());
            return Err(CompileError::Scene(errors.cloned().collect()));
        }
    };
    let shape = pick_shape(scene, name).map_err(CompileError::Usage)?;
    if let Some(name) = options.atlas.as_deref() {
        pick_atlas(&analysis.program, Some(name)).map_err(CompileError::Usage)?;
    }
    let target = codegen::Rendered { shape, name };
    codegen::generate(&analysis.program, scene, &analysis.atlases, target, options)
        .map_err(CompileError::Scene)
}

/// "did you mean `best`?" among `choices`, or the list of them.
pub fn suggest<'a>(name: &str, choices: impl IntoIterator<Item = &'a str>) -> String {
    let choices: Vec<&str> = choices.into_iter().collect();
    match crate::sema::closest(name, choices.iter().copied()) {
        Some(best) => format!("did you mean `{best}`?"),
        None if choices.is_empty() => String::from("there are none"),
        None => format!("choose one of: {}", choices.join(", ")),
    }
}

/// The shape to render or evaluate: the named one, else the render target, else the
/// only shape. An error is a usage message (the choice was made outside the scene).
pub fn pick_shape<'a>(scene: &'a Scene, name: Option<&str>) -> Result<&'a ir::Shape, String> {
    let names = || scene.shapes.iter().map(|s| s.name.as_str());
    match name {
        Some(n) => scene
            .shape(n)
            .ok_or_else(|| format!("the scene has no shape `{n}`; {}", suggest(n, names()))),
        None => match (&scene.render, scene.shapes.as_slice()) {
            (Some(r), _) => Ok(r),
            (None, [only]) => Ok(&only.shape),
            (None, []) => Err(String::from("the scene has no shape")),
            (None, _) => Err(format!(
                "the scene has no render item; choose a shape with --shape: {}",
                names().collect::<Vec<_>>().join(", ")
            )),
        },
    }
}

/// The atlas named outside the scene, or the only one (None when there is none).
pub fn pick_atlas<'a>(
    program: &'a Program,
    name: Option<&str>,
) -> Result<Option<&'a sema::AtlasDef>, String> {
    let names = || program.atlases.iter().map(|a| a.name.as_str());
    match name {
        Some(n) => match program.atlases.iter().find(|a| a.name == n) {
            Some(a) => Ok(Some(a)),
            None => Err(format!(
                "the scene has no atlas `{n}`; {}",
                suggest(n, names())
            )),
        },
        None => match program.atlases.as_slice() {
            [] => Ok(None),
            [only] => Ok(Some(only)),
            _ => Err(format!(
                "the scene has several atlases; choose one with --atlas: {}",
                names().collect::<Vec<_>>().join(", ")
            )),
        },
    }
}

/// The injection point of the internal-compiler-error tests:
/// `SDFC_TEST_CORRUPT_WGSL=material` breaks the first material's code, any other value
/// appends a broken function, so the E0900 path runs end to end through the real binary.
/// Without the variable (or with it empty) it does nothing. (It is in every build, not behind a cargo
/// feature: a feature the tests turn on would compile the library a second time in CI.)
pub mod test_hooks {
    use crate::codegen::Module;

    pub fn corrupt(mut module: Module) -> Module {
        match std::env::var("SDFC_TEST_CORRUPT_WGSL").as_deref() {
            Ok("material") => corrupt_first_material(&mut module),
            Ok("") | Err(_) => {}
            Ok(_) => module.wgsl.push_str("\nfn corrupted( {\n"),
        }
        module
    }

    /// Inserts an undefined name at the start of the first material's code, keeping the
    /// source map in step.
    pub fn corrupt_first_material(module: &mut Module) {
        let Some(at) = module
            .source_map
            .iter()
            .find(|r| matches!(r.what, crate::codegen::Definition::Material(_)))
            .map(|r| r.wgsl.start)
        else {
            return;
        };
        let line_end = module.wgsl[at..].find('\n').map_or(at, |i| at + i + 1);
        let broken = "            let corrupted = undefined_name;\n";
        module.wgsl.insert_str(line_end, broken);
        for r in &mut module.source_map {
            if r.wgsl.start >= line_end {
                r.wgsl.start += broken.len();
            }
            if r.wgsl.end >= line_end {
                r.wgsl.end += broken.len();
            }
        }
    }
}
