//! The protocol-free editor queries, with the cursor marked `$0` in each case.

use sdfc::ide::{self, Document, SymbolKind};

#[path = "ide/actions.rs"]
mod actions;
#[path = "ide/complete.rs"]
mod complete;
#[path = "ide/format.rs"]
mod format;
#[path = "ide/rename.rs"]
mod rename;
#[path = "ide/semantic.rs"]
mod semantic;

const SCENE: &str = "let radius = 0.5;
let ball = sphere(radius).translate([0, 1, 0]);
atlas skin on ball {
    steps = 12;
    seed front = [0, 1, 0.5] tangent [1, 0, 0];
    seed top = [0, 1.5, 0];
    merge front top;
}
material m { color = [skin.uv, 0]; roughness = 0.3 * pi; }
render ball.paint(m);
";

/// The document and the offset of `$0`, which is removed.
fn at(marked: &str) -> (Document, usize) {
    let offset = marked.find("$0").expect("a $0 cursor");
    let text = marked.replacen("$0", "", 1);
    (Document::new(text, None), offset)
}

/// The scene with `$0` inserted before the n-th occurrence of `needle`.
fn cursor(needle: &str, n: usize) -> String {
    let start = SCENE
        .match_indices(needle)
        .nth(n)
        .unwrap_or_else(|| panic!("{needle} #{n}"))
        .0;
    format!("{}$0{}", &SCENE[..start], &SCENE[start..])
}

fn hover_snapshot(needle: &str, n: usize) -> String {
    let marked = cursor(needle, n);
    let (doc, offset) = at(&marked);
    let h = ide::hover(&doc, offset + 1).unwrap_or_else(|| panic!("no hover at {needle}"));
    let line = marked.lines().find(|l| l.contains("$0")).unwrap();
    format!("{line}\n{}\n--\n{}", &doc.text[h.span.range()], h.markdown)
}

#[test]
fn hovers() {
    let cases = [
        ("radius", 1, "let_constant"),
        ("sphere", 0, "builtin_function"),
        ("translate", 0, "builtin_method"),
        ("skin", 1, "atlas"),
        ("front", 1, "seed"),
        ("uv", 0, "atlas_field"),
        ("pi", 0, "constant"),
        ("ball", 2, "let_shape"),
    ];
    for (needle, n, name) in cases {
        insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false, omit_expression => true }, {
            insta::assert_snapshot!(format!("hover_{name}"), hover_snapshot(needle, n));
        });
    }
    // Nothing to say about punctuation or numbers.
    let (doc, offset) = at(&SCENE.replacen("0.5;", "0$0.5;", 1));
    assert_eq!(ide::hover(&doc, offset), None);
}

/// Hover documents the normal map and the material's `normal` from the tables.
#[test]
fn hover_on_normal_maps() {
    let text = "let ball = sphere(1);\natlas skin on ball { seed front = [0, 0, 1]; }\nlet t = image(\"n.png\");\nmaterial m { normal = t.sample_normal(skin.uv, convention: \"dx\"); }\nrender ball.paint(m);\n";
    let doc = Document::new(text.to_string(), None);
    let at = |needle: &str| text.find(needle).unwrap() + 1;
    let h = ide::hover(&doc, at("sample_normal")).expect("hover on sample_normal");
    assert_eq!(&doc.text[h.span.range()], "sample_normal");
    for part in [
        "sample_normal(texture: texture, uv: vec2, strength: float = 1, convention: string = \"gl\", wrap: string = \"repeat\") -> vec3",
        "parallel transport (Eq. 52)",
        "\"dx\" (DirectX)",
    ] {
        assert!(h.markdown.contains(part), "{part} not in {}", h.markdown);
    }
    let h = ide::hover(&doc, at("normal =")).expect("hover on the normal setting");
    assert_eq!(&doc.text[h.span.range()], "normal");
    assert!(
        h.markdown.starts_with("```sdf\nnormal: vec3\n```"),
        "{}",
        h.markdown
    );
    assert!(h.markdown.contains("shading normal"), "{}", h.markdown);
    // Every block's settings have hover; the value after `=` is not the setting.
    let h = ide::hover(&doc, at("front")).unwrap();
    assert!(!h.markdown.contains("setting"), "{}", h.markdown);
    let scene = "atlas a on sphere(1) { steps = 8; seed s = [0, 0, 1]; }\nrender sphere(1) { size = [64, 64]; }\n";
    let doc = Document::new(scene.to_string(), None);
    for (needle, expect) in [
        ("steps", "steps: float = 20"),
        ("size", "size: vec2 = [960, 540]"),
    ] {
        let h = ide::hover(&doc, scene.find(needle).unwrap() + 1).unwrap();
        assert!(h.markdown.contains(expect), "{needle}: {}", h.markdown);
    }
}

#[test]
fn definition_and_references() {
    let (doc, offset) = at(&cursor("ball", 2));
    let def = ide::definition(&doc, offset + 1).unwrap();
    assert_eq!(&doc.text[def.range()], "ball");
    assert_eq!(def.start, SCENE.find("ball").unwrap());
    let refs = ide::references(&doc, offset + 1, true);
    assert_eq!(refs.len(), 3, "{refs:?}");
    assert!(refs.iter().all(|r| &doc.text[r.range()] == "ball"));
    assert_eq!(ide::references(&doc, offset + 1, false).len(), 2);
    // Seeds resolve through merges.
    let (doc, offset) = at(&cursor("top", 1));
    let def = ide::definition(&doc, offset + 1).unwrap();
    assert_eq!(def.start, SCENE.find("top =").unwrap());
}

#[test]
fn outline() {
    let doc = Document::new(SCENE, None);
    let symbols = ide::symbols(&doc);
    let top: Vec<(&str, SymbolKind)> = symbols.iter().map(|s| (s.name.as_str(), s.kind)).collect();
    assert_eq!(
        top,
        vec![
            ("radius", SymbolKind::Let),
            ("ball", SymbolKind::Let),
            ("skin", SymbolKind::Atlas),
            ("m", SymbolKind::Material),
            ("render", SymbolKind::Render)
        ]
    );
    let children: Vec<(&str, SymbolKind)> = symbols[2]
        .children
        .iter()
        .map(|s| (s.name.as_str(), s.kind))
        .collect();
    assert_eq!(
        children,
        vec![
            ("front", SymbolKind::Seed),
            ("top", SymbolKind::Seed),
            ("front – top", SymbolKind::Merge)
        ]
    );
}

#[test]
fn the_walker_visits_every_node_in_source_order() {
    use sdfc::ide::walk::{self, Visitor};
    use sdfc::syntax::ast::{Arg, AtlasStmt, Expr, ExprKind, Setting};
    #[derive(Default)]
    struct Trace(Vec<String>);
    impl<'a> Visitor<'a> for Trace {
        fn expr(&mut self, e: &'a Expr) {
            match &e.kind {
                ExprKind::Name(n) => self.0.push(n.clone()),
                ExprKind::Call { callee, .. } => self.0.push(format!("{}(", callee.name)),
                ExprKind::Method { method, .. } => self.0.push(format!(".{}(", method.name)),
                ExprKind::Field { field, .. } => self.0.push(format!(".{}", field.name)),
                _ => {}
            }
            walk::walk_expr(self, e);
        }
        fn arg(&mut self, a: &'a Arg) {
            if let Some(n) = &a.name {
                self.0.push(format!("{}:", n.name));
            }
            walk::walk_arg(self, a);
        }
        fn setting(&mut self, s: &'a Setting) {
            self.0.push(format!("{} =", s.name.name));
            walk::walk_setting(self, s);
        }
        fn atlas_stmt(&mut self, s: &'a AtlasStmt) {
            if let AtlasStmt::Seed { name, .. } = s {
                self.0.push(format!("seed {}", name.name));
            }
            walk::walk_atlas_stmt(self, s);
        }
    }
    let doc = Document::new(SCENE, None);
    let mut trace = Trace::default();
    walk::walk_file(&mut trace, &doc.analysis.parsed.file);
    // Each node before its children, and children in source order (a method's
    // receiver before its arguments).
    assert_eq!(
        trace.0.join(" "),
        ".translate( sphere( radius ball steps = seed front seed top color = .uv skin \
         roughness = pi .paint( ball m"
    );
}
