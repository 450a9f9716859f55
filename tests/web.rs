//! Compiled scenes in a real browser: headless Chromium (Debian's `chromium`, WebGPU
//! on SwiftShader, Tint as the WGSL compiler) driven by `tools/browser/page.mjs`
//! (puppeteer-core, installed by `npm ci` from its lockfile), pages served from
//! http://127.0.0.1 by a small file server in this test.
//!
//! - Every example (loop walk, and `sphere.sdf` unrolled too) compiles in Tint with no
//!   message, and every pipeline builds with one bind group layout per group from the manifest's users alone, on a
//!   device with WebGPU's default limits.
//! - The page `sdfc export-web` writes renders `capsule.sdf` and `normal_map.sdf`
//!   within the reference-image tolerance of `sdfc render` at the same size.
//!
//! Without Chromium, Node or puppeteer-core the tests say so and skip, unless
//! `SDFC_REQUIRE_TOOLS=1` (as in CI), which makes that a failure.

mod common;

use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::Command;

fn chromium() -> PathBuf {
    PathBuf::from(std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into()))
}

fn tool() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/browser")
}

/// Whether the browser tools are here; a failure under `SDFC_REQUIRE_TOOLS=1`.
fn tools_present(what: &str) -> bool {
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let puppeteer = tool()
        .join("node_modules/puppeteer-core/package.json")
        .is_file();
    let missing = [
        (!chromium().is_file()).then_some("chromium"),
        (!node).then_some("node"),
        (!puppeteer).then_some("puppeteer-core (npm ci in tools/browser)"),
    ];
    let missing: Vec<&str> = missing.into_iter().flatten().collect();
    if missing.is_empty() {
        return true;
    }
    if std::env::var("SDFC_REQUIRE_TOOLS").as_deref() == Ok("1") {
        panic!(
            "SDFC_REQUIRE_TOOLS=1 but {} is not installed",
            missing.join(", ")
        );
    }
    eprintln!("SKIPPED: {what}: {} is not installed", missing.join(", "));
    false
}

/// Serves `root` on 127.0.0.1 (a secure context for WebGPU) from a thread: GET of a
/// file under it, 404 otherwise. Returns the base URL.
fn serve(root: PathBuf) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    std::thread::spawn(move || {
        for stream in listener.incoming() {
            let Ok(mut stream) = stream else { continue };
            let root = root.clone();
            std::thread::spawn(move || {
                let mut line = String::new();
                let mut reader = BufReader::new(stream.try_clone().unwrap());
                if reader.read_line(&mut line).is_err() {
                    return;
                }
                // Drain the headers.
                let mut header = String::new();
                while reader.read_line(&mut header).is_ok_and(|n| n > 2) {
                    header.clear();
                }
                let path = line.split_whitespace().nth(1).unwrap_or("/");
                let path = path
                    .split('?')
                    .next()
                    .unwrap_or("/")
                    .trim_start_matches('/');
                let file = root.join(path);
                let inside = !path.split('/').any(|c| c == "..");
                let (status, body) = match std::fs::read(&file) {
                    Ok(b) if inside => ("200 OK", b),
                    _ => ("404 Not Found", Vec::new()),
                };
                let kind = match file.extension().and_then(|e| e.to_str()) {
                    Some("html") => "text/html",
                    Some("js" | "mjs") => "text/javascript",
                    Some("json") => "application/json",
                    Some("png") => "image/png",
                    _ => "text/plain",
                };
                let _ = write!(
                    stream,
                    "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                    body.len()
                );
                let _ = stream.write_all(&body);
            });
        }
    });
    format!("http://127.0.0.1:{port}")
}

fn export(scene: &str, dir: &Path) {
    export_with(scene, dir, "loop")
}

fn export_with(scene: &str, dir: &Path, walk: &str) {
    let args = [
        "export-web",
        scene,
        "--walk",
        walk,
        "-o",
        dir.to_str().unwrap(),
    ];
    let (code, _, err) = common::sdfc(&args);
    assert_eq!(code, 0, "{scene}: {err}");
}

/// Runs the page script on `url`; its JSON line.
fn page(url: &str, raw: Option<&Path>) -> serde_json::Value {
    let mut cmd = Command::new("node");
    cmd.arg(tool().join("page.mjs")).arg(url);
    if let Some(raw) = raw {
        cmd.arg(raw);
    }
    let out = cmd.output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{url}: {}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(stdout.lines().last().unwrap_or("null")).unwrap()
}

#[test]
fn every_example_compiles_in_tint_and_builds_from_the_manifest_under_default_limits() {
    if !tools_present("the browser check of every example") {
        return;
    }
    let root = tempfile::tempdir().unwrap();
    let mut names = Vec::new();
    for e in std::fs::read_dir("examples").unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "sdf") {
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            export(p.to_str().unwrap(), &root.path().join(&name));
            names.push(name);
        }
    }
    names.sort();
    // One module with the unrolled walk (Tint builds the robot's slowly: the sphere's).
    export_with(
        "examples/sphere.sdf",
        &root.path().join("sphere_unrolled"),
        "unrolled",
    );
    names.push("sphere_unrolled".into());
    std::fs::write(
        root.path().join("modules.json"),
        serde_json::to_vec(&names).unwrap(),
    )
    .unwrap();
    for f in ["check.html", "check.js"] {
        std::fs::copy(tool().join(f), root.path().join(f)).unwrap();
    }
    let base = serve(root.path().to_path_buf());
    let t = std::time::Instant::now();
    let report = page(&format!("{base}/check.html"), None);
    eprintln!(
        "{} modules checked in Chromium in {:.1?}",
        names.len(),
        t.elapsed()
    );
    assert!(report["error"].is_null(), "{report}");
    let modules = report["modules"].as_array().expect("a report per module");
    assert_eq!(modules.len(), names.len(), "{report}");
    let mut problems = Vec::new();
    let times: Vec<String> = modules
        .iter()
        .map(|m| format!("{} {} ms", m["name"], m["ms"]))
        .collect();
    eprintln!("per module: {}", times.join(", "));
    for m in modules {
        let (msgs, errs) = (
            m["messages"].as_array().unwrap(),
            m["errors"].as_array().unwrap(),
        );
        if !msgs.is_empty() || !errs.is_empty() {
            problems.push(format!("{}: {msgs:?} {errs:?}", m["name"]));
        }
    }
    assert!(problems.is_empty(), "in Chromium:\n{}", problems.join("\n"));
    // The device had WebGPU's default limits.
    assert_eq!(report["maxColorAttachmentBytesPerSample"], 32, "{report}");
}

#[test]
fn the_exported_page_renders_what_sdfc_render_renders() {
    if !tools_present("the exported page's render") {
        return;
    }
    let (w, h) = (160u32, 90u32);
    for scene in ["examples/capsule.sdf", "examples/normal_map.sdf"] {
        let dir = tempfile::tempdir().unwrap();
        let site = dir.path().join("site");
        export(scene, &site);
        let base = serve(site);
        let raw = dir.path().join("frame.rgba");
        let t = std::time::Instant::now();
        let report = page(&format!("{base}/index.html?size={w}x{h}"), Some(&raw));
        eprintln!(
            "{scene}: the page rendered in Chromium in {:.1?}",
            t.elapsed()
        );
        assert!(report["error"].is_null(), "{scene}: {report}");
        assert_eq!(
            report["messages"],
            serde_json::json!([]),
            "{scene}: Tint said something"
        );
        let browser = std::fs::read(&raw).unwrap();
        assert_eq!(browser.len(), (4 * w * h) as usize);
        let reference = dir.path().join("ref.png");
        let size = format!("{w}x{h}");
        let out_path = reference.to_str().unwrap();
        let args = [
            "render", scene, "--walk", "loop", "--size", &size, "-o", out_path,
        ];
        let (code, _, err) = common::sdfc(&args);
        assert_eq!(code, 0, "{scene}: {err}");
        let reference = image::open(&reference).unwrap().to_rgba8();
        let (mean, share) = common::image_difference(reference.as_raw(), &browser);
        eprintln!(
            "{scene}: browser against sdfc render: mean {mean:.3}/255, share over 16 {share:.4}"
        );
        // The reference-image tolerance of tests/gpu.rs.
        assert!(
            mean <= 1.5 && share <= 0.005,
            "{scene}: mean {mean}, share {share}"
        );
    }
}
