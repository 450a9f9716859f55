//! The checker's item level: definitions, atlases, materials and the render item.

use super::builtins::{Check, SettingSpec, ATLAS_SETTINGS, MATERIAL_SETTINGS, RENDER_SETTINGS};
use super::settings::Settings;
use super::show::fmt_num;
use super::types::Value;
use super::*;
use crate::access::Access;
use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::syntax::ast::{self, AtlasStmt, Ident, ItemKind, Setting};
use std::collections::{HashMap, HashSet};

/// Checks a parsed file. `access` says where texture paths are resolved and which
/// folders they may reach; without a base folder, texture files are not looked up.
pub fn check(file: &ast::File, access: &Access, diags: &mut Vec<Diagnostic>) -> Program {
    let mut c = Checker {
        diags,
        access,
        prog: Program::default(),
        scope: HashMap::new(),
        items: HashMap::new(),
        used: HashSet::new(),
        used_early: HashSet::new(),
        duplicates: HashSet::new(),
        sizes: super::size::Sizes::default(),
        suggestion_budget: SUGGESTION_BUDGET,
    };
    c.run(file);
    c.prog
}

/// The closest candidate within a small edit distance, for "did you mean" help.
pub fn suggest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (name.chars().count() / 3).max(1);
    candidates
        .into_iter()
        // The edit distance is at least the difference in characters (a byte-length
        // difference over 4 per allowed edit cannot be within the limit).
        .filter(|c| c.len().abs_diff(name.len()) <= 4 * limit)
        .filter(|c| *c != name)
        .map(|c| (strsim::osa_distance(name, c), c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, c)| (*d, *c))
        .map(|(_, c)| c)
}

pub(crate) struct Checker<'d> {
    pub(crate) diags: &'d mut Vec<Diagnostic>,
    pub(crate) access: &'d Access,
    pub(crate) prog: Program,
    /// Top-level names visible so far.
    pub(crate) scope: HashMap<String, DefId>,
    /// Every top-level name of the file with its first definition, for "used before its definition".
    pub(crate) items: HashMap<String, Span>,
    pub(crate) used: HashSet<DefId>,
    /// Names used before their definition (already reported; not "unused").
    pub(crate) used_early: HashSet<String>,
    /// Definitions that repeat an earlier name (already reported; not "unused").
    duplicates: HashSet<DefId>,
    /// Depths and sizes of values with their `let`s inlined.
    sizes: super::size::Sizes,
    /// Name comparisons left for did-you-mean suggestions in this file.
    pub(crate) suggestion_budget: usize,
}

/// The most seeds one atlas may have.
pub const MAX_SEEDS: usize = 1024;
/// The most merges one atlas may have.
pub const MAX_MERGES: usize = 1024;

/// How many name comparisons did-you-mean suggestions may make in one file.
const SUGGESTION_BUDGET: usize = 1_000_000;

impl Checker<'_> {
    /// A `let`'s value, or an error when, with the `let`s it uses inlined, it is deeper
    /// or larger than the limits of [`super::size`].
    fn bounded(&mut self, v: Value, span: Span) -> Value {
        use super::size::{MAX_INLINED_DEPTH, MAX_INLINED_SIZE};
        let (depth, size) = self.sizes.measure(&v);
        let problem = if depth > MAX_INLINED_DEPTH {
            Some((
                codes::E_TOO_DEEP,
                format!(
                    "with the `let`s it uses inlined, this value is {depth} levels deep; the limit is {MAX_INLINED_DEPTH}"
                ),
            ))
        } else if size > MAX_INLINED_SIZE {
            Some((
                codes::E_TOO_LARGE_VALUE,
                format!(
                    "with the `let`s it uses inlined, this value has more than {MAX_INLINED_SIZE} operations{}",
                    if size == u64::MAX { String::new() } else { format!(" ({size})") }
                ),
            ))
        } else {
            None
        };
        match problem {
            None => v,
            Some((code, message)) => {
                self.error(
                    Diagnostic::error(code, message, span, "over the limit")
                        .with_note(
                            "a `let` is inlined where it is used: a chain of `let`s each using \
                             the one before grows deeper, and one used twice by the next \
                             doubles in size",
                        )
                        .with_help("use fewer chained `let`s, or reuse a shape fewer times"),
                );
                Value::Error
            }
        }
    }

    pub(crate) fn error(&mut self, d: Diagnostic) {
        self.diags.push(d);
    }

    pub(crate) fn define(
        &mut self,
        name: &Ident,
        kind: DefKind,
        item_span: Span,
        value: Value,
    ) -> DefId {
        let id = DefId::new(self.prog.defs.len());
        self.prog.defs.push(Def {
            name: name.name.clone(),
            kind,
            span: name.span,
            item_span,
            ty: value.ty(),
            value,
        });
        id
    }

    fn run(&mut self, file: &ast::File) {
        // First pass: every item name, to report duplicates and uses before definitions.
        let mut duplicate = vec![false; file.items.len()];
        for (i, item) in file.items.iter().enumerate() {
            if let Some(name) = item.name() {
                if let Some(first) = self.items.get(&name.name) {
                    duplicate[i] = true;
                    let first = *first;
                    self.error(
                        Diagnostic::error(
                            codes::E_DUPLICATE_DEF,
                            format!("`{}` is defined twice", name.name),
                            name.span,
                            "defined again here",
                        )
                        .with_label(first, "first defined here")
                        .with_help("give one of them another name"),
                    );
                } else {
                    self.items.insert(name.name.clone(), name.span);
                }
            }
        }
        let mut first_render: Option<Span> = None;
        for (item, dup) in file.items.iter().zip(duplicate) {
            let id = match &item.kind {
                ItemKind::Let { name, value } => {
                    let v = self.expr(value);
                    let v = self.bounded(v, value.span);
                    Some((self.define(name, DefKind::Let, item.span, v), name))
                }
                ItemKind::Param { name, value, range } => Some((
                    self.param_item(name, value, range.as_ref(), item.span),
                    name,
                )),
                ItemKind::Atlas { name, shape, body } => {
                    Some((self.atlas(name, shape, body, item.span), name))
                }
                ItemKind::Material { name, body } => {
                    Some((self.material(name, body, item.span), name))
                }
                ItemKind::Render { target, body } => {
                    let span = Span::new(item.span.start, item.span.start + "render".len());
                    if let Some(first) = first_render {
                        self.error(
                            Diagnostic::error(
                                codes::E_DUPLICATE_RENDER,
                                "a scene has at most one `render` item",
                                span,
                                "second `render` item",
                            )
                            .with_label(first, "first `render` item"),
                        );
                    } else {
                        first_render = Some(span);
                    }
                    self.render(target, body, item.span);
                    None
                }
                ItemKind::Error { name } => name
                    .as_ref()
                    .map(|n| (self.define(n, DefKind::Let, item.span, Value::Error), n)),
            };
            if let Some((id, name)) = id {
                if dup {
                    self.duplicates.insert(id);
                } else {
                    self.scope.insert(name.name.clone(), id);
                }
            }
        }
        self.unused();
    }

    fn unused(&mut self) {
        let mut warnings = Vec::new();
        for (i, def) in self.prog.defs.iter().enumerate() {
            let id = DefId::new(i);
            if self.used.contains(&id)
                || self.duplicates.contains(&id)
                || self.used_early.contains(&def.name)
                || def.name.starts_with('_')
                || def.value.is_error()
            {
                continue;
            }
            match def.kind {
                DefKind::Let => warnings.push(
                    Diagnostic::warning(
                        codes::W_UNUSED,
                        format!("`{}` is never used", def.name),
                        def.span,
                        "defined here",
                    )
                    .with_help(format!(
                        "use it, remove it, or name it `_{}` to keep it",
                        def.name
                    )),
                ),
                DefKind::Material => warnings.push(
                    Diagnostic::warning(
                        codes::W_UNUSED_ITEM,
                        format!("material `{}` is never used", def.name),
                        def.span,
                        "defined here",
                    )
                    .with_help(format!("apply it with `shape.paint({})`", def.name)),
                ),
                _ => {}
            }
        }
        self.diags.extend(warnings);
    }

    /// Checks the settings of a block against its table; returns the values by setting name.
    fn settings(
        &mut self,
        block: &str,
        specs: &'static [SettingSpec],
        body: &[&Setting],
    ) -> HashMap<&'static str, (Value, Span)> {
        let mut out: HashMap<&'static str, (Value, Span)> = HashMap::new();
        let mut seen: HashMap<&str, Span> = HashMap::new();
        for s in body {
            let value = self.expr(&s.value);
            let Some(spec) = specs.iter().find(|spec| spec.name == s.name.name) else {
                let mut d = Diagnostic::error(
                    codes::E_UNKNOWN_SETTING,
                    format!("`{block}` blocks have no setting `{}`", s.name.name),
                    s.name.span,
                    "unknown setting",
                );
                if let Some(best) = suggest(&s.name.name, specs.iter().map(|x| x.name)) {
                    d = d.with_suggestion(best);
                }
                let names: Vec<&str> = specs.iter().map(|x| x.name).collect();
                self.error(d.with_note(format!(
                    "the settings of `{block}` are: {}",
                    names.join(", ")
                )));
                continue;
            };
            if let Some(first) = seen.get(spec.name) {
                let first = *first;
                self.error(
                    Diagnostic::error(
                        codes::E_DUPLICATE_SETTING,
                        format!("`{}` is set twice", spec.name),
                        s.name.span,
                        "set again here",
                    )
                    .with_label(first, "first set here"),
                );
                continue;
            }
            seen.insert(spec.name, s.name.span);
            let v = self.setting_value(spec, value, s.value.span);
            out.insert(spec.name, (v, s.value.span));
        }
        out
    }

    fn setting_value(&mut self, spec: &SettingSpec, value: Value, span: Span) -> Value {
        if value.is_error() {
            return value;
        }
        if matches!(value, Value::Uniform(_)) && !spec.field {
            self.refuse_run_time(&format!("`{}`", spec.name), span);
            return Value::Error;
        }
        let ty = value.ty();
        if ty.is_field() && !spec.field {
            self.error(
                Diagnostic::error(
                    codes::E_NOT_CONSTANT,
                    format!("`{}` must be a constant", spec.name),
                    span,
                    format!("this is a surface field ({ty})"),
                )
                .with_note("only material attributes can vary over the surface"),
            );
            return Value::Error;
        }
        if !ty.base().fits(spec.ty) {
            let want = spec.ty.describe();
            self.error(Diagnostic::error(
                codes::E_TYPE_MISMATCH,
                format!("`{}` expects {want}, found {ty}", spec.name),
                span,
                format!("expected {want}"),
            ));
            return Value::Error;
        }
        if !self.check_constant(spec.name, spec.check, &value, span) {
            return Value::Error;
        }
        value
    }

    /// Applies a parameter check to a constant; reports and returns false when it fails.
    pub(crate) fn check_constant(
        &mut self,
        name: &str,
        check: Check,
        value: &Value,
        span: Span,
    ) -> bool {
        let Some(c) = value.components() else {
            if let (Check::OneOf(options), Value::Str(s)) = (check, value) {
                if !options.contains(&s.as_str()) {
                    let list = options
                        .iter()
                        .map(|o| format!("\"{o}\""))
                        .collect::<Vec<_>>()
                        .join(", ");
                    let mut d = Diagnostic::error(
                        codes::E_OUT_OF_RANGE,
                        format!("`{name}` must be one of {list}"),
                        span,
                        format!("found {s:?}"),
                    );
                    if let Some(best) = suggest(s, options.iter().copied()) {
                        d = d.with_help(format!("did you mean \"{best}\"?")).with_fix(
                            format!("replace with \"{best}\""),
                            span,
                            format!("\"{best}\""),
                        );
                    }
                    self.error(d);
                    return false;
                }
            }
            return true;
        };
        // Rendered only for a message: numbers are formatted exactly, which costs.
        let shown = || value.display();
        match check {
            Check::Positive if c.iter().any(|x| *x <= 0.0) => {
                self.error(Diagnostic::error(
                    codes::E_NOT_POSITIVE,
                    format!("`{name}` must be positive"),
                    span,
                    format!("this is {}", shown()),
                ));
                false
            }
            Check::NonNegative if c.iter().any(|x| *x < 0.0) => {
                self.error(Diagnostic::error(
                    codes::E_NOT_POSITIVE,
                    format!("`{name}` must not be negative"),
                    span,
                    format!("this is {}", shown()),
                ));
                false
            }
            Check::NonZero if c.iter().all(|x| *x == 0.0) => {
                self.error(Diagnostic::error(
                    codes::E_ZERO_VECTOR,
                    format!("`{name}` is a direction and cannot be zero"),
                    span,
                    "the zero vector has no direction",
                ));
                false
            }
            _ => true,
        }
    }

    fn const_vec3(&mut self, e: &ast::Expr, what: &str) -> Option<[f64; 3]> {
        let v = self.expr(e);
        match &v {
            Value::Error => None,
            Value::Vec(c) if c.len() == 3 => Some([c[0], c[1], c[2]]),
            Value::Uniform(_) => {
                self.refuse_run_time(&format!("a seed's {what}"), e.span);
                None
            }
            Value::Field(..) => {
                self.error(Diagnostic::error(
                    codes::E_NOT_CONSTANT,
                    format!("a seed's {what} must be a constant"),
                    e.span,
                    format!("this is a surface field ({})", v.ty()),
                ));
                None
            }
            other => {
                self.error(Diagnostic::error(
                    codes::E_TYPE_MISMATCH,
                    format!("a seed's {what} must be a vec3, found {}", other.ty()),
                    e.span,
                    "expected vec3",
                ));
                None
            }
        }
    }

    fn atlas(&mut self, name: &Ident, shape: &ast::Expr, body: &[AtlasStmt], span: Span) -> DefId {
        let shape_value = self.expr(shape);
        self.check_atlas_shape(&shape_value, shape.span);
        if !matches!(shape_value, Value::Shape(_) | Value::Error) {
            self.error(
                Diagnostic::error(
                    codes::E_ATLAS_NOT_SHAPE,
                    format!("an atlas needs a shape, found {}", shape_value.ty()),
                    shape.span,
                    "not a shape",
                )
                .with_note("seeds are placed on the surface of the shape after `on`"),
            );
        }
        let atlas_id = AtlasId::new(self.prog.atlases.len());
        let def = self.define(name, DefKind::Atlas, span, Value::Atlas(atlas_id));
        let settings: Vec<&Setting> = body
            .iter()
            .filter_map(|s| {
                if let AtlasStmt::Setting(s) = s {
                    Some(s)
                } else {
                    None
                }
            })
            .collect();
        let mut values = self.settings("atlas", ATLAS_SETTINGS, &settings);
        for (name, min, max, note) in [
            ("steps", 1.0, 64.0, "N is unrolled into the shader; the paper uses 5 to 40"),
            ("refine", 0.0, 8.0, "each correction costs about two more walks; 2 reach 2e-4 of the distance on a cylinder"),
        ] {
            if let Some((Value::Float(n), vspan)) = values.get(name) {
                let (n, vspan) = (*n, *vspan);
                if n.fract() != 0.0 || !(min..=max).contains(&n) {
                    self.error(
                        Diagnostic::error(
                            codes::E_OUT_OF_RANGE,
                            format!("`{name}` must be a whole number from {min} to {max}"),
                            vspan,
                            format!("this is {}", fmt_num(n)),
                        )
                        .with_note(note),
                    );
                    values.remove(name);
                }
            }
        }
        let params = AtlasParams::new(&Settings::new(ATLAS_SETTINGS, &values));

        let (seeds, local) = self.seeds(name, atlas_id, body);
        if seeds.is_empty() && !body.iter().any(|s| matches!(s, AtlasStmt::Error(_))) {
            self.error(
                Diagnostic::error(
                    codes::E_NO_SEEDS,
                    format!("atlas `{}` has no seed", name.name),
                    name.span,
                    "this atlas needs at least one seed",
                )
                .with_help("add one: `seed main = [0, 0, 1];`"),
            );
        }
        let broken = body.iter().any(|s| matches!(s, AtlasStmt::Error(_)));
        let mut merges = self.merges(name, body, &seeds, &local, broken);
        let seeds = self.limit(seeds, MAX_SEEDS, "seeds", |s| s.span, name);
        // Merges of seeds past the limit go with them.
        merges.retain(|m| m.a < seeds.len() && m.b < seeds.len());
        let merges = self.limit(merges, MAX_MERGES, "merges", |m| m.span, name);
        self.prog.atlases.push(AtlasDef {
            name: name.name.clone(),
            def,
            span,
            shape: shape_value,
            shape_span: shape.span,
            params,
            seeds,
            merges,
        });
        def
    }

    /// Keeps the first `max` of an atlas's seeds or merges; the first one past the limit
    /// is an error that names the limit.
    fn limit<T>(
        &mut self,
        mut items: Vec<T>,
        max: usize,
        what: &str,
        span: impl Fn(&T) -> Span,
        atlas: &Ident,
    ) -> Vec<T> {
        if items.len() > max {
            self.error(
                Diagnostic::error(
                    codes::E_TOO_MANY,
                    format!(
                        "atlas `{}` has {} {what}; the limit is {max}",
                        atlas.name,
                        items.len()
                    ),
                    span(&items[max]),
                    format!("{what} past the limit start here"),
                )
                .with_note(
                    "the merge geometry solved at check time grows with the seeds and merges \
                     (walks between merged seeds, and a solve for frames and offsets)",
                )
                .with_help("split the surface into several atlases"),
            );
            items.truncate(max);
        }
        items
    }

    /// Checks the seed statements of an atlas; returns the seeds and their indices by name.
    fn seeds(
        &mut self,
        atlas: &Ident,
        atlas_id: AtlasId,
        body: &[AtlasStmt],
    ) -> (Vec<SeedDef>, HashMap<String, usize>) {
        let mut seeds: Vec<SeedDef> = Vec::new();
        let mut local: HashMap<String, usize> = HashMap::new();
        for stmt in body {
            if let AtlasStmt::Seed {
                name: seed_name,
                position,
                tangent,
                span,
            } = stmt
            {
                let pos = self.const_vec3(position, "position");
                let tan = tangent.as_ref().and_then(|t| {
                    let v = self.const_vec3(t, "tangent")?;
                    if v == [0.0; 3] {
                        self.error(Diagnostic::error(
                            codes::E_ZERO_VECTOR,
                            "a seed's tangent cannot be zero",
                            t.span,
                            "the zero vector has no direction",
                        ));
                        return None;
                    }
                    Some(v)
                });
                if let Some(&first) = local.get(&seed_name.name) {
                    let first_span = seeds[first].span;
                    self.error(
                        Diagnostic::error(
                            codes::E_DUPLICATE_SEED,
                            format!(
                                "seed `{}` is declared twice in atlas `{}`",
                                seed_name.name, atlas.name
                            ),
                            seed_name.span,
                            "declared again here",
                        )
                        .with_label(first_span, "first declared here"),
                    );
                    continue;
                }
                let value = pos.map(|p| Value::Vec(p.to_vec())).unwrap_or(Value::Error);
                let def = self.define(seed_name, DefKind::Seed { atlas: atlas_id }, *span, value);
                local.insert(seed_name.name.clone(), seeds.len());
                seeds.push(SeedDef {
                    name: seed_name.name.clone(),
                    def,
                    span: seed_name.span,
                    position: pos.unwrap_or([0.0; 3]),
                    position_span: position.span,
                    tangent: tan,
                    tangent_span: tangent.as_ref().map(|t| t.span),
                });
            }
        }
        (seeds, local)
    }

    /// Checks the merge statements. When `broken`, a statement of the block did not parse
    /// and may have declared the seed, so unknown seeds are not reported.
    fn merges(
        &mut self,
        atlas: &Ident,
        body: &[AtlasStmt],
        seeds: &[SeedDef],
        local: &HashMap<String, usize>,
        broken: bool,
    ) -> Vec<MergeDef> {
        let mut merges: Vec<MergeDef> = Vec::new();
        for stmt in body {
            let AtlasStmt::Merge { seeds: names, span } = stmt else {
                continue;
            };
            if names.len() < 2 {
                self.error(
                    Diagnostic::error(
                        codes::E_BAD_MERGE,
                        "a merge needs at least two seeds",
                        *span,
                        "only one seed named",
                    )
                    .with_help("write `merge a b;` to blend seed `a` with seed `b`"),
                );
            }
            let mut ids = Vec::new();
            for n in names {
                match local.get(&n.name) {
                    Some(&i) => {
                        self.prog.references.push(Reference {
                            span: n.span,
                            def: seeds[i].def,
                        });
                        ids.push(Some(i));
                    }
                    None if broken => ids.push(None),
                    None => {
                        let mut d = Diagnostic::error(
                            codes::E_UNKNOWN_SEED,
                            format!("atlas `{}` has no seed `{}`", atlas.name, n.name),
                            n.span,
                            "unknown seed",
                        );
                        let other =
                            self.prog.defs.iter().find(|d| {
                                d.name == n.name && matches!(d.kind, DefKind::Seed { .. })
                            });
                        if let Some(other) = other {
                            let DefKind::Seed { atlas: other_atlas } = other.kind else {
                                unreachable!()
                            };
                            let owner = self
                                .prog
                                .atlases
                                .get(other_atlas.index())
                                .map(|a| a.name.clone())
                                .unwrap_or_default();
                            d = d
                                .with_label(
                                    other.span,
                                    format!("`{}` is a seed of atlas `{owner}`", n.name),
                                )
                                .with_note("only seeds of the same atlas can be merged");
                        } else if let Some(best) =
                            suggest(&n.name, local.keys().map(|s| s.as_str()))
                        {
                            d = d.with_suggestion(best);
                        }
                        self.error(d);
                        ids.push(None);
                    }
                }
            }
            for (k, pair) in ids.windows(2).enumerate() {
                let (Some(a), Some(b)) = (pair[0], pair[1]) else {
                    continue;
                };
                let edge_span = names[k].span.to(names[k + 1].span);
                if a == b {
                    self.error(Diagnostic::error(
                        codes::E_BAD_MERGE,
                        format!("seed `{}` is merged with itself", seeds[a].name),
                        edge_span,
                        "the same seed twice",
                    ));
                    continue;
                }
                if let Some(prev) = merges
                    .iter()
                    .find(|m| (m.a, m.b) == (a, b) || (m.a, m.b) == (b, a))
                {
                    let prev = prev.span;
                    self.error(
                        Diagnostic::warning(
                            codes::W_DUPLICATE_MERGE,
                            format!(
                                "seeds `{}` and `{}` are already merged",
                                seeds[a].name, seeds[b].name
                            ),
                            edge_span,
                            "merged again here",
                        )
                        .with_label(prev, "first merged here"),
                    );
                    continue;
                }
                merges.push(MergeDef {
                    a,
                    b,
                    span: edge_span,
                });
            }
        }
        merges
    }

    fn material(&mut self, name: &Ident, body: &[Setting], span: Span) -> DefId {
        let id = MaterialId::new(self.prog.materials.len());
        let def = self.define(name, DefKind::Material, span, Value::Material(id));
        let refs: Vec<&Setting> = body.iter().collect();
        let values = self.settings("material", MATERIAL_SETTINGS, &refs);

        let m = MaterialDef {
            name: name.name.clone(),
            def,
            span,
            attrs: MaterialAttrs::new(&Settings::new(MATERIAL_SETTINGS, &values)),
        };
        self.prog.materials.push(m);
        def
    }

    fn render(&mut self, target: &ast::Expr, body: &[Setting], span: Span) {
        let value = self.expr(target);
        if !matches!(value, Value::Shape(_) | Value::Error) {
            self.error(
                Diagnostic::error(
                    codes::E_RENDER_NOT_SHAPE,
                    format!("`render` needs a shape, found {}", value.ty()),
                    target.span,
                    "not a shape",
                )
                .with_help("render a shape, for example `render sphere(1);`"),
            );
        }
        let refs: Vec<&Setting> = body.iter().collect();
        let mut values = self.settings("render", RENDER_SETTINGS, &refs);
        if let Some((v @ Value::Vec(c), vspan)) = values.get("size") {
            if c.iter().any(|x| x.fract() != 0.0 || *x > 16384.0) {
                self.error(Diagnostic::error(
                    codes::E_OUT_OF_RANGE,
                    "`size` must be whole numbers of pixels, at most 16384",
                    *vspan,
                    format!("this is {}", v.display()),
                ));
                values.remove("size");
            }
        }
        if self.prog.render.is_none() {
            self.prog.render = Some(RenderDef {
                span,
                target: value,
                target_span: target.span,
                settings: RenderSettings::new(&Settings::new(RENDER_SETTINGS, &values)),
            });
        }
    }
}
