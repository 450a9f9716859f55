//! Rename: `let` names, atlases, materials and seeds, through the definitions
//! and references the checker records.

use super::Document;
use crate::sema::builtins::{self, CONSTANTS};
use crate::sema::{DefId, DefKind};
use crate::span::Span;
use crate::syntax::lexer::{lex, Token, KEYWORDS};

/// Why a rename is refused; the message is shown to the user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RenameError(pub String);

impl std::fmt::Display for RenameError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// What is under the cursor when it is not a renamable name.
fn refuse(doc: &Document, offset: usize) -> RenameError {
    let lexed = lex(&doc.text, &mut Vec::new());
    let tok = lexed
        .tokens
        .iter()
        .find(|(_, s)| s.start <= offset && offset <= s.end && !s.is_empty())
        .map(|(t, _)| *t);
    RenameError(match tok {
        Some(Token::Ident(n)) if builtins::lookup(n).is_some() => {
            format!("`{n}` is a builtin function and cannot be renamed")
        }
        Some(Token::Ident(n)) if CONSTANTS.iter().any(|c| c.name == n) => {
            format!("`{n}` is a builtin and cannot be renamed")
        }
        Some(Token::Ident(n)) => format!("`{n}` is not a name defined in this scene"),
        Some(
            t @ (Token::Let
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
            | Token::False),
        ) => format!("{t} is a keyword and cannot be renamed"),
        _ => String::from("there is no name to rename here"),
    })
}

fn target(doc: &Document, offset: usize) -> Result<DefId, RenameError> {
    doc.analysis
        .program
        .def_at(offset)
        .ok_or_else(|| refuse(doc, offset))
}

/// The name under the cursor and its span, when it can be renamed.
pub fn prepare_rename(doc: &Document, offset: usize) -> Result<(Span, String), RenameError> {
    let program = &doc.analysis.program;
    let id = target(doc, offset)?;
    let span = program
        .references
        .iter()
        .find(|r| r.def == id && r.span.contains(offset))
        .map(|r| r.span)
        .unwrap_or(program.def(id).span);
    Ok((span, program.def(id).name.clone()))
}

/// Checks that `name` is a valid identifier that no keyword or builtin uses.
pub fn check_new_name(name: &str) -> Result<(), RenameError> {
    let mut chars = name.chars();
    let valid = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !valid {
        return Err(RenameError(format!("`{name}` is not a valid name")));
    }
    if KEYWORDS.contains(&name) {
        return Err(RenameError(format!("`{name}` is a keyword")));
    }
    if builtins::lookup(name).is_some() || CONSTANTS.iter().any(|c| c.name == name) {
        return Err(RenameError(format!("`{name}` is the name of a builtin")));
    }
    Ok(())
}

/// Every span to replace with `new_name` to rename the name at `offset`:
/// its definition and every reference.
pub fn rename(doc: &Document, offset: usize, new_name: &str) -> Result<Vec<Span>, RenameError> {
    let program = &doc.analysis.program;
    let id = target(doc, offset)?;
    check_new_name(new_name)?;
    let def = program.def(id);
    if def.name == new_name {
        return Ok(Vec::new());
    }
    // Seeds share a namespace with the seeds of their atlas; every other
    // definition with the items of the file.
    let clash = program.defs.iter().find(|d| {
        d.name == new_name
            && match (def.kind, d.kind) {
                (DefKind::Seed { atlas: a }, DefKind::Seed { atlas: b }) => a == b,
                (DefKind::Seed { .. }, _) | (_, DefKind::Seed { .. }) => false,
                _ => true,
            }
    });
    let item_clash = !matches!(def.kind, DefKind::Seed { .. })
        && doc
            .analysis
            .parsed
            .file
            .items
            .iter()
            .any(|i| i.name().is_some_and(|n| n.name == new_name));
    if clash.is_some() || item_clash {
        return Err(RenameError(format!(
            "`{new_name}` is already defined in this scene"
        )));
    }
    let mut spans: Vec<Span> = std::iter::once(def.span)
        .chain(program.references_to(id).map(|r| r.span))
        .collect();
    spans.sort();
    spans.dedup();
    Ok(spans)
}
