//! Output files. Every file sdfc writes goes through [`write_output`], which decides by
//! what the path is:
//!
//! - a regular file, or nothing yet: written **atomically**. The bytes go to an unnamed
//!   file in the destination's folder (`O_TMPFILE` on Linux), which is given a name and
//!   renamed over the destination only once complete, so a reader never sees half a file
//!   and a process killed mid-write leaves the old file intact and no litter. Where
//!   unnamed files are not supported, a named `.NAME.sdfc-PID-*.tmp` file is used, and
//!   stale ones of dead processes are removed by the next write to the same output.
//!   The new file keeps the old one's permissions (0644 for a new one).
//! - a symbolic link: followed; its target is written by these rules and the link stays.
//! - a character device or a FIFO (`/dev/stdout`, `/dev/null`, a named pipe): written
//!   through directly, never replaced.
//! - a folder, a block device or a socket: refused with a clear error.
//! - anything under `/dev` or `/proc` (`/dev/stdout` when the shell redirected it to a
//!   file): written through, never replaced.

use std::io::Write;
use std::path::{Path, PathBuf};

/// How many symbolic links [`write_output`] follows before it gives up (as Linux does).
const MAX_LINKS: usize = 40;

/// Writes `bytes` to `path` by the rules of this module. The error says what went wrong
/// in words fit for the user (the path is not repeated).
pub fn write_output(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    // What the path finally is, links followed by the kernel (which also follows
    // /proc's links to pipes and terminals, as /dev/stdout is).
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_dir() => Err(refused("is a folder; give a file name")),
        // /dev/stdout, /dev/fd/N and the like are written through even when they lead
        // to a regular file: replacing the file would cut it off from the shell's
        // redirection.
        Ok(meta) if is_stream(&meta.file_type()) || is_system(path) => write_through(path, bytes),
        Ok(meta) if meta.is_file() => {
            write_atomic(&follow_links(path)?, bytes, Some(meta.permissions()))
        }
        Ok(_) => Err(refused(
            "is not a regular file, a character device or a FIFO; sdfc writes only to those",
        )),
        // Nothing there yet (perhaps the target of a dangling link): create it.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            write_atomic(&follow_links(path)?, bytes, None)
        }
        Err(e) => Err(e),
    }
}

/// Replaces the file at `path` atomically without following a symbolic link or
/// writing through a device or FIFO found there (whatever is at `path` is replaced):
/// for files with predictable names in shared folders, such as internal-compiler-error
/// reports in the temporary folder, where a link planted by someone else must not
/// redirect the write.
pub fn replace_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.is_dir()) {
        return Err(refused("is a folder; give a file name"));
    }
    write_atomic(path, bytes, None)
}

/// Paths the system owns (`/dev/…`, `/proc/…`): never replaced, only written to.
fn is_system(path: &Path) -> bool {
    path.starts_with("/dev") || path.starts_with("/proc")
}

fn write_through(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut file = std::fs::OpenOptions::new().write(true).open(path)?;
    file.write_all(bytes)?;
    file.flush()
}

fn refused(why: &str) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, why.to_string())
}

#[cfg(unix)]
fn is_stream(kind: &std::fs::FileType) -> bool {
    use std::os::unix::fs::FileTypeExt;
    kind.is_char_device() || kind.is_fifo()
}

#[cfg(not(unix))]
fn is_stream(_: &std::fs::FileType) -> bool {
    false
}

/// The path a chain of symbolic links ends at (the path itself when it is not a link).
/// The end need not exist: a dangling link's target is created.
pub fn follow_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut path = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&path)?;
                path = match path.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            _ => return Ok(path),
        }
    }
    Err(refused("is a chain of too many symbolic links"))
}

fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The prefix of the named temporary files of an output: `.NAME.sdfc-`.
fn temp_prefix(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    format!(".{name}.sdfc-")
}

fn write_atomic(
    path: &Path,
    bytes: &[u8],
    permissions: Option<std::fs::Permissions>,
) -> std::io::Result<()> {
    let dir = folder_of(path);
    if !dir.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!("its folder {} does not exist", dir.display()),
        ));
    }
    remove_stale(dir, &temp_prefix(path));
    #[cfg(target_os = "linux")]
    if let Some(result) = linux::write_unnamed(dir, path, bytes, permissions.clone()) {
        return result;
    }
    write_named(dir, path, bytes, permissions)
}

/// The portable way: a named temporary file beside the destination, renamed over it.
fn write_named(
    dir: &Path,
    path: &Path,
    bytes: &[u8],
    permissions: Option<std::fs::Permissions>,
) -> std::io::Result<()> {
    let mut tmp = tempfile::Builder::new()
        .prefix(&format!("{}{}-", temp_prefix(path), std::process::id()))
        .suffix(".tmp")
        .tempfile_in(dir)?;
    set_permissions(tmp.as_file(), permissions)?;
    write_pausable(tmp.as_file_mut(), bytes)?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Gives a new output file the old one's permissions, or 0644 (temporary files are
/// created private).
fn set_permissions(
    file: &std::fs::File,
    permissions: Option<std::fs::Permissions>,
) -> std::io::Result<()> {
    match permissions {
        Some(p) => file.set_permissions(p),
        None => readable(file),
    }
}

/// Sets a file's permissions to 0644.
pub fn readable(file: &std::fs::File) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        file.set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    #[cfg(not(unix))]
    let _ = file;
    Ok(())
}

/// Removes named temporary files `PREFIX<pid>-*.tmp` left in `dir` by processes that no
/// longer run (killed mid-write). Best effort: errors are ignored.
fn remove_stale(dir: &Path, prefix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(prefix)) else {
            continue;
        };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if rest.ends_with(".tmp") && !process_alive(pid) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    #[cfg(target_os = "linux")]
    {
        Path::new("/proc").join(pid.to_string()).exists()
    }
    #[cfg(not(target_os = "linux"))]
    {
        true
    }
}

/// Writes `bytes`; with `SDFC_TEST_PAUSE_WRITE` set (the atomic-write tests), writes
/// half, says so on stderr and sleeps, so a test can kill the process mid-write.
fn write_pausable(file: &mut std::fs::File, bytes: &[u8]) -> std::io::Result<()> {
    if std::env::var_os("SDFC_TEST_PAUSE_WRITE").is_some() {
        let half = bytes.len() / 2;
        file.write_all(&bytes[..half])?;
        file.flush()?;
        eprintln!("sdfc-test: paused mid-write");
        std::thread::sleep(std::time::Duration::from_secs(60));
        return file.write_all(&bytes[half..]);
    }
    file.write_all(bytes)
}

#[cfg(target_os = "linux")]
mod linux {
    use rustix::fs::{AtFlags, Mode, OFlags, CWD};
    use std::path::Path;

    /// Writes through an `O_TMPFILE` file: it has no name until it is complete, so a
    /// crash while writing leaves nothing behind. None where the file system does not
    /// support it (the caller falls back to a named temporary file).
    pub(super) fn write_unnamed(
        dir: &Path,
        path: &Path,
        bytes: &[u8],
        permissions: Option<std::fs::Permissions>,
    ) -> Option<std::io::Result<()>> {
        let fd = rustix::fs::open(
            dir,
            OFlags::TMPFILE | OFlags::WRONLY | OFlags::CLOEXEC,
            Mode::from_raw_mode(0o600),
        )
        .ok()?;
        let mut file = std::fs::File::from(fd);
        Some((|| {
            super::set_permissions(&file, permissions)?;
            super::write_pausable(&mut file, bytes)?;
            file.sync_all()?;
            // Name it (a name no other writer uses), then rename it over the output.
            let name = dir.join(format!(
                "{}{}-{:x}.tmp",
                super::temp_prefix(path),
                std::process::id(),
                unique()
            ));
            let proc_path = format!("/proc/self/fd/{}", std::os::fd::AsRawFd::as_raw_fd(&file));
            rustix::fs::linkat(&file, "", CWD, &name, AtFlags::EMPTY_PATH)
                .or_else(|_| {
                    rustix::fs::linkat(CWD, &proc_path, CWD, &name, AtFlags::SYMLINK_FOLLOW)
                })
                .map_err(std::io::Error::from)?;
            std::fs::rename(&name, path).inspect_err(|_| {
                let _ = std::fs::remove_file(&name);
            })
        })())
    }

    fn unique() -> u64 {
        use std::sync::atomic::{AtomicU64, Ordering};
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos() as u64)
            .unwrap_or(0);
        (nanos << 16) ^ COUNTER.fetch_add(1, Ordering::Relaxed)
    }
}

/// What a path finally names, for telling whether two paths are one file: the links
/// followed, and the folder made absolute (the file itself need not exist yet).
fn identity(path: &Path) -> Option<PathBuf> {
    let end = follow_links(path).ok()?;
    let dir = std::fs::canonicalize(folder_of(&end)).ok()?;
    Some(dir.join(end.file_name()?))
}

/// Refuses outputs that name one file (the last write would silently replace the
/// others) or that name an input: `outputs` and `inputs` are (what names it, path),
/// as `("--charts", path)`. Streams (`/dev/stdout`, anything under `/dev` or `/proc`)
/// are written through, so several outputs may share them. The error names both.
pub fn distinct_outputs(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<(), String> {
    let mut seen: Vec<(&str, PathBuf)> = Vec::new();
    for (what, path) in inputs {
        if let Some(id) = identity(path) {
            seen.push((what, id));
        }
    }
    let first_output = seen.len();
    for (what, path) in outputs {
        if is_system(path) {
            continue;
        }
        let Some(id) = identity(path) else { continue };
        let stream = std::fs::metadata(&id).is_ok_and(|m| is_stream(&m.file_type()));
        if is_system(&id) || stream {
            continue;
        }
        if let Some((k, (other, _))) = seen.iter().enumerate().find(|(_, (_, p))| *p == id) {
            let role = if k < first_output {
                "the input"
            } else {
                "the output"
            };
            return Err(format!(
                "{what} {} names the same file as {role} {other}: give each output its own file",
                path.display()
            ));
        }
        seen.push((what, id));
    }
    Ok(())
}

/// The longest output file name, in bytes: Linux's NAME_MAX (255) less what the
/// temporary file an output is written through adds to it (`.NAME.sdfc-PID-XXXXXX.tmp`).
pub const MAX_NAME_BYTES: usize = 255 - 40;

/// Whether `path` can be written, checked before the work that produces it: not a
/// folder (nor a name ending in a separator), a name the file system takes, in a folder
/// that exists and takes a new file (tried with a temporary file there, removed at
/// once). Streams under `/dev` and `/proc` are written through and pass.
pub fn check_writable(path: &Path) -> Result<(), String> {
    let text = path.as_os_str().to_string_lossy();
    let folder_like = text.ends_with(std::path::MAIN_SEPARATOR)
        || text.ends_with('/')
        || [".", ".."]
            .iter()
            .any(|d| text == *d || text.ends_with(&format!("/{d}")));
    if path.is_dir() || folder_like {
        return Err("it names a folder, not a file".into());
    }
    if is_system(path) {
        return Ok(());
    }
    // Written through its links, as `write_output` writes it.
    let target = follow_links(path).map_err(|e| e.to_string())?;
    if is_system(&target) {
        return Ok(());
    }
    match target.file_name() {
        Some(name) if name.len() > MAX_NAME_BYTES => {
            return Err(format!(
                "its file name is {} bytes long; outputs are written through a temporary file with a longer name, so sdfc takes at most {MAX_NAME_BYTES}",
                name.len()
            ));
        }
        None => return Err("it names no file".into()),
        Some(_) => {}
    }
    let parent = folder_of(&target);
    if !parent.is_dir() {
        return Err("its folder does not exist".into());
    }
    tempfile::Builder::new()
        .prefix(&format!("{}{}-", temp_prefix(&target), std::process::id()))
        .suffix(".tmp")
        .tempfile_in(parent)
        .map(drop)
        .map_err(|e| format!("its folder does not take new files ({e})"))
}
