//! Writing a rendered frame, for `sdfc render` of a scene and of a baked mesh alike:
//! the PNG, the EXR AOVs and the timings.

use super::RenderArgs;
use sdfc::fsutil::write_output;
use sdfc::gpu::Frame;
use std::path::Path;
use std::process::ExitCode;

/// Writes the PNG and the AOVs of a frame, and the timings after `header` when asked.
pub fn write_frame(args: &RenderArgs, frame: &Frame, header: Option<String>) -> ExitCode {
    let png = match encode_png(frame) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: cannot encode the image: {e}");
            return ExitCode::from(super::exit::USAGE);
        }
    };
    if let Err(e) = write_output(&args.output, &png) {
        eprintln!("error: cannot write {}: {e}", args.output.display());
        return ExitCode::from(super::exit::USAGE);
    }
    for (name, path) in &args.aov {
        if let Err(e) = write_exr(path, frame, name) {
            eprintln!("error: cannot write {}: {e}", path.display());
            return ExitCode::from(super::exit::USAGE);
        }
    }
    if let Some(header) = header {
        let t = &frame.timings;
        eprint!("{header}");
        eprintln!("pipeline:  {:.2} ms", t.pipeline.as_secs_f64() * 1e3);
        eprintln!(
            "frame:     {:.2} ms ({}, {}x{})",
            t.frame.as_secs_f64() * 1e3,
            if t.frame_from_timestamps {
                "GPU timestamps"
            } else {
                "submit to complete"
            },
            frame.width,
            frame.height
        );
        eprintln!("readback:  {:.2} ms", t.readback.as_secs_f64() * 1e3);
        if t.tile_leaves + t.tiles_whole > 0 {
            eprintln!(
                "tiles:     {:.2} ms on the CPU ({} leaves listed over the {}-pixel tiles, {} tiles walk a whole group)",
                t.tiles.as_secs_f64() * 1e3,
                t.tile_leaves,
                sdfc::gpu::tiles::TILE,
                t.tiles_whole
            );
        }
        // The frame's variant (its view, its atlas AOV switch and, where a tile's list
        // was too long, the crowded tiles' paths), built at its first frame.
        if let Some(built) = t.pipeline_built {
            let crowded = match t.tiles_whole > 0 {
                true => format!(
                    " with the paths for crowded tiles (a tile's list was over {} leaves)",
                    sdfc::gpu::tiles::MAX_PER_TILE
                ),
                false => String::new(),
            };
            eprintln!(
                "built:     this view's pipeline{crowded}, {:.2} ms, at its first frame",
                built.as_secs_f64() * 1e3
            );
        }
        if t.coarse_samples > 0 {
            eprintln!(
                "multi-scale: {} coarse samples walked first, one pixel in {}x{} (the frame's time includes them)",
                t.coarse_samples,
                sdfc::codegen::coarse::STEP,
                sdfc::codegen::coarse::STEP
            );
        }
    }
    eprintln!(
        "wrote {} ({}x{})",
        args.output.display(),
        frame.width,
        frame.height
    );
    ExitCode::SUCCESS
}

fn write_exr(path: &Path, frame: &Frame, name: &str) -> Result<(), String> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let texel = |x: usize, y: usize| -> (f32, f32, f32) {
        let i = y * w + x;
        let (p, n, a) = (frame.position[i], frame.normal[i], frame.atlas[i]);
        match name {
            // u, v and the status (0 ok, 1-4 the failures, -1 no surface).
            "uv" => (a[0], a[1], a[3]),
            "depth" => (p[3], p[3], p[3]),
            "position" => (p[0], p[1], p[2]),
            "normal" => (n[0], n[1], n[2]),
            _ => (n[3], n[3], n[3]),
        }
    };
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let channels = SpecificChannels::rgb(|Vec2(x, y)| texel(x, y));
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_channels((w, h), channels)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| e.to_string())?;
    write_output(path, bytes.get_ref()).map_err(|e| e.to_string())
}

fn encode_png(frame: &Frame) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    let img = image::RgbaImage::from_raw(frame.width, frame.height, frame.color.clone())
        .ok_or("frame size mismatch")?;
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .map_err(|e| e.to_string())?;
    Ok(bytes)
}
