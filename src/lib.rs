//! # sdfc: a compiler and runtime for signed-distance scenes with Implicit UVs
//!
//! A scene file (`*.sdf`) describes signed-distance shapes, seeds and merge
//! graphs for Implicit UVs, textures and materials. Data flows one way:
//!
//! ```text
//!  text ──lex──▶ tokens ──parse──▶ AST ──resolve+check──▶ checked program ──lower──▶ IR
//!  (syntax::lexer)    (syntax::parser)     (sema)                                     │
//!                                                                  ┌──────────────────┤
//!                                                                  ▼                  ▼
//!                                                   WGSL (naga-validated)      CPU reference (f64)
//!                                                                  │
//!                                                                  ▼
//!                                                             GPU (wgpu)
//! ```
//!
//! Every stage reports problems as [`diagnostic::Diagnostic`]s and keeps going,
//! so one run shows every independent problem. No input makes any stage panic.

pub mod access;
pub mod asset;
pub mod bake;
pub mod bench;
pub mod choice;
pub mod codegen;
pub mod codes;
pub mod diagnostic;
pub mod driver;
pub mod fsutil;
pub mod gpu;
mod id;
pub mod ide;
pub mod incremental;
pub mod ir;
#[cfg(feature = "lsp")]
pub mod lsp;
pub mod reference;
pub mod sema;
pub mod span;
pub mod syntax;
pub mod uv;
pub mod view;
#[cfg(feature = "viewer")]
pub mod viewer;

pub use diagnostic::{Diagnostic, Severity};
pub use span::Span;
