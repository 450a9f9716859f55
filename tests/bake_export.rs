//! The bake's export formats (src/bake/export): the .glb round trip, the Khronos
//! glTF-Validator's verdict on it, the reader on broken files, and the .ktx2 against an
//! independent parser (the `ktx2` crate).

use crate::common;

use common::glb::{join_text, split};

use image::{Rgba, RgbaImage};
use sdfc::bake::export::{check_atlas, check_mesh, check_textures, glb, ktx2, read_glb};
use sdfc::bake::ChartLayout;
use sdfc::bake::{FlatLayout, MeshData, Textures};
use serde_json::{json, Value};

/// A unit quad (chart 0, two triangles) beside a unit cube (charts 1 to 6, a quad of
/// four vertices per face), on a 64-texel atlas of 16-texel charts.
fn quad_and_cube() -> (MeshData, FlatLayout) {
    let layout = FlatLayout::fit(7, 64).unwrap();
    assert_eq!((layout.chart_size, layout.levels()), (16, 4));
    let mut mesh = MeshData::default();
    let mut face = |chart: usize, corner: [f32; 3], t: [f32; 3], b: [f32; 3], n: [f32; 3]| {
        let base = mesh.positions.len() as u32;
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            let p = std::array::from_fn(|c| corner[c] + u * t[c] + v * b[c]);
            mesh.positions.push(p);
            mesh.normals.push(n);
            mesh.tangents.push([t[0], t[1], t[2], 1.0]);
            mesh.texcoords
                .push(layout.texcoord(chart, u as f64, v as f64));
        }
        mesh.indices.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
    };
    face(
        0,
        [-2.5, -0.5, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    );
    // Each cube face: outward normal n, tangent t, bitangent n × t, so that (t, b) turns
    // counter-clockwise seen from outside.
    let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let faces = [
        (0, 1.0),
        (0, -1.0),
        (1, 1.0),
        (1, -1.0),
        (2, 1.0),
        (2, -1.0),
    ];
    for (chart, (i, sign)) in (1..).zip(faces) {
        let n: [f32; 3] = axes[i].map(|x| x * sign);
        let t = axes[(i + 1) % 3];
        let b = [
            n[1] * t[2] - n[2] * t[1],
            n[2] * t[0] - n[0] * t[2],
            n[0] * t[1] - n[1] * t[0],
        ];
        let corner = std::array::from_fn(|c| 0.5 * n[c] - 0.5 * t[c] - 0.5 * b[c]);
        face(chart, corner, t, b, n);
    }
    (mesh, layout)
}

/// Small patterned textures of the layout's size; the metallic-roughness image has a
/// varying alpha (stored as an RGBA PNG), the others are opaque (stored as RGB).
fn textures(layout: &FlatLayout, emissive: bool) -> Textures {
    let (w, h) = (layout.width, layout.height);
    let image = |f: &dyn Fn(u32, u32) -> [u8; 4]| RgbaImage::from_fn(w, h, |x, y| Rgba(f(x, y)));
    Textures {
        base_color: image(&|x, y| [(x * 4) as u8, (y * 4) as u8, 200, 255]),
        metallic_roughness: image(&|x, y| [0, (x ^ y) as u8 * 3, (x + y) as u8, (x * 3) as u8]),
        normal: image(&|x, y| [128 + (x % 7) as u8, 128 - (y % 5) as u8, 250, 255]),
        emissive: emissive.then(|| image(&|x, _| [(x * 2) as u8, 0, 0, 255])),
        emissive_strength: 1.0,
    }
}

fn assert_textures_eq(a: &Textures, b: &Textures) {
    assert!(a.base_color == b.base_color, "base colour differs");
    assert!(
        a.metallic_roughness == b.metallic_roughness,
        "metallic-roughness differs"
    );
    assert!(a.normal == b.normal, "normal differs");
    assert!(a.emissive == b.emissive, "emissive differs");
}

#[test]
fn glb_round_trip() {
    let (mesh, layout) = quad_and_cube();
    for emissive in [true, false] {
        let textures = textures(&layout, emissive);
        let bytes = glb(
            &mesh,
            &textures,
            &ChartLayout::from(layout.clone()),
            "quad and cube",
            "material",
        )
        .unwrap();
        assert_eq!(&bytes[..4], b"glTF");
        assert_eq!(bytes.len() % 4, 0);
        let (mesh2, textures2, layout2) = read_glb(&bytes).unwrap();
        assert_eq!(mesh2, mesh);
        assert_eq!(layout2, ChartLayout::from(layout.clone()));
        assert_textures_eq(&textures2, &textures);
    }
}

/// Emission over 1 travels as `KHR_materials_emissive_strength`: the strength reads
/// back as written, the extension is listed as used (not required) only where the
/// strength is not 1 and there is an emissive image, and a strength that is not a
/// finite number, 0 or more, is refused.
#[test]
fn the_emissive_strength_round_trips_as_its_extension() {
    let (mesh, layout) = quad_and_cube();
    let atlas = ChartLayout::from(layout.clone());
    let write = |emissive: bool, strength: f32| {
        let mut t = textures(&layout, emissive);
        t.emissive_strength = strength;
        glb(&mesh, &t, &atlas, "q", "material")
    };
    let bytes = write(true, 2.5).unwrap();
    let (_, back, _) = read_glb(&bytes).unwrap();
    assert_eq!(back.emissive_strength, 2.5);
    let (doc, _) = split(&bytes);
    assert_eq!(
        doc["extensionsUsed"],
        json!(["KHR_materials_emissive_strength"])
    );
    assert!(doc.get("extensionsRequired").is_none(), "{doc}");
    assert_eq!(
        doc["materials"][0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"],
        json!(2.5)
    );
    for (emissive, strength) in [(true, 1.0), (false, 2.5)] {
        let bytes = write(emissive, strength).unwrap();
        let (doc, _) = split(&bytes);
        assert!(doc.get("extensionsUsed").is_none(), "{doc}");
        assert!(doc["materials"][0].get("extensions").is_none(), "{doc}");
        let (_, back, _) = read_glb(&bytes).unwrap();
        assert_eq!(back.emissive_strength, 1.0);
    }
    for bad in [f32::NAN, f32::INFINITY, -1.0] {
        let e = write(true, bad).unwrap_err();
        assert!(e.contains("emissive strength"), "{e}");
    }
    // A file whose strength is negative is refused by the reader too.
    let (mut doc, bin) = split(&write(true, 2.5).unwrap());
    doc["materials"][0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] =
        json!(-3.0);
    let e = read_glb(&join_text(doc.to_string().into_bytes(), &bin)).unwrap_err();
    assert!(e.to_string().contains("emissive strength"), "{e}");
}

/// `weld` (the exported mesh's vertices shared inside charts) gives what welding every
/// vertex by its bits gives, for cells of n × n vertices whose inner vertices it does
/// not look up (n ≥ 3), whose sides are shared inside a chart and split across charts;
/// and it takes any vertex count and any n, 0 included, without a panic.
#[test]
fn weld_shares_the_side_vertices_as_welding_every_vertex_does() {
    use sdfc::bake::images::weld;
    // Welding every vertex by its bits, in first-seen order.
    let every = |m: &MeshData| {
        let mut out = MeshData::default();
        let mut seen = std::collections::HashMap::new();
        let remap: Vec<u32> = (0..m.positions.len())
            .map(|k| {
                let key: Vec<u32> = m.positions[k]
                    .iter()
                    .chain(&m.normals[k])
                    .chain(&m.tangents[k])
                    .chain(&m.texcoords[k])
                    .map(|x| x.to_bits())
                    .collect();
                *seen.entry(key).or_insert_with(|| {
                    out.positions.push(m.positions[k]);
                    out.normals.push(m.normals[k]);
                    out.tangents.push(m.tangents[k]);
                    out.texcoords.push(m.texcoords[k]);
                    out.positions.len() as u32 - 1
                })
            })
            .collect();
        out.indices = m.indices.iter().map(|&i| remap[i as usize]).collect();
        out
    };
    for n in [1usize, 2, 3, 4, 17] {
        // Chart 0: 2 × 2 cells of a plane, its texture coordinates continuous across
        // them; chart 1: one cell over the same points, with texture coordinates of
        // its own (split from chart 0 along every side).
        let mut mesh = MeshData::default();
        let q = (n.max(2) - 1) as f32;
        for (chart, cx, cy) in [(0, 0, 0), (0, 1, 0), (0, 0, 1), (0, 1, 1), (1, 0, 0)] {
            let base = mesh.positions.len() as u32;
            for j in 0..n {
                for i in 0..n {
                    let (x, y) = (
                        (cx as f32 * q + i as f32) / q,
                        (cy as f32 * q + j as f32) / q,
                    );
                    mesh.positions.push([x, y, 0.0]);
                    mesh.normals.push([0.0, 0.0, 1.0]);
                    mesh.tangents.push([1.0, 0.0, 0.0, 1.0]);
                    mesh.texcoords
                        .push([x * 0.25 + chart as f32 * 0.5, y * 0.25]);
                }
            }
            for j in 0..n.saturating_sub(1) {
                for i in 0..n - 1 {
                    let k = (j * n + i) as u32 + base;
                    let n = n as u32;
                    mesh.indices
                        .extend([k, k + 1, k + n + 1, k, k + n + 1, k + n]);
                }
            }
        }
        let welded = weld(&mesh, n);
        assert_eq!(welded, every(&mesh), "n = {n}");
        if n >= 2 {
            // Chart 0 is one grid of (2n − 1)² vertices, chart 1 keeps its n².
            assert_eq!(
                welded.positions.len(),
                (2 * n - 1).pow(2) + n * n,
                "n = {n}"
            );
        }
        // A count that is not whole cells, and n = 0: every vertex looked up.
        let mut cut = mesh.clone();
        cut.positions.pop();
        cut.normals.pop();
        cut.tangents.pop();
        cut.texcoords.pop();
        cut.indices.retain(|&i| (i as usize) < cut.positions.len());
        cut.indices.truncate(cut.indices.len() / 3 * 3);
        assert_eq!(weld(&cut, n), every(&cut), "n = {n}, cut");
        assert_eq!(weld(&mesh, 0), every(&mesh), "n = 0");
    }
}

#[test]
fn glb_document_structure() {
    let (mesh, layout) = quad_and_cube();
    let bytes = glb(
        &mesh,
        &textures(&layout, true),
        &ChartLayout::from(layout.clone()),
        "q",
        "material",
    )
    .unwrap();
    let (doc, _) = split(&bytes);
    assert_eq!(doc["asset"]["version"], "2.0");
    assert_eq!(
        doc["asset"]["generator"],
        format!("sdfc {}", env!("CARGO_PKG_VERSION"))
    );
    assert_eq!(
        doc["extras"]["sdfc_atlas"],
        serde_json::to_value(&layout).unwrap()
    );
    assert_eq!(
        doc["samplers"],
        json!([{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}])
    );
    let material = &doc["materials"][0];
    assert_eq!(material["name"], "material");
    assert_eq!(doc["meshes"][0]["name"], "q");
    assert_eq!(material["emissiveFactor"], json!([1.0, 1.0, 1.0]));
    assert!(material["normalTexture"].is_object());
    assert!(material["pbrMetallicRoughness"]["metallicRoughnessTexture"].is_object());
    for view in doc["bufferViews"].as_array().unwrap() {
        assert_eq!(view["byteOffset"].as_u64().unwrap() % 4, 0);
    }
    let position = &doc["accessors"][0];
    assert_eq!(position["min"], json!([-2.5, -0.5, -0.5]));
    assert_eq!(position["max"], json!([0.5, 0.5, 0.5]));
    for image in doc["images"].as_array().unwrap() {
        assert_eq!(image["mimeType"], "image/png");
    }

    let plain = glb(
        &mesh,
        &textures(&layout, false),
        &ChartLayout::from(layout.clone()),
        "q",
        "material",
    )
    .unwrap();
    let (doc, _) = split(&plain);
    assert!(doc["materials"][0].get("emissiveTexture").is_none());
    assert_eq!(
        doc["materials"][0]["emissiveFactor"],
        json!([0.0, 0.0, 0.0])
    );
    // Three textures' level 0, then the three images of their smaller levels.
    let images = doc["images"].as_array().unwrap();
    assert_eq!(images.len(), 6);
    assert_eq!(doc["extras"]["sdfc_levels"], json!([3, 4, 5]));
    for (i, name) in ["base_color", "metallic_roughness", "normal"]
        .iter()
        .enumerate()
    {
        assert_eq!(images[i]["name"], *name);
        assert_eq!(images[i + 3]["name"], format!("{name}_levels"));
    }
}

#[test]
fn glb_passes_the_khronos_validator() {
    let (mesh, layout) = quad_and_cube();
    let dir = tempfile::tempdir().unwrap();
    for emissive in [true, false] {
        let bytes = glb(
            &mesh,
            &textures(&layout, emissive),
            &ChartLayout::from(layout.clone()),
            "quad and cube",
            "material",
        )
        .unwrap();
        let path = dir.path().join(format!("export-{emissive}.glb"));
        std::fs::write(&path, &bytes).unwrap();
        let Some(report) = common::gltf_validate(&path) else {
            return;
        };
        eprintln!(
            "glTF-Validator on the export (emissive: {emissive}):\n{}",
            report.json
        );
        assert_eq!(
            (report.errors, report.warnings),
            (0, 0),
            "{:#?}",
            report.messages
        );
        // The notes allowed: the flat atlas is as tall as its charts need, which is
        // rarely a power of two (only WebGL 1 cares, and only for mipmaps or repeat
        // wrapping, which the atlas's sampler does not ask for); and the images of the
        // levels below level 0, which only sdfc reads (listed in extras.sdfc_levels),
        // are used by no texture.
        let (doc, _) = split(&bytes);
        let levels: Vec<String> = doc["extras"]["sdfc_levels"]
            .as_array()
            .expect("the levels' images are listed")
            .iter()
            .map(|i| format!("/images/{i}"))
            .collect();
        assert_eq!(levels.len(), if emissive { 4 } else { 3 });
        let other: Vec<_> = report
            .messages
            .iter()
            .filter(|m| m["code"] != "IMAGE_NPOT_DIMENSIONS")
            .filter(|m| {
                m["code"] != "UNUSED_OBJECT" || !levels.iter().any(|l| m["pointer"] == l.as_str())
            })
            .collect();
        assert!(other.is_empty(), "{other:#?}");
    }
}

#[test]
fn glb_refuses_bad_input() {
    let (mesh, layout) = quad_and_cube();
    let tex = textures(&layout, true);
    let refused = |mesh: &MeshData, tex: &Textures, layout: &FlatLayout| {
        assert!(
            glb(mesh, tex, &ChartLayout::from(layout.clone()), "x", "x").is_err(),
            "bad input accepted"
        );
    };
    let mut m = mesh.clone();
    m.normals.pop();
    refused(&m, &tex, &layout);
    let mut m = mesh.clone();
    m.indices[5] = m.positions.len() as u32;
    refused(&m, &tex, &layout);
    let mut m = mesh.clone();
    m.indices.pop();
    refused(&m, &tex, &layout);
    let mut m = mesh.clone();
    m.positions[3][1] = f32::NAN;
    refused(&m, &tex, &layout);
    refused(&MeshData::default(), &tex, &layout);
    let mut t = tex.clone();
    t.emissive = Some(RgbaImage::new(32, 64));
    refused(&mesh, &t, &layout);
    let mut l = layout.clone();
    l.chart_size = 12;
    refused(&mesh, &tex, &l);
    let mut l = layout.clone();
    l.level_origins.push([0, 60]); // 1-texel charts
    refused(&mesh, &tex, &l);
    let mut l = layout.clone();
    l.level_origins[1] = [40, 32]; // past the right edge
    refused(&mesh, &tex, &l);
}

/// A GLB of `doc` and `bin`, padded as the spec says.
fn join(doc: &Value, bin: &[u8]) -> Vec<u8> {
    join_text(serde_json::to_vec(doc).unwrap(), bin)
}

/// What `read_glb` returns must pass the checks (when it accepts a damaged file).
fn read_checked(bytes: &[u8]) -> Result<(), String> {
    let (mesh, textures, layout) = read_glb(bytes)?;
    check_mesh(&mesh).unwrap();
    check_atlas(&layout).unwrap();
    check_textures(&textures, &layout).unwrap();
    Ok(())
}

#[test]
fn read_glb_rejects_garbage_and_truncations() {
    let (mesh, layout) = quad_and_cube();
    let bytes = glb(
        &mesh,
        &textures(&layout, true),
        &ChartLayout::from(layout.clone()),
        "q",
        "material",
    )
    .unwrap();
    for garbage in [
        &b""[..],
        b"glTF",
        b"glTF\x02\0\0\0\xff\xff\xff\xff",
        b"glTF\x01\0\0\0\x0c\0\0\0",
        b"{\"asset\": {\"version\": \"2.0\"}}",
        &[0xff; 64],
    ] {
        assert!(read_glb(garbage).is_err());
    }
    for len in 0..bytes.len() {
        assert!(read_glb(&bytes[..len]).is_err(), "truncated to {len} bytes");
    }
    // The length in the header cut short, with the chunks intact after it.
    let mut short = bytes.clone();
    short[8..12].copy_from_slice(&((bytes.len() - 4) as u32).to_le_bytes());
    assert!(read_glb(&short).is_err());
}

#[test]
fn read_glb_survives_flipped_bytes() {
    let (mesh, layout) = quad_and_cube();
    let bytes = glb(
        &mesh,
        &textures(&layout, true),
        &ChartLayout::from(layout.clone()),
        "q",
        "material",
    )
    .unwrap();
    let json_end = 20 + u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    // Every byte of the header and the JSON, every 7th of the buffer (mostly PNG data,
    // whose checksums catch most changes).
    let positions = (0..json_end).chain((json_end..bytes.len()).step_by(7));
    let mut accepted = 0;
    for at in positions {
        // 0x08 turns digits into others ('1' into '9'), 0xff makes any byte non-ASCII.
        for flip in [0xff, 0x08, 0x01] {
            let mut broken = bytes.clone();
            broken[at] ^= flip;
            accepted += read_checked(&broken).is_ok() as usize;
        }
    }
    eprintln!("{accepted} of the flipped files still read (harmless changes)");
}

#[test]
fn read_glb_rejects_inconsistent_documents() {
    let (mesh, layout) = quad_and_cube();
    let bytes = glb(
        &mesh,
        &textures(&layout, false),
        &ChartLayout::from(layout.clone()),
        "q",
        "material",
    )
    .unwrap();
    let (doc, bin) = split(&bytes);
    read_checked(&join(&doc, &bin)).unwrap();
    let edits: &[(&str, Value)] = &[
        ("/accessors/0/count", json!(1_000_000_000_000u64)),
        ("/accessors/0/count", json!(0)),
        ("/accessors/3/count", json!(1)),
        ("/accessors/4/byteOffset", json!(u64::MAX - 2)),
        ("/accessors/4/componentType", json!(5126)),
        ("/accessors/1/type", json!("VEC4")),
        (
            "/accessors/2/sparse",
            json!({"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}),
        ),
        ("/bufferViews/0/byteOffset", json!(4_294_967_295u32)),
        ("/bufferViews/0/byteLength", json!(1_000_000_000_000_000u64)),
        ("/bufferViews/0/byteStride", json!(4)),
        ("/bufferViews/0/buffer", json!(1)),
        ("/meshes/0/primitives/0/indices", json!(99)),
        ("/meshes/0/primitives/0/attributes/POSITION", json!(4)),
        ("/meshes/0/primitives/0/attributes/NORMAL", json!(5)),
        ("/meshes/0/primitives/0/mode", json!(1)),
        ("/meshes/0/primitives/0/material", json!(7)),
        (
            "/materials/0/pbrMetallicRoughness/baseColorTexture/index",
            json!(99),
        ),
        ("/materials/0/normalTexture", json!(null)),
        ("/textures/0/source", json!(99)),
        ("/images/0/mimeType", json!("image/jpeg")),
        ("/images/1/bufferView", json!(0)),
        ("/buffers/0/byteLength", json!(bin.len() + 4)),
        ("/buffers/0/uri", json!("x.bin")),
        ("/extras", json!(null)),
        ("/extras/sdfc_atlas/chart_size", json!(3)),
        ("/extras/sdfc_atlas/width", json!(65)),
        ("/extras/sdfc_atlas/columns", json!(0)),
        ("/extras/sdfc_atlas/level_origins", json!([])),
        (
            "/extras/sdfc_atlas/level_origins",
            json!([[0, 0], [60, 60]]),
        ),
        ("/asset", json!(null)),
    ];
    for (pointer, value) in edits {
        let mut broken = doc.clone();
        let (parent, key) = pointer.rsplit_once('/').unwrap();
        match broken.pointer_mut(parent).unwrap() {
            Value::Object(map) if value.is_null() => drop(map.remove(key)),
            Value::Object(map) => drop(map.insert(key.into(), value.clone())),
            _ => panic!("{pointer}"),
        }
        let error = read_glb(&join(&broken, &bin)).err();
        assert!(error.is_some(), "{pointer} = {value} accepted");
    }
    // An index past the vertices, in the buffer.
    let at = doc["bufferViews"][4]["byteOffset"].as_u64().unwrap() as usize;
    let mut broken = bin.clone();
    broken[at..at + 4].copy_from_slice(&1000u32.to_le_bytes());
    assert!(read_glb(&join(&doc, &broken)).is_err());
}

/// The levels of a flat atlas's chart grid, stacked style: a 3 × 2 grid of 16-texel
/// charts halved down to 2-texel charts (48 × 32 to 6 × 4, not powers of two).
fn grid_levels() -> Vec<RgbaImage> {
    (0..4)
        .map(|l| {
            let n = 16 >> l;
            RgbaImage::from_fn(3 * n, 2 * n, |x, y| {
                Rgba([x as u8, y as u8, l as u8 * 60, 255 - x as u8])
            })
        })
        .collect()
}

#[test]
fn ktx2_parses_with_the_right_header_dfd_and_levels() {
    let levels = grid_levels();
    for srgb in [true, false] {
        let bytes = ktx2(&levels, srgb).unwrap();
        let reader = ::ktx2::Reader::new(&bytes[..]).expect("the ktx2 crate rejects the file");
        let header = reader.header();
        let format = if srgb {
            ::ktx2::Format::R8G8B8A8_SRGB
        } else {
            ::ktx2::Format::R8G8B8A8_UNORM
        };
        assert_eq!(header.format, Some(format));
        assert_eq!(header.type_size, 1);
        assert_eq!(
            (header.pixel_width, header.pixel_height, header.pixel_depth),
            (48, 32, 0)
        );
        assert_eq!(
            (header.layer_count, header.face_count, header.level_count),
            (0, 1, 4)
        );
        assert_eq!(header.supercompression_scheme, None);
        assert_eq!(
            (header.index.sgd_byte_offset, header.index.sgd_byte_length),
            (0, 0)
        );

        // The DFD is the one the ktx2 crate derives from the format, byte for byte.
        let (basic, type_size) = ::ktx2::dfd::Basic::from_format(format).unwrap();
        assert_eq!(type_size, 1);
        assert_eq!(reader.basic_dfd(), Some(&basic));
        assert_eq!(reader.dfd_blocks().len(), 1);
        let dfd = header.index.dfd_byte_offset as usize
            ..(header.index.dfd_byte_offset + header.index.dfd_byte_length) as usize;
        assert_eq!(&bytes[dfd.clone()][..4], &(dfd.len() as u32).to_le_bytes());
        assert_eq!(bytes[dfd][4..], ::ktx2::dfd::Block::Basic(basic).to_vec());
        let transfer = if srgb {
            ::ktx2::TransferFunction::SRGB
        } else {
            ::ktx2::TransferFunction::Linear
        };
        assert_eq!(reader.transfer_function(), Some(transfer));
        let writer = format!("sdfc {}", env!("CARGO_PKG_VERSION"));
        assert_eq!(
            reader.writer().map(|w| w.trim_end_matches('\0')),
            Some(&*writer)
        );

        // The levels: level 0 first in the index, their data smallest first in the file,
        // each on a 4-byte boundary, and the texels as given.
        let data: Vec<_> = reader.levels().collect();
        assert_eq!(data.len(), 4);
        let mut previous_offset = usize::MAX;
        for (level, image) in data.iter().zip(&levels) {
            assert_eq!(level.data, image.as_raw().as_slice());
            assert_eq!(level.uncompressed_byte_length, image.as_raw().len() as u64);
            let offset = level.data.as_ptr() as usize - bytes.as_ptr() as usize;
            assert_eq!(offset % 4, 0);
            assert!(offset < previous_offset, "levels not stored smallest first");
            previous_offset = offset;
        }
        let last = data[3].data.as_ptr() as usize - bytes.as_ptr() as usize;
        let kvd_end = (header.index.kvd_byte_offset + header.index.kvd_byte_length) as usize;
        assert_eq!(last, kvd_end.next_multiple_of(4));
        let first = data[0].data.as_ptr() as usize - bytes.as_ptr() as usize;
        assert_eq!(first + data[0].data.len(), bytes.len());
    }
}

#[test]
fn ktx2_refuses_levels_that_are_not_halvings() {
    let levels = grid_levels();
    assert!(ktx2(&[], true).is_err());
    assert!(ktx2(&[RgbaImage::new(0, 0)], true).is_err());
    assert!(ktx2(&[levels[0].clone(), levels[2].clone()], true).is_err());
    assert!(ktx2(&[levels[1].clone(), levels[0].clone()], true).is_err());
    // 1 × 1 is a level too; below it there is none.
    let tiny = [RgbaImage::new(2, 1), RgbaImage::new(1, 1)];
    assert!(ktx2(&tiny, false).is_ok());
    assert!(ktx2(&[tiny[0].clone(), tiny[1].clone(), tiny[1].clone()], false).is_err());
    assert!(ktx2(&levels[..1], true).is_ok());
}
