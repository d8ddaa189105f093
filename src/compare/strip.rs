//! Image strips (PNG) for a few frames: reference | run | per-pixel error heat map, seen from
//! the shot camera, cloth and obstacles rendered as `viewcloth render --color shade` does.
//!
//! Heat map: where both show cloth, the angle between the shading normals on a white → red
//! ramp saturating at `HEAT_FULL_DEG`; where exactly one shows cloth (silhouette mismatch),
//! black; elsewhere light grey over an obstacle and white over the background.

use crate::math::Real;
use crate::metrics::FrameImage;

/// Frames drawn per run: the first, middle and last compared.
pub const STRIP_FRAMES: usize = 3;
/// Angle (degrees) at which the heat map is fully red.
pub const HEAT_FULL_DEG: Real = 30.0;

/// The frames to draw among `compared`: first, middle and last (fewer when fewer compared).
pub fn strip_frames(compared: &[usize]) -> Vec<usize> {
    let n = compared.len();
    let mut picks: Vec<usize> = (0..STRIP_FRAMES.min(n))
        .map(|k| compared[if STRIP_FRAMES.min(n) > 1 { k * (n - 1) / (STRIP_FRAMES.min(n) - 1) } else { 0 }])
        .collect();
    picks.dedup();
    picks
}

/// The heat map (8-bit RGB, row-major) of `candidate` against `reference` (module doc).
///
/// # Panics
/// If the images differ in size.
pub fn heat_map(reference: &FrameImage, candidate: &FrameImage) -> Vec<u8> {
    let (ri, ci) = (&reference.image, &candidate.image);
    assert_eq!((ri.width, ri.height), (ci.width, ci.height), "heat_map: images differ in size");
    let mut rgb = Vec::with_capacity(3 * ri.face.len());
    for p in 0..ri.face.len() {
        let pixel = match (reference.cloth(p), candidate.cloth(p)) {
            (true, true) => {
                let (a, b) = (&reference.shading[p], &candidate.shading[p]);
                let deg = a.cross(b).norm().atan2(a.dot(b)).to_degrees();
                let s = (deg / HEAT_FULL_DEG).clamp(0.0, 1.0);
                let gb = (255.0 * (1.0 - s)).round() as u8;
                [255, gb, gb]
            }
            (true, false) | (false, true) => [0, 0, 0],
            (false, false) if ri.covered(p) || ci.covered(p) => [210, 210, 210],
            (false, false) => [255, 255, 255],
        };
        rgb.extend_from_slice(&pixel);
    }
    rgb
}

/// Three `width` × `height` RGB images side by side.
pub fn side_by_side(images: [&[u8]; 3], width: usize, height: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(9 * width * height);
    for row in 0..height {
        for image in images {
            out.extend_from_slice(&image[3 * width * row..3 * width * (row + 1)]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::metrics::Image;

    /// A 4 × 1 image: per pixel, the face (0 cloth, 1 obstacle, None empty) and shading normal.
    fn image(pixels: [(Option<u32>, Vec3); 4]) -> FrameImage {
        let face = pixels.map(|p| p.0.unwrap_or(u32::MAX)).to_vec();
        let normal = pixels.map(|p| p.1).to_vec();
        let depth = pixels.map(|p| if p.0.is_some() { 1.0 } else { Real::INFINITY }).to_vec();
        let image = Image { width: 4, height: 1, depth, normal: normal.clone(), face };
        FrameImage { image, shading: normal, cloth_triangles: 1, visible_fraction: vec![1.0] }
    }

    #[test]
    fn heat_is_the_angle_then_black_for_silhouette_grey_for_obstacles() {
        let (y, tilted) = (Vec3::y(), Vec3::new(0.0, 1.0, 15.0_f64.to_radians().tan()).normalize());
        let r = image([(Some(0), y), (Some(0), y), (Some(1), y), (None, Vec3::zeros())]);
        let c = image([(Some(0), tilted), (None, Vec3::zeros()), (Some(1), y), (None, Vec3::zeros())]);
        let heat = heat_map(&r, &c);
        // 15° is half way to full red.
        assert_eq!(heat, [255, 128, 128, 0, 0, 0, 210, 210, 210, 255, 255, 255]);
        assert_eq!(heat_map(&r, &r)[..3], [255, 255, 255]);
    }

    #[test]
    fn strips_pick_first_middle_last() {
        assert_eq!(strip_frames(&[1, 2, 3, 4, 5]), [1, 3, 5]);
        assert_eq!(strip_frames(&[2, 4]), [2, 4]);
        assert_eq!(strip_frames(&[7]), [7]);
        assert!(strip_frames(&[]).is_empty());
        let (a, b, c) = ([1u8; 6], [2u8; 6], [3u8; 6]);
        assert_eq!(side_by_side([&a, &b, &c], 1, 2), [1, 1, 1, 2, 2, 2, 3, 3, 3, 1, 1, 1, 2, 2, 2, 3, 3, 3]);
    }
}
