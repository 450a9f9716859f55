//! `sdfc render MESH.glb`: a baked mesh and its flat seamless atlas → PNG (and EXR
//! AOVs), through [`sdfc::gpu::MeshRenderer`]. A `.glb` carries no camera or light: the
//! camera frames the mesh's bounds and the light is the `render` item's default, or
//! both come from a scene's `render` item with `--camera-from SCENE`.

use super::frame::write_frame;
use super::RenderArgs;
use sdfc::bake::export::ReadError;
use sdfc::gpu::{MeshError, MeshRenderer};
use sdfc::view::View;
use std::process::ExitCode;
use std::time::Instant;

/// The largest `.glb` read (its JSON and textures have limits of their own, see
/// [`sdfc::bake::export::gltf`]); over it is a resource error (exit 5).
pub const MAX_GLB_BYTES: usize = 1 << 30;

pub fn run(args: RenderArgs) -> ExitCode {
    let usage = |message: String| {
        eprintln!("error: {message}");
        ExitCode::from(super::exit::USAGE)
    };
    if args.shape.is_some() || args.atlas.is_some() {
        return usage(String::from(
            "--shape and --atlas name parts of a scene; a baked mesh has neither",
        ));
    }
    if !args.view.for_mesh() {
        return usage(MeshError::View(args.view).to_string());
    }
    let name = args.scene.display().to_string();
    let load_start = Instant::now();
    let bytes = match super::read_bytes(&args.scene, MAX_GLB_BYTES) {
        Ok(b) if b.len() > MAX_GLB_BYTES => {
            eprintln!("error: {name} is larger than the limit of {MAX_GLB_BYTES} bytes (1 GiB) for a .glb");
            return ExitCode::from(super::exit::RESOURCE);
        }
        Ok(b) => b,
        Err(e) => return usage(format!("cannot read {name}: {e}")),
    };
    let (mesh, textures, layout) = match sdfc::bake::export::read_glb(&bytes) {
        Ok(x) => x,
        Err(ReadError::Invalid(e)) => {
            return usage(format!("{name} is not a mesh baked by sdfc: {e}"))
        }
        Err(ReadError::Limit(e)) => {
            eprintln!("error: {name} is over a limit of what sdfc reads: {e}");
            return ExitCode::from(super::exit::RESOURCE);
        }
    };
    let load_time = load_start.elapsed();
    let gpu = match super::open_gpu(args.backend) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let fail = |e: MeshError| match e {
        MeshError::Input(_) | MeshError::View(_) => usage(e.to_string()),
        MeshError::Internal(ice) => {
            eprintln!("error: {ice}");
            super::compile::save_for_report(&name, &ice.wgsl);
            ExitCode::from(super::exit::ICE)
        }
        MeshError::Gpu(e) => {
            eprintln!("error: {e}");
            ExitCode::from(super::exit::gpu(&e))
        }
    };
    let filter = args.filter.unwrap_or_default();
    let renderer = match MeshRenderer::with_filter(&gpu, &mesh, &textures, &layout, filter) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let mut view = match &args.camera_from {
        Some(scene) => {
            let (_, analysis) = match super::load(scene) {
                Ok(x) => x,
                Err(code) => return code,
            };
            match super::view_for(&analysis, None) {
                Ok(v) => v,
                Err(code) => return code,
            }
        }
        None => View::framing(renderer.bounds()),
    };
    if let Some((w, h)) = args.size {
        view.width = w;
        view.height = h;
    }
    let frame = match renderer.render(&gpu, &view, args.view) {
        Ok(f) => f,
        Err(e) => return fail(e),
    };
    let header = args.timings.then(|| {
        format!(
            "adapter:   {}\nload:      {:.2} ms (.glb → mesh, {} triangles, {}×{} atlas)\n",
            gpu.describe(),
            load_time.as_secs_f64() * 1e3,
            mesh.indices.len() / 3,
            layout.width(),
            layout.height()
        )
    });
    write_frame(&args, &frame, header)
}
