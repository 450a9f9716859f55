//! The lexer and parser: never a panic, every span inside the text.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let text = common::text(data);
    let mut diags = Vec::new();
    let _ = sdfc::syntax::lexer::lex(&text, &mut diags);
    let mut diags = Vec::new();
    let _parsed = sdfc::syntax::parse(&text, &mut diags);
    common::assert_spans(&text, &diags);
});
