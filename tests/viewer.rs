//! `sdfc view`: the parts that need no window (picking, seed edits on real example
//! files, the reload state machine, the orbit camera), then one real window under Xvfb
//! whose screenshot must match `sdfc render` of the same view.

use crate::common;

use glam::DVec3;
use sdfc::driver::check;
use sdfc::ide::seed_edit::{add_seed, merge, move_seed, remove_seed};
use sdfc::ide::Document;
use sdfc::view::{Camera, View};
use sdfc::viewer::edit::SeedEditor;
use sdfc::viewer::pick;
use sdfc::viewer::reload::{Outcome, Reloader};
use sdfc::viewer::Orbit;
use std::path::{Path, PathBuf};

const SPHERE: &str = "
let ball = sphere(1);
atlas a on ball {
    seed front = [0, 0, 1];
    seed back = [0, 0, -1];
}
render ball {
    camera = look_at([0, 0, 5], [0, 0, 0], fov: 0.8);
    size = [64, 48];
}
";

fn sphere_view() -> (sdfc::driver::Analysis, View) {
    let a = check(SPHERE, None);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    let shape = a.scene.as_ref().and_then(|s| s.render.clone()).unwrap();
    let view = View::new(a.program.render.as_ref(), &shape);
    (a, view)
}

#[test]
fn picking_hits_the_analytic_point_on_a_sphere() {
    let (a, view) = sphere_view();
    let shape = a.scene.as_ref().and_then(|s| s.render.as_ref()).unwrap();
    let c = view.camera;
    let mut hits = 0;
    // The sphere spans about 11.6 pixels around the centre: hits inside (one near the
    // rim, where rays graze), a miss outside.
    let pixels = [
        (32.0, 24.0),
        (25.5, 19.5),
        (38.0, 17.0),
        (28.0, 33.0),
        (40.25, 30.75),
        (42.5, 24.0),
        (45.0, 20.0),
    ];
    for (px, py) in pixels {
        let dir = c.ray(px, py, view.width as f64, view.height as f64);
        // The ray against the unit sphere: |eye + t dir|² = 1.
        let b = c.eye.dot(dir);
        let disc = b * b - (c.eye.length_squared() - 1.0);
        let picked = pick::surface(shape, &view, px, py);
        if disc < 0.0 {
            assert!(picked.is_none(), "pixel ({px}, {py}) misses the sphere");
            continue;
        }
        let t = -b - disc.sqrt();
        let expected = c.eye + dir * t;
        let p = picked.unwrap_or_else(|| panic!("pixel ({px}, {py}) hits the sphere"));
        let error = (p.position - expected).length();
        assert!(
            error < 1e-4 * view.scale,
            "pixel ({px}, {py}): {:?} vs {expected:?} ({error:e})",
            p.position
        );
        assert!((p.normal - expected).length() < 1e-4);
        hits += 1;
    }
    assert_eq!(hits, 6);
    // A corner of the image looks past the sphere.
    assert!(pick::surface(shape, &view, 0.5, 0.5).is_none());
}

#[test]
fn the_seed_under_the_cursor_is_the_visible_one() {
    let (a, view) = sphere_view();
    let shape = a.scene.as_ref().and_then(|s| s.render.as_ref()).unwrap();
    // Both seeds project to the centre; only the front one is visible.
    let (sx, sy, _) = pick::project(&view, DVec3::Z).unwrap();
    assert!((sx - 32.0).abs() < 1e-9 && (sy - 24.0).abs() < 1e-9);
    let s = pick::seed(&a, a.field(shape), &view, sx + 2.0, sy - 1.0, 12.0).unwrap();
    assert_eq!((s.atlas.as_str(), s.seed.as_str()), ("a", "front"));
    assert!(pick::seed(&a, a.field(shape), &view, sx + 20.0, sy, 12.0).is_none());
    assert_eq!(
        pick::atlas_at(&a, DVec3::X, view.scale).as_deref(),
        Some("a")
    );
}

#[test]
fn the_orbit_camera_gives_back_the_scene_camera() {
    let camera = Camera::look_at(DVec3::new(3.0, 2.0, 4.0), DVec3::new(0.5, 0.0, -0.2), 0.7);
    let orbit = Orbit::from_camera(&camera, DVec3::ZERO);
    let back = orbit.camera();
    for (x, y) in [
        (back.eye, camera.eye),
        (back.forward, camera.forward),
        (back.right, camera.right),
        (back.up, camera.up),
    ] {
        assert!((x - y).length() < 1e-12, "{x:?} vs {y:?}");
    }
    // Zoom keeps the target; pan keeps the distance and moves along the image plane.
    let mut o = orbit;
    o.zoom(2.0);
    assert!((o.target - orbit.target).length() < 1e-12 && o.distance < orbit.distance);
    o.pan(10.0, 0.0, 100.0);
    let moved = o.target - orbit.target;
    assert!(moved.dot(camera.forward).abs() < 1e-9 && moved.dot(camera.right) < 0.0);
    assert_eq!(sdfc::viewer::interactive_divisor(10.0, 40.0), 1);
    assert_eq!(sdfc::viewer::interactive_divisor(160.0, 40.0), 2);
    assert_eq!(sdfc::viewer::interactive_divisor(1e6, 40.0), 8);
}

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

/// `examples/NAME` copied into a temporary folder, with a comment added inside its
/// atlas block before the `merge` line: (folder, path, text).
fn scratch(name: &str) -> (tempfile::TempDir, PathBuf, String) {
    let text = std::fs::read_to_string(examples().join(name)).unwrap();
    let text = text.replacen(
        "    merge ",
        "    // the ring around the hole\n    merge ",
        1,
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, &text).unwrap();
    (dir, path, text)
}

fn doc(text: &str) -> Document {
    Document::new(text, Some(&examples()))
}

/// The file after an edit: it checks clean, and every comment of the original is there.
fn assert_clean(text: &str, original: &str) -> Document {
    let d = doc(text);
    assert!(
        !d.analysis.has_errors(),
        "{}",
        sdfc::diagnostic::render("edited", text, &d.analysis.diagnostics, false)
    );
    for line in original
        .lines()
        .filter(|l| l.trim_start().starts_with("//"))
    {
        assert!(
            text.contains(line),
            "the comment {line:?} was lost:\n{text}"
        );
    }
    d
}

#[test]
fn seed_edits_rewrite_the_scene_file_and_undo() {
    let (_dir, path, original) = scratch("plate_hole.sdf");
    let mut editor = SeedEditor::new(&path, sdfc::access::Access::new(Some(&examples())));
    let seeds = |d: &Document| d.analysis.program.atlases[0].seeds.len();

    // Add: a new seed after the last one, the file's indentation kept.
    let d0 = doc(&original);
    let edits = add_seed(&d0, "top", DVec3::new(1.5, 0.1, 1.5)).map(|(e, n)| {
        assert_eq!(n, "s0");
        e
    });
    let t1 = editor.apply("add", &d0, edits, false).unwrap();
    assert!(
        t1.contains("    seed south = [0, 0.1, 1.2];\n    seed s0 = [1.5, 0.1, 1.5];\n"),
        "{t1}"
    );
    assert_eq!(std::fs::read_to_string(&path).unwrap(), t1);
    let d1 = assert_clean(&t1, &original);
    assert_eq!(seeds(&d1), 5);

    // Move: only the position's text changes.
    let t2 = editor
        .apply(
            "move",
            &d1,
            move_seed(&d1, "top", "s0", DVec3::new(-1.5, 0.1, -1.5)),
            false,
        )
        .unwrap();
    assert_eq!(t2, t1.replace("[1.5, 0.1, 1.5]", "[-1.5, 0.1, -1.5]"));
    let d2 = assert_clean(&t2, &original);

    // Merge twice: a tree edge, then a cycle that closes on the flat plate.
    let t3 = editor
        .apply("merge", &d2, merge(&d2, "top", "north", "s0"), true)
        .unwrap();
    assert!(
        t3.contains("    merge east north west south east;\n    merge north s0;\n"),
        "{t3}"
    );
    let d3 = assert_clean(&t3, &original);
    assert_eq!(d3.analysis.program.atlases[0].merges.len(), 5);
    let t4 = editor
        .apply("merge", &d3, merge(&d3, "top", "s0", "west"), true)
        .unwrap();
    let d4 = assert_clean(&t4, &original);
    assert_eq!(d4.analysis.program.atlases[0].merges.len(), 6);
    // Merging again is refused, and so is a merge across the hole (unreachable).
    assert!(merge(&d4, "top", "west", "s0").is_err());
    let refused = editor
        .apply("merge", &d4, merge(&d4, "top", "east", "west"), true)
        .unwrap_err();
    assert!(
        refused.contains("E0402") && refused.contains("was not changed"),
        "{refused}"
    );
    assert_eq!(std::fs::read_to_string(&path).unwrap(), t4);

    // Remove: the seed's line goes, and the ring loses the edges through it.
    let t5 = editor
        .apply("remove", &d4, remove_seed(&d4, "top", "north"), false)
        .unwrap();
    assert!(!t5.contains("north"), "{t5}");
    assert!(
        t5.contains("    merge west south east;\n    merge s0 west;\n"),
        "{t5}"
    );
    let d5 = assert_clean(&t5, &original);
    assert_eq!(seeds(&d5), 4);
    assert_eq!(d5.analysis.program.atlases[0].merges.len(), 3);

    // Undo, step by step, back to the original bytes.
    for expected in [&t4, &t3, &t2, &t1, &original] {
        let (text, _) = editor.undo().unwrap();
        assert_eq!(&text, expected);
        assert_eq!(&std::fs::read_to_string(&path).unwrap(), expected);
    }
    assert!(editor.undo().is_err());

    // An edit made on a stale document (the file changed since) is refused, and undo
    // never overwrites someone else's change.
    let stale = editor.apply(
        "add",
        &d1,
        add_seed(&d1, "top", DVec3::Y).map(|(e, _)| e),
        false,
    );
    assert!(stale.unwrap_err().contains("changed since"));
    let t = editor
        .apply(
            "add",
            &d0,
            add_seed(&d0, "top", DVec3::new(1.5, 0.1, 1.5)).map(|(e, _)| e),
            false,
        )
        .unwrap();
    std::fs::write(&path, format!("{t}// edited elsewhere\n")).unwrap();
    assert!(editor.undo().unwrap_err().contains("changed since"));
}

/// `p` projected onto the zero set of `shape` (Newton steps along the gradient).
fn project(shape: &sdfc::ir::Shape, mut p: DVec3) -> DVec3 {
    for _ in 0..50 {
        let d = sdfc::ir::eval::distance(shape, p);
        let g = sdfc::ir::eval::gradient(shape, p);
        if d.abs() < 1e-9 || g.length_squared() < 1e-12 {
            break;
        }
        p -= g * (d / g.length_squared());
    }
    p
}

#[test]
fn seed_edits_check_clean_on_every_example() {
    use sdfc::ide::seed_edit::{checked, Checked};
    let mut edited = 0;
    for entry in std::fs::read_dir(examples()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("sdf") {
            continue;
        }
        let original = std::fs::read_to_string(&path).unwrap();
        let d = doc(&original);
        let Some(Some(atlas)) = d.analysis.atlases.first() else {
            continue;
        };
        let name = atlas.name.clone();
        let seeds = &d.analysis.program.atlases[0].seeds;
        let first = &seeds[0].name;
        let last = &seeds[seeds.len() - 1].name;
        // Add halfway between the first two seeds (on the surface), move the first onto
        // its projection, remove the last with its merges.
        let a = atlas.seeds[0].seed.p;
        let b = atlas
            .seeds
            .get(1)
            .map_or(a + DVec3::splat(0.05), |s| s.seed.p);
        let mid = project(&atlas.shape, (a + b) * 0.5);
        let mut cases = vec![
            ("add", add_seed(&d, &name, mid).map(|(e, _)| e)),
            ("move", move_seed(&d, &name, first, a)),
        ];
        if seeds.len() > 1 {
            cases.push(("remove", remove_seed(&d, &name, last)));
        }
        for (what, edits) in cases {
            let edits = edits.unwrap_or_else(|e| panic!("{}: {what}: {e}", path.display()));
            match checked(
                &d,
                &edits,
                &sdfc::access::Access::new(Some(&examples())),
                false,
            ) {
                Checked::Accepted { text, doc: after } => {
                    for line in original
                        .lines()
                        .filter(|l| l.trim_start().starts_with("//"))
                    {
                        assert!(
                            text.contains(line),
                            "{}: {what} lost {line:?}",
                            path.display()
                        );
                    }
                    let count = after.analysis.program.atlases[0].seeds.len();
                    let expected = match what {
                        "add" => seeds.len() + 1,
                        "remove" => seeds.len() - 1,
                        _ => seeds.len(),
                    };
                    assert_eq!(count, expected, "{}: {what}", path.display());
                    edited += 1;
                }
                Checked::Refused {
                    text, diagnostics, ..
                } => panic!(
                    "{}: {what} refused:\n{}",
                    path.display(),
                    sdfc::diagnostic::render("edited", &text, &diagnostics, false)
                ),
            }
        }
    }
    assert!(edited >= 30, "only {edited} edits");
}

#[test]
fn the_reload_state_machine_keeps_the_last_good_scene() {
    let good = "render sphere(1) { size = [8, 8]; }";
    let other = "render sphere(2) { size = [8, 8]; }";
    let bad = "render sphere(oops) { size = [8, 8]; }";
    let access = sdfc::access::Access::new(None);
    let mut r: Reloader<u32> = Reloader::new("scene.sdf", access, None, Default::default());
    let mut builds = 0;
    let mut build = |_: &sdfc::driver::Compiled| {
        builds += 1;
        Ok::<u32, String>(builds)
    };
    assert_eq!(r.reload(good, false, &mut build), Outcome::Swapped);
    assert_eq!(r.good.as_ref().unwrap().pipeline, 1);
    assert_eq!(r.reload(good, false, &mut build), Outcome::Unchanged);
    // good → bad: the old pipeline stays, the window is stale, edits wait.
    let Outcome::Failed(report) = r.reload(bad, false, &mut build) else {
        panic!("a bad file fails");
    };
    assert!(
        report.contains("error") && report.contains("oops"),
        "{report}"
    );
    assert_eq!(r.good.as_ref().unwrap().pipeline, 1);
    assert!(r.stale.is_some() && r.current().is_none());
    assert_eq!(r.good.as_ref().unwrap().doc.text, good);
    // bad → good: swapped.
    assert_eq!(r.reload(other, false, &mut build), Outcome::Swapped);
    assert_eq!(r.good.as_ref().unwrap().pipeline, 2);
    assert!(r.stale.is_none() && r.current().is_some());
    // A pipeline that fails to build keeps the last good one too.
    let failed = r.reload(good, false, |_| Err::<u32, _>("no".to_string()));
    assert!(matches!(failed, Outcome::Failed(ref m) if m.contains("pipeline did not build")));
    assert_eq!(r.good.as_ref().unwrap().pipeline, 2);
    // The same text again with `force` (a texture changed) builds again.
    assert_eq!(r.reload(good, true, &mut build), Outcome::Swapped);
    assert_eq!(r.good.as_ref().unwrap().pipeline, 3);
}

#[test]
fn the_viewer_window_shows_what_render_draws() {
    let require = std::env::var("SDFC_REQUIRE_GPU").is_ok_and(|v| v == "1");
    let xvfb = std::process::Command::new("xvfb-run")
        .arg("--help")
        .output()
        .is_ok();
    if !xvfb {
        if require {
            panic!("SDFC_REQUIRE_GPU=1 but xvfb-run is missing (apt-get install xvfb xauth)");
        }
        eprintln!("SKIPPED: no xvfb-run for the viewer's window test");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("render.png");
    // The per-pixel walk, and the multi-scale atlas pass (which must draw the same).
    for multiscale in ["off", "on"] {
        let shot = dir.path().join(format!("view-{multiscale}.png"));
        let out = std::process::Command::new("xvfb-run")
            .args([
                "-a",
                "-s",
                "-screen 0 640x480x24",
                env!("CARGO_BIN_EXE_sdfc"),
                "view",
            ])
            .arg("examples/capsule.sdf")
            .args([
                "--size",
                "160x120",
                "--frames",
                "2",
                "--multiscale",
                multiscale,
            ])
            .arg("--screenshot")
            .arg(&shot)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        if out.status.code() == Some(4) && !require {
            eprintln!("SKIPPED: no window or adapter for the viewer:\n{stderr}");
            return;
        }
        assert!(out.status.success(), "sdfc view failed:\n{stderr}");
        assert!(stderr.contains("saved"), "{stderr}");
        assert_eq!(
            stderr.contains("multi-scale atlas pass: on"),
            multiscale == "on",
            "{stderr}"
        );
        compare_with_render(&shot, &reference, &stderr);
    }
    // The pass ran in the window: its map shows rebuilt (green) and walked (red) pixels.
    let walked = dir.path().join("walked.png");
    let out = std::process::Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_sdfc"))
        .args([
            "view",
            "examples/sphere.sdf",
            "--size",
            "160x120",
            "--frames",
            "2",
        ])
        .args(["--view", "walked", "--multiscale", "on", "--screenshot"])
        .arg(&walked)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let map = image::open(&walked).unwrap().to_rgba8();
    let count = |f: fn(&image::Rgba<u8>) -> bool| map.pixels().filter(|p| f(p)).count();
    let green = count(|p| p[1] as i32 > p[0] as i32 + 60);
    let red = count(|p| p[0] as i32 > p[1] as i32 + 60);
    assert!(green > 500 && red > 0, "green {green}, red {red}");
}

/// The viewer's screenshot `shot` against `sdfc render` of the same view (the
/// per-pixel walk) into `reference`.
fn compare_with_render(shot: &Path, reference: &Path, stderr: &str) {
    let (code, _, err) = common::sdfc(&[
        "render",
        "examples/capsule.sdf",
        "--walk",
        "loop",
        "--size",
        "160x120",
        "-o",
        reference.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let a = image::open(shot).unwrap().to_rgba8();
    let b = image::open(reference).unwrap().to_rgba8();
    assert_eq!(a.dimensions(), b.dimensions());
    let (mean, share) = common::image_difference(a.as_raw(), b.as_raw());
    eprintln!(
        "viewer window vs render: mean |Δ| = {mean:.3}/255, {:.3}% of pixels off by > 16 ({})",
        share * 100.0,
        stderr
            .lines()
            .find(|l| l.starts_with("saved"))
            .unwrap_or("")
    );
    assert!(mean <= 1.5 && share <= 0.005, "mean {mean}, share {share}");
}

/// The scene of the real-window mouse test: a unit ball seen head-on.
const BALL: &str = "// A ball for the viewer's mouse test.
let ball = sphere(1);
atlas a on ball {
    seed front = [0, 0, 1];
}
render ball {
    camera = look_at([0, 0, 5], fov: 0.8);
    size = [160, 120];
}
";

/// What a scripted viewer session left: the scene's folder, its text, the viewer's
/// log, and all of it with the script's steps as context for failures.
struct Driven {
    dir: tempfile::TempDir,
    text: String,
    viewer: String,
    context: String,
}

/// Runs `script` (bash, with `$SDFC`, `$SCENE` and `$LOG`) under Xvfb against a scene
/// file written with `source` (named `file`), and checks the script ended with
/// `exit=0`. `None` when the session is skipped: no xvfb-run or xdotool, or no adapter
/// for the window (a failure instead with SDFC_REQUIRE_GPU=1).
fn drive(file: &str, source: &str, script: &str, what: &str) -> Option<Driven> {
    let require = std::env::var("SDFC_REQUIRE_GPU").is_ok_and(|v| v == "1");
    let has = |tool: &str| {
        std::process::Command::new(tool)
            .arg("--help")
            .output()
            .is_ok()
    };
    if !has("xvfb-run") || !has("xdotool") {
        if require {
            panic!("SDFC_REQUIRE_GPU=1 but xvfb-run or xdotool is missing (apt-get install xvfb xauth xdotool)");
        }
        eprintln!("SKIPPED: no xvfb-run or xdotool for {what}");
        return None;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join(file);
    let log = dir.path().join("view.log");
    let path = dir.path().join("drive.sh");
    std::fs::write(&scene, source).unwrap();
    std::fs::write(&path, script).unwrap();
    let out = std::process::Command::new("timeout")
        .args([
            "120",
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 640x480x24",
            "bash",
        ])
        .arg(&path)
        .env("SDFC", env!("CARGO_BIN_EXE_sdfc"))
        .env("SCENE", &scene)
        .env("LOG", &log)
        .output()
        .unwrap();
    let steps = String::from_utf8_lossy(&out.stdout);
    let errors = String::from_utf8_lossy(&out.stderr);
    let viewer = std::fs::read_to_string(&log).unwrap_or_default();
    let text = std::fs::read_to_string(&scene).unwrap();
    let context = format!("steps:\n{steps}\n{errors}\nviewer:\n{viewer}\nfile:\n{text}");
    if viewer.contains("no GPU adapter") && !require {
        eprintln!("SKIPPED: no adapter for {what}:\n{context}");
        return None;
    }
    assert!(steps.contains("exit=0"), "{context}");
    Some(Driven {
        dir,
        text,
        viewer,
        context,
    })
}

/// Drives a real viewer window with X events (xdotool, through XTEST), and edits the
/// file behind its back (first fixing the broken file it starts on). Each step waits for its effect (at most 30 s) and says so.
const DRIVE: &str = r#"
set -u
"$SDFC" view "$SCENE" 2>"$LOG" &
pid=$!
count() { grep -c -- "$1" "$2" 2>/dev/null || true; }
wait_until() { # PATTERN FILE N: until PATTERN is on N lines of FILE (0: on none)
  for i in $(seq 1 300); do
    c=$(count "$1" "$2")
    if [ "$3" = 0 ]; then [ "$c" = 0 ] && return 0; else [ "$c" -ge "$3" ] && return 0; fi
    sleep 0.1
  done
  echo "STEP FAILED: waiting for $3 x '$1' in $2" >&2; kill $pid; exit 1
}
echo "step: a file broken at start is watched until it is fixed"
wait_until 'not reloaded' "$LOG" 1
sed -i 's/sphere(oops)/sphere(1)/' "$SCENE"
wait_until '^loaded' "$LOG" 1
win=$(xdotool search --sync --name 'sdfc view' | head -1)
xdotool windowfocus --sync "$win"
xdotool mousemove --window "$win" 100 60
sleep 0.3
echo "step: ctrl-click adds a seed"
xdotool keydown ctrl; sleep 0.2; xdotool click 1; sleep 0.2; xdotool keyup ctrl
wait_until 'seed s0' "$SCENE" 1
wait_until '^loaded' "$LOG" 2
echo "step: alt-click removes it"
xdotool keydown alt; sleep 0.2; xdotool click 1; sleep 0.2; xdotool keyup alt
wait_until 'seed s0' "$SCENE" 0
wait_until '^loaded' "$LOG" 3
echo "step: ctrl-z brings it back"
xdotool key ctrl+z
wait_until 'seed s0' "$SCENE" 1
wait_until '^loaded' "$LOG" 4
echo "step: dragging it moves it"
xdotool mousedown 1; sleep 0.2
for x in 98 95 92 90 88; do xdotool mousemove --window "$win" $x 45; sleep 0.05; done
sleep 0.2; xdotool mouseup 1
wait_until 'move seed' "$LOG" 1
wait_until '^loaded' "$LOG" 5
echo "step: shift-clicking two seeds merges them"
xdotool mousemove --window "$win" 80 60; sleep 0.2
xdotool keydown shift; sleep 0.2; xdotool click 1; sleep 0.3
xdotool mousemove --window "$win" 88 45; sleep 0.2; xdotool click 1; sleep 0.2
xdotool keyup shift
wait_until 'merge front s0;' "$SCENE" 1
wait_until '^loaded' "$LOG" 6
echo "step: an edit elsewhere reloads"
echo "// changed elsewhere" >> "$SCENE"
wait_until '^loaded' "$LOG" 7
echo "step: a broken file keeps the last good scene"
sed -i 's/sphere(1)/sphere(oops)/' "$SCENE"
wait_until 'not reloaded' "$LOG" 2
echo "step: Esc quits"
xdotool key Escape
wait $pid
echo "exit=$?"
"#;

#[test]
fn the_viewer_takes_mouse_and_file_edits_in_a_real_window() {
    // Broken at first: the viewer starts, says why, and waits for the fix.
    let broken = BALL.replace("sphere(1)", "sphere(oops)");
    let Some(Driven {
        text,
        viewer,
        context,
        ..
    }) = drive("ball.sdf", &broken, DRIVE, "the viewer's mouse test")
    else {
        return;
    };

    for said in [
        "add seed `s0` to atlas `a`: written",
        "remove seed `s0`: written",
        "undo `remove seed `s0``: written",
        "move seed `s0`: written",
        "merge `front` and `s0`: written",
        "not reloaded; showing the last good version",
        "error[E0100]",
    ] {
        assert!(
            viewer.contains(said),
            "the viewer did not say {said:?}\n{context}"
        );
    }
    // The file as the edits left it: the comment on top kept, the seed moved on the
    // surface (up and left of where it was added), then the two edits made elsewhere.
    assert!(
        text.starts_with("// A ball for the viewer's mouse test.\n"),
        "{context}"
    );
    assert!(text.ends_with("}\n// changed elsewhere\n"), "{context}");
    assert!(text.contains(";\n    merge front s0;\n}"), "{context}");
    let line = text.lines().find(|l| l.contains("seed s0 = ")).unwrap();
    let nums: Vec<f64> = line
        .split(['[', ']', ','])
        .filter_map(|t| t.trim().parse().ok())
        .collect();
    let p = DVec3::new(nums[0], nums[1], nums[2]);
    assert!((p.length() - 1.0).abs() < 1e-4, "s0 = {p:?} is on the ball");
    assert!(
        p.x > 0.0 && p.y > 0.0,
        "s0 = {p:?} moved up, still right of the centre"
    );
}

/// Sliders in a real window: `P` selects the parameter, a right-drag moves it (a new
/// picture, no new pipeline); `P` again selects `time`, which a right-drag scrubs
/// (another picture); the panel's own slider, left-dragged, moves the parameter to
/// its end; `W` writes the parameter back as the default (the comment kept).
const DRIVE_PARAMS: &str = r#"
set -u
"$SDFC" view "$SCENE" 2>"$LOG" &
pid=$!
count() { grep -c -- "$1" "$2" 2>/dev/null || true; }
wait_until() {
  for i in $(seq 1 300); do
    c=$(count "$1" "$2")
    [ "$c" -ge "$3" ] && return 0
    sleep 0.1
  done
  echo "STEP FAILED: waiting for $3 x '$1' in $2" >&2; kill $pid; exit 1
}
wait_until '^loaded' "$LOG" 1
win=$(xdotool search --sync --name 'sdfc view' | head -1)
xdotool windowfocus --sync "$win"
xdotool mousemove --window "$win" 60 280
sleep 0.5
echo "step: a screenshot before"
xdotool key s
wait_until 'saved' "$LOG" 1
echo "step: P selects the parameter"
xdotool key p
wait_until 'selected; right-drag' "$LOG" 1
echo "step: a right-drag below the panel moves it"
xdotool mousedown 3; sleep 0.2
for x in 70 90 110 130 150; do xdotool mousemove --window "$win" $x 280; sleep 0.05; done
sleep 0.2; xdotool mouseup 3
wait_until 'moved, with no new pipeline' "$LOG" 1
sleep 0.5
echo "step: a screenshot after"
xdotool key s
wait_until 'saved' "$LOG" 2
echo "step: P again selects time, and a right-drag scrubs it"
xdotool key p
wait_until 'parameter `time` = 0.0000' "$LOG" 1
xdotool mousemove --window "$win" 60 280; sleep 0.2
xdotool mousedown 3; sleep 0.2
for x in 70 90 110 130 150; do xdotool mousemove --window "$win" $x 280; sleep 0.05; done
sleep 0.2; xdotool mouseup 3
wait_until 'moved, with no new pipeline' "$LOG" 2
sleep 0.5
xdotool key s
wait_until 'saved' "$LOG" 3
echo "step: the panel's slider, dragged to its right end with the left button"
wait_until 'panel: slider `radius`' "$LOG" 1
line=$(grep -m1 'panel: slider `radius`' "$LOG")
x0=$(echo "$line" | sed -E 's/.* from ([0-9]+) to ([0-9]+) at y ([0-9]+).*/\1/')
x1=$(echo "$line" | sed -E 's/.* from ([0-9]+) to ([0-9]+) at y ([0-9]+).*/\2/')
y=$(echo "$line" | sed -E 's/.* from ([0-9]+) to ([0-9]+) at y ([0-9]+).*/\3/')
xdotool mousemove --window "$win" $((x0 + 30)) "$y"; sleep 0.3
xdotool mousedown 1; sleep 0.2
for k in 1 2 3 4 5 6; do xdotool mousemove --window "$win" $((x0 + 30 + k * (x1 - x0) / 6)) "$y"; sleep 0.05; done
sleep 0.2; xdotool mouseup 1
wait_until 'moved in the panel, with no new pipeline' "$LOG" 1
sleep 0.5
xdotool key s
wait_until 'saved' "$LOG" 4
echo "step: W writes it back"
xdotool key w
wait_until "set the parameters' defaults" "$LOG" 1
wait_until '^loaded' "$LOG" 2
xdotool key Escape
wait $pid
echo "exit=$?"
"#;

#[test]
fn the_viewer_sliders_move_a_parameter_without_a_new_pipeline() {
    let source = "// A ball whose radius is a slider.\nparam radius = 0.5 in [0.3, 1]; // the knob\n\nrender sphere(radius).translate([0.6 * sin(time), 0, 0]) {\n    camera = orbit(target: [0, 0, 0], distance: 4, yaw: 0deg, pitch: 0deg);\n    size = [480, 320];\n}\n";
    let Some(Driven {
        dir,
        text,
        viewer,
        context,
    }) = drive("knob.sdf", source, DRIVE_PARAMS, "the viewer's slider test")
    else {
        return;
    };

    // The drag built no pipeline: one, for the first load.
    let moved = viewer
        .lines()
        .find(|l| l.contains("moved, with no new pipeline"))
        .unwrap();
    assert!(moved.contains("(1 pipelines built)"), "{context}");
    // The picture changed: the two screenshots differ.
    let mut shots: Vec<std::path::PathBuf> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    shots.sort();
    assert_eq!(shots.len(), 4, "{context}");
    let shot = |i: usize| image::open(&shots[i]).unwrap().to_rgba8();
    let (a, b, c, d) = (shot(0), shot(1), shot(2), shot(3));
    let (mean, _) = common::image_difference(a.as_raw(), b.as_raw());
    assert!(
        mean > 2.0,
        "the drag did not change the picture: mean {mean}/255\n{context}"
    );
    // Scrubbed forward by 90 of the window's 480 pixels: 0.75 s of `time` (the ball
    // moves by 0.6 sin(0.75), about 0.41), from one pipeline still.
    let (mean, _) = common::image_difference(b.as_raw(), c.as_raw());
    assert!(
        mean > 2.0,
        "the scrub did not move the ball: mean {mean}/255\n{context}"
    );
    let scrubbed = viewer
        .lines()
        .filter(|l| l.contains("moved, with no new pipeline"))
        .nth(1)
        .unwrap_or_else(|| panic!("{context}"));
    assert!(
        scrubbed.contains("parameter `time` = ") && scrubbed.contains("(1 pipelines built)"),
        "{context}"
    );
    // The panel's slider (egui, left-dragged): the radius grows to its end (a left
    // drag on the scene would turn the camera instead), still one pipeline.
    let (mean, _) = common::image_difference(c.as_raw(), d.as_raw());
    assert!(
        mean > 2.0,
        "the panel's slider changed nothing: mean {mean}/255\n{context}"
    );
    let paneled = viewer
        .lines()
        .find(|l| l.contains("moved in the panel, with no new pipeline"))
        .unwrap_or_else(|| panic!("{context}"));
    assert!(
        paneled.contains("parameter `radius` = 0.9")
            || paneled.contains("parameter `radius` = 1.0"),
        "{paneled}\n{context}"
    );
    assert!(paneled.contains("(1 pipelines built)"), "{context}");
    // Written back: the new default in range, everything else as it was.
    let line = text.lines().nth(1).unwrap();
    let value: f64 = line
        .strip_prefix("param radius = ")
        .and_then(|l| l.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{context}"));
    assert!(value > 0.55 && value <= 1.0, "{value}\n{context}");
    assert_eq!(
        text.replacen(&format!("{value}"), "0.5", 1),
        source,
        "{context}"
    );
}
