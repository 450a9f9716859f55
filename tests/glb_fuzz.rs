//! Hostile `.glb` files for `sdfc render` (hardening round 3): mutations of real baked
//! files (a flat and a packed layout from `sdfc bake examples/sphere.sdf`, plus two
//! small ones written by the library, one with an emissive texture), from byte flips in
//! the header to JSON-level edits (wrong types, huge and overflowing numbers, accessors
//! out of range, deep nesting, arrays at the value limit, hostile atlas layouts and
//! chart tables, other image formats, hostile PNGs, textures of other sizes).
//!
//! The property, for every variant: in-process, `read_glb` returns `Ok` or `Err`
//! without panicking, within 20 s, and what it accepts passes the crate's own checks
//! and an independent one (`targets::glb`, the body of the cargo-fuzz target `glb`);
//! through the real binary (`sdfc render FILE.glb --size 32x24`), for a subset that
//! covers every mutation kind, the exit status is 0, 2 or 5 (2 for what the reader
//! calls invalid, 5 for what is over a limit), never a signal, an internal error (3)
//! or a panic (101), within 20 s and under 1 GB of peak memory (measured by GNU
//! time). The test process's own peak stays under 1 GB too.
//!
//! Variants come from a seeded xorshift: `GLB_FUZZ_SEED=N` changes the seed, and a
//! failure names the seed, the variant's index and kind and what was changed, and
//! leaves the file (up to 4 MiB) in `target/tmp/glb_fuzz/`. The suite runs a bounded number; the
//! ignored test runs at least 1,000 in-process and 100 through the binary:
//! `cargo test --release --test suite glb_fuzz:: -- --ignored --nocapture`.

use crate::common;

use common::glb::{crc32, join_text, split, zlib_zeros};

#[path = "../fuzz/fuzz_targets/targets.rs"]
mod targets;

use image::{ExtendedColorType, ImageEncoder, Rgba, RgbaImage};
use sdfc::bake::export::gltf::MAX_JSON_VALUES;
use sdfc::bake::export::{glb, read_glb, ReadError};
use sdfc::bake::{ChartLayout, FlatLayout, MeshData, PackedChart, PackedLayout, Textures};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The longest a variant may take, in-process or through the binary.
const TIME_LIMIT: Duration = Duration::from_secs(20);
/// The most memory a render or the test process may take: 1 GB.
const MEMORY_LIMIT: u64 = 1_000_000_000;
const DEFAULT_SEED: u64 = 0x5dfc_61b0_2025_0003;

// ---------------------------------------------------------------------------------
// The generator.

/// xorshift64*, seeded through splitmix64.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Rng((z ^ (z >> 31)) | 1)
    }

    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }

    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
}

// ---------------------------------------------------------------------------------
// GLB files and PNGs.

/// Appends a PNG chunk: its length, kind, data and CRC.
fn png_chunk(out: &mut Vec<u8>, kind: &[u8], data: &[u8]) {
    out.extend((data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend(kind);
    out.extend(data);
    let crc = crc32(&out[start..]);
    out.extend(crc.to_be_bytes());
}

const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// A PNG of `width` × `height` built by hand: IHDR (`depth`, `color`, `interlace`),
/// the `extra` chunks, then one IDAT of zeros as many as a non-interlaced image of
/// that format needs (a real, small PNG however large it says it is).
fn raw_png(
    width: u32,
    height: u32,
    depth: u8,
    color: u8,
    interlace: u8,
    extra: &[(&[u8], Vec<u8>)],
) -> Vec<u8> {
    let mut png = PNG_SIGNATURE.to_vec();
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([depth, color, 0, 0, interlace]);
    png_chunk(&mut png, b"IHDR", &ihdr);
    for (kind, data) in extra {
        png_chunk(&mut png, kind, data);
    }
    let channels = match color {
        0 | 3 => 1,
        2 => 3,
        4 => 2,
        _ => 4,
    };
    let row = (width as u64 * channels * depth as u64).div_ceil(8);
    png_chunk(
        &mut png,
        b"IDAT",
        &zlib_zeros((height as u64 * (1 + row)).max(1)),
    );
    png_chunk(&mut png, b"IEND", &[]);
    png
}

/// A black RGB PNG of `width` × `height`, small however large.
fn solid_png(width: u32, height: u32) -> Vec<u8> {
    raw_png(width, height, 8, 2, 0, &[])
}

/// A PNG through the `image` crate's encoder, of pseudo-random texels.
fn encoded_png(width: u32, height: u32, color: ExtendedColorType, rng: &mut Rng) -> Vec<u8> {
    let len = (width as u64 * height as u64 * color.bits_per_pixel() as u64).div_ceil(8);
    let data: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&data, width, height, color)
        .unwrap();
    png
}

fn jpeg(width: u32, height: u32) -> Vec<u8> {
    let rgb: Vec<u8> = (0..width * height * 3).map(|i| (i * 7) as u8).collect();
    let mut out = Vec::new();
    image::codecs::jpeg::JpegEncoder::new(&mut out)
        .encode(&rgb, width, height, ExtendedColorType::Rgb8)
        .unwrap();
    out
}

// ---------------------------------------------------------------------------------
// The base files.

/// A real file to mutate: its bytes, its document and BIN chunk.
struct Base {
    name: String,
    bytes: Vec<u8>,
    doc: Value,
    bin: Vec<u8>,
    packed: bool,
    width: u32,
    height: u32,
}

impl Base {
    fn new(name: &str, bytes: Vec<u8>) -> Base {
        let (doc, bin) = split(&bytes);
        let layout = &doc["extras"]["sdfc_atlas"];
        Base {
            name: name.to_owned(),
            packed: layout.get("charts").is_some(),
            width: layout["width"].as_u64().unwrap() as u32,
            height: layout["height"].as_u64().unwrap() as u32,
            bytes,
            doc,
            bin,
        }
    }
}

/// One quad, one chart, written by the library: a flat layout with an emissive
/// texture (four images), or a packed one.
fn library_quad(packed: bool) -> Vec<u8> {
    let (layout, tc): (ChartLayout, Box<dyn Fn(f64, f64) -> [f32; 2]>) = if packed {
        let l = PackedLayout::fit(&[[1, 1]], 64).unwrap();
        let c = l.clone();
        (
            ChartLayout::Packed(l),
            Box::new(move |u, v| c.texcoord(0, u, v)),
        )
    } else {
        let l = FlatLayout::fit(1, 64).unwrap();
        let c = l.clone();
        (
            ChartLayout::Flat(l),
            Box::new(move |u, v| c.texcoord(0, u, v)),
        )
    };
    let mut mesh = MeshData::default();
    for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        mesh.positions.push([u as f32, v as f32, 0.0]);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.tangents.push([1.0, 0.0, 0.0, 1.0]);
        mesh.texcoords.push(tc(u, v));
    }
    mesh.indices = vec![0, 1, 2, 0, 2, 3];
    let image = RgbaImage::from_fn(layout.width(), layout.height(), |x, y| {
        Rgba([x as u8, y as u8, 50, if packed { 255 } else { 200 }])
    });
    let textures = Textures {
        base_color: image.clone(),
        metallic_roughness: image.clone(),
        normal: image.clone(),
        emissive: (!packed).then_some(image),
        emissive_strength: 1.0,
    };
    glb(&mesh, &textures, &layout, "quad", "quad").unwrap()
}

/// The bases: `sdfc bake examples/sphere.sdf` at a small size, flat (with and
/// without a gutter) and packed, and the library's two quads. Baking needs a GPU
/// adapter; without one only the library's files are used (said on stderr).
fn bases(dir: &Path) -> Vec<Base> {
    let mut out = Vec::new();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere.sdf");
    let bakes: [(&str, &[&str]); 3] = [
        ("sphere-flat", &[]),
        ("sphere-gutter", &["--gutter=1"]),
        ("sphere-packed", &["--layout", "packed"]),
    ];
    for (name, extra) in bakes {
        let file = dir.join(format!("{name}.glb"));
        let status = Command::new(env!("CARGO_BIN_EXE_sdfc"))
            .arg("bake")
            .arg(&scene)
            .args(["--size", if extra.is_empty() { "64" } else { "128" }])
            .args(["--grid", "8"])
            .args(extra)
            .arg("-o")
            .arg(&file)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        if status.status.success() {
            let bytes = std::fs::read(&file).unwrap();
            read_glb(&bytes).expect("a baked file reads back");
            out.push(Base::new(name, bytes));
        } else {
            eprintln!(
                "note: `sdfc bake {name}` failed ({:?}), using the library's files only: {}",
                status.status.code(),
                String::from_utf8_lossy(&status.stderr)
            );
        }
    }
    for (name, packed) in [("quad-emissive", false), ("quad-packed", true)] {
        let bytes = library_quad(packed);
        read_glb(&bytes).expect("the library's file reads back");
        out.push(Base::new(name, bytes));
    }
    out
}

// ---------------------------------------------------------------------------------
// Editing a document.

#[derive(Clone, Debug)]
enum Seg {
    Key(String),
    Idx(usize),
}

fn get_mut<'a>(mut v: &'a mut Value, path: &[Seg]) -> &'a mut Value {
    for s in path {
        v = match s {
            Seg::Key(k) => &mut v[k.as_str()],
            Seg::Idx(i) => &mut v[*i],
        };
    }
    v
}

fn get<'a>(mut v: &'a Value, path: &[Seg]) -> &'a Value {
    for s in path {
        v = match s {
            Seg::Key(k) => &v[k.as_str()],
            Seg::Idx(i) => &v[*i],
        };
    }
    v
}

fn show(path: &[Seg]) -> String {
    path.iter()
        .map(|s| match s {
            Seg::Key(k) => k.clone(),
            Seg::Idx(i) => i.to_string(),
        })
        .collect::<Vec<_>>()
        .join(".")
}

/// Every path in `v` (long arrays sampled: their first three elements and the last),
/// skipping the root's `extras` unless `extras`.
fn paths(v: &Value, path: &mut Vec<Seg>, out: &mut Vec<Vec<Seg>>, extras: bool) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                if !extras && path.is_empty() && k == "extras" {
                    continue;
                }
                path.push(Seg::Key(k.clone()));
                out.push(path.clone());
                paths(x, path, out, extras);
                path.pop();
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                if i < 3 || i + 1 == a.len() {
                    path.push(Seg::Idx(i));
                    out.push(path.clone());
                    paths(x, path, out, extras);
                    path.pop();
                }
            }
        }
        _ => {}
    }
}

fn all_paths(v: &Value, extras: bool) -> Vec<Vec<Seg>> {
    let mut out = Vec::new();
    paths(v, &mut Vec::new(), &mut out, extras);
    out
}

/// JSON values as the reader counts them: every value, an `extras` as one.
fn count_values(v: &Value) -> u64 {
    match v {
        Value::Object(m) => {
            1 + m
                .iter()
                .map(|(k, x)| if k == "extras" { 1 } else { count_values(x) })
                .sum::<u64>()
        }
        Value::Array(a) => 1 + a.iter().map(count_values).sum::<u64>(),
        _ => 1,
    }
}

/// A variant being made: the document, the BIN chunk, and raw JSON texts that
/// replace placeholder strings when written (numbers JSON values cannot hold).
struct Work {
    doc: Value,
    bin: Vec<u8>,
    raws: Vec<String>,
}

impl Work {
    fn new(base: &Base) -> Work {
        Work {
            doc: base.doc.clone(),
            bin: base.bin.clone(),
            raws: Vec::new(),
        }
    }

    /// A placeholder for the JSON text `text`.
    fn raw(&mut self, text: impl Into<String>) -> Value {
        self.raws.push(text.into());
        Value::String(format!("@@RAW{}@@", self.raws.len() - 1))
    }

    fn text(&self) -> String {
        let mut text = serde_json::to_string(&self.doc).unwrap();
        for (i, r) in self.raws.iter().enumerate().rev() {
            text = text.replace(&format!("\"@@RAW{i}@@\""), r);
        }
        text
    }

    fn bytes(&self) -> Vec<u8> {
        join_text(self.text().into_bytes(), &self.bin)
    }

    fn len(&self, key: &str) -> usize {
        self.doc[key].as_array().map_or(0, Vec::len)
    }

    /// Appends `bytes` to the buffer as a new view; its index.
    fn append(&mut self, bytes: &[u8]) -> usize {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        let offset = self.bin.len();
        self.bin.extend(bytes);
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.doc["buffers"][0]["byteLength"] = json!(self.bin.len());
        let views = self.doc["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}));
        views.len() - 1
    }

    /// Image `which` (or every image) replaced by `bytes`.
    fn set_image(&mut self, which: Option<usize>, bytes: &[u8]) {
        let view = self.append(bytes);
        for (i, image) in self.doc["images"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .enumerate()
        {
            if which.is_none_or(|w| w == i) {
                image["bufferView"] = json!(view);
            }
        }
    }

    /// The byte range of accessor `a`'s view in the BIN chunk.
    fn accessor_bytes(&self, a: usize) -> std::ops::Range<usize> {
        let view = &self.doc["bufferViews"]
            [self.doc["accessors"][a]["bufferView"].as_u64().unwrap() as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        start..start + view["byteLength"].as_u64().unwrap() as usize
    }

    fn layout(&mut self) -> &mut Value {
        &mut self.doc["extras"]["sdfc_atlas"]
    }
}

/// Numbers for the document's fields: edges of integer types, overflowing ones,
/// floats, and what JSON cannot hold (NaN, 1e999).
const NUMBERS: &[&str] = &[
    "0",
    "1",
    "2",
    "3",
    "4",
    "5",
    "-1",
    "-4",
    "255",
    "256",
    "4095",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "-2147483648",
    "4294967295",
    "4294967296",
    "9007199254740993",
    "9223372036854775807",
    "9223372036854775808",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775809",
    "1e999",
    "-1e999",
    "1e308",
    "1e-400",
    "1.5",
    "0.5",
    "-0",
    "0.0",
    "4.0",
    "1e2",
    "NaN",
    "Infinity",
    "-Infinity",
    "5120",
    "5121",
    "5122",
    "5123",
    "5124",
    "5125",
    "5126",
    "34962",
    "34963",
];

/// Numbers for the atlas layout's fields (u32s).
const LAYOUT_NUMBERS: &[&str] = &[
    "0",
    "1",
    "2",
    "3",
    "4",
    "7",
    "8",
    "16",
    "31",
    "32",
    "33",
    "64",
    "8191",
    "8192",
    "8193",
    "32768",
    "65536",
    "65537",
    "1073741824",
    "2147483648",
    "4294967295",
    "4294967296",
    "-1",
    "1.5",
    "1e999",
    "null",
    "\"8\"",
];

fn wrong_value(rng: &mut Rng, w: &mut Work) -> Value {
    match rng.below(14) {
        0 => Value::Null,
        1 => json!(true),
        2 => json!("x"),
        3 => json!("0"),
        4 => json!(1.5),
        5 => json!(-1),
        6 => json!([]),
        7 => json!({}),
        8 => json!([0, 0]),
        9 => json!({"a": 0}),
        10 => json!("image/png"),
        11 => json!("a".repeat(100_000)),
        12 => w.raw("1e999"),
        _ => json!(0),
    }
}

// ---------------------------------------------------------------------------------
// The mutations.

/// What a mutation made: the file and what was changed.
struct Made {
    bytes: Vec<u8>,
    what: String,
    /// For the value-limit boundary: whether the reader must refuse it for the limit
    /// (`Some(true)`) or must not (`Some(false)`).
    over_value_limit: Option<bool>,
}

fn made(bytes: Vec<u8>, what: impl Into<String>) -> Made {
    Made {
        bytes,
        what: what.into(),
        over_value_limit: None,
    }
}

type Mutation = fn(&Base, &mut Rng, bool) -> Made;

/// Every kind: its name and its generator (`big`: the ignored test's larger cases).
const KINDS: &[(&str, Mutation)] = &[
    ("header", header),
    ("chunk-lengths", chunk_lengths),
    ("truncate", truncate),
    ("extend", extend),
    ("json-bytes", json_bytes),
    ("bin-bytes", bin_bytes),
    ("numbers", numbers),
    ("wrong-types", wrong_types),
    ("missing-fields", missing_fields),
    ("accessor-ranges", accessor_ranges),
    ("bin-values", bin_values),
    ("mesh-structure", mesh_structure),
    ("deep-nesting", deep_nesting),
    ("huge-arrays", huge_arrays),
    ("layout-extras", layout_extras),
    ("chart-tables", chart_tables),
    ("image-types", image_types),
    ("png-bytes", png_bytes),
    ("texture-sizes", texture_sizes),
    ("big-atlas", big_atlas),
    ("chart-search", chart_search),
    ("overdraw", overdraw),
];

/// The kinds whose every distinct accepted case goes through the binary in the full
/// campaign (their cost is in `sdfc render`).
const RENDER_KINDS: &[&str] = &["big-atlas", "chart-search", "overdraw"];

const EDGE_U32: &[u32] = &[
    0,
    1,
    3,
    4,
    8,
    12,
    19,
    20,
    0x7FFF_FFFF,
    0x8000_0000,
    0xFFFF_FFF8,
    0xFFFF_FFFC,
    u32::MAX,
];

fn put_u32(bytes: &mut [u8], at: usize, value: u32) {
    bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
}

fn json_len(bytes: &[u8]) -> usize {
    u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize
}

fn header(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut b = base.bytes.clone();
    let what = match rng.below(5) {
        0 => {
            let flips: Vec<usize> = (0..1 + rng.below(3)).map(|_| rng.below(20 * 8)).collect();
            for &bit in &flips {
                b[bit / 8] ^= 1 << (bit % 8);
            }
            format!("header bits {flips:?} flipped")
        }
        1 => {
            let magic = *rng.pick(&[b"glTf", b"GLTF", b"\0\0\0\0", b"gltF"]);
            b[..4].copy_from_slice(magic);
            format!("magic {:?}", String::from_utf8_lossy(magic))
        }
        2 => {
            let v = *rng.pick(&[0, 1, 3, 0x0100_0002, u32::MAX]);
            put_u32(&mut b, 4, v);
            format!("version {v}")
        }
        3 => {
            let len = b.len() as u32;
            let v = *rng.pick(&[
                0,
                11,
                12,
                19,
                20,
                len - 1,
                len + 1,
                len + 4,
                len / 2,
                u32::MAX,
            ]);
            put_u32(&mut b, 8, v);
            format!("total length {v} (file {len})")
        }
        _ => {
            let at = rng.below(20);
            let v = rng.next() as u8;
            b[at] = v;
            format!("header byte {at} = {v:#x}")
        }
    };
    made(b, what)
}

fn chunk_lengths(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut b = base.bytes.clone();
    let jl = json_len(&b) as u32;
    let bin_at = 20 + jl as usize;
    let bl = base.bin.len() as u32;
    let total = b.len() as u32;
    let what = match rng.below(6) {
        0 => {
            let v = *rng.pick(&[
                0,
                1,
                3,
                4,
                jl - 4,
                jl - 1,
                jl + 1,
                jl + 4,
                jl + 8,
                total - 20,
                total,
                u32::MAX,
                0x7FFF_FFFF,
                0xFFFF_FFF8,
            ]);
            put_u32(&mut b, 12, v);
            format!("JSON chunk length {v} (was {jl})")
        }
        1 => {
            let v = *rng.pick(&[0, 1, 4, bl - 1, bl - 4, bl + 1, bl + 4, bl * 2, u32::MAX]);
            put_u32(&mut b, bin_at, v);
            format!("BIN chunk length {v} (was {bl})")
        }
        2 => {
            let kind = *rng.pick(&[b"BIN\0", b"json", b"JSON", b"\0\0\0\0"]);
            b[16..20].copy_from_slice(kind);
            format!("JSON chunk type {:?}", String::from_utf8_lossy(kind))
        }
        3 => {
            let kind = *rng.pick(&[b"JSON", b"bin\0", b"BIN ", b"\0\0\0\0"]);
            b[bin_at + 4..bin_at + 8].copy_from_slice(kind);
            format!("BIN chunk type {:?}", String::from_utf8_lossy(kind))
        }
        4 => {
            // Both lengths moved together, the total consistent.
            let d = *rng.pick(&[4u32, 8, 1]);
            put_u32(&mut b, 12, jl + d);
            format!("JSON chunk length +{d} (the BIN chunk header read from inside the JSON)")
        }
        _ => {
            let v = *rng.pick(EDGE_U32);
            let at = *rng.pick(&[8usize, 12, bin_at]);
            put_u32(&mut b, at, v);
            format!("u32 at {at} = {v}")
        }
    };
    made(b, what)
}

fn truncate(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let b = &base.bytes;
    let jl = json_len(b);
    let marks = [
        0,
        3,
        4,
        8,
        11,
        12,
        16,
        19,
        20,
        21,
        20 + jl / 2,
        20 + jl - 1,
        20 + jl,
        24 + jl,
        28 + jl,
        29 + jl,
        b.len() - 1,
    ];
    let at = if rng.chance(50) {
        *rng.pick(&marks)
    } else {
        rng.below(b.len())
    };
    let mut out = b[..at].to_vec();
    let what = if rng.chance(40) && at >= 12 {
        // With the header's length fixed to the cut.
        put_u32(&mut out, 8, at as u32);
        format!("truncated to {at} bytes, header length fixed")
    } else {
        format!("truncated to {at} bytes")
    };
    made(out, what)
}

fn extend(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut b = base.bytes.clone();
    let what = match rng.below(5) {
        0 => {
            let n = 1 + rng.below(4096);
            b.extend((0..n).map(|_| rng.next() as u8));
            format!("{n} random bytes appended")
        }
        1 => {
            let n = 1 + rng.below(4096);
            b.extend((0..n).map(|_| rng.next() as u8));
            let len = b.len() as u32;
            put_u32(&mut b, 8, len);
            format!("{n} random bytes appended, header length fixed")
        }
        2 => {
            let n = *rng.pick(&[0usize, 4, 1000, 1 << 20]);
            b.extend((n as u32).to_le_bytes());
            b.extend(b"XTRA");
            b.extend(vec![0xAB; n]);
            let len = b.len() as u32;
            put_u32(&mut b, 8, len);
            format!("a third chunk of {n} bytes")
        }
        3 => {
            let n = *rng.pick(&[4usize, 64, 1 << 20]);
            let bin_at = 20 + json_len(&b);
            let bl = u32::from_le_bytes(b[bin_at..bin_at + 4].try_into().unwrap());
            put_u32(&mut b, bin_at, bl + n as u32);
            b.extend(vec![0u8; n]);
            let len = b.len() as u32;
            put_u32(&mut b, 8, len);
            format!("BIN chunk extended by {n} zeros")
        }
        _ => {
            // A second JSON chunk after the BIN chunk.
            let json = br#"{"asset":{"version":"2.0"}}  "#;
            b.extend((json.len() as u32 + 1).to_le_bytes());
            b.extend(b"JSON");
            b.extend(json);
            b.push(b' ');
            let len = b.len() as u32;
            put_u32(&mut b, 8, len);
            "a second JSON chunk".into()
        }
    };
    made(b, what)
}

fn json_bytes(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut text = serde_json::to_vec(&base.doc).unwrap();
    let mut edits = Vec::new();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(text.len());
        match rng.below(5) {
            0 => {
                text[at] ^= 1 << rng.below(8);
                edits.push(format!("flip@{at}"));
            }
            1 => {
                text.remove(at);
                edits.push(format!("del@{at}"));
            }
            2 => {
                let c = *rng.pick(b"{}[]\",:0-e.\\\0\xff");
                text.insert(at, c);
                edits.push(format!("ins {:?}@{at}", c as char));
            }
            3 => {
                // A digit changed: a different number in place.
                if let Some(p) = (at..text.len()).find(|&i| text[i].is_ascii_digit()) {
                    text[p] = b'0' + rng.below(10) as u8;
                    edits.push(format!("digit@{p}"));
                }
            }
            _ => {
                let c = *rng.pick(&[0u8, 0xC0, 0xFF, 0x80, b'\n']);
                text[at] = c;
                edits.push(format!("byte {c:#x}@{at}"));
            }
        }
    }
    made(
        join_text(text, &base.bin),
        format!("JSON text edits {edits:?}"),
    )
}

fn bin_bytes(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let n = 1 + rng.below(16);
    let region = rng.below(3);
    let mut at = Vec::new();
    for _ in 0..n {
        // Anywhere, in the vertex data, or in the images.
        let range = match region {
            0 => 0..w.bin.len(),
            1 => 0..w.accessor_bytes(4).end,
            _ => w.accessor_bytes(4).end..w.bin.len(),
        };
        let p = range.start + rng.below(range.len());
        w.bin[p] ^= 1 << rng.below(8);
        at.push(p);
    }
    made(w.bytes(), format!("BIN bits flipped at {at:?}"))
}

fn numbers(base: &Base, rng: &mut Rng, _: bool) -> Made {
    const KEYS: &[&str] = &[
        "byteLength",
        "byteOffset",
        "byteStride",
        "count",
        "componentType",
        "bufferView",
        "buffer",
        "indices",
        "material",
        "mode",
        "index",
        "source",
        "sampler",
        "texCoord",
        "scene",
        "mesh",
        "POSITION",
        "NORMAL",
        "TANGENT",
        "TEXCOORD_0",
    ];
    let mut w = Work::new(base);
    let all = all_paths(&w.doc, false);
    let keyed: Vec<&Vec<Seg>> = all
        .iter()
        .filter(|p| matches!(p.last(), Some(Seg::Key(k)) if KEYS.contains(&k.as_str())))
        .collect();
    let numeric: Vec<&Vec<Seg>> = all
        .iter()
        .filter(|p| get(&base.doc, p).is_number())
        .collect();
    let path = if rng.chance(75) {
        (*rng.pick(&keyed)).clone()
    } else {
        (*rng.pick(&numeric)).clone()
    };
    let n = *rng.pick(NUMBERS);
    *get_mut(&mut w.doc, &path) = w.raw(n);
    made(w.bytes(), format!("{} = {n}", show(&path)))
}

fn wrong_types(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let all = all_paths(&w.doc, rng.chance(20));
    let path = rng.pick(&all).clone();
    let v = wrong_value(rng, &mut w);
    let shown = v.to_string().chars().take(40).collect::<String>();
    *get_mut(&mut w.doc, &path) = v;
    made(w.bytes(), format!("{} = {shown}", show(&path)))
}

fn missing_fields(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let all: Vec<Vec<Seg>> = all_paths(&w.doc, true)
        .into_iter()
        .filter(|p| matches!(p.last(), Some(Seg::Key(_))))
        .collect();
    let mut removed = Vec::new();
    for _ in 0..1 + rng.below(2) {
        let path = rng.pick(&all).clone();
        let Some(Seg::Key(k)) = path.last() else {
            unreachable!()
        };
        let parent = path[..path.len() - 1]
            .iter()
            .try_fold(&mut w.doc, |v, s| match s {
                Seg::Key(k) => v.get_mut(k.as_str()),
                Seg::Idx(i) => v.get_mut(*i),
            });
        if let Some(o) = parent.and_then(Value::as_object_mut) {
            o.remove(k);
            removed.push(show(&path));
        }
    }
    made(w.bytes(), format!("removed {removed:?}"))
}

fn accessor_ranges(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let accessors = w.len("accessors");
    let views = w.len("bufferViews");
    let a = rng.below(accessors);
    let v = rng.below(views);
    let count = w.doc["accessors"][a]["count"].as_u64().unwrap();
    let view_len = w.doc["bufferViews"][v]["byteLength"].as_u64().unwrap();
    let what = match rng.below(16) {
        0 => {
            let x = if rng.chance(50) {
                json!(views + rng.below(3))
            } else {
                w.raw(*rng.pick(&["4294967296", "18446744073709551615", "-1"]))
            };
            let s = x.to_string();
            w.doc["accessors"][a]["bufferView"] = x;
            format!("accessors.{a}.bufferView = {s}")
        }
        1 => {
            let x = *rng.pick(&[
                count + 1,
                count + 2,
                count + 1000,
                count * 2,
                1 << 32,
                u64::MAX,
                u64::MAX / 12 + 1,
                (1 << 62) / 3,
            ]);
            w.doc["accessors"][a]["count"] = json!(x);
            format!("accessors.{a}.count = {x} (was {count})")
        }
        2 => {
            let x = *rng.pick(&[1, 2, 4, 8, view_len, view_len - 4, view_len + 4, 1 << 63]);
            w.doc["accessors"][a]["byteOffset"] = json!(x);
            format!("accessors.{a}.byteOffset = {x}")
        }
        3 => {
            let x = *rng.pick(&[0u64, 1, 2, 3, 4, 8, 12, 16, 20, 252, 256, 1 << 32, u64::MAX]);
            w.doc["bufferViews"][v]["byteStride"] = json!(x);
            format!("bufferViews.{v}.byteStride = {x}")
        }
        4 => {
            let off = w.doc["bufferViews"][v]["byteOffset"].as_u64().unwrap_or(0);
            let x = *rng.pick(&[
                off + 1,
                off + 4,
                off + view_len,
                w.bin.len() as u64,
                u64::MAX - view_len / 2,
                u64::MAX,
            ]);
            w.doc["bufferViews"][v]["byteOffset"] = json!(x);
            format!("bufferViews.{v}.byteOffset = {x}")
        }
        5 => {
            let x = *rng.pick(&[0, 1, view_len - 4, view_len + 1, view_len + 4, u64::MAX]);
            w.doc["bufferViews"][v]["byteLength"] = json!(x);
            format!("bufferViews.{v}.byteLength = {x}")
        }
        6 => {
            let len = w.bin.len() as u64;
            match rng.below(4) {
                0 => {
                    let x = *rng.pick(&[0, 1, len - 4, len + 1, len + 4, u64::MAX]);
                    w.doc["buffers"][0]["byteLength"] = json!(x);
                    format!("buffers.0.byteLength = {x}")
                }
                1 => {
                    let buffers = w.doc["buffers"].as_array_mut().unwrap();
                    buffers.push(json!({"byteLength": 4}));
                    buffers.swap(0, 1);
                    "buffers: a second one, first".into()
                }
                2 => {
                    let uri = *rng.pick(&["x.bin", "../../../etc/passwd", "data:,", "/dev/zero"]);
                    w.doc["buffers"][0]["uri"] = json!(uri);
                    format!("buffers.0.uri = {uri}")
                }
                _ => {
                    w.doc["buffers"] = json!([]);
                    "buffers = []".into()
                }
            }
        }
        7 => {
            let x = *rng.pick(&[1u64, 2, 1 << 32]);
            w.doc["bufferViews"][v]["buffer"] = json!(x);
            format!("bufferViews.{v}.buffer = {x}")
        }
        8 => {
            w.doc["accessors"][a]["sparse"] = json!({
                "count": 1,
                "indices": {"bufferView": 0, "componentType": 5125},
                "values": {"bufferView": 0}
            });
            format!("accessors.{a}.sparse")
        }
        9 => {
            w.doc["accessors"][a]["normalized"] = json!(true);
            format!("accessors.{a}.normalized")
        }
        10 => {
            let t = *rng.pick(&["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT4", "vec3", ""]);
            w.doc["accessors"][a]["type"] = json!(t);
            format!("accessors.{a}.type = {t:?}")
        }
        11 => {
            let c = *rng.pick(&[5120, 5121, 5122, 5123, 5124, 5125, 5126, 0, 5127]);
            w.doc["accessors"][a]["componentType"] = json!(c);
            format!("accessors.{a}.componentType = {c}")
        }
        12 => {
            w.doc["accessors"][a]["count"] = json!(0);
            format!("accessors.{a}.count = 0")
        }
        13 => {
            // Another accessor's view (same data read as something else).
            let b = rng.below(accessors);
            let view = w.doc["accessors"][b]["bufferView"].clone();
            w.doc["accessors"][a]["bufferView"] = view;
            format!("accessors.{a}.bufferView = accessors.{b}'s")
        }
        14 => {
            let off = w.doc["bufferViews"][v]["byteOffset"].as_u64().unwrap_or(0);
            w.doc["bufferViews"][v]["byteOffset"] = json!(off + 1);
            w.doc["bufferViews"][v]["byteLength"] = json!(view_len - 1);
            format!("bufferViews.{v} misaligned by 1")
        }
        _ => {
            // Two views overlapping, an accessor over both.
            let len = w.bin.len() as u64;
            w.doc["bufferViews"][v]["byteOffset"] = json!(0);
            w.doc["bufferViews"][v]["byteLength"] = json!(len);
            format!("bufferViews.{v} = the whole buffer")
        }
    };
    made(w.bytes(), what)
}

fn bin_values(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let vertices = w.doc["accessors"][0]["count"].as_u64().unwrap() as u32;
    let index_accessor = w.doc["meshes"][0]["primitives"][0]["indices"]
        .as_u64()
        .unwrap() as usize;
    let indices = w.accessor_bytes(index_accessor);
    let what = match rng.below(8) {
        0 => {
            let v = *rng.pick(&[vertices, vertices + 1, u32::MAX, 0x8000_0000, 0xFFFF_FFFE]);
            let slot = rng.below(indices.len() / 4);
            put_u32(&mut w.bin, indices.start + 4 * slot, v);
            format!("index {slot} = {v} ({vertices} vertices)")
        }
        1 => {
            let a = rng.below(4);
            let r = w.accessor_bytes(a);
            let slot = rng.below(r.len() / 4);
            let x = *rng.pick(&[
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::MAX,
                -f32::MAX,
                1e38,
                f32::MIN_POSITIVE / 2.0,
                -0.0,
            ]);
            w.bin[r.start + 4 * slot..][..4].copy_from_slice(&x.to_le_bytes());
            format!("accessor {a} float {slot} = {x}")
        }
        2 => {
            let r = w.accessor_bytes(3);
            let (u, v) = *rng.pick(&[(2.0f32, -1.0f32), (1e30, 1e30), (-0.0, 1.0), (0.5, 0.5)]);
            let all = rng.chance(50);
            for k in 0..r.len() / 8 {
                if all || rng.chance(10) {
                    w.bin[r.start + 8 * k..][..4].copy_from_slice(&u.to_le_bytes());
                    w.bin[r.start + 8 * k + 4..][..4].copy_from_slice(&v.to_le_bytes());
                }
            }
            format!("texcoords = ({u}, {v}) (all: {all})")
        }
        3 => {
            let (c, m) = *rng.pick(&[(5123u32, 2u64), (5121, 4)]);
            let count = w.doc["accessors"][index_accessor]["count"]
                .as_u64()
                .unwrap();
            w.doc["accessors"][index_accessor]["componentType"] = json!(c);
            w.doc["accessors"][index_accessor]["count"] = json!(count * m);
            format!("indices read as componentType {c}")
        }
        4 => {
            let count = w.doc["accessors"][index_accessor]["count"]
                .as_u64()
                .unwrap();
            let d = 1 + rng.below(2) as u64;
            w.doc["accessors"][index_accessor]["count"] = json!(count - d);
            format!("indices count - {d}")
        }
        5 => {
            w.bin[indices.clone()].fill(0);
            "every index 0".into()
        }
        6 => {
            let r = w.accessor_bytes(0);
            let x = *rng.pick(&[0.0f32, 1e30, -1e30, 3e38]);
            for k in 0..r.len() / 4 {
                w.bin[r.start + 4 * k..][..4].copy_from_slice(&x.to_le_bytes());
            }
            format!("every position component = {x}")
        }
        _ => {
            let a = 1 + rng.below(2);
            let r = w.accessor_bytes(a);
            w.bin[r].fill(0);
            format!("accessor {a} all zeros")
        }
    };
    made(w.bytes(), what)
}

fn mesh_structure(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let p0 = w.doc["meshes"][0]["primitives"][0].clone();
    let what = match rng.below(13) {
        0 => {
            let n = *rng.pick(&[1usize, 100]);
            let m = w.doc["meshes"][0].clone();
            w.doc["meshes"].as_array_mut().unwrap().extend(vec![m; n]);
            format!("mesh 0 duplicated {n} times")
        }
        1 => {
            let n = *rng.pick(&[1usize, 1000]);
            w.doc["meshes"][0]["primitives"]
                .as_array_mut()
                .unwrap()
                .extend(vec![p0.clone(); n]);
            format!("primitive 0 duplicated {n} times")
        }
        2 => {
            let mut m = w.doc["meshes"][0].clone();
            m["primitives"][0]["mode"] = json!(0);
            m["primitives"][0]["attributes"] = json!({});
            w.doc["meshes"].as_array_mut().unwrap().insert(0, m);
            "a broken copy of mesh 0 first".into()
        }
        3 => {
            let mode = *rng.pick(&[0, 1, 2, 3, 5, 6, 7, -1, 4]);
            w.doc["meshes"][0]["primitives"][0]["mode"] = json!(mode);
            format!("mode = {mode}")
        }
        4 => {
            let attrs = &mut w.doc["meshes"][0]["primitives"][0]["attributes"];
            let k = *rng.pick(&["POSITION", "NORMAL", "TANGENT", "TEXCOORD_0"]);
            match rng.below(4) {
                0 => {
                    attrs.as_object_mut().unwrap().remove(k);
                    format!("attribute {k} removed")
                }
                1 => {
                    let v = attrs.as_object_mut().unwrap().remove(k).unwrap();
                    attrs[format!("{k}_X")] = v;
                    format!("attribute {k} renamed")
                }
                2 => {
                    attrs["TEXCOORD_1"] = json!(3);
                    attrs["COLOR_0"] = json!(2);
                    attrs["JOINTS_0"] = json!(0);
                    "extra attributes".into()
                }
                _ => {
                    attrs[k] = p0["indices"].clone();
                    format!("attribute {k} = the indices' accessor")
                }
            }
        }
        5 => {
            if rng.chance(50) {
                let n = w.len("materials");
                w.doc["meshes"][0]["primitives"][0]["material"] = json!(n);
                format!("material = {n}")
            } else {
                w.doc["materials"] = json!([]);
                "materials = []".into()
            }
        }
        6 => {
            let prim = w.doc["meshes"][0]["primitives"][0].as_object_mut().unwrap();
            if rng.chance(50) {
                prim.remove("indices");
                "indices removed".into()
            } else {
                prim.insert("indices".into(), json!(0));
                "indices = accessor 0 (floats)".into()
            }
        }
        7 => {
            w.doc["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": 0}]);
            "a morph target".into()
        }
        8 => {
            if rng.chance(50) {
                w.doc["meshes"] = json!([]);
                "meshes = []".into()
            } else {
                w.doc["meshes"][0]["primitives"] = json!([]);
                "primitives = []".into()
            }
        }
        9 => {
            let ext = *rng.pick(&["KHR_draco_mesh_compression", "EXT_meshopt_compression", "x"]);
            w.doc["extensionsRequired"] = json!([ext]);
            w.doc["extensionsUsed"] = json!([ext]);
            format!("extension {ext} required")
        }
        10 => match rng.below(3) {
            0 => {
                w.doc["scene"] = json!(5);
                "scene = 5".into()
            }
            1 => {
                w.doc["nodes"][0]["children"] = json!([0]);
                "node 0 its own child".into()
            }
            _ => {
                w.doc["nodes"] = json!([]);
                "nodes = []".into()
            }
        },
        11 => {
            let t = w.len("textures");
            match rng.below(5) {
                0 => {
                    w.doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] =
                        json!(t);
                    format!("baseColorTexture = {t}")
                }
                1 => {
                    w.doc["textures"][0]["source"] = json!(99);
                    "textures.0.source = 99".into()
                }
                2 => {
                    w.doc["textures"][0]["sampler"] = json!(99);
                    "textures.0.sampler = 99".into()
                }
                3 => {
                    w.doc["materials"][0]["emissiveTexture"] = json!({"index": 0});
                    "emissiveTexture = texture 0".into()
                }
                _ => {
                    let m = w.doc["materials"][0].as_object_mut().unwrap();
                    m.remove("emissiveTexture");
                    m.remove("normalTexture");
                    "normal and emissive textures removed".into()
                }
            }
        }
        _ => {
            let key = *rng.pick(&["meshes", "accessors", "bufferViews", "images", "extras"]);
            let text = w.text();
            let text = format!("{{\"{key}\":[],{}", &text[1..]);
            return made(
                join_text(text.into_bytes(), &w.bin),
                format!("duplicate key {key} (an empty one first)"),
            );
        }
    };
    made(w.bytes(), what)
}

fn deep_nesting(base: &Base, rng: &mut Rng, big: bool) -> Made {
    let mut w = Work::new(base);
    let depths: &[usize] = if big {
        &[127, 128, 129, 1000, 10_000, 100_000, 1_000_000]
    } else {
        &[127, 128, 129, 1000, 10_000, 100_000]
    };
    let depth = *rng.pick(depths);
    let closed = rng.chance(80);
    let text = match rng.below(3) {
        0 => format!(
            "{}{}",
            "[".repeat(depth),
            if closed {
                "]".repeat(depth)
            } else {
                String::new()
            }
        ),
        1 => format!(
            "{}0{}",
            "{\"a\":".repeat(depth),
            if closed {
                "}".repeat(depth)
            } else {
                String::new()
            }
        ),
        _ => format!(
            "{}{}",
            "[{\"a\":".repeat(depth / 2),
            if closed {
                "}]".repeat(depth / 2)
            } else {
                String::new()
            }
        ),
    };
    let at = rng.below(6);
    let raw = w.raw(text);
    let place = match at {
        0 => {
            w.doc["deep"] = raw;
            "the root"
        }
        1 => {
            w.doc["extras"]["deep"] = raw;
            "the root's extras"
        }
        2 => {
            w.layout()["deep"] = raw;
            "the atlas layout"
        }
        3 => {
            w.doc["accessors"][0]["extras"] = raw;
            "accessor 0's extras"
        }
        4 => {
            w.doc["meshes"][0]["deep"] = raw;
            "mesh 0"
        }
        _ => {
            if w.layout().get("charts").is_some() {
                w.layout()["charts"] = raw;
                "the chart table"
            } else {
                w.layout()["level_origins"] = raw;
                "the level origins"
            }
        }
    };
    made(
        w.bytes(),
        format!("nesting {depth} deep (closed: {closed}) in {place}"),
    )
}

fn huge_arrays(base: &Base, rng: &mut Rng, big: bool) -> Made {
    let mut w = Work::new(base);
    let count = count_values(&w.doc);
    match rng.below(5) {
        0 | 1 => {
            // At the value limit: the unused array and its elements bring the count
            // to the limit + delta.
            let delta = *rng.pick(&[-2i64, -1, 0, 1, 2]);
            let n = MAX_JSON_VALUES as i64 - count as i64 - 1 + delta;
            let (place, objects) = *rng.pick(&[
                ("unused", false),
                ("unused", true),
                ("mesh", false),
                ("asset", false),
            ]);
            let element = if objects { json!({}) } else { json!(0) };
            let array = w.raw(format!(
                "[{}]",
                vec![element.to_string(); n as usize].join(",")
            ));
            match place {
                "mesh" => w.doc["meshes"][0]["unused"] = array,
                "asset" => w.doc["asset"]["unused"] = array,
                _ => w.doc["unused"] = array,
            }
            Made {
                bytes: w.bytes(),
                what: format!(
                    "an unused array in {place} bringing the values to the limit {delta:+}"
                ),
                over_value_limit: Some(delta > 0),
            }
        }
        2 => {
            let n = if big { 5_000_000 } else { 1_000_000 };
            let place = rng.below(3);
            let array = w.raw(format!("[{}]", vec!["0"; n].join(",")));
            match place {
                0 => w.doc["extras"]["padding"] = array,
                1 => w.doc["accessors"][0]["extras"] = json!({"padding": array}),
                _ => w.doc["meshes"][0]["extras"] = array,
            }
            made(w.bytes(), format!("{n} zeros in an extras ({place})"))
        }
        3 => {
            let n = *rng.pick(&[200_000usize, 1 << 20]);
            w.doc["unused"] = w.raw(format!("[{}]", vec![r#"{"a":[0]}"#; n].join(",")));
            made(w.bytes(), format!("{n} unused objects"))
        }
        _ => {
            let n = *rng.pick(&[1usize << 20, 16 << 20]);
            w.doc["asset"]["copyright"] = w.raw(format!("\"{}\"", "x".repeat(n)));
            made(w.bytes(), format!("a string of {n} bytes"))
        }
    }
}

fn layout_extras(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let packed = base.packed;
    let fields: &[&str] = if packed {
        &["width", "height", "cell_size", "levels"]
    } else {
        &["width", "height", "chart_size", "columns", "rows", "gutter"]
    };
    let what = match rng.below(9) {
        0 | 1 => {
            let mut set = Vec::new();
            for _ in 0..1 + rng.below(2) {
                let f = *rng.pick(fields);
                let n = *rng.pick(LAYOUT_NUMBERS);
                let v = w.raw(n);
                w.layout()[f] = v;
                set.push(format!("{f} = {n}"));
            }
            format!("layout {set:?}")
        }
        2 => {
            let key = if packed { "charts" } else { "level_origins" };
            let len = w.layout()[key].as_array().unwrap().len();
            let i = rng.below(len);
            let n = *rng.pick(LAYOUT_NUMBERS);
            let v = w.raw(n);
            let (field, c) = if packed {
                (*rng.pick(&["origin", "cells"]), rng.below(2))
            } else {
                ("", rng.below(2))
            };
            if packed {
                w.layout()[key][i][field][c] = v;
            } else {
                w.layout()[key][i][c] = v;
            }
            format!("layout {key}.{i}.{field}[{c}] = {n}")
        }
        3 => {
            let all: Vec<&str> = fields
                .iter()
                .copied()
                .chain([if packed { "charts" } else { "level_origins" }])
                .collect();
            let f = *rng.pick(&all);
            w.layout().as_object_mut().unwrap().remove(f);
            format!("layout field {f} removed")
        }
        4 => {
            let f = *rng.pick(fields);
            let v = wrong_value(rng, &mut w);
            let s = v.to_string().chars().take(40).collect::<String>();
            w.layout()[f] = v;
            format!("layout {f} = {s}")
        }
        5 => {
            let v = wrong_value(rng, &mut w);
            let s = v.to_string().chars().take(40).collect::<String>();
            if rng.chance(50) {
                w.doc["extras"]["sdfc_atlas"] = v;
                format!("extras.sdfc_atlas = {s}")
            } else {
                w.doc["extras"] = v;
                format!("extras = {s}")
            }
        }
        6 => {
            if packed {
                w.layout().as_object_mut().unwrap().remove("charts");
                "packed layout without its charts".into()
            } else {
                let l = w.layout();
                l["cell_size"] = json!(2);
                l["levels"] = json!(1);
                l["charts"] = json!([{"origin": [0, 0], "cells": [1, 1]}]);
                "flat layout with a packed layout's fields".into()
            }
        }
        7 => {
            let text = w.text();
            let (from, to) = if rng.chance(50) {
                ("\"sdfc_atlas\":{", "\"sdfc_atlas\":{\"width\":1,")
            } else {
                ("\"sdfc_atlas\":", "\"sdfc_atlas\":null,\"sdfc_atlas\":")
            };
            return made(
                join_text(text.replacen(from, to, 1).into_bytes(), &w.bin),
                format!("duplicate key: {to}"),
            );
        }
        _ => {
            let l = w.layout();
            l["unknown"] = json!({"a": [1, 2, 3]});
            l["k".repeat(10_000)] = json!(1);
            "unknown layout fields".into()
        }
    };
    made(w.bytes(), what)
}

fn chart_tables(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let what = if base.packed {
        let charts = w.layout()["charts"].as_array().unwrap().len();
        match rng.below(9) {
            0 => {
                let i = rng.below(charts);
                let c = w.layout()["charts"][i].clone();
                w.layout()["charts"].as_array_mut().unwrap().push(c);
                format!("chart {i} duplicated (overlap)")
            }
            1 => {
                let i = rng.below(charts);
                let d = *rng.pick(&[1u64, 2, 64, 8192, 1 << 31]);
                let o = w.layout()["charts"][i]["origin"][0].as_u64().unwrap();
                w.layout()["charts"][i]["origin"][0] = json!(o + d);
                format!("chart {i} moved right by {d}")
            }
            2 => {
                let keep = charts / 2;
                w.layout()["charts"].as_array_mut().unwrap().truncate(keep);
                format!("only the first {keep} charts")
            }
            3 => {
                w.layout()["charts"] = json!([]);
                "no charts".into()
            }
            4 => {
                let i = rng.below(charts);
                let c = w.layout()["charts"][i]["cells"].clone();
                w.layout()["charts"][i]["cells"] = json!([c[1], c[0]]);
                format!("chart {i}'s cells swapped")
            }
            5 => {
                let cells = *rng.pick(&[
                    [65536u32, 1],
                    [65537, 1],
                    [1, 65536],
                    [0, 1],
                    [65536, 65536],
                ]);
                let i = rng.below(charts);
                w.layout()["charts"][i]["cells"] = json!(cells);
                format!("chart {i}'s cells = {cells:?}")
            }
            6 => {
                // Overflowing u32 in the block's size: cells 65536 at a cell size of
                // 2^31 (31 levels), the image left as it is.
                let i = rng.below(charts);
                let (n, levels) = *rng.pick(&[(1u64 << 31, 31), (1 << 17, 17), (1 << 16, 16)]);
                let cells = *rng.pick(&[[65536u32, 1], [32769, 1], [1, 65536]]);
                let l = w.layout();
                l["cell_size"] = json!(n);
                l["levels"] = json!(levels);
                l["charts"][i]["cells"] = json!(cells);
                format!("cell_size {n}, levels {levels}, chart {i}'s cells {cells:?}")
            }
            7 => {
                let levels = *rng.pick(&[0u64, 2, 30, 31, 32]);
                w.layout()["levels"] = json!(levels);
                format!("levels = {levels}")
            }
            _ => {
                let c = w.layout()["charts"][0].clone();
                let n = 100_000;
                w.layout()["charts"] = Value::Array(vec![c; n]);
                format!("chart 0 {n} times")
            }
        }
    } else {
        let levels = w.layout()["level_origins"].as_array().unwrap().len();
        match rng.below(9) {
            0 => {
                let f = *rng.pick(&["columns", "rows"]);
                let x = w.layout()[f].as_u64().unwrap();
                let n = *rng.pick(&[x + 1, x * 2, x / 2, 1]);
                w.layout()[f] = json!(n);
                format!("{f} = {n} (was {x})")
            }
            1 => {
                let i = rng.below(levels);
                let j = rng.below(levels);
                w.layout()["level_origins"]
                    .as_array_mut()
                    .unwrap()
                    .swap(i, j);
                format!("level origins {i} and {j} swapped")
            }
            2 => {
                let n = *rng.pick(&[0usize, 1, levels + 1, 40]);
                let o = w.layout()["level_origins"][0].clone();
                w.layout()["level_origins"] = Value::Array(vec![o; n]);
                format!("{n} level origins")
            }
            3 => {
                let c = w.layout()["chart_size"].as_u64().unwrap();
                let n = *rng.pick(&[c / 2, c * 2, c + 1, 1 << 31]);
                w.layout()["chart_size"] = json!(n);
                format!("chart_size = {n} (was {c})")
            }
            4 => {
                let c = w.layout()["chart_size"].as_u64().unwrap();
                let g = *rng.pick(&[c / 2, c, c + 1, 1 << 30, 1 << 31]);
                w.layout()["gutter"] = json!(g);
                format!("gutter = {g}")
            }
            5 | 6 => {
                // Overflowing u32 in the level-0 stride: charts of 2^31 texels with a
                // gutter of 2^30 (the stride 2^31 + 2 · 2^30 wraps to 0), one level,
                // the image left as it is.
                let (n, g) = *rng.pick(&[(1u64 << 31, 1u64 << 30), (1 << 31, 1 << 31)]);
                let l = w.layout();
                l["chart_size"] = json!(n);
                l["gutter"] = json!(g);
                l["level_origins"] = json!([[0, 0]]);
                format!("chart_size {n}, gutter {g}, one level at (0, 0)")
            }
            7 => {
                let i = rng.below(levels);
                let x = *rng.pick(&[1u64, 8191, 1 << 31, u32::MAX as u64]);
                w.layout()["level_origins"][i] = json!([x, x]);
                format!("level {i} at ({x}, {x})")
            }
            _ => {
                let n = *rng.pick(&[65536u64, 1 << 31, u32::MAX as u64]);
                let l = w.layout();
                l["columns"] = json!(n);
                l["rows"] = json!(n);
                format!("a {n}×{n} chart grid")
            }
        }
    };
    made(w.bytes(), what)
}

fn image_types(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let images = w.len("images");
    let which = rng.chance(50).then(|| rng.below(images));
    let targets: Vec<usize> = (0..images)
        .filter(|&i| which.is_none_or(|w| w == i))
        .collect();
    let op = rng.below(6);
    let mut what = String::new();
    for i in targets {
        let image = &mut w.doc["images"][i];
        what = match op {
            0 => {
                let m = *rng.pick(&[
                    "image/jpeg",
                    "image/ktx2",
                    "image/webp",
                    "",
                    "IMAGE/PNG",
                    "image/png; charset=x",
                    "image/png\u{0}",
                ]);
                image["mimeType"] = json!(m);
                format!("mimeType {m:?}")
            }
            1 => {
                image.as_object_mut().unwrap().remove("mimeType");
                "no mimeType".into()
            }
            2 => {
                image["mimeType"] = rng
                    .pick(&[json!(1), json!(null), json!(["image/png"])])
                    .clone();
                "mimeType of another type".into()
            }
            3 => {
                let o = image.as_object_mut().unwrap();
                o.remove("bufferView");
                let uri = *rng.pick(&[
                    "base_color.png",
                    "data:image/png;base64,iVBORw0KGgo=",
                    "../../../../etc/passwd",
                    "/dev/zero",
                ]);
                o.insert("uri".into(), json!(uri));
                format!("uri {uri:?} instead of the buffer")
            }
            4 => {
                image["uri"] = json!("other.png");
                "both uri and bufferView".into()
            }
            _ => {
                image["bufferView"] = json!(0);
                "bufferView = the positions".into()
            }
        };
    }
    made(w.bytes(), format!("{what} (image {which:?}, None: all)"))
}

fn png_bytes(base: &Base, rng: &mut Rng, big: bool) -> Made {
    let mut w = Work::new(base);
    let (lw, lh) = (base.width, base.height);
    let images = w.len("images");
    let which = rng.chance(50).then(|| rng.below(images));
    // A real PNG of the layout's size to cut or damage.
    let real = encoded_png(lw, lh, ExtendedColorType::Rgb8, rng);
    let (png, what): (Vec<u8>, String) = match rng.below(16) {
        0 => {
            let at = rng.below(real.len());
            (real[..at].to_vec(), format!("a PNG cut at {at}"))
        }
        1 => {
            let n = *rng.pick(&[0usize, 1, 8, 100, 10_000]);
            (
                (0..n).map(|_| rng.next() as u8).collect(),
                format!("{n} garbage bytes"),
            )
        }
        2 => (PNG_SIGNATURE.to_vec(), "a PNG signature only".into()),
        3 => {
            let (x, y) = *rng.pick(&[
                (100_000u32, 100_000u32),
                (8193, 1),
                (1, 8193),
                (u32::MAX, u32::MAX),
                (0x8000_0000, 1),
            ]);
            let mut png = PNG_SIGNATURE.to_vec();
            let mut ihdr = x.to_be_bytes().to_vec();
            ihdr.extend(y.to_be_bytes());
            ihdr.extend([8, 6, 0, 0, 0]);
            png_chunk(&mut png, b"IHDR", &ihdr);
            png_chunk(&mut png, b"IEND", &[]);
            (png, format!("an IHDR claiming {x}×{y}, no data"))
        }
        4 => {
            let mut png = real.clone();
            let at = 8 + rng.below(png.len() - 8);
            png[at] ^= 1 << rng.below(8);
            (png, format!("a PNG with a bit flipped at {at}"))
        }
        5 => (jpeg(lw, lh), "a JPEG of the layout's size".into()),
        6 => {
            let c = *rng.pick(&[
                ExtendedColorType::L8,
                ExtendedColorType::La8,
                ExtendedColorType::Rgba8,
                ExtendedColorType::Rgb16,
                ExtendedColorType::Rgba16,
                ExtendedColorType::L16,
            ]);
            (encoded_png(lw, lh, c, rng), format!("a {c:?} PNG"))
        }
        7 => {
            let (depth, color) = *rng.pick(&[(8u8, 3u8), (1, 0), (2, 0), (4, 3), (16, 2), (7, 2)]);
            let extra: Vec<(&[u8], Vec<u8>)> = if color == 3 && rng.chance(50) {
                vec![(&b"PLTE"[..], vec![255; 3 * 4])]
            } else {
                vec![]
            };
            (
                raw_png(lw, lh, depth, color, 0, &extra),
                format!("depth {depth}, colour type {color}"),
            )
        }
        8 => (
            raw_png(lw, lh, 8, 2, 1, &[]),
            "an interlaced PNG with a non-interlaced amount of data".into(),
        ),
        9 => {
            // Text and profile chunks that inflate to much more than the image.
            let n: u64 = if big { 1 << 30 } else { 64 << 20 };
            let kind: &[u8] = *rng.pick(&[&b"zTXt"[..], b"iCCP", b"iTXt"]);
            let mut data = b"Comment\0".to_vec();
            match kind {
                b"iTXt" => data.extend([1, 0, 0, 0]),
                _ => data.push(0),
            }
            data.extend(zlib_zeros(n));
            (
                raw_png(lw, lh, 8, 2, 0, &[(kind, data)]),
                format!(
                    "a {} chunk inflating to {n} bytes",
                    String::from_utf8_lossy(kind)
                ),
            )
        }
        10 => {
            // The right IHDR, the IDAT of a larger image (a bomb in the data).
            let mut png = PNG_SIGNATURE.to_vec();
            let mut ihdr = lw.to_be_bytes().to_vec();
            ihdr.extend(lh.to_be_bytes());
            ihdr.extend([8, 2, 0, 0, 0]);
            png_chunk(&mut png, b"IHDR", &ihdr);
            let n: u64 = if big { 1 << 30 } else { 64 << 20 };
            png_chunk(&mut png, b"IDAT", &zlib_zeros(n));
            png_chunk(&mut png, b"IEND", &[]);
            (png, format!("IDAT inflating to {n} bytes for {lw}×{lh}"))
        }
        11 => {
            // The right IHDR, IDAT short by a row.
            let mut png = PNG_SIGNATURE.to_vec();
            let mut ihdr = lw.to_be_bytes().to_vec();
            ihdr.extend(lh.to_be_bytes());
            ihdr.extend([8, 2, 0, 0, 0]);
            png_chunk(&mut png, b"IHDR", &ihdr);
            png_chunk(
                &mut png,
                b"IDAT",
                &zlib_zeros((lh as u64 - 1) * (1 + 3 * lw as u64)),
            );
            png_chunk(&mut png, b"IEND", &[]);
            (png, "IDAT a row short".into())
        }
        12 => {
            // Many chunks: 100,000 empty unknown ancillary chunks before the data.
            let extra: Vec<(&[u8], Vec<u8>)> = vec![(&b"tEXt"[..], b"a\0b".to_vec()); 100_000];
            (
                raw_png(lw, lh, 8, 2, 0, &extra),
                "100,000 tEXt chunks".into(),
            )
        }
        13 => {
            // A second IHDR claiming a huge size, after the first.
            let mut ihdr = 100_000u32.to_be_bytes().to_vec();
            ihdr.extend(100_000u32.to_be_bytes());
            ihdr.extend([8, 6, 0, 0, 0]);
            (
                raw_png(lw, lh, 8, 2, 0, &[(&b"IHDR"[..], ihdr)]),
                "a second IHDR of 100000×100000".into(),
            )
        }
        14 => {
            // An APNG control chunk claiming many frames.
            let mut actl = u32::MAX.to_be_bytes().to_vec();
            actl.extend(0u32.to_be_bytes());
            (
                raw_png(lw, lh, 8, 2, 0, &[(&b"acTL"[..], actl)]),
                "an acTL of 4294967295 frames".into(),
            )
        }
        _ => {
            let mut png = real.clone();
            png.truncate(png.len() - 12);
            (png, "a PNG without IEND".into())
        }
    };
    w.set_image(which, &png);
    made(w.bytes(), format!("{what} (image {which:?}, None: all)"))
}

fn texture_sizes(base: &Base, rng: &mut Rng, _: bool) -> Made {
    let mut w = Work::new(base);
    let (lw, lh) = (base.width, base.height);
    let images = w.len("images");
    let which = rng.chance(60).then(|| rng.below(images));
    if rng.chance(15) {
        // A fourth (emissive) texture of another size.
        let png = encoded_png(lw + 1, lh, ExtendedColorType::Rgb8, rng);
        let view = w.append(&png);
        let images = w.doc["images"].as_array_mut().unwrap();
        images.push(json!({"bufferView": view, "mimeType": "image/png"}));
        let image = images.len() - 1;
        let textures = w.doc["textures"].as_array_mut().unwrap();
        textures.push(json!({"source": image, "sampler": 0}));
        let texture = textures.len() - 1;
        w.doc["materials"][0]["emissiveTexture"] = json!({"index": texture});
        return made(w.bytes(), format!("an emissive texture of {}×{lh}", lw + 1));
    }
    let (x, y) = *rng.pick(&[
        (lw + 1, lh),
        (lw - 1, lh),
        (lw, lh + 1),
        (lw, lh - 1),
        (lh, lw),
        (1, 1),
        (lw * 2, lh * 2),
        (lw / 2, lh / 2),
        (0, 0),
        (0, lh),
        (8192, 8192),
    ]);
    let png = if x == 0 || y == 0 || x as u64 * y as u64 > 1 << 20 {
        solid_png(x, y)
    } else {
        encoded_png(x, y, ExtendedColorType::Rgb8, rng)
    };
    w.set_image(which, &png);
    made(
        w.bytes(),
        format!("a {x}×{y} PNG for a {lw}×{lh} atlas (image {which:?}, None: all)"),
    )
}

fn big_atlas(base: &Base, rng: &mut Rng, big: bool) -> Made {
    let mut w = Work::new(base);
    let sizes: &[(u32, u32)] = if big {
        &[
            (1024, 1024),
            (2048, 2048),
            (4096, 4096),
            (8192, 4096),
            (8192, 8192),
        ]
    } else {
        &[(256, 256), (1024, 512), (2048, 1024), (8192, 8192)]
    };
    let (x, y) = *rng.pick(sizes);
    let (x, y) = (x.max(base.width), y.max(base.height));
    let l = w.layout();
    l["width"] = json!(x);
    l["height"] = json!(y);
    w.set_image(None, &solid_png(x, y));
    made(
        w.bytes(),
        format!("the atlas enlarged to {x}×{y}, with solid PNGs of that size"),
    )
}

/// Many vertices on one chart of a packed atlas whose 64-texel tile holds 1,024
/// one-cell charts (2 × 2 texels each): the renderer finds each vertex's chart by
/// scanning its tile's charts. One triangle is drawn. Written by the library (valid
/// throughout).
fn chart_search(_: &Base, rng: &mut Rng, big: bool) -> Made {
    let sizes: &[usize] = if big {
        &[100_000, 1_000_000]
    } else {
        &[3_000, 30_000]
    };
    let n = *rng.pick(sizes);
    let charts: Vec<PackedChart> = (0..1024)
        .map(|k| PackedChart {
            origin: [2 * (k % 32), 2 * (k / 32)],
            cells: [1, 1],
        })
        .collect();
    let layout = PackedLayout {
        width: 64,
        height: 64,
        cell_size: 2,
        levels: 1,
        charts,
    };
    let target = if rng.chance(50) {
        1023
    } else {
        rng.below(1024)
    };
    let mut mesh = MeshData::default();
    for i in 0..n {
        let t = i as f32 / n as f32;
        mesh.positions.push([t, (i % 3) as f32, 0.0]);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.tangents.push([1.0, 0.0, 0.0, 1.0]);
        mesh.texcoords
            .push(layout.texcoord(target, (i % 2) as f64, (i % 5) as f64 / 4.0));
    }
    // One triangle: the cost measured is the search's, not the GPU's.
    mesh.indices = vec![0, 1, 2];
    let image = RgbaImage::from_pixel(64, 64, Rgba([90, 120, 200, 255]));
    let textures = Textures {
        base_color: image.clone(),
        metallic_roughness: image.clone(),
        normal: image,
        emissive: None,
        emissive_strength: 1.0,
    };
    let bytes = glb(
        &mesh,
        &textures,
        &ChartLayout::Packed(layout),
        "search",
        "search",
    )
    .unwrap();
    made(
        bytes,
        format!("{n} vertices on one packed chart (number {target} of 1024 in one 64-texel tile)"),
    )
}

/// Many copies of one triangle that covers much of the frame, on a flat atlas of one
/// chart: every fragment shaded as many times (the GPU's work, on lavapipe the CPU's).
fn overdraw(_: &Base, rng: &mut Rng, big: bool) -> Made {
    let sizes: &[usize] = if big {
        &[30_000, 300_000]
    } else {
        &[300, 3_000]
    };
    let n = *rng.pick(sizes);
    let layout = FlatLayout::fit(1, 64).unwrap();
    let mut mesh = MeshData::default();
    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)];
    for i in 0..3 * n {
        let (u, v) = corners[i % 3];
        mesh.positions
            .push([u as f32, v as f32, (i / 3) as f32 * 1e-6]);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.tangents.push([1.0, 0.0, 0.0, 1.0]);
        mesh.texcoords.push(layout.texcoord(0, u, v));
    }
    mesh.indices = (0..3 * n as u32).collect();
    let image = RgbaImage::from_pixel(layout.width, layout.height, Rgba([200, 90, 60, 255]));
    let textures = Textures {
        base_color: image.clone(),
        metallic_roughness: image.clone(),
        normal: image,
        emissive: None,
        emissive_strength: 1.0,
    };
    let bytes = glb(
        &mesh,
        &textures,
        &ChartLayout::Flat(layout),
        "overdraw",
        "overdraw",
    )
    .unwrap();
    made(
        bytes,
        format!("{n} copies of a triangle covering half the frame"),
    )
}

// ---------------------------------------------------------------------------------
// Running a variant.

#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
enum Outcome {
    Ok,
    Invalid,
    Limit,
    /// `targets::glb` panicked (a failure): the binary still runs it.
    Panic,
}

/// `read_glb` through `targets::glb` on a thread of its own: the outcome, or the
/// panic's message; `None` past [`TIME_LIMIT`] (the thread is left running).
fn read_in_process(bytes: Vec<u8>) -> Option<Result<(Outcome, String), String>> {
    let (tx, rx) = mpsc::channel();
    std::thread::Builder::new()
        .name("read_glb".into())
        .spawn(move || {
            let r = std::panic::catch_unwind(AssertUnwindSafe(|| targets::glb(&bytes)));
            let r = match r {
                Ok(Ok(())) => Ok((Outcome::Ok, String::new())),
                Ok(Err(ReadError::Invalid(m))) => Ok((Outcome::Invalid, m)),
                Ok(Err(ReadError::Limit(m))) => Ok((Outcome::Limit, m)),
                Err(p) => Err(p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default()),
            };
            let _ = tx.send(r);
        })
        .unwrap();
    rx.recv_timeout(TIME_LIMIT).ok()
}

/// A run of `sdfc render`.
struct Render {
    code: Option<i32>,
    signal: Option<i32>,
    /// Peak resident memory in bytes (GNU time's %M), when measured.
    peak: Option<u64>,
    secs: f64,
    timed_out: bool,
    stderr: String,
    wrote_output: bool,
}

/// `sdfc render FILE --size 32x24 -o OUT.png` under `/usr/bin/time` (its own process
/// group, killed whole past [`TIME_LIMIT`]).
fn render(file: &Path) -> Render {
    let out = file.with_extension("png");
    let stats = file.with_extension("time");
    let err = file.with_extension("err");
    let _ = std::fs::remove_file(&out);
    let _ = std::fs::remove_file(&stats);
    let gnu_time = Path::new("/usr/bin/time").exists();
    let mut cmd = if gnu_time {
        let mut c = Command::new("/usr/bin/time");
        c.args(["-f", "%M %x %e", "-o"])
            .arg(&stats)
            .arg(env!("CARGO_BIN_EXE_sdfc"));
        c
    } else {
        Command::new(env!("CARGO_BIN_EXE_sdfc"))
    };
    cmd.arg("render")
        .arg(file)
        .args(["--size", "32x24", "-o"])
        .arg(&out)
        .current_dir(file.parent().unwrap())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&err).unwrap());
    #[cfg(unix)]
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    let start = Instant::now();
    let mut child = cmd.spawn().unwrap();
    let mut timed_out = false;
    let mut polled_peak = 0u64;
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if !gnu_time {
            polled_peak = polled_peak.max(vm_hwm(&format!("/proc/{}/status", child.id())));
        }
        if start.elapsed() > TIME_LIMIT {
            timed_out = true;
            kill_group(&mut child);
            break child.wait().unwrap();
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let secs = start.elapsed().as_secs_f64();
    let mut run = Render {
        code: status.code(),
        signal: None,
        peak: (!gnu_time && polled_peak > 0).then_some(polled_peak),
        secs,
        timed_out,
        stderr: std::fs::read_to_string(&err).unwrap_or_default(),
        wrote_output: out.exists(),
    };
    #[cfg(unix)]
    {
        run.signal = std::os::unix::process::ExitStatusExt::signal(&status);
    }
    if gnu_time {
        let text = std::fs::read_to_string(&stats).unwrap_or_default();
        for line in text.lines() {
            if let Some(s) = line.strip_prefix("Command terminated by signal ") {
                run.signal = s.trim().parse().ok();
                run.code = None;
            }
        }
        if let Some(last) = text.lines().last() {
            let f: Vec<&str> = last.split_whitespace().collect();
            if f.len() == 3 {
                run.peak = f[0].parse::<u64>().ok().map(|kb| kb * 1024);
                if run.signal.is_none() {
                    run.code = f[1].parse().ok();
                }
            }
        }
    }
    let _ = std::fs::remove_file(&out);
    run
}

fn kill_group(child: &mut std::process::Child) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    unsafe {
        libc::kill(-(child.id() as i32), libc::SIGKILL);
    }
    let _ = child.kill();
}

/// VmHWM (peak resident memory) in a /proc status file, in bytes (0 if absent).
fn vm_hwm(status: &str) -> u64 {
    std::fs::read_to_string(status)
        .unwrap_or_default()
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

// ---------------------------------------------------------------------------------
// The campaign.

struct Plan {
    /// Variants per kind.
    per_kind: usize,
    /// Every `ok_every`-th accepted file through the binary, and every `err_every`-th
    /// refused one (besides the first of each kind and the first accepted of each).
    ok_every: usize,
    err_every: usize,
    big: bool,
    min_in_process: usize,
    min_binary: usize,
}

#[derive(Default)]
struct Tally {
    /// Per kind: how many of each outcome.
    outcomes: BTreeMap<&'static str, BTreeMap<Outcome, usize>>,
    codes: BTreeMap<String, usize>,
    in_process: usize,
    binary: usize,
    slowest_read: (f64, String),
    slowest_render: (f64, String),
    peak_render: (u64, String),
    /// The test process's VmHWM after each read, and the read that raised it last.
    peak_read: (u64, String),
    /// Accepted files the renderer then refused (exit 2), with its message.
    render_refusals: Vec<String>,
    failures: Vec<String>,
}

fn seed() -> u64 {
    match std::env::var("GLB_FUZZ_SEED") {
        Ok(s) => s
            .strip_prefix("0x")
            .map_or_else(|| s.parse(), |h| u64::from_str_radix(h, 16))
            .expect("GLB_FUZZ_SEED: a number"),
        Err(_) => DEFAULT_SEED,
    }
}

fn campaign(plan: Plan) {
    let seed = seed();
    let dir = tempfile::tempdir().unwrap();
    let kept = Path::new(env!("CARGO_TARGET_TMPDIR")).join("glb_fuzz");
    let bases = bases(dir.path());
    // A GPU adapter is needed for accepted files to render (exit 4 without one).
    let control = render(&write(dir.path(), "control.glb", &bases[0].bytes));
    let no_gpu = control.code == Some(4);
    assert!(
        control.code == Some(0) || no_gpu,
        "the unmodified {} does not render: {:?} {}",
        bases[0].name,
        control.code,
        control.stderr
    );
    if no_gpu {
        eprintln!("note: no GPU adapter: accepted files may exit 4");
    }
    let flat: Vec<usize> = (0..bases.len()).filter(|&b| !bases[b].packed).collect();
    let mut t = Tally::default();
    let mut first_of_kind = std::collections::HashSet::new();
    let mut first_ok_of_kind = std::collections::HashSet::new();
    let mut big_seen = std::collections::HashSet::new();
    let (mut oks, mut errs) = (0usize, 0usize);
    let started = Instant::now();
    // A read past the time limit leaves its thread running: the campaign stops.
    let mut stuck = false;
    for round in 0..plan.per_kind {
        for (k, &(kind, mutate)) in KINDS.iter().enumerate() {
            let index = round * KINDS.len() + k;
            let mut rng = Rng::new(seed ^ (index as u64).wrapping_mul(0x9E37_79B9));
            let b = if kind == "big-atlas" {
                flat[rng.below(flat.len())]
            } else {
                rng.below(bases.len())
            };
            let base = &bases[b];
            let m = mutate(base, &mut rng, plan.big);
            let tag = format!(
                "seed {seed:#x} variant {index} ({kind} of {}): {}",
                base.name, m.what
            );
            // The failing file is kept when small (the seed regenerates any).
            let fail = |t: &mut Tally, why: String| {
                let kept = if m.bytes.len() <= 4 << 20 {
                    std::fs::create_dir_all(&kept).unwrap();
                    let file = kept.join(format!("{seed:x}-{index}-{kind}.glb"));
                    std::fs::write(&file, &m.bytes).unwrap();
                    format!("file {}", file.display())
                } else {
                    format!("{} bytes, not kept", m.bytes.len())
                };
                t.failures.push(format!("{tag}: {why} ({kept})"));
            };
            let start = Instant::now();
            let result = read_in_process(m.bytes.clone());
            let hwm = vm_hwm("/proc/self/status");
            if hwm > t.peak_read.0 {
                t.peak_read = (hwm, tag.clone());
            }
            let secs = start.elapsed().as_secs_f64();
            t.in_process += 1;
            if secs > t.slowest_read.0 {
                t.slowest_read = (secs, tag.clone());
            }
            let (outcome, message) = match result {
                None => {
                    fail(&mut t, format!("read_glb took over {TIME_LIMIT:?}"));
                    stuck = true;
                    // The thread is still running: stop here.
                    break;
                }
                Some(Err(panic)) => {
                    fail(&mut t, format!("panicked: {panic}"));
                    (Outcome::Panic, panic)
                }
                Some(Ok(x)) => x,
            };
            *t.outcomes
                .entry(kind)
                .or_default()
                .entry(outcome)
                .or_default() += 1;
            if let Some(over) = m.over_value_limit {
                let limited = outcome == Outcome::Limit && message.contains("values");
                if over != limited {
                    fail(
                        &mut t,
                        format!("the value limit: over {over}, got {outcome:?} {message}"),
                    );
                }
            }
            let through = match outcome {
                Outcome::Ok => {
                    oks += 1;
                    first_ok_of_kind.insert(kind) || oks % plan.ok_every == 0
                }
                Outcome::Panic => true,
                _ => {
                    errs += 1;
                    errs % plan.err_every == 0
                }
            };
            // In the full campaign, the costly kinds' each size once (what they made, up
            // to a parenthesis), instead of the sample.
            let costly = plan.big && RENDER_KINDS.contains(&kind);
            let size = m.what.split(" (").next().unwrap().to_owned();
            let through = if costly {
                outcome == Outcome::Ok && big_seen.insert(size)
            } else {
                through
            };
            let through = first_of_kind.insert(kind) | through;
            if !through {
                continue;
            }
            let file = write(dir.path(), &format!("v{index}.glb"), &m.bytes);
            let r = render(&file);
            std::fs::remove_file(&file).unwrap();
            t.binary += 1;
            let code = match (r.code, r.signal) {
                _ if r.timed_out => "killed after 20 s".into(),
                (_, Some(s)) => format!("signal {s}"),
                (Some(c), None) => c.to_string(),
                (None, None) => "none".into(),
            };
            *t.codes.entry(code.clone()).or_default() += 1;
            if r.secs > t.slowest_render.0 {
                t.slowest_render = (r.secs, tag.clone());
            }
            if let Some(p) = r.peak {
                if p > t.peak_render.0 {
                    t.peak_render = (p, tag.clone());
                }
                if p > MEMORY_LIMIT {
                    fail(&mut t, format!("render took {} MB", p / 1_000_000));
                }
            }
            let expected: &[i32] = match outcome {
                Outcome::Invalid => &[2],
                Outcome::Limit => &[5],
                Outcome::Ok | Outcome::Panic if no_gpu => &[0, 2, 4, 5],
                Outcome::Ok | Outcome::Panic => &[0, 2, 5],
            };
            if RENDER_KINDS.contains(&kind) {
                eprintln!(
                    "  {kind}: {}: exit {code}, {:.1} s, {} MB",
                    m.what,
                    r.secs,
                    r.peak.unwrap_or(0) / 1_000_000
                );
            }
            if r.timed_out {
                fail(&mut t, format!("render took over {TIME_LIMIT:?}"));
            } else if r.signal.is_some() || !r.code.is_some_and(|c| expected.contains(&c)) {
                fail(
                    &mut t,
                    format!(
                        "render exited {code}, expected {expected:?} (read_glb: {outcome:?} {message}): {}",
                        r.stderr.trim()
                    ),
                );
            } else if r.code != Some(0) && r.wrote_output {
                fail(&mut t, format!("render exited {code} but wrote its output"));
            }
            if outcome == Outcome::Ok && r.code == Some(2) {
                t.render_refusals
                    .push(format!("{tag}: {}", r.stderr.trim()));
            }
        }
        if stuck {
            break;
        }
    }
    let own_peak = vm_hwm("/proc/self/status");
    if own_peak > MEMORY_LIMIT {
        t.failures.push(format!(
            "the test process peaked at {} MB",
            own_peak / 1_000_000
        ));
    }

    eprintln!(
        "glb_fuzz: seed {seed:#x}, {} bases ({}), {} variants in-process, {} through the binary, {:.1} s",
        bases.len(),
        bases.iter().map(|b| b.name.as_str()).collect::<Vec<_>>().join(", "),
        t.in_process,
        t.binary,
        started.elapsed().as_secs_f64()
    );
    let mut totals: BTreeMap<Outcome, usize> = BTreeMap::new();
    for (kind, o) in &t.outcomes {
        eprintln!("  {kind:16} {o:?}");
        for (k, n) in o {
            *totals.entry(*k).or_default() += n;
        }
    }
    eprintln!("  outcomes: {totals:?}");
    eprintln!("  exit codes: {:?}", t.codes);
    eprintln!(
        "  slowest read_glb: {:.3} s, {}",
        t.slowest_read.0, t.slowest_read.1
    );
    eprintln!(
        "  slowest render: {:.2} s, {}",
        t.slowest_render.0, t.slowest_render.1
    );
    eprintln!(
        "  peak render memory: {} MB, {}",
        t.peak_render.0 / 1_000_000,
        t.peak_render.1
    );
    eprintln!(
        "  test process peak (VmHWM): {} MB, last raised by {}",
        own_peak / 1_000_000,
        t.peak_read.1
    );
    for r in &t.render_refusals {
        eprintln!("  accepted, then refused by the renderer: {r}");
    }
    assert!(
        t.failures.is_empty(),
        "{} failures:\n{}",
        t.failures.len(),
        t.failures.join("\n")
    );
    assert!(
        t.in_process >= plan.min_in_process,
        "only {} variants in-process",
        t.in_process
    );
    assert!(
        t.binary >= plan.min_binary,
        "only {} through the binary",
        t.binary
    );
    assert!(
        t.outcomes.len() == KINDS.len(),
        "kinds without an outcome: {:?}",
        KINDS
            .iter()
            .filter(|k| !t.outcomes.contains_key(k.0))
            .collect::<Vec<_>>()
    );
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// A bounded campaign in every `cargo test`: 50 variants of each kind in-process, the
/// first of each kind and a sample through the binary.
#[test]
fn hostile_glb_files_are_refused_or_rendered_safely() {
    // The test process's peak memory is this test's alone.
    if !crate::common::in_own_process("glb_fuzz::hostile_glb_files_are_refused_or_rendered_safely")
    {
        return;
    }
    campaign(Plan {
        per_kind: 50,
        ok_every: 8,
        err_every: 20,
        big: false,
        min_in_process: 50 * KINDS.len(),
        min_binary: KINDS.len(),
    });
}

/// The full campaign: 60 variants of each kind (1,320) in-process, with larger cases
/// (textures up to 8192 × 8192, nesting a million deep, inflation bombs of 1 GiB),
/// and at least 100 through the binary.
#[test]
#[ignore = "minutes: cargo test --release --test suite glb_fuzz:: -- --ignored --nocapture"]
fn hostile_glb_files_full_campaign() {
    // The test process's peak memory is this test's alone.
    if !crate::common::in_own_process("glb_fuzz::hostile_glb_files_full_campaign") {
        return;
    }
    campaign(Plan {
        per_kind: 60,
        ok_every: 4,
        err_every: 10,
        big: true,
        min_in_process: 1000,
        min_binary: 100,
    });
}

/// Boundaries checked exactly once: serde_json's recursion limit (128) refuses deep
/// nesting outside `extras` before it overflows the stack, and inside `extras` the
/// raw text is skipped without recursion.
#[test]
fn deep_nesting_is_refused_or_skipped_without_overflowing_the_stack() {
    let base = Base::new("quad", library_quad(false));
    for depth in [10_000usize, 100_000] {
        for inside_extras in [false, true] {
            let mut w = Work::new(&base);
            let raw = w.raw(format!("{}{}", "[".repeat(depth), "]".repeat(depth)));
            if inside_extras {
                w.doc["extras"]["deep"] = raw;
            } else {
                w.doc["deep"] = raw;
            }
            let r = read_in_process(w.bytes()).expect("in time");
            let (outcome, message) = r.unwrap_or_else(|p| panic!("panicked: {p}"));
            if inside_extras {
                assert_eq!(outcome, Outcome::Ok, "{message}");
            } else {
                assert_eq!(outcome, Outcome::Invalid, "{message}");
                assert!(message.contains("recursion limit"), "{message}");
            }
        }
    }
}

/// The renderer's search for each vertex's packed chart, at its worst: a million
/// vertices (a 50 MB file) on the last of 1,024 charts in one tile. Within the time
/// limit, like any other file.
#[test]
#[ignore = "a 50 MB file through the binary: cargo test --release --test suite glb_fuzz:: -- --ignored"]
fn a_packed_chart_search_of_a_million_vertices_finishes_in_time() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng::new(1);
    let base = Base::new("quad", library_quad(true));
    let m = loop {
        let m = chart_search(&base, &mut rng, true);
        if m.what
            .starts_with("1000000 vertices on one packed chart (number 1023 ")
        {
            break m;
        }
    };
    let start = Instant::now();
    let (outcome, message) = read_in_process(m.bytes.clone()).unwrap().unwrap();
    assert_eq!(outcome, Outcome::Ok, "{message}");
    eprintln!(
        "{} bytes, read in {:.2} s",
        m.bytes.len(),
        start.elapsed().as_secs_f64()
    );
    let r = render(&write(dir.path(), "search.glb", &m.bytes));
    eprintln!(
        "render: {:?} in {:.1} s, {} MB: {}",
        r.code,
        r.secs,
        r.peak.unwrap_or(0) / 1_000_000,
        r.stderr.trim()
    );
    assert!(!r.timed_out, "render took over {TIME_LIMIT:?}");
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}

/// A flat layout whose level-0 stride overflows u32: charts of 2^31 texels with a
/// gutter of 2^30 (2^31 + 2 · 2^30 = 2^32), one level, in the quad's 64 × 48 image.
/// Its grid is far outside the image: refused as invalid (a wrapping sum would make
/// the stride 0 and the grid fit; an overflow check would panic).
#[test]
fn a_flat_layout_whose_stride_overflows_u32_is_refused() {
    let base = Base::new("quad", library_quad(false));
    let mut w = Work::new(&base);
    let l = w.layout();
    l["chart_size"] = json!(1u64 << 31);
    l["gutter"] = json!(1u64 << 30);
    l["level_origins"] = json!([[0, 0]]);
    let (outcome, message) = read_in_process(w.bytes())
        .expect("in time")
        .unwrap_or_else(|p| panic!("panicked: {p}"));
    assert_eq!(outcome, Outcome::Invalid, "{message}");
}

/// A packed layout whose chart block overflows u32: a chart of 65,536 × 1 cells at a
/// cell size of 2^31 (31 levels), 65,536 · (2^31 − 1) + 1 texels wide. Refused as
/// invalid, without an overflow.
#[test]
fn a_packed_layout_whose_block_overflows_u32_is_refused() {
    let base = Base::new("quad", library_quad(true));
    let mut w = Work::new(&base);
    let l = w.layout();
    l["cell_size"] = json!(1u64 << 31);
    l["levels"] = json!(31);
    l["charts"][0]["cells"] = json!([65536, 1]);
    let (outcome, message) = read_in_process(w.bytes())
        .expect("in time")
        .unwrap_or_else(|p| panic!("panicked: {p}"));
    assert_eq!(outcome, Outcome::Invalid, "{message}");
}
