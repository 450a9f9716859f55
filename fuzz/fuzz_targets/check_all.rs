//! The check, code generation and naga validation: never a panic, never an internal
//! compiler error (E0900: naga rejected generated code), every span inside the text.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let text = common::text(data);
    let analysis = sdfc::driver::check_all(&text, Some(&common::base_dir()));
    common::assert_spans(&text, &analysis.diagnostics);
    if let Some(d) = analysis
        .diagnostics
        .iter()
        .find(|d| d.code == sdfc::codes::E_INTERNAL)
    {
        panic!("internal compiler error: {} / {}", d.message, d.notes.join(" / "));
    }
});
