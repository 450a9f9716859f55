//! Least-squares texels: a chart's inner texels chosen so that the bilinear filter
//! every reader applies draws the material between the texels, not only at them.
//!
//! A point-sampled texel holds the material at the texel's point, and a reader's
//! bilinear filter draws straight lines between texels: where the material changes
//! within a texel (a mortar line across it), the picture is the material sampled once
//! by the bake and again by the filter, and its edges spread over both. Here each
//! chart's inner texels minimize the squared difference between that bilinear
//! reconstruction and the material sampled on the half-texel grid (four samples a
//! texel, placed on the exported triangles as the texels are), with the chart's border
//! texels held as they are: point samples, bitwise equal to the chart's beside it.
//!
//! With the samples on a (2n − 1)² grid over a chart of n × n texels, the
//! reconstruction at a sample is `A ⊗ A` applied to the texels, where a column of `A`
//! is a texel's hat (1 at its own sample, ½ at the two beside it). The normal
//! equations are then `(T ⊗ T) x = r` with `T = AᵀA` restricted to the inner texels:
//! tridiagonal, 3⁄2 on the diagonal and ¼ beside it, strictly diagonally dominant, so
//! `x = T⁻¹ R T⁻¹` is two sweeps of the Thomas algorithm. A material that is bilinear
//! between the texels is reproduced exactly (`tests/bake_fit.rs`); the result is
//! clamped to the range of the chart's samples, so no channel leaves its legal range.

use super::charts::{ChartTable, Samples};
use super::gpu::{BakePass, Shaded};
use super::images;
use super::mesh::QuadMesh;
use super::mips::{Texel, CHANNELS};
use crate::gpu::{Gpu, GpuError};
use rayon::prelude::*;

/// The channels fitted: base colour, roughness, metallic and emission, the first eight
/// of a texel. The shading normal keeps its point sample: it is a unit vector, which a
/// fit of its components would not keep.
pub const FITTED: usize = 8;

/// The sub-texel samples shaded at once, in whole charts (a chart with more is one
/// batch): with their points, results, dispatch buffers and fitted texels, about
/// 100 MiB at this count ([`super::pipeline::FIT_BATCH_SAMPLE_BYTES`]).
pub const BATCH_POINTS: usize = 1 << 18;

/// How many [`half_points`] a chart of `n` texels a side has, without listing them:
/// `(2n − 3)² − (n − 2)²`.
pub fn half_count(n: usize) -> usize {
    if n < 3 {
        0
    } else {
        (2 * n - 3).pow(2) - (n - 2).pow(2)
    }
}

/// How many charts of `n` texels a side are fitted at once.
fn batch_charts(n: usize) -> usize {
    (BATCH_POINTS / half_count(n).max(1)).max(1)
}

/// The most sub-texel samples held at once when `cells` charts of `n` texels a side
/// are fitted (for the bake's memory estimate).
pub fn batch_samples(n: usize, cells: usize) -> usize {
    half_count(n) * batch_charts(n).min(cells)
}

/// How a bake chooses its level-0 texels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Texels {
    /// Every texel the material at its own point.
    #[default]
    Points,
    /// Inner texels fitted for a bilinear reader ([`fit`]): four times the material
    /// samples of `Points`.
    Fit,
}

/// The half-texel grid points `(a, b)` of a chart with `n` texels a side that the fit
/// reads and that are not texel points: `1 ≤ a, b ≤ 2n − 3`, not both even. A texel
/// `(i, j)` sits at `(2i, 2j)`.
pub fn half_points(n: usize) -> Vec<(usize, usize)> {
    if n < 3 {
        return Vec::new();
    }
    let last = 2 * n - 3;
    (1..=last)
        .flat_map(|b| (1..=last).map(move |a| (a, b)))
        .filter(|&(a, b)| a % 2 == 1 || b % 2 == 1)
        .collect()
}

/// Fits the inner texels of every chart of `level0` (see the module's text), shading
/// the sub-texel samples with `pass` in batches of charts. Returns how many samples it
/// shaded; `progress` advances by each batch's.
#[allow(clippy::too_many_arguments)]
pub fn fit(
    gpu: &Gpu,
    pass: &BakePass,
    mesh: &QuadMesh,
    table: &ChartTable,
    grid: &Samples<[f64; 3]>,
    level0: &mut Samples<Texel<CHANNELS>>,
    progress: &dyn Fn(usize),
) -> Result<usize, GpuError> {
    let n = level0.n;
    let offsets = half_points(n);
    if offsets.is_empty() || table.is_empty() {
        return Ok(0);
    }
    let m = n - 2;
    let half = 0.5 / (n - 1) as f64;
    let batch = batch_charts(n);
    let mut shaded_count = 0;
    for first in (0..table.len()).step_by(batch) {
        let charts = first..(first + batch).min(table.len());
        let points: Vec<[f32; 4]> = charts
            .clone()
            .into_par_iter()
            .flat_map_iter(|c| {
                offsets.iter().map(move |&(a, b)| {
                    images::interior_point(
                        mesh,
                        table,
                        grid,
                        c,
                        (a as f64 * half, b as f64 * half),
                        half,
                    )
                })
            })
            .collect();
        let shaded = pass.run(gpu, &points, progress)?;
        drop(points);
        shaded_count += shaded.len();
        let samples = &*level0;
        let fitted: Vec<Vec<Texel<CHANNELS>>> = charts
            .clone()
            .into_par_iter()
            .map(|c| {
                let own = &shaded[(c - first) * offsets.len()..][..offsets.len()];
                fit_chart(n, &|i, j| samples.get(table, c, i, j), &offsets, own)
            })
            .collect();
        for (c, inner) in charts.zip(fitted) {
            level0.interiors[c * m * m..(c + 1) * m * m].copy_from_slice(&inner);
        }
    }
    Ok(shaded_count)
}

/// The fitted channels of a shaded sample.
fn channels(s: &Shaded) -> [f64; FITTED] {
    let e = s.emission;
    [
        s.color[0],
        s.color[1],
        s.color[2],
        s.roughness,
        s.metallic,
        e[0],
        e[1],
        e[2],
    ]
    .map(f64::from)
}

/// One chart's inner texels, row by row (`(n − 2)²`, as [`Samples::interiors`] holds
/// them): `texel(i, j)` gives the chart's point-sampled texels, `samples` the shaded
/// [`half_points`] in their order. Channels past [`FITTED`] keep their point samples.
pub fn fit_chart(
    n: usize,
    texel: &dyn Fn(usize, usize) -> Texel<CHANNELS>,
    offsets: &[(usize, usize)],
    samples: &[Shaded],
) -> Vec<Texel<CHANNELS>> {
    if n < 3 {
        return Vec::new();
    }
    let m = n - 2;
    let side = 2 * n - 1;
    let inner: Vec<Texel<CHANNELS>> = (1..=m)
        .flat_map(|j| (1..=m).map(move |i| (i, j)))
        .map(|(i, j)| texel(i, j))
        .collect();
    let mut data = vec![[0.0; FITTED]; side * side];
    for (&(a, b), s) in offsets.iter().zip(samples) {
        data[b * side + a] = channels(s);
    }
    // The texels: borders as they are, the inner ones (the unknowns) zero.
    let mut coef = vec![[0.0; FITTED]; n * n];
    for j in 0..n {
        for i in 0..n {
            let t = texel(i, j);
            let v: [f64; FITTED] = std::array::from_fn(|k| t[k] as f64);
            if (1..=m).contains(&i) && (1..=m).contains(&j) {
                data[2 * j * side + 2 * i] = v;
            } else {
                coef[j * n + i] = v;
            }
        }
    }
    // A sample or texel the material left undefined: the chart keeps its point
    // samples (a fit would spread it over the whole chart).
    if data.iter().chain(&coef).flatten().any(|x| !x.is_finite()) {
        return inner;
    }
    // The range of the chart's samples, which the fitted texels keep to.
    let (mut lo, mut hi) = ([f64::INFINITY; FITTED], [f64::NEG_INFINITY; FITTED]);
    let mut extend = |v: &[f64; FITTED]| {
        for k in 0..FITTED {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    };
    let last = 2 * n - 3;
    for j in 0..n {
        for i in 0..n {
            if !((1..=m).contains(&i) && (1..=m).contains(&j)) {
                extend(&coef[j * n + i]);
            }
        }
    }
    for b in 1..=last {
        for a in 1..=last {
            extend(&data[b * side + a]);
        }
    }
    // The residual of the samples against the border texels' reconstruction.
    let hat = |d: isize| match d {
        0 => 1.0,
        -1 | 1 => 0.5,
        _ => 0.0,
    };
    let reconstruct = |a: usize, b: usize, k: usize| {
        let (i0, j0) = ((a - 1) / 2, (b - 1) / 2);
        let mut sum = 0.0;
        for j in j0..=(j0 + 1).min(n - 1) {
            for i in i0..=(i0 + 1).min(n - 1) {
                let w = hat(a as isize - 2 * i as isize) * hat(b as isize - 2 * j as isize);
                sum += w * coef[j * n + i][k];
            }
        }
        sum
    };
    let mut out = inner;
    let mut rhs = vec![0.0; m * m];
    for k in 0..FITTED {
        let residual = |a: usize, b: usize| data[b * side + a][k] - reconstruct(a, b, k);
        for j in 1..=m {
            for i in 1..=m {
                let mut r = 0.0;
                for db in -1isize..=1 {
                    for da in -1isize..=1 {
                        let (a, b) = ((2 * i) as isize + da, (2 * j) as isize + db);
                        r += hat(da) * hat(db) * residual(a as usize, b as usize);
                    }
                }
                rhs[(j - 1) * m + (i - 1)] = r;
            }
        }
        solve_kronecker(&mut rhs, m);
        for (t, x) in out.iter_mut().zip(&rhs) {
            t[k] = x.clamp(lo[k], hi[k]) as f32;
        }
    }
    out
}

/// Solves `(T ⊗ T) x = r` in place for the `m × m` array `r` (row by row), `T` the
/// `m × m` tridiagonal matrix with 3⁄2 on its diagonal and ¼ beside it.
fn solve_kronecker(r: &mut [f64], m: usize) {
    let mut line = vec![0.0; m];
    for j in 0..m {
        line.copy_from_slice(&r[j * m..(j + 1) * m]);
        thomas(&mut line);
        r[j * m..(j + 1) * m].copy_from_slice(&line);
    }
    for i in 0..m {
        for (j, x) in line.iter_mut().enumerate() {
            *x = r[j * m + i];
        }
        thomas(&mut line);
        for (j, x) in line.iter().enumerate() {
            r[j * m + i] = *x;
        }
    }
}

/// Solves `T x = d` in place (the Thomas algorithm), `T` as in [`solve_kronecker`].
fn thomas(d: &mut [f64]) {
    const DIAG: f64 = 1.5;
    const SIDE: f64 = 0.25;
    let m = d.len();
    let mut c = vec![0.0; m];
    let mut pivot = DIAG;
    c[0] = SIDE / pivot;
    d[0] /= pivot;
    for i in 1..m {
        pivot = DIAG - SIDE * c[i - 1];
        c[i] = SIDE / pivot;
        d[i] = (d[i] - SIDE * d[i - 1]) / pivot;
    }
    for i in (0..m.saturating_sub(1)).rev() {
        d[i] -= c[i] * d[i + 1];
    }
}
