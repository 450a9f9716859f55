//! Check, codegen and naga (see `targets::check_all`); textures resolve in tests/ui.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "targets.rs"]
mod targets;

fuzz_target!(|data: &[u8]| targets::check_all(
    data,
    std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/ui"))
));
