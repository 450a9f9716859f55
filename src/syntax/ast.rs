//! The abstract syntax tree. Every node carries the byte span it came from.

use crate::span::Span;

/// A name as written, with its span.
#[derive(Debug, Clone, PartialEq)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

/// A whole scene file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct File {
    pub items: Vec<Item>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Item {
    pub kind: ItemKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ItemKind {
    /// `let name = value;`
    Let { name: Ident, value: Expr },
    /// `param name = default in [min, max];`: a value the host sets at run time
    /// (`in …` may be left out for vectors, whose components then range over [0, 1]).
    Param {
        name: Ident,
        value: Expr,
        range: Option<Expr>,
    },
    /// `atlas name on shape { … }`
    Atlas {
        name: Ident,
        shape: Expr,
        body: Vec<AtlasStmt>,
    },
    /// `material name { field = value; … }`
    Material { name: Ident, body: Vec<Setting> },
    /// `render shape { field = value; … }` (the block may be left out: `render shape;`)
    Render { target: Expr, body: Vec<Setting> },
    /// An item that did not parse; its name, when it could be read, is still defined.
    Error { name: Option<Ident> },
}

impl Item {
    /// The name the item defines, if any.
    pub fn name(&self) -> Option<&Ident> {
        match &self.kind {
            ItemKind::Let { name, .. }
            | ItemKind::Param { name, .. }
            | ItemKind::Atlas { name, .. }
            | ItemKind::Material { name, .. } => Some(name),
            ItemKind::Error { name } => name.as_ref(),
            ItemKind::Render { .. } => None,
        }
    }
}

/// `name = value;` inside a block.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    pub name: Ident,
    pub value: Expr,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum AtlasStmt {
    Setting(Setting),
    /// `seed name = position [tangent direction];`
    Seed {
        name: Ident,
        position: Expr,
        tangent: Option<Expr>,
        span: Span,
    },
    /// `merge a b [c …];`: edges between consecutive seeds.
    Merge {
        seeds: Vec<Ident>,
        span: Span,
    },
    /// A statement that did not parse.
    Error(Span),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    Deg,
    Rad,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnaryOp {
    Neg,
    Not,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinaryOp {
    /// `|`: union of shapes, or of booleans.
    Or,
    /// `&`: intersection of shapes, or of booleans.
    And,
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
    Add,
    /// `-`: subtraction, or difference of shapes.
    Sub,
    Mul,
    Div,
    Rem,
}

impl BinaryOp {
    pub fn symbol(self) -> &'static str {
        match self {
            BinaryOp::Or => "|",
            BinaryOp::And => "&",
            BinaryOp::Eq => "==",
            BinaryOp::Ne => "!=",
            BinaryOp::Lt => "<",
            BinaryOp::Le => "<=",
            BinaryOp::Gt => ">",
            BinaryOp::Ge => ">=",
            BinaryOp::Add => "+",
            BinaryOp::Sub => "-",
            BinaryOp::Mul => "*",
            BinaryOp::Div => "/",
            BinaryOp::Rem => "%",
        }
    }
}

/// An argument of a call, positional or named (`name: value`).
#[derive(Debug, Clone, PartialEq)]
pub struct Arg {
    pub name: Option<Ident>,
    pub value: Expr,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    /// A number; `unit` is its `deg`/`rad` suffix. Degrees are converted by the checker.
    Number {
        value: f64,
        unit: Option<Unit>,
    },
    Bool(bool),
    /// A string with escapes decoded.
    Str(String),
    Name(String),
    /// `[a, b, …]`
    Vector(Vec<Expr>),
    Paren(Box<Expr>),
    Unary {
        op: UnaryOp,
        expr: Box<Expr>,
    },
    Binary {
        op: BinaryOp,
        lhs: Box<Expr>,
        rhs: Box<Expr>,
    },
    /// `f(args)`
    Call {
        callee: Ident,
        args: Vec<Arg>,
    },
    /// `receiver.f(args)`, sugar for `f(receiver, args)`.
    Method {
        receiver: Box<Expr>,
        method: Ident,
        args: Vec<Arg>,
    },
    /// `receiver.name`: a swizzle or an atlas field.
    Field {
        receiver: Box<Expr>,
        field: Ident,
    },
    /// An expression that did not parse.
    Error,
}

impl Expr {
    pub fn new(kind: ExprKind, span: Span) -> Self {
        Expr { kind, span }
    }
}
