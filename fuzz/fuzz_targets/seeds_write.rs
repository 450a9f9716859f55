//! `sdfc seeds --write` (see `targets::seeds_write`); textures resolve in examples/,
//! which has every texture the examples and the UI scenes that check name.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "targets.rs"]
mod targets;

fuzz_target!(|data: &[u8]| {
    targets::seeds_write(
        data,
        std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples")),
    );
});
