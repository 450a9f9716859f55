//! The whole check (front end, atlas geometry, lowering): never a panic, every span
//! inside the text.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let text = common::text(data);
    let analysis = sdfc::driver::check(&text, Some(&common::base_dir()));
    common::assert_spans(&text, &analysis.diagnostics);
});
