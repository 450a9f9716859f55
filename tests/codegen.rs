//! Code generation: the WGSL library, every example at every target, snapshots of
//! the generated scene code, the manifest, and `sdfc compile`.

use sdfc::codegen::{self, targets::Output, Target};
use sdfc::codes;
use sdfc::driver::{self, CompileError};
use std::path::Path;

fn generate_with(
    src: &str,
    dir: Option<&Path>,
    options: &codegen::Options,
) -> Result<codegen::Module, Vec<sdfc::Diagnostic>> {
    let a = driver::check(src, dir);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    match driver::generate(&a, options) {
        Ok(m) => Ok(m),
        Err(CompileError::Scene(d)) => Err(d),
        Err(e) => panic!("{e:?}"),
    }
}

fn generate(src: &str, dir: Option<&Path>) -> Result<codegen::Module, Vec<sdfc::Diagnostic>> {
    generate_with(src, dir, &codegen::Options::default())
}

#[test]
fn library_files_validate_on_their_own() {
    for (name, text) in [
        ("sdf.wgsl", codegen::SDF_LIBRARY),
        ("render.wgsl", codegen::RENDER_LIBRARY),
        ("dual.wgsl", codegen::DUAL_LIBRARY),
        ("blit.wgsl", sdfc::viewer::present::BLIT),
    ] {
        if let Err(e) = codegen::validate(text) {
            panic!("shaders/{name} does not validate:\n{e}");
        }
    }
}

/// The module validates; it carries no library function that nothing reaches (the
/// library is shaken on its text, codegen::shake, so naga's compaction finds none); the
/// compacted module keeps every entry point and `sdf_NAME` and translates to every
/// target.
fn every_target(name: &str, module: &codegen::Module) {
    let full = codegen::validate(&module.wgsl)
        .unwrap_or_else(|e| panic!("{name}: naga rejects the generated WGSL:\n{e}"));
    // With the entry point the runtime appends where AOVs are rgba32uint (GL).
    codegen::validate(&codegen::aov::with_scene_bits(&module.wgsl))
        .unwrap_or_else(|e| panic!("{name}: naga rejects the module with fs_aov_bits:\n{e}"));
    let v = codegen::compact(&full).unwrap_or_else(|e| panic!("{name}: compaction: {e}"));
    // The library's functions, as naga names them before and after compaction.
    let library = codegen::shake::full_library();
    let names = |m: &naga::Module| -> Vec<String> {
        m.functions
            .iter()
            .filter_map(|(_, f)| f.name.clone())
            .filter(|n| library.contains(&format!("\nfn {n}(")))
            .collect()
    };
    assert_eq!(
        names(&v.module),
        names(&full.module),
        "{name}: the module carries library functions that nothing reaches"
    );
    let pass = module.coarse_slots > 0;
    assert_eq!(
        v.module.entry_points.len(),
        codegen::ENTRY_POINTS.len() + usize::from(pass)
    );
    for shape in &module.manifest.shapes {
        let f = format!("sdf_{shape}");
        assert!(
            v.module
                .functions
                .iter()
                .any(|(_, x)| x.name.as_deref() == Some(&f)),
            "{name}: compaction dropped {f}"
        );
    }
    for target in [Target::Wgsl, Target::Spirv, Target::Msl] {
        match codegen::translate(&v, &module.header, target, "") {
            Ok(Output::Text(t)) => assert!(!t.is_empty()),
            Ok(Output::Binary(b)) => {
                assert_eq!(&b[..4], &0x0723_0203u32.to_le_bytes(), "{name}: not SPIR-V")
            }
            Err(e) => panic!("{name}: {target:?}: {e}"),
        }
    }
    let coarse = pass.then_some("cs_coarse");
    for entry in ["vs_main", "fs_main", "cs_points", "cs_grid"]
        .into_iter()
        .chain(coarse)
    {
        if let Err(e) = codegen::translate(&v, &module.header, Target::Glsl, entry) {
            panic!("{name}: GLSL {entry}: {e}");
        }
    }
}

/// Every example compiles, validates and translates to all four targets, with the
/// multi-scale atlas pass too (its fragment stage reads a writable storage buffer:
/// MSL 1.2).
#[test]
fn every_example_compiles_at_every_target() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut compiled = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "sdf") {
            continue;
        }
        let src = std::fs::read_to_string(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let module = generate(&src, Some(&dir)).unwrap_or_else(|d| panic!("{name}: {d:?}"));
        every_target(&name, &module);
        let a = driver::check(&src, Some(&dir));
        let options = codegen::Options {
            multiscale: true,
            ..Default::default()
        };
        let module = driver::generate(&a, &options).unwrap_or_else(|d| panic!("{name}: {d:?}"));
        every_target(&format!("{name} with the multi-scale pass"), &module);
        compiled += 1;
    }
    assert!(compiled >= 5, "only {compiled} examples");
}

/// The scene part of a module (after the shared library), for snapshots.
fn scene_part(m: &codegen::Module) -> String {
    let start = m.wgsl.find("// ---- scene ----").unwrap();
    let end = m.wgsl.find("struct Material {").unwrap();
    m.wgsl[start..end].to_string()
}

#[test]
fn wgsl_snapshots() {
    let cases = [
        ("sphere", "render sphere(0.5);"),
        ("csg_materials", "material red { color = [1, 0, 0]; } material blue { color = [0, 0, 1]; roughness = 0.2; }\nlet a = sphere(1).paint(red);\nrender smooth_union(a, box([1, 2, 1]).translate([1, 0, 0]).paint(blue), 0.2) - cylinder(0.2, 4);"),
        ("warps", "let t = box([1, 2, 1]).twist(rate: 0.5);\nrender t.rotate(axis: [1, 1, 0], angle: 30deg).repeat([4, 4, 4]).scale([1, 2, 1]);"),
        ("fields", "material m { color = mix([1, 1, 1], 0.5 + 0.5 * normal, checker(position.xz, 4)); roughness = clamp(position.y, 0, 1); }\nrender sphere(1).paint(m);"),
    ];
    for (name, src) in cases {
        let m = generate(src, None).unwrap();
        every_target(name, &m);
        insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false, omit_expression => true, description => src }, {
            insta::assert_snapshot!(format!("wgsl_{name}"), scene_part(&m));
        });
    }
}

#[test]
fn manifest_describes_bindings_and_textures() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let m = generate(
        "let t = image(\"textures/bricks.png\");\nmaterial m { color = t.sample(position.xz, wrap: \"mirror\"); }\nrender sphere(1).paint(m);",
        Some(&dir),
    )
    .unwrap();
    every_target("textured", &m);
    assert_eq!(m.manifest.textures.len(), 1);
    assert_eq!(m.manifest.textures[0].path, "textures/bricks.png");
    assert_eq!(m.manifest.textures[0].wrap, "mirror");
    let kind = |b: &codegen::Binding| {
        serde_json::to_value(b.kind)
            .unwrap()
            .as_str()
            .unwrap()
            .to_string()
    };
    let kinds: Vec<(u32, u32, String)> = m
        .manifest
        .bindings
        .iter()
        .map(|b| (b.group, b.binding, kind(b)))
        .collect();
    assert_eq!(
        kinds,
        [
            (0, 0, "uniform"),
            (0, 1, "texture-2d"),
            (0, 2, "sampler"),
            (1, 0, "uniform"),
            (1, 1, "storage-read"),
            (1, 2, "storage-read-write"),
            (1, 3, "storage-read")
        ]
        .map(|(g, b, k)| (g, b, k.to_string()))
    );
    // The header comment documents the same bindings, and the WGSL declares exactly
    // them: both come from the one table.
    let v = codegen::validate(&m.wgsl).unwrap();
    let mut declared: Vec<(u32, u32, String)> = v
        .module
        .global_variables
        .iter()
        .filter_map(|(_, g)| {
            let b = g.binding.as_ref()?;
            Some((b.group, b.binding, g.name.clone().unwrap_or_default()))
        })
        .collect();
    // naga orders globals by first use; the table by slot.
    declared.sort();
    let table: Vec<(u32, u32, String)> = m
        .manifest
        .bindings
        .iter()
        .map(|b| (b.group, b.binding, b.name.clone()))
        .collect();
    assert_eq!(declared, table);
    for b in &m.manifest.bindings {
        assert!(
            m.header.contains(&format!(
                "@group({}) @binding({}) {} {}",
                b.group,
                b.binding,
                kind(b),
                b.name
            )),
            "header lacks {}",
            b.name
        );
    }
    assert_eq!(m.manifest.globals_layout.len(), 9);
}

/// The words after `const NAME: u32 = OFFSET` in the module's tables.
fn table_at(m: &codegen::Module, name: &str) -> usize {
    let line = m
        .wgsl
        .lines()
        .find(|l| l.starts_with(&format!("const {name}: u32 = ")))
        .unwrap_or_else(|| panic!("no {name}"));
    line.split(" = ")
        .nth(1)
        .unwrap()
        .trim_end_matches("u;")
        .parse()
        .unwrap()
}

/// The robot example checked, and its module with the seed grid on, the loop walk and
/// `options` (the seed data, the pruning).
fn robot_with(options: codegen::Options) -> (driver::Analysis, codegen::Module) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let src = std::fs::read_to_string(dir.join("robot.sdf")).unwrap();
    let a = driver::check(&src, Some(&dir));
    let options = codegen::Options {
        seed_grid: codegen::SeedGridChoice::On,
        walk: codegen::WalkForm::Loop,
        ..options
    };
    let m = driver::generate(&a, &options).unwrap();
    (a, m)
}

#[test]
fn seed_grids_live_in_the_tables_buffer() {
    let (a, m) = robot_with(codegen::Options {
        prune: true,
        ..Default::default()
    });
    let atlas = a.atlases[0].as_ref().unwrap();
    // The grid's lists, word for word, at the offsets the module bakes in.
    let grid = atlas.seed_grid();
    let words = &m.manifest.tables;
    let at = |name: &str, len: usize| {
        let k = table_at(&m, name);
        words[k..k + len].to_vec()
    };
    assert_eq!(at("ATLAS_0_START_AT", grid.start.len()), grid.start);
    assert_eq!(at("ATLAS_0_ITEMS_AT", grid.items.len()), grid.items);
    let bound: Vec<u32> = grid.bound.iter().map(|&b| (b as f32).to_bits()).collect();
    assert_eq!(at("ATLAS_0_BOUND_AT", bound.len()), bound);
    // The pruning's per-seed limits (uv::prune), after the grid.
    let pruning = atlas.pruning().expect("the robot's walks are pruned");
    let limits: Vec<u32> = pruning
        .limit
        .iter()
        .map(|&l| (l as f32).to_bits())
        .collect();
    assert_eq!(at("ATLAS_0_PRUNE_AT", limits.len()), limits);
    assert_eq!(
        words.len(),
        grid.start.len() + 2 * grid.items.len() + limits.len()
    );
    assert!(grid.items.len() > 1000, "{}", grid.items.len());
    // One read-only storage binding in the render group, declared and documented.
    let tables: Vec<_> = m
        .manifest
        .bindings
        .iter()
        .filter(|b| b.name == "tables")
        .collect();
    assert_eq!(tables.len(), 1);
    assert_eq!(
        (tables[0].group, tables[0].kind),
        (0, codegen::bindings::Kind::StorageRead)
    );
    assert!(m.wgsl.contains(&format!(
        "@group(0) @binding({}) var<storage, read> tables: array<u32>;",
        tables[0].binding
    )));
    // No baked array grows with seeds × cells: the largest is per seed (or per edge).
    let longest = m
        .wgsl
        .lines()
        .filter(|l| l.starts_with("var<private> ATLAS_"))
        .map(|l| {
            let ty = l.split(" = ").next().unwrap();
            ty.rsplit(", ")
                .next()
                .unwrap()
                .trim_end_matches('>')
                .parse::<usize>()
                .unwrap()
        })
        .max()
        .unwrap();
    assert!(longest <= 2 * atlas.seeds.len(), "{longest}");
    // The manifest JSON carries the words; a module without an atlas has no tables.
    let json = serde_json::to_value(&m.manifest).unwrap();
    assert_eq!(json["tables"].as_array().unwrap().len(), words.len());
    let plain = generate("render sphere(1);", None).unwrap();
    assert!(plain.manifest.tables.is_empty());
    assert!(plain.manifest.bindings.iter().all(|b| b.name != "tables"));
    assert!(!plain.wgsl.contains("tables"));
}

/// With `--seed-data buffer` (and by default above 64 seeds), the seeds' records
/// (position, normal, e1, offset) and the merge graph's adjacency go to the tables
/// buffer, word for word, before the grid, and nothing of the atlas is baked in as an
/// array.
#[test]
fn seeds_in_buffer_move_the_atlas_data_to_the_tables() {
    let (a, m) = robot_with(codegen::Options {
        seed_data: codegen::SeedData::Buffer,
        ..Default::default()
    });
    let atlas = a.atlases[0].as_ref().unwrap();
    let words = &m.manifest.tables;
    let at = |name: &str, len: usize| {
        let k = table_at(&m, name);
        words[k..k + len].to_vec()
    };
    let n = atlas.seeds.len();
    let f = |v: f64| (v as f32).to_bits();
    let records: Vec<u32> = atlas
        .seeds
        .iter()
        .flat_map(|s| {
            let (p, q, e) = (s.seed.p, s.seed.n, s.seed.e1);
            [
                p.x, p.y, p.z, q.x, q.y, q.z, e.x, e.y, e.z, s.offset.x, s.offset.y,
            ]
            .map(f)
        })
        .collect();
    assert_eq!(at("ATLAS_0_SEEDS_AT", n * codegen::SEED_WORDS), records);
    let edges: Vec<(usize, f64)> = atlas.graph.neighbors.iter().flatten().copied().collect();
    assert!(!edges.is_empty());
    let mut starts = vec![0u32];
    for list in &atlas.graph.neighbors {
        starts.push(starts.last().unwrap() + list.len() as u32);
    }
    assert_eq!(at("ATLAS_0_ADJ_START_AT", n + 1), starts);
    let adj: Vec<u32> = edges.iter().map(|&(j, _)| j as u32).collect();
    assert_eq!(at("ATLAS_0_ADJ_AT", edges.len()), adj);
    let adj_d: Vec<u32> = edges.iter().map(|&(_, d)| f(d)).collect();
    assert_eq!(at("ATLAS_0_ADJ_D_AT", edges.len()), adj_d);
    let grid = atlas.seed_grid();
    assert_eq!(at("ATLAS_0_START_AT", grid.start.len()), grid.start);
    assert_eq!(
        words.len(),
        n * codegen::SEED_WORDS + n + 1 + 2 * edges.len() + grid.start.len() + 2 * grid.items.len()
    );
    assert!(
        !m.wgsl.lines().any(|l| l.starts_with("var<private> ATLAS_")),
        "a baked array is left"
    );
    codegen::validate(&m.wgsl).unwrap();
    // By default, atlases of up to 64 seeds are baked in and larger ones are not.
    for n in [codegen::AUTO_BAKED_SEEDS, codegen::AUTO_BAKED_SEEDS + 1] {
        let seeds: String = (0..n)
            .map(|i| {
                let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let (r, t) = ((1.0 - y * y).sqrt(), 2.4 * i as f64);
                format!(
                    "seed s{i} = [{:.4}, {y:.4}, {:.4}];\n",
                    r * t.cos(),
                    r * t.sin()
                )
            })
            .collect();
        let src = format!(
            "let s = sphere(1);\natlas a on s {{\n{seeds}}}\nmaterial m {{ color = [a.uv.x, a.uv.y, 0]; }}\nrender s.paint(m);"
        );
        let m = generate(&src, None).unwrap();
        let baked = m.wgsl.contains("var<private> ATLAS_0_P:");
        assert_eq!(baked, n <= codegen::AUTO_BAKED_SEEDS, "{n} seeds");
        assert_eq!(
            m.wgsl.contains("const ATLAS_0_SEEDS_AT"),
            !baked,
            "{n} seeds"
        );
        codegen::validate(&m.wgsl).unwrap();
    }
}

#[test]
fn lipschitz_bound_reaches_the_shader() {
    let m = generate("render box(1).twist(rate: 2);", None).unwrap();
    let l = m.manifest.lipschitz;
    assert!(l > 1.5, "{l}");
    assert!(m.wgsl.contains(&format!(
        "const SCENE_LIPSCHITZ: f32 = {};",
        codegen::lit(l)
    )));
}

use crate::common;
use common::sdfc;

#[test]
fn compile_command_writes_every_target() {
    let dir = tempfile::tempdir().unwrap();
    for (target, file) in [
        ("wgsl", "out.wgsl"),
        ("spirv", "out.spv"),
        ("glsl", "out.glsl"),
        ("msl", "out.metal"),
    ] {
        let out = dir.path().join(file);
        let manifest = dir.path().join(format!("{file}.json"));
        let (code, _, err) = sdfc(&[
            "compile",
            "examples/warps.sdf",
            "--target",
            target,
            "-o",
            out.to_str().unwrap(),
            "--manifest",
            manifest.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{target}: {err}");
        assert!(std::fs::metadata(&out).unwrap().len() > 1000);
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap();
        assert_eq!(m["entry_points"][1]["name"], "fs_main");
    }
    // No stray temporary files are left beside the outputs.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 8);
    let (code, stdout, _) = sdfc(&["compile", "examples/warps.sdf"]);
    assert_eq!(code, 0);
    // naga's WGSL writer names arguments uniquely; the function keeps its name and type.
    assert!(stdout.contains("fn sdf_twisted(") && stdout.contains("-> f32 {"));
    assert_eq!(
        sdfc(&["compile", "examples/warps.sdf", "--target", "spirv"]).0,
        2
    );
    assert_eq!(sdfc(&["compile", "tests/ui/unknown_name.sdf"]).0, 1);
    // A seed on a hole's axis has no gradient to project along.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.sdf");
    std::fs::write(&bad, "let s = sphere(1) - cylinder(0.2, 4);\natlas a on s { seed x = [0, 0.5, 0]; }\nmaterial m { color = [a.uv, 0]; }\nrender s.paint(m);").unwrap();
    let (code, _, err) = sdfc(&["compile", bad.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(
        err.contains("E0401") && err.contains("seed `x` cannot be projected"),
        "{err}"
    );
}

#[test]
fn naga_rejection_is_an_internal_compiler_error_with_the_wgsl_saved() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .args(["compile", "examples/warps.sdf"])
        .env("SDFC_TEST_CORRUPT_WGSL", "1")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("error[E0900]: internal compiler error: naga rejected the generated WGSL"),
        "{err}"
    );
    let saved = err
        .lines()
        .find_map(|l| l.strip_prefix("note: the generated WGSL is saved at "))
        .and_then(|l| l.split(';').next())
        .expect("the path of the saved WGSL");
    let text = std::fs::read_to_string(saved).unwrap();
    assert!(text.contains("fn sdf_twisted") && text.contains("fn corrupted( {"));
    let _ = std::fs::remove_file(saved);
}

/// naga's rejection of code generated from a scene definition is reported on that
/// definition's span in the scene, not on a WGSL line.
#[test]
fn naga_rejection_points_at_the_scene_definition() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .args(["compile", "examples/plate.sdf"])
        .env("SDFC_TEST_CORRUPT_WGSL", "material")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    let src = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/plate.sdf"),
    )
    .unwrap();
    let line = src
        .lines()
        .position(|l| l.starts_with("material tiled"))
        .unwrap()
        + 1;
    assert!(
        err.contains(&format!("┌─ examples/plate.sdf:{line}:1")),
        "{err}"
    );
    assert!(
        err.contains("naga rejected the WGSL generated for material `tiled`"),
        "{err}"
    );
    assert!(
        err.contains("note: the generated WGSL is saved at"),
        "{err}"
    );
    if let Some(saved) = err
        .lines()
        .find_map(|l| l.strip_prefix("note: the generated WGSL is saved at "))
        .and_then(|l| l.split(';').next())
    {
        let _ = std::fs::remove_file(saved);
    }
}

#[test]
fn naga_errors_map_to_the_scene_definition_that_produced_the_code() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/plate.sdf"))
        .unwrap();
    let analysis = driver::check_all(&text, None);
    assert!(analysis.diagnostics.is_empty());
    // check_all keeps the validated module.
    let compiled = analysis.compiled.as_ref().expect("the validated module");
    // Broken inside the material's code (the test-side injection point), naga's error
    // lands on the material item.
    let mut module = compiled.module.clone();
    driver::test_hooks::corrupt_first_material(&mut module);
    let e = codegen::validate(&module.wgsl)
        .err()
        .expect("naga rejects it");
    let d = module.internal_error(&e);
    assert_eq!(d.code, codes::E_INTERNAL);
    let primary = d.primary.as_ref().expect("a place in the scene");
    assert!(
        text[primary.span.range()].starts_with("material tiled {"),
        "{d:#?}"
    );
    assert!(primary.message.contains("material `tiled`"), "{d:#?}");
    assert!(
        d.notes
            .iter()
            .any(|n| n.starts_with("naga:") && n.contains("`undefined_name`")),
        "naga's own message names the undefined identifier: {d:#?}"
    );
    // Every region of the source map is a real definition of the scene.
    use codegen::Definition;
    let whats: Vec<&Definition> = compiled.module.source_map.iter().map(|r| &r.what).collect();
    assert_eq!(
        whats,
        [
            &Definition::Shape("plate".into()),
            &Definition::RenderedShape,
            &Definition::Atlas("tiles".into()),
            &Definition::Material("tiled".into()),
        ]
    );
    for r in &compiled.module.source_map {
        assert!(r.wgsl.end <= compiled.module.wgsl.len() && r.wgsl.start < r.wgsl.end);
        assert!(!text[r.span.range()].is_empty());
    }
    // Code of the shared library is no definition of the scene: the diagnostic says so
    // and has no place, rather than pointing at byte 0.
    let mut module = compiled.module.clone();
    module.wgsl = module
        .wgsl
        .replacen("fn camera_ray(", "fn camera_ray(oops ", 1);
    let e = codegen::validate(&module.wgsl)
        .err()
        .expect("naga rejects it");
    let d = module.internal_error(&e);
    assert!(d.primary.is_none(), "{d:#?}");
    let rendered = sdfc::diagnostic::render("plate.sdf", &text, &[d], false);
    assert!(
        rendered.contains("error[E0900]") && !rendered.contains("plate.sdf:1:1"),
        "{rendered}"
    );
}

/// The templates of shaders/*.wgsl.in are filled completely (every placeholder has a
/// value and every value a placeholder), in every walk form and seed-grid choice, and
/// the filled module validates.
#[test]
fn templates_are_filled_completely_and_validate() {
    use codegen::template;
    assert!(template::placeholders(template::ATLAS).contains(&"walk_steps"));
    assert_eq!(
        template::placeholders(template::ENTRY),
        [
            "bindings",
            "view_constants",
            "view",
            "atlas_aov_on",
            "atlas_aov"
        ]
    );
    assert_eq!(template::placeholders(template::TRACE), ["map", "suffix"]);
    assert_eq!(
        template::placeholders(template::COARSE),
        [
            "step",
            "slots",
            "flatness",
            "condition",
            "reads",
            "side",
            "samples"
        ]
    );
    let m = template::fill(
        "fn a_{{k}}() {}",
        &[("k", "1".into()), ("extra", "2".into())],
    );
    assert_eq!(m.unwrap_err().unused, ["extra"]);
    let m = template::fill("fn a_{{k}}_{{j}}() {}", &[("k", "1".into())]);
    assert_eq!(m.unwrap_err().missing, ["j"]);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let src = std::fs::read_to_string(dir.join("plate.sdf")).unwrap();
    for walk in [codegen::WalkForm::Unrolled, codegen::WalkForm::Loop] {
        for seed_grid in [codegen::SeedGridChoice::On, codegen::SeedGridChoice::Off] {
            // With the multi-scale pass's template too (the view's pipeline constants,
            // in every module, are validated in their default form as well).
            let options = codegen::Options {
                walk,
                seed_grid,
                multiscale: seed_grid == codegen::SeedGridChoice::On,
                ..Default::default()
            };
            let m = generate_with(&src, Some(&dir), &options).unwrap();
            assert!(
                !m.wgsl.contains("{{"),
                "{walk:?} {seed_grid:?}: a placeholder is left"
            );
            codegen::validate(&m.wgsl).unwrap_or_else(|e| panic!("{walk:?} {seed_grid:?}: {e}"));
        }
    }
}

/// What `sdfc compile` writes carries only what the scene uses: a one-sphere scene has
/// none of the library's other primitives. The WGSL written is the very text naga
/// validated, comments and names as generated (naga's writer would rename `sdf_part2`
/// to `sdf_part2_`, against the header's `sdf_NAME`).
#[test]
fn standalone_modules_carry_only_what_the_scene_uses() {
    let src = "let part2 = sphere(0.5);\nrender part2;";
    // The validated module, whose header lists each binding's users as derived.
    let analysis = sdfc::driver::check(src, None);
    let module = sdfc::driver::compile(&analysis, &Default::default())
        .unwrap()
        .module;
    let (code, out, err) = common::sdfc_with_input(&["compile", "-"], src.as_bytes());
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with("// Generated by sdfc"),
        "the header comes first"
    );
    assert_eq!(out, module.wgsl);
    codegen::validate(&out).unwrap_or_else(|e| panic!("the written module: {e}"));
    assert!(out.contains("fn sd_sphere(") && out.contains("fn sdf_part2(p: vec3<f32>) -> f32 {"));
    let library = codegen::shake::full_library();
    for unused in ["fn sd_torus(", "fn sd_box(", "fn op_twist("] {
        assert!(
            library.contains(unused) && !out.contains(unused),
            "{unused}"
        );
    }
    let functions: Vec<&str> = library
        .lines()
        .filter(|l| l.starts_with("fn "))
        .map(|l| &l[..l.find('(').unwrap() + 1])
        .collect();
    let kept = functions.iter().filter(|f| out.contains(**f)).count();
    assert!(
        kept * 2 < functions.len(),
        "{kept} of the library's {} functions",
        functions.len()
    );
}

/// Choices made on the command line that name nothing in the scene are usage errors
/// (exit 2) with a did-you-mean, not scene diagnostics.
#[test]
fn unknown_shape_atlas_or_entry_is_a_usage_error() {
    for (args, want) in [
        (
            vec!["compile", "examples/warps.sdf", "--shape", "twistd"],
            "the scene has no shape `twistd`; did you mean `twisted`?",
        ),
        (
            vec!["compile", "examples/plate.sdf", "--atlas", "tile"],
            "the scene has no atlas `tile`; did you mean `tiles`?",
        ),
        (
            vec![
                "compile",
                "examples/warps.sdf",
                "--target",
                "glsl",
                "--entry",
                "fs_mian",
            ],
            "no entry point `fs_mian`; did you mean `fs_main`?",
        ),
        (
            vec![
                "eval",
                "examples/warps.sdf",
                "--shape",
                "zzz",
                "--points",
                "-",
            ],
            "the scene has no shape `zzz`",
        ),
    ] {
        let (code, _, err) = common::sdfc_with_input(&args, b"[[0, 0, 0]]");
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("E0400") && !err.contains("E0900"), "{err}");
    }
}
