//! Implicit UVs: the math of the paper and its CPU reference in f64.
//!
//! [`logmap`] is Alg. 1 (one seed); [`atlas`] prepares seeds at compile time and
//! finds each point's geodesic-nearest seed. The generated WGSL runs the same
//! walk, unrolled to the atlas's N.

pub mod atlas;
pub mod logmap;

pub use atlas::{Atlas, Sample};
pub use logmap::{LogMap, Params, Seed, Status};
