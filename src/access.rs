//! What a scene may read: texture files, confined to the scene's folder (and folders the
//! user allows), resolved without disclosing anything about files outside them.
//!
//! The rule: a path is resolved against the scene's folder, following symbolic links one
//! step at a time. If the path, or any link on the way, leads outside the allowed roots,
//! it is refused with the same message whether or not the file exists; nothing outside
//! the roots is ever opened, listed or examined. Inside the roots, folders, devices,
//! FIFOs and sockets are refused without being opened (so a FIFO cannot block the
//! compiler), and files are checked against [`MAX_TEXTURE_BYTES`].

use std::path::{Component, Path, PathBuf};

/// The largest texture file sdfc reads, in bytes.
pub const MAX_TEXTURE_BYTES: u64 = 64 << 20;
/// The largest texture side, in texels (wgpu's guaranteed `max_texture_dimension_2d`).
pub const MAX_TEXTURE_SIDE: u32 = 8192;
/// How many symbolic links one path may pass through.
const MAX_LINKS: usize = 40;

/// The folders a scene may read from.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Access {
    /// The folder relative paths start from (the scene file's); None for a document with
    /// no folder (an untitled editor buffer), where no file is read.
    pub base: Option<PathBuf>,
    /// Every allowed root, canonical: the base, then the extra ones (`--allow-path`,
    /// the language server's workspace folders).
    roots: Vec<PathBuf>,
    /// Run-time parameters set for this check (`--param NAME=VALUE`, `--time T`), by
    /// name, as the bits of their components: what the compile-time consumers (the CPU
    /// reference, seed placement) read as the parameters' current values. Unset ones
    /// take their defaults, `time` 0.
    params: std::collections::BTreeMap<String, Vec<u64>>,
}

/// Why a path cannot be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refusal {
    /// Outside the allowed folders (or through a link that leads out). Says nothing more.
    Outside,
    NotFound,
    Folder,
    /// A FIFO, device or socket: never opened.
    NotRegular(&'static str),
    TooLarge(u64),
    /// A loop or an over-long chain of links.
    Links,
    Io(String),
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::Outside => f.write_str("it is outside the folders this scene may read"),
            Refusal::NotFound => f.write_str("no such file"),
            Refusal::Folder => f.write_str("it is a folder, not an image file"),
            Refusal::NotRegular(what) => write!(f, "it is {what}, not an image file"),
            Refusal::TooLarge(n) => write!(
                f,
                "the file has {n} bytes; the limit is {MAX_TEXTURE_BYTES} ({} MiB)",
                MAX_TEXTURE_BYTES >> 20
            ),
            Refusal::Links => f.write_str("it passes through too many symbolic links"),
            Refusal::Io(e) => f.write_str(e),
        }
    }
}

impl Access {
    /// Reads below `base` only; `None` reads nothing.
    pub fn new(base: Option<&Path>) -> Access {
        let mut access = Access {
            base: base.map(Path::to_path_buf),
            roots: Vec::new(),
            params: Default::default(),
        };
        if let Some(b) = base {
            access.allow(b);
        }
        access
    }

    /// Also allows reading below `dir`.
    pub fn allow(&mut self, dir: &Path) {
        let dir = canonical(dir);
        if !self.roots.contains(&dir) {
            self.roots.push(dir);
        }
    }

    /// Sets run-time parameter `name` (or `time`) to `value` for this check.
    pub fn set_param(&mut self, name: &str, value: &[f64]) {
        self.params.insert(
            name.to_string(),
            value.iter().map(|x| x.to_bits()).collect(),
        );
    }

    /// The value set for run-time parameter `name`, if any.
    pub fn param(&self, name: &str) -> Option<Vec<f64>> {
        self.params
            .get(name)
            .map(|v| v.iter().map(|b| f64::from_bits(*b)).collect())
    }

    /// The names of the parameters set.
    pub fn params_set(&self) -> impl Iterator<Item = &str> {
        self.params.keys().map(String::as_str)
    }

    pub fn roots(&self) -> &[PathBuf] {
        &self.roots
    }

    fn inside(&self, path: &Path) -> bool {
        self.roots.iter().any(|r| path.starts_with(r))
    }

    /// Resolves `path` (relative to the base, or absolute) to a regular file inside the
    /// roots, or says why not. None when there is no base.
    pub fn resolve(&self, path: &str) -> Option<Result<PathBuf, Refusal>> {
        let base = canonical(self.base.as_deref()?);
        Some(self.resolve_from(&base, Path::new(path)))
    }

    fn resolve_from(&self, base: &Path, path: &Path) -> Result<PathBuf, Refusal> {
        // Before touching the file system: the path as written must stay inside.
        let lexical = normalize(&base.join(path));
        if !self.inside(&lexical) {
            return Err(Refusal::Outside);
        }
        let mut pending: Vec<std::ffi::OsString> = components_rev(path);
        let mut current = if path.is_absolute() {
            PathBuf::from("/")
        } else {
            base.to_path_buf()
        };
        let mut links = 0;
        while let Some(part) = pending.pop() {
            match part.to_str() {
                Some("..") => {
                    current.pop();
                    continue;
                }
                Some(".") | Some("") => continue,
                _ => {}
            }
            let next = current.join(&part);
            match std::fs::symlink_metadata(&next) {
                Ok(m) if m.file_type().is_symlink() => {
                    links += 1;
                    if links > MAX_LINKS {
                        return Err(Refusal::Links);
                    }
                    let target =
                        std::fs::read_link(&next).map_err(|e| Refusal::Io(e.to_string()))?;
                    if !self.inside(&normalize(&current.join(&target))) {
                        return Err(Refusal::Outside);
                    }
                    if target.is_absolute() {
                        current = PathBuf::from("/");
                    }
                    pending.extend(components_rev(&target));
                }
                _ => current = next,
            }
        }
        let current = normalize(&current);
        if !self.inside(&current) {
            return Err(Refusal::Outside);
        }
        let meta = match std::fs::symlink_metadata(&current) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(Refusal::NotFound),
            Err(e) => return Err(Refusal::Io(e.to_string())),
        };
        let kind = meta.file_type();
        if kind.is_dir() {
            return Err(Refusal::Folder);
        }
        if !kind.is_file() {
            return Err(Refusal::NotRegular(special_kind(&kind)));
        }
        if meta.len() > MAX_TEXTURE_BYTES {
            return Err(Refusal::TooLarge(meta.len()));
        }
        Ok(current)
    }
}

/// A path's components, last first (to be popped in order), without the root.
fn components_rev(path: &Path) -> Vec<std::ffi::OsString> {
    let mut parts: Vec<std::ffi::OsString> = path
        .components()
        .filter_map(|c| match c {
            Component::Normal(n) => Some(n.to_os_string()),
            Component::ParentDir => Some("..".into()),
            _ => None,
        })
        .collect();
    parts.reverse();
    parts
}

/// `.` and `..` removed without the file system.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c.as_os_str()),
        }
    }
    out
}

fn canonical(dir: &Path) -> PathBuf {
    std::fs::canonicalize(dir).unwrap_or_else(|_| {
        let abs = std::env::current_dir()
            .map(|cwd| cwd.join(dir))
            .unwrap_or_else(|_| dir.to_path_buf());
        normalize(&abs)
    })
}

#[cfg(unix)]
fn special_kind(kind: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if kind.is_fifo() {
        "a FIFO"
    } else if kind.is_char_device() || kind.is_block_device() {
        "a device"
    } else if kind.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "not a regular file"
}

/// What the header of an image file says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageInfo {
    pub width: u32,
    pub height: u32,
}

/// Reads only the header of the image at `path` (already resolved): its format from its
/// contents and its size, checked against [`MAX_TEXTURE_SIDE`].
pub fn image_header(path: &Path) -> Result<ImageInfo, String> {
    let reader = image::ImageReader::open(path)
        .map_err(|e| e.to_string())?
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    match reader.format() {
        Some(image::ImageFormat::Png) | Some(image::ImageFormat::Jpeg) => {}
        _ => return Err(String::from("its contents are not a PNG or JPEG image")),
    }
    let (width, height) = reader
        .into_dimensions()
        .map_err(|e| format!("its image header cannot be read: {e}"))?;
    if width == 0 || height == 0 {
        return Err(format!("the image is {width}×{height}: it has no texels"));
    }
    if width.max(height) > MAX_TEXTURE_SIDE {
        return Err(format!(
            "the image is {width}×{height}; the limit is {MAX_TEXTURE_SIDE} texels a side"
        ));
    }
    Ok(ImageInfo { width, height })
}

/// Decoder limits for loading a texture whose header passed [`image_header`]: a file
/// changed since the check cannot make the decoder allocate more than this.
pub fn decoder_limits() -> image::Limits {
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(4 * (MAX_TEXTURE_SIDE as u64).pow(2) + (64 << 20));
    limits
}
