//! Running the `sdfc` binary from integration tests.
#![allow(dead_code)]

pub mod glb;
pub mod quiet;

use std::io::Write;
use std::process::{Command, Stdio};

/// Every scene of `examples/` and `tests/ui/`, sorted: the corpus of the tests that run
/// something over all of them.
pub fn scene_files() -> Vec<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<std::path::PathBuf> = ["examples", "tests/ui"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root.join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .collect();
    files.sort();
    files
}

/// Runs `sdfc` in the package root; (exit code, stdout, stderr).
pub fn sdfc(args: &[&str]) -> (i32, String, String) {
    sdfc_with_input(args, b"")
}

/// Runs `sdfc` in the package root with `input` on standard input.
pub fn sdfc_with_input(args: &[&str], input: &[u8]) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The child may exit before reading all of its input (a usage error): not a failure.
    let _ = child.stdin.take().unwrap().write_all(input);
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A small deterministic generator (xorshift) for test points.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// The Khronos glTF-Validator's report on one file.
pub struct GltfReport {
    pub errors: u64,
    pub warnings: u64,
    pub infos: u64,
    pub hints: u64,
    /// Each issue: `code`, `message`, `severity` (0 error … 3 hint), `pointer`/`offset`.
    pub messages: Vec<serde_json::Value>,
    /// The whole report, as the validator printed it.
    pub json: String,
}

/// Runs the Khronos glTF-Validator (`tools/gltf-validator`, installed there by
/// `npm ci`) on the glTF or GLB file at `path`. When Node or the validator is missing
/// this fails the test if `SDFC_REQUIRE_TOOLS=1` (as in CI) and otherwise says so on
/// stderr and returns `None`, for the caller to skip its check.
pub fn gltf_validate(path: &std::path::Path) -> Option<GltfReport> {
    let tool = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/gltf-validator");
    let installed = tool
        .join("node_modules/gltf-validator/package.json")
        .is_file();
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !installed || !node {
        let missing = if node {
            "the glTF-Validator (run `npm ci` in tools/gltf-validator)"
        } else {
            "node"
        };
        if std::env::var("SDFC_REQUIRE_TOOLS").as_deref() == Ok("1") {
            panic!("SDFC_REQUIRE_TOOLS=1 but {missing} is not installed");
        }
        eprintln!(
            "SKIPPED: glTF validation of {}: {missing} is not installed",
            path.display()
        );
        return None;
    }
    let out = Command::new("node")
        .arg(tool.join("validate.mjs"))
        .arg(path)
        .output()
        .unwrap();
    let json = String::from_utf8_lossy(&out.stdout).into_owned();
    // Exit status 0: clean, 1: errors or warnings (both print a report), 2: no report.
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "the glTF-Validator failed on {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    let issues = &report["issues"];
    let count = |key: &str| issues[key].as_u64().unwrap();
    Some(GltfReport {
        errors: count("numErrors"),
        warnings: count("numWarnings"),
        infos: count("numInfos"),
        hints: count("numHints"),
        messages: issues["messages"].as_array().cloned().unwrap_or_default(),
        json,
    })
}

/// Every texel two charts share, at every level, in an 8-bit image: equal, exactly.
/// Returns how many side texels and corner texels were compared.
pub fn assert_borders_identical(
    img: &image::RgbaImage,
    file: &sdfc::bake::table::ChartsFile,
    what: &str,
) -> (usize, usize) {
    let mut sides = 0;
    let mut corners = 0;
    let texel = |c: usize, l: usize, (i, j): (usize, usize)| {
        let r = file.charts[c].rects[l];
        *img.get_pixel(r[0] + i as u32, r[1] + j as u32)
    };
    use sdfc::bake::charts::side_texel_rect;
    // A side's length in texels: sides 0 and 2 run along the width.
    let along = |r: [u32; 4], s: usize| if s % 2 == 0 { r[2] } else { r[3] } as usize;
    for (c, chart) in file.charts.iter().enumerate() {
        for l in 0..file.levels {
            let r = chart.rects[l];
            let (w, h) = (r[2] as usize, r[3] as usize);
            for s in 0..4 {
                for nb in &chart.neighbours[s] {
                    let n = along(r, s);
                    let r2 = file.charts[nb.chart as usize].rects[l];
                    assert_eq!(n, along(r2, nb.side as usize), "{what}: level {l}, chart {c} side {s} and chart {} side {} differ in length", nb.chart, nb.side);
                    for k in 0..n {
                        let kk = if nb.reversed { n - 1 - k } else { k };
                        let a = texel(c, l, side_texel_rect(w, h, s, k, 0));
                        let b = texel(
                            nb.chart as usize,
                            l,
                            side_texel_rect(
                                r2[2] as usize,
                                r2[3] as usize,
                                nb.side as usize,
                                kk,
                                0,
                            ),
                        );
                        assert_eq!(a, b, "{what}: level {l}, chart {c} side {s} texel {k} against chart {} side {}", nb.chart, nb.side);
                        sides += 1;
                    }
                }
            }
        }
    }
    // Corners: every chart around a mesh vertex has the same corner texel.
    let mut first: std::collections::HashMap<(u32, usize), image::Rgba<u8>> = Default::default();
    for (c, chart) in file.charts.iter().enumerate() {
        for l in 0..file.levels {
            let r = chart.rects[l];
            for q in 0..4 {
                let t = texel(c, l, side_texel_rect(r[2] as usize, r[3] as usize, q, 0, 0));
                let seen = *first.entry((chart.corners[q], l)).or_insert(t);
                assert_eq!(seen, t, "{what}: level {l}, corner {q} of chart {c}");
                corners += 1;
            }
        }
    }
    (sides, corners)
}

/// `n` points on the surface of `shape` with their unit normals: random points of its
/// framing box projected onto the zero set (to 1e-9), where the gradient is not
/// degenerate and `keep` accepts the point. Deterministic for a `seed`.
pub fn surface_points<'a>(
    shape: impl Into<sdfc::ir::Field<'a>>,
    n: usize,
    seed: u64,
    keep: impl Fn(glam::DVec3) -> bool,
) -> Vec<(glam::DVec3, glam::DVec3)> {
    use glam::DVec3;
    let shape: sdfc::ir::Field = shape.into();
    let b = shape.framing_bounds();
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    while out.len() < n {
        let r = DVec3::new(rng.unit(), rng.unit(), rng.unit());
        let Some(x) = sdfc::ir::eval::project(shape, b.min + (b.max - b.min) * r, 1e-9) else {
            continue;
        };
        let g = sdfc::ir::eval::gradient(shape, x);
        if g.length() > 0.5 && keep(x) {
            out.push((x, g.normalize()));
        }
    }
    out
}

/// Mean absolute difference per channel (0–255) and the share of pixels that differ
/// by more than 16 in any channel.
pub fn image_difference(a: &[u8], b: &[u8]) -> (f64, f64) {
    let mut sum = 0u64;
    let mut bad = 0usize;
    for (pa, pb) in a.chunks(4).zip(b.chunks(4)) {
        let mut worst = 0;
        for k in 0..3 {
            let d = (pa[k] as i32 - pb[k] as i32).unsigned_abs();
            sum += d as u64;
            worst = worst.max(d);
        }
        if worst > 16 {
            bad += 1;
        }
    }
    let n = (a.len() / 4) as f64;
    (sum as f64 / (n * 3.0), bad as f64 / n)
}

/// The view of a checked scene's render item at `w` × `h` pixels.
pub fn scene_view(a: &sdfc::driver::Analysis, (w, h): (u32, u32)) -> sdfc::view::View {
    let shape = a
        .scene
        .as_ref()
        .and_then(|s| s.render.clone())
        .unwrap_or_default();
    let mut view = sdfc::view::View::new(a.program.render.as_ref(), &shape);
    (view.width, view.height) = (w, h);
    view
}

/// The PSNR in dB of two RGBA8 images of equal layout, over the colour channels.
pub fn psnr(a: &[u8], b: &[u8]) -> f64 {
    let mut sum = 0.0;
    for (pa, pb) in a.chunks(4).zip(b.chunks(4)) {
        for k in 0..3 {
            sum += (pa[k] as f64 - pb[k] as f64).powi(2);
        }
    }
    let mse = sum / (a.len() / 4 * 3) as f64;
    10.0 * (255.0f64 * 255.0 / mse.max(1e-12)).log10()
}

/// The largest difference of any byte (channel) between two images of equal layout.
pub fn worst_byte_difference(a: &[u8], b: &[u8]) -> u8 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

/// The error codes of a scene after the whole check (codegen and naga included), each
/// run once; asserts no internal compiler error (E0900) and every span inside the text.
pub fn error_codes(src: &str) -> Vec<&'static str> {
    let a = sdfc::driver::check_all(src, None);
    for d in &a.diagnostics {
        assert_ne!(
            d.code, "E0900",
            "internal compiler error: {}\n{src}",
            d.message
        );
        for l in d.primary.iter().chain(&d.secondary) {
            assert!(l.span.end <= src.len());
        }
    }
    let mut c: Vec<&'static str> = a
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| d.code)
        .collect();
    c.dedup();
    c
}

/// Holes in a GPU frame of `shape` seen through `view`: the pixels a conservative CPU
/// trace hits (half steps, `steps × 4` of them) that the frame misses. Returns
/// (covered, holes).
pub fn holes(
    shape: &sdfc::ir::Shape,
    view: &sdfc::view::View,
    frame: &sdfc::gpu::Frame,
    steps: u32,
) -> (usize, usize) {
    let (mut covered, mut holes) = (0, 0);
    let (w, h) = (view.width as f64, view.height as f64);
    for y in 0..view.height {
        for x in 0..view.width {
            let dir = view.camera.ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
            if sdfc::view::trace_cpu(shape, view, dir, 0.5, steps * 4).is_some() {
                covered += 1;
                if frame.position[(y * view.width + x) as usize][3] < 0.0 {
                    holes += 1;
                }
            }
        }
    }
    (covered, holes)
}

/// llvmpipe's GL backend for a test, or `None` after saying loudly why the test is
/// skipped; with `SDFC_REQUIRE_GPU=1` a missing backend is a failure instead.
pub fn gl_for_tests() -> Option<sdfc::gpu::Gpu> {
    match sdfc::gpu::Gpu::new(sdfc::gpu::Backend::Gl) {
        Ok(g) => Some(g),
        Err(e) => {
            if std::env::var("SDFC_REQUIRE_GPU").is_ok_and(|v| v == "1") {
                panic!("SDFC_REQUIRE_GPU=1 but the GL backend is missing: {e}");
            }
            eprintln!("SKIPPING GPU TEST: {e}");
            None
        }
    }
}

/// `sdfc render SCENE` at `size` (WIDTHxHEIGHT) with the loop walk and forward
/// gradients (the library's default, as `export-web` and the embedding example compile
/// it) and `extra` arguments, written to `out`; its pixels (RGBA).
#[allow(dead_code)]
pub fn render_as_library(
    scene: &str,
    size: &str,
    extra: &[&str],
    out: &std::path::Path,
) -> image::RgbaImage {
    let args = [
        "render",
        scene,
        "--walk",
        "loop",
        "--gradients",
        "forward",
        "--size",
        size,
        "-o",
        out.to_str().unwrap(),
    ];
    let (code, _, err) = sdfc(&[&args[..], extra].concat());
    assert_eq!(code, 0, "{scene}: {err}");
    image::open(out).unwrap().to_rgba8()
}

/// Whether the calling test, `path` (`FILE::NAME`), runs in a process of its own, as a
/// test that measures its process's peak memory must: the tests share one binary
/// (tests/suite.rs). In the suite's process this runs the binary again with only that
/// test, passes its output on, fails where it fails, and says no (the caller returns);
/// in that second process it says yes.
pub fn in_own_process(path: &str) -> bool {
    const ALONE: &str = "SDFC_TEST_ALONE";
    if std::env::var(ALONE).as_deref() == Ok(path) {
        return true;
    }
    let exe = std::env::current_exe().expect("the test binary's path");
    let out = Command::new(exe)
        .args([path, "--exact", "--include-ignored", "--nocapture"])
        .args(["--test-threads", "1"])
        .env(ALONE, path)
        .output()
        .expect("the test binary runs again");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    print!("{stdout}");
    eprint!("{stderr}");
    assert!(out.status.success(), "{path} failed in its own process");
    assert!(
        stdout.contains("test result: ok. 1 passed"),
        "{path} is not the name of one test: {stdout}"
    );
    false
}

/// Runs `f` on the field and the shape of the `render` item of `examples/NAME`.
pub fn with_example<T>(
    name: &str,
    f: impl FnOnce(sdfc::ir::Field<'_>, &sdfc::ir::Shape) -> T,
) -> T {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    let analysis = sdfc::driver::check(&text, path.parent());
    let scene = analysis.scene.as_ref().unwrap();
    let shape = sdfc::driver::pick_shape(scene, None).unwrap();
    f(analysis.field(shape), shape)
}

/// A twisted box with a material that shows its normals: creases whose faces turn
/// along them, where a corner's gradient can be either face's normal (`warps.sdf`'s
/// twisted box, alone). For the bake's tangent frames (`tests/bake.rs`) and its
/// close-up against the implicit render (`tests/bake_fidelity.rs`).
pub const TWISTED_BOX: &str = "
let twisted = box([0.6, 2, 0.6]).twist(axis: [0, 1, 0], rate: 1.2);
material paint {
    color = 0.5 + 0.5 * normal;
    roughness = 0.35;
}
render twisted.paint(paint) {
    camera = orbit(target: [0, 0, 0], distance: 2, yaw: 20deg, pitch: 25deg);
    light = sun(direction: [0.3, 1, 0.4]);
}
";

/// The default adapter and llvmpipe's GL backend, for a test that holds on both (the
/// GL backend renders its AOVs through rgba32uint targets: `sdfc::codegen::aov`); each
/// one missing is skipped or fails as `gpu_for_tests` and `gl_for_tests` say.
pub fn both_for_tests() -> Vec<sdfc::gpu::Gpu> {
    [sdfc::gpu::gpu_for_tests(), gl_for_tests()]
        .into_iter()
        .flatten()
        .collect()
}

/// A scene checked without errors (asserted) and compiled with the loop walk, as the
/// bake's tests compile theirs (the unrolled walk's pipeline is slow to build on a
/// software adapter, and the bake does not depend on the walk's form).
pub fn check_and_compile_loop(
    source: &str,
    base: &std::path::Path,
) -> (sdfc::driver::Analysis, sdfc::driver::Compiled) {
    let analysis = sdfc::driver::check(source, Some(base));
    assert!(!analysis.has_errors(), "{:?}", analysis.diagnostics);
    let compiled = sdfc::driver::compile(
        &analysis,
        &sdfc::codegen::Options {
            walk: sdfc::codegen::WalkForm::Loop,
            ..Default::default()
        },
    )
    .expect("compiles");
    (analysis, compiled)
}

/// The connected pieces of a mesh, by shared vertex index.
pub fn mesh_pieces(m: &sdfc::bake::MeshData) -> usize {
    let mut parent: Vec<usize> = (0..m.positions.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for t in m.indices.chunks_exact(3) {
        for k in 1..3 {
            let (a, b) = (
                find(&mut parent, t[0] as usize),
                find(&mut parent, t[k] as usize),
            );
            parent[a] = b;
        }
    }
    let roots: std::collections::HashSet<usize> =
        (0..parent.len()).map(|x| find(&mut parent, x)).collect();
    roots.len()
}

/// The number that starts the report line `label` of `sdfc bake` (0 without the
/// line), as in `folded:         18 triangles ...`.
pub fn report_count(report: &str, label: &str) -> usize {
    report
        .lines()
        .find_map(|l| l.strip_prefix(label))
        .map(|rest| {
            let digits: String = rest
                .trim_start()
                .chars()
                .take_while(char::is_ascii_digit)
                .collect();
            digits.parse().expect("a count")
        })
        .unwrap_or(0)
}

/// How many triangles hold each edge of a mesh, the edge by its ends' positions' bits
/// (so split vertices at one place make one edge).
pub fn edges_by_position(
    m: &sdfc::bake::MeshData,
) -> std::collections::HashMap<[[u32; 3]; 2], usize> {
    let mut held = std::collections::HashMap::new();
    for t in m.indices.chunks_exact(3) {
        for k in 0..3 {
            let a = m.positions[t[k] as usize].map(f32::to_bits);
            let c = m.positions[t[(k + 1) % 3] as usize].map(f32::to_bits);
            *held.entry(if a < c { [a, c] } else { [c, a] }).or_default() += 1;
        }
    }
    held
}
