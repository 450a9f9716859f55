//! Limits and safety (docs/limits.md): what sdfc does to the user's files, which
//! files a scene may read, and how bad input and resource limits are reported.

use crate::common;

use common::{sdfc, sdfc_with_input};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const SCENE: &str = "let s = sphere(1);\nrender s { camera = orbit(); }\n";

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sdfc"))
}

/// A folder with `scene.sdf` in it.
fn scene_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.sdf"), SCENE).unwrap();
    dir
}

fn compile_to(dir: &Path, out: &Path) -> (i32, String) {
    let o = bin()
        .arg("compile")
        .arg(dir.join("scene.sdf"))
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

// ---- outputs ---------------------------------------------------------------------

#[cfg(unix)]
#[test]
fn output_through_a_symlink_replaces_the_target_and_keeps_the_link() {
    let dir = scene_dir();
    let target = dir.path().join("real.wgsl");
    std::fs::write(&target, "old").unwrap();
    let link = dir.path().join("link.wgsl");
    std::os::unix::fs::symlink("real.wgsl", &link).unwrap();
    let (code, err) = compile_to(dir.path(), &link);
    assert_eq!(code, 0, "{err}");
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::read_to_string(&target)
        .unwrap()
        .contains("fn fs_main"));
}

#[cfg(unix)]
#[test]
fn output_to_a_fifo_writes_through_it() {
    let dir = scene_dir();
    let fifo = dir.path().join("out.fifo");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let (code, err) = compile_to(dir.path(), &fifo);
    if code != 0 {
        // Unblock the reader before failing.
        drop(std::fs::OpenOptions::new().write(true).open(&fifo));
        let _ = reader.join();
        panic!("exit {code}: {err}");
    }
    let text = reader.join().unwrap();
    assert!(
        text.contains("fn fs_main"),
        "the reader got {} bytes",
        text.len()
    );
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
}

/// `-o /dev/fd/1` is `-o /dev/stdout` one link further (/dev/stdout links to
/// /proc/self/fd/1). The test does not name /dev/stdout itself: a broken build that
/// replaced its output's path would replace the test machine's /dev/stdout, while
/// /proc/self/fd cannot be written to.
#[cfg(target_os = "linux")]
#[test]
fn output_to_standard_output_goes_to_the_pipe() {
    let dir = scene_dir();
    let o = bin()
        .arg("compile")
        .arg(dir.path().join("scene.sdf"))
        .args(["-o", "/dev/fd/1"])
        .stdout(Stdio::piped())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).contains("fn fs_main"));
}

#[test]
fn output_to_a_folder_is_refused() {
    let dir = scene_dir();
    let (code, err) = compile_to(dir.path(), dir.path());
    assert_eq!(code, 2);
    assert!(err.contains("is a folder"), "{err}");
}

#[cfg(unix)]
#[test]
fn output_keeps_the_old_files_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scene_dir();
    let out = dir.path().join("out.wgsl");
    std::fs::write(&out, "old").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o600)).unwrap();
    assert_eq!(compile_to(dir.path(), &out).0, 0);
    let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600);
    let fresh = dir.path().join("fresh.wgsl");
    assert_eq!(compile_to(dir.path(), &fresh).0, 0);
    let mode = std::fs::metadata(&fresh).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o644);
}

/// A process killed mid-write leaves the old output whole and no temporary file in the
/// folder (the test hook pauses the write half-way).
#[cfg(target_os = "linux")]
#[test]
fn killed_mid_write_leaves_the_old_file_and_no_litter() {
    use std::io::BufRead;
    let dir = scene_dir();
    let out = dir.path().join("out.wgsl");
    std::fs::write(&out, "the old output").unwrap();
    let before = names(dir.path());
    let mut child = bin()
        .arg("compile")
        .arg(dir.path().join("scene.sdf"))
        .arg("-o")
        .arg(&out)
        .env("SDFC_TEST_PAUSE_WRITE", "1")
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    while stderr.read_line(&mut line).unwrap() > 0 && !line.contains("paused mid-write") {
        line.clear();
    }
    assert!(line.contains("paused mid-write"), "the hook never paused");
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "the old output");
    // Where the file system has unnamed temporary files (ext4, tmpfs, btrfs, xfs), none
    // is left; elsewhere the named fallback is, and the next write removes it.
    let unnamed = rustix::fs::open(
        dir.path(),
        rustix::fs::OFlags::TMPFILE | rustix::fs::OFlags::WRONLY,
        rustix::fs::Mode::from_raw_mode(0o600),
    )
    .is_ok();
    if unnamed {
        assert_eq!(
            names(dir.path()),
            before,
            "a temporary file was left behind"
        );
    } else {
        eprintln!("note: no O_TMPFILE on this file system: checking the named fallback");
        let left: Vec<String> = names(dir.path())
            .into_iter()
            .filter(|n| !before.contains(n))
            .collect();
        assert!(
            left.iter().all(|n| n.starts_with(".out.wgsl.sdfc-")),
            "{left:?}"
        );
        assert_eq!(compile_to(dir.path(), &out).0, 0);
        assert_eq!(names(dir.path()), before, "the stale file was not removed");
    }
}

/// Named temporary files of dead processes (left where unnamed files are unsupported)
/// are removed by the next write of the same output.
#[test]
fn stale_temporary_files_are_cleaned() {
    let dir = scene_dir();
    // No process has this id (above Linux's largest pid_max).
    let stale = dir.path().join(".out.wgsl.sdfc-4999999-abc123.tmp");
    std::fs::write(&stale, "half").unwrap();
    let mine = dir.path().join(".other.wgsl.sdfc-4999999-abc123.tmp");
    std::fs::write(&mine, "someone else's").unwrap();
    assert_eq!(compile_to(dir.path(), &dir.path().join("out.wgsl")).0, 0);
    assert!(!stale.exists());
    assert!(
        mine.exists(),
        "only the output's own temporary files are removed"
    );
}

// ---- textures: what a scene may read -----------------------------------------------

fn png_bytes() -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui/textures/bricks.png"))
        .unwrap()
}

/// (code, message) of each diagnostic of a scene binding `image(path)` in `dir`.
fn texture_diagnostics(dir: &Path, path: &str) -> Vec<(String, String)> {
    let src =
        format!("let t = image({path:?});\nlet s = sphere(1);\nrender s {{ camera = orbit(); }}\n");
    sdfc::driver::analyze(&src, Some(dir))
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| (d.code.to_string(), d.message.clone()))
        .collect()
}

fn one_error(dir: &Path, path: &str, code: &str, words: &str) {
    let d = texture_diagnostics(dir, path);
    assert_eq!(d.len(), 1, "{path}: {d:?}");
    assert_eq!(d[0].0, code, "{path}: {d:?}");
    assert!(
        d[0].1.contains(words),
        "{path}: {:?} lacks {words:?}",
        d[0].1
    );
}

/// A PNG header (signature, IHDR and an empty IDAT, CRCs included) that claims `w`×`h`.
fn png_header(w: u32, h: u32) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    let mut chunk = b"IHDR".to_vec();
    chunk.extend(w.to_be_bytes());
    chunk.extend(h.to_be_bytes());
    chunk.extend([8, 2, 0, 0, 0]);
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    out.extend(13u32.to_be_bytes());
    out.extend(&chunk);
    out.extend(crc32(&chunk).to_be_bytes());
    // An empty IDAT: the decoder reads up to the first image data for the header.
    out.extend(0u32.to_be_bytes());
    out.extend(b"IDAT");
    out.extend(crc32(b"IDAT").to_be_bytes());
    out
}

#[test]
fn texture_contents_are_checked_at_check_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("ok.png"), png_bytes()).unwrap();
    std::fs::write(d.join("text.png"), "hello, not an image\n").unwrap();
    std::fs::write(d.join("empty.png"), "").unwrap();
    std::fs::write(d.join("cut.png"), &png_bytes()[..20]).unwrap();
    std::fs::write(d.join("huge.png"), png_header(20000, 20000)).unwrap();
    std::fs::create_dir(d.join("folder.png")).unwrap();
    assert_eq!(texture_diagnostics(d, "ok.png"), vec![]);
    one_error(d, "text.png", "E0304", "cannot read texture \"text.png\"");
    one_error(d, "empty.png", "E0304", "header");
    one_error(d, "cut.png", "E0304", "header");
    one_error(d, "huge.png", "E0304", "20000×20000; the limit is 8192");
    one_error(d, "folder.png", "E0306", "is a folder");
    one_error(d, "missing.png", "E0303", "not found");
}

#[cfg(unix)]
#[test]
fn special_files_are_refused_without_opening_them() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.png");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    // Opening a FIFO for reading would block this test forever.
    one_error(dir.path(), "pipe.png", "E0306", "a FIFO");
}

/// Absolute paths, `../` escapes and symbolic links that lead out are refused with the
/// same words whether or not the file exists.
#[cfg(unix)]
#[test]
fn paths_outside_the_scene_folder_are_refused_without_disclosure() {
    let root = tempfile::tempdir().unwrap();
    let scene = root.path().join("scene");
    std::fs::create_dir_all(scene.join("sub")).unwrap();
    std::fs::write(root.path().join("secret.png"), png_bytes()).unwrap();
    std::os::unix::fs::symlink(root.path().join("secret.png"), scene.join("out.png")).unwrap();
    std::os::unix::fs::symlink(root.path().join("none.png"), scene.join("dangling.png")).unwrap();
    std::os::unix::fs::symlink("/etc/passwd", scene.join("passwd.png")).unwrap();
    std::fs::write(scene.join("sub/in.png"), png_bytes()).unwrap();
    std::os::unix::fs::symlink("sub/in.png", scene.join("inside.png")).unwrap();
    let secret = root.path().join("secret.png");
    let missing = root.path().join("none.png");
    let refused = [
        "../secret.png".to_string(),
        "../none.png".to_string(),
        secret.display().to_string(),
        missing.display().to_string(),
        "out.png".to_string(),
        "dangling.png".to_string(),
        "passwd.png".to_string(),
        "sub/../../secret.png".to_string(),
    ];
    let mut messages = Vec::new();
    for p in &refused {
        let d = texture_diagnostics(&scene, p);
        assert_eq!(d.len(), 1, "{p}: {d:?}");
        assert_eq!(d[0].0, "E0306", "{p}: {d:?}");
        messages.push(d[0].1.replace(p.as_str(), "PATH"));
    }
    messages.dedup();
    assert_eq!(messages.len(), 1, "the refusals differ: {messages:?}");
    assert_eq!(texture_diagnostics(&scene, "inside.png"), vec![]);
    assert_eq!(texture_diagnostics(&scene, "sub/in.png"), vec![]);
    assert_eq!(texture_diagnostics(&scene, "./sub/../sub/in.png"), vec![]);
}

#[test]
fn allow_path_widens_what_a_scene_may_read() {
    let root = tempfile::tempdir().unwrap();
    let scene = root.path().join("scene");
    let shared = root.path().join("shared");
    std::fs::create_dir_all(&scene).unwrap();
    std::fs::create_dir_all(&shared).unwrap();
    std::fs::write(shared.join("t.png"), png_bytes()).unwrap();
    let src =
        "let t = image(\"../shared/t.png\");\nlet s = sphere(1);\nrender s { camera = orbit(); }\n";
    std::fs::write(scene.join("s.sdf"), src).unwrap();
    let run = |extra: &[&Path]| {
        let mut cmd = bin();
        for p in extra {
            cmd.arg("--allow-path").arg(p);
        }
        let o = cmd.arg("check").arg(scene.join("s.sdf")).output().unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, err) = run(&[]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("E0306") && err.contains("--allow-path"),
        "{err}"
    );
    let (code, err) = run(&[&shared]);
    assert_eq!(code, Some(0), "{err}");
}

// ---- input text --------------------------------------------------------------------

#[test]
fn a_byte_order_mark_is_accepted_and_kept_by_fmt() {
    let src = format!("\u{feff}{SCENE}");
    let a = sdfc::driver::analyze(&src, None);
    assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
    let formatted = sdfc::ide::format::format(&src).unwrap();
    assert!(formatted.starts_with('\u{feff}'));
}

#[test]
fn invalid_utf8_is_a_spanned_error_with_its_byte_offset() {
    let mut bytes = b"let s = sphere(1);\nlet x = \"".to_vec();
    bytes.extend([0xff, 0xfe]);
    bytes.extend(b"\";\nrender s { camera = orbit(); }\n");
    let (code, _, err) = sdfc_with_input(&["check", "-"], &bytes);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("error[E0005]: invalid UTF-8 at byte 28: 0xff 0xfe"),
        "{err}"
    );
    assert!(err.contains("-:2:10"), "no position: {err}");
    // Reported once, not again as an unexpected character.
    assert_eq!(err.matches("error[").count(), 1, "{err}");
}

#[test]
fn a_run_of_nul_bytes_gives_a_short_message() {
    let bytes = vec![0u8; 1 << 20];
    let (code, _, err) = sdfc_with_input(&["check", "-"], &bytes);
    assert_eq!(code, 1);
    assert!(err.contains("E0001"), "{}", &err[..err.len().min(500)]);
    assert!(err.len() < 4000, "{} bytes of messages", err.len());
    assert!(err.contains("more characters"), "{err}");
}

#[test]
fn an_oversized_file_is_refused_with_the_limit() {
    let mut src = String::from("let s = sphere(1);\n");
    while src.len() <= sdfc::syntax::MAX_SOURCE_BYTES {
        src.push_str("// padding padding padding padding padding padding padding padding\n");
    }
    let (code, _, err) = sdfc_with_input(&["check", "-"], src.as_bytes());
    assert_eq!(code, 1);
    assert!(
        err.contains("E0006") && err.contains("limit of 8 MiB"),
        "{err}"
    );
}

#[test]
fn check_of_a_folder_checks_its_scene_files() {
    let (code, _, err) = sdfc(&["check", "examples"]);
    assert_eq!(code, 0, "{err}");
    let n = std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "sdf")
        })
        .count();
    assert!(
        err.contains(&format!("checked {n} files: 0 errors")),
        "{err}"
    );
    let empty = tempfile::tempdir().unwrap();
    let (code, _, err) = sdfc(&["check", empty.path().to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("no .sdf files"), "{err}");
    assert!(!err.contains("checked"), "{err}");
}

/// Diagnostics per file are capped; the JSON lines end with the note that counts the
/// rest.
#[test]
fn diagnostics_are_capped_per_file() {
    let mut src = String::new();
    for i in 0..3000 {
        src.push_str(&format!("let a{i} = nope{i};\n"));
    }
    let (code, out, _) = sdfc_with_input(&["check", "--format", "json", "-"], src.as_bytes());
    assert_eq!(code, 1);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), sdfc::diagnostic::MAX_DIAGNOSTICS + 1);
    let last: serde_json::Value = serde_json::from_str(lines.last().unwrap()).unwrap();
    assert_eq!(last["code"], "N0002");
    assert!(last["message"]
        .as_str()
        .unwrap()
        .contains("more diagnostics"));
}

// ---- exit codes for resources --------------------------------------------------------

#[test]
fn render_sizes_beyond_the_limits_are_refused() {
    let (code, _, err) = sdfc(&["render", "examples/sphere.sdf", "--size", "100000x100000"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("16384x16384"), "{err}");
}

/// A render too large for the GPU's memory limit exits 5 and names the limit, before
/// anything is allocated.
#[test]
fn render_over_the_memory_limit_is_a_resource_error() {
    let out: PathBuf = tempfile::tempdir().unwrap().path().join("x.png");
    let (code, _, err) = sdfc(&[
        "render",
        "examples/sphere.sdf",
        "--size",
        "16384x16384",
        "-o",
        out.to_str().unwrap(),
    ]);
    if code == 4 && std::env::var("SDFC_REQUIRE_GPU").as_deref() != Ok("1") {
        eprintln!("SKIPPED: no GPU adapter ({err})");
        return;
    }
    assert_eq!(code, 5, "{err}");
    assert!(err.contains("limit"), "{err}");
    assert!(!out.exists());
}

/// An internal-compiler-error report has a predictable name in the shared temporary
/// folder: a symbolic link planted there is replaced, never followed.
#[cfg(unix)]
#[test]
fn ice_reports_do_not_follow_planted_links() {
    let tmp = tempfile::tempdir().unwrap();
    let victim = tmp.path().join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    let report = tmp.path().join("sdfc-ice-scene.wgsl");
    std::os::unix::fs::symlink(&victim, &report).unwrap();
    sdfc::fsutil::replace_file(&report, b"fn broken(").unwrap();
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert!(!std::fs::symlink_metadata(&report)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read_to_string(&report).unwrap(), "fn broken(");
}
