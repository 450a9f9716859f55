//! The `.glb` reader of `sdfc render MESH.glb` on arbitrary bytes (see `targets::glb`).
//! Seeds: any .glb that `sdfc bake` writes (tests/glb_fuzz.rs mutates two baked ones).
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "targets.rs"]
mod targets;

fuzz_target!(|data: &[u8]| {
    let _ = targets::glb(data);
});
