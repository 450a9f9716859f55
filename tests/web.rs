//! Compiled scenes in a real browser: headless Chromium (Debian's `chromium`, WebGPU
//! on SwiftShader, Tint as the WGSL compiler) driven by `tools/browser/page.mjs`
//! (puppeteer-core, installed by `npm ci` from its lockfile), pages served from
//! http://127.0.0.1 by a small file server in this test.
//!
//! - Every example (loop walk, and `sphere.sdf` unrolled too) compiles in Tint with no
//!   message, and its render pipeline builds with one bind group layout per group from
//!   the manifest's users alone, on a device with WebGPU's default limits; so do the
//!   compute pipelines of the modules that hold what changes them (the test says
//!   which, and why not all).
//! - The page `sdfc export-web` writes renders `capsule.sdf`, `normal_map.sdf`, the
//!   displaced, shell-mapped and many-seed examples and an animated one (its first frame, `?still`)
//!   within the reference-image tolerance of `sdfc render` at the same size.
//!
//! Without Chromium, Node or puppeteer-core the tests say so and skip, unless
//! `SDFC_REQUIRE_TOOLS=1` (as in CI), which makes that a failure.

use crate::common;

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
    export_args(scene, dir, &["--walk", walk]);
}

fn export_args(scene: &str, dir: &Path, extra: &[&str]) {
    let args = ["export-web", scene, "-o", dir.to_str().unwrap()];
    let (code, _, err) = common::sdfc(&[&args[..], extra].concat());
    assert_eq!(code, 0, "{scene}: {err}");
}

/// Runs the page script on `url`; its JSON line.
fn page(url: &str, raw: Option<&Path>) -> serde_json::Value {
    page_with(url, raw, false)
}

/// [`page`], with real mouse input on the canvas after the first frame when `input`.
fn page_with(url: &str, raw: Option<&Path>, input: bool) -> serde_json::Value {
    let mut cmd = Command::new("node");
    cmd.arg(tool().join("page.mjs")).arg(url);
    cmd.env("SDFC_PAGE_INPUT", if input { "1" } else { "0" });
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
    // And one with the multi-scale pass: cs_coarse's pipeline from its manifest users.
    export_args(
        "examples/robot.sdf",
        &root.path().join("robot_multiscale"),
        &["--walk", "loop", "--multiscale"],
    );
    names.push("robot_multiscale".into());
    // SwiftShader compiles a compute pipeline to machine code when it is created (a
    // render pipeline waits for its first draw), and those builds were 70 % of this
    // check (88 of 121 s on 2 cores). Tint's front end reads every entry point of every
    // module (createShaderModule), every module's fs_main goes through Tint's back end
    // (the unrolled walk's too), and
    // `manifest::pipelines_build_with_layouts_from_the_manifest_users_alone` builds
    // every entry point of every example from its manifest on wgpu. The compute entry
    // points are built here on the modules that hold what changes their bindings or
    // their code: a field that reads a texture (displacement), run-time parameters and
    // time, and the multi-scale pass (cs_coarse) with a merge graph.
    const COMPUTE_ON: [&str; 3] = ["displaced_sphere", "animated_bar", "robot_multiscale"];
    for name in COMPUTE_ON {
        assert!(
            names.iter().any(|n| n == name),
            "{name} is not a module here"
        );
    }
    let queue: Vec<serde_json::Value> = names
        .iter()
        .map(|n| serde_json::json!({ "name": n, "compute": COMPUTE_ON.contains(&n.as_str()) }))
        .collect();
    std::fs::write(
        root.path().join("modules.json"),
        serde_json::to_vec(&queue).unwrap(),
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
        // What was built: fs_main everywhere, every compute entry point where asked.
        let built: Vec<&str> = m["built"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b.as_str().unwrap())
            .collect();
        let compute = built.iter().filter(|b| b.starts_with("cs_")).count();
        let asked = COMPUTE_ON.contains(&m["name"].as_str().unwrap());
        let (fs, cs) = (
            built.contains(&"fs_main"),
            if asked { compute >= 5 } else { compute == 0 },
        );
        assert!(fs && cs, "{m}");
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
    for scene in [
        "examples/capsule.sdf",
        "examples/normal_map.sdf",
        "examples/displaced_column.sdf",
        "examples/shell_tiles.sdf",
        "examples/robot.sdf",
        "examples/waving_robot.sdf",
    ] {
        let dir = tempfile::tempdir().unwrap();
        let site = dir.path().join("site");
        export(scene, &site);
        let base = serve(site);
        let raw = dir.path().join("frame.rgba");
        // The first scene also takes real mouse input: its orbit controls.
        let input = ["examples/capsule.sdf", "examples/waving_robot.sdf"].contains(&scene);
        let t = std::time::Instant::now();
        let report = page_with(
            &format!("{base}/index.html?size={w}x{h}&still"),
            Some(&raw),
            input,
        );
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
        let size = format!("{w}x{h}");
        let reference = common::render_as_library(scene, &size, &[], &dir.path().join("ref.png"));
        let (mean, share) = common::image_difference(reference.as_raw(), &browser);
        eprintln!(
            "{scene}: browser against sdfc render: mean {mean:.3}/255, share over 16 {share:.4}"
        );
        // The reference-image tolerance of tests/gpu.rs.
        assert!(
            mean <= 1.5 && share <= 0.005,
            "{scene}: mean {mean}, share {share}"
        );
        if input {
            // A drag turns the camera and the wheel zooms: each frame differs from
            // the one before.
            let dragged = std::fs::read(dir.path().join("frame.rgba.drag")).unwrap();
            let zoomed = std::fs::read(dir.path().join("frame.rgba.wheel")).unwrap();
            let (turned, _) = common::image_difference(&browser, &dragged);
            let (closer, _) = common::image_difference(&dragged, &zoomed);
            eprintln!("{scene}: a drag changed the frame by {turned:.2}/255, the wheel by {closer:.2}/255");
            assert!(
                turned > 2.0 && closer > 2.0,
                "{scene}: drag {turned}, wheel {closer}"
            );
            // A scene with parameters has a slider each: moving one redraws.
            let slider = dir.path().join("frame.rgba.slider");
            if scene.contains("waving_robot") {
                let slid = std::fs::read(&slider).expect("a slider for `blend`");
                let (moved, _) = common::image_difference(&zoomed, &slid);
                eprintln!("{scene}: the first slider changed the frame by {moved:.2}/255");
                assert!(moved > 0.2, "{scene}: the slider changed {moved}");
            } else {
                assert!(!slider.exists(), "{scene} has no parameters, so no slider");
            }
        }
    }
}

#[test]
fn the_exported_page_runs_the_multiscale_pass_as_sdfc_render_does() {
    if !tools_present("the exported page's multi-scale pass") {
        return;
    }
    let (w, h) = (320u32, 240u32);
    let size = format!("{w}x{h}");
    let scene = "examples/sphere.sdf";
    let dir = tempfile::tempdir().unwrap();
    let (with, without) = (dir.path().join("with"), dir.path().join("without"));
    export_args(scene, &with, &["--walk", "loop", "--multiscale"]);
    export(scene, &without);
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(with.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["coarse"]["entry_point"], "cs_coarse");
    // A frame of the page in `view` (0 colour, 15 walked), and `sdfc render`'s.
    let frame = |site: &Path, view: u32| {
        let base = serve(site.to_path_buf());
        let raw = dir.path().join("frame.rgba");
        let url = format!("{base}/index.html?size={size}&still&view={view}");
        let report = page(&url, Some(&raw));
        assert!(report["error"].is_null(), "{report}");
        assert_eq!(
            report["messages"],
            serde_json::json!([]),
            "Tint said something"
        );
        std::fs::read(&raw).unwrap()
    };
    let render = |view: &str, multiscale: &str| {
        let extra = ["--view", view, "--multiscale", multiscale];
        common::render_as_library(scene, &size, &extra, &dir.path().join("ref.png")).into_raw()
    };
    // The walked view: rebuilt pixels green, walked ones red.
    let green = |px: &[u8]| {
        px.chunks(4)
            .filter(|p| p[1] as i32 > p[0] as i32 + 60)
            .count()
    };
    let red = |px: &[u8]| {
        px.chunks(4)
            .filter(|p| p[0] as i32 > p[1] as i32 + 60)
            .count()
    };
    let walked = frame(&with, 15);
    let reference = render("walked", "on");
    let (g, r) = (green(&walked), red(&walked));
    let (g_ref, r_ref) = (green(&reference), red(&reference));
    eprintln!("walked view: browser {g} rebuilt, {r} walked; sdfc render {g_ref}, {r_ref}");
    // SwiftShader and lavapipe round differently, so a few decisions differ.
    assert!(g_ref > 1000, "sdfc render rebuilt {g_ref}");
    assert!(
        g.abs_diff(g_ref) * 20 <= g_ref && r.abs_diff(r_ref) * 5 <= r_ref.max(100),
        "browser {g}/{r}, render {g_ref}/{r_ref}"
    );
    // Without the pass every pixel that reads the atlas walks.
    let plain = frame(&without, 15);
    assert_eq!(green(&plain), 0, "a page without the pass rebuilt pixels");
    // The colour with the pass, against sdfc render's with it.
    let colour = frame(&with, 0);
    let (mean, share) = common::image_difference(&render("color", "on"), &colour);
    eprintln!("colour with the pass: browser against sdfc render: mean {mean:.3}/255, share over 16 {share:.4}");
    assert!(mean <= 1.5 && share <= 0.005, "mean {mean}, share {share}");
}

/// `sdfc serve` running on a scene, on a free port of 127.0.0.1; killed when dropped.
struct Served {
    child: std::process::Child,
    /// `127.0.0.1:PORT`.
    addr: String,
    /// Its standard error after the line that says where (drained by a thread).
    log: std::sync::Arc<std::sync::Mutex<String>>,
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Served {
    fn start(scene: &Path) -> Served {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sdfc"))
            .args(["serve", scene.to_str().unwrap(), "--port", "0"])
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut reader = BufReader::new(child.stderr.take().unwrap());
        let mut said = String::new();
        let addr = loop {
            let mut line = String::new();
            if reader.read_line(&mut line).unwrap_or(0) == 0 {
                let _ = child.kill();
                panic!("sdfc serve ended before serving:\n{said}");
            }
            said.push_str(&line);
            if let Some(at) = line.strip_prefix("serving ") {
                let url = at.split(" at http://").nth(1).expect("a URL");
                break url.split('/').next().unwrap().to_string();
            }
        };
        let log = std::sync::Arc::new(std::sync::Mutex::new(said));
        let sink = log.clone();
        std::thread::spawn(move || {
            let mut line = String::new();
            while reader.read_line(&mut line).unwrap_or(0) > 0 {
                sink.lock().unwrap().push_str(&line);
                line.clear();
            }
        });
        Served { child, addr, log }
    }

    /// Sends `request` as it is; the status and the body.
    fn raw(&self, request: &str) -> (u16, Vec<u8>) {
        use std::io::Read;
        let mut s = std::net::TcpStream::connect(&self.addr).unwrap();
        s.write_all(request.as_bytes()).unwrap();
        let mut out = Vec::new();
        let _ = s.read_to_end(&mut out);
        let end = out
            .windows(4)
            .position(|w| w == b"\r\n\r\n")
            .unwrap_or_else(|| panic!("no head in {:?}", String::from_utf8_lossy(&out)));
        let status = String::from_utf8_lossy(&out[9..12]).parse().unwrap();
        (status, out[end + 4..].to_vec())
    }

    fn get(&self, path: &str) -> (u16, Vec<u8>) {
        let host = &self.addr;
        self.raw(&format!("GET {path} HTTP/1.1\r\nHost: {host}\r\n\r\n"))
    }
}

/// A folder with `capsule.sdf` and its texture: a scene to serve or render.
fn capsule_site(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir.join("textures")).unwrap();
    std::fs::copy(
        "examples/textures/bricks.png",
        dir.join("textures/bricks.png"),
    )
    .unwrap();
    let scene = dir.join("capsule.sdf");
    std::fs::copy("examples/capsule.sdf", &scene).unwrap();
    scene
}

#[test]
fn serve_answers_only_for_the_page_and_the_scene_folder() {
    let dir = tempfile::tempdir().unwrap();
    let site = dir.path().join("site");
    let scene = capsule_site(&site);
    let secret = dir.path().join("secret.txt");
    std::fs::write(&secret, "outside").unwrap();
    std::os::unix::fs::symlink("../secret.txt", site.join("link.txt")).unwrap();
    std::os::unix::fs::symlink("..", site.join("up")).unwrap();
    std::fs::write(site.join(".hidden"), "hidden").unwrap();
    let served = Served::start(&scene);
    // The page, its files from memory, and the scene's folder.
    let (code, page) = served.get("/");
    assert_eq!(code, 200);
    assert!(String::from_utf8_lossy(&page).contains("const live = true;"));
    let (code, wgsl) = served.get("/scene.wgsl");
    assert_eq!(code, 200);
    assert!(String::from_utf8_lossy(&wgsl).contains("fn fs_main"));
    assert_eq!(served.get("/gen/1/scene.wgsl"), (200, wgsl));
    assert_eq!(served.get("/gen/2/scene.wgsl").0, 410);
    assert_eq!(served.get("/textures/0/0.png").0, 200);
    let own = std::fs::read(&scene).unwrap();
    assert_eq!(served.get("/capsule.sdf"), (200, own));
    let png = std::fs::read(site.join("textures/bricks.png")).unwrap();
    assert_eq!(served.get("/textures/bricks.png"), (200, png));
    // Out of the folder, however written, and a missing file: the same 404.
    let missing = served.get("/missing.txt");
    assert_eq!(missing.0, 404);
    let absolute = format!("/{}", secret.display());
    for path in [
        "/../secret.txt",
        "/%2e%2e/secret.txt",
        "/%2E%2E%2Fsecret.txt",
        "/textures/%2e%2e/%2e%2e/secret.txt",
        "/link.txt",
        "/up/secret.txt",
        "/.hidden",
        absolute.as_str(),
        &format!("/{}", secret.display().to_string().replace('/', "%2F")),
    ] {
        assert_eq!(served.get(path), missing, "{path}");
    }
    // GET and HEAD only; a bounded head; loopback names only.
    let host = served.addr.clone();
    let (code, body) = served.raw(&format!(
        "HEAD /scene.wgsl HTTP/1.1\r\nHost: {host}\r\n\r\n"
    ));
    assert_eq!((code, body.len()), (200, 0));
    for method in ["POST", "PUT", "DELETE"] {
        let r = served.raw(&format!("{method} / HTTP/1.1\r\nHost: {host}\r\n\r\n"));
        assert_eq!(r.0, 405, "{method}");
    }
    let big = "x".repeat(16 << 10);
    let r = served.raw(&format!(
        "GET / HTTP/1.1\r\nHost: {host}\r\nX: {big}\r\n\r\n"
    ));
    assert_eq!(r.0, 431);
    assert_eq!(
        served.raw("GET / HTTP/1.1\r\nHost: example.com\r\n\r\n").0,
        421
    );
    // The event stream starts with the state: the first good build.
    let mut events = std::net::TcpStream::connect(&served.addr).unwrap();
    write!(events, "GET /events HTTP/1.1\r\nHost: {host}\r\n\r\n").unwrap();
    events
        .set_read_timeout(Some(std::time::Duration::from_secs(20)))
        .unwrap();
    let mut reader = BufReader::new(events);
    let mut stream = String::new();
    while !stream.contains("\ndata: ") {
        assert!(reader.read_line(&mut stream).unwrap() > 0, "{stream}");
    }
    reader.read_line(&mut stream).unwrap();
    assert!(
        stream.contains("text/event-stream")
            && stream.contains("event: scene\ndata: {\"generation\":1,"),
        "{stream}"
    );
    // A change to the texture the scene reads is a new build, told to the stream.
    let bricks = site.join("textures/bricks.png");
    let mut image = image::open(&bricks).unwrap().to_rgba8();
    image::imageops::invert(&mut image);
    let tmp = site.join("textures/new.png");
    image.save(&tmp).unwrap();
    std::fs::rename(&tmp, &bricks).unwrap();
    let mut more = String::new();
    let t = std::time::Instant::now();
    while !more.contains("event: scene\ndata: {\"generation\":2,") {
        let n = reader.read_line(&mut more).unwrap_or(0);
        let late = t.elapsed().as_secs() > 30;
        assert!(
            n > 0 && !late,
            "no new build after the texture changed: {more}"
        );
    }
}

#[test]
fn serve_says_when_the_port_is_taken() {
    let taken = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port().to_string();
    let (code, _, err) = common::sdfc(&["serve", "examples/sphere.sdf", "--port", &port]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot listen on 127.0.0.1:"), "{err}");
    let (code, _, err) = common::sdfc(&["serve", "examples/no_such.sdf"]);
    assert_eq!(code, 2, "{err}");
}

/// Writes `text` over `path` the way editors do: a new file renamed over the old.
fn save(path: &Path, text: &str) {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

/// `sdfc render` of `text` (beside a copy of the capsule's texture) at `w`×`h`.
fn reference(dir: &Path, text: &str, (w, h): (u32, u32)) -> Vec<u8> {
    let scene = capsule_site(dir);
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("ref.png");
    let size = format!("{w}x{h}");
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--walk",
        "loop",
        "--size",
        &size,
        "-o",
        out.to_str().unwrap(),
    ];
    let (code, _, err) = common::sdfc(&args);
    assert_eq!(code, 0, "{err}");
    image::open(&out).unwrap().to_rgba8().into_raw()
}

#[test]
fn serve_reloads_the_page_on_edits_and_keeps_the_picture_on_errors() {
    if !tools_present("sdfc serve in a browser") {
        return;
    }
    let (w, h) = (160u32, 90u32);
    let dir = tempfile::tempdir().unwrap();
    let scene = capsule_site(&dir.path().join("site"));
    let original = std::fs::read_to_string(&scene).unwrap();
    // The edit makes the radius a slider (at 0.8).
    let edited = original.replace("let radius = 0.5;", "param radius = 0.8 in [0.3, 1];");
    let broken = edited.replace("param radius = 0.8 in [0.3, 1];", "let radius = ;");
    assert!(edited != original && broken != edited);
    let refs = [
        reference(&dir.path().join("ref0"), &original, (w, h)),
        reference(&dir.path().join("ref1"), &edited, (w, h)),
    ];
    // The edit changes the picture by more than twice the tolerance below.
    let (mean, _) = common::image_difference(&refs[0], &refs[1]);
    assert!(mean > 3.0, "the edit changes little: mean {mean}");
    let served = Served::start(&scene);
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let t = std::time::Instant::now();
    let mut node = Command::new("node")
        .arg(tool().join("page.mjs"))
        .arg("live")
        .arg(format!("http://{}/index.html?size={w}x{h}", served.addr))
        .arg(&frames)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut to_page = node.stdin.take().unwrap();
    let mut from_page = BufReader::new(node.stdout.take().unwrap());
    let mut next = |k: usize| -> (serde_json::Value, Vec<u8>) {
        let mut line = String::new();
        from_page.read_line(&mut line).unwrap();
        let report: serde_json::Value = serde_json::from_str(&line)
            .unwrap_or_else(|e| panic!("{e}: {line:?}\nserver: {}", served.log.lock().unwrap()));
        assert!(report["error"].is_null(), "{report}");
        eprintln!("serve: report {k} after {:.1?}", t.elapsed());
        let px = std::fs::read(frames.join(format!("{k}.rgba"))).unwrap();
        assert_eq!(px.len(), (4 * w * h) as usize);
        (report, px)
    };
    let close = |px: &[u8], reference: &[u8], what: &str| {
        let (mean, share) = common::image_difference(reference, px);
        eprintln!(
            "serve: {what} against sdfc render: mean {mean:.3}/255, share over 16 {share:.4}"
        );
        assert!(
            mean <= 1.5 && share <= 0.005,
            "{what}: mean {mean}, share {share}"
        );
    };
    // The first build, read from the canvas itself.
    let (first, px0) = next(0);
    assert_eq!(first["generation"], 1, "{first}");
    assert_eq!(
        first["messages"],
        serde_json::json!([]),
        "Tint said something"
    );
    close(&px0, &refs[0], "the first build");
    // An edit reaches the page: a new generation, the edited picture.
    save(&scene, &edited);
    writeln!(to_page, "window.sdfcGeneration > 1").unwrap();
    let (second, px1) = next(1);
    assert_eq!(second["generation"], 2, "{second}");
    assert!(second["overlay"].is_null(), "{second}");
    // The new parameter has its slider on the page (the first build had none).
    assert_eq!(first["sliders"], serde_json::json!([]), "{first}");
    assert_eq!(second["sliders"], serde_json::json!(["radius"]), "{second}");
    close(&px1, &refs[1], "the edited build");
    // A broken edit: its diagnostics on the page, the last good picture kept.
    save(&scene, &broken);
    writeln!(to_page, "window.sdfcDiagnostics").unwrap();
    let (third, px2) = next(2);
    assert_eq!(third["generation"], 2, "{third}");
    assert_eq!(
        third["diagnostics"]["diagnostics"][0]["code"], "E0010",
        "{third}"
    );
    assert_eq!(
        third["diagnostics"]["diagnostics"][0]["start"]["line"], 3,
        "{third}"
    );
    let overlay = third["overlay"].as_str().unwrap_or_default();
    assert!(
        overlay.contains("error[E0010]: expected an expression")
            && overlay.contains("let radius = ;"),
        "{third}"
    );
    assert!(px2 == px1, "the picture changed after a broken edit");
    drop(to_page);
    assert!(node.wait().unwrap().success());
    let log = served.log.lock().unwrap().clone();
    assert!(
        log.contains("not rebuilt; the page keeps generation 2"),
        "{log}"
    );
}
