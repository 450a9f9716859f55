//! A compiled scene as a static web page (`sdfc export-web`): `index.html`, the
//! WebGPU driver `sdfc.js` (a plain ES module: it takes a `GPUDevice`, the WGSL, the
//! manifest and the textures' mip levels, and draws into a canvas with orbit
//! controls), `scene.wgsl`, `manifest.json` (with the scene's own values), `web.json`
//! (where each texture's levels are) and `textures/I/L.png`, every mip level of
//! texture I as the runtime makes it. Any static file server can serve the folder;
//! [`serve`] (`sdfc serve`) serves it from memory and rebuilds it on change.

#[cfg(feature = "serve")]
pub mod serve;

use crate::codegen::Module;
use crate::ir::texture::Textures;
use std::path::{Path, PathBuf};

/// The driver, and the page that runs it (`{{TITLE}}` is the scene's name).
pub const DRIVER_JS: &str = include_str!("../../web/sdfc.js");
const INDEX_HTML: &str = include_str!("../../web/index.html");

/// What the page does not do that sdfc's own runtime does: an atlas on a moving shape
/// (whose geometry sdfc recomputes on the CPU when a parameter changes,
/// [`crate::codegen::moving`]) keeps its geometry at the module's values in the page,
/// which has no CPU reference. One warning per such atlas.
pub fn warnings(module: &crate::codegen::Module) -> Vec<String> {
    module
        .moving
        .iter()
        .map(|m| {
            format!(
                "atlas `{}` is on a shape that moves with parameters: the page keeps its seeds where they lie at the exported values (sdfc render, view and embedding hosts recompute them)",
                m.def.name
            )
        })
        .collect()
}

/// The page, titled `title`. A `live` page (`sdfc serve`) follows the server's
/// `/events` instead of loading the files beside it once.
pub fn index_html(title: &str, live: bool) -> Vec<u8> {
    let escaped = title
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;");
    INDEX_HTML
        .replace("{{TITLE}}", &escaped)
        .replace("{{LIVE}}", if live { "true" } else { "false" })
        .into_bytes()
}

/// The files of the page, as (path relative to the folder, bytes).
pub fn files(
    title: &str,
    module: &Module,
    textures: &Textures,
) -> Result<Vec<(PathBuf, Vec<u8>)>, String> {
    let manifest =
        serde_json::to_vec_pretty(&module.manifest).map_err(|e| format!("the manifest: {e}"))?;
    let mut out = vec![
        (PathBuf::from("index.html"), index_html(title, false)),
        (PathBuf::from("sdfc.js"), DRIVER_JS.as_bytes().to_vec()),
        (PathBuf::from("scene.wgsl"), module.wgsl.as_bytes().to_vec()),
        (PathBuf::from("manifest.json"), manifest),
    ];
    let mut web = Vec::new();
    for (i, t) in module.manifest.textures.iter().enumerate() {
        let chain = textures
            .get(&t.path)
            .ok_or_else(|| format!("no decoded image for texture \"{}\"", t.path))?;
        let mut levels = Vec::new();
        for (l, level) in chain.levels.iter().enumerate() {
            let path = format!("textures/{i}/{l}.png");
            let mut png = Vec::new();
            level
                .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                .map_err(|e| format!("texture \"{}\" level {l}: {e}", t.path))?;
            out.push((PathBuf::from(&path), png));
            levels.push(path);
        }
        web.push(serde_json::json!({ "path": t.path, "levels": levels }));
    }
    let web = serde_json::json!({ "title": title, "textures": web });
    out.push((
        PathBuf::from("web.json"),
        serde_json::to_vec_pretty(&web).unwrap_or_default(),
    ));
    Ok(out)
}

/// Writes the page's files into `dir` (made if missing), each atomically; the paths
/// written.
pub fn export(
    dir: &Path,
    title: &str,
    module: &Module,
    textures: &Textures,
) -> Result<Vec<PathBuf>, String> {
    let files = files(title, module, textures)?;
    let mut written = Vec::new();
    for (rel, bytes) in files {
        let path = dir.join(&rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .map_err(|e| format!("cannot make {}: {e}", parent.display()))?;
        }
        crate::fsutil::write_output(&path, &bytes)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}
