//! Least-squares texels (`--texels fit`, `src/bake/fit.rs`): the solver against a
//! dense least-squares solve, and a bake whose fitted texels keep every border texel
//! of the point-sampled bake and draw the material closer between texels, measured at
//! points the fit never saw.

use crate::common;

use common::{assert_borders_identical, Rng};
use sdfc::bake::fit::{fit_chart, half_points, FITTED};
use sdfc::bake::gpu::{BakePass, Shaded};
use sdfc::bake::mips::{Texel, CHANNELS};
use sdfc::bake::pipeline::{self, Baked, Options, Quiet, Resolution, Texels};
use sdfc::bake::table::ChartsFile;
use sdfc::gpu::gpu_for_tests;
use std::path::Path;

/// A shaded sample holding `v` in the fitted channels (the rest unused by the fit).
fn shaded(v: [f64; FITTED]) -> Shaded {
    let f = v.map(|x| x as f32);
    Shaded {
        position: [0.0; 3],
        residual: 0.0,
        color: [f[0], f[1], f[2]],
        roughness: f[3],
        metallic: f[4],
        emission: [f[5], f[6], f[7]],
        normal: [0.0, 0.0, 1.0],
        material: 1,
    }
}

/// The bilinear reconstruction of `n × n` texels at half-texel grid point `(a, b)`.
fn reconstruct(texels: &[[f64; FITTED]], n: usize, a: usize, b: usize, k: usize) -> f64 {
    let hat = |d: i64| match d.abs() {
        0 => 1.0,
        1 => 0.5,
        _ => 0.0,
    };
    let mut sum = 0.0;
    for j in 0..n {
        for i in 0..n {
            sum +=
                hat(a as i64 - 2 * i as i64) * hat(b as i64 - 2 * j as i64) * texels[j * n + i][k];
        }
    }
    sum
}

/// A chart of `n × n` texels with the material `g(x, y, k)` (x and y in half-texel
/// units): the point-sampled texels (corner (0, 0) held at 0 and (n−1, n−1) at 1, so
/// that the fit's clamp to the samples' range stays out of the way) and the shaded
/// half points.
fn chart(
    n: usize,
    g: &dyn Fn(f64, f64, usize) -> f64,
) -> (Vec<[f64; FITTED]>, Vec<(usize, usize)>, Vec<Shaded>) {
    let mut texels = vec![[0.0; FITTED]; n * n];
    for j in 0..n {
        for i in 0..n {
            texels[j * n + i] = std::array::from_fn(|k| g(2.0 * i as f64, 2.0 * j as f64, k));
        }
    }
    texels[0] = [0.0; FITTED];
    texels[n * n - 1] = [1.0; FITTED];
    let offsets = half_points(n);
    let samples = offsets
        .iter()
        .map(|&(a, b)| shaded(std::array::from_fn(|k| g(a as f64, b as f64, k))))
        .collect();
    (texels, offsets, samples)
}

fn as_texel(v: [f64; FITTED]) -> Texel<CHANNELS> {
    std::array::from_fn(|k| if k < FITTED { v[k] as f32 } else { 0.5 })
}

/// The fitted chart's texels: the given borders, the fitted inside.
fn fitted(
    n: usize,
    texels: &[[f64; FITTED]],
    offsets: &[(usize, usize)],
    s: &[Shaded],
) -> Vec<[f64; FITTED]> {
    let texel = |i: usize, j: usize| as_texel(texels[j * n + i]);
    let inner = fit_chart(n, &texel, offsets, s);
    let mut out = texels.to_vec();
    let m = n - 2;
    for j in 1..=m {
        for i in 1..=m {
            let t = inner[(j - 1) * m + (i - 1)];
            out[j * n + i] = std::array::from_fn(|k| t[k] as f64);
            // The normal's channels keep their point samples.
            assert!(t[FITTED..].iter().all(|&x| x == 0.5));
        }
    }
    out
}

#[test]
fn the_fit_is_the_least_squares_solution_and_reproduces_a_bilinear_material() {
    let mut rng = Rng(7);
    for n in [3, 4, 9, 16] {
        // A material bilinear between the texels: the fit gives back its texels.
        let coef: Vec<[f64; FITTED]> = (0..n * n)
            .map(|_| std::array::from_fn(|_| 0.1 + 0.8 * rng.unit()))
            .collect();
        let g = |x: f64, y: f64, k: usize| reconstruct(&coef, n, x as usize, y as usize, k);
        let (mut texels, offsets, samples) = chart(n, &g);
        texels[0] = coef[0];
        texels[n * n - 1] = coef[n * n - 1];
        let got = fitted(n, &texels, &offsets, &samples);
        for (a, b) in got.iter().zip(&coef) {
            for k in 0..FITTED {
                assert!(
                    (a[k] - b[k]).abs() < 1e-6,
                    "n = {n}: {} against {}",
                    a[k],
                    b[k]
                );
            }
        }

        // A sample or a texel the material left undefined (inside the chart or on
        // its border): the chart keeps its point samples.
        let m = n - 2;
        let (texels, offsets, samples) = chart(n, &g);
        for undefined in 0..3 {
            let (mut texels, mut samples) = (texels.clone(), samples.clone());
            match undefined {
                0 => samples[offsets.len() / 2].color[1] = f32::NAN,
                1 => texels[n + 1][2] = f64::NAN,
                _ => texels[n - 1][0] = f64::INFINITY,
            }
            let texel = |i: usize, j: usize| as_texel(texels[j * n + i]);
            let kept = fit_chart(n, &texel, &offsets, &samples);
            for (r, t) in kept.iter().enumerate() {
                let want = texel(r % m + 1, r / m + 1);
                assert!(
                    t.iter()
                        .zip(&want)
                        .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())),
                    "n = {n}, case {undefined}"
                );
            }
        }

        // A material that is not: a sharp edge at an angle, and ripples. The fit is
        // the dense least-squares solution over the half-texel samples.
        let phase: [f64; FITTED] = std::array::from_fn(|_| rng.unit() * 6.0);
        let g = |x: f64, y: f64, k: usize| {
            let edge = ((x * 0.9 + y * 0.4 - n as f64 - phase[k]) * 1.5).tanh();
            0.5 + 0.2 * edge + 0.08 * (x * 1.7 + phase[k]).sin() * (y * 1.1).cos()
        };
        let (texels, offsets, samples) = chart(n, &g);
        let got = fitted(n, &texels, &offsets, &samples);
        let last = 2 * n - 3;
        for k in 0..FITTED {
            // Rows: every half point the fit reads; columns: the inner texels.
            let rows: Vec<(usize, usize)> = (1..=last)
                .flat_map(|b| (1..=last).map(move |a| (a, b)))
                .collect();
            let mut a_mat = nalgebra::DMatrix::<f64>::zeros(rows.len(), m * m);
            let mut rhs = nalgebra::DVector::<f64>::zeros(rows.len());
            let mut borders = texels.clone();
            for j in 1..=m {
                for i in 1..=m {
                    borders[j * n + i] = [0.0; FITTED];
                }
            }
            for (r, &(a, b)) in rows.iter().enumerate() {
                let data = if a % 2 == 0 && b % 2 == 0 {
                    texels[(b / 2) * n + a / 2][k]
                } else {
                    g(a as f64, b as f64, k)
                };
                rhs[r] = data - reconstruct(&borders, n, a, b, k);
                for j in 1..=m {
                    for i in 1..=m {
                        let h = |d: i64| match d.abs() {
                            0 => 1.0,
                            1 => 0.5,
                            _ => 0.0,
                        };
                        a_mat[(r, (j - 1) * m + i - 1)] =
                            h(a as i64 - 2 * i as i64) * h(b as i64 - 2 * j as i64);
                    }
                }
            }
            let svd = a_mat.clone().svd(true, true);
            let x = svd.solve(&rhs, 1e-12).unwrap();
            for j in 1..=m {
                for i in 1..=m {
                    let (want, have) = (x[(j - 1) * m + i - 1], got[j * n + i][k]);
                    assert!(
                        (want - have).abs() < 2e-6,
                        "n = {n}, channel {k}, texel ({i}, {j}): {have} against the dense solve's {want}"
                    );
                }
            }
            // And it beats the point samples over the same samples.
            let sse = |t: &[[f64; FITTED]]| -> f64 {
                rows.iter()
                    .map(|&(a, b)| (reconstruct(t, n, a, b, k) - g(a as f64, b as f64, k)).powi(2))
                    .sum()
            };
            if n > 3 {
                assert!(sse(&got) < sse(&texels), "n = {n}, channel {k}");
            }
        }
    }
}

/// A brick image on a sphere and a box (the examples' brick texture, read through the
/// sphere's atlas): edges that cross texels.
const BRICKS: &str = "
let s = sphere(1) | box([0.6, 0.6, 0.6]).translate([0.8, 0, 0]);
atlas a on s {
    seed top = [0, 0, 1] tangent [1, 0, 0];
}
let bricks = image(\"textures/bricks.png\");
material m {
    color = bricks.sample(a.uv * 0.5).rgb;
    roughness = 0.5;
}
render s.paint(m);
";

#[test]
fn fitted_texels_keep_the_borders_and_draw_the_material_closer_between_texels() {
    let Some(gpu) = gpu_for_tests() else { return };
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let (analysis, compiled) = common::check_and_compile_loop(BRICKS, &base);
    let scene = analysis.scene.as_ref().unwrap();
    let shape = sdfc::driver::pick_shape(scene, None).unwrap();
    let bake = |texels: Texels| -> Baked {
        let options = Options {
            size: 512,
            resolution: Resolution::Cells(8),
            texels,
            ..Options::default()
        };
        pipeline::bake(
            &gpu,
            &compiled.module,
            &base,
            analysis.field(shape),
            &options,
            &Quiet,
        )
        .expect("bakes")
    };
    let (points, fit) = (bake(Texels::Points), bake(Texels::Fit));
    let n = points.levels[0].n;
    assert!(n >= 8, "{n}² texels a chart");
    assert_eq!(points.report.fit_samples, 0);
    assert_eq!(
        fit.report.fit_samples,
        half_points(n).len() * fit.table.len()
    );

    // Every level-0 border sample is the point-sampled bake's, bitwise (the levels
    // above average the insides too, so they differ from it there), and the written
    // image keeps every level's borders identical across charts.
    let (p, f) = (&points.levels[0], &fit.levels[0]);
    assert!(p.corners == f.corners, "level 0: corners differ");
    assert!(p.edges == f.edges, "level 0: side texels differ");
    assert!(p.interiors != f.interiors, "the fit changed no texel");
    let file = ChartsFile::new(&fit.table, &fit.atlas, &fit.patches);
    let (sides, _) =
        assert_borders_identical(&fit.textures.base_color, &file, "fitted base colour");
    assert!(sides > 1000, "{sides} side texels compared");

    // Between texels, at points the fit never read (random chart-local points, placed
    // and shaded as the bake places and shades texels), the fitted texels' bilinear
    // reconstruction is closer to the material than the point samples'.
    let pass = BakePass::new(&gpu, &compiled.module, &base).unwrap();
    let mut rng = Rng(11);
    let probes: Vec<(usize, f64, f64)> = (0..20_000)
        .map(|_| {
            let c = (rng.unit() * fit.table.len() as f64) as usize % fit.table.len();
            (c, rng.unit(), rng.unit())
        })
        .collect();
    let inputs: Vec<[f32; 4]> = probes
        .iter()
        .map(|&(c, u, v)| {
            sdfc::bake::images::interior_point(
                &fit.quads,
                &fit.table,
                &fit.vertex_grid,
                c,
                (u, v),
                0.25 / (n - 1) as f64,
            )
        })
        .collect();
    let truth = pass.run(&gpu, &inputs, &|_| {}).unwrap();
    let error = |baked: &Baked| -> f64 {
        let l0 = &baked.levels[0];
        let mut sum = 0.0;
        for (&(c, u, v), s) in probes.iter().zip(&truth) {
            let (x, y) = (u * (n - 1) as f64, v * (n - 1) as f64);
            let (i, j) = ((x as usize).min(n - 2), (y as usize).min(n - 2));
            let (fx, fy) = (x - i as f64, y - j as f64);
            for k in 0..3 {
                let t = |a: usize, b: usize| l0.get(&baked.table, c, a, b)[k] as f64;
                let value = t(i, j) * (1.0 - fx) * (1.0 - fy)
                    + t(i + 1, j) * fx * (1.0 - fy)
                    + t(i, j + 1) * (1.0 - fx) * fy
                    + t(i + 1, j + 1) * fx * fy;
                sum += (value - s.color[k] as f64).powi(2);
            }
        }
        (sum / (3 * probes.len()) as f64).sqrt()
    };
    let (e_points, e_fit) = (error(&points), error(&fit));
    eprintln!(
        "{n}² texels a chart; between texels, colour RMS: points {e_points:.5}, fit {e_fit:.5}"
    );
    assert!(e_fit < 0.95 * e_points, "points {e_points}, fit {e_fit}");
}
