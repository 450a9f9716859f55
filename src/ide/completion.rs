//! A completion item: what the editor lists, and the item of a builtin function, for
//! completion by name ([`super::complete`]) and after `receiver.` ([`super::member`]).

use crate::sema::builtins::Builtin;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CompletionKind {
    Function,
    /// A `let` name.
    Variable,
    Atlas,
    Material,
    Seed,
    /// A builtin constant or surface input (`pi`, `position`).
    Constant,
    Keyword,
    /// A named argument, inserted as `name: `.
    Parameter,
    /// A setting of a block, inserted as `name = `.
    Setting,
    /// An atlas field (`.uv`).
    Field,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Completion {
    pub label: String,
    pub kind: CompletionKind,
    /// A signature or a type.
    pub detail: Option<String>,
    pub documentation: Option<String>,
    /// What to insert when it differs from the label.
    pub insert_text: Option<String>,
}

impl Completion {
    pub(super) fn new(label: impl Into<String>, kind: CompletionKind) -> Completion {
        Completion {
            label: label.into(),
            kind,
            detail: None,
            documentation: None,
            insert_text: None,
        }
    }

    pub(super) fn detail(mut self, d: impl Into<String>) -> Completion {
        self.detail = Some(d.into());
        self
    }

    pub(super) fn doc(mut self, d: impl Into<String>) -> Completion {
        self.documentation = Some(d.into());
        self
    }

    pub(super) fn insert(mut self, t: impl Into<String>) -> Completion {
        self.insert_text = Some(t.into());
        self
    }
}

pub(super) fn function(b: &Builtin) -> Completion {
    Completion::new(b.name, CompletionKind::Function)
        .detail(b.signature())
        .doc(format!("{} — {}", b.kind.title(), b.doc))
}
