//! A minimal PNG encoder: 8-bit RGB, no compression, no dependencies.
//!
//! Layout (PNG Specification, W3C Recommendation, 2nd edition 2003 = ISO/IEC 15948:2004): the
//! 8-byte signature, then chunks `length (u32 BE) · type · data · CRC-32 (u32 BE, over type and
//! data)`: IHDR (§11.2.2; colour type 2 = RGB, bit depth 8, no interlace), one IDAT, IEND. The
//! image data are the rows, each prefixed by its filter type 0 (None, §9.2), in a zlib stream
//! (RFC 1950: header 0x78 0x01, Adler-32 of the uncompressed data at the end) whose deflate data
//! (RFC 1951 §3.2.4) are *stored* blocks of at most 65 535 bytes. Previews are a few MB
//! uncompressed; writing them is not where the time goes, and stored blocks keep the encoder
//! obviously correct.

/// The PNG file signature (§5.2).
pub const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// Largest payload of a stored deflate block (LEN is 16 bits, RFC 1951 §3.2.4).
const MAX_STORED: usize = 65_535;

/// Encodes a `width` × `height` image of 8-bit RGB triples (row-major, row 0 at the top).
///
/// # Panics
/// If `rgb.len() != 3 · width · height`, or a dimension is 0 or above 2³¹ − 1 (§11.2.2).
pub fn encode(width: usize, height: usize, rgb: &[u8]) -> Vec<u8> {
    assert_eq!(rgb.len(), 3 * width * height, "png::encode: {width}x{height} needs {} bytes", 3 * width * height);
    assert!((1..=i32::MAX as usize).contains(&width) && (1..=i32::MAX as usize).contains(&height));
    let mut ihdr = Vec::with_capacity(13);
    ihdr.extend_from_slice(&(width as u32).to_be_bytes());
    ihdr.extend_from_slice(&(height as u32).to_be_bytes());
    // Bit depth 8, colour type 2 (RGB), compression 0, filter method 0, no interlace.
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut rows = Vec::with_capacity((3 * width + 1) * height);
    for row in rgb.chunks_exact(3 * width) {
        rows.push(0); // filter type None
        rows.extend_from_slice(row);
    }
    let idat = zlib_stored(&rows);
    let mut png = Vec::with_capacity(SIGNATURE.len() + 3 * 12 + ihdr.len() + idat.len());
    png.extend_from_slice(&SIGNATURE);
    chunk(&mut png, b"IHDR", &ihdr);
    chunk(&mut png, b"IDAT", &idat);
    chunk(&mut png, b"IEND", &[]);
    png
}

/// Appends one chunk: length, type, data, CRC-32 of type and data (§5.3).
fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let crc = crc32(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// A zlib stream (RFC 1950) of `data` in stored deflate blocks (RFC 1951 §3.2.4).
fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let blocks = data.len().div_ceil(MAX_STORED).max(1);
    let mut out = Vec::with_capacity(data.len() + 5 * blocks + 6);
    // CMF 0x78: deflate with a 32 KiB window; FLG 0x01: no dictionary, level 0, and
    // (CMF · 256 + FLG) divisible by 31.
    out.extend_from_slice(&[0x78, 0x01]);
    let mut pieces = data.chunks(MAX_STORED).peekable();
    if pieces.peek().is_none() {
        out.extend_from_slice(&[1, 0, 0, 0xff, 0xff]); // one empty final block
    }
    while let Some(piece) = pieces.next() {
        // Block header: BFINAL in bit 0, BTYPE = 00 (stored) in bits 1–2, then padding to the
        // byte boundary; LEN and its one's complement NLEN, little-endian.
        out.push(u8::from(pieces.peek().is_none()));
        let len = piece.len() as u16;
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(piece);
    }
    out.extend_from_slice(&adler32(data).to_be_bytes());
    out
}

/// CRC-32 table for the reflected polynomial 0xEDB88320 (PNG §5.5, Annex D).
const CRC_TABLE: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut n = 0;
    while n < 256 {
        let mut c = n as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            k += 1;
        }
        table[n] = c;
        n += 1;
    }
    table
};

/// CRC-32 (ISO 3309 / ITU-T V.42, as in PNG and zlib).
pub fn crc32(bytes: &[u8]) -> u32 {
    !bytes.iter().fold(!0u32, |c, &b| CRC_TABLE[((c ^ b as u32) & 0xff) as usize] ^ (c >> 8))
}

/// Adler-32 (RFC 1950 §8.2): s1 = 1 + Σ bytes, s2 = Σ s1, both mod 65521.
pub fn adler32(bytes: &[u8]) -> u32 {
    const MOD: u32 = 65_521;
    // 5552 is the longest run of bytes over which s2 cannot overflow a u32 (zlib's NMAX).
    let (mut s1, mut s2) = (1u32, 0u32);
    for run in bytes.chunks(5552) {
        for &b in run {
            s1 += b as u32;
            s2 += s1;
        }
        s1 %= MOD;
        s2 %= MOD;
    }
    (s2 << 16) | s1
}

/// The tests' own PNG reader, shared with `tests/render.rs`.
#[cfg(test)]
#[path = "../../tests/support/png_decode.rs"]
mod png_decode;

#[cfg(test)]
mod tests {
    use super::png_decode::{decode, inflate_stored, Decoded};
    use super::*;

    #[test]
    fn crc32_and_adler32_of_known_strings() {
        // The check values of the CRC-32 catalogue and of the Adler-32 article.
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
        assert_eq!(adler32(b"Wikipedia"), 0x11E6_0398);
        assert_eq!(adler32(b""), 1);
        // A run long enough to need the modular reductions: a million 0xff bytes, against the
        // definition evaluated in u64.
        let long = vec![0xffu8; 1_000_000];
        let (s1, s2) =
            long.iter().fold((1u64, 0u64), |(a, b), &x| ((a + x as u64) % 65521, (b + a + x as u64) % 65521));
        assert_eq!(adler32(&long), ((s2 << 16) | s1) as u32);
    }

    #[test]
    fn two_by_two_image_is_a_valid_png() {
        #[rustfmt::skip]
        let rgb = [
            255, 0, 0,    0, 255, 0,
            0, 0, 255,    10, 20, 30,
        ];
        let png = encode(2, 2, &rgb);
        assert_eq!(png[..8], SIGNATURE);
        // IHDR comes first: length 13, then the size.
        assert_eq!(png[8..16], [0, 0, 0, 13, b'I', b'H', b'D', b'R']);
        assert_eq!(png[16..24], [0, 0, 0, 2, 0, 0, 0, 2]);
        // The decoder checks every chunk's CRC, the zlib header, the stored blocks and the
        // Adler-32, and returns the filtered rows.
        let Decoded { width, height, bit_depth, colour_type, chunks, filtered } = decode(&png).unwrap();
        assert_eq!((width, height, bit_depth, colour_type), (2, 2, 8, 2));
        assert_eq!(chunks, ["IHDR", "IDAT", "IEND"]);
        assert_eq!(filtered, [0, 255, 0, 0, 0, 255, 0, 0, 0, 0, 255, 10, 20, 30]);
    }

    #[test]
    fn large_images_take_several_stored_blocks() {
        // 200 × 200 RGB with a filter byte per row: 120 200 bytes, two full blocks' worth.
        let (w, h) = (200, 200);
        let rgb: Vec<u8> = (0..3 * w * h).map(|i| (i * 7 % 251) as u8).collect();
        let png = encode(w, h, &rgb);
        let d = decode(&png).unwrap();
        let expected: Vec<u8> = rgb.chunks(3 * w).flat_map(|r| std::iter::once(0).chain(r.iter().copied())).collect();
        assert_eq!(d.filtered, expected);
        let idat = &png[8 + 25 + 8..png.len() - 12 - 4];
        let (data, blocks) = inflate_stored(idat).unwrap();
        assert_eq!(data, expected);
        assert_eq!(blocks, [65_535, 120_200 - 65_535]);
    }

    #[test]
    fn an_empty_stream_is_one_empty_final_block() {
        let z = zlib_stored(&[]);
        assert_eq!(z, [0x78, 0x01, 1, 0, 0, 0xff, 0xff, 0, 0, 0, 1]);
        assert_eq!(inflate_stored(&z).unwrap(), (vec![], vec![0]));
    }
}
