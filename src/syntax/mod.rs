//! Syntax: text → tokens ([`lexer`]) → AST ([`ast`]) through the recovering [`parser`].

pub mod ast;
pub mod lexer;
pub mod parser;
pub mod reuse;
pub mod source;

pub use parser::{parse, parse_reusing, Parsed};
pub use reuse::ItemCache;
pub use source::{decode, MAX_SOURCE_BYTES};
