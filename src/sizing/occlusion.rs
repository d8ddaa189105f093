//! Occlusion for the view factors (issue 19 item 2; Koh et al. 2014 leave it out, §3: "we do
//! not consider occlusion"): cloth hidden from the camera behind obstacles or other cloth is
//! coarsened like cloth outside the frame, blended by the share of it that is seen.
//!
//! At a camera time the obstacles (as they are then) and the cloth (as it is now: its motion
//! over the window is not predicted, as for the other view factors) are rasterised into a
//! low-resolution depth image (`metrics::rasterize`). A point of a face is hidden when it lies
//! behind the depth image by more than a tolerance. Two choices make the test err towards
//! "seen":
//! - the depth image is replaced by its maximum over each pixel's 3 × 3 neighbourhood, so an
//!   occluder hides only where it covers a pixel and all its neighbours (thin occluders and
//!   silhouette edges do not hide; a face never hides itself, since its own surface reaches
//!   farther than it within a pixel on one side);
//! - the tolerance is `SEEN_WITHIN` plus one pixel's footprint at the point's depth, so cloth
//!   layers in contact, and cloth lying on a body, count as seen.
//!
//! A face's visible fraction v is the share of its `SAMPLES` points that are not hidden; points
//! outside the image count as seen (the frustum factor, eqs. 3–4, handles them). The occluded
//! view factor is v · μ₂ + (1 − v) · μ_out, and the lookahead window's weighted maximum
//! (eq. 6) then applies to it, so a face is coarsened only when it is hidden over the whole
//! window.

use crate::camera::View;
use crate::math::{Real, Vec3};

/// Depth (m) behind the nearest surface within which a point counts as seen.
pub const SEEN_WITHIN: Real = 0.01;

/// Barycentric coordinates of the points sampled on each face: the centroid and the three
/// points halfway between it and each corner's side (4/6, 1/6, 1/6).
const SAMPLES: [[Real; 3]; 4] = [
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
    [4.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 1.0 / 6.0, 4.0 / 6.0],
];

/// A low-resolution depth image of everything that can hide cloth, seen by one view, with each
/// pixel holding the farthest depth of its 3 × 3 neighbourhood.
#[derive(Clone, Debug)]
pub struct DepthMap {
    view: View,
    width: usize,
    height: usize,
    /// Row-major, row 0 at the top; `Real::INFINITY` where a pixel or one of its neighbours is
    /// empty.
    depth: Vec<Real>,
}

impl DepthMap {
    /// Rasterises `triangles` over `positions` seen by `view` into an image `height` pixels high
    /// (width from the view's aspect) and max-filters it: everything drawn together, the
    /// reference the tests hold `from_depth`'s per-part images to (the view factors combine a
    /// kept obstacle image with the cloth's, `sizing::view`).
    #[cfg(test)]
    pub fn new(positions: &[Vec3], triangles: &[[usize; 3]], view: &View, height: usize) -> Self {
        let (width, height) = Self::size(view, height);
        Self::from_depth(
            view,
            width,
            height,
            &crate::metrics::rasterize(positions, triangles, view, width, height).depth,
        )
    }

    /// The image size (width, height) of a map `height` pixels high seen by `view`.
    pub fn size(view: &View, height: usize) -> (usize, usize) {
        let height = height.max(1);
        (((height as Real) * view.aspect).round().max(1.0) as usize, height)
    }

    /// The map of a rasterised depth image (`metrics::rasterize`'s, of the size `size` gives),
    /// max-filtered. The depth image of a union of triangle sets is the per-pixel minimum of
    /// theirs (each triangle covers the same pixel centres alone as among others).
    pub fn from_depth(view: &View, width: usize, height: usize, depth: &[Real]) -> Self {
        DepthMap { view: *view, width, height, depth: max_filter(depth, width, height) }
    }

    /// Whether `p` is not hidden: outside the image, or not behind the filtered depth by more
    /// than the tolerance (module doc).
    pub fn sees(&self, p: &Vec3) -> bool {
        let d = p - self.view.eye;
        let z = d.dot(&self.view.forward);
        if !(z >= self.view.near && z <= self.view.far) {
            return true;
        }
        let tan_v = self.view.tan_half_fov;
        let tan_h = self.view.aspect * tan_v;
        let u = (1.0 + d.dot(&self.view.right) / (z * tan_h)) * 0.5 * self.width as Real;
        let v = (1.0 - d.dot(&self.view.up) / (z * tan_v)) * 0.5 * self.height as Real;
        if !(u >= 0.0 && v >= 0.0 && u < self.width as Real && v < self.height as Real) {
            return true;
        }
        let nearest = self.depth[v as usize * self.width + u as usize];
        let pixel = 2.0 * z * tan_v / self.height as Real;
        z <= nearest + SEEN_WITHIN + pixel
    }

    /// Share of the face's sample points that are seen, in {0, ¼, ½, ¾, 1}.
    pub fn visible_fraction(&self, x: &[Vec3; 3]) -> Real {
        let seen = SAMPLES.iter().filter(|b| self.sees(&(x[0] * b[0] + x[1] * b[1] + x[2] * b[2]))).count();
        seen as Real / SAMPLES.len() as Real
    }
}

/// The maximum over each pixel's 3 × 3 neighbourhood (clamped at the image's border), as two
/// 1-D passes.
fn max_filter(depth: &[Real], width: usize, height: usize) -> Vec<Real> {
    let at = |k: usize, lo: usize, hi: usize, step: usize, src: &[Real]| {
        (lo..=hi).map(|i| src[k + i * step]).fold(Real::NEG_INFINITY, Real::max)
    };
    let mut rows = vec![0.0; depth.len()];
    for j in 0..height {
        for i in 0..width {
            rows[j * width + i] = at(j * width, i.saturating_sub(1), (i + 1).min(width - 1), 1, depth);
        }
    }
    let mut out = vec![0.0; depth.len()];
    for j in 0..height {
        for i in 0..width {
            out[j * width + i] = at(i, j.saturating_sub(1), (j + 1).min(height - 1), width, &rows);
        }
    }
    out
}

/// The occluded view factor of a face seen in a fraction `visible` of it: v μ₂ + (1 − v) μ_out.
pub fn occluded_factor(mu2: Real, visible: Real, mu_out: Real) -> Real {
    visible * mu2 + (1.0 - visible) * mu_out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::rasterize;

    /// Eye at the origin looking along +y, z up, 90° vertical fov, square image.
    fn view() -> View {
        crate::metrics::raster::tests::view(1.0)
    }

    /// A square at depth `y` facing the eye, `half` wide, centred on (cx, cz).
    fn square(y: Real, half: Real, cx: Real, cz: Real) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        let p = vec![
            Vec3::new(cx - half, y, cz - half),
            Vec3::new(cx + half, y, cz - half),
            Vec3::new(cx + half, y, cz + half),
            Vec3::new(cx - half, y, cz + half),
        ];
        (p, vec![[0, 1, 2], [0, 2, 3]])
    }

    fn merge(parts: &[(Vec<Vec3>, Vec<[usize; 3]>)]) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        for (pp, tt) in parts {
            let off = p.len();
            p.extend(pp);
            t.extend(tt.iter().map(|x| x.map(|i| i + off)));
        }
        (p, t)
    }

    #[test]
    fn a_wall_in_front_hides_what_is_behind_it_and_not_what_is_beside_or_before_it() {
        // A wall 2 m away covering the middle of the image (±0.5 m of ±2 m).
        let (p, t) = square(2.0, 0.5, 0.0, 0.0);
        let map = DepthMap::new(&p, &t, &view(), 64);
        assert!(!map.sees(&Vec3::new(0.0, 4.0, 0.0)), "behind the wall");
        assert!(map.sees(&Vec3::new(0.0, 1.0, 0.0)), "in front of the wall");
        assert!(map.sees(&Vec3::new(0.0, 2.005, 0.0)), "on the wall, within the tolerance");
        assert!(map.sees(&Vec3::new(1.5, 4.0, 0.0)), "behind, beside the wall");
        assert!(map.sees(&Vec3::new(0.0, -1.0, 0.0)), "behind the eye: out of the image");
        assert!(map.sees(&Vec3::new(50.0, 4.0, 0.0)), "outside the image");
    }

    #[test]
    fn the_minimum_of_two_parts_images_is_the_image_of_both() {
        // A wall in front of part of a far sheet, a pole crossing both, overlapping and
        // sharing pixel edges: drawn apart and combined, the map is the one drawn together.
        let parts = [square(2.0, 0.5, 0.1, 0.0), square(4.0, 1.5, -0.3, 0.2), square(3.0, 0.05, 0.0, -0.4)];
        let (p, t) = merge(&parts);
        let together = DepthMap::new(&p, &t, &view(), 64);
        let (width, height) = DepthMap::size(&view(), 64);
        let mut depth = vec![Real::INFINITY; width * height];
        for (pp, tt) in &parts {
            let image = rasterize(pp, tt, &view(), width, height);
            depth.iter_mut().zip(&image.depth).for_each(|(d, e)| *d = d.min(*e));
        }
        let apart = DepthMap::from_depth(&view(), width, height, &depth);
        assert_eq!((apart.width, apart.height), (together.width, together.height));
        assert!(apart.depth.iter().zip(&together.depth).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(together.depth.iter().any(|d| d.is_finite()) && together.depth.iter().any(|d| d.is_infinite()));
    }

    #[test]
    fn a_surface_never_hides_itself_even_seen_at_a_grazing_angle() {
        // A long floor strip seen nearly edge-on, and its own sample points.
        let p = vec![
            Vec3::new(-1.0, 1.0, -0.3),
            Vec3::new(1.0, 1.0, -0.3),
            Vec3::new(1.0, 20.0, -0.25),
            Vec3::new(-1.0, 20.0, -0.25),
        ];
        let t = vec![[0, 1, 2], [0, 2, 3]];
        let map = DepthMap::new(&p, &t, &view(), 48);
        for k in 0..200 {
            let s = k as Real / 199.0;
            let x = Vec3::new(0.9 * (2.0 * s - 1.0), 1.0 + 19.0 * s, -0.3 + 0.05 * s);
            assert!(map.sees(&x), "point {k} hidden by its own surface");
        }
    }

    #[test]
    fn thin_occluders_and_silhouette_edges_do_not_hide() {
        // A 1-pixel-wide pole in front of a far wall: the wall behind it stays seen.
        let pole = square(2.0, 0.02, 0.0, 0.0);
        let (p, t) = merge(&[pole]);
        let map = DepthMap::new(&p, &t, &view(), 64);
        assert!(map.sees(&Vec3::new(0.0, 4.0, 0.0)));
    }

    #[test]
    fn visible_fraction_counts_the_hidden_share_of_a_face() {
        // A wall hiding x < 0 behind it at depth 2 (its right edge on the axis).
        let (p, t) = square(2.0, 1.0, -1.0, 0.0);
        let map = DepthMap::new(&p, &t, &view(), 128);
        let face = |cx: Real| [Vec3::new(cx - 0.5, 4.0, -0.5), Vec3::new(cx + 0.5, 4.0, -0.5), Vec3::new(cx, 4.0, 0.5)];
        assert_eq!(map.visible_fraction(&face(-1.0)), 0.0);
        assert_eq!(map.visible_fraction(&face(2.0)), 1.0);
        // Straddling the edge: the centroid and one side point hidden, the other side seen.
        let v = map.visible_fraction(&face(0.0));
        assert!(v > 0.0 && v < 1.0, "partly hidden: {v}");
        assert_eq!(occluded_factor(1.0, 0.0, 0.1), 0.1);
        assert_eq!(occluded_factor(1.0, 1.0, 0.1), 1.0);
        assert!((occluded_factor(0.8, 0.5, 0.1) - 0.45).abs() < 1e-15);
    }

    #[test]
    fn max_filter_takes_the_farthest_of_each_neighbourhood() {
        let inf = Real::INFINITY;
        #[rustfmt::skip]
        let d = vec![
            1.0, 1.0, 1.0, 1.0,
            1.0, 2.0, 1.0, 1.0,
            1.0, 1.0, 1.0, inf,
        ];
        #[rustfmt::skip]
        let expected = vec![
            2.0, 2.0, 2.0, 1.0,
            2.0, 2.0, inf, inf,
            2.0, 2.0, inf, inf,
        ];
        assert_eq!(max_filter(&d, 4, 3), expected);
    }
}
