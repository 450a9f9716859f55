//! The baked mesh as binary glTF 2.0 (.glb), and back.
//!
//! A GLB file (glTF 2.0 specification, §4.4 "GLB File Format Specification") is a
//! 12-byte header (the magic `glTF`, version 2, the file's length; little-endian u32s)
//! and two chunks, each a u32 length, a u32 type and the data:
//!
//! ```text
//!  "glTF" 2 length │ len "JSON" document (padded with spaces to 4 bytes)
//!                  │ len "BIN\0" buffer 0 (padded with zeros to 4 bytes)
//! ```
//!
//! What [`glb`] writes into the document (built with `gltf-json`'s types):
//!
//! - one buffer, the BIN chunk, cut into buffer views that each start on a 4-byte
//!   boundary: POSITION (vec3, with the min/max glTF requires), NORMAL (vec3), TANGENT
//!   (vec4), TEXCOORD_0 (vec2), all f32 with target ARRAY_BUFFER; the u32 indices with
//!   target ELEMENT_ARRAY_BUFFER; then one PNG per image (no target);
//! - one mesh with one TRIANGLES primitive, one node, one scene (the default);
//! - one material: baseColorTexture (sRGB), metallicRoughnessTexture (G roughness, B
//!   metallic), normalTexture, and when the material emits, emissiveTexture with
//!   emissiveFactor [1, 1, 1], and where the emission is over 1,
//!   `KHR_materials_emissive_strength` with the largest value (the texture then holds
//!   the emission divided by it; [`EMISSIVE_STRENGTH`]);
//! - one sampler for every texture: LINEAR magnification and minification, no mipmap
//!   filter (the atlas has its own levels, selected by sdfc's renderer, see
//!   [`ChartLayout`]), CLAMP_TO_EDGE in both directions;
//! - the material's textures hold the part of the atlas other tools read: a flat
//!   layout's level 0 (the image's rows down to
//!   [`crate::asset::FlatLayout::image_height`], which TEXCOORD_0 spans), a packed
//!   layout's whole image. The flat layout's smaller levels, the rows below, are
//!   images of their own (named `…_levels`), listed in the root's
//!   `extras.sdfc_levels` ([`LEVELS_KEY`]) and used by no texture: a third of the
//!   image that other tools would load and never read;
//! - the layout of the atlas, `serde_json` of [`ChartLayout`] (a flat or a packed layout,
//!   whose table gives each chart's place, in the whole image: level 0 over the levels),
//!   in the root's `extras.sdfc_atlas`, where glTF readers that do not know it ignore it.
//!
//! Images whose alpha is 255 everywhere are stored as RGB PNGs; [`read_glb`] returns
//! every image as RGBA with alpha 255 there, so a round trip gives back equal data.
//!
//! [`read_glb`] reads such files (and any glTF shaped like them) with explicit bounds
//! checks throughout: for any input bytes it returns an error ([`ReadError`]) or data
//! that passes [`check_mesh`], [`check_textures`] and [`check_atlas`], never panics,
//! and never allocates much more than the input's size before a check. Its limits,
//! each checked before the work it bounds ([`ReadError::Limit`]):
//!
//! - the JSON chunk is at most [`MAX_JSON_BYTES`] and holds at most
//!   [`MAX_JSON_VALUES`] JSON values outside `extras` (which gltf-json keeps as raw
//!   text), counted without building them, so its typed parse (a few hundred bytes a
//!   value at most) stays small;
//! - the textures' decoded size: the atlas at most [`MAX_IMAGE_SIZE`] a side, and the
//!   memory its textures take in `sdfc render` ([`texture_bytes`]) at most
//!   [`MAX_TEXTURE_BYTES`], both from the layout before any PNG is decoded; each PNG's
//!   header must then give its part's size (the material's: the layout's width by
//!   [`crate::asset::FlatLayout::image_height`]; the levels': the rest of the height;
//!   a file from before the split: the whole layout), and the decoder's own limits
//!   hold it to that.

use gltf_json::accessor::{ComponentType, GenericComponentType, Type};
use gltf_json::buffer::{Target, View};
use gltf_json::extensions::material::{EmissiveStrength, EmissiveStrengthFactor};
use gltf_json::extras::RawValue;
use gltf_json::material::{EmissiveFactor, NormalTexture, PbrMetallicRoughness};
use gltf_json::mesh::{Mode, Primitive, Semantic};
use gltf_json::texture::{Info, MagFilter, MinFilter, Sampler, WrappingMode};
use gltf_json::validation::{Checked, USize64};
use gltf_json::{Accessor, Asset, Buffer, Image, Index, Material, Mesh, Node, Root, Scene};
use gltf_json::{Texture, Value};
use image::{ExtendedColorType, ImageEncoder, RgbaImage};

use super::{check_atlas, check_mesh, check_textures};
use crate::bake::{ChartLayout, MeshData, Textures};

mod read;

pub use read::read_glb;

/// The glTF extension that carries emission over 1 (the emissive texture then holds
/// the emission divided by its `emissiveStrength`): listed in `extensionsUsed` (not
/// required: a reader without it shows the emission dimmer) where it is written.
pub const EMISSIVE_STRENGTH: &str = "KHR_materials_emissive_strength";

/// The key of the atlas layout in the root's `extras`.
pub const LAYOUT_KEY: &str = "sdfc_atlas";

/// The key, in the root's `extras`, of the images that hold a flat layout's levels
/// below level 0 (the image's rows from [`crate::asset::FlatLayout::image_height`]
/// down): their indices, base colour, metallic-roughness, normal, and emission when the
/// material has it. Absent when level 0 is the whole image.
pub const LEVELS_KEY: &str = "sdfc_levels";

/// The largest image side [`read_glb`] decodes: 8192, as for a scene's textures (an
/// 8192 × 8192 atlas is over [`MAX_TEXTURE_BYTES`] anyway).
pub const MAX_IMAGE_SIZE: u32 = 8192;
/// The most memory the textures of a `.glb` may take in `sdfc render`
/// ([`texture_bytes`]): 768 MiB, so that the whole render stays under 1 GB (a 4096²
/// bake with three textures, 630 MiB by this count, rendered in 822 MiB on lavapipe;
/// an 8192 × 4096 atlas with three, 1,336 MB). A 4096² atlas with an emissive texture
/// (853 MiB) is refused: bake it at 2048 to render it here.
pub const MAX_TEXTURE_BYTES: u64 = 768 << 20;
/// The largest JSON chunk [`read_glb`] parses: 64 MiB. sdfc's own is about 2 KB, plus
/// 37 bytes a chart for a packed layout (354 KB for the 9,642 charts of a sphere at
/// the default grid of 48, 11 MB for 308,574 one-cell charts at grid 256); [`glb`]
/// refuses to write a larger one.
pub const MAX_JSON_BYTES: usize = 64 << 20;
/// The most JSON values [`read_glb`] parses outside `extras` (every number, string,
/// array and object counts; an `extras` counts as one): 65,536. sdfc writes about 200.
pub const MAX_JSON_VALUES: u64 = 1 << 16;

/// The memory, in bytes, `images` textures of `width` × `height` take in `sdfc render`:
/// per texel of each, the decoded RGBA8 image (4), the GPU texture with a full mip
/// chain (4 × 4/3) and the upload's staging copy (4), 40/3 bytes in all. (Decoding
/// holds less: an RGB PNG's pixels (3) beside their RGBA8 copy.)
pub fn texture_bytes(width: u32, height: u32, images: usize) -> u64 {
    (images as u64 * width as u64 * height as u64).saturating_mul(40) / 3
}

/// Why [`read_glb`] refused a file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReadError {
    /// Not a glTF that sdfc reads: malformed, or not shaped like the ones it writes.
    Invalid(String),
    /// Over one of the reader's limits (named in the message): [`MAX_JSON_BYTES`],
    /// [`MAX_JSON_VALUES`], [`MAX_IMAGE_SIZE`], [`MAX_TEXTURE_BYTES`].
    Limit(String),
}

impl ReadError {
    /// The same error with its message prefixed by `context`.
    fn context(self, context: &str) -> ReadError {
        match self {
            ReadError::Invalid(m) => ReadError::Invalid(format!("{context}: {m}")),
            ReadError::Limit(m) => ReadError::Limit(format!("{context}: {m}")),
        }
    }
}

impl std::fmt::Display for ReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReadError::Invalid(m) | ReadError::Limit(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for ReadError {}

impl From<String> for ReadError {
    fn from(message: String) -> ReadError {
        ReadError::Invalid(message)
    }
}

impl From<&str> for ReadError {
    fn from(message: &str) -> ReadError {
        ReadError::Invalid(message.to_owned())
    }
}

impl From<ReadError> for String {
    fn from(e: ReadError) -> String {
        e.to_string()
    }
}

const MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Writes `mesh` with `textures` as a binary glTF: see the module's documentation.
/// `layout` is the atlas's (the textures must be its size); `name` names the mesh,
/// its node and its scene, `material` the material (the scene's material names).
pub fn glb(
    mesh: &MeshData,
    textures: &Textures,
    layout: &ChartLayout,
    name: &str,
    material: &str,
) -> Result<Vec<u8>, String> {
    check_mesh(mesh)?;
    check_atlas(layout)?;
    check_textures(textures, layout)?;

    let mut doc = Builder::default();
    let bounds = Some(bounds(&mesh.positions));
    let position = doc.attribute(&mesh.positions, Type::Vec3, bounds);
    let normal = doc.attribute(&mesh.normals, Type::Vec3, None);
    let tangent = doc.attribute(&mesh.tangents, Type::Vec4, None);
    let texcoord = doc.attribute(&mesh.texcoords, Type::Vec2, None);
    let view = doc.view_with(Some(Target::ElementArrayBuffer), |bin| {
        bin.extend(mesh.indices.iter().flat_map(|i| i.to_le_bytes()))
    });
    let indices = doc.accessor(
        view,
        mesh.indices.len(),
        ComponentType::U32,
        Type::Scalar,
        None,
    );

    doc.root.push(Sampler {
        mag_filter: Some(Checked::Valid(MagFilter::Linear)),
        min_filter: Some(Checked::Valid(MinFilter::Linear)),
        wrap_s: Checked::Valid(WrappingMode::ClampToEdge),
        wrap_t: Checked::Valid(WrappingMode::ClampToEdge),
        ..Default::default()
    });
    // The material's textures hold level 0's rows; the flat layout's smaller levels,
    // which only sdfc's lookup reads, follow as images of their own.
    let top = layout.image_height();
    let part = |image: &RgbaImage, y: u32, h: u32| {
        image::imageops::crop_imm(image, 0, y, image.width(), h).to_image()
    };
    let level0 = |image: &RgbaImage| part(image, 0, top);
    let base_color = doc.texture(&level0(&textures.base_color), "base_color")?;
    let metallic_roughness =
        doc.texture(&level0(&textures.metallic_roughness), "metallic_roughness")?;
    let normal_map = doc.texture(&level0(&textures.normal), "normal")?;
    let emissive = match &textures.emissive {
        Some(image) => Some(doc.texture(&level0(image), "emissive")?),
        None => None,
    };
    let mut levels = Vec::new();
    if top < layout.height() {
        let rest = layout.height() - top;
        for (image, name) in textures.named() {
            let index = doc.image(&part(image, top, rest), &format!("{name}_levels"))?;
            levels.push(index.value());
        }
    }
    // Emission over 1: the texture holds emission ÷ the strength.
    let strength = (emissive.is_some() && textures.emissive_strength != 1.0).then(|| {
        doc.root.extensions_used.push(EMISSIVE_STRENGTH.to_owned());
        gltf_json::extensions::material::Material {
            emissive_strength: Some(EmissiveStrength {
                emissive_strength: EmissiveStrengthFactor(textures.emissive_strength),
            }),
            ..Default::default()
        }
    });
    let material = doc.root.push(Material {
        name: Some(material.to_owned()),
        pbr_metallic_roughness: PbrMetallicRoughness {
            base_color_texture: Some(info(base_color)),
            metallic_roughness_texture: Some(info(metallic_roughness)),
            ..Default::default()
        },
        normal_texture: Some(NormalTexture {
            index: normal_map,
            scale: 1.0,
            tex_coord: 0,
            extensions: None,
            extras: Default::default(),
        }),
        emissive_factor: EmissiveFactor(if emissive.is_some() {
            [1.0; 3]
        } else {
            [0.0; 3]
        }),
        emissive_texture: emissive.map(info),
        extensions: strength,
        ..Default::default()
    });

    let attributes = [
        (Semantic::Positions, position),
        (Semantic::Normals, normal),
        (Semantic::Tangents, tangent),
        (Semantic::TexCoords(0), texcoord),
    ];
    let mesh = doc.root.push(Mesh {
        name: Some(name.to_owned()),
        primitives: vec![Primitive {
            attributes: attributes
                .into_iter()
                .map(|(s, a)| (Checked::Valid(s), a))
                .collect(),
            indices: Some(indices),
            material: Some(material),
            mode: Checked::Valid(Mode::Triangles),
            targets: None,
            extensions: None,
            extras: Default::default(),
        }],
        weights: None,
        extensions: None,
        extras: Default::default(),
    });
    let node = doc.root.push(Node {
        name: Some(name.to_owned()),
        mesh: Some(mesh),
        ..Default::default()
    });
    let scene = doc.root.push(Scene {
        name: Some(name.to_owned()),
        nodes: vec![node],
        extensions: None,
        extras: Default::default(),
    });
    doc.root.scene = Some(scene);
    doc.root.asset = Asset {
        generator: Some(format!("sdfc {}", env!("CARGO_PKG_VERSION"))),
        ..Default::default()
    };
    // Straight to text: a packed layout's table as JSON values would take ten times
    // its text.
    let layout = serde_json::to_string(layout).map_err(|e| e.to_string())?;
    let extras = if levels.is_empty() {
        format!("{{\"{LAYOUT_KEY}\":{layout}}}")
    } else {
        let levels = serde_json::to_string(&levels).map_err(|e| e.to_string())?;
        format!("{{\"{LAYOUT_KEY}\":{layout},\"{LEVELS_KEY}\":{levels}}}")
    };
    doc.root.extras = Some(RawValue::from_string(extras).map_err(|e| e.to_string())?);
    doc.finish()
}

/// The per-component minimum and maximum of `points` (glTF requires both for POSITION),
/// as JSON arrays of the exact f32 values.
fn bounds(points: &[[f32; 3]]) -> (Value, Value) {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in points {
        for c in 0..3 {
            min[c] = min[c].min(p[c]);
            max[c] = max[c].max(p[c]);
        }
    }
    let json = |v: [f32; 3]| Value::from(v.map(f64::from).to_vec());
    (json(min), json(max))
}

fn info(texture: Index<Texture>) -> Info {
    Info {
        index: texture,
        tex_coord: 0,
        extensions: None,
        extras: Default::default(),
    }
}

/// A document being written and its binary buffer.
#[derive(Default)]
struct Builder {
    root: Root,
    bin: Vec<u8>,
}

impl Builder {
    /// Appends `bytes` to the buffer, 4-byte aligned, as a new buffer view.
    fn view(&mut self, bytes: &[u8], target: Option<Target>) -> Index<View> {
        self.view_with(target, |bin| bin.extend_from_slice(bytes))
    }

    /// A new buffer view, 4-byte aligned, of the bytes `write` appends to the buffer.
    fn view_with(
        &mut self,
        target: Option<Target>,
        write: impl FnOnce(&mut Vec<u8>),
    ) -> Index<View> {
        self.pad();
        let offset = self.bin.len();
        write(&mut self.bin);
        let length = self.bin.len() - offset;
        self.root.push(View {
            buffer: Index::new(0),
            byte_length: USize64(length as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Checked::Valid),
            extensions: None,
            extras: Default::default(),
        })
    }

    /// A vertex attribute of `N` f32s per vertex: its view and accessor.
    fn attribute<const N: usize>(
        &mut self,
        values: &[[f32; N]],
        type_: Type,
        min_max: Option<(Value, Value)>,
    ) -> Index<Accessor> {
        // Straight into the buffer (no copy of the attribute's bytes on the way).
        let view = self.view_with(Some(Target::ArrayBuffer), |bin| {
            bin.extend(values.iter().flatten().flat_map(|x| x.to_le_bytes()))
        });
        self.accessor(view, values.len(), ComponentType::F32, type_, min_max)
    }

    /// A tightly packed accessor over a whole view.
    fn accessor(
        &mut self,
        view: Index<View>,
        count: usize,
        component: ComponentType,
        type_: Type,
        min_max: Option<(Value, Value)>,
    ) -> Index<Accessor> {
        let (min, max) = min_max.unzip();
        self.root.push(Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(count as u64),
            component_type: Checked::Valid(GenericComponentType(component)),
            type_: Checked::Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
            extensions: None,
            extras: Default::default(),
        })
    }

    /// Stores `image` as a PNG in the buffer: its image.
    fn image(&mut self, image: &RgbaImage, name: &str) -> Result<Index<Image>, String> {
        let png = encode_png(image).map_err(|e| format!("encoding the {name} image: {e}"))?;
        let view = self.view(&png, None);
        Ok(self.root.push(Image {
            buffer_view: Some(view),
            mime_type: Some(gltf_json::image::MimeType("image/png".into())),
            name: Some(name.to_owned()),
            uri: None,
            extensions: None,
            extras: Default::default(),
        }))
    }

    /// Stores `image` as a PNG in the buffer; a texture of it with sampler 0.
    fn texture(&mut self, image: &RgbaImage, name: &str) -> Result<Index<Texture>, String> {
        let source = self.image(image, name)?;
        Ok(self.root.push(Texture {
            name: Some(name.to_owned()),
            sampler: Some(Index::new(0)),
            source,
            extensions: None,
            extras: Default::default(),
        }))
    }

    fn pad(&mut self) {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
    }

    /// The GLB file: header, JSON chunk, BIN chunk.
    fn finish(mut self) -> Result<Vec<u8>, String> {
        self.pad();
        self.root.push(Buffer {
            byte_length: USize64(self.bin.len() as u64),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let mut json = self.root.to_vec().map_err(|e| e.to_string())?;
        json.resize(json.len().next_multiple_of(4), b' ');
        if json.len() > MAX_JSON_BYTES {
            return Err(format!(
                "the glTF's JSON would be {} bytes, over the limit of {} MiB that sdfc reads back (a packed layout of fewer charts: a larger --max-chart or a coarser --grid)",
                json.len(),
                MAX_JSON_BYTES >> 20
            ));
        }
        let length = 12 + 8 + json.len() + 8 + self.bin.len();
        let too_big = || format!("the glTF would be {length} bytes, past GLB's 4 GiB");
        let word = |n: usize| {
            u32::try_from(n)
                .map(u32::to_le_bytes)
                .map_err(|_| too_big())
        };
        let mut head = Vec::with_capacity(length - self.bin.len());
        head.extend_from_slice(MAGIC);
        head.extend_from_slice(&2u32.to_le_bytes());
        head.extend_from_slice(&word(length)?);
        head.extend_from_slice(&word(json.len())?);
        head.extend_from_slice(&CHUNK_JSON.to_le_bytes());
        head.extend_from_slice(&json);
        head.extend_from_slice(&word(self.bin.len())?);
        head.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        // The buffer becomes the file in place (its bytes moved up), not copied: a
        // second copy of a large mesh's buffer was the export's peak.
        let mut out = self.bin;
        out.reserve_exact(head.len());
        out.splice(0..0, head);
        Ok(out)
    }
}

/// PNG bytes of `image`: RGB when it is opaque, RGBA otherwise.
fn encode_png(image: &RgbaImage) -> image::ImageResult<Vec<u8>> {
    let mut png = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut png);
    let (w, h) = image.dimensions();
    if image.pixels().all(|p| p[3] == 255) {
        let rgb: Vec<u8> = image.pixels().flat_map(|p| [p[0], p[1], p[2]]).collect();
        encoder.write_image(&rgb, w, h, ExtendedColorType::Rgb8)?;
    } else {
        encoder.write_image(image.as_raw(), w, h, ExtendedColorType::Rgba8)?;
    }
    Ok(png)
}
