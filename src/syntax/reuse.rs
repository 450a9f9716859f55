//! Reusing the items of the last parse of a document. The parser splits a file at its
//! item keywords and parses each item on its own, so an item whose text is unchanged
//! parses to the same tree, moved by where it now starts. [`ItemCache`] keeps the
//! items that parsed without a diagnostic, by their text, for the next parse: the
//! language server's parse of a 5,000-line scene after a one-line edit then parses one
//! item instead of hundreds.

use super::ast::*;
use crate::span::Span;
use std::collections::HashMap;

/// Items of the last parse, by their text (from their first token's start to their
/// last token's end), with spans relative to that start.
#[derive(Debug, Default)]
pub struct ItemCache {
    items: HashMap<String, Item>,
    /// The items of the parse under way: what the next parse can reuse.
    next: HashMap<String, Item>,
    /// How many items the parse under way reused, and the last parse.
    hits: usize,
    reused: usize,
}

impl ItemCache {
    /// The item whose text is `text`, starting at byte `at` of the new file.
    pub(super) fn take(&mut self, text: &str, at: usize) -> Option<Item> {
        let (key, relative) = self.items.remove_entry(text)?;
        let mut item = relative.clone();
        shift_item(&mut item, at as isize);
        self.next.insert(key, relative);
        self.hits += 1;
        Some(item)
    }

    /// Keeps `item`, parsed without a diagnostic from `text` at byte `at`.
    pub(super) fn keep(&mut self, text: &str, at: usize, item: &Item) {
        let mut relative = item.clone();
        shift_item(&mut relative, -(at as isize));
        self.next.insert(text.to_string(), relative);
    }

    /// Ends a parse: only its items are kept.
    pub(super) fn finish(&mut self) {
        self.items = std::mem::take(&mut self.next);
        self.reused = std::mem::take(&mut self.hits);
    }

    /// How many items the last parse reused.
    pub fn reused(&self) -> usize {
        self.reused
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }

    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

fn shift(s: &mut Span, by: isize) {
    s.start = s.start.wrapping_add_signed(by);
    s.end = s.end.wrapping_add_signed(by);
}

fn shift_ident(i: &mut Ident, by: isize) {
    shift(&mut i.span, by);
}

fn shift_setting(s: &mut Setting, by: isize) {
    shift(&mut s.span, by);
    shift_ident(&mut s.name, by);
    shift_expr(&mut s.value, by);
}

fn shift_item(item: &mut Item, by: isize) {
    shift(&mut item.span, by);
    match &mut item.kind {
        ItemKind::Let { name, value } => {
            shift_ident(name, by);
            shift_expr(value, by);
        }
        ItemKind::Param { name, value, range } => {
            shift_ident(name, by);
            shift_expr(value, by);
            if let Some(r) = range {
                shift_expr(r, by);
            }
        }
        ItemKind::Atlas { name, shape, body } => {
            shift_ident(name, by);
            shift_expr(shape, by);
            for stmt in body {
                match stmt {
                    AtlasStmt::Setting(s) => shift_setting(s, by),
                    AtlasStmt::Seed {
                        name,
                        position,
                        tangent,
                        span,
                    } => {
                        shift_ident(name, by);
                        shift_expr(position, by);
                        if let Some(t) = tangent {
                            shift_expr(t, by);
                        }
                        shift(span, by);
                    }
                    AtlasStmt::Merge { seeds, span } => {
                        seeds.iter_mut().for_each(|s| shift_ident(s, by));
                        shift(span, by);
                    }
                    AtlasStmt::Error(span) => shift(span, by),
                }
            }
        }
        ItemKind::Material { name, body } => {
            shift_ident(name, by);
            body.iter_mut().for_each(|s| shift_setting(s, by));
        }
        ItemKind::Render { target, body } => {
            shift_expr(target, by);
            body.iter_mut().for_each(|s| shift_setting(s, by));
        }
        ItemKind::Error { name } => {
            if let Some(n) = name {
                shift_ident(n, by);
            }
        }
    }
}

fn shift_args(args: &mut [Arg], by: isize) {
    for a in args {
        if let Some(n) = &mut a.name {
            shift_ident(n, by);
        }
        shift_expr(&mut a.value, by);
    }
}

/// Recursion as deep as the expression, which the parser bounds (`MAX_NESTING`).
fn shift_expr(e: &mut Expr, by: isize) {
    shift(&mut e.span, by);
    match &mut e.kind {
        ExprKind::Number { .. }
        | ExprKind::Bool(_)
        | ExprKind::Str(_)
        | ExprKind::Name(_)
        | ExprKind::Error => {}
        ExprKind::Vector(items) => items.iter_mut().for_each(|x| shift_expr(x, by)),
        ExprKind::Paren(x) | ExprKind::Unary { expr: x, .. } => shift_expr(x, by),
        ExprKind::Binary { lhs, rhs, .. } => {
            shift_expr(lhs, by);
            shift_expr(rhs, by);
        }
        ExprKind::Call { callee, args } => {
            shift_ident(callee, by);
            shift_args(args, by);
        }
        ExprKind::Method {
            receiver,
            method,
            args,
        } => {
            shift_expr(receiver, by);
            shift_ident(method, by);
            shift_args(args, by);
        }
        ExprKind::Field { receiver, field } => {
            shift_expr(receiver, by);
            shift_ident(field, by);
        }
    }
}
