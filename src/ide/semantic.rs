//! Semantic tokens: every keyword, literal, comment and name of a document,
//! classified by what it is (a builtin function, a shape, an atlas, a seed, a
//! named argument, a setting …), in source order.

use super::walk::{self, Visitor};
use super::Document;
use crate::sema::builtins::{self, CONSTANTS};
use crate::sema::DefKind;
use crate::span::Span;
use crate::syntax::ast::{Arg, AtlasStmt, Expr, ExprKind, Setting};
use crate::syntax::lexer::{lex, Token};
use std::collections::HashMap;

/// What a token is. The language server maps these to its legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TokenKind {
    Keyword,
    Number,
    String,
    Comment,
    Operator,
    /// A builtin function or method.
    Function,
    /// A `let` name.
    Variable,
    /// An atlas.
    Atlas,
    /// A seed of an atlas.
    Seed,
    /// A material.
    Material,
    /// A named argument.
    Parameter,
    /// A block setting, an atlas field or a swizzle.
    Property,
}

impl TokenKind {
    /// Every kind, in the order of the language server's legend.
    pub const ALL: &'static [TokenKind] = &[
        TokenKind::Keyword,
        TokenKind::Number,
        TokenKind::String,
        TokenKind::Comment,
        TokenKind::Operator,
        TokenKind::Function,
        TokenKind::Variable,
        TokenKind::Atlas,
        TokenKind::Seed,
        TokenKind::Material,
        TokenKind::Parameter,
        TokenKind::Property,
    ];
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SemanticToken {
    pub span: Span,
    pub kind: TokenKind,
    /// The name is defined here.
    pub declaration: bool,
    /// A builtin function or constant.
    pub builtin: bool,
}

/// Identifier kinds known from the syntax tree, by span start.
#[derive(Default)]
struct Names {
    kinds: HashMap<usize, (TokenKind, bool)>,
}

impl Names {
    fn set(&mut self, span: Span, kind: TokenKind, builtin: bool) {
        self.kinds.insert(span.start, (kind, builtin));
    }
}

impl<'a> Visitor<'a> for Names {
    fn arg(&mut self, a: &'a Arg) {
        if let Some(n) = &a.name {
            self.set(n.span, TokenKind::Parameter, false);
        }
        walk::walk_arg(self, a);
    }

    fn expr(&mut self, e: &'a Expr) {
        match &e.kind {
            ExprKind::Name(n) if CONSTANTS.iter().any(|c| c.name == n) => {
                self.set(e.span, TokenKind::Variable, true);
            }
            ExprKind::Call { callee: f, .. } | ExprKind::Method { method: f, .. } => {
                let builtin = builtins::lookup(&f.name).is_some();
                self.set(f.span, TokenKind::Function, builtin);
            }
            ExprKind::Field { field, .. } => self.set(field.span, TokenKind::Property, false),
            _ => {}
        }
        walk::walk_expr(self, e);
    }

    fn setting(&mut self, s: &'a Setting) {
        self.set(s.name.span, TokenKind::Property, false);
        walk::walk_setting(self, s);
    }

    fn atlas_stmt(&mut self, stmt: &'a AtlasStmt) {
        match stmt {
            AtlasStmt::Seed { name, .. } => self.set(name.span, TokenKind::Seed, false),
            AtlasStmt::Merge { seeds, .. } => seeds
                .iter()
                .for_each(|s| self.set(s.span, TokenKind::Seed, false)),
            _ => {}
        }
        walk::walk_atlas_stmt(self, stmt);
    }
}

fn def_kind(kind: DefKind) -> TokenKind {
    match kind {
        DefKind::Let | DefKind::Param => TokenKind::Variable,
        DefKind::Atlas => TokenKind::Atlas,
        DefKind::Material => TokenKind::Material,
        DefKind::Seed { .. } => TokenKind::Seed,
    }
}

/// Every token of the document worth colouring, in source order.
pub fn semantic_tokens(doc: &Document) -> Vec<SemanticToken> {
    let program = &doc.analysis.program;
    let mut names = Names::default();
    walk::walk_file(&mut names, &doc.analysis.parsed.file);
    // Resolved names win over what the syntax says.
    let mut resolved: HashMap<usize, (TokenKind, bool)> = HashMap::new();
    for d in &program.defs {
        resolved.insert(d.span.start, (def_kind(d.kind), true));
    }
    for r in &program.references {
        resolved.insert(r.span.start, (def_kind(program.def(r.def).kind), false));
    }
    let lexed = lex(&doc.text, &mut Vec::new());
    let mut out: Vec<SemanticToken> = lexed
        .comments
        .iter()
        .map(|c| SemanticToken {
            span: c.span,
            kind: TokenKind::Comment,
            declaration: false,
            builtin: false,
        })
        .collect();
    for (tok, span) in &lexed.tokens {
        let token = |kind, declaration, builtin| SemanticToken {
            span: *span,
            kind,
            declaration,
            builtin,
        };
        let t = match tok {
            Token::Let
            | Token::Param
            | Token::In
            | Token::Atlas
            | Token::Material
            | Token::Render
            | Token::On
            | Token::Seed
            | Token::Tangent
            | Token::Merge
            | Token::True
            | Token::False => token(TokenKind::Keyword, false, false),
            Token::Number(_) | Token::BadNumber(_) => token(TokenKind::Number, false, false),
            Token::Str(_) | Token::UnterminatedStr(_) => token(TokenKind::String, false, false),
            Token::Ident(_) => {
                if let Some(&(kind, declaration)) = resolved.get(&span.start) {
                    token(kind, declaration, false)
                } else if let Some(&(kind, builtin)) = names.kinds.get(&span.start) {
                    token(kind, false, builtin)
                } else {
                    token(TokenKind::Variable, false, false)
                }
            }
            t if t.is_binary_operator() || *t == Token::Bang => {
                token(TokenKind::Operator, false, false)
            }
            _ => continue,
        };
        out.push(t);
    }
    out.sort_by_key(|t| t.span.start);
    out
}
