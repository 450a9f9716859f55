//! The `.glb` reader's limits (src/bake/export/gltf.rs, the reader in gltf/read.rs) on
//! hostile files, through the library and through `sdfc render MESH.glb`: an atlas
//! layout that claims 16384² (or
//! 8192² of textures, over the memory limit) with solid PNGs of that size, a PNG
//! larger than its layout, a JSON chunk over its size limit and one with too many
//! values. Each is refused before anything large is decoded or parsed, with exit 5
//! and a message naming the limit; malformed files stay exit 2. No GPU is needed:
//! `render` reads the file before it opens an adapter.

use crate::common;

use common::glb::{crc32, join_text, split, zlib_zeros};

use common::sdfc;
use image::{Rgba, RgbaImage};
use sdfc::bake::export::gltf::{
    texture_bytes, MAX_IMAGE_SIZE, MAX_JSON_BYTES, MAX_JSON_VALUES, MAX_TEXTURE_BYTES,
};
use sdfc::bake::export::{glb, read_glb, ReadError};
use sdfc::bake::{ChartLayout, FlatLayout, MeshData, Textures};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A solid black RGB PNG of `width` × `height`, a real one (any decoder decodes it)
/// that is small however large it says it is: 13 bits per 258 zero bytes.
fn solid_png(width: u32, height: u32) -> Vec<u8> {
    let chunk = |out: &mut Vec<u8>, kind: &[u8], data: &[u8]| {
        out.extend((data.len() as u32).to_be_bytes());
        let start = out.len();
        out.extend(kind);
        out.extend(data);
        let crc = crc32(&out[start..]);
        out.extend(crc.to_be_bytes());
    };
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]); // 8-bit RGB, no interlace
    chunk(&mut png, b"IHDR", &ihdr);
    // Each row: filter type 0, then 3 bytes a texel.
    let raw = height as u64 * (1 + 3 * width as u64);
    chunk(&mut png, b"IDAT", &zlib_zeros(raw));
    chunk(&mut png, b"IEND", &[]);
    png
}

/// A real .glb from the writer: one quad on a 64 × 48 flat atlas of one chart.
fn quad_glb() -> Vec<u8> {
    let layout = FlatLayout::fit(1, 64).unwrap();
    let mut mesh = MeshData::default();
    for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        mesh.positions.push([u as f32, v as f32, 0.0]);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.tangents.push([1.0, 0.0, 0.0, 1.0]);
        mesh.texcoords.push(layout.texcoord(0, u, v));
    }
    mesh.indices = vec![0, 1, 2, 0, 2, 3];
    let image = RgbaImage::from_pixel(layout.width, layout.height, Rgba([200, 100, 50, 255]));
    let textures = Textures {
        base_color: image.clone(),
        metallic_roughness: image.clone(),
        normal: image,
        emissive: None,
        emissive_strength: 1.0,
    };
    glb(&mesh, &textures, &ChartLayout::from(layout), "quad", "quad").unwrap()
}

fn join(doc: &Value, bin: &[u8]) -> Vec<u8> {
    join_text(serde_json::to_vec(doc).unwrap(), bin)
}

/// The quad's .glb with every image replaced by `png` (one buffer view for all) and,
/// when given, the layout's width and height replaced: a flat layout of one chart
/// fitted to `width`, `height` tall. Without `extras.sdfc_levels`, as files were
/// before the levels below level 0 had images of their own: each texture's image is
/// then the whole atlas.
fn hostile(png: &[u8], size: Option<(u32, u32)>) -> Vec<u8> {
    let (mut doc, mut bin) = split(&quad_glb());
    doc["extras"].as_object_mut().unwrap().remove("sdfc_levels");
    bin.resize(bin.len().next_multiple_of(4), 0);
    let offset = bin.len();
    bin.extend(png);
    bin.resize(bin.len().next_multiple_of(4), 0);
    let views = doc["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": png.len()}));
    let view = views.len() - 1;
    for image in doc["images"].as_array_mut().unwrap() {
        image["bufferView"] = json!(view);
    }
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    if let Some((width, height)) = size {
        let mut layout = FlatLayout::fit(1, width).unwrap();
        assert!(layout.height <= height);
        layout.height = height;
        doc["extras"]["sdfc_atlas"] = serde_json::to_value(&layout).unwrap();
    }
    join(&doc, &bin)
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// `sdfc render FILE -o out.png`: the status and standard error; no image is written.
fn render(file: &Path) -> (i32, String) {
    let out = file.with_extension("png");
    let (code, _, err) = sdfc(&[
        "render",
        file.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!out.exists(), "{err}");
    (code, err)
}

fn limit(bytes: &[u8]) -> String {
    match read_glb(bytes) {
        Err(ReadError::Limit(m)) => m,
        other => panic!("not refused for a limit: {:?}", other.map(|x| x.2)),
    }
}

#[test]
fn the_png_builder_makes_real_pngs() {
    // The control for the tests below: the same construction at the layout's own size
    // reads back, black everywhere, so a refusal below is the limit's.
    let (doc, _) = split(&quad_glb());
    let (w, h) = (
        doc["extras"]["sdfc_atlas"]["width"].as_u64().unwrap() as u32,
        doc["extras"]["sdfc_atlas"]["height"].as_u64().unwrap() as u32,
    );
    let (_, textures, _) = read_glb(&hostile(&solid_png(w, h), None)).expect("reads");
    assert!(textures.base_color.pixels().all(|p| p.0 == [0, 0, 0, 255]));
    let big = image::load_from_memory(&solid_png(1000, 3)).unwrap();
    assert_eq!((big.width(), big.height()), (1000, 3));
}

/// A file from before the levels had images of their own (the whole atlas in each
/// texture, TEXCOORD_0 over the whole height) still reads: the same atlas, and texture
/// coordinates over level 0's rows as the renderer now reads them.
#[test]
fn a_file_with_the_whole_atlas_in_each_texture_still_reads() {
    let (doc, _) = split(&quad_glb());
    let layout: FlatLayout = serde_json::from_value(doc["extras"]["sdfc_atlas"].clone()).unwrap();
    let (w, h, top) = (layout.width, layout.height, layout.image_height());
    assert!(
        top < h,
        "{layout:?}: the quad's atlas has levels below level 0"
    );
    assert_eq!(doc["images"].as_array().unwrap().len(), 6);
    let (mesh, textures, _) = read_glb(&hostile(&solid_png(w, h), None)).expect("reads");
    assert_eq!(textures.base_color.dimensions(), (w, h));
    let (new, _, _) = read_glb(&quad_glb()).unwrap();
    for (old, new) in mesh.texcoords.iter().zip(&new.texcoords) {
        // Written over level 0's rows, read as if over the whole image: scaled by h/top.
        let expected = new[1] as f64 * h as f64 / top as f64;
        assert!((old[1] as f64 - expected).abs() < 1e-6, "{old:?} {new:?}");
        assert_eq!(old[0], new[0]);
    }
    // With the levels' list but one image short: refused, named.
    let (mut doc, bin) = split(&quad_glb());
    doc["extras"]["sdfc_levels"] = json!([3, 4]);
    let Err(ReadError::Invalid(e)) = read_glb(&join(&doc, &bin)) else {
        panic!("a short list of the levels' images was read");
    };
    assert!(
        e.contains("lists 2 images for the 3 textures' levels"),
        "{e}"
    );
}

#[test]
fn a_layout_of_16384_squared_is_refused_before_decoding() {
    let png = solid_png(16384, 16384);
    // 805 MB of pixels in about 5 MB of PNG.
    assert!(png.len() < 6 << 20, "{}", png.len());
    let bytes = hostile(&png, Some((16384, 16384)));
    let message = limit(&bytes);
    assert!(message.contains("16384×16384"), "{message}");
    assert!(message.contains("limit of 8192 × 8192"), "{message}");
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "huge.glb", &bytes);
    let (code, err) = render(&file);
    assert_eq!(code, 5, "{err}");
    assert!(
        err.contains("limit of 8192 × 8192 for a .glb's textures"),
        "{err}"
    );
}

#[test]
fn textures_over_the_memory_limit_are_refused_before_decoding() {
    // 8192² is within the side limit, but three such textures take 2.5 GiB.
    assert_eq!(MAX_IMAGE_SIZE, 8192);
    assert!(texture_bytes(8192, 8192, 3) > MAX_TEXTURE_BYTES);
    assert!(texture_bytes(4096, 4096, 3) < MAX_TEXTURE_BYTES);
    assert!(texture_bytes(4096, 4096, 4) > MAX_TEXTURE_BYTES);
    assert_eq!(texture_bytes(3, 1, 1), 40);
    let bytes = hostile(&solid_png(8192, 8192), Some((8192, 8192)));
    let message = limit(&bytes);
    assert!(message.contains("limit of 768 MiB"), "{message}");
    let dir = tempfile::tempdir().unwrap();
    let (code, err) = render(&write(dir.path(), "big.glb", &bytes));
    assert_eq!(code, 5, "{err}");
    assert!(
        err.contains("2560 MiB") && err.contains("limit of 768 MiB"),
        "{err}"
    );
}

#[test]
fn a_png_larger_than_its_layout_is_refused_before_decoding() {
    // Over the side limit: a limit (exit 5).
    let bytes = hostile(&solid_png(16384, 16384), None);
    assert!(limit(&bytes).contains("its PNG is 16384×16384"));
    let dir = tempfile::tempdir().unwrap();
    let (code, err) = render(&write(dir.path(), "png.glb", &bytes));
    assert_eq!(code, 5, "{err}");
    assert!(err.contains("limit of 8192 × 8192"), "{err}");
    // Within it but not the layout's size: a malformed file (exit 2).
    let bytes = hostile(&solid_png(128, 128), None);
    assert!(matches!(read_glb(&bytes), Err(ReadError::Invalid(_))));
    let (code, err) = render(&write(dir.path(), "other.glb", &bytes));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("its PNG is 128×128 texels, the atlas's part 64×48"),
        "{err}"
    );
}

#[test]
fn a_json_chunk_over_its_limit_is_refused_before_parsing() {
    let (doc, bin) = split(&quad_glb());
    // Whitespace is valid JSON: just over the limit, with nothing else to parse.
    let mut json = serde_json::to_vec(&doc).unwrap();
    json.resize(MAX_JSON_BYTES + 4, b' ');
    let bytes = join_text(json, &bin);
    assert!(limit(&bytes).contains("limit of 64 MiB"));
    let dir = tempfile::tempdir().unwrap();
    let (code, err) = render(&write(dir.path(), "json.glb", &bytes));
    assert_eq!(code, 5, "{err}");
    assert!(err.contains("over the limit of 64 MiB"), "{err}");
    // At the limit, it reads.
    let mut json = serde_json::to_vec(&doc).unwrap();
    json.resize(MAX_JSON_BYTES, b' ');
    read_glb(&join_text(json, &bin)).expect("reads at the limit");
}

#[test]
fn json_values_over_their_limit_are_refused_before_parsing() {
    let (doc, bin) = split(&quad_glb());
    let nodes = |n: usize| {
        let mut d = doc.clone();
        d["nodes"] = Value::Array(vec![json!({}); n]);
        join(&d, &bin)
    };
    // sdfc's own file counts a few hundred values, and a file that grows to near the
    // limit still reads.
    read_glb(&nodes(MAX_JSON_VALUES as usize - 1000)).expect("reads under the limit");
    let bytes = nodes(MAX_JSON_VALUES as usize + 1);
    assert!(bytes.len() < 1 << 20);
    assert!(limit(&bytes).contains("65536 values"));
    let dir = tempfile::tempdir().unwrap();
    let (code, err) = render(&write(dir.path(), "nodes.glb", &bytes));
    assert_eq!(code, 5, "{err}");
    assert!(
        err.contains("more than 65536 values outside `extras`, the limit"),
        "{err}"
    );
    // An unused array, unknown to glTF: counted too (the parser would skip it, but
    // a count cannot tell which keys a reader ignores).
    let mut d = doc.clone();
    d["unused"] = Value::Array(vec![json!(0); 100_000]);
    assert!(limit(&join(&d, &bin)).contains("65536"));
    // `extras` counts as one value: gltf-json keeps it as text.
    let mut d = doc.clone();
    d["extras"]["padding"] = Value::Array(vec![json!(0); 100_000]);
    read_glb(&join(&d, &bin)).expect("extras are not counted");
    // Malformed JSON stays a usage error (exit 2).
    let mut json = serde_json::to_vec(&doc).unwrap();
    json.push(b'{');
    let bytes = join_text(json, &bin);
    assert!(matches!(read_glb(&bytes), Err(ReadError::Invalid(_))));
    let (code, err) = render(&write(dir.path(), "bad.glb", &bytes));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a mesh baked by sdfc"), "{err}");
}

/// The writer refuses a JSON chunk the reader would refuse: a packed layout of ~1.9M
/// one-cell charts (2 × 2 texels each, 37 bytes of JSON each).
#[test]
fn the_writer_refuses_a_json_chunk_over_the_readers_limit() {
    use sdfc::bake::{PackedChart, PackedLayout};
    let (width, rows) = (16384u32, 240u32);
    let charts: Vec<PackedChart> = (0..rows)
        .flat_map(|j| {
            (0..width / 2).map(move |i| PackedChart {
                origin: [2 * i, 2 * j],
                cells: [1, 1],
            })
        })
        .collect();
    let layout = ChartLayout::Packed(PackedLayout {
        width,
        height: 2 * rows,
        cell_size: 2,
        levels: 1,
        charts,
    });
    let image = RgbaImage::from_pixel(width, 2 * rows, Rgba([0, 0, 0, 255]));
    let textures = Textures {
        base_color: image.clone(),
        metallic_roughness: image.clone(),
        normal: image,
        emissive: None,
        emissive_strength: 1.0,
    };
    let mut mesh = MeshData::default();
    for p in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        mesh.positions.push(p);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.tangents.push([1.0, 0.0, 0.0, 1.0]);
        mesh.texcoords.push([0.0, 0.0]);
    }
    mesh.indices = vec![0, 1, 2];
    let error = glb(&mesh, &textures, &layout, "many", "many").unwrap_err();
    assert!(
        error.contains("over the limit of 64 MiB that sdfc reads back"),
        "{error}"
    );
}
