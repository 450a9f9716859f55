//! The benchmarks' charts (plotters): SVG or PNG, by the file's extension, written
//! atomically. Text needs a TrueType font for its layout (and, in a PNG, its glyphs):
//! the one `SDFC_PLOT_FONT` names, or the first of a few common system fonts.

use plotters::coord::Shift;
use plotters::prelude::*;
use std::error::Error;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The environment variable naming a TrueType or OpenType font file for the charts.
pub const FONT_VAR: &str = "SDFC_PLOT_FONT";

/// Common places of a sans-serif font: Debian/Ubuntu, Fedora, Arch, macOS, Windows.
const SYSTEM_FONTS: [&str; 9] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// A chart: what it draws on any plotters backend.
pub trait Figure {
    /// The image size in pixels.
    fn size(&self) -> (u32, u32) {
        (800, 560)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), Box<dyn Error>>
    where
        DB::ErrorType: 'static;
}

/// The image formats of a chart.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Format {
    Svg,
    Png,
}

/// A chart's path, checked before any measuring starts (clap's value parser).
pub fn parse_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    format_of(&path)?;
    Ok(path)
}

/// The format a path's extension names.
pub fn format_of(path: &Path) -> Result<Format, String> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("svg") => Ok(Format::Svg),
        Some("png") => Ok(Format::Png),
        _ => Err(format!(
            "{}: a chart is written as .svg or .png; name the file with one of those extensions",
            path.display()
        )),
    }
}

/// Registers the chart font once; the error names where it looked. The benchmarks call
/// it before measuring, so a missing font is reported at once.
pub fn font() -> Result<(), String> {
    static FONT: OnceLock<Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let named = std::env::var_os(FONT_VAR).map(PathBuf::from);
        let candidates: Vec<PathBuf> = match &named {
            Some(p) => vec![p.clone()],
            None => SYSTEM_FONTS.iter().map(PathBuf::from).collect(),
        };
        for path in &candidates {
            let Ok(bytes) = std::fs::read(path) else {
                continue;
            };
            // plotters keeps fonts for the life of the process.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                return Ok(());
            }
            if named.is_some() {
                return Err(format!(
                    "{} is not a TrueType or OpenType font",
                    path.display()
                ));
            }
        }
        Err(match named {
            Some(p) => format!("cannot read the font {} ({FONT_VAR})", p.display()),
            None => format!(
                "no font for the chart's text; set {FONT_VAR} to a .ttf file (looked for {})",
                SYSTEM_FONTS.join(", ")
            ),
        })
    })
    .clone()
}

/// Draws `figure` and writes it to `path` (atomically), in the format of its extension.
pub fn write(path: &Path, figure: &impl Figure) -> Result<(), String> {
    let format = format_of(path)?;
    font()?;
    let (w, h) = figure.size();
    let bytes = match format {
        Format::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
                figure.draw(&root).map_err(|e| e.to_string())?;
                root.present().map_err(|e| e.to_string())?;
            }
            svg.into_bytes()
        }
        Format::Png => {
            let mut rgb = vec![0u8; (w * h * 3) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
                figure.draw(&root).map_err(|e| e.to_string())?;
                root.present().map_err(|e| e.to_string())?;
            }
            let image = image::RgbImage::from_raw(w, h, rgb).ok_or("a chart of the wrong size")?;
            let mut png = Vec::new();
            image
                .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                .map_err(|e| e.to_string())?;
            png
        }
    };
    sdfc::fsutil::write_output(path, &bytes).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two lines, one rising and one flat, on log-log axes.
    struct Lines;

    impl Figure for Lines {
        fn size(&self) -> (u32, u32) {
            (320, 240)
        }
        fn draw<DB: DrawingBackend>(
            &self,
            root: &DrawingArea<DB, Shift>,
        ) -> Result<(), Box<dyn Error>>
        where
            DB::ErrorType: 'static,
        {
            root.fill(&WHITE)?;
            let mut chart = ChartBuilder::on(root)
                .caption("test chart", ("sans-serif", 16))
                .x_label_area_size(30)
                .y_label_area_size(40)
                .build_cartesian_2d((1.0..100.0).log_scale(), (1.0..100.0).log_scale())?;
            chart.configure_mesh().x_desc("seeds").draw()?;
            chart.draw_series(LineSeries::new(
                [(1.0, 1.0), (100.0, 100.0)],
                RED.stroke_width(3),
            ))?;
            chart.draw_series(LineSeries::new(
                [(1.0, 10.0), (100.0, 10.0)],
                BLUE.stroke_width(3),
            ))?;
            Ok(())
        }
    }

    #[test]
    fn paths_name_their_format() {
        assert_eq!(format_of(Path::new("a/sweep.PNG")), Ok(Format::Png));
        assert_eq!(format_of(Path::new("sweep.svg")), Ok(Format::Svg));
        assert!(parse_path("sweep.pdf")
            .unwrap_err()
            .contains(".svg or .png"));
        assert!(parse_path("sweep").is_err());
    }

    #[test]
    fn charts_are_drawn_as_svg_and_png() {
        if let Err(e) = font() {
            // Machines without any of the fonts: say so, and fail where tools are required.
            assert!(std::env::var("SDFC_REQUIRE_TOOLS").is_err(), "{e}");
            eprintln!("SKIPPED: {e}");
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let svg = dir.path().join("c.svg");
        write(&svg, &Lines).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg") && text.contains("test chart") && text.contains("seeds"));
        let png = dir.path().join("c.png");
        write(&png, &Lines).unwrap();
        let image = image::open(&png).unwrap().to_rgb8();
        assert_eq!(image.dimensions(), (320, 240));
        let count = |c: [u8; 3]| image.pixels().filter(|p| p.0 == c).count();
        // Both lines are there: the rising one longer than the flat one's span.
        let (red, blue) = (count([255, 0, 0]), count([0, 0, 255]));
        assert!(red > 300 && blue > 300, "red {red}, blue {blue}");
        // The caption is drawn: dark pixels in the top rows, where no axis is.
        let dark = image
            .enumerate_pixels()
            .filter(|(_, y, p)| *y < 20 && p.0.iter().all(|&v| v < 100))
            .count();
        assert!(dark > 40, "{dark} dark pixels in the caption");
        // The blue line is flat: its pixels span at most a few rows.
        let rows: std::collections::BTreeSet<u32> = image
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0 == [0, 0, 255])
            .map(|(_, y, _)| y)
            .collect();
        assert!(rows.len() <= 4, "{rows:?}");
    }
}
