//! Builders of hostile `.glb` and PNG files for the reader's tests (glb_limits,
//! glb_fuzz): a GLB's chunks split and joined, and tiny PNGs that claim any size.
#![allow(dead_code)]

use serde_json::Value;

/// Bits of a DEFLATE stream, least significant first.
#[derive(Default)]
pub struct Bits {
    out: Vec<u8>,
    acc: u64,
    n: u32,
}

impl Bits {
    fn put(&mut self, value: u64, bits: u32) {
        self.acc |= value << self.n;
        self.n += bits;
        while self.n >= 8 {
            self.out.push(self.acc as u8);
            self.acc >>= 8;
            self.n -= 8;
        }
    }

    /// A Huffman code, most significant bit first.
    fn code(&mut self, code: u32, bits: u32) {
        self.put((code.reverse_bits() >> (32 - bits)) as u64, bits);
    }
}

/// A zlib stream of `n` zero bytes: one fixed-Huffman block of a literal 0 and
/// matches of 258 bytes at distance 1 (13 bits each).
pub fn zlib_zeros(n: u64) -> Vec<u8> {
    let mut b = Bits::default();
    b.put(0x78, 8);
    b.put(0x01, 8);
    b.put(1, 1); // the final block
    b.put(1, 2); // fixed Huffman codes
    b.code(0x30, 8); // literal 0
    let rest = n - 1;
    for _ in 0..rest / 258 {
        b.code(0xC5, 8); // length 258 (code 285)
        b.code(0, 5); // distance 1
    }
    for _ in 0..rest % 258 {
        b.code(0x30, 8);
    }
    b.code(0, 7); // end of block
    if b.n > 0 {
        b.out.push(b.acc as u8);
    }
    // Adler-32 of n zeros: a = 1, b = n · 1.
    let adler = ((n % 65521) << 16) | 1;
    b.out.extend((adler as u32).to_be_bytes());
    b.out
}

pub fn crc32(bytes: &[u8]) -> u32 {
    let table: Vec<u32> = (0..256u32)
        .map(|mut c| {
            for _ in 0..8 {
                c = if c & 1 == 1 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
            c
        })
        .collect();
    !bytes.iter().fold(!0u32, |c, &b| {
        table[((c ^ b as u32) & 0xff) as usize] ^ (c >> 8)
    })
}

/// The JSON and BIN chunks of a GLB written by `glb`.
pub fn split(bytes: &[u8]) -> (Value, Vec<u8>) {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    (doc, bytes[20 + len + 8..].to_vec())
}

/// A GLB of the JSON text `json` (padded with spaces) and `bin`.
pub fn join_text(mut json: Vec<u8>, bin: &[u8]) -> Vec<u8> {
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((20 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}
