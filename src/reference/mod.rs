//! The CPU reference layer above the UV math: the f64 interpreter of material fields
//! ([`material`]), the mesher of zero sets ([`mesh`]), samples of a zero set drawn
//! uniformly by area ([`surface`]), and the
//! environment that evaluates displacement heights and
//! shell-map uv from a scene's prepared atlases and decoded textures ([`Env`]), which
//! the IR's evaluator takes as an argument ([`crate::ir::Heights`]).

pub mod coarse;
pub mod material;
pub mod mesh;
pub mod surface;

use crate::ir::texture::Textures;
use crate::ir::{Height, Heights};
use crate::sema::AtlasId;
use crate::uv::Atlas;
use glam::{DVec2, DVec3};
use material::AtlasValues;
use std::sync::Arc;

/// The atlases and textures a scene's heights read: the CPU half of displacements
/// and shell maps (§5.2.2, §5.4 of the Implicit UVs paper).
#[derive(Debug, Clone, Default)]
pub struct Env {
    /// One per atlas of the program, in order (None where it is not prepared, or not
    /// yet: an atlas's own shape sees only the atlases declared before it).
    atlases: Vec<Option<Arc<Atlas>>>,
    textures: Textures,
}

impl Env {
    /// The environment of `atlases` (prepared, one per atlas of the program) and the
    /// program's decoded `textures`.
    pub fn new(atlases: &[Option<Atlas>], textures: &Textures) -> Env {
        Env {
            atlases: atlases.iter().map(|a| a.clone().map(Arc::new)).collect(),
            textures: textures.clone(),
        }
    }

    /// [`Env::new`] behind an `Arc`, as an atlas keeps the environment of its shape.
    pub fn shared(atlases: &[Option<Atlas>], textures: &Textures) -> Arc<dyn Heights> {
        Arc::new(Env::new(atlases, textures))
    }

    /// The attributes of the one atlas `h` reads, sampled at `q`.
    fn atlas_values(&self, h: &Height, k: AtlasId, q: DVec3) -> AtlasValues {
        match (h.atlas, self.atlases.get(k.index())) {
            (Some(mine), Some(Some(a))) if mine == k => AtlasValues::from_sample(&a.sample(q)),
            _ => AtlasValues::FAILED,
        }
    }
}

impl Heights for Env {
    fn scalar(&self, h: &Height, q: DVec3, n: DVec3) -> Option<f64> {
        let mut atlas = |k: AtlasId| self.atlas_values(h, k, q);
        Some(material::eval_scalar(
            &h.value,
            q,
            n,
            &self.textures,
            self.atlases.len(),
            &mut atlas,
        ))
    }

    fn uv(&self, h: &Height, q: DVec3, n: DVec3) -> Option<DVec2> {
        let mut atlas = |k: AtlasId| self.atlas_values(h, k, q);
        Some(material::eval_vec2(
            &h.value,
            q,
            n,
            &self.textures,
            self.atlases.len(),
            &mut atlas,
        ))
    }
}
