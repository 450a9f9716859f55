//! The agreement suite: for every math builtin (the `Math` rows of the builtins table)
//! and every primitive, the three evaluators of the language agree on sampled
//! arguments. For math: the constant folder (a `let` of the call on constants, folded
//! by the checker), the f64 interpreter of surface fields (the same call on `position`'s
//! components in a material, `reference::material`) and the GPU (the generated
//! `scene_material` in `cs_material`). The folder and the interpreter share one
//! definition (`sema::math`), so they must agree exactly (bit for bit); the GPU computes
//! in f32, within a relative 2e-5 (stated per row where the function amplifies f32's
//! rounding of its arguments). For primitives: the CPU reference's distance against the
//! GPU's (`cs_points`), within 1e-5 of the shape's size, and the primitive's bounds and
//! Lipschitz constant against sampled points. A builtin of either kind with no row
//! here fails the suite.

use glam::DVec3;
use sdfc::sema::builtins::{Kind, BUILTINS};
use sdfc::sema::math::{Math, MATH};
use sdfc::sema::Value;

use crate::common;
use common::Rng;

/// How a math builtin is sampled: its arguments' ranges, as (lo, hi) per float
/// argument, and the vector forms to try.
struct Domain {
    name: &'static str,
    args: &'static [(f64, f64)],
    /// The first argument is `position` (a vec3), the others floats widened to it.
    widened: bool,
    /// Relative tolerance of the GPU against the CPU.
    tol: f64,
}

const fn d(name: &'static str, args: &'static [(f64, f64)]) -> Domain {
    Domain {
        name,
        args,
        widened: true,
        tol: 2e-5,
    }
}

/// Every math builtin's arguments. `length`, `normalize`, `cross`, `dot` and
/// `distance` take vectors; they are sampled with `position` and a constant vector.
const DOMAINS: &[Domain] = &[
    d("sin", &[(-3.0, 3.0)]),
    d("cos", &[(-3.0, 3.0)]),
    d("tan", &[(-1.2, 1.2)]),
    // Mesa's lavapipe computes asin and acos with polynomial approximations good to
    // about 3e-4 (measured: 3.3e-4 and 1.2e-4 at worst); the others to 2e-6 or better.
    Domain {
        name: "asin",
        args: &[(-0.95, 0.95)],
        widened: true,
        tol: 5e-4,
    },
    Domain {
        name: "acos",
        args: &[(-0.95, 0.95)],
        widened: true,
        tol: 5e-4,
    },
    d("atan", &[(-4.0, 4.0)]),
    d("atan2", &[(-2.0, 2.0), (0.2, 2.0)]),
    d("sqrt", &[(0.01, 9.0)]),
    d("abs", &[(-3.0, 3.0)]),
    d("floor", &[(-3.0, 3.0)]),
    d("ceil", &[(-3.0, 3.0)]),
    d("fract", &[(-3.0, 3.0)]),
    d("sign", &[(-3.0, 3.0)]),
    d("exp", &[(-3.0, 3.0)]),
    d("log", &[(0.05, 9.0)]),
    d("pow", &[(0.1, 3.0), (-2.0, 2.0)]),
    d("min", &[(-3.0, 3.0), (-3.0, 3.0)]),
    d("max", &[(-3.0, 3.0), (-3.0, 3.0)]),
    d("clamp", &[(-3.0, 3.0), (-2.0, -0.5), (0.5, 2.0)]),
    d("mix", &[(-3.0, 3.0), (-3.0, 3.0), (-0.5, 1.5)]),
    d("smoothstep", &[(-1.0, -0.2), (0.2, 1.0), (-1.5, 1.5)]),
    d("step", &[(-2.0, 2.0), (-2.0, 2.0)]),
    d("radians", &[(-360.0, 360.0)]),
    d("degrees", &[(-7.0, 7.0)]),
    Domain {
        name: "length",
        args: &[],
        widened: false,
        tol: 2e-5,
    },
    Domain {
        name: "normalize",
        args: &[],
        widened: false,
        tol: 2e-5,
    },
    Domain {
        name: "cross",
        args: &[],
        widened: false,
        tol: 2e-5,
    },
    Domain {
        name: "dot",
        args: &[],
        widened: false,
        tol: 2e-5,
    },
    Domain {
        name: "distance",
        args: &[],
        widened: false,
        tol: 2e-5,
    },
];

/// A constant vector the vector builtins pair with `position`.
const OTHER: [f64; 3] = [0.4, -1.3, 0.7];

fn lit(x: f64) -> String {
    format!("{x:?}")
}

fn vec_lit(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", lit(v[0]), lit(v[1]), lit(v[2]))
}

/// One sampled call: the point (the arguments' values in its components), the call
/// on constants and the call on the material's `position`.
struct Case {
    p: DVec3,
    constant: String,
    field: String,
}

/// A point of the domain away from the builtin's jumps, and its two spellings.
fn case(m: Math, dom: &Domain, rng: &mut Rng, vector: bool) -> Case {
    let name = dom.name;
    loop {
        let mut c = [0.0; 3];
        for (k, r) in dom.args.iter().enumerate() {
            c[k] = rng.range(r.0, r.1);
        }
        if dom.args.is_empty() {
            c = [
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
            ];
        }
        let p = DVec3::from_array(c);
        let (constant, field) = if dom.args.is_empty() {
            let other = if matches!(m, Math::Length | Math::Normalize) {
                String::new()
            } else {
                format!(", {}", vec_lit(OTHER))
            };
            (
                format!("{name}({}{other})", vec_lit(c)),
                format!("{name}(position{other})"),
            )
        } else if vector {
            // The first argument is the whole point; the others are floats (fixed, 37 %
            // into their ranges) widened to vec3.
            let rest: Vec<String> = dom.args[1..]
                .iter()
                .map(|r| lit(r.0 + 0.37 * (r.1 - r.0)))
                .collect();
            let tail: String = rest.iter().map(|r| format!(", {r}")).collect();
            let c = [c[0], c[1], c[2]].map(|x| x.clamp(dom.args[0].0, dom.args[0].1));
            let p = DVec3::from_array(c);
            return Case {
                p,
                constant: format!("{name}({}{tail})", vec_lit(c)),
                field: format!("{name}(position{tail})"),
            };
        } else {
            let axes = ["x", "y", "z"];
            let consts: Vec<String> = (0..dom.args.len()).map(|k| lit(c[k])).collect();
            let fields: Vec<String> = (0..dom.args.len())
                .map(|k| format!("position.{}", axes[k]))
                .collect();
            (
                format!("{name}({})", consts.join(", ")),
                format!("{name}({})", fields.join(", ")),
            )
        };
        // Away from jumps, so that f32 and f64 land on the same side.
        let comps: Vec<Vec<f64>> = if dom.args.is_empty() {
            vec![c.to_vec(), OTHER.to_vec()]
        } else {
            (0..dom.args.len()).map(|k| vec![c[k]]).collect()
        };
        let refs: Vec<&[f64]> = comps.iter().map(|v| v.as_slice()).collect();
        if m.jump(&refs) > 1e-3 {
            return Case { p, constant, field };
        }
    }
}

/// The folded value of `let k = CALL;` as components.
fn folded(call: &str) -> Vec<f64> {
    let src = format!("let k = {call};\nrender sphere(1);\n");
    let a = sdfc::driver::check(&src, None);
    assert!(!a.has_errors(), "{src}: {:?}", a.diagnostics);
    let def = a.program.defs.iter().find(|d| d.name == "k").unwrap();
    match &def.value {
        Value::Float(x) => vec![*x],
        Value::Vec(v) => v.clone(),
        other => panic!("{call} folded to {other:?}"),
    }
}

#[test]
fn every_math_builtin_has_one_definition_and_a_row_here() {
    let math: Vec<&str> = BUILTINS
        .iter()
        .filter(|b| b.kind == Kind::Math)
        .map(|b| b.name)
        .collect();
    for name in &math {
        let id = sdfc::sema::builtins::lookup(name).unwrap().id;
        assert!(
            Math::of(id).is_some(),
            "`{name}` has no row in sema::math::MATH"
        );
        assert!(
            DOMAINS.iter().any(|d| d.name == *name),
            "`{name}` has no row in the agreement suite's DOMAINS"
        );
    }
    assert_eq!(
        MATH.len(),
        math.len(),
        "MATH holds a row that is not a math builtin"
    );
    for (i, row) in MATH.iter().enumerate() {
        assert_eq!(row.op as usize, i, "MATH is in Math order");
        assert_eq!(row.id.builtin().kind, Kind::Math);
    }
}

#[test]
fn folder_interpreter_and_gpu_agree_on_every_math_builtin() {
    let gpu = sdfc::gpu::gpu_for_tests();
    let mut rng = Rng(2026);
    let mut report = Vec::new();
    let mut failures = Vec::new();
    for dom in DOMAINS {
        let id = sdfc::sema::builtins::lookup(dom.name).unwrap().id;
        let m = Math::of(id).unwrap();
        let forms: &[bool] = if dom.widened && !dom.args.is_empty() {
            &[false, true]
        } else {
            &[false]
        };
        for &vector in forms {
            let cases: Vec<Case> = (0..12).map(|_| case(m, dom, &mut rng, vector)).collect();
            // One material per case would need one shape each: one scene per case keeps
            // the CPU side exact; the GPU evaluates all of a form's cases in one module
            // whose material is the call on `position`.
            let field = &cases[0].field;
            let src = format!("material m {{ color = {field}; }}\nrender sphere(1).paint(m);\n");
            let a = sdfc::driver::check(&src, None);
            assert!(!a.has_errors(), "{src}: {:?}", a.diagnostics);
            let cpu =
                sdfc::reference::material::MaterialEval::load(&a.program, &a.atlases).unwrap();
            let n = DVec3::Z;
            let mut want = Vec::new();
            for c in &cases {
                let f = folded(&c.constant);
                let v = cpu.eval(1, c.p, n, 0.0).color;
                let got: Vec<f64> = if f.len() == 1 {
                    vec![v.x]
                } else {
                    v.to_array().to_vec()
                };
                let f3 = if f.len() == 1 {
                    f.clone()
                } else {
                    f[..3].to_vec()
                };
                assert_eq!(
                    got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                    f3.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                    "{}: folded {f3:?} but the interpreter gives {got:?} ({})",
                    c.constant,
                    c.field
                );
                want.push(got);
            }
            let Some(gpu) = &gpu else { continue };
            let module = sdfc::driver::compile(&a, &Default::default())
                .unwrap()
                .module;
            let points: Vec<(DVec3, DVec3, f64)> = cases.iter().map(|c| (c.p, n, 0.0)).collect();
            let got = sdfc::gpu::eval_materials(gpu, &module, cpu.textures(), &points).unwrap();
            let mut worst = 0.0f64;
            for ((c, w), g) in cases.iter().zip(&want).zip(&got) {
                for (k, wv) in w.iter().enumerate() {
                    let e = (g.color[k] as f64 - wv).abs() / wv.abs().max(1.0);
                    worst = worst.max(e);
                    if e > dom.tol {
                        failures.push(format!(
                            "{} at {}: GPU {} against {wv} (relative {e:.1e}, tolerance {:.0e})",
                            c.field, c.p, g.color[k], dom.tol
                        ));
                    }
                }
            }
            report.push(format!("{:<28} {worst:.1e}", cases[0].field));
        }
    }
    eprintln!(
        "worst GPU error, relative, per builtin form:\n{}",
        report.join("\n")
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn folder_interpreter_and_gpu_agree_on_the_operators() {
    // `%` (floored, as WGSL's expression the emitter writes) and `==`/`!=` of vectors
    // (every component equal; any differing), where the folder and the generated code
    // once differed.
    let gpu = sdfc::gpu::gpu_for_tests();
    for (constant, field, p, want) in [
        (
            "-7.5 % 2.0",
            "position.x % position.y",
            [-7.5, 2.0, 0.0],
            0.5,
        ),
        (
            "7.5 % -2.0",
            "position.x % position.y",
            [7.5, -2.0, 0.0],
            -0.5,
        ),
        (
            "-7.5 % -2.0",
            "position.x % position.y",
            [-7.5, -2.0, 0.0],
            -1.5,
        ),
    ] {
        assert_eq!(folded(constant), vec![want], "{constant}");
        check_field(gpu.as_ref(), field, DVec3::from_array(p), want);
    }
    // Vector comparisons fold as `sema::math` defines them (and the emitter writes
    // them, `all(a == b)` and `any(a != b)`): `==` when every component is equal, `!=`
    // when any differs. Booleans cannot reach a material's numbers, so no GPU value.
    for (op, want) in [("==", false), ("!=", true)] {
        let constant = format!("[1.0, 2.0, 3.0] {op} [1.0, 5.0, 3.0]");
        let src = format!("let k = {constant};\nrender sphere(1);\n");
        let a = sdfc::driver::check(&src, None);
        let def = a.program.defs.iter().find(|d| d.name == "k").unwrap();
        assert_eq!(def.value, Value::Bool(want), "{constant}");
    }
}

/// The material `color = FIELD` at `p`: the interpreter gives `want`, and so does the GPU.
fn check_field(gpu: Option<&sdfc::gpu::Gpu>, field: &str, p: DVec3, want: f64) {
    let src = format!("material m {{ color = {field}; }}\nrender sphere(1).paint(m);\n");
    let a = sdfc::driver::check(&src, None);
    assert!(!a.has_errors(), "{src}: {:?}", a.diagnostics);
    let cpu = sdfc::reference::material::MaterialEval::load(&a.program, &a.atlases).unwrap();
    assert_eq!(
        cpu.eval(1, p, DVec3::Z, 0.0).color.x,
        want,
        "{field} at {p}"
    );
    let Some(gpu) = gpu else { return };
    let module = sdfc::driver::compile(&a, &Default::default())
        .unwrap()
        .module;
    let got =
        sdfc::gpu::eval_materials(gpu, &module, cpu.textures(), &[(p, DVec3::Z, 0.0)]).unwrap();
    assert!(
        (got[0].color[0] as f64 - want).abs() < 1e-6,
        "{field} at {p}: GPU {} against {want}",
        got[0].color[0]
    );
}

#[test]
fn cpu_and_gpu_agree_on_every_primitive_and_its_bounds_hold() {
    let gpu = sdfc::gpu::gpu_for_tests();
    let mut rng = Rng(37);
    for b in BUILTINS.iter().filter(|b| b.kind == Kind::Primitive) {
        let name = b.name;
        let src = format!("render {name}();\n");
        let a = sdfc::driver::check(&src, None);
        assert!(!a.has_errors(), "{src}: {:?}", a.diagnostics);
        let shape = a.scene.as_ref().unwrap().render.clone().unwrap();
        let node = shape.root_node();
        let framing = shape.framing_bounds();
        let size = (framing.max - framing.min).max_element();
        let (lo, hi) = (
            framing.min - DVec3::splat(0.25 * size),
            framing.max + DVec3::splat(0.25 * size),
        );
        let points: Vec<DVec3> = (0..400)
            .map(|_| {
                DVec3::new(
                    rng.range(lo.x, hi.x),
                    rng.range(lo.y, hi.y),
                    rng.range(lo.z, hi.z),
                )
            })
            .collect();
        let cpu: Vec<f64> = points
            .iter()
            .map(|&p| sdfc::ir::eval::distance(&shape, p))
            .collect();
        // The bounds hold every point inside; the Lipschitz bound every pair's slope.
        for (p, d) in points.iter().zip(&cpu) {
            if *d < 0.0 {
                let inside = p.cmpge(node.bounds.min - DVec3::splat(1e-9)).all()
                    && p.cmple(node.bounds.max + DVec3::splat(1e-9)).all();
                assert!(
                    inside,
                    "{name}: {p} is inside (f = {d}) but outside its bounds {:?}",
                    node.bounds
                );
            }
        }
        for w in points.windows(2).zip(cpu.windows(2)) {
            let ((p, q), (a, b)) = ((w.0[0], w.0[1]), (w.1[0], w.1[1]));
            let slope = (a - b).abs() / (p - q).length();
            assert!(
                slope <= node.lipschitz * (1.0 + 1e-9),
                "{name}: slope {slope} between {p} and {q} over its Lipschitz bound {}",
                node.lipschitz
            );
        }
        let Some(gpu) = &gpu else { continue };
        let module = sdfc::driver::compile(&a, &Default::default())
            .unwrap()
            .module;
        let got = sdfc::gpu::eval_points(gpu, &module, &points).unwrap();
        for ((p, c), g) in points.iter().zip(&cpu).zip(&got) {
            let e = (g[0] as f64 - c).abs();
            assert!(
                e <= 1e-5 * size.max(1.0),
                "{name} at {p}: GPU {} against CPU {c}",
                g[0]
            );
        }
    }
}

#[test]
fn every_primitive_kind_matches_its_wgsl_function_and_builtin() {
    use sdfc::ir::prim::{Slot, KINDS};
    // The shader library's signatures: `fn NAME(p: vec3<f32>, a: f32, b: vec3<f32>, …)`.
    let library = std::fs::read_to_string("shaders/sdf.wgsl").unwrap();
    for (code, kind) in KINDS.iter().enumerate() {
        assert_eq!(kind.code as usize, code, "KINDS is in code order");
        let head = format!("fn {}(", kind.wgsl);
        let at = library
            .find(&head)
            .unwrap_or_else(|| panic!("shaders/sdf.wgsl has no `{}`", kind.wgsl));
        let params = &library[at + head.len()..];
        let params = &params[..params.find(')').unwrap()];
        let types: Vec<&str> = params
            .split(',')
            .skip(1)
            .map(|p| p.split(':').nth(1).unwrap().trim())
            .collect();
        let slots: Vec<&str> = kind
            .slots
            .iter()
            .map(|s| match s {
                Slot::Float => "f32",
                Slot::Vec3 => "vec3<f32>",
            })
            .collect();
        assert_eq!(
            types, slots,
            "{}: the WGSL parameters and the slots differ",
            kind.wgsl
        );
    }
    // Every primitive builtin lowers to the kind its WGSL function is named after, with
    // as many parameters as its slots hold.
    for b in BUILTINS.iter().filter(|b| b.kind == Kind::Primitive) {
        let a = sdfc::driver::check(&format!("render {}();", b.name), None);
        let shape = a.scene.as_ref().unwrap().render.clone().unwrap();
        // A cone is a capped cone moved up to stand on y = 0: its one primitive node.
        let p = shape
            .nodes
            .iter()
            .find_map(|n| match &n.op {
                sdfc::ir::Op::Prim(p) => Some(p),
                _ => None,
            })
            .unwrap_or_else(|| panic!("{} does not lower to a primitive", b.name));
        let words: usize = p
            .kind()
            .slots
            .iter()
            .map(|s| if *s == Slot::Vec3 { 3 } else { 1 })
            .sum();
        assert_eq!(p.params().len(), words, "{}", b.name);
        let wgsl = p.kind().wgsl.trim_start_matches("sd_");
        let name = if b.name == "cone" {
            "capped_cone"
        } else {
            b.name
        };
        assert_eq!(wgsl, name, "{} lowers to {}", b.name, p.kind().wgsl);
    }
}
