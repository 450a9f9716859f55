//! The atlas's levels as an uncompressed KTX2 texture.
//!
//! KTX 2.0 (Khronos, <https://registry.khronos.org/KTX/specs/2.0/ktxspec.v2.html>) is a
//! container for GPU textures. No maintained Rust crate writes it (`ktx2` only reads),
//! so [`ktx2`] writes it here, uncompressed, in this order (all little-endian):
//!
//! ```text
//!  identifier     «KTX 20»\r\n\x1A\n (12 bytes)
//!  header         vkFormat, typeSize = 1, width, height, depth = 0, layerCount = 0,
//!                 faceCount = 1, levelCount, supercompressionScheme = 0 (u32s)
//!  index          dfdByteOffset, dfdByteLength, kvdByteOffset, kvdByteLength (u32s),
//!                 sgdByteOffset = 0, sgdByteLength = 0 (u64s)
//!  level index    per level, level 0 first: byteOffset, byteLength,
//!                 uncompressedByteLength (u64s)
//!  DFD            dfdTotalSize (u32), then one Khronos Basic Data Format Descriptor
//!                 block for the format (KDF 1.3 §5): 24 bytes and a 16-byte sample
//!                 per channel
//!  key/value data one entry, KTXwriter = "sdfc <version>" (NUL-terminated), each
//!                 entry padded to 4 bytes
//!  levels         the texels, row by row from the top, smallest level first (as the
//!                 spec requires, for streaming), each starting on a 4-byte boundary
//!                 (mipPadding: lcm(texel block size 4, 4))
//! ```
//!
//! The format is VK_FORMAT_R8G8B8A8_SRGB (43) or VK_FORMAT_R8G8B8A8_UNORM (37); the
//! DFD says the same: RGBSDA colour model, BT.709 primaries, the sRGB or linear
//! transfer function, straight alpha, and for sRGB the alpha sample marked linear.
//! KTX2's default orientation for 2D textures, right-down, is the atlas's (its origin
//! at the top left), so no KTXorientation entry is needed.

use image::RgbaImage;

/// KTX2's file identifier.
pub const IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];
/// VkFormat of 8-bit RGBA with sRGB-encoded colour.
pub const VK_FORMAT_R8G8B8A8_SRGB: u32 = 43;
/// VkFormat of 8-bit linear RGBA.
pub const VK_FORMAT_R8G8B8A8_UNORM: u32 = 37;

const HEADER_LEN: usize = 80;
const LEVEL_INDEX_ENTRY_LEN: usize = 24;

/// An uncompressed KTX2 file of `levels`, level 0 first (the full-size image) and each
/// next one half the size of the one before (rounded down, at least 1), in sRGB
/// (`srgb`: colour sRGB-encoded, alpha linear) or linear RGBA8. See the module's
/// documentation for the layout.
pub fn ktx2(levels: &[RgbaImage], srgb: bool) -> Result<Vec<u8>, String> {
    let (width, height) = levels
        .first()
        .ok_or("a KTX2 needs at least one level")?
        .dimensions();
    if width == 0 || height == 0 {
        return Err("a KTX2 level 0 cannot be empty".into());
    }
    // A full chain has floor(log2(max side)) + 1 levels.
    let full_chain = 32 - width.max(height).leading_zeros() as usize;
    if levels.len() > full_chain {
        return Err(format!(
            "{} levels for a {width}×{height} texture, which has at most {full_chain}",
            levels.len()
        ));
    }
    for (l, level) in levels.iter().enumerate() {
        let expected = ((width >> l).max(1), (height >> l).max(1));
        if level.dimensions() != expected {
            let (w, h) = level.dimensions();
            return Err(format!(
                "KTX2 level {l} is {w}×{h}, not {}×{} (half of the level before)",
                expected.0, expected.1
            ));
        }
    }

    let dfd = data_format_descriptor(srgb);
    let kvd = key_value_data(&[(
        "KTXwriter",
        format!("sdfc {}\0", env!("CARGO_PKG_VERSION")).as_bytes(),
    )]);
    let dfd_offset = HEADER_LEN + LEVEL_INDEX_ENTRY_LEN * levels.len();
    let kvd_offset = dfd_offset + dfd.len();

    // The levels' places, smallest level first, each 4-byte aligned.
    let mut end = kvd_offset + kvd.len();
    let mut places = vec![(0, 0); levels.len()];
    for (l, level) in levels.iter().enumerate().rev() {
        let offset = end.next_multiple_of(4);
        places[l] = (offset, level.as_raw().len());
        end = offset + level.as_raw().len();
    }
    let u32_of =
        |n: usize| u32::try_from(n).map_err(|_| "the KTX2 header is too large".to_string());

    let mut out = Vec::with_capacity(end);
    out.extend_from_slice(&IDENTIFIER);
    let format = if srgb {
        VK_FORMAT_R8G8B8A8_SRGB
    } else {
        VK_FORMAT_R8G8B8A8_UNORM
    };
    let header = [
        format,
        1, // typeSize: the size of one component (u8)
        width,
        height,
        0, // pixelDepth: not a 3D texture
        0, // layerCount: not an array
        1, // faceCount: not a cube map
        levels.len() as u32,
        0, // supercompressionScheme: none
        u32_of(dfd_offset)?,
        u32_of(dfd.len())?,
        u32_of(kvd_offset)?,
        u32_of(kvd.len())?,
    ];
    for word in header {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteOffset: no global data
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteLength
    for &(offset, length) in &places {
        for word in [offset, length, length] {
            out.extend_from_slice(&(word as u64).to_le_bytes());
        }
    }
    out.extend_from_slice(&dfd);
    out.extend_from_slice(&kvd);
    for (l, level) in levels.iter().enumerate().rev() {
        out.resize(places[l].0, 0);
        out.extend_from_slice(level.as_raw());
    }
    debug_assert_eq!(out.len(), end);
    Ok(out)
}

/// The DFD of R8G8B8A8 (sRGB or UNORM): dfdTotalSize, then one basic block (Khronos
/// Data Format Specification 1.3, §5 "Khronos Basic Data Format Descriptor Block").
fn data_format_descriptor(srgb: bool) -> Vec<u8> {
    const SAMPLES: usize = 4;
    const BLOCK_LEN: usize = 24 + 16 * SAMPLES;
    const KHR_DF_MODEL_RGBSDA: u8 = 1;
    const KHR_DF_PRIMARIES_BT709: u8 = 1;
    const KHR_DF_TRANSFER_LINEAR: u8 = 1;
    const KHR_DF_TRANSFER_SRGB: u8 = 2;
    const KHR_DF_VERSIONNUMBER_1_3: u16 = 2;
    // Channel ids of the RGBSDA model, and the qualifier bit of a linear sample in an
    // otherwise non-linear format.
    const CHANNELS: [u8; SAMPLES] = [0, 1, 2, 15];
    const KHR_DF_SAMPLE_DATATYPE_LINEAR: u8 = 0x10;

    let mut dfd = Vec::with_capacity(4 + BLOCK_LEN);
    dfd.extend_from_slice(&(4 + BLOCK_LEN as u32).to_le_bytes()); // dfdTotalSize
    dfd.extend_from_slice(&0u32.to_le_bytes()); // vendorId KHR (0), descriptorType basic (0)
    dfd.extend_from_slice(&KHR_DF_VERSIONNUMBER_1_3.to_le_bytes());
    dfd.extend_from_slice(&(BLOCK_LEN as u16).to_le_bytes()); // descriptorBlockSize
    let transfer = if srgb {
        KHR_DF_TRANSFER_SRGB
    } else {
        KHR_DF_TRANSFER_LINEAR
    };
    // colorModel, colorPrimaries, transferFunction, flags (straight alpha).
    dfd.extend_from_slice(&[KHR_DF_MODEL_RGBSDA, KHR_DF_PRIMARIES_BT709, transfer, 0]);
    dfd.extend_from_slice(&[0; 4]); // texelBlockDimension0..3 (each minus one): 1×1×1×1
    dfd.extend_from_slice(&[4, 0, 0, 0, 0, 0, 0, 0]); // bytesPlane0..7: 4 bytes a texel
    for (i, channel) in CHANNELS.into_iter().enumerate() {
        let alpha = channel == 15;
        let qualifiers = if srgb && alpha {
            KHR_DF_SAMPLE_DATATYPE_LINEAR
        } else {
            0
        };
        dfd.extend_from_slice(&(8 * i as u16).to_le_bytes()); // bitOffset
        dfd.push(7); // bitLength minus one
        dfd.push(channel | qualifiers); // channelType
        dfd.extend_from_slice(&[0; 4]); // samplePosition0..3
        dfd.extend_from_slice(&0u32.to_le_bytes()); // sampleLower
        dfd.extend_from_slice(&255u32.to_le_bytes()); // sampleUpper
    }
    debug_assert_eq!(dfd.len(), 4 + BLOCK_LEN);
    dfd
}

/// Key/value data: each entry its byte length (u32), the key, a NUL, the value, and
/// padding to 4 bytes; entries sorted by key, as the spec requires.
fn key_value_data(entries: &[(&str, &[u8])]) -> Vec<u8> {
    let mut entries = entries.to_vec();
    entries.sort_by_key(|&(key, _)| key.as_bytes());
    let mut kvd = Vec::new();
    for (key, value) in entries {
        let len = key.len() + 1 + value.len();
        kvd.extend_from_slice(&(len as u32).to_le_bytes());
        kvd.extend_from_slice(key.as_bytes());
        kvd.push(0);
        kvd.extend_from_slice(value);
        kvd.resize(kvd.len().next_multiple_of(4), 0);
    }
    kvd
}
