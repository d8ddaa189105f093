//! Visible error: how different two rasterised views of the cloth look (DESIGN.md "Error against
//! run time"): shading (normal angle, with interpolated and with flat normals), outline
//! (silhouette) and depth. The obstacles are rasterised with the cloth, so cloth they hide does
//! not count: every measure is over the pixels where cloth is the front surface.

use rayon::prelude::*;

use super::raster::{coverage, rasterize, shading_normals, vertex_normals, Image};
use crate::camera::View;
use crate::math::{Real, Vec3};

/// One frame seen by the camera: the cloth and the obstacles rasterised together (each hides
/// what is behind it), triangles `0..cloth_triangles` being cloth.
#[derive(Clone, Debug)]
pub struct FrameImage {
    pub image: Image,
    /// Per pixel, the interpolated vertex normal (`raster::shading_normals`).
    pub shading: Vec<Vec3>,
    pub cloth_triangles: usize,
    /// Per cloth triangle, the fraction of the pixel centres it covers where it is the front
    /// surface (0 for one that covers none).
    pub visible_fraction: Vec<Real>,
}

impl FrameImage {
    /// Rasterises `triangles` over `positions` (the first `cloth_triangles` cloth, the rest
    /// obstacles; no vertex shared between the two) from `view`.
    ///
    /// # Panics
    /// As `rasterize`, or if `cloth_triangles > triangles.len()`.
    pub fn render(
        positions: &[Vec3],
        triangles: &[[usize; 3]],
        cloth_triangles: usize,
        view: &View,
        width: usize,
        height: usize,
    ) -> FrameImage {
        let image = rasterize(positions, triangles, view, width, height);
        let normals = vertex_normals(positions, triangles);
        let shading = shading_normals(&image, positions, triangles, &normals, view);
        let mut front = vec![0u32; cloth_triangles];
        for &f in image.face.iter().filter(|&&f| (f as usize) < cloth_triangles) {
            front[f as usize] += 1;
        }
        let covered = coverage(positions, &triangles[..cloth_triangles], view, width, height);
        let visible_fraction = front
            .par_iter()
            .zip(&covered)
            .map(|(&v, &c)| if c > 0 { (v as Real / c as Real).min(1.0) } else { 0.0 })
            .collect();
        FrameImage { image, shading, cloth_triangles, visible_fraction }
    }

    /// True when cloth is the front surface at `pixel`.
    pub fn cloth(&self, pixel: usize) -> bool {
        (self.image.face[pixel] as usize) < self.cloth_triangles
    }
}

/// The visible difference between a reference and a candidate image, over the pixels where
/// cloth is the front surface in either (pixels where only an obstacle or nothing is seen in
/// both do not count).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct VisibleError {
    /// Mean angle (degrees) between the two images' shading normals (interpolated vertex
    /// normals, what a renderer shades) over pixels where both show cloth (0 when none).
    pub normal_deg: Real,
    /// The same with flat face normals (faceting included).
    pub normal_flat_deg: Real,
    /// Silhouette mismatch: pixels where exactly one image shows cloth / pixels where either
    /// does (0 when neither does).
    pub silhouette: Real,
    /// Mean |depth difference| over pixels where both show cloth, divided by the depth range
    /// (max − min) of the cloth pixels of both images (the scene depth); 0 if that range is 0 or
    /// no pixel shows cloth in both.
    pub depth: Real,
    /// Pixels where either image shows cloth.
    pub pixels: usize,
}

/// Compares `candidate` with `reference`, pixel by pixel. Sums run serially in pixel order, so the
/// result does not depend on the thread count.
///
/// # Panics
/// If the images differ in size: both are rendered by the caller at one resolution, so a mismatch
/// is a bug, not an input error.
pub fn visible_error(reference: &FrameImage, candidate: &FrameImage) -> VisibleError {
    let (ri, ci) = (&reference.image, &candidate.image);
    assert_eq!((ri.width, ri.height), (ci.width, ci.height), "visible_error: images differ in size");
    // atan2(|a × b|, a · b): accurate for small angles, where acos is not.
    let angle = |a: &Vec3, b: &Vec3| a.cross(b).norm().atan2(a.dot(b)).to_degrees();
    let (mut either, mut one, mut both) = (0usize, 0usize, 0usize);
    let (mut shading_sum, mut flat_sum, mut depth_sum) = (0.0, 0.0, 0.0);
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for p in 0..ri.face.len() {
        let (r, c) = (reference.cloth(p), candidate.cloth(p));
        if !(r || c) {
            continue;
        }
        either += 1;
        for (cloth, d) in [(r, ri.depth[p]), (c, ci.depth[p])] {
            if cloth {
                lo = lo.min(d);
                hi = hi.max(d);
            }
        }
        if r && c {
            both += 1;
            shading_sum += angle(&reference.shading[p], &candidate.shading[p]);
            flat_sum += angle(&ri.normal[p], &ci.normal[p]);
            depth_sum += (ri.depth[p] - ci.depth[p]).abs();
        } else {
            one += 1;
        }
    }
    let mean = |sum: Real| if both > 0 { sum / both as Real } else { 0.0 };
    let range = hi - lo;
    VisibleError {
        normal_deg: mean(shading_sum),
        normal_flat_deg: mean(flat_sum),
        silhouette: if either > 0 { one as Real / either as Real } else { 0.0 },
        depth: if range > 0.0 { mean(depth_sum) / range } else { 0.0 },
        pixels: either,
    }
}

#[cfg(test)]
mod tests {
    use super::super::raster::tests::{view, wavy_grid};
    use super::*;

    fn v(x: Real, y: Real, z: Real) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// Cloth only, seen by `view(aspect)`.
    fn cloth(x: &[Vec3], tris: &[[usize; 3]], aspect: Real, w: usize, h: usize) -> FrameImage {
        FrameImage::render(x, tris, tris.len(), &view(aspect), w, h)
    }

    /// An `nx` × `nz` grid over [−s/2, s/2]² in x–z, at depth y = `depth(x, z)`: 2 nx nz
    /// triangles.
    pub(crate) fn sheet(
        nx: usize,
        nz: usize,
        s: Real,
        depth: impl Fn(Real, Real) -> Real,
    ) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        super::super::test_grid(nx, nz, |u, w| {
            let (a, b) = (s * (u - 0.5), s * (w - 0.5));
            v(a, depth(a, b), b)
        })
    }

    /// `cloth` followed by `obstacle`, renumbered: one mesh to rasterise.
    fn with_obstacle(
        cloth: &(Vec<Vec3>, Vec<[usize; 3]>),
        obstacle: &(Vec<Vec3>, Vec<[usize; 3]>),
    ) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        let n = cloth.0.len();
        let x = cloth.0.iter().chain(&obstacle.0).copied().collect();
        let t = cloth.1.iter().copied().chain(obstacle.1.iter().map(|t| t.map(|i| i + n))).collect();
        (x, t)
    }

    #[test]
    fn identical_images_have_no_error() {
        let (x, tris) = wavy_grid(20);
        let image = cloth(&x, &tris, 2.0, 200, 100);
        let e = visible_error(&image, &image);
        assert_eq!((e.normal_deg, e.normal_flat_deg, e.silhouette, e.depth), (0.0, 0.0, 0.0, 0.0));
        assert!(e.pixels > 1000);
        let empty = cloth(&x, &[], 2.0, 200, 100);
        assert_eq!(visible_error(&empty, &empty), VisibleError::default());
    }

    #[test]
    fn unit_square_facing_the_camera_covers_its_pixel_count() {
        // At depth 2 with tan(fov/2) = 1 and 400 rows, the image spans 4 m: 100 px per metre, so
        // a unit square covers 100² pixels, wherever it sits against the pixel grid.
        let (w, h) = (400, 400);
        for (dx, dz) in [(0.0, 0.0), (0.0031, -0.0047), (0.211, 0.137)] {
            let (mut x, tris) = sheet(3, 3, 1.0, |_, _| 2.0);
            x.iter_mut().for_each(|p| *p += v(dx, 0.0, dz));
            let image = cloth(&x, &tris, 1.0, w, h);
            let n = (0..w * h).filter(|&p| image.cloth(p)).count() as Real;
            assert!((n - 10_000.0).abs() < 100.0, "offset ({dx}, {dz}): {n} pixels");
            // Nothing in front; pixel centres on a shared edge count for both its triangles
            // (`raster::coverage`), so a fraction may fall a little below 1.
            assert!(image.visible_fraction.iter().all(|&f| f > 0.9), "{:?}", image.visible_fraction);
        }
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
        let reference = cloth(&tri(0.0), &[[0, 1, 2]], 2.0, w, h);
        let candidate = cloth(&tri(s), &[[0, 1, 2]], 2.0, w, h);
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
        assert!(e.normal_deg < 1e-9 && e.normal_flat_deg < 1e-9 && e.depth == 0.0, "{e:?}");
    }

    #[test]
    fn tilted_square_has_its_tilt_as_normal_error() {
        let (w, h) = (200, 100);
        let square = |tilt_deg: Real| {
            let (s, c) = tilt_deg.to_radians().sin_cos();
            // Rotated about the vertical axis through (0, 2, 0).
            let p = |x: Real, z: Real| v(x * c, 2.0 + x * s, z);
            vec![p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)]
        };
        let tris = [[0, 1, 2], [0, 2, 3]];
        let reference = cloth(&square(0.0), &tris, 2.0, w, h);
        let candidate = cloth(&square(10.0), &tris, 2.0, w, h);
        let e = visible_error(&reference, &candidate);
        assert!((e.normal_deg - 10.0).abs() < 1e-9, "{e:?}");
        assert!((e.normal_flat_deg - 10.0).abs() < 1e-9, "{e:?}");
        assert!(e.depth > 0.0 && e.silhouette > 0.0, "{e:?}");
    }

    #[test]
    fn cloth_wholly_behind_an_obstacle_has_no_visible_error() {
        let (w, h) = (200, 100);
        // A wall at depth 1.5 filling the view; two very different cloths behind it.
        let wall = sheet(1, 1, 20.0, |_, _| 1.5);
        let flat = sheet(10, 10, 1.0, |_, _| 2.0);
        let wavy = wavy_grid(30);
        let render = |c: &(Vec<Vec3>, Vec<[usize; 3]>)| {
            let (x, t) = with_obstacle(c, &wall);
            FrameImage::render(&x, &t, c.1.len(), &view(2.0), w, h)
        };
        let (a, b) = (render(&flat), render(&wavy));
        assert_eq!(visible_error(&a, &b), VisibleError::default());
        assert!(a.visible_fraction.iter().chain(&b.visible_fraction).all(|&f| f == 0.0));
        // Without the wall they differ everywhere.
        let e = visible_error(&cloth(&flat.0, &flat.1, 2.0, w, h), &cloth(&wavy.0, &wavy.1, 2.0, w, h));
        assert!(e.silhouette > 0.3 && e.normal_deg > 1.0, "{e:?}");
    }

    #[test]
    fn a_half_hidden_cloth_counts_only_its_visible_half() {
        let (w, h) = (200, 200);
        // An obstacle hides x < 0 (at depth 1.5); cloth at depth 2 spans x ∈ [−0.5, 0.5].
        let wall = (
            vec![v(-5.0, 1.5, -5.0), v(0.0, 1.5, -5.0), v(0.0, 1.5, 5.0), v(-5.0, 1.5, 5.0)],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let a = sheet(8, 8, 1.0, |_, _| 2.0);
        let b = sheet(8, 8, 1.0, |x, _| 2.0 + 0.1 * x);
        let render = |c: &(Vec<Vec3>, Vec<[usize; 3]>)| {
            let (x, t) = with_obstacle(c, &wall);
            FrameImage::render(&x, &t, c.1.len(), &view(1.0), w, h)
        };
        let (ra, rb) = (render(&a), render(&b));
        let e = visible_error(&ra, &rb);
        // 50 px per metre at depth 2: the right half, 25 × 50 px (b is slightly smaller there).
        assert!((e.pixels as Real - 1250.0).abs() < 60.0, "{e:?}");
        let f = &ra.visible_fraction;
        let centre_x = |t: &[usize; 3]| t.iter().map(|&i| a.0[i].x).sum::<Real>() / 3.0;
        for (t, &frac) in a.1.iter().zip(f) {
            let hidden = centre_x(t) < 0.0;
            assert!(if hidden { frac == 0.0 } else { frac > 0.9 }, "triangle centred at x = {}: {frac}", centre_x(t));
        }
    }

    #[test]
    fn sine_wrinkle_has_the_analytic_mean_normal_angle() {
        // y = 1.2 + A sin(2πx / λ) against the flat sheet y = 1.2: at x the normals differ by
        // atan(A k |cos kx|), k = 2π/λ. Seen head on, pixels sample x uniformly (the depth
        // ripple moves them by < 1 %), so the mean over whole periods is
        // (1/π) ∫₀^π atan(A k |cos u|) du, integrated here by the midpoint rule.
        let (amp, lambda) = (0.01, 0.2);
        let ak = amp * 2.0 * std::f64::consts::PI / lambda;
        let m = 100_000;
        let analytic = (0..m)
            .map(|i| (ak * ((i as Real + 0.5) / m as Real * std::f64::consts::PI).cos().abs()).atan())
            .sum::<Real>()
            / m as Real;
        let k = 2.0 * std::f64::consts::PI / lambda;
        // 1 m wide: five whole periods, 40 columns of quads per period.
        let flat = sheet(200, 20, 1.0, |_, _| 1.2);
        let wrinkled = sheet(200, 20, 1.0, |x, _| 1.2 + amp * (k * x).sin());
        let (a, b) = (cloth(&flat.0, &flat.1, 1.0, 600, 600), cloth(&wrinkled.0, &wrinkled.1, 1.0, 600, 600));
        let e = visible_error(&a, &b);
        let expected = analytic.to_degrees();
        assert!((e.normal_deg - expected).abs() < 0.05 * expected, "{} vs {expected}°", e.normal_deg);
    }

    #[test]
    fn coarse_and_fine_meshes_of_one_surface_agree_in_shading_normals() {
        let (w, h) = (300, 300);
        // A flat sheet: none at all.
        let (coarse, fine) = (sheet(3, 3, 1.0, |_, _| 2.0), sheet(40, 40, 1.0, |_, _| 2.0));
        let e = visible_error(&cloth(&fine.0, &fine.1, 1.0, w, h), &cloth(&coarse.0, &coarse.1, 1.0, w, h));
        assert!(e.normal_deg < 1e-6 && e.normal_flat_deg < 1e-6, "{e:?}");
        // A sheet bent round a cylinder of radius 1, 1.4 m wide (80°), in 7 columns of facets
        // 11.5° apart against 70, seen through a narrow lens (tan(fov/2) = 0.2) that frames
        // only its middle, where every vertex is interior (at a boundary vertex the area-weighted
        // normal is its one facet's). Flat normals are off by up to 5.7°, shading normals nearly agree.
        let bend = |x: Real, _| 2.0 + 1.0 - (1.0 - x * x).sqrt();
        let (coarse, fine) = (sheet(7, 14, 1.4, bend), sheet(70, 14, 1.4, bend));
        let mut narrow = view(1.0);
        narrow.tan_half_fov = 0.2;
        let render = |m: &(Vec<Vec3>, Vec<[usize; 3]>)| FrameImage::render(&m.0, &m.1, m.1.len(), &narrow, w, h);
        let e = visible_error(&render(&fine), &render(&coarse));
        assert_eq!(e.pixels, w * h, "the sheet fills the frame");
        assert!(e.normal_flat_deg > 2.0, "{e:?}");
        // What is left is second order in the facet angle (normals interpolated linearly along a
        // chord, not along the arc): ≈ 0.37° here.
        assert!(e.normal_deg < 0.15 * e.normal_flat_deg && e.normal_deg < 0.5, "{e:?}");
    }

    #[test]
    fn depth_error_is_relative_to_scene_depth() {
        // Hand-made 3 × 1 images: pixel 0 both (depths 2 and 2.5), pixel 1 reference only (4),
        // pixel 2 neither.
        let image = |depth: [Real; 3]| {
            let normal: Vec<Vec3> = depth.map(|d| if d.is_finite() { Vec3::y() } else { Vec3::zeros() }).to_vec();
            let image = Image {
                width: 3,
                height: 1,
                depth: depth.to_vec(),
                normal: normal.clone(),
                face: depth.map(|d| if d.is_finite() { 0 } else { u32::MAX }).to_vec(),
            };
            FrameImage { image, shading: normal, cloth_triangles: 1, visible_fraction: vec![1.0] }
        };
        let reference = image([2.0, 4.0, Real::INFINITY]);
        let candidate = image([2.5, Real::INFINITY, Real::INFINITY]);
        let e = visible_error(&reference, &candidate);
        // |2 − 2.5| / (4 − 2).
        let expected = VisibleError { normal_deg: 0.0, normal_flat_deg: 0.0, silhouette: 0.5, depth: 0.25, pixels: 2 };
        assert_eq!(e, expected);
        let json = serde_json::to_value(e).unwrap();
        assert_eq!(json["pixels"], 2);
    }

    #[test]
    #[should_panic(expected = "differ in size")]
    fn different_sizes_panic() {
        let (x, tris) = wavy_grid(2);
        visible_error(&cloth(&x, &tris, 2.0, 20, 10), &cloth(&x, &tris, 2.0, 10, 20));
    }
}
