//! The `sdfc` binary: exit codes, human and JSON output.

use std::path::Path;

use crate::common;
use common::{sdfc, sdfc_with_input};

#[test]
fn clean_file_exits_zero() {
    let (code, _, err) = sdfc(&["check", "examples/capsule.sdf"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("checked 1 file: 0 errors, 0 warnings"),
        "{err}"
    );
}

#[test]
fn errors_exit_one_and_are_all_printed() {
    let (code, _, err) = sdfc(&[
        "check",
        "--color",
        "never",
        "tests/ui/many_independent_errors.sdf",
    ]);
    assert_eq!(code, 1);
    for c in [
        "E0010", "E0100", "E0103", "E0107", "E0110", "E0113", "E0200", "E0300", "E0301",
    ] {
        assert!(
            err.contains(&format!("error[{c}]")),
            "missing {c} in:\n{err}"
        );
    }
    assert!(
        err.contains("checked 1 file: 9 errors, 0 warnings"),
        "{err}"
    );
}

#[test]
fn warnings_alone_exit_zero() {
    let (code, _, _) = sdfc(&["check", "tests/ui/unused_binding.sdf"]);
    assert_eq!(code, 0);
}

#[test]
fn several_files_any_error_exits_one() {
    let (code, _, _) = sdfc(&["check", "examples/capsule.sdf", "tests/ui/unknown_name.sdf"]);
    assert_eq!(code, 1);
}

#[test]
fn io_and_usage_problems_exit_two() {
    let (code, _, err) = sdfc(&["check", "does/not/exist.sdf"]);
    assert_eq!(code, 2);
    assert!(err.contains("cannot read does/not/exist.sdf"), "{err}");
    assert_eq!(sdfc(&["check"]).0, 2);
    assert_eq!(sdfc(&["frobnicate"]).0, 2);
    assert_eq!(
        sdfc(&["check", "--format", "xml", "examples/capsule.sdf"]).0,
        2
    );
}

#[test]
fn help_on_every_subcommand() {
    let (code, out, _) = sdfc(&["--help"]);
    assert_eq!(code, 0);
    assert!(out.contains("check"));
    let (code, out, _) = sdfc(&["check", "--help"]);
    assert_eq!(code, 0);
    assert!(out.contains("Exit status"), "{out}");
}

#[test]
fn json_output_has_positions_labels_and_notes() {
    let (code, out, _) = sdfc(&["check", "--format", "json", "tests/ui/unknown_name.sdf"]);
    assert_eq!(code, 1);
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    assert_eq!(lines.len(), 2);
    let e = lines.iter().find(|d| d["code"] == "E0100").unwrap();
    assert_eq!(e["severity"], "error");
    assert_eq!(e["message"], "cannot find `raduis` in this scene");
    assert_eq!(e["file"], "tests/ui/unknown_name.sdf");
    let src = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui/unknown_name.sdf"),
    )
    .unwrap();
    let start = e["byte_start"].as_u64().unwrap() as usize;
    let end = e["byte_end"].as_u64().unwrap() as usize;
    assert_eq!(&src[start..end], "raduis");
    assert_eq!(e["start"]["line"], 3);
    assert_eq!(e["start"]["column"], 16);
    assert_eq!(e["end"]["line"], 3);
    assert_eq!(e["end"]["column"], 22);
    assert_eq!(e["labels"][0]["message"], "not defined");
    assert_eq!(e["help"], "did you mean `radius`?");
    let w = lines.iter().find(|d| d["code"] == "W0001").unwrap();
    assert_eq!(w["severity"], "warning");
    assert!(w["notes"].is_array());
}

#[test]
fn json_columns_count_characters_not_bytes() {
    let (_, out, _) = sdfc(&["check", "--format", "json", "tests/ui/unicode_and_crlf.sdf"]);
    let e: serde_json::Value = out
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .find(|d| d["code"] == "E0100")
        .unwrap();
    // `let label = "größe"; let s = sphere(grosse);`: `grosse` starts at character 37.
    assert_eq!(e["start"]["line"], 3);
    assert_eq!(e["start"]["column"], 37);
}

#[test]
fn reads_standard_input() {
    let (code, out, _) = sdfc_with_input(&["check", "--format", "json", "-"], b"render spher(1);");
    assert_eq!(code, 1);
    assert!(out.contains("E0103"));
}

#[test]
fn eval_prints_one_object_per_point_in_order() {
    let (code, text, err) = sdfc_with_input(
        &["eval", "examples/sphere.sdf", "--points", "-"],
        b"[[0, 0, 2], [0, 0.5, 0], [3, 4, 0]]",
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        text.starts_with("{\"point\":[0.0,0.0,2.0],\"distance\":1.0,"),
        "{text}"
    );
    let lines: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3);
    let d: Vec<f64> = lines
        .iter()
        .map(|l| l["distance"].as_f64().unwrap())
        .collect();
    assert!(
        (d[0] - 1.0).abs() < 1e-12 && (d[1] + 0.5).abs() < 1e-12 && (d[2] - 4.0).abs() < 1e-12,
        "{d:?}"
    );
    let s = &lines[2]["surface"];
    assert!(
        (s[0].as_f64().unwrap() - 0.6).abs() < 1e-8 && (s[1].as_f64().unwrap() - 0.8).abs() < 1e-8
    );
}

#[test]
fn eval_rejects_bad_points_and_unknown_shapes() {
    let dir = std::env::temp_dir().join(format!("sdfc-eval-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "[[1, 2]]").unwrap();
    let (code, _, err) = sdfc(&[
        "eval",
        "examples/sphere.sdf",
        "--points",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("point 0 is not an [x, y, z] array"), "{err}");
    let (code, _, err) = sdfc(&[
        "eval",
        "examples/sphere.sdf",
        "--shape",
        "nope",
        "--points",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("no shape `nope`"), "{err}");
    let (code, _, _) = sdfc(&[
        "eval",
        "tests/ui/unknown_name.sdf",
        "--points",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
}

#[test]
fn fmt_check_passes_on_every_example() {
    let mut args = vec!["fmt", "--check"];
    let examples: Vec<String> = std::fs::read_dir("examples")
        .unwrap()
        .map(|e| e.unwrap().path().display().to_string())
        .filter(|p| p.ends_with(".sdf"))
        .collect();
    assert!(examples.len() >= 5);
    args.extend(examples.iter().map(String::as_str));
    let (code, out, err) = sdfc(&args);
    assert_eq!((code, out.as_str()), (0, ""), "{err}");
}

#[test]
fn fmt_rewrites_checks_and_refuses_syntax_errors() {
    let dir = tempfile::tempdir().unwrap();
    let messy = dir.path().join("messy.sdf");
    let clean = dir.path().join("clean.sdf");
    let broken = dir.path().join("broken.sdf");
    std::fs::write(&messy, "let a=sphere(1);/* keep */\nrender  a;\n").unwrap();
    std::fs::write(&clean, "let a = sphere(1);\nrender a;\n").unwrap();
    std::fs::write(&broken, "let a = sphere(1)\nrender  a;\n").unwrap();
    let path = |p: &Path| p.display().to_string();

    // --check names the files that would change and changes nothing.
    let (code, out, err) = sdfc(&["fmt", "--check", &path(&messy), &path(&clean)]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(out, format!("{}\n", path(&messy)));
    assert!(err.contains("1 file would be reformatted"), "{err}");
    assert!(std::fs::read_to_string(&messy)
        .unwrap()
        .starts_with("let a=sphere"));

    let (code, _, err) = sdfc(&["fmt", &path(&messy), &path(&clean)]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        std::fs::read_to_string(&messy).unwrap(),
        "let a = sphere(1); /* keep */\nrender a;\n"
    );
    assert_eq!(sdfc(&["fmt", "--check", &path(&messy)]).0, 0);

    // Syntax errors: exit 1 with the diagnostics, the file left as it is.
    let (code, _, err) = sdfc(&["fmt", &path(&broken)]);
    assert_eq!(code, 1);
    assert!(err.contains("error[E0010]"), "{err}");
    assert!(err.contains("was not formatted"), "{err}");
    assert_eq!(
        std::fs::read_to_string(&broken).unwrap(),
        "let a = sphere(1)\nrender  a;\n"
    );
    assert_eq!(sdfc(&["fmt", "does/not/exist.sdf"]).0, 2);
}

#[test]
fn fmt_formats_standard_input_to_standard_output() {
    let (code, out, _) = sdfc_with_input(&["fmt", "-"], b"render sphere( 1 ) ;");
    assert_eq!(code, 0);
    assert_eq!(out, "render sphere(1);\n");
}

#[test]
fn render_keeps_the_level_view_for_baked_meshes() {
    let (code, _, err) = sdfc(&["render", "examples/sphere.sdf", "--view", "level"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no level view"), "{err}");
}

#[test]
fn render_refuses_a_glb_that_is_not_a_baked_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.glb");
    std::fs::write(&junk, b"not a glb").unwrap();
    let junk = junk.to_str().unwrap();
    let (code, _, err) = sdfc(&["render", junk, "-o", "/dev/null"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("is not a mesh baked by sdfc"), "{err}");
    let (code, _, err) = sdfc(&["render", junk, "--view", "steps"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no steps view"), "{err}");
}

#[test]
fn a_chart_without_a_font_is_refused_before_measuring() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .args(["bench", "--seed-sweep", "--plot", "sweep.png"])
        .env("SDFC_PLOT_FONT", "/no/such/font.ttf")
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cannot read the font /no/such/font.ttf"),
        "{err}"
    );
    assert!(!err.contains("adapter"), "measured first: {err}");
    // A chart is .svg or .png.
    let (code, _, err) = sdfc(&["bench", "--seed-sweep", "--plot", "sweep.pdf"]);
    assert_eq!(code, 2);
    assert!(err.contains(".svg or .png"), "{err}");
}

/// `bench --lsp-latency` on a file whose name needs percent-encoding in a URI (a
/// space, brackets, a comma): the in-process client opens it by a real `file:` URI, so
/// the server answers (a raw path with a space is no URI: the server ignored it, and
/// the bench waited ten minutes for diagnostics, then failed).
#[test]
fn lsp_latency_measures_a_file_whose_name_needs_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("my scene (v2),b.sdf");
    std::fs::write(&path, "render sphere(1);\n").unwrap();
    let (code, out, err) = common::sdfc(&[
        "bench",
        path.to_str().unwrap(),
        "--lsp-latency",
        "--edits",
        "2",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("the full set") && out.contains("p95"), "{out}");
}
