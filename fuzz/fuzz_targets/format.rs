//! The formatter: formatting twice changes nothing, and formatting never changes the
//! token stream (comments aside, which it keeps but the lexer sets apart).
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fn tokens(text: &str) -> Vec<String> {
    let mut diags = Vec::new();
    sdfc::syntax::lexer::lex(text, &mut diags)
        .tokens
        .iter()
        .map(|(t, _)| format!("{t:?}"))
        .collect()
}

fuzz_target!(|data: &[u8]| {
    let text = common::text(data);
    let Ok(once) = sdfc::ide::format::format(&text) else {
        return;
    };
    let twice = sdfc::ide::format::format(&once)
        .unwrap_or_else(|d| panic!("the formatted text has errors: {d:?}\n{once}"));
    assert_eq!(once, twice, "formatting twice changed the text");
    assert_eq!(
        tokens(&text),
        tokens(&once),
        "formatting changed the tokens:\n{text}\n---\n{once}"
    );
});
