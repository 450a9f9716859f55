//! Syntax: text → tokens ([`lexer`]) → AST ([`ast`]) through the recovering [`parser`].

pub mod ast;
pub mod lexer;
pub mod parser;
pub mod source;

pub use parser::{parse, Parsed};
pub use source::{decode, MAX_SOURCE_BYTES};
