//! Material textures on the CPU: decoding, the mip chain (the very levels the GPU
//! uploads, `gpu::texture`), and an f64 mirror of WGSL's `textureSampleGrad` through
//! the samplers sdfc creates (linear mag, min and mip filters; repeat, mirror or clamp).
//!
//! What the CPU can only approximate: a GPU computes the level of detail λ and the
//! bilinear weights in reduced precision (Vulkan requires at least 4 bits of λ's
//! fraction and 8 bits of sub-texel position; lavapipe and most hardware use 8 bits for
//! both, and may approximate the ρ of the scale factor). For a level difference Δ
//! between texels and levels, that is an error of at most about Δ/256 + Δ/512 on each
//! channel; with sRGB decoding after filtering weights, colours stay within 2/255 where
//! the texture is not extreme (see tests/material_ref.rs for what is asserted).

use crate::sema::Program;
use glam::{DVec2, DVec4};
use image::RgbaImage;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// A decoded image and its mip chain: level 0 is the image, each next level halves
/// each side (at least 1), down to 1×1.
#[derive(Debug, Clone, PartialEq)]
pub struct MipChain {
    pub levels: Vec<RgbaImage>,
}

/// Decodes an image file (already resolved by [`crate::access::Access`]) with the
/// decoder limits of [`crate::access::decoder_limits`], as RGBA8.
pub fn decode(path: &Path) -> Result<RgbaImage, String> {
    let unreadable =
        |e: &dyn std::fmt::Display| format!("cannot read texture {}: {e}", path.display());
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| unreadable(&e))?
        .with_guessed_format()
        .map_err(|e| unreadable(&e))?;
    // The header was checked at check time; these limits hold even if the file changed.
    reader.limits(crate::access::decoder_limits());
    Ok(reader.decode().map_err(|e| unreadable(&e))?.to_rgba8())
}

impl MipChain {
    /// The chain of `image`: each level is the previous one resized to half (at least
    /// one texel a side) with a triangle filter on the stored (sRGB-encoded) bytes.
    /// The GPU uploads exactly these levels, so both sides filter the same texels.
    pub fn new(image: RgbaImage) -> MipChain {
        let (w, h) = image.dimensions();
        let count = 32 - w.max(h).max(1).leading_zeros();
        let mut levels = Vec::with_capacity(count as usize);
        let mut level = image;
        for _ in 1..count {
            let (lw, lh) = level.dimensions();
            let next = image::imageops::resize(
                &level,
                (lw / 2).max(1),
                (lh / 2).max(1),
                image::imageops::FilterType::Triangle,
            );
            levels.push(std::mem::replace(&mut level, next));
        }
        levels.push(level);
        MipChain { levels }
    }

    /// Level 0's size.
    pub fn size(&self) -> DVec2 {
        let (w, h) = self.levels[0].dimensions();
        DVec2::new(w as f64, h as f64)
    }

    /// The level of detail of a sample with uv derivatives `ddx` and `ddy` (Vulkan's
    /// λ_base = log2 ρ_max with ρ the exact lengths of the scaled derivatives), before
    /// clamping to the chain.
    pub fn lod(&self, ddx: DVec2, ddy: DVec2) -> f64 {
        let s = self.size();
        let rho = (ddx * s).length().max((ddy * s).length());
        rho.log2()
    }

    /// `textureSampleGrad(t, s, uv, ddx, ddy)` with a sampler of `wrap` and linear
    /// filters: trilinear between the two levels around λ (bilinear in level 0 when
    /// magnifying). Colour textures (`srgb`) are decoded to linear per texel before
    /// filtering, as the GPU's `Rgba8UnormSrgb` format does; alpha stays linear.
    pub fn sample_grad(&self, uv: DVec2, ddx: DVec2, ddy: DVec2, wrap: Wrap, srgb: bool) -> DVec4 {
        let last = (self.levels.len() - 1) as f64;
        let lod = self.lod(ddx, ddy);
        // NaN (a zero or non-finite derivative) samples level 0, as log2(0) = -inf does.
        let lod = if lod.is_nan() {
            0.0
        } else {
            lod.clamp(0.0, last)
        };
        let base = lod.floor();
        let t = lod - base;
        let a = self.bilinear(base as usize, uv, wrap, srgb);
        if t == 0.0 {
            return a;
        }
        let b = self.bilinear(base as usize + 1, uv, wrap, srgb);
        a + (b - a) * t
    }

    /// Bilinear filtering in one level (texel centres at half-integers).
    pub fn bilinear(&self, level: usize, uv: DVec2, wrap: Wrap, srgb: bool) -> DVec4 {
        let img = &self.levels[level];
        let (w, h) = img.dimensions();
        if w == 0 || h == 0 {
            return DVec4::ZERO;
        }
        let x = uv.x * w as f64 - 0.5;
        let y = uv.y * h as f64 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return DVec4::ZERO;
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |i: f64, j: f64| {
            let (i, j) = (wrap.apply(i as i64, w), wrap.apply(j as i64, h));
            let p = img.get_pixel(i, j).0;
            let c = |k: usize| {
                let v = p[k] as f64 / 255.0;
                if srgb && k < 3 {
                    srgb_to_linear(v)
                } else {
                    v
                }
            };
            DVec4::new(c(0), c(1), c(2), c(3))
        };
        let top = texel(x0, y0) * (1.0 - fx) + texel(x0 + 1.0, y0) * fx;
        let bottom = texel(x0, y0 + 1.0) * (1.0 - fx) + texel(x0 + 1.0, y0 + 1.0) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// The sRGB transfer function's inverse (IEC 61966-2-1), as the GPU's sRGB formats
/// decode.
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A sampler's address mode, from `sample(…, wrap)` (as `gpu::texture::sampler` maps it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Mirror,
    Clamp,
}

impl Wrap {
    pub fn parse(s: &str) -> Wrap {
        match s {
            "mirror" => Wrap::Mirror,
            "clamp" => Wrap::Clamp,
            _ => Wrap::Repeat,
        }
    }

    /// The texel index `i` of a row of `n` texels addresses (Vulkan's wrapping).
    pub fn apply(self, i: i64, n: u32) -> u32 {
        let n = n as i64;
        let k = match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let t = i.rem_euclid(2 * n);
                if t < n {
                    t
                } else {
                    2 * n - 1 - t
                }
            }
        };
        k as u32
    }
}

/// The decoded textures of a program, by the path as the scene writes it (the key of
/// `codegen::TextureUse::path`).
#[derive(Debug, Clone, Default)]
pub struct Textures {
    images: HashMap<String, Arc<MipChain>>,
}

impl Textures {
    /// Decodes every texture of the program from the file that
    /// [`crate::access::Access`] resolved at check time (never from the path as
    /// written, so nothing outside the allowed folders is read).
    pub fn load(program: &Program) -> Result<Textures, String> {
        let mut out = Textures::default();
        for t in &program.textures {
            if out.images.contains_key(&t.path) {
                continue;
            }
            let Some(full) = &t.resolved else {
                return Err(format!(
                    "texture \"{}\" was not resolved when the scene was checked",
                    t.path
                ));
            };
            out.insert(&t.path, decode(full)?);
        }
        Ok(out)
    }

    /// Already decoded images, by the path the scene writes.
    pub fn from_images(images: impl IntoIterator<Item = (String, RgbaImage)>) -> Textures {
        let mut out = Textures::default();
        for (path, img) in images {
            out.insert(&path, img);
        }
        out
    }

    pub fn insert(&mut self, path: &str, image: RgbaImage) {
        self.images
            .insert(path.to_string(), Arc::new(MipChain::new(image)));
    }

    pub fn get(&self, path: &str) -> Option<&MipChain> {
        self.images.get(path).map(|m| &**m)
    }
}
