//! Run-time parameters against their constants: a scene with `param x = … in [lo, hi]`
//! set to a value renders, evaluates on the CPU and on the GPU as the same scene with
//! that value written in; its WGSL is the same whatever the value (no recompiling);
//! at the range's ends no ray passes through the surface.

use glam::DVec3;
use sdfc::access::Access;
use sdfc::gpu::{self, gpu_for_tests, ViewMode};
use sdfc::ir::eval;
use sdfc::view::View;
use std::path::Path;

use crate::common;

/// A scene around one number: `{P}` is replaced by a parameter or by the constant.
struct Case {
    template: &'static str,
    lo: f64,
    hi: f64,
}

const CAMERA: &str =
    "camera = orbit(target: [0, 0, 0], distance: 5, yaw: 30deg, pitch: 20deg); size = [96, 64];";

/// One case per kind of run-time number the generator writes from the block.
const CASES: &[Case] = &[
    Case {
        template: "sphere({P})",
        lo: 0.4,
        hi: 1.1,
    },
    Case {
        template: "box({P})",
        lo: 0.5,
        hi: 1.5,
    },
    Case {
        template: "box([{P}, 1, 0.6])",
        lo: 0.3,
        hi: 1.6,
    },
    Case {
        template: "box_frame([1.2, 1, 0.8], thickness: {P})",
        lo: 0.05,
        hi: 0.3,
    },
    Case {
        template: "torus({P}, 0.25)",
        lo: 0.5,
        hi: 1.2,
    },
    Case {
        template: "capsule([0, -0.8, 0], [{P}, 0.8, 0], 0.3)",
        lo: -0.8,
        hi: 0.8,
    },
    Case {
        template: "cylinder(0.5, {P})",
        lo: 0.5,
        hi: 2.0,
    },
    Case {
        template: "capped_cone(1.2, {P}, 0.2)",
        lo: 0.3,
        hi: 0.9,
    },
    Case {
        template: "smooth_union(sphere(0.6), box([0.5, 1.4, 0.5]).translate([0.7, 0, 0]), {P})",
        lo: 0.05,
        hi: 0.6,
    },
    Case {
        template: "box([0.8, 0.8, 0.8]).translate([{P}, 0.2, 0])",
        lo: -1.0,
        hi: 1.0,
    },
    Case {
        template: "box([0.6, 1.4, 0.8]).rotate_z({P})",
        lo: -1.2,
        hi: 1.2,
    },
    Case {
        template: "box([0.6, 1.4, 0.8]).rotate(axis: [1, 1, 0], angle: {P})",
        lo: 0.0,
        hi: 2.5,
    },
    Case {
        template: "octahedron(0.8).scale({P})",
        lo: 0.6,
        hi: 1.4,
    },
    Case {
        template: "octahedron(0.8).scale([1, {P}, 1.2])",
        lo: 0.5,
        hi: 1.5,
    },
    Case {
        template: "box([0.7, 2, 0.7]).twist(rate: {P})",
        lo: -1.5,
        hi: 1.5,
    },
    Case {
        template: "box([2.4, 0.4, 0.7]).bend(rate: {P})",
        lo: -0.6,
        hi: 0.6,
    },
    Case {
        template: "sphere(0.5).elongate([{P}, 0.2, 0])",
        lo: 0.0,
        hi: 0.8,
    },
    Case {
        template: "box(1).round({P})",
        lo: 0.0,
        hi: 0.3,
    },
    Case {
        template: "sphere(0.9).shell({P}) - box([2, 0.5, 2]).translate([0, 0.6, 0])",
        lo: 0.05,
        hi: 0.4,
    },
    Case {
        template: "sphere(0.3).repeat([{P}, 8, {P}])",
        lo: 0.9,
        hi: 1.6,
    },
    Case {
        template: "sphere(0.8).displace(0.5, scale: {P})",
        lo: 0.05,
        hi: 0.5,
    },
];

fn num(x: f64) -> String {
    format!("{x:?}")
}

/// The parametric source and the constant one at `value`.
fn sources(c: &Case, value: f64) -> (String, String) {
    let mid = 0.5 * (c.lo + c.hi);
    let body = |p: &str| format!("render ({}) {{ {CAMERA} }}\n", c.template.replace("{P}", p));
    let param = format!(
        "param x = {} in [{}, {}];\n{}",
        num(mid),
        num(c.lo),
        num(c.hi),
        body("x")
    );
    (param, body(&format!("({})", num(value))))
}

fn analyze(src: &str, value: Option<f64>) -> sdfc::driver::Analysis {
    let mut access = Access::new(None);
    if let Some(v) = value {
        access.set_param("x", &[v]);
    }
    let a = sdfc::driver::check_all_with(src, &access);
    assert!(!a.has_errors(), "{src}: {:?}", a.diagnostics);
    a
}

fn shape(a: &sdfc::driver::Analysis) -> sdfc::ir::Shape {
    a.scene.as_ref().unwrap().render.clone().unwrap()
}

fn module(a: &sdfc::driver::Analysis) -> sdfc::Module {
    a.compiled.as_ref().expect("a module").module.clone()
}

fn points(n: usize) -> Vec<DVec3> {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| DVec3::new(next(), next(), next()) * 1.8)
        .collect()
}

#[test]
fn a_parameter_equals_its_constant_on_the_cpu_and_its_wgsl_does_not_change() {
    for c in CASES {
        let mut wgsl: Option<String> = None;
        for value in [c.lo, 0.5 * (c.lo + c.hi), c.hi] {
            let (param, constant) = sources(c, value);
            let (a, b) = (analyze(&param, Some(value)), analyze(&constant, None));
            let (sa, sb) = (shape(&a), shape(&b));
            for p in points(500) {
                let (da, db) = (eval::distance(&sa, p), eval::distance(&sb, p));
                assert!(
                    (da - db).abs() <= 1e-5,
                    "{}: at {value}, {p}: {da} ≠ {db}",
                    c.template
                );
                let (ga, gb) = (eval::gradient(&sa, p), eval::gradient(&sb, p));
                assert!(
                    (ga - gb).length() <= 1e-5,
                    "{}: gradient at {p}",
                    c.template
                );
            }
            // The range's bounds hold the shape at this value, and the step bound.
            let (ra, rb) = (sa.root_node(), sb.root_node());
            assert!(
                ra.lipschitz >= rb.lipschitz - 1e-12,
                "{}: {value}",
                c.template
            );
            if rb.bounds.is_finite() {
                assert!(
                    ra.bounds.min.cmple(rb.bounds.min + 1e-9).all()
                        && ra.bounds.max.cmpge(rb.bounds.max - 1e-9).all(),
                    "{}: at {value} the bounds {:?} do not hold {:?}",
                    c.template,
                    ra.bounds,
                    rb.bounds
                );
            }
            let m = module(&a);
            match &wgsl {
                None => wgsl = Some(m.wgsl.clone()),
                Some(w) => assert_eq!(
                    w, &m.wgsl,
                    "{}: the WGSL changed with the value",
                    c.template
                ),
            }
            let field = m
                .manifest
                .params
                .fields
                .iter()
                .find(|f| f.name == "x")
                .unwrap();
            assert_eq!(field.default, vec![value]);
            assert_eq!((field.min, field.max), (c.lo, Some(c.hi)));
        }
    }
}

#[test]
fn a_parameter_equals_its_constant_on_the_gpu() {
    let Some(gpu) = gpu_for_tests() else { return };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut worst: (f64, &str) = (0.0, "");
    for c in CASES {
        for value in [c.lo, c.hi] {
            let (param, constant) = sources(c, value);
            let (a, b) = (analyze(&param, Some(value)), analyze(&constant, None));
            let (ma, mb) = (module(&a), module(&b));
            // The view of the constant scene for both (the camera is explicit).
            let view = View::new(b.program.render.as_ref(), &shape(&b));
            let fa = gpu::render(&gpu, &ma, &view, ViewMode::Color, root).unwrap();
            let fb = gpu::render(&gpu, &mb, &view, ViewMode::Color, root).unwrap();
            let (mean, share) = common::image_difference(&fa.color, &fb.color);
            assert!(
                mean <= 1.5 && share <= 0.005,
                "{} at {value}: mean {mean}/255, share over 16 {share}",
                c.template
            );
            if mean > worst.0 {
                worst = (mean, c.template);
            }
            // Distances on the GPU against the constant scene's CPU reference.
            let pts = points(400);
            let values = gpu::eval_points(&gpu, &ma, &pts).unwrap();
            let sb = shape(&b);
            for (p, v) in pts.iter().zip(&values) {
                let d = eval::distance(&sb, *p);
                assert!(
                    (v[0] as f64 - d).abs() <= 1e-4 * d.abs().max(1.0),
                    "{} at {value}, {p}: GPU {} CPU {d}",
                    c.template,
                    v[0]
                );
            }
        }
    }
    eprintln!("worst mean difference {:.3}/255 ({})", worst.0, worst.1);
}

#[test]
fn no_ray_passes_through_the_surface_at_the_ends_of_a_range() {
    let Some(gpu) = gpu_for_tests() else { return };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (template, lo, hi) in [
        ("box([0.8, 2.5, 0.8]).twist(rate: {P})", -1.8, 1.8),
        ("box([3, 0.4, 0.8]).bend(rate: {P})", -0.8, 0.8),
        ("octahedron(0.8).scale([1, {P}, 1.5])", 0.4, 1.6),
        ("box([0.8, 1, 0.6]).displace(0.5, scale: {P})", 0.05, 0.6),
        (
            "smooth_union(box([0.4, 2, 0.4]), sphere(0.7).translate([0.6, 0, 0]), {P})",
            0.05,
            0.8,
        ),
    ] {
        let c = Case { template, lo, hi };
        for value in [lo, hi] {
            let (param, constant) = sources(&c, value);
            let (a, b) = (analyze(&param, Some(value)), analyze(&constant, None));
            let mut view = View::new(b.program.render.as_ref(), &shape(&b));
            (view.width, view.height) = (96, 96);
            let steps = view.max_steps;
            // Steps over the range's bounds are smaller than the constant's: enough of
            // them that a miss can only be an overshoot.
            view.max_steps = steps * 4;
            let frame = gpu::render(&gpu, &module(&a), &view, ViewMode::Color, root).unwrap();
            // Conservative reference: half steps, four times as many.
            let (covered, holes) = common::holes(&shape(&b), &view, &frame, steps);
            assert!(
                covered > 300,
                "{template} at {value}: {covered} pixels covered"
            );
            assert!(
                holes as f64 <= 0.01 * covered as f64,
                "{template} at {value}: {holes} holes in {covered} covered pixels"
            );
        }
    }
}

#[test]
fn the_command_line_sets_parameters_and_refuses_bad_ones() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("p.sdf");
    std::fs::write(
        &scene,
        "param radius = 0.6 in [0.3, 0.9];\nrender sphere(radius).translate([0.2 * sin(time), 0, 0]);\n",
    )
    .unwrap();
    let s = scene.to_str().unwrap();
    let out = dir.path().join("o.png");
    let o = out.to_str().unwrap();
    let (code, _, err) = common::sdfc(&[
        "render",
        s,
        "--param",
        "radius=0.8",
        "--time",
        "2",
        "-o",
        o,
        "--size",
        "32x32",
        "--walk",
        "loop",
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = common::sdfc(&["render", s, "--param", "radiu=0.8", "-o", o]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("did you mean `radius`"), "{err}");
    let (code, _, err) =
        common::sdfc_with_input(&["eval", s, "--param", "radius=1.5"], b"[[0, 0, 0]]");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("outside the range of `radius`"), "{err}");
    let (code, _, err) = common::sdfc(&["render", s, "--time", "-1", "-o", o]);
    assert_eq!(code, 2, "{err}");
}

/// §5.1 under animation: the bar twists by `1.2 · sin(time)` while its atlas stays on
/// the rest pose. At each frame the uv the GPU computes with the parameters' block
/// equals the uv of the scene with that frame's rate written in.
#[test]
fn an_animated_twist_keeps_the_rest_pose_uv_at_every_frame() {
    let Some(gpu) = gpu_for_tests() else { return };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let source = std::fs::read_to_string(root.join("animated_bar.sdf")).unwrap();
    let options = sdfc::Options {
        walk: sdfc::WalkForm::Loop,
        ..Default::default()
    };
    let build = |src: &str, time: Option<f64>| {
        let mut access = Access::new(Some(&root));
        if let Some(t) = time {
            access.set_param("time", &[t]);
        }
        let a = sdfc::driver::check_with(src, &access);
        assert!(!a.has_errors(), "{:?}", a.diagnostics);
        let m = sdfc::driver::compile(&a, &options).unwrap().module;
        (a, m)
    };
    let mut wgsl = None;
    for t in [0.0, 0.7, 2.0, 4.5] {
        let (a, param) = build(&source, Some(t));
        let rate = 1.2 * f64::sin(t);
        let constant = source.replace("swing * sin(time)", &format!("({rate:?})"));
        let (b, fixed) = build(&constant, None);
        match &wgsl {
            None => wgsl = Some(param.wgsl.clone()),
            Some(w) => assert_eq!(w, &param.wgsl, "the WGSL changed with the time"),
        }
        // The surface points of this frame (hits of the constant scene's render),
        // and the uv both modules compute there.
        let mut view = View::new(b.program.render.as_ref(), &shape(&b));
        (view.width, view.height) = (64, 64);
        let frame = gpu::render(&gpu, &fixed, &view, ViewMode::Color, &root).unwrap();
        let points: Vec<DVec3> = frame
            .position
            .iter()
            .filter(|p| p[3] >= 0.0)
            .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        let ua = gpu::eval_atlas(&gpu, &param, &points).unwrap();
        let ub = gpu::eval_atlas(&gpu, &fixed, &points).unwrap();
        let (mut compared, mut worst) = (0, 0.0f32);
        for (x, y) in ua.iter().zip(&ub) {
            if x.status == 0 && y.status == 0 {
                compared += 1;
                worst = worst
                    .max((x.uv[0] - y.uv[0]).abs())
                    .max((x.uv[1] - y.uv[1]).abs());
            }
        }
        let _ = &a;
        eprintln!("time {t}: {compared} points, worst uv difference {worst:e}");
        assert!(compared > 150, "time {t}: only {compared} points compared");
        assert!(worst <= 1e-5, "time {t}: the uv differ by {worst}");
    }
}

/// Every example turned parametric, number by number (up to eight numbers each,
/// spread over the file), with the language server's "make this number a parameter":
/// where the checker accepts the parameter, the scene set to each end of its range
/// evaluates on the CPU as the scene with that end written in, and its WGSL is the same
/// at both ends.
#[test]
fn every_example_made_parametric_equals_its_constants() {
    use sdfc::ide::{actions, make_param, Document};
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut names: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .collect();
    names.sort();
    let (mut tried, mut accepted, mut moving) = (0, 0, 0);
    for path in names {
        let text = std::fs::read_to_string(&path).unwrap();
        let doc = Document::new(text.as_str(), Some(&root));
        let lexed = sdfc::syntax::lexer::lex(&text, &mut Vec::new());
        let numbers: Vec<sdfc::Span> = lexed
            .tokens
            .iter()
            .filter(|(t, _)| matches!(t, sdfc::syntax::lexer::Token::Number(_)))
            .map(|(_, s)| *s)
            .collect();
        let step = numbers.len().div_ceil(8).max(1);
        for span in numbers.iter().step_by(step) {
            let Some(edits) = make_param::offered(&doc, *span) else {
                continue;
            };
            tried += 1;
            let param = actions::apply(&text, &edits);
            let decl = &edits[0].text;
            let name = decl["param ".len()..]
                .split(' ')
                .next()
                .unwrap()
                .to_string();
            let range = &decl[decl.find(" in [").unwrap() + 5..decl.rfind(']').unwrap()];
            let ends: Vec<&str> = range.split(", ").collect();
            let mut wgsl: Option<String> = None;
            // The module at the defaults, whose atlases on moving shapes follow the
            // parameter on the CPU ([`sdfc::Module::tables_at`]).
            let base = {
                let d = sdfc::driver::check_with(&param, &Access::new(Some(&root)));
                (!d.has_errors()).then(|| {
                    let options = sdfc::Options {
                        walk: sdfc::WalkForm::Loop,
                        ..Default::default()
                    };
                    sdfc::driver::compile(&d, &options).unwrap().module
                })
            };
            for end in ends {
                let radians = end.ends_with("deg");
                let x: f64 = end
                    .trim_end_matches("deg")
                    .trim_end_matches("rad")
                    .parse()
                    .unwrap();
                let value = if radians { x.to_radians() } else { x };
                let mut access = Access::new(Some(&root));
                access.set_param(&name, &[value]);
                let a = sdfc::driver::check_with(&param, &access);
                if a.has_errors() {
                    // Not a number a parameter may set (a setting, a seed, a period…).
                    break;
                }
                let constant = actions::apply(
                    &text,
                    &[sdfc::diagnostic::Edit {
                        span: edits[1].span,
                        text: format!("({end})"),
                    }],
                );
                let b = sdfc::driver::check_with(&constant, &Access::new(Some(&root)));
                if b.has_errors() {
                    // The range's end is not a valid constant there (a zero size).
                    break;
                }
                let (Some(sa), Some(sb)) = (
                    a.scene.as_ref().and_then(|s| s.render.clone()),
                    b.scene.as_ref().and_then(|s| s.render.clone()),
                ) else {
                    break;
                };
                // Near the surface (far from it, a warp's field is the lower bound of
                // its bounding ball, whose radius holds over the whole range).
                for (x, n) in common::surface_points(b.field(&sb), 30, 7, |_| true) {
                    for t in [-0.02, 0.0, 0.03] {
                        let p = x + n * t;
                        let (da, db) = (
                            eval::distance(a.field(&sa), p),
                            eval::distance(b.field(&sb), p),
                        );
                        assert!(
                            (da - db).abs() <= 1e-5,
                            "{}: `{name}` = {end}: at {p}, {da} against {db}",
                            path.display()
                        );
                    }
                }
                let options = sdfc::Options {
                    walk: sdfc::WalkForm::Loop,
                    ..Default::default()
                };
                let m = sdfc::driver::compile(&a, &options).unwrap().module;
                if let Some(base) = &base {
                    let at = |n: &str| (n == name).then(|| vec![value]);
                    let moved = base.tables_at(&at).unwrap();
                    moving += usize::from(!base.moving.is_empty());
                    same_tables(base, &moved, &m.manifest.tables, &path, &name);
                }
                match &wgsl {
                    None => {
                        wgsl = Some(m.wgsl);
                        accepted += 1;
                    }
                    Some(w) => assert!(
                        w == &m.wgsl,
                        "{}: the WGSL changed with `{name}`",
                        path.display()
                    ),
                }
            }
        }
    }
    eprintln!(
        "{accepted} of {tried} numbers of the examples became parameters and agreed; \
         {moving} ends moved an atlas's own shape"
    );
    assert!(accepted >= 40, "only {accepted} of {tried}");
    assert!(moving >= 10, "only {moving} ends moved an atlas's shape");
}

/// The `tables` words of `base` recomputed at a parameter's value (`moved`) against
/// those of the scene compiled at that value (`compiled`): outside the moving atlases'
/// records, identical; inside, integers identical and floats within 1e-5 (the CPU
/// recomputation rewrites the shape's numbers where the compiler lowers them again).
fn same_tables(base: &sdfc::Module, moved: &[u32], compiled: &[u32], path: &Path, name: &str) {
    assert_eq!(moved.len(), compiled.len(), "{}: `{name}`", path.display());
    let mut floats = vec![false; moved.len()];
    for m in &base.moving {
        let at = m.at;
        let n = at.count as usize;
        let mut mark = |from: u32, len: usize| floats[from as usize..][..len].fill(true);
        mark(at.seeds, n * sdfc::codegen::SEED_WORDS);
        mark(at.adj_d, at.capacity as usize);
        if let Some(s) = at.sigma {
            mark(s, 1);
        }
    }
    for (i, ((a, b), float)) in moved.iter().zip(compiled).zip(floats).enumerate() {
        if float {
            let (x, y) = (f32::from_bits(*a) as f64, f32::from_bits(*b) as f64);
            assert!(
                (x - y).abs() <= 1e-5 * (1.0 + y.abs()),
                "{}: `{name}`: word {i}: recomputed {x} against compiled {y}",
                path.display()
            );
        } else {
            assert_eq!(a, b, "{}: `{name}`: word {i}", path.display());
        }
    }
}
