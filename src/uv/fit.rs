//! Encoding a shape as a displaced simple shape (§5.3 of the Implicit UVs paper):
//! rays from the base's surface along its normals to the target, each ray's signed
//! length stored at the uv of Alg. 1, resampled onto a height map's texels.
//!
//! The base is sampled by projecting a deterministic cloud of points in its bounds
//! onto its surface (Π_f); samples whose walk fails (outside the atlas's reach) are
//! dropped. Each texel takes the inverse-distance-weighted mean of the samples within
//! [`REACH`] texels of its centre in uv, or the nearest sample when none is that close.

use super::{Atlas, Status};
use crate::ir::{eval, Shape};
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// The radius, in texels, of a texel's gather.
pub const REACH: f64 = 1.5;

/// A fitted height map: `values[j * size + i]` is texel (i, j)'s signed ray length,
/// the texel at uv `uv_min + (i + 0.5, j + 0.5) / size * (uv_max − uv_min)`.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightMap {
    pub size: u32,
    pub uv_min: DVec2,
    pub uv_max: DVec2,
    pub values: Vec<f64>,
    /// How many base samples had coordinates and a hit.
    pub samples: usize,
}

impl HeightMap {
    pub fn range(&self) -> (f64, f64) {
        let lo = self.values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = self
            .values
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    }

    /// The map as a 16-bit grey image: value = round(65535 · (h − lo) / (hi − lo)),
    /// so h = lo + (hi − lo) · texel (the texel read in [0, 1]).
    pub fn encode16(&self) -> (image::ImageBuffer<image::Luma<u16>, Vec<u16>>, f64, f64) {
        let (lo, hi) = self.range();
        let span = (hi - lo).max(1e-12);
        let img = image::ImageBuffer::from_fn(self.size, self.size, |i, j| {
            let h = self.values[(j * self.size + i) as usize];
            image::Luma([((h - lo) / span * 65535.0).round().clamp(0.0, 65535.0) as u16])
        });
        (img, lo, hi - lo)
    }
}

/// Why no height map can be fitted.
#[derive(Debug, Clone, PartialEq)]
pub enum FitError {
    /// Too few base samples had coordinates and a ray hit.
    TooFewSamples(usize),
}

/// The signed distance along `n` from `x` to the zero set of `target` (positive outward),
/// within `reach`; `None` when the ray finds no surface.
pub fn ray_length(target: &Shape, x: DVec3, n: DVec3, reach: f64) -> Option<f64> {
    let g0 = eval::distance(target, x);
    // Outside the target the surface is inwards (−n), inside it is outwards (+n).
    let dir = if g0 > 0.0 { -1.0 } else { 1.0 };
    let l = target.lipschitz().max(1.0);
    let (mut t, mut prev) = (0.0, 0.0);
    for _ in 0..512 {
        let g = eval::distance(target, x + n * (dir * t));
        if (g > 0.0) != (g0 > 0.0) || g.abs() < 1e-12 {
            // Bisect between prev and t.
            let (mut a, mut b) = (prev, t);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                let gm = eval::distance(target, x + n * (dir * m));
                if (gm > 0.0) == (g0 > 0.0) {
                    a = m;
                } else {
                    b = m;
                }
            }
            return Some(dir * 0.5 * (a + b));
        }
        prev = t;
        t += (g.abs() / l).max(1e-5 * reach);
        if t > reach {
            return None;
        }
    }
    None
}

/// Fits the height map of `target` over `base` in the coordinates of `atlas` (on the
/// base): `size` × `size` texels over the uv rectangle `uv` (by default the samples'
/// extent), from about `samples` base points.
pub fn fit(
    base: &Shape,
    target: &Shape,
    atlas: &Atlas,
    size: u32,
    samples: usize,
    uv: Option<(DVec2, DVec2)>,
) -> Result<HeightMap, FitError> {
    let b = base.framing_bounds();
    let scale = (b.max - b.min).max_element().max(1e-3);
    let reach = 2.0 * scale;
    let (lo, hi) = (
        b.min - DVec3::splat(0.1 * scale),
        b.max + DVec3::splat(0.1 * scale),
    );
    // A deterministic low-discrepancy cloud (R3 sequence) in the bounds.
    let g = 1.220_744_084_605_759_5_f64;
    let alpha = DVec3::new(1.0 / g, 1.0 / (g * g), 1.0 / (g * g * g));
    let hits: Vec<(DVec2, f64)> = (0..samples)
        .into_par_iter()
        .filter_map(|k| {
            let u = (DVec3::splat(0.5) + alpha * (k as f64 + 1.0)).fract();
            let p = lo + (hi - lo) * u;
            let x = eval::project(base, p, 1e-9 * scale)?;
            let s = atlas.sample(x);
            if s.status != Status::Ok {
                return None;
            }
            let n = eval::gradient(base, x).try_normalize()?;
            Some((s.uv, ray_length(target, x, n, reach)?))
        })
        .collect();
    if hits.len() < 16 {
        return Err(FitError::TooFewSamples(hits.len()));
    }
    let (uv_min, uv_max) = uv.unwrap_or_else(|| {
        let mut a = DVec2::splat(f64::INFINITY);
        let mut z = DVec2::splat(f64::NEG_INFINITY);
        for (uv, _) in &hits {
            a = a.min(*uv);
            z = z.max(*uv);
        }
        (a, z)
    });
    let n = size as usize;
    let span = (uv_max - uv_min).max(DVec2::splat(1e-9));
    // Bin the samples by texel.
    let mut bins: Vec<Vec<(DVec2, f64)>> = vec![Vec::new(); n * n];
    let texel = |uv: DVec2| (uv - uv_min) / span * size as f64;
    for &(uv, h) in &hits {
        let t = texel(uv);
        let (i, j) = (t.x.floor(), t.y.floor());
        if i >= 0.0 && j >= 0.0 && (i as usize) < n && (j as usize) < n {
            bins[j as usize * n + i as usize].push((t, h));
        }
    }
    let values: Vec<f64> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            let c = DVec2::new((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let (mut sum, mut weight) = (0.0, 0.0);
            let mut nearest = (f64::INFINITY, 0.0);
            // Rings of bins outwards until something is found.
            for r in 0..=(n as i64) {
                for dj in -r..=r {
                    for di in -r..=r {
                        if di.abs().max(dj.abs()) != r {
                            continue; // the ring at r only
                        }
                        let (i, j) = ((k % n) as i64 + di, (k / n) as i64 + dj);
                        if i < 0 || j < 0 || i >= n as i64 || j >= n as i64 {
                            continue;
                        }
                        for &(t, h) in &bins[j as usize * n + i as usize] {
                            let d = (t - c).length();
                            if d < nearest.0 {
                                nearest = (d, h);
                            }
                            if d <= REACH && r <= 2 {
                                let w = 1.0 / (d * d + 1e-3);
                                sum += w * h;
                                weight += w;
                            }
                        }
                    }
                }
                if r >= 2 && (weight > 0.0 || nearest.0.is_finite()) {
                    break;
                }
            }
            if weight > 0.0 {
                sum / weight
            } else {
                nearest.1
            }
        })
        .collect();
    Ok(HeightMap {
        size,
        uv_min,
        uv_max,
        values,
        samples: hits.len(),
    })
}
