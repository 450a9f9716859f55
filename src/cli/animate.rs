//! `sdfc render SCENE --animate SECONDS [--fps F] -o OUT`: one pipeline, one frame per
//! step of `time` (only the parameters' block changes between frames), written as an
//! animated GIF (`.gif`), an animated PNG (`.png`), or numbered PNG frames (a name
//! with `%04d`, or any `%0Nd`). Every file is written atomically.

use super::RenderArgs;
use sdfc::codegen::Module;
use sdfc::fsutil::write_output;
use sdfc::gpu::{Frame, Gpu, Renderer};
use sdfc::view::View;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The most frames one animation may have.
pub const MAX_FRAMES: usize = 3600;

/// Where the frames go.
enum Sink {
    Gif,
    Apng,
    /// Numbered PNGs: the name before and after `%0Nd`, and N.
    Numbered(String, String, usize),
}

fn sink(output: &Path) -> Result<Sink, String> {
    let name = output.to_string_lossy();
    if let Some(at) = name.find('%') {
        let rest = &name[at + 1..];
        let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        if !rest[digits.len()..].starts_with('d') || digits.len() > 2 {
            return Err(format!(
                "{name}: a frame pattern is `%0Nd` (for example frame%04d.png)"
            ));
        }
        let width = digits.parse::<usize>().unwrap_or(1).clamp(1, 12);
        let after = &rest[digits.len() + 1..];
        return Ok(Sink::Numbered(
            name[..at].to_string(),
            after.to_string(),
            width,
        ));
    }
    match output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("gif") => Ok(Sink::Gif),
        Some("png") => Ok(Sink::Apng),
        _ => Err(format!(
            "{name}: an animation is written as .gif, .png (animated PNG) or frames named with %04d"
        )),
    }
}

/// The frames' times: `count` of them, `1 / fps` apart from `start`.
fn times(seconds: f64, fps: f64, start: f64) -> Result<Vec<f64>, String> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!(
            "--animate {seconds}: the length is a positive number of seconds"
        ));
    }
    if !(fps.is_finite() && fps > 0.0 && fps <= 120.0) {
        return Err(format!("--fps {fps}: frames per second lie in (0, 120]"));
    }
    let count = (seconds * fps).round().max(1.0);
    if count > MAX_FRAMES as f64 {
        return Err(format!(
            "{count} frames ({seconds} s at {fps} fps); an animation has at most {MAX_FRAMES}"
        ));
    }
    Ok((0..count as usize)
        .map(|i| start + i as f64 / fps)
        .collect())
}

/// Renders and writes the animation.
pub fn run(args: &RenderArgs, gpu: &Gpu, module: &Module, view: &View, seconds: f64) -> ExitCode {
    let usage = |e: String| {
        eprintln!("error: {e}");
        ExitCode::from(super::exit::USAGE)
    };
    let sink = match sink(&args.output) {
        Ok(s) => s,
        Err(e) => return usage(e),
    };
    let layout = &module.manifest.params;
    if !layout.fields.iter().any(|f| f.name == "time") {
        return usage(String::from(
            "the scene does not read `time`, so every frame would be the same (use `time` in a shape or a material)",
        ));
    }
    let times = match times(seconds, args.fps, args.run_time.time.unwrap_or(0.0)) {
        Ok(t) => t,
        Err(e) => return usage(e),
    };
    let renderer = match Renderer::new_for(
        gpu,
        module,
        &super::base_dir(&args.scene),
        (args.view, view.atlas_aov),
    ) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(super::exit::gpu(&e));
        }
    };
    let bar = indicatif::ProgressBar::new(times.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:>8} [{bar:30}] {pos}/{len} ({elapsed})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_message("frames");
    let mut frames: Vec<Frame> = Vec::with_capacity(times.len());
    for (i, t) in times.iter().enumerate() {
        let time = |name: &str| (name == "time").then(|| vec![*t]);
        if let Err(e) = renderer.set_param_values(gpu, module, &time) {
            // The atlas keeps its last geometry, as in the viewer.
            bar.suspend(|| {
                eprintln!("warning: frame {i} (time {t} s): {e}; it keeps its last geometry")
            });
        }
        let frame = match renderer.frames(gpu, view, args.view, 0, 1) {
            Ok((f, _)) => f,
            Err(e) => {
                bar.abandon();
                eprintln!("error: frame {i} (time {t} s): {e}");
                return ExitCode::from(super::exit::gpu(&e));
            }
        };
        if let Sink::Numbered(before, after, width) = &sink {
            let path = PathBuf::from(format!("{before}{i:0width$}{after}"));
            if let Err(e) = write_png(&path, &frame) {
                bar.abandon();
                return usage(e);
            }
        } else {
            frames.push(frame);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let written = match sink {
        Sink::Gif => encode_gif(&frames, args.fps),
        Sink::Apng => encode_apng(&frames, args.fps),
        Sink::Numbered(..) => {
            eprintln!(
                "wrote {} frames ({:.2} s at {} fps)",
                times.len(),
                seconds,
                args.fps
            );
            return ExitCode::SUCCESS;
        }
    };
    match written.and_then(|bytes| {
        write_output(&args.output, &bytes)
            .map_err(|e| format!("cannot write {}: {e}", args.output.display()))
    }) {
        Ok(()) => {
            eprintln!(
                "wrote {} ({} frames, {}x{}, {} fps)",
                args.output.display(),
                times.len(),
                view.width,
                view.height,
                args.fps
            );
            ExitCode::SUCCESS
        }
        Err(e) => usage(e),
    }
}

fn write_png(path: &Path, frame: &Frame) -> Result<(), String> {
    let img = image::RgbaImage::from_raw(frame.width, frame.height, frame.color.clone())
        .ok_or("frame size mismatch")?;
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .map_err(|e| e.to_string())?;
    write_output(path, &bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// An animated GIF (each frame quantized to its own palette), looping forever.
fn encode_gif(frames: &[Frame], fps: f64) -> Result<Vec<u8>, String> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let mut bytes = Vec::new();
    {
        let mut enc = GifEncoder::new_with_speed(&mut bytes, 10);
        enc.set_repeat(Repeat::Infinite)
            .map_err(|e| e.to_string())?;
        let delay = image::Delay::from_numer_denom_ms(1000, fps.round().max(1.0) as u32);
        for f in frames {
            let img = image::RgbaImage::from_raw(f.width, f.height, f.color.clone())
                .ok_or("frame size mismatch")?;
            enc.encode_frame(image::Frame::from_parts(img, 0, 0, delay))
                .map_err(|e| e.to_string())?;
        }
    }
    Ok(bytes)
}

/// An animated PNG (lossless), looping forever.
fn encode_apng(frames: &[Frame], fps: f64) -> Result<Vec<u8>, String> {
    let first = frames.first().ok_or("no frames")?;
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, first.width, first.height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_animated(frames.len() as u32, 0)
            .map_err(|e| e.to_string())?;
        let (num, den) = ((1000.0 / fps).round().clamp(1.0, 65535.0) as u16, 1000u16);
        enc.set_frame_delay(num, den).map_err(|e| e.to_string())?;
        let mut w = enc.write_header().map_err(|e| e.to_string())?;
        for f in frames {
            w.write_image_data(&f.color).map_err(|e| e.to_string())?;
        }
        w.finish().map_err(|e| e.to_string())?;
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns_and_counts() {
        assert!(matches!(sink(Path::new("a.gif")), Ok(Sink::Gif)));
        assert!(matches!(sink(Path::new("a.PNG")), Ok(Sink::Apng)));
        match sink(Path::new("out/f%04d.png")) {
            Ok(Sink::Numbered(b, a, 4)) => assert_eq!((b.as_str(), a.as_str()), ("out/f", ".png")),
            _ => panic!("a numbered pattern"),
        }
        assert!(sink(Path::new("a.jpg")).is_err());
        assert!(sink(Path::new("f%q.png")).is_err());
        assert_eq!(times(1.0, 4.0, 0.5).unwrap(), vec![0.5, 0.75, 1.0, 1.25]);
        assert!(times(1000.0, 24.0, 0.0).is_err());
        assert!(times(0.0, 24.0, 0.0).is_err());
        assert!(times(1.0, 0.0, 0.0).is_err());
    }
}
