//! Visible error: how different two rasterised views of the cloth look (DESIGN.md "Error against
//! run time"): shading (normal angle), outline (silhouette) and depth.

use super::raster::Image;
use crate::math::Real;

/// The visible difference between a reference and a candidate image.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct VisibleError {
    /// Mean angle (degrees) between the two images' normals over pixels both cover (0 when none).
    pub normal_deg: Real,
    /// Silhouette mismatch: pixels covered by exactly one image / pixels covered by either (0 when
    /// neither covers any).
    pub silhouette: Real,
    /// Mean |depth difference| over pixels both cover, divided by the depth range (max − min) of
    /// all covered pixels of both images (the scene depth); 0 if that range is 0 or no pixel is
    /// covered by both.
    pub depth: Real,
    /// Pixels covered by either image.
    pub pixels: usize,
}

/// Compares `candidate` with `reference`, pixel by pixel. Sums run serially in pixel order, so the
/// result does not depend on the thread count.
///
/// # Panics
/// If the images differ in size: both are rendered by the caller at one resolution, so a mismatch
/// is a bug, not an input error.
pub fn visible_error(reference: &Image, candidate: &Image) -> VisibleError {
    assert_eq!(
        (reference.width, reference.height),
        (candidate.width, candidate.height),
        "visible_error: images differ in size"
    );
    let (mut either, mut one, mut both) = (0usize, 0usize, 0usize);
    let (mut angle_sum, mut depth_sum) = (0.0, 0.0);
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for p in 0..reference.face.len() {
        let (r, c) = (reference.covered(p), candidate.covered(p));
        if !(r || c) {
            continue;
        }
        either += 1;
        for (covered, d) in [(r, reference.depth[p]), (c, candidate.depth[p])] {
            if covered {
                lo = lo.min(d);
                hi = hi.max(d);
            }
        }
        if r && c {
            both += 1;
            let (a, b) = (&reference.normal[p], &candidate.normal[p]);
            // atan2(|a × b|, a · b): accurate for small angles, where acos is not.
            angle_sum += a.cross(b).norm().atan2(a.dot(b)).to_degrees();
            depth_sum += (reference.depth[p] - candidate.depth[p]).abs();
        } else {
            one += 1;
        }
    }
    let mean = |sum: Real| if both > 0 { sum / both as Real } else { 0.0 };
    let range = hi - lo;
    VisibleError {
        normal_deg: mean(angle_sum),
        silhouette: if either > 0 { one as Real / either as Real } else { 0.0 },
        depth: if range > 0.0 { mean(depth_sum) / range } else { 0.0 },
        pixels: either,
    }
}

#[cfg(test)]
mod tests {
    use super::super::raster::rasterize;
    use super::super::raster::tests::{view, wavy_grid};
    use super::*;
    use crate::math::Vec3;

    fn v(x: Real, y: Real, z: Real) -> Vec3 {
        Vec3::new(x, y, z)
    }

    #[test]
    fn identical_images_have_no_error() {
        let (x, tris) = wavy_grid(20);
        let image = rasterize(&x, &tris, &view(2.0), 200, 100);
        let e = visible_error(&image, &image);
        assert_eq!((e.normal_deg, e.silhouette, e.depth), (0.0, 0.0, 0.0));
        assert!(e.pixels > 1000);
        let empty = rasterize(&x, &[], &view(2.0), 200, 100);
        assert_eq!(visible_error(&empty, &empty), VisibleError::default());
    }

    #[test]
    fn shifted_triangle_silhouette_is_xor_over_union() {
        // At depth 2 with a 90° fov and 100 rows: 0.04 m per pixel. A right triangle with legs of
        // L = 40 px, and the same shifted by s = 10 px along its horizontal leg.
        let (w, h, px) = (200, 100, 0.04);
        let (l, s) = (40.0, 10.0);
        let tri = |dx: Real| {
            let o = v(-0.8 + dx * px, 2.0, -0.8);
            vec![o, o + v(l * px, 0.0, 0.0), o + v(0.0, 0.0, l * px)]
        };
        let reference = rasterize(&tri(0.0), &[[0, 1, 2]], &view(2.0), w, h);
        let candidate = rasterize(&tri(s), &[[0, 1, 2]], &view(2.0), w, h);
        let e = visible_error(&reference, &candidate);
        // Each area is L²/2; the overlap is the triangle with legs L − s.
        let overlap = (l - s) * (l - s) / 2.0;
        let union = l * l - overlap;
        let xor = l * l - 2.0 * overlap;
        // One row of pixels.
        let tol = l;
        assert!((e.pixels as Real - union).abs() < tol, "{e:?}");
        assert!((e.silhouette - xor / union).abs() < tol / union, "{e:?} vs {}", xor / union);
        assert!(e.silhouette > 0.3, "{e:?}");
        // Both flat at the same depth.
        assert!(e.normal_deg < 1e-9 && e.depth == 0.0, "{e:?}");
    }

    #[test]
    fn tilted_triangle_has_its_tilt_as_normal_error() {
        let (w, h) = (200, 100);
        let square = |tilt_deg: Real| {
            let (s, c) = tilt_deg.to_radians().sin_cos();
            // Rotated about the vertical axis through (0, 2, 0).
            let p = |x: Real, z: Real| v(x * c, 2.0 + x * s, z);
            vec![p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)]
        };
        let tris = [[0, 1, 2], [0, 2, 3]];
        let reference = rasterize(&square(0.0), &tris, &view(2.0), w, h);
        let candidate = rasterize(&square(10.0), &tris, &view(2.0), w, h);
        let e = visible_error(&reference, &candidate);
        assert!((e.normal_deg - 10.0).abs() < 1e-9, "{e:?}");
        assert!(e.depth > 0.0 && e.silhouette > 0.0, "{e:?}");
    }

    #[test]
    fn depth_error_is_relative_to_scene_depth() {
        // Hand-made 3 × 1 images: pixel 0 both (depths 2 and 2.5), pixel 1 reference only (4),
        // pixel 2 neither.
        let image = |depth: [Real; 3]| Image {
            width: 3,
            height: 1,
            depth: depth.to_vec(),
            normal: depth.map(|d| if d.is_finite() { Vec3::y() } else { Vec3::zeros() }).to_vec(),
            face: depth.map(|d| if d.is_finite() { 0 } else { u32::MAX }).to_vec(),
        };
        let reference = image([2.0, 4.0, Real::INFINITY]);
        let candidate = image([2.5, Real::INFINITY, Real::INFINITY]);
        let e = visible_error(&reference, &candidate);
        // |2 − 2.5| / (4 − 2).
        assert_eq!(e, VisibleError { normal_deg: 0.0, silhouette: 0.5, depth: 0.25, pixels: 2 });
        let json = serde_json::to_value(e).unwrap();
        assert_eq!(json["pixels"], 2);
    }

    #[test]
    #[should_panic(expected = "differ in size")]
    fn different_sizes_panic() {
        let (x, tris) = wavy_grid(2);
        visible_error(&rasterize(&x, &tris, &view(2.0), 20, 10), &rasterize(&x, &tris, &view(2.0), 10, 20));
    }
}
