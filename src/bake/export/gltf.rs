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
//!   emissiveFactor [1, 1, 1];
//! - one sampler for every texture: LINEAR magnification and minification, no mipmap
//!   filter (the atlas holds its own levels side by side in the image, selected by the
//!   renderer, see [`ChartLayout`]), CLAMP_TO_EDGE in both directions;
//! - the layout of the atlas, `serde_json` of [`ChartLayout`] (a flat or a packed layout,
//!   whose table gives each chart's place), in the root's
//!   `extras.sdfc_atlas`, where glTF readers that do not know it ignore it.
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
//!   header must then give the layout's size, and the decoder's own limits hold it
//!   to that.

use std::io::Cursor;

use gltf_json::accessor::{ComponentType, GenericComponentType, Type};
use gltf_json::buffer::{Target, View};
use gltf_json::extras::RawValue;
use gltf_json::material::{EmissiveFactor, NormalTexture, PbrMetallicRoughness};
use gltf_json::mesh::{Mode, Primitive, Semantic};
use gltf_json::texture::{Info, MagFilter, MinFilter, Sampler, WrappingMode};
use gltf_json::validation::{Checked, USize64};
use gltf_json::{Accessor, Asset, Buffer, Image, Index, Material, Mesh, Node, Root, Scene};
use gltf_json::{Texture, Value};
use image::{ExtendedColorType, ImageEncoder, ImageFormat, RgbaImage};

use super::{check_atlas, check_mesh, check_textures};
use crate::bake::{ChartLayout, MeshData, Textures};

/// The key of the atlas layout in the root's `extras`.
pub const LAYOUT_KEY: &str = "sdfc_atlas";

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
/// its node, its scene and its material.
pub fn glb(
    mesh: &MeshData,
    textures: &Textures,
    layout: &ChartLayout,
    name: &str,
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
    let indices: Vec<u8> = mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
    let view = doc.view(&indices, Some(Target::ElementArrayBuffer));
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
    let base_color = doc.texture(&textures.base_color, "base_color")?;
    let metallic_roughness = doc.texture(&textures.metallic_roughness, "metallic_roughness")?;
    let normal_map = doc.texture(&textures.normal, "normal")?;
    let emissive = match &textures.emissive {
        Some(image) => Some(doc.texture(image, "emissive")?),
        None => None,
    };
    let material = doc.root.push(Material {
        name: Some(name.to_owned()),
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
    let extras = format!("{{\"{LAYOUT_KEY}\":{layout}}}");
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
        self.pad();
        let offset = self.bin.len() as u64;
        self.bin.extend_from_slice(bytes);
        self.root.push(View {
            buffer: Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(offset)),
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
        let bytes: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes, Some(Target::ArrayBuffer));
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

    /// Stores `image` as a PNG in the buffer; a texture of it with sampler 0.
    fn texture(&mut self, image: &RgbaImage, name: &str) -> Result<Index<Texture>, String> {
        let png = encode_png(image).map_err(|e| format!("encoding the {name} image: {e}"))?;
        let view = self.view(&png, None);
        let source = self.root.push(Image {
            buffer_view: Some(view),
            mime_type: Some(gltf_json::image::MimeType("image/png".into())),
            name: Some(name.to_owned()),
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
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
        let mut out = Vec::with_capacity(length);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&word(length)?);
        out.extend_from_slice(&word(json.len())?);
        out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
        out.extend_from_slice(&json);
        out.extend_from_slice(&word(self.bin.len())?);
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(&self.bin);
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

/// Reads a binary glTF written by [`glb`] (or shaped like one: the first mesh's first
/// primitive, TRIANGLES, with POSITION, NORMAL, TANGENT and TEXCOORD_0 as f32 and
/// unsigned indices, its material's PNG textures in the GLB's buffer, and the atlas
/// layout in `extras.sdfc_atlas`). Any other input is an error, never a panic; what
/// is over a limit (see the module's documentation) is a [`ReadError::Limit`],
/// found before the work it bounds.
pub fn read_glb(bytes: &[u8]) -> Result<(MeshData, Textures, ChartLayout), ReadError> {
    let (json, bin) = split_glb(bytes)?;
    check_json(json)?;
    let root = Root::from_slice(json).map_err(|e| format!("the glTF's JSON: {e}"))?;
    let layout = read_layout(&root)?;
    check_atlas(&layout)?;
    let bin = match root.buffers.first() {
        Some(buffer) if buffer.uri.is_none() => usize::try_from(buffer.byte_length.0)
            .ok()
            .and_then(|len| bin.get(..len))
            .ok_or("buffer 0 is longer than the GLB's BIN chunk")?,
        _ => return Err("buffer 0 is not the GLB's BIN chunk".into()),
    };
    let doc = Reader { root: &root, bin };

    let primitive = root
        .meshes
        .first()
        .and_then(|mesh| mesh.primitives.first())
        .ok_or("the glTF has no mesh")?;
    if !matches!(primitive.mode, Checked::Valid(Mode::Triangles)) {
        return Err("the glTF's primitive is not made of triangles".into());
    }
    let material = primitive
        .material
        .and_then(|m| root.get(m))
        .ok_or("the glTF's primitive has no material")?;
    check_texture_size(&layout, 3 + material.emissive_texture.is_some() as usize)?;
    let attribute = |semantic: Semantic| {
        let name = semantic.to_string();
        primitive
            .attributes
            .get(&Checked::Valid(semantic))
            .copied()
            .ok_or_else(|| format!("the glTF's primitive has no {name}"))
    };
    let mesh = MeshData {
        positions: doc.floats(attribute(Semantic::Positions)?, Type::Vec3)?,
        normals: doc.floats(attribute(Semantic::Normals)?, Type::Vec3)?,
        tangents: doc.floats(attribute(Semantic::Tangents)?, Type::Vec4)?,
        texcoords: doc.floats(attribute(Semantic::TexCoords(0))?, Type::Vec2)?,
        indices: doc.indices(
            primitive
                .indices
                .ok_or("the glTF's primitive has no indices")?,
        )?,
    };
    check_mesh(&mesh)?;

    let pbr = &material.pbr_metallic_roughness;
    let texture = |index: Option<Index<Texture>>, what: &str| {
        index
            .ok_or_else(|| ReadError::from(format!("the glTF's material has no {what} texture")))
            .and_then(|index| doc.image(index, &layout))
            .map_err(|e| e.context(&format!("the {what} texture")))
    };
    let textures = Textures {
        base_color: texture(
            pbr.base_color_texture.as_ref().map(|t| t.index),
            "base colour",
        )?,
        metallic_roughness: texture(
            pbr.metallic_roughness_texture.as_ref().map(|t| t.index),
            "metallic-roughness",
        )?,
        normal: texture(material.normal_texture.as_ref().map(|t| t.index), "normal")?,
        emissive: match &material.emissive_texture {
            Some(t) => Some(texture(Some(t.index), "emissive")?),
            None => None,
        },
    };
    check_textures(&textures, &layout)?;
    Ok((mesh, textures, layout))
}

/// Checks the JSON chunk against [`MAX_JSON_BYTES`] and [`MAX_JSON_VALUES`] before it is
/// parsed: the values are counted as they are read, none is built.
fn check_json(json: &[u8]) -> Result<(), ReadError> {
    if json.len() > MAX_JSON_BYTES {
        return Err(ReadError::Limit(format!(
            "its JSON chunk is {} bytes, over the limit of {} MiB ({MAX_JSON_BYTES} bytes) for a .glb's JSON",
            json.len(),
            MAX_JSON_BYTES >> 20
        )));
    }
    use serde::de::DeserializeSeed;
    let count = std::cell::Cell::new(0);
    let mut reader = serde_json::Deserializer::from_slice(json);
    let counted = Counter { count: &count }
        .deserialize(&mut reader)
        .and_then(|()| reader.end());
    match counted {
        _ if count.get() > MAX_JSON_VALUES => Err(ReadError::Limit(format!(
            "its JSON has more than {MAX_JSON_VALUES} values outside `extras`, the limit for a .glb's JSON"
        ))),
        Err(e) => Err(ReadError::Invalid(format!("the glTF's JSON: {e}"))),
        Ok(()) => Ok(()),
    }
}

/// Counts a JSON document's values into `count`, stopping past [`MAX_JSON_VALUES`];
/// the value of an `extras` key counts as one (gltf-json keeps it as raw text).
struct Counter<'a> {
    count: &'a std::cell::Cell<u64>,
}

impl Counter<'_> {
    fn bump<E: serde::de::Error>(&self) -> Result<(), E> {
        self.count.set(self.count.get() + 1);
        if self.count.get() > MAX_JSON_VALUES {
            return Err(E::custom("too many values"));
        }
        Ok(())
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for Counter<'_> {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for Counter<'_> {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E: serde::de::Error>(self, _: bool) -> Result<(), E> {
        self.bump()
    }
    fn visit_i64<E: serde::de::Error>(self, _: i64) -> Result<(), E> {
        self.bump()
    }
    fn visit_u64<E: serde::de::Error>(self, _: u64) -> Result<(), E> {
        self.bump()
    }
    fn visit_f64<E: serde::de::Error>(self, _: f64) -> Result<(), E> {
        self.bump()
    }
    fn visit_str<E: serde::de::Error>(self, _: &str) -> Result<(), E> {
        self.bump()
    }
    fn visit_unit<E: serde::de::Error>(self) -> Result<(), E> {
        self.bump()
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        self.bump()?;
        while seq
            .next_element_seed(Counter { count: self.count })?
            .is_some()
        {}
        Ok(())
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        self.bump()?;
        while let Some(key) = map.next_key_seed(IsExtras)? {
            if key {
                map.next_value::<serde::de::IgnoredAny>()?;
                self.bump()?;
            } else {
                map.next_value_seed(Counter { count: self.count })?;
            }
        }
        Ok(())
    }
}

/// Reads a key: whether it is `extras`.
struct IsExtras;

impl<'de> serde::de::DeserializeSeed<'de> for IsExtras {
    type Value = bool;
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<bool, D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de> serde::de::Visitor<'de> for IsExtras {
    type Value = bool;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a key")
    }
    fn visit_str<E: serde::de::Error>(self, key: &str) -> Result<bool, E> {
        Ok(key == "extras")
    }
}

/// Checks the decoded size of `images` textures of `layout`'s size before any is
/// decoded: [`MAX_IMAGE_SIZE`] a side and [`MAX_TEXTURE_BYTES`] in all.
fn check_texture_size(layout: &ChartLayout, images: usize) -> Result<(), ReadError> {
    let (w, h) = (layout.width(), layout.height());
    if w > MAX_IMAGE_SIZE || h > MAX_IMAGE_SIZE {
        return Err(ReadError::Limit(format!(
            "its atlas is {w}×{h} texels, over the limit of {MAX_IMAGE_SIZE} × {MAX_IMAGE_SIZE} for a .glb's textures"
        )));
    }
    let bytes = texture_bytes(w, h, images);
    if bytes > MAX_TEXTURE_BYTES {
        return Err(ReadError::Limit(format!(
            "its {images} textures of {w}×{h} texels would take about {} MiB decoded and on the GPU, over the limit of {} MiB for a .glb's textures",
            bytes >> 20,
            MAX_TEXTURE_BYTES >> 20
        )));
    }
    Ok(())
}

/// A PNG's width and height from its header (the IHDR chunk, which comes first).
fn png_size(png: &[u8]) -> Option<(u32, u32)> {
    let word = |at: usize| Some(u32::from_be_bytes(png.get(at..at + 4)?.try_into().ok()?));
    if png.get(..8)? != b"\x89PNG\r\n\x1a\n" || png.get(12..16)? != b"IHDR" {
        return None;
    }
    Some((word(16)?, word(20)?))
}

/// The JSON and BIN chunks of a GLB file (the BIN chunk is empty when absent).
fn split_glb(bytes: &[u8]) -> Result<(&[u8], &[u8]), String> {
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    if bytes.get(..4) != Some(MAGIC) {
        return Err("not a binary glTF (no `glTF` magic)".into());
    }
    let header = || "a truncated GLB header".to_string();
    if word(4).ok_or_else(header)? != 2 {
        return Err("not a glTF 2.0 binary (version is not 2)".into());
    }
    let length = word(8).ok_or_else(header)? as usize;
    let bytes = bytes
        .get(..length)
        .ok_or_else(|| format!("the GLB says {length} bytes, the file has {}", bytes.len()))?;
    // A chunk at `at`: its type and data.
    let chunk = |at: usize| -> Option<(u32, &[u8])> {
        let len = word(at)? as usize;
        let start = at.checked_add(8)?;
        Some((word(at + 4)?, bytes.get(start..start.checked_add(len)?)?))
    };
    let json = match chunk(12) {
        Some((CHUNK_JSON, json)) => json,
        Some(_) => return Err("the GLB's first chunk is not JSON".into()),
        None => return Err("the GLB's JSON chunk is truncated".into()),
    };
    let next = 20 + json.len();
    if next == bytes.len() {
        return Ok((json, &[]));
    }
    match chunk(next) {
        Some((CHUNK_BIN, bin)) => Ok((json, bin)),
        Some(_) => Err("the GLB's second chunk is not BIN".into()),
        None => Err("the GLB's BIN chunk is truncated".into()),
    }
}

/// The atlas layout from the root's `extras.sdfc_atlas`, parsed from the text into the
/// layout's own types (no JSON values are built: a packed layout's table can be
/// large).
fn read_layout(root: &Root) -> Result<ChartLayout, String> {
    #[derive(serde::Deserialize)]
    struct Extras<'a> {
        #[serde(borrow, rename = "sdfc_atlas")]
        atlas: Option<&'a RawValue>,
    }
    let missing =
        || format!("the glTF has no atlas layout (extras.{LAYOUT_KEY}): not from sdfc bake");
    let extras = root.extras.as_ref().ok_or_else(missing)?;
    let extras: Extras =
        serde_json::from_str(extras.get()).map_err(|e| format!("the glTF's extras: {e}"))?;
    let layout = extras.atlas.ok_or_else(missing)?.get();
    // As `ChartLayout`'s untagged form reads it: packed, else flat.
    serde_json::from_str(layout)
        .map(ChartLayout::Packed)
        .or_else(|_| serde_json::from_str(layout).map(ChartLayout::Flat))
        .map_err(|e| format!("the glTF's atlas layout (neither packed nor flat): {e}"))
}

/// A parsed document and its buffer 0, for bounds-checked reads.
struct Reader<'a> {
    root: &'a Root,
    bin: &'a [u8],
}

impl Reader<'_> {
    /// The bytes of buffer view `index` and its stride.
    fn view(&self, index: Index<View>) -> Result<(&[u8], Option<usize>), String> {
        let view = self
            .root
            .get(index)
            .ok_or("a buffer view index is out of range")?;
        if view.buffer.value() != 0 {
            return Err("a buffer view is not in buffer 0".into());
        }
        let start = view.byte_offset.map_or(0, |o| o.0);
        let bytes = start
            .checked_add(view.byte_length.0)
            .and_then(|end| Some(usize::try_from(start).ok()?..usize::try_from(end).ok()?))
            .and_then(|range| self.bin.get(range))
            .ok_or("a buffer view is past the end of its buffer")?;
        Ok((bytes, view.byte_stride.map(|s| s.0)))
    }

    /// Accessor `index`'s elements, each `size` bytes, after checking that it is a
    /// dense accessor of `type_` and of one of the component types `components`, and
    /// that all of its elements lie in its view. Also returns the component type.
    fn elements(
        &self,
        index: Index<Accessor>,
        type_: Type,
        components: &[ComponentType],
    ) -> Result<(ComponentType, impl Iterator<Item = &[u8]>), String> {
        let accessor = self
            .root
            .get(index)
            .ok_or("an accessor index is out of range")?;
        let component = match accessor.component_type {
            Checked::Valid(GenericComponentType(c)) if components.contains(&c) => c,
            _ => return Err("an accessor has an unexpected component type".into()),
        };
        if accessor.type_ != Checked::Valid(type_) || accessor.normalized {
            return Err(format!("an accessor is not a {type_:?}"));
        }
        if accessor.sparse.is_some() {
            return Err("sparse accessors are not supported".into());
        }
        let view = accessor
            .buffer_view
            .ok_or("an accessor has no buffer view")?;
        let (bytes, stride) = self.view(view)?;
        let size = type_.multiplicity() * component.size();
        let stride = stride.unwrap_or(size);
        let offset = accessor.byte_offset.map_or(0, |o| o.0);
        let count = accessor.count.0;
        // The last element's end, which must lie in the view.
        let end = match count.checked_sub(1) {
            None => Some(offset),
            Some(last) => last
                .checked_mul(stride as u64)
                .and_then(|x| x.checked_add(offset)?.checked_add(size as u64)),
        };
        if stride < size || end.is_none_or(|end| end > bytes.len() as u64) {
            return Err("an accessor is past the end of its buffer view".into());
        }
        let (offset, count) = (offset as usize, count as usize);
        let elements = (0..count).map(move |i| &bytes[offset + i * stride..][..size]);
        Ok((component, elements))
    }

    /// An f32 accessor of `N` components.
    fn floats<const N: usize>(
        &self,
        index: Index<Accessor>,
        type_: Type,
    ) -> Result<Vec<[f32; N]>, String> {
        let (_, elements) = self.elements(index, type_, &[ComponentType::F32])?;
        let float = |b: &[u8], c: usize| {
            f32::from_le_bytes([b[4 * c], b[4 * c + 1], b[4 * c + 2], b[4 * c + 3]])
        };
        Ok(elements
            .map(|e| std::array::from_fn(|c| float(e, c)))
            .collect())
    }

    /// An index accessor (u8, u16 or u32).
    fn indices(&self, index: Index<Accessor>) -> Result<Vec<u32>, String> {
        use ComponentType::{U16, U32, U8};
        let (component, elements) = self.elements(index, Type::Scalar, &[U8, U16, U32])?;
        Ok(elements
            .map(|e| match component {
                U8 => e[0] as u32,
                U16 => u16::from_le_bytes([e[0], e[1]]) as u32,
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            })
            .collect())
    }

    /// The image of texture `index`, a PNG in a buffer view, as RGBA. Images of
    /// another size than `layout`'s are refused before they are decoded (a
    /// [`ReadError::Limit`] when over [`MAX_IMAGE_SIZE`]).
    fn image(&self, index: Index<Texture>, layout: &ChartLayout) -> Result<RgbaImage, ReadError> {
        let texture = self
            .root
            .get(index)
            .ok_or("a texture index is out of range")?;
        let image = self
            .root
            .get(texture.source)
            .ok_or("an image index is out of range")?;
        if image.mime_type.as_ref().map(|m| m.0.as_str()) != Some("image/png") {
            return Err("the image is not a PNG in the GLB".into());
        }
        let (png, _) = self.view(image.buffer_view.ok_or("the image is not in the GLB")?)?;
        let (pw, ph) = png_size(png).ok_or("the image is not a PNG")?;
        if pw > MAX_IMAGE_SIZE || ph > MAX_IMAGE_SIZE {
            return Err(ReadError::Limit(format!(
                "its PNG is {pw}×{ph} texels, over the limit of {MAX_IMAGE_SIZE} × {MAX_IMAGE_SIZE} for a .glb's textures"
            )));
        }
        if (pw, ph) != (layout.width(), layout.height()) {
            return Err(format!(
                "its PNG is {pw}×{ph} texels, the atlas {}×{}",
                layout.width(),
                layout.height()
            )
            .into());
        }
        let mut reader = image::ImageReader::with_format(Cursor::new(png), ImageFormat::Png);
        let mut limits = image::Limits::default();
        let (w, h) = (
            layout.width().min(MAX_IMAGE_SIZE),
            layout.height().min(MAX_IMAGE_SIZE),
        );
        limits.max_image_width = Some(w);
        limits.max_image_height = Some(h);
        // The decoded image (at most 16-bit RGBA) and some room for the decoder.
        limits.max_alloc = Some(w as u64 * h as u64 * 8 + (1 << 20));
        reader.limits(limits);
        let image = reader
            .decode()
            .map_err(|e| format!("decoding its PNG: {e}"))?;
        Ok(image.into_rgba8())
    }
}
