//! Semantic analysis: name resolution, type checking and constant folding.
//!
//! The checker walks the AST once, in order, and produces a [`Program`]: every
//! definition with its type and folded value, every reference (for go-to-definition
//! and rename), and the atlases, materials and render settings in a form the IR
//! lowers directly. It keeps going after errors; an expression with an error has
//! the value [`Value::Error`], which is accepted everywhere so one mistake is
//! reported once.

pub mod builtins;
mod check;
mod displace;
mod expr;
pub mod fold;
pub mod interval;
pub mod math;
pub mod params;
pub mod settings;
mod show;
pub mod size;
pub mod types;

/// The closest name within a small edit distance, for "did you mean" help.
pub use check::suggest as closest;
pub use check::{check, MAX_SEEDS};
/// The span of the `displace` call inside a shape value, if any.
pub use displace::{displaced, undisplaced};
pub use settings::{AtlasParams, MaterialAttrs, RenderSettings};
pub use types::{
    AtlasAttr, AtlasId, Camera, FieldExpr, Light, MaterialId, Node, ParamRef, SurfaceInput, Ty,
    Uniform, Value,
};

use crate::span::Span;
use std::path::PathBuf;

crate::id::define_id!(
    /// Index of a definition in [`Program::defs`].
    DefId
);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DefKind {
    Let,
    /// A run-time parameter (`param`).
    Param,
    Atlas,
    Material,
    Seed {
        atlas: AtlasId,
    },
}

/// A named definition.
#[derive(Debug, Clone, PartialEq)]
pub struct Def {
    pub name: String,
    pub kind: DefKind,
    /// The span of the name where it is defined.
    pub span: Span,
    /// The span of the whole item or statement.
    pub item_span: Span,
    pub ty: Ty,
    /// The folded value (for seeds, the position as written).
    pub value: Value,
}

/// A use of a definition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reference {
    pub span: Span,
    pub def: DefId,
}

#[derive(Debug, Clone, PartialEq)]
pub struct SeedDef {
    pub name: String,
    pub def: DefId,
    pub span: Span,
    /// The position as written (projection onto the surface happens later).
    pub position: [f64; 3],
    pub position_span: Span,
    pub tangent: Option<[f64; 3]>,
    pub tangent_span: Option<Span>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct MergeDef {
    /// Seed indices within the atlas.
    pub a: usize,
    pub b: usize,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct AtlasDef {
    pub name: String,
    pub def: DefId,
    pub span: Span,
    pub shape: Value,
    pub shape_span: Span,
    pub params: AtlasParams,
    pub seeds: Vec<SeedDef>,
    pub merges: Vec<MergeDef>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct MaterialDef {
    pub name: String,
    pub def: DefId,
    pub span: Span,
    pub attrs: MaterialAttrs,
}

#[derive(Debug, Clone, PartialEq)]
pub struct RenderDef {
    pub span: Span,
    pub target: Value,
    pub target_span: Span,
    pub settings: RenderSettings,
}

/// A texture file referenced by `image(path)`.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureRef {
    pub path: String,
    /// The path resolved against the scene file's folder, when it is known.
    pub resolved: Option<PathBuf>,
    pub span: Span,
}

/// The checked program: the output of semantic analysis.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Program {
    pub defs: Vec<Def>,
    pub references: Vec<Reference>,
    pub atlases: Vec<AtlasDef>,
    pub materials: Vec<MaterialDef>,
    pub render: Option<RenderDef>,
    pub textures: Vec<TextureRef>,
    /// The run-time parameters: `time` first, then each `param` item in order.
    pub params: Vec<ParamDef>,
}

/// A run-time parameter: a `param` item, or the built-in `time`.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamDef {
    pub name: String,
    /// 1 for a float, else the vector size.
    pub size: usize,
    pub default: Vec<f64>,
    /// The value this check used (the default unless set, see `Access::set_param`).
    pub value: Vec<f64>,
    /// Every value the host may set lies in `[range.0, range.1]` (per component).
    pub range: (f64, f64),
    /// The name where it is defined (empty for `time`).
    pub span: Span,
    /// Whether the scene reads it.
    pub used: bool,
}

impl ParamDef {
    /// The built-in `time`: seconds, from 0.
    pub fn time() -> ParamDef {
        ParamDef {
            name: String::from("time"),
            size: 1,
            default: vec![0.0],
            value: vec![0.0],
            range: (0.0, f64::INFINITY),
            span: Span::new(0, 0),
            used: false,
        }
    }
}

impl Program {
    pub fn def(&self, id: DefId) -> &Def {
        &self.defs[id.index()]
    }

    pub fn atlas(&self, id: AtlasId) -> &AtlasDef {
        &self.atlases[id.index()]
    }

    pub fn material(&self, id: MaterialId) -> &MaterialDef {
        &self.materials[id.index()]
    }

    /// The top-level definition of a name (a `let`, atlas or material).
    pub fn lookup(&self, name: &str) -> Option<&Def> {
        self.defs
            .iter()
            .find(|d| d.name == name && !matches!(d.kind, DefKind::Seed { .. }))
    }

    /// Every shape bound by a `let`, in order.
    pub fn shapes(&self) -> impl Iterator<Item = &Def> {
        self.defs
            .iter()
            .filter(|d| d.kind == DefKind::Let && d.ty == Ty::Shape)
    }

    /// The definition at a source offset, from a definition or any of its references.
    pub fn def_at(&self, offset: usize) -> Option<DefId> {
        self.references
            .iter()
            .find(|r| r.span.contains(offset))
            .map(|r| r.def)
            .or_else(|| {
                let i = self.defs.iter().position(|d| d.span.contains(offset))?;
                Some(DefId::new(i))
            })
    }

    /// Every reference to a definition.
    pub fn references_to(&self, def: DefId) -> impl Iterator<Item = &Reference> {
        self.references.iter().filter(move |r| r.def == def)
    }
}
