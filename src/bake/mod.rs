//! Baking: a textured implicit scene becomes a textured mesh with a seamless atlas
//! (Purnomo, Cohen and Kumar, "Seamless Texture Atlases", Symposium on Geometry Processing
//! 2004; how sdfc applies it: docs/papers.md, "Seamless atlases on an implicit surface").
//!
//! The stages, one module each:
//!
//! ```text
//!  shape ──mesh──▶ chart grid (dual contouring, quads) ──charts──▶ chart table
//!        ──texels──▶ level-0 sample points (shared boundaries computed once)
//!        ──GPU material pass──▶ attributes (──fit──▶ least-squares inner texels)
//!        ──mips──▶ boundary-symmetric levels
//!        ──layout──▶ flat atlas image ──export──▶ .glb / .ktx2 / charts.json
//! ```

pub mod charts;
pub mod clip;
pub mod coverage;
pub mod export;
pub mod fit;
pub mod folded;
pub mod gpu;
pub mod images;
pub mod memory;
/// The mesher lives with the CPU geometry (dual contouring, surface samples).
pub use crate::reference::mesh;
pub mod mips;
pub mod patches;
pub mod pipeline;
pub mod table;

pub use crate::asset::{
    packed, ChartLayout, FlatLayout, MeshData, PackedChart, PackedLayout, Textures,
};
pub use patches::Patches;
