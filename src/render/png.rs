//! Preview images as PNG (8-bit RGB), through the `png` crate.
//!
//! The settings are fixed so that the same pixels always give the same bytes: zlib level 6
//! (`flate2`/`miniz_oxide`, the versions `Cargo.lock` pins; `png` itself is pinned exactly in
//! `Cargo.toml`) and the adaptive filter (per row, the filter with the smallest sum of absolute
//! differences, a deterministic choice). A 960×540 preview of `sheet_on_sphere` is 17–40 KB,
//! against 1.5 MB stored uncompressed.

use png::{BitDepth, ColorType, DeflateCompression, Encoder, Filter};

/// zlib compression level: the zlib default, a good size for little time on these images
/// (large flat areas of white and of a few shaded colours).
const LEVEL: u8 = 6;

/// Encodes a `width` × `height` image of 8-bit RGB triples (row-major, row 0 at the top).
///
/// # Panics
/// If `rgb.len() != 3 · width · height`, or a dimension is 0 or above 2³¹ − 1 (PNG §11.2.2): the
/// only ways encoding into memory can fail.
pub fn encode(width: usize, height: usize, rgb: &[u8]) -> Vec<u8> {
    assert_eq!(rgb.len(), 3 * width * height, "png::encode: {width}x{height} needs {} bytes", 3 * width * height);
    assert!((1..=i32::MAX as usize).contains(&width) && (1..=i32::MAX as usize).contains(&height));
    let mut out = Vec::new();
    let mut encoder = Encoder::new(&mut out, width as u32, height as u32);
    encoder.set_color(ColorType::Rgb);
    encoder.set_depth(BitDepth::Eight);
    encoder.set_deflate_compression(DeflateCompression::Level(LEVEL));
    encoder.set_filter(Filter::Adaptive);
    let mut writer = encoder.write_header().expect("PNG header of a valid size into memory");
    writer.write_image_data(rgb).expect("PNG data of the right length into memory");
    writer.finish().expect("PNG end into memory");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decodes `png` with the crate's decoder: (width, height, colour type, bit depth, pixels).
    fn decode(png: &[u8]) -> (u32, u32, ColorType, BitDepth, Vec<u8>) {
        let mut reader = png::Decoder::new(std::io::Cursor::new(png)).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width, info.height, info.color_type, info.bit_depth, buf)
    }

    #[test]
    fn two_by_two_image_round_trips() {
        #[rustfmt::skip]
        let rgb = [
            255, 0, 0,    0, 255, 0,
            0, 0, 255,    10, 20, 30,
        ];
        let png = encode(2, 2, &rgb);
        assert_eq!(png[..8], [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n']);
        // IHDR comes first: length 13, then the size.
        assert_eq!(png[8..16], [0, 0, 0, 13, b'I', b'H', b'D', b'R']);
        assert_eq!(png[16..24], [0, 0, 0, 2, 0, 0, 0, 2]);
        assert_eq!(decode(&png), (2, 2, ColorType::Rgb, BitDepth::Eight, rgb.to_vec()));
    }

    #[test]
    fn a_flat_image_compresses_and_round_trips() {
        // 960 × 540, white with a shaded band: what a preview mostly is.
        let (w, h) = (960, 540);
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|p| if (200..300).contains(&(p / w)) { [173, 216, (p % w / 4) as u8] } else { [255; 3] })
            .collect();
        let png = encode(w, h, &rgb);
        assert!(png.len() < rgb.len() / 50, "{} bytes", png.len());
        assert_eq!(decode(&png).4, rgb);
        // The same pixels, the same bytes.
        assert_eq!(encode(w, h, &rgb), png);
    }

    /// The bytes for fixed pixels, pinned: a `png`, `flate2` or `miniz_oxide` upgrade that
    /// changes what a run renders to fails here (then re-pin deliberately, knowing that
    /// previews rendered before and after differ in bytes though not in pixels).
    #[test]
    fn the_encoding_is_pinned() {
        let (w, h) = (64, 48);
        let rgb: Vec<u8> = (0..3 * w * h)
            .map(|i| {
                let (x, y, c) = (i / 3 % w, i / 3 / w, i % 3);
                ((x * 7 + y * y * 3 + c * 50) ^ (x * y)) as u8
            })
            .collect();
        let png = encode(w, h, &rgb);
        // FNV-1a 64 of the file.
        let hash = png.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
        assert_eq!((png.len(), hash), (7939, 0x204a_6248_72dc_3a39), "encoding changed");
    }
}
