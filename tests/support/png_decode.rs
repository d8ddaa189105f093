//! A PNG reader for the tests, written apart from the encoder (`src/render/png.rs`) so that the
//! two check each other: chunk CRCs by the bitwise CRC-32 definition, the zlib header, deflate
//! *stored* blocks only (RFC 1951 §3.2.4; anything else is an error), the Adler-32 by its plain
//! definition, and RGB rows with filter type 0. Included by the encoder's unit tests and by
//! `tests/render.rs`.

#![allow(dead_code)]

/// What the reader found.
#[derive(Debug)]
pub struct Decoded {
    pub width: usize,
    pub height: usize,
    pub bit_depth: u8,
    pub colour_type: u8,
    /// Chunk types in file order.
    pub chunks: Vec<String>,
    /// The inflated image data: rows, each with its filter byte.
    pub filtered: Vec<u8>,
}

/// Reads a PNG of stored deflate blocks, checking every CRC and the Adler-32.
pub fn decode(png: &[u8]) -> Result<Decoded, String> {
    const SIGNATURE: [u8; 8] = [137, 80, 78, 71, 13, 10, 26, 10];
    if png.len() < 8 || png[..8] != SIGNATURE {
        return Err("no PNG signature".into());
    }
    let (mut at, mut chunks, mut idat, mut ihdr) = (8, Vec::new(), Vec::new(), None);
    while at < png.len() {
        let len = be32(png, at)? as usize;
        let body = png.get(at + 4..at + 8 + len).ok_or("chunk runs past the end")?;
        let crc = be32(png, at + 8 + len)?;
        if crc != crc32_bitwise(body) {
            return Err(format!("bad CRC on chunk at byte {at}"));
        }
        let kind = String::from_utf8_lossy(&body[..4]).into_owned();
        let data = &body[4..];
        match kind.as_str() {
            "IHDR" => ihdr = Some(data.to_vec()),
            "IDAT" => idat.extend_from_slice(data),
            _ => {}
        }
        chunks.push(kind);
        at += 12 + len;
    }
    if chunks.first().map(String::as_str) != Some("IHDR") || chunks.last().map(String::as_str) != Some("IEND") {
        return Err(format!("chunks {chunks:?}: IHDR must come first and IEND last"));
    }
    let ihdr = ihdr.filter(|h| h.len() == 13).ok_or("IHDR is not 13 bytes")?;
    let (filtered, _) = inflate_stored(&idat)?;
    Ok(Decoded {
        width: be32(&ihdr, 0)? as usize,
        height: be32(&ihdr, 4)? as usize,
        bit_depth: ihdr[8],
        colour_type: ihdr[9],
        chunks,
        filtered,
    })
}

/// The RGB bytes of a decoded 8-bit RGB image whose rows all use filter type 0.
pub fn rgb(d: &Decoded) -> Result<Vec<u8>, String> {
    if (d.bit_depth, d.colour_type) != (8, 2) {
        return Err(format!("bit depth {} colour type {}: expected 8-bit RGB", d.bit_depth, d.colour_type));
    }
    let stride = 3 * d.width + 1;
    if d.filtered.len() != stride * d.height {
        return Err(format!("{} bytes of image data for {}x{}", d.filtered.len(), d.width, d.height));
    }
    let mut out = Vec::with_capacity(3 * d.width * d.height);
    for row in d.filtered.chunks(stride) {
        if row[0] != 0 {
            return Err(format!("filter type {}: only 0 is expected", row[0]));
        }
        out.extend_from_slice(&row[1..]);
    }
    Ok(out)
}

/// Inflates a zlib stream made of stored blocks only: the data and each block's length.
pub fn inflate_stored(z: &[u8]) -> Result<(Vec<u8>, Vec<usize>), String> {
    let (cmf, flg) = (*z.first().ok_or("empty zlib stream")?, *z.get(1).ok_or("short zlib header")?);
    if cmf & 0x0f != 8 || !(cmf as u32 * 256 + flg as u32).is_multiple_of(31) || flg & 0x20 != 0 {
        return Err(format!("bad zlib header {cmf:#04x} {flg:#04x}"));
    }
    let (mut at, mut data, mut blocks) = (2, Vec::new(), Vec::new());
    loop {
        // A stored block after a stored block starts on a byte boundary: its 3 header bits are
        // the low bits of one byte, the rest of which is padding.
        let header = *z.get(at).ok_or("stream ends before the final block")?;
        if (header >> 1) & 3 != 0 {
            return Err(format!("block type {} at byte {at}: only stored blocks are expected", (header >> 1) & 3));
        }
        let len = le16(z, at + 1)?;
        if le16(z, at + 3)? != !len {
            return Err(format!("NLEN is not the complement of LEN at byte {at}"));
        }
        let payload = z.get(at + 5..at + 5 + len as usize).ok_or("stored block runs past the end")?;
        data.extend_from_slice(payload);
        blocks.push(len as usize);
        at += 5 + len as usize;
        if header & 1 == 1 {
            break;
        }
    }
    if be32(z, at)? != adler32_plain(&data) || at + 4 != z.len() {
        return Err("bad Adler-32 or trailing bytes".into());
    }
    Ok((data, blocks))
}

fn be32(b: &[u8], at: usize) -> Result<u32, String> {
    let s = b.get(at..at + 4).ok_or_else(|| format!("no 4 bytes at {at}"))?;
    Ok(u32::from_be_bytes([s[0], s[1], s[2], s[3]]))
}

fn le16(b: &[u8], at: usize) -> Result<u16, String> {
    let s = b.get(at..at + 2).ok_or_else(|| format!("no 2 bytes at {at}"))?;
    Ok(u16::from_le_bytes([s[0], s[1]]))
}

/// CRC-32 bit by bit: reflected polynomial 0xEDB88320, initial and final XOR with all ones.
pub fn crc32_bitwise(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 == 1 { (c >> 1) ^ 0xEDB8_8320 } else { c >> 1 };
        }
    }
    !c
}

/// Adler-32 by its definition, reducing after every byte.
pub fn adler32_plain(bytes: &[u8]) -> u32 {
    let (mut a, mut b) = (1u32, 0u32);
    for &x in bytes {
        a = (a + x as u32) % 65521;
        b = (b + a) % 65521;
    }
    (b << 16) | a
}
