//! Completion and signature help, with the cursor marked `$0`.

use super::at;
use sdfc::ide::complete::{completions, signature_help, CompletionKind};
use sdfc::sema::builtins::{PTy, BUILTINS};

const PRELUDE: &str = "let radius = 0.5;
let ball = sphere(radius);
atlas skin on ball {
    seed front = [0, 0, 1];
    seed top = [0, 1, 0];
}
";

fn labels(marked: &str) -> Vec<String> {
    let (doc, offset) = at(&format!("{PRELUDE}{marked}"));
    completions(&doc, offset)
        .into_iter()
        .map(|c| c.label)
        .collect()
}

#[test]
fn atlas_fields_after_a_dot() {
    assert_eq!(
        labels("material m { color = skin.$0 }"),
        ["uv", "distance", "status", "transport", "seed"]
    );
    assert_eq!(
        labels("material m { color = [skin.u$0, 0]; }"),
        ["uv", "distance", "status", "transport", "seed"]
    );
}

/// The builtins offered after the `.`, by name.
fn methods(marked: &str) -> Vec<String> {
    let (doc, offset) = at(&format!("{PRELUDE}{marked}"));
    completions(&doc, offset)
        .into_iter()
        .filter(|c| c.kind == CompletionKind::Function)
        .map(|c| c.label)
        .collect()
}

#[test]
fn members_follow_the_receivers_type() {
    // A shape: exactly the builtins that take a shape first, none of the others.
    let shape = methods("let b = ball.$0");
    let takes_a_shape: Vec<&str> = BUILTINS
        .iter()
        .filter(|b| b.params.first().is_some_and(|p| p.ty == PTy::Shape))
        .map(|b| b.name)
        .collect();
    assert_eq!(shape, takes_a_shape);
    for unrelated in ["sphere", "orbit", "sin", "sample", "image"] {
        assert!(!shape.iter().any(|m| m == unrelated), "{unrelated}");
    }
    assert!(labels("let b = ball.$0")
        .iter()
        .all(|l| BUILTINS.iter().any(|b| b.name == l)));
    // The receiver may be any expression, typed by the checker, and half-typed text
    // after the cursor does not matter.
    assert_eq!(methods("let b = sphere(1).translate([0, 1, 0]).$0"), shape);
    assert_eq!(methods("let b = (ball | ball).rot$0 nonsense ]"), shape);
    // A texture: `sample` and `sample_normal`.
    assert_eq!(
        labels("let t = image(\"a.png\");\nmaterial m { color = t.$0 }"),
        ["sample", "sample_normal"]
    );
    // A vector: its swizzles and the math on it.
    let v = labels("let v = [1, 2, 3];\nlet w = v.$0");
    for l in [
        "x",
        "y",
        "z",
        "xy",
        "xyz",
        "rgb",
        "length",
        "normalize",
        "cross",
        "sin",
    ] {
        assert!(v.iter().any(|m| m == l), "no {l} in {v:?}");
    }
    for l in ["w", "a", "translate", "sphere", "checker"] {
        assert!(!v.iter().any(|m| m == l), "{l} in {v:?}");
    }
    // A surface field: swizzles, and only the builtins that take fields.
    let uv = labels("material m { color = skin.uv.$0 }");
    for l in ["x", "y", "xy", "checker", "grid", "sin"] {
        assert!(uv.iter().any(|m| m == l), "no {l} in {uv:?}");
    }
    for l in ["z", "cross", "translate"] {
        assert!(!uv.iter().any(|m| m == l), "{l} in {uv:?}");
    }
    // A number: math; a material or an unknown name: nothing.
    let f = methods("let f = radius.$0");
    assert!(f.contains(&String::from("sqrt")) && !f.contains(&String::from("sphere")));
    assert!(labels("material m { color = [1, 0, 0]; }\nlet x = m.$0").is_empty());
    assert!(labels("let x = nothing.$0").is_empty());
}

#[test]
fn keywords_and_settings_by_block() {
    assert_eq!(labels("$0"), ["let", "atlas", "material", "render"]);
    assert_eq!(
        labels("let a = 1;\n$0"),
        ["let", "atlas", "material", "render"]
    );
    assert_eq!(
        labels("material m {\n    roughness = 0.5;\n    $0\n}"),
        ["color", "roughness", "metallic", "emission", "normal"]
    );
    assert_eq!(
        labels("render ball { $0 }"),
        ["camera", "size", "light", "background", "ambient"]
    );
    let atlas = labels("atlas a on ball {\n    $0\n}");
    assert_eq!(&atlas[..2], ["seed", "merge"]);
    assert!(
        atlas.contains(&String::from("steps")) && atlas.contains(&String::from("sharp_tolerance")),
        "{atlas:?}"
    );
    let (doc, offset) = at(&format!("{PRELUDE}material m {{ r$0 }}"));
    let c = completions(&doc, offset)
        .into_iter()
        .find(|c| c.label == "roughness")
        .unwrap();
    assert_eq!(c.kind, CompletionKind::Setting);
    assert_eq!(c.insert_text.as_deref(), Some("roughness = "));
    // Nothing where a name is being defined.
    assert!(labels("let $0").is_empty());
    assert!(labels("atlas a on ball { seed $0 }").is_empty());
    assert_eq!(labels("atlas a $0"), ["on"]);
    // Nor in comments and strings.
    assert!(labels("// sph$0").is_empty());
    assert!(labels("/* sph$0 */").is_empty());
    assert!(labels("/* unclosed $0").is_empty());
    // Comments elsewhere do not matter.
    assert_eq!(
        labels("// a comment\n/* another */ $0"),
        ["let", "atlas", "material", "render"]
    );
    assert!(labels("let t = image(\"tex$0\");").is_empty());
}

#[test]
fn seeds_after_merge() {
    let marked = "atlas skin2 on ball { seed a = [0, 0, 1]; seed b = [1, 0, 0]; merge a $0 }";
    assert_eq!(labels(marked), ["a", "b"]);
}

#[test]
fn names_builtins_and_named_arguments_in_expressions() {
    let all = labels("let c = capsule(a: [0, 0, 0], $0);\nlet later = 1;");
    // Named arguments not given yet come first.
    assert_eq!(&all[..2], ["b:", "radius:"]);
    for name in [
        "radius",
        "ball",
        "skin",
        "pi",
        "position",
        "sphere",
        "smooth_union",
        "true",
    ] {
        assert!(all.iter().any(|l| l == name), "no {name} in {all:?}");
    }
    // A name is visible after its definition only.
    assert!(!all.iter().any(|l| l == "c" || l == "later"), "{all:?}");
    // Positional arguments use up parameters; a method's receiver is the first.
    assert_eq!(&labels("let t = torus(1, $0")[..1], ["minor:"]);
    assert_eq!(&labels("let t = ball.translate($0")[..1], ["offset:"]);
    assert_eq!(
        labels("let t = ball.translate(offset: [0, 0, 0], $0")
            .iter()
            .filter(|l| l.ends_with(':'))
            .count(),
        0
    );
    // Inside a vector, no named arguments.
    assert!(!labels("let t = torus([$0").iter().any(|l| l.ends_with(':')));
    let (doc, offset) = at(&format!("{PRELUDE}let s = sph$0"));
    let c = completions(&doc, offset)
        .into_iter()
        .find(|c| c.label == "sphere")
        .unwrap();
    assert_eq!(c.kind, CompletionKind::Function);
    assert_eq!(
        c.detail.as_deref(),
        Some("sphere(radius: float = 1) -> shape")
    );
}

/// The signature with the active parameter in brackets.
fn signature(marked: &str) -> String {
    let (doc, offset) = at(&format!("{PRELUDE}{marked}"));
    let Some(h) = signature_help(&doc, offset) else {
        return String::from("none");
    };
    let mut label = h.label.clone();
    if let Some(i) = h.active_parameter {
        let (s, e) = h.parameters[i];
        label = format!("{}[{}]{}", &label[..s], &label[s..e], &label[e..]);
    }
    label
}

#[test]
fn signature_help_tracks_the_active_parameter() {
    assert_eq!(
        signature("let t = torus($0"),
        "torus([major: float = 1], minor: float = 0.25) -> shape"
    );
    assert_eq!(
        signature("let t = torus(1, $0)"),
        "torus(major: float = 1, [minor: float = 0.25]) -> shape"
    );
    assert_eq!(
        signature("let t = torus(minor: 0.1, major: $0)"),
        "torus([major: float = 1], minor: float = 0.25) -> shape"
    );
    // A method's receiver is the first parameter; commas inside vectors do not count.
    assert_eq!(
        signature("let t = ball.translate([1, 2$0, 3])"),
        "translate(shape: shape, [offset: vec3]) -> shape"
    );
    // The innermost call wins, and a closed call is left.
    assert_eq!(
        signature("let t = torus(sin($0"),
        "sin([x: float or vector]) -> T"
    );
    assert_eq!(
        signature("let t = torus(sin(1), $0"),
        "torus(major: float = 1, [minor: float = 0.25]) -> shape"
    );
    // After named arguments: the first parameter not given yet.
    assert_eq!(
        signature("let t = torus(minor: 1, $0"),
        "torus([major: float = 1], minor: float = 0.25) -> shape"
    );
    assert_eq!(
        signature("let c = cylinder(radius: 0.2, $0"),
        "cylinder(radius: float = 0.5, [height: float = 1]) -> shape"
    );
    assert_eq!(
        signature("let c = capsule(a: [0, 0, 0], $0"),
        "capsule(a: vec3 = [0, -0.5, 0], [b: vec3 = [0, 0.5, 0]], radius: float = 0.25) -> shape"
    );
    assert_eq!(
        signature("let c = capsule([0, 0, 0], radius: 1, $0"),
        "capsule(a: vec3 = [0, -0.5, 0], [b: vec3 = [0, 0.5, 0]], radius: float = 0.25) -> shape"
    );
    assert_eq!(
        signature("let t = ball.translate(offset: [0, 0, 0], $0"),
        "translate(shape: shape, offset: vec3) -> shape"
    );
    // A named argument being typed is its parameter.
    assert_eq!(
        signature("let c = capsule(a: [0, 0, 0], radius: $0"),
        "capsule(a: vec3 = [0, -0.5, 0], b: vec3 = [0, 0.5, 0], [radius: float = 0.25]) -> shape"
    );
    // No parameter left, or outside a call: no active parameter, or no help.
    assert_eq!(
        signature("let t = torus(1, 2, 3, $0"),
        "torus(major: float = 1, minor: float = 0.25) -> shape"
    );
    assert_eq!(signature("let t = torus(1);$0"), "none");
    assert_eq!(signature("let t = nope($0"), "none");
}

#[test]
fn signature_labels_match_the_builtins_table() {
    for b in BUILTINS {
        let (doc, offset) = at(&format!("let x = {}($0);", b.name));
        let h = signature_help(&doc, offset).unwrap();
        assert_eq!(h.label, b.signature());
        assert_eq!(h.parameters.len(), b.params.len());
        for ((s, e), p) in h.parameters.iter().zip(b.params) {
            assert!(
                h.label[*s..*e].starts_with(&format!("{}: ", p.name)),
                "{}",
                h.label
            );
        }
    }
}
