//! The reader of [`super`]'s binary glTF: [`read_glb`], with its bounds checks and
//! limits (see the parent module's documentation).

use std::io::Cursor;

use gltf_json::accessor::{ComponentType, GenericComponentType, Type};
use gltf_json::buffer::View;
use gltf_json::extras::RawValue;
use gltf_json::mesh::{Mode, Semantic};
use gltf_json::validation::Checked;
use gltf_json::{Accessor, Image, Index, Root, Texture};
use image::{ImageFormat, RgbaImage};

use super::{
    texture_bytes, ReadError, CHUNK_BIN, CHUNK_JSON, LAYOUT_KEY, LEVELS_KEY, MAGIC, MAX_IMAGE_SIZE,
    MAX_JSON_BYTES, MAX_JSON_VALUES, MAX_TEXTURE_BYTES,
};
use crate::bake::export::{check_atlas, check_mesh, check_textures};
use crate::bake::{ChartLayout, MeshData, Textures};

/// Reads a binary glTF written by [`super::glb`] (or shaped like one: the first mesh's first
/// primitive, TRIANGLES, with POSITION, NORMAL, TANGENT and TEXCOORD_0 as f32 and
/// unsigned indices, its material's PNG textures in the GLB's buffer, and the atlas
/// layout in `extras.sdfc_atlas`). Any other input is an error, never a panic; what
/// is over a limit (see [`super`]'s documentation) is a [`ReadError::Limit`],
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
    // The material's images hold the rows TEXCOORD_0 spans (a flat layout's level 0),
    // the images of `extras.sdfc_levels` the rest. (Files from before that split hold
    // the whole atlas in the material's images, with texture coordinates over it.)
    let (width, height, top) = (layout.width(), layout.height(), layout.image_height());
    let levels = read_levels(&root)?;
    let whole = levels.is_none() && top < height;
    let own_rows = if whole { height } else { top };
    let texture = |index: Option<Index<Texture>>, what: &str| {
        index
            .ok_or_else(|| ReadError::from(format!("the glTF's material has no {what} texture")))
            .and_then(|index| {
                let texture = root.get(index).ok_or("a texture index is out of range")?;
                doc.image(texture.source, (width, own_rows))
            })
            .map_err(|e| e.context(&format!("the {what} texture")))
    };
    let mut textures = Textures {
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
        emissive_strength: material
            .extensions
            .as_ref()
            .and_then(|e| e.emissive_strength.as_ref())
            .map_or(1.0, |s| s.emissive_strength.0),
    };
    if top < height && !whole {
        let levels = levels.unwrap_or_default();
        let images = textures.named().len();
        if levels.len() != images {
            return Err(format!(
                "extras.{LEVELS_KEY} lists {} images for the {images} textures' levels",
                levels.len()
            )
            .into());
        }
        let below: Vec<RgbaImage> = levels
            .iter()
            .map(|&i| {
                doc.image(Index::new(i), (width, height - top))
                    .map_err(|e| e.context(&format!("image {i} of extras.{LEVELS_KEY}")))
            })
            .collect::<Result<_, _>>()?;
        let mut stacked = [
            Some(&mut textures.base_color),
            Some(&mut textures.metallic_roughness),
            Some(&mut textures.normal),
            textures.emissive.as_mut(),
        ];
        for (image, below) in stacked.iter_mut().flatten().zip(below) {
            let mut whole = RgbaImage::new(width, height);
            image::imageops::replace(&mut whole, *image, 0, 0);
            image::imageops::replace(&mut whole, &below, 0, top as i64);
            **image = whole;
        }
    }
    check_textures(&textures, &layout)?;
    let mut mesh = mesh;
    if whole {
        // Texture coordinates over the whole image, as such files wrote them.
        let scale = height as f64 / top as f64;
        for tc in &mut mesh.texcoords {
            tc[1] = (tc[1] as f64 * scale) as f32;
        }
        // (A huge coordinate may have become infinite.)
        check_mesh(&mesh)?;
    }
    Ok((mesh, textures, layout))
}

/// The image indices of `extras.sdfc_levels`, if the file has them.
fn read_levels(root: &Root) -> Result<Option<Vec<u32>>, String> {
    #[derive(serde::Deserialize)]
    struct Extras {
        #[serde(rename = "sdfc_levels")]
        levels: Option<Vec<u32>>,
    }
    let Some(extras) = root.extras.as_ref() else {
        return Ok(None);
    };
    let extras: Extras =
        serde_json::from_str(extras.get()).map_err(|e| format!("the glTF's extras: {e}"))?;
    match extras.levels {
        Some(levels) if levels.len() > 4 => Err(format!(
            "extras.{LEVELS_KEY} lists {} images; a material has at most 4 textures",
            levels.len()
        )),
        levels => Ok(levels),
    }
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

    /// Image `index`, a PNG in a buffer view, as RGBA. Images of another size than
    /// `(w, h)` are refused before they are decoded (a [`ReadError::Limit`] when over
    /// [`MAX_IMAGE_SIZE`]).
    fn image(&self, index: Index<Image>, (w, h): (u32, u32)) -> Result<RgbaImage, ReadError> {
        let image = self
            .root
            .get(index)
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
        if (pw, ph) != (w, h) {
            return Err(format!("its PNG is {pw}×{ph} texels, the atlas's part {w}×{h}").into());
        }
        let mut reader = image::ImageReader::with_format(Cursor::new(png), ImageFormat::Png);
        let mut limits = image::Limits::default();
        let (w, h) = (w.min(MAX_IMAGE_SIZE), h.min(MAX_IMAGE_SIZE));
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
