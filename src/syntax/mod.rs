//! Syntax: text → tokens ([`lexer`]) → AST ([`ast`]) through the recovering [`parser`].

pub mod ast;
pub mod lexer;
pub mod parser;

pub use parser::{parse, Parsed};
