//! Per-node bounds (`ir::guard`): a union's operand skipped by its box leaves the field
//! (distance and materials) exactly as it was, on every example and on random scenes,
//! and only operands whose fields are bounded below by their boxes are guarded.

use glam::DVec3;
use sdfc::ir::{eval, guard, Shape};
use std::path::Path;

use crate::common;
use common::Rng;

use crate::gen;

/// Every shape of a scene: its named shapes and the render target.
fn shapes(src: &str, dir: &Path) -> Vec<(String, Shape)> {
    let a = sdfc::driver::check(src, Some(dir));
    let Some(scene) = a.scene.as_ref() else {
        return Vec::new();
    };
    let mut out: Vec<(String, Shape)> = scene
        .shapes
        .iter()
        .map(|n| (n.name.clone(), n.shape.clone()))
        .collect();
    if let Some(r) = &scene.render {
        out.push(("render".into(), r.clone()));
    }
    out
}

/// Compares the guarded and the unguarded field at points of the shape's framing box
/// (grown by half), half of them pulled near the surface; returns (points, points where
/// some guard skipped its operand).
fn check_shape(name: &str, shape: &Shape, rng: &mut Rng, n: usize) -> (usize, usize) {
    let b = shape.framing_bounds();
    let (lo, size) = (b.min - (b.max - b.min) * 0.25, (b.max - b.min) * 1.5);
    let guards: Vec<_> = (0..shape.nodes.len())
        .filter_map(|i| shape.guard(sdfc::ir::NodeId::new(i)).cloned())
        .collect();
    let mut skipped = 0;
    for i in 0..n {
        let mut p = lo + size * DVec3::new(rng.unit(), rng.unit(), rng.unit());
        if i % 2 == 0 {
            if let Some(q) = eval::project(shape, p, 1e-9) {
                p = q + eval::gradient(shape, q).normalize_or_zero() * rng.range(-0.05, 0.05);
            }
        }
        let guarded = eval::eval_blend(shape, p);
        let full = eval::eval_unguarded(shape, p);
        let same = guarded.0.to_bits() == full.0.to_bits() && guarded.1 == full.1
            || guarded.0.is_nan() && full.0.is_nan();
        assert!(
            same,
            "{name}: at {p}, guarded {guarded:?} but every operand gives {full:?}"
        );
        // Whether some guard skips here, with its first operand's own distance.
        if guards.iter().any(|g| {
            let first = eval::node_distance(shape, g.first, p);
            !g.needed(p, first)
        }) {
            skipped += 1;
        }
    }
    (n, skipped)
}

#[test]
fn guarded_fields_equal_the_full_field_on_every_example() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut rng = Rng(0x5EED_0B0D);
    let (mut points, mut skipped, mut guarded_shapes) = (0, 0, 0);
    for file in common::scene_files()
        .into_iter()
        .filter(|f| f.starts_with(root.join("examples")))
    {
        let src = std::fs::read_to_string(&file).unwrap();
        for (name, shape) in shapes(&src, file.parent().unwrap()) {
            let n = shape.nodes.len();
            if (0..n).any(|i| shape.guard(sdfc::ir::NodeId::new(i)).is_some()) {
                guarded_shapes += 1;
            }
            let (p, s) = check_shape(
                &format!("{}: {name}", file.display()),
                &shape,
                &mut rng,
                300,
            );
            points += p;
            skipped += s;
        }
    }
    eprintln!("{points} points on {guarded_shapes} guarded shapes; a guard skipped at {skipped}");
    // The comparison ran where guards skip, not only where they evaluate everything.
    assert!(guarded_shapes >= 5, "{guarded_shapes}");
    assert!(skipped * 10 >= points, "{skipped} of {points}");
}

#[test]
fn guarded_fields_equal_the_full_field_on_random_scenes() {
    // Where the generator's texture paths resolve (as in tests/random_scenes.rs).
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("ui");
    let mut rng = Rng(0xB0_1D5);
    let (mut points, mut skipped, mut validated) = (0, 0, 0);
    for seed in 0..400u64 {
        let scene = gen::scene(seed);
        if scene.mutation.is_some() {
            continue;
        }
        for (name, shape) in shapes(&scene.text, &dir) {
            let (p, s) = check_shape(&format!("seed {seed}: {name}"), &shape, &mut rng, 40);
            points += p;
            skipped += s;
        }
        // Every operand bounded: the generated code validates (the same scene as
        // written, a naga rejection is a compiler bug).
        let a = sdfc::driver::check(&scene.text, Some(&dir));
        if a.has_errors() {
            continue;
        }
        let options = sdfc::codegen::Options {
            bounds: sdfc::codegen::Bounds::All,
            walk: sdfc::codegen::WalkForm::Loop,
            ..Default::default()
        };
        if let Ok(m) = sdfc::driver::generate(&a, &options) {
            sdfc::codegen::validate(&m.wgsl)
                .unwrap_or_else(|e| panic!("seed {seed}: --bounds all: {e}\n{}", scene.text));
            validated += 1;
        }
    }
    eprintln!("random scenes: {points} points, a guard skipped at {skipped}; {validated} modules validated with every operand bounded");
    assert!(skipped > 100, "{skipped} of {points}");
    assert!(validated >= 80, "{validated}");
}

fn render_shape(src: &str) -> Shape {
    let a = sdfc::driver::check(src, None);
    assert!(!a.has_errors(), "{:#?}", a.diagnostics);
    a.scene.unwrap().render.unwrap()
}

#[test]
fn only_fields_bounded_below_by_their_boxes_are_guarded() {
    // A ground plane (no box) and a blend on it: the blend is guarded, with its box.
    let s = render_shape(
        "render plane([0, 1, 0], -1) | smooth_union(box(1), torus(0.6, 0.1), 0.1).translate([2, 0, 0]);",
    );
    let g = s.guard(s.root()).expect("the union is guarded");
    assert_eq!(g.center, DVec3::new(2.0, 0.0, 0.0));
    assert!(
        // The torus's extent (the box is smaller) and k / 4 on every side.
        (g.half - DVec3::new(0.725, 0.525, 0.725))
            .abs()
            .max_element()
            < 1e-12,
        "{}",
        g.half
    );
    // A hard union: the margin for single precision only.
    assert!(g.slack > 0.0 && g.slack < 1e-3, "{}", g.slack);
    assert_eq!(g.cost, guard::costs(&s)[g.guarded.index()]);
    // Two operands with boxes: the smaller box is guarded (a chain of unions tests each
    // new operand against the running union).
    let s = render_shape(
        "render sphere(0.3).translate([-2, 0, 0]) | sphere(0.5) | sphere(0.2).translate([2, 0, 0]);",
    );
    let g = s.guard(s.root()).unwrap();
    assert_eq!(g.center, DVec3::new(2.0, 0.0, 0.0));
    let inner = s.guard(g.first).unwrap();
    assert_eq!(inner.center, DVec3::new(-2.0, 0.0, 0.0));
    // Fields that can fall below the distance to their boxes: no guard.
    for operand in [
        "sphere(0.5).scale([1, 0.3, 1])",
        "ellipsoid([0.5, 0.2, 0.3])",
        "tri_prism(0.5, 0.3)",
        "sphere(0.2).repeat([1, 1, 1])",
        "plane([0, 1, 0], 0)",
        // A warp of an unbounded shape: its box is a framing guess, not a bound.
        "plane([0, 1, 0], 0).twist(rate: 0.1)",
    ] {
        let s = render_shape(&format!(
            "render sphere(0.1) | {operand}.translate([3, 0, 0]);"
        ));
        let sdfc::ir::Op::Csg { b, .. } = s.root_node().op else {
            panic!("{operand}: not a union")
        };
        // The sphere may be guarded (evaluated after the other), never the other.
        let g = s.guard(s.root()).expect("the sphere is guarded");
        assert!(g.guarded != b && g.first == b, "{operand} is guarded");
    }
    // The twisted plane again, far from the origin, where the guess is farthest off.
    let s = render_shape(
        "render sphere(30).translate([0, -100, 0]) | plane([0, 1, 0], 0).twist(rate: 0.1);",
    );
    let p = DVec3::new(0.0, -60.0, 0.0);
    assert_eq!(eval::eval_blend(&s, p), eval::eval_unguarded(&s, p));
    assert!(eval::distance(&s, p) < -59.0);
    // An intersection is bounded below where an exact operand's box is the result's.
    let s = render_shape(
        "render plane([0, 1, 0], -3) | (sphere(0.2).repeat([1, 1, 1]) & box([3, 0.5, 3])).translate([5, 0, 0]);",
    );
    let sdfc::ir::Op::Csg { b, .. } = s.root_node().op else {
        panic!("not a union")
    };
    assert_eq!(s.guard(s.root()).map(|g| g.guarded), Some(b));
}

/// Every example with every operand bounded (`--bounds all`, with and without the
/// walks' pruning, whose whole fields carry guards too) generates WGSL naga accepts, and
/// the guards are there; the default emits none.
#[test]
fn every_example_validates_with_node_bounds() {
    use sdfc::codegen::{self, Bounds};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut with_guards = 0;
    for file in common::scene_files()
        .into_iter()
        .filter(|f| f.starts_with(root.join("examples")))
    {
        let src = std::fs::read_to_string(&file).unwrap();
        let a = sdfc::driver::check(&src, file.parent());
        assert!(!a.has_errors(), "{}", file.display());
        let guard_line = "if (sd_box(p - ";
        let default = sdfc::driver::generate(&a, &codegen::Options::default()).unwrap();
        assert!(!default.wgsl.contains(guard_line), "{}", file.display());
        for prune in [false, true] {
            let options = codegen::Options {
                bounds: Bounds::All,
                walk: codegen::WalkForm::Loop,
                prune,
                ..Default::default()
            };
            let m = sdfc::driver::generate(&a, &options)
                .unwrap_or_else(|e| panic!("{}: {e:?}", file.display()));
            codegen::validate(&m.wgsl).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            if !prune && m.wgsl.contains(guard_line) {
                with_guards += 1;
            }
        }
    }
    assert!(with_guards >= 8, "{with_guards}");
}

/// `sdfc compile --bounds` reaches the code generator: `costly` guards csg.sdf's column
/// and gilded parts, `off` (the default) guards nothing.
#[test]
fn compile_command_takes_the_bounds_choice() {
    let dir = tempfile::tempdir().unwrap();
    let guard_line = "if (sd_box(p - ";
    for (bounds, want) in [(None, false), (Some("off"), false), (Some("costly"), true)] {
        let out = dir.path().join("csg.wgsl");
        let out_s = out.to_str().unwrap();
        let mut args = vec![
            "compile",
            "examples/csg.sdf",
            "--target",
            "wgsl",
            "-o",
            out_s,
        ];
        if let Some(b) = bounds {
            args.extend(["--bounds", b]);
        }
        let (code, _, stderr) = common::sdfc(&args);
        assert_eq!(code, 0, "{bounds:?}: {stderr}");
        let wgsl = std::fs::read_to_string(&out).unwrap();
        assert_eq!(wgsl.contains(guard_line), want, "{bounds:?}");
    }
    let (code, _, stderr) = common::sdfc(&["compile", "examples/csg.sdf", "--bounds", "some"]);
    assert_eq!(code, 2, "{stderr}");
}

/// A shared node reached from several guards' helper functions is still one function:
/// a chain of `let`s each used twice stays linear in the WGSL, not exponential.
#[test]
fn guards_keep_shared_nodes_one_function_each() {
    use sdfc::codegen::{self, Bounds};
    let functions = |depth: usize, bounds: Bounds| {
        let mut src = String::from("let s0 = sphere(0.2);\n");
        for i in 1..=depth {
            src += &format!(
                "let s{i} = smooth_union(s{0}, s{0}.translate([{1}, 0, 0]), 0.05);\n",
                i - 1,
                0.5 * (1u64 << i) as f64
            );
        }
        src += &format!("render s{depth};\n");
        let a = sdfc::driver::check(&src, None);
        assert!(!a.has_errors(), "{:?}", a.diagnostics);
        let options = codegen::Options {
            bounds,
            walk: codegen::WalkForm::Loop,
            ..Default::default()
        };
        let m = sdfc::driver::generate(&a, &options).unwrap();
        codegen::validate(&m.wgsl).unwrap();
        assert_eq!(m.wgsl.contains("if (sd_box(p - "), bounds == Bounds::All);
        m.wgsl.matches("\nfn ").count()
    };
    // Every level adds one guard helper per function that reaches it (scene_map and each
    // named shape's map_): the same growth as without guards, not 2^depth.
    for depth in [6, 12] {
        let (off, all) = (functions(depth, Bounds::Off), functions(depth, Bounds::All));
        eprintln!("depth {depth}: {off} functions without guards, {all} with");
        assert!(
            all <= 2 * off,
            "depth {depth}: {off} functions without guards, {all} with"
        );
    }
}
