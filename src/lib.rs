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
//! Every stage reports problems as [`Diagnostic`]s and keeps going, so one run shows
//! every independent problem. No input makes any stage panic.
//!
//! ## Compiling and rendering a scene
//!
//! The public surface is what a program embedding sdfc calls: [`check`] a scene's
//! text, [`compile`] it into a validated WGSL [`Module`] (the shader text, its
//! manifest of bindings and entry points), and [`render`] it headless with wgpu.
//!
//! ```
//! let scene = r#"
//!     let ball = sphere(1);
//!     atlas skin on ball { seed front = [0, 0, 1]; }
//!     material checkered { color = checker(skin.uv, 8); }
//!     render ball.paint(checkered) { size = [64, 48]; }
//! "#;
//! let analysis = sdfc::check(scene, None);
//! assert!(!analysis.has_errors(), "{:?}", analysis.diagnostics);
//! let compiled = sdfc::compile(&analysis, &sdfc::Options::default()).unwrap();
//! assert!(compiled.module.wgsl.contains("fn fs_main"));
//! // Headless, wherever wgpu finds an adapter (Mesa's lavapipe will do).
//! if let Ok(gpu) = sdfc::Gpu::new(sdfc::Backend::Auto) {
//!     let view = sdfc::View::of(&analysis, None).unwrap();
//!     let here = std::path::Path::new(".");
//!     let frame = sdfc::render(&gpu, &compiled.module, &view, sdfc::ViewMode::Color, here);
//!     assert_eq!(frame.unwrap().color.len(), 64 * 48 * 4);
//! }
//! // A scene with errors gives diagnostics with spans, codes and fixes instead.
//! let bad = "render sphere(radius: -1);";
//! let analysis = sdfc::check(bad, None);
//! assert!(analysis.diagnostics[0].is_error());
//! eprint!("{}", sdfc::diagnostic::render("bad.sdf", bad, &analysis.diagnostics, false));
//! ```
//!
//! The modules below the public surface are the compiler's rooms (ARCHITECTURE.md);
//! they are public for the `sdfc` binary and the test suite, hidden from these docs,
//! and not a stable interface.
#![warn(missing_docs)]

// The public surface.
pub use codegen::{Module, Options, WalkForm};
pub use diagnostic::{Diagnostic, Severity};
pub use driver::{check, check_all, compile, compile_shape, Analysis, CompileError, Compiled};
pub use gpu::embed::SceneRenderer;
pub use gpu::{globals, render, Backend, Frame, Gpu, GpuError, ViewMode};
pub use ir::texture::Textures;
pub use span::Span;
pub use view::View;

pub mod choice;
pub mod diagnostic;
pub mod span;

// The compiler's rooms, lowest layer first (ARCHITECTURE.md): public for the binary and
// the tests, not a stable interface.
#[doc(hidden)]
pub mod access;
#[doc(hidden)]
pub mod asset;
#[doc(hidden)]
pub mod bake;
#[doc(hidden)]
pub mod bench;
#[doc(hidden)]
pub mod codegen;
#[doc(hidden)]
pub mod codes;
#[doc(hidden)]
pub mod driver;
#[doc(hidden)]
pub mod fsutil;
#[doc(hidden)]
pub mod gpu;
mod id;
#[doc(hidden)]
pub mod ide;
#[doc(hidden)]
pub mod incremental;
#[doc(hidden)]
pub mod ir;
#[doc(hidden)]
#[cfg(feature = "lsp")]
pub mod lsp;
#[doc(hidden)]
pub mod reference;
#[doc(hidden)]
pub mod sema;
#[doc(hidden)]
pub mod syntax;
#[doc(hidden)]
pub mod uv;
#[doc(hidden)]
pub mod view;
#[doc(hidden)]
#[cfg(feature = "viewer")]
pub mod viewer;
#[doc(hidden)]
pub mod web;
