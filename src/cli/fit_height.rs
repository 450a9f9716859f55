//! `sdfc fit-height`: a target shape encoded as a displacement of a base shape (§5.3).

use super::{exit, FitHeightArgs};
use sdfc::fsutil::write_output;
use sdfc::uv::fit::{fit, FitError};
use std::process::ExitCode;

fn fail(message: impl std::fmt::Display, code: u8) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(code)
}

pub fn run(args: FitHeightArgs) -> ExitCode {
    let (_, analysis) = match super::load(&args.scene) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let Some(scene) = &analysis.scene else {
        return ExitCode::from(exit::SCENE);
    };
    let shape = |name: &str| sdfc::driver::pick_shape(scene, Some(name));
    let (base, target) = match (shape(&args.base), shape(&args.target)) {
        (Ok(b), Ok(t)) => (b, t),
        (Err(e), _) | (_, Err(e)) => return fail(e, exit::USAGE),
    };
    let atlas = match sdfc::driver::pick_atlas(&analysis.program, args.atlas.as_deref()) {
        Ok(Some(a)) => a,
        Ok(None) => {
            return fail(
                "the scene has no atlas to give the height map its uv",
                exit::USAGE,
            )
        }
        Err(e) => return fail(e, exit::USAGE),
    };
    let Some(prepared) = analysis.atlas(&atlas.name) else {
        return fail(
            format!("atlas `{}` could not be prepared", atlas.name),
            exit::SCENE,
        );
    };
    // The atlas must be on the base: its uv are what `displace` reads there.
    if sdfc::ir::lower_shape(&atlas.shape).as_ref() != Some(base) {
        return fail(
            format!(
                "atlas `{}` is not on `{}`: the height map is read at the base's uv, so fit with an atlas on the base",
                atlas.name, args.base
            ),
            exit::USAGE,
        );
    }
    if !(2..=8192).contains(&args.size) {
        return fail(
            format!("--size {} must be between 2 and 8192", args.size),
            exit::USAGE,
        );
    }
    let samples = args
        .samples
        .unwrap_or(args.size as usize * args.size as usize * 6);
    let uv = match &args.uv_rect {
        Some(r) if r.len() == 4 && r[2] > r[0] && r[3] > r[1] => {
            Some((glam::DVec2::new(r[0], r[1]), glam::DVec2::new(r[2], r[3])))
        }
        Some(_) => {
            return fail(
                "--uv-rect takes U0 V0 U1 V1 with U1 > U0 and V1 > V0",
                exit::USAGE,
            )
        }
        None => None,
    };
    let map = match fit(base, target, prepared, args.size, samples, uv) {
        Ok(m) => m,
        Err(FitError::TooFewSamples(n)) => {
            return fail(
                format!("only {n} points of the base have coordinates and a ray hit on the target; seed the atlas where the base meets the target's rays"),
                exit::SCENE,
            )
        }
    };
    let (img, offset, range) = map.encode16();
    let mut bytes = std::io::Cursor::new(Vec::new());
    if let Err(e) = img.write_to(&mut bytes, image::ImageFormat::Png) {
        return fail(format!("cannot encode the height map: {e}"), exit::USAGE);
    }
    if let Err(e) = write_output(&args.output, bytes.get_ref()) {
        return fail(
            format!("cannot write {}: {e}", args.output.display()),
            exit::USAGE,
        );
    }
    let (u0, u1) = (map.uv_min, map.uv_max);
    let file = args
        .output
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    println!(
        "wrote {} ({}x{} texels, 16-bit grey) from {} base samples: height = {offset:.6} + {range:.6} * texel",
        args.output.display(),
        map.size,
        map.size,
        map.samples,
    );
    println!(
        "let fitted = image(\"{file}\");\nlet fit = {}.displace({offset:.6} + {range:.6} * fitted.sample((({}.uv - [{:.6}, {:.6}]) / [{:.6}, {:.6}]), wrap: \"clamp\").r);",
        args.base,
        atlas.name,
        u0.x,
        u0.y,
        u1.x - u0.x,
        u1.y - u0.y,
    );
    ExitCode::SUCCESS
}
