//! Protocol-free editor queries over one analysed document: hover, go to
//! definition, references and document symbols; in submodules, code actions, inlay
//! hints and merge hover, formatting,
//! semantic tokens, rename, completion and signature help. The language server
//! (`src/lsp`) only converts these to and from the protocol.

pub mod actions;
pub mod complete;
mod completion;
pub mod format;
pub mod make_param;
mod member;
pub mod rename;
pub mod seed_edit;
pub mod seeds;
pub mod semantic;
pub mod walk;

use crate::driver::Analysis;
use crate::sema::builtins::{self, CONSTANTS};
use crate::sema::{AtlasAttr, DefKind, Value};
use crate::span::Span;
use crate::syntax::ast::{AtlasStmt, Expr, ExprKind, Ident, Item, ItemKind, Setting};
use std::path::Path;
use walk::Visitor;

/// One analysed document.
#[derive(Clone)]
pub struct Document {
    pub text: String,
    pub analysis: Analysis,
}

impl Document {
    pub fn new(text: impl Into<String>, base_dir: Option<&Path>) -> Document {
        Document::with_access(text, &crate::access::Access::new(base_dir))
    }

    /// A document whose files may be read from the folders of `access`.
    pub fn with_access(text: impl Into<String>, access: &crate::access::Access) -> Document {
        let text = text.into();
        let analysis = crate::driver::check_all_with(&text, access);
        Document { text, analysis }
    }

    /// A document with the front end's analysis only (parse, names, types): what the
    /// language server publishes at once, before the geometry and code generation.
    pub fn front(text: impl Into<String>, access: &crate::access::Access) -> Document {
        Document::front_reusing(text, access, None)
    }

    /// [`Document::front`], reusing the unchanged items of the document's last parse.
    pub fn front_reusing(
        text: impl Into<String>,
        access: &crate::access::Access,
        cache: Option<&mut crate::syntax::ItemCache>,
    ) -> Document {
        let text = text.into();
        let analysis = crate::driver::analyze_reusing(&text, access, cache);
        Document { text, analysis }
    }

    /// [`Document::with_access`], reusing the unchanged items of the document's last
    /// parse.
    pub fn full_reusing(
        text: impl Into<String>,
        access: &crate::access::Access,
        cache: Option<&mut crate::syntax::ItemCache>,
    ) -> Document {
        let text = text.into();
        let analysis = crate::driver::check_all_reusing(&text, access, cache);
        Document { text, analysis }
    }
}

/// Markdown for the editor, and the span it describes.
#[derive(Debug, Clone, PartialEq)]
pub struct Hover {
    pub span: Span,
    pub markdown: String,
}

/// What names the identifier at a position refer to, besides definitions.
enum Named<'a> {
    /// A call or method call of a builtin function.
    Function(&'a Ident),
    /// `.name` after an expression.
    Field(&'a Ident),
    /// A bare name (a constant such as `pi`, or a definition).
    Name(&'a str, Span),
}

/// Finds the innermost name at an offset in the items around it.
struct NameFinder<'a> {
    offset: usize,
    found: Option<Named<'a>>,
}

impl<'a> Visitor<'a> for NameFinder<'a> {
    fn item(&mut self, item: &'a Item) {
        if item.span.contains(self.offset) {
            walk::walk_item(self, item);
        }
    }

    fn expr(&mut self, e: &'a Expr) {
        if !e.span.contains(self.offset) {
            return;
        }
        let at = |i: &Ident| i.span.contains(self.offset);
        match &e.kind {
            ExprKind::Name(n) => self.found = Some(Named::Name(n, e.span)),
            ExprKind::Call { callee, .. } if at(callee) => {
                self.found = Some(Named::Function(callee))
            }
            ExprKind::Method { method, .. } if at(method) => {
                self.found = Some(Named::Function(method))
            }
            ExprKind::Field { field, .. } if at(field) => self.found = Some(Named::Field(field)),
            _ => {}
        }
        // Inner expressions are visited after, and win.
        walk::walk_expr(self, e);
    }
}

fn named_at(doc: &Document, offset: usize) -> Option<Named<'_>> {
    let mut finder = NameFinder {
        offset,
        found: None,
    };
    walk::walk_file(&mut finder, &doc.analysis.parsed.file);
    finder.found
}

/// Hover at a byte offset.
pub fn hover(doc: &Document, offset: usize) -> Option<Hover> {
    let program = &doc.analysis.program;
    if let Some(id) = program.def_at(offset) {
        let def = program.def(id);
        let span = program
            .references
            .iter()
            .find(|r| r.span.contains(offset))
            .map(|r| r.span)
            .unwrap_or(def.span);
        let markdown = match def.kind {
            DefKind::Let => match &def.value {
                Value::Float(_) | Value::Vec(_) | Value::Bool(_) | Value::Str(_) => format!(
                    "```sdf\nlet {}: {} = {}\n```",
                    def.name,
                    def.ty,
                    def.value.display()
                ),
                _ => format!("```sdf\nlet {}: {}\n```", def.name, def.ty),
            },
            DefKind::Param => {
                let p = program.params.iter().find(|p| p.span == def.span)?;
                let show = |v: &[f64]| {
                    if v.len() == 1 {
                        Value::Float(v[0]).display()
                    } else {
                        Value::Vec(v.to_vec()).display()
                    }
                };
                format!(
                    "```sdf\nparam {}: {} = {} in {}\n```\nA run-time parameter: the host sets it \
                     (a slider, `sdfc render --param {}=…`) without recompiling. Default {}, \
                     range [{}, {}]{}.",
                    p.name,
                    def.ty,
                    show(&p.default),
                    show(&[p.range.0, p.range.1]),
                    p.name,
                    show(&p.default),
                    Value::Float(p.range.0).display(),
                    Value::Float(p.range.1).display(),
                    if p.size > 1 { " per component" } else { "" }
                )
            }
            DefKind::Atlas => {
                let a = program.atlases.iter().find(|a| a.def == id)?;
                let p = &a.params;
                format!("```sdf\natlas {}\n```\n{} seeds, {} merges; N = {}, D = {}, ε1 = {}, ε2 = {}, r_min = {}", a.name, a.seeds.len(), a.merges.len(), p.steps, p.max_distance, p.heuristic_tolerance, p.sharp_tolerance, p.min_reach)
            }
            DefKind::Material => format!("```sdf\nmaterial {}\n```", def.name),
            DefKind::Seed { atlas } => {
                let a = program.atlas(atlas);
                let s = a.seeds.iter().find(|s| s.def == id)?;
                let tangent = s
                    .tangent
                    .map(|t| format!("tangent {}", Value::Vec(t.to_vec()).display()))
                    .unwrap_or_else(|| String::from("default tangent"));
                let mut text = format!(
                    "```sdf\nseed {} = {} {tangent}\n```\nin atlas `{}`",
                    s.name,
                    Value::Vec(s.position.to_vec()).display(),
                    a.name
                );
                // What the compile-time geometry made of it (when the file is valid).
                let prepared = doc
                    .analysis
                    .atlases
                    .get(atlas.index())
                    .and_then(|p| p.as_ref());
                if let Some(pa) = prepared {
                    let k = a.seeds.iter().position(|x| x.def == id)?;
                    let ps = &pa.seeds[k];
                    let pt = crate::uv::diagnose::fmt_point;
                    text += &format!(
                        "\n\nprojected to {} (moved {:.4}); frame e1 = {}, e2 = {}; uv offset ({:.4}, {:.4})",
                        pt(ps.seed.p),
                        ps.moved,
                        pt(ps.seed.e1),
                        pt(ps.seed.e2),
                        ps.offset.x,
                        ps.offset.y
                    );
                    for &(j, d) in &pa.graph.neighbors[k] {
                        text += &format!(
                            "\n\nmerged with `{}`: geodesic length {d:.4}",
                            pa.seed_names[j]
                        );
                    }
                }
                text
            }
        };
        return Some(Hover { span, markdown });
    }
    if let Some(h) = setting_hover(doc, offset) {
        return Some(h);
    }
    let Some(named) = named_at(doc, offset) else {
        return actions::merge_hover(doc, offset);
    };
    match named {
        Named::Function(ident) => {
            let b = builtins::lookup(&ident.name)?;
            Some(Hover {
                span: ident.span,
                markdown: format!(
                    "```sdf\n{}\n```\n{} — {}",
                    b.signature(),
                    b.kind.title(),
                    b.doc
                ),
            })
        }
        Named::Field(ident) => {
            let (_, name, ty, doc_text) = AtlasAttr::ALL.iter().find(|a| a.1 == ident.name)?;
            Some(Hover {
                span: ident.span,
                markdown: format!("```sdf\nATLAS.{name}: field<{ty}>\n```\n{doc_text}"),
            })
        }
        Named::Name(n, span) => {
            let c = CONSTANTS.iter().find(|c| c.name == n)?;
            Some(Hover {
                span,
                markdown: format!("```sdf\n{}\n```\n{}", c.name, c.doc),
            })
        }
    }
}

/// Hover on the name of a block's setting (`roughness = …`): its type, default and
/// documentation from the settings tables.
fn setting_hover(doc: &Document, offset: usize) -> Option<Hover> {
    for item in &doc.analysis.parsed.file.items {
        let (settings, specs): (Vec<&Setting>, _) = match &item.kind {
            ItemKind::Atlas { body, .. } => (
                body.iter()
                    .filter_map(|s| match s {
                        AtlasStmt::Setting(s) => Some(s),
                        _ => None,
                    })
                    .collect(),
                builtins::ATLAS_SETTINGS,
            ),
            ItemKind::Material { body, .. } => (body.iter().collect(), builtins::MATERIAL_SETTINGS),
            ItemKind::Render { body, .. } => (body.iter().collect(), builtins::RENDER_SETTINGS),
            _ => continue,
        };
        let Some(s) = settings.into_iter().find(|s| s.name.span.contains(offset)) else {
            continue;
        };
        let spec = specs.iter().find(|spec| spec.name == s.name.name)?;
        let field = if spec.field {
            " (may be a surface field)"
        } else {
            ""
        };
        return Some(Hover {
            span: s.name.span,
            markdown: format!(
                "```sdf
{}
```
setting{field} — {}",
                spec.describe(),
                spec.doc
            ),
        });
    }
    None
}

/// The definition of the name at an offset.
pub fn definition(doc: &Document, offset: usize) -> Option<Span> {
    let program = &doc.analysis.program;
    program.def_at(offset).map(|id| program.def(id).span)
}

/// Every use of the name at an offset, with its definition first when asked.
pub fn references(doc: &Document, offset: usize, include_definition: bool) -> Vec<Span> {
    let program = &doc.analysis.program;
    let Some(id) = program.def_at(offset) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    if include_definition {
        out.push(program.def(id).span);
    }
    out.extend(program.references_to(id).map(|r| r.span));
    out
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SymbolKind {
    Let,
    Atlas,
    Material,
    Render,
    Seed,
    Merge,
}

/// An outline entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Symbol {
    pub name: String,
    pub kind: SymbolKind,
    /// The whole item or statement.
    pub span: Span,
    /// The name, where there is one.
    pub selection: Span,
    pub children: Vec<Symbol>,
}

/// Builds the outline: a symbol per item, and per seed and merge under its atlas.
struct Outline {
    out: Vec<Symbol>,
}

impl Symbol {
    fn leaf(name: &Ident, kind: SymbolKind, span: Span) -> Symbol {
        Symbol {
            name: name.name.clone(),
            kind,
            span,
            selection: name.span,
            children: Vec::new(),
        }
    }
}

impl<'a> Visitor<'a> for Outline {
    fn item(&mut self, item: &'a Item) {
        let symbol = match &item.kind {
            ItemKind::Let { name, .. } | ItemKind::Param { name, .. } => {
                Symbol::leaf(name, SymbolKind::Let, item.span)
            }
            ItemKind::Material { name, .. } => Symbol::leaf(name, SymbolKind::Material, item.span),
            ItemKind::Atlas { name, .. } => Symbol::leaf(name, SymbolKind::Atlas, item.span),
            ItemKind::Render { target, .. } => Symbol {
                name: String::from("render"),
                kind: SymbolKind::Render,
                span: item.span,
                selection: target.span,
                children: Vec::new(),
            },
            ItemKind::Error { .. } => return,
        };
        self.out.push(symbol);
        walk::walk_item(self, item);
    }

    fn atlas_stmt(&mut self, stmt: &'a AtlasStmt) {
        let child = match stmt {
            AtlasStmt::Seed { name, span, .. } => Symbol::leaf(name, SymbolKind::Seed, *span),
            AtlasStmt::Merge { seeds, span } if !seeds.is_empty() => Symbol {
                name: seeds
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>()
                    .join(" – "),
                kind: SymbolKind::Merge,
                span: *span,
                selection: seeds[0].span.to(seeds[seeds.len() - 1].span),
                children: Vec::new(),
            },
            _ => return,
        };
        if let Some(atlas) = self.out.last_mut() {
            atlas.children.push(child);
        }
    }

    /// The outline stops at statements.
    fn expr(&mut self, _: &'a Expr) {}

    fn setting(&mut self, _: &'a Setting) {}
}

/// The document's outline: items, with seeds and merges under their atlas.
pub fn symbols(doc: &Document) -> Vec<Symbol> {
    let mut outline = Outline { out: Vec::new() };
    walk::walk_file(&mut outline, &doc.analysis.parsed.file);
    outline.out
}
