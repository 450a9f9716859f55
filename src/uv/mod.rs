//! Implicit UVs: the math of the paper and its CPU reference in f64.
//!
//! [`logmap`] is Alg. 1 (one seed), built of the pieces of [`geodesic`] that its Newton
//! corrections ([`refine`]) share; [`merge`] solves the merge graph (frames and
//! offsets, §4.4); [`atlas`] prepares seeds at compile time and runs Alg. 2 per point
//! (nearest seed, then the blend); [`grid`] is the seed acceleration structure. The generated WGSL runs the same
//! walk, unrolled to the atlas's N.

pub mod atlas;
pub mod diagnose;
pub mod fit;
pub mod geodesic;
pub mod grid;
pub mod logmap;
pub mod merge;
pub mod prune;
pub mod refine;
pub mod seeds;

pub use atlas::{Atlas, Sample, Search};
pub use logmap::{LogMap, Params, Seed, Status};
