//! The one walk over the syntax tree that the editor queries share (hover's name
//! lookup, semantic tokens, the outline, merge hover).
//!
//! A [`Visitor`] overrides the nodes it cares about; each method's default walks
//! the node's children through the `walk_*` function of the same name, which an
//! override calls to keep descending (or leaves out to prune). Children are visited
//! in source order.

use crate::syntax::ast::{Arg, AtlasStmt, Expr, ExprKind, File, Item, ItemKind, Setting};

/// Callbacks for each kind of node; `'a` lets a visitor keep references into the tree.
pub trait Visitor<'a> {
    fn item(&mut self, item: &'a Item) {
        walk_item(self, item);
    }

    fn atlas_stmt(&mut self, stmt: &'a AtlasStmt) {
        walk_atlas_stmt(self, stmt);
    }

    fn setting(&mut self, setting: &'a Setting) {
        walk_setting(self, setting);
    }

    fn expr(&mut self, expr: &'a Expr) {
        walk_expr(self, expr);
    }

    fn arg(&mut self, arg: &'a Arg) {
        walk_arg(self, arg);
    }
}

/// Visits every item of a file.
pub fn walk_file<'a, V: Visitor<'a> + ?Sized>(v: &mut V, file: &'a File) {
    for item in &file.items {
        v.item(item);
    }
}

/// Visits an item's expressions, atlas statements and settings.
pub fn walk_item<'a, V: Visitor<'a> + ?Sized>(v: &mut V, item: &'a Item) {
    match &item.kind {
        ItemKind::Let { value, .. } => v.expr(value),
        ItemKind::Param { value, range, .. } => {
            v.expr(value);
            if let Some(r) = range {
                v.expr(r);
            }
        }
        ItemKind::Atlas { shape, body, .. } => {
            v.expr(shape);
            for s in body {
                v.atlas_stmt(s);
            }
        }
        ItemKind::Material { body, .. } => {
            for s in body {
                v.setting(s);
            }
        }
        ItemKind::Render { target, body } => {
            v.expr(target);
            for s in body {
                v.setting(s);
            }
        }
        ItemKind::Error { .. } => {}
    }
}

/// Visits a statement's setting or expressions (a seed's position and tangent).
pub fn walk_atlas_stmt<'a, V: Visitor<'a> + ?Sized>(v: &mut V, stmt: &'a AtlasStmt) {
    match stmt {
        AtlasStmt::Setting(s) => v.setting(s),
        AtlasStmt::Seed {
            position, tangent, ..
        } => {
            v.expr(position);
            if let Some(t) = tangent {
                v.expr(t);
            }
        }
        AtlasStmt::Merge { .. } | AtlasStmt::Error(_) => {}
    }
}

pub fn walk_setting<'a, V: Visitor<'a> + ?Sized>(v: &mut V, setting: &'a Setting) {
    v.expr(&setting.value);
}

pub fn walk_arg<'a, V: Visitor<'a> + ?Sized>(v: &mut V, arg: &'a Arg) {
    v.expr(&arg.value);
}

/// Visits an expression's sub-expressions and arguments (a method's receiver first).
/// Deeply nested expressions grow the stack instead of overflowing it, as the checker does.
pub fn walk_expr<'a, V: Visitor<'a> + ?Sized>(v: &mut V, expr: &'a Expr) {
    stacker::maybe_grow(64 * 1024, 1024 * 1024, || match &expr.kind {
        ExprKind::Vector(items) => items.iter().for_each(|i| v.expr(i)),
        ExprKind::Paren(inner) | ExprKind::Unary { expr: inner, .. } => v.expr(inner),
        ExprKind::Binary { lhs, rhs, .. } => {
            v.expr(lhs);
            v.expr(rhs);
        }
        ExprKind::Call { args, .. } => args.iter().for_each(|a| v.arg(a)),
        ExprKind::Method { receiver, args, .. } => {
            v.expr(receiver);
            args.iter().for_each(|a| v.arg(a));
        }
        ExprKind::Field { receiver, .. } => v.expr(receiver),
        ExprKind::Number { .. }
        | ExprKind::Bool(_)
        | ExprKind::Str(_)
        | ExprKind::Name(_)
        | ExprKind::Error => {}
    });
}
