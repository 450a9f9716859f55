//! Baked assets as plain data: a triangle mesh with its attributes, its texture
//! images, and the [`ChartLayout`] of its atlas (flat or packed). `bake` makes them, `gpu`
//! renders them, `codegen` writes the mesh renderer's shader for them, and
//! `bake::export` reads and writes them as glTF; so they live in a leaf module below
//! all of those (ARCHITECTURE.md).

pub mod packed;

pub use packed::{PackedChart, PackedLayout};

use serde::{Deserialize, Serialize};

/// Linear → sRGB-encoded 8-bit.
pub fn srgb8(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let s = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// Linear [0, 1] → 8-bit.
pub fn unorm8(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// A triangle mesh ready for export: every vertex has all four attributes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    pub positions: Vec<[f32; 3]>,
    /// Unit normals.
    pub normals: Vec<[f32; 3]>,
    /// Unit tangents along +u of the chart, w = ±1 (glTF's bitangent sign).
    pub tangents: Vec<[f32; 4]>,
    /// Level-0 atlas coordinates in [0, 1]², origin at the image's top left (glTF's).
    pub texcoords: Vec<[f32; 2]>,
    /// Triangles, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

/// The baked images of one material, all the same size (the flat atlas).
#[derive(Debug, Clone)]
pub struct Textures {
    /// Base colour, sRGB-encoded, alpha 255.
    pub base_color: image::RgbaImage,
    /// glTF's metallicRoughness: linear; G = roughness, B = metallic.
    pub metallic_roughness: image::RgbaImage,
    /// Tangent-space normal map (glTF's convention: linear, +Y up in the chart's v).
    pub normal: image::RgbaImage,
    /// Emission, sRGB-encoded; `None` when the material emits nothing.
    pub emissive: Option<image::RgbaImage>,
    /// What the emissive image's (decoded, linear) values are multiplied by: 1, or
    /// where the emission is over 1 somewhere its largest value, the image then holding
    /// the emission divided by it (glTF's `KHR_materials_emissive_strength`).
    pub emissive_strength: f32,
}

impl Textures {
    /// Refuses an emissive strength that is not a finite number, 0 or more (glTF's
    /// `emissiveStrength`).
    pub fn check_emissive_strength(&self) -> Result<(), String> {
        let strength = self.emissive_strength;
        if strength.is_finite() && strength >= 0.0 {
            Ok(())
        } else {
            Err(format!(
                "the emissive strength is {strength}; it must be a finite number, 0 or more"
            ))
        }
    }

    /// The images with their names (`base_color`, `metallic_roughness`, `normal`,
    /// `emissive` when there is one), in that order.
    pub fn named(&self) -> Vec<(&image::RgbaImage, &'static str)> {
        let mut out = vec![
            (&self.base_color, "base_color"),
            (&self.metallic_roughness, "metallic_roughness"),
            (&self.normal, "normal"),
        ];
        if let Some(e) = &self.emissive {
            out.push((e, "emissive"));
        }
        out
    }
}

/// Where each chart's levels lie in the flat atlas (§3.3): every chart has the same
/// level-0 resolution `chart_size` (a power of two), placed in a `columns` × `rows`
/// grid; level `l` is the same grid with cells of `chart_size >> l` texels, with its
/// top-left corner at `level_origins[l]` (texels). Level 0's origin is (0, 0). The
/// outermost texel centres of a chart lie on its boundary (the half-texel inset):
/// chart-local (u, v) ∈ [0, 1]² maps to texel coordinates
/// `origin + cell · n + 0.5 + (u, v) · (n − 1)` with `n = chart_size >> l`.
/// Serialized into the glTF's `extras.sdfc_atlas` so that `sdfc render OUT.glb` can
/// select levels per fragment (Eq. 1–2).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FlatLayout {
    /// The atlas image's width and height in texels.
    pub width: u32,
    pub height: u32,
    pub chart_size: u32,
    pub columns: u32,
    pub rows: u32,
    /// One origin per level, from level 0 (chart_size texels) to the last (2 texels).
    pub level_origins: Vec<[u32; 2]>,
    /// Texels of gutter around each level-0 chart, filled from the neighbouring charts
    /// across each side (0: none). A level-0 cell is then `chart_size + 2 · gutter`
    /// texels and the chart sits `gutter` texels in: for engines that build their own
    /// mip chain of the image, whose coarse texels then average a chart with its real
    /// neighbours' texels instead of an unrelated chart's.
    #[serde(default)]
    pub gutter: u32,
}

impl FlatLayout {
    /// The number of levels.
    pub fn levels(&self) -> usize {
        self.level_origins.len()
    }

    /// The resolution of one chart at level `l`.
    pub fn size_at(&self, level: usize) -> u32 {
        self.chart_size >> level
    }

    /// The cell of chart `chart` (column, row).
    pub fn cell(&self, chart: usize) -> [u32; 2] {
        [chart as u32 % self.columns, chart as u32 / self.columns]
    }

    /// The texels from one cell of level `l` to the next: the chart's size, plus the
    /// gutter on both sides at level 0.
    pub fn stride(&self, level: usize) -> u32 {
        self.size_at(level) + if level == 0 { 2 * self.gutter } else { 0 }
    }

    /// The top-left texel of chart `chart` at level `l` (inside its gutter).
    pub fn chart_origin(&self, chart: usize, level: usize) -> [u32; 2] {
        let stride = self.stride(level);
        let inset = if level == 0 { self.gutter } else { 0 };
        let [cx, cy] = self.cell(chart);
        let [ox, oy] = self.level_origins[level];
        [ox + cx * stride + inset, oy + cy * stride + inset]
    }

    /// The height of level 0's part of the image: its rows of charts, from the top. The
    /// glTF's material textures hold this part alone, every texel a level-0 texel that
    /// other tools read; the levels below it, which only sdfc's lookup reads, travel in
    /// images of their own (`bake::export`). Texture coordinates are relative to it.
    pub fn image_height(&self) -> u32 {
        let top = self.level_origins.first().map_or(0, |o| o[1]);
        top.saturating_add(self.rows.saturating_mul(self.stride(0)))
            .clamp(1, self.height.max(1))
    }

    /// The level-0 atlas coordinate (glTF TEXCOORD_0, in [0, 1]) of chart-local (u, v):
    /// over the width and [`FlatLayout::image_height`].
    pub fn texcoord(&self, chart: usize, u: f64, v: f64) -> [f32; 2] {
        // (Through chart_origin, which includes the gutter.)
        let n = self.chart_size as f64;
        let [x, y] = self.chart_origin(chart, 0);
        [
            ((x as f64 + 0.5 + u * (n - 1.0)) / self.width as f64) as f32,
            ((y as f64 + 0.5 + v * (n - 1.0)) / self.image_height() as f64) as f32,
        ]
    }

    /// The flat layout for `charts` charts in an atlas at most `size` texels a side: the
    /// largest power-of-two chart size whose level-0 grid (at most two thirds of the
    /// height) and the smaller levels (below it, side by side) fit. The image is `size`
    /// wide and only as tall as the charts need. `None` when even 2-texel charts do not fit.
    pub fn fit(charts: usize, size: u32) -> Option<FlatLayout> {
        FlatLayout::fit_with(charts, size, 0)
    }

    /// [`FlatLayout::fit`], with a gutter of `gutter` texels around each level-0 chart
    /// (a chart at least as large as its gutter). A generic mip chain's level k stays
    /// within a chart and its gutter while 2^k − 1 ≤ `gutter`: 1 texel keeps level 1,
    /// 2 (the command line's default) keep level 1, 3 or 4 keep levels 1 and 2.
    pub fn fit_with(charts: usize, size: u32, gutter: u32) -> Option<FlatLayout> {
        // Chart sizes are powers of two (each level halves them, down to 2).
        let mut n = if size >= 2 { 1 << size.ilog2() } else { 0 };
        while n >= 2 && n >= gutter {
            let g = gutter;
            let stride = n + 2 * g;
            let columns = size / stride;
            let rows = (2 * size / 3) / stride;
            if (columns as u64) * (rows as u64) >= charts.max(1) as u64 {
                let rows = (charts.max(1) as u32).div_ceil(columns);
                let mut origins = vec![[0, 0]];
                let mut x = 0;
                let mut level = 1;
                while n >> level >= 2 {
                    origins.push([x, rows * stride]);
                    x += columns * (n >> level);
                    level += 1;
                }
                // The image is as tall as the levels need (the paper's packed style
                // does the same): level 0's rows, then half a chart per row for the rest.
                let height = rows * stride + if origins.len() > 1 { rows * n / 2 } else { 0 };
                return Some(FlatLayout {
                    width: size,
                    height,
                    chart_size: n,
                    columns,
                    rows,
                    level_origins: origins,
                    gutter: g,
                });
            }
            n /= 2;
        }
        None
    }
}

impl FlatLayout {
    /// The texels that hold samples (every chart at every level) over the image's.
    pub fn utilisation(&self, charts: usize) -> f64 {
        let used: u64 = (0..self.levels())
            .map(|l| (self.size_at(l) as u64).pow(2) * charts as u64)
            .sum();
        used as f64 / (self.width as u64 * self.height as u64) as f64
    }
}

/// Where a baked image's charts lie: flat (§3.3, one chart per quad, all the same
/// size) or packed (§3.4, grown rectangular charts of their own sizes). (Not the
/// atlas of Implicit UVs, `uv::Atlas`, nor an `atlas` item, `sema::AtlasDef`.)
/// Serialized into the glTF's `extras.sdfc_atlas` as the one or the other's fields (a
/// flat layout's JSON is unchanged from before packed layouts existed).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum ChartLayout {
    Packed(PackedLayout),
    Flat(FlatLayout),
}

impl From<FlatLayout> for ChartLayout {
    fn from(l: FlatLayout) -> ChartLayout {
        ChartLayout::Flat(l)
    }
}

impl From<PackedLayout> for ChartLayout {
    fn from(l: PackedLayout) -> ChartLayout {
        ChartLayout::Packed(l)
    }
}

impl ChartLayout {
    pub fn width(&self) -> u32 {
        match self {
            ChartLayout::Flat(l) => l.width,
            ChartLayout::Packed(l) => l.width,
        }
    }

    pub fn height(&self) -> u32 {
        match self {
            ChartLayout::Flat(l) => l.height,
            ChartLayout::Packed(l) => l.height,
        }
    }

    /// The height of the part of the image other tools read (texture coordinates are
    /// relative to it): a flat layout's level 0 ([`FlatLayout::image_height`]); a
    /// packed layout's whole image (each chart's levels lie beside it in its block).
    pub fn image_height(&self) -> u32 {
        match self {
            ChartLayout::Flat(l) => l.image_height(),
            ChartLayout::Packed(l) => l.height,
        }
    }

    pub fn levels(&self) -> usize {
        match self {
            ChartLayout::Flat(l) => l.levels(),
            ChartLayout::Packed(l) => l.levels(),
        }
    }

    /// A cell's (mesh quad's) level-0 samples a side: the flat layout's chart size.
    pub fn cell_size(&self) -> u32 {
        match self {
            ChartLayout::Flat(l) => l.chart_size,
            ChartLayout::Packed(l) => l.cell_size,
        }
    }

    /// Chart `p`'s rectangle `[x, y, width, height]` at level `l`.
    pub fn rect(&self, p: usize, l: usize) -> [u32; 4] {
        match self {
            ChartLayout::Flat(layout) => {
                let [x, y] = layout.chart_origin(p, l);
                let n = layout.size_at(l);
                [x, y, n, n]
            }
            ChartLayout::Packed(layout) => layout.rect(p, l),
        }
    }

    /// The texels that hold samples over the image's.
    pub fn utilisation(&self, charts: usize) -> f64 {
        match self {
            ChartLayout::Flat(l) => l.utilisation(charts),
            ChartLayout::Packed(l) => l.utilisation(),
        }
    }
}
