//! Geometric error: the two-sided distance between two cloth surfaces, over the whole cloth or a
//! masked part of it (the triangles a camera sees).
//!
//! Each side's surface integral ∫ d(x, other) dA is approximated by the degree-2 triangle rule
//! with nodes at the vertices and the centroid: the centroid weighs 3A/4 and each vertex A/12
//! (exact for quadratic integrands), so a vertex weighs 1/12 of the area of its (counted)
//! adjacent triangles. The two sides pool their samples: the mean is
//! (∫_A d(·, B) + ∫_B d(·, A)) / (|A| + |B|), and the 95th percentile is that of the same
//! area-weighted distribution.

use super::raster::Image;
use crate::collision::sdf::MeshSdf;
use crate::math::{Real, Vec3};

/// A triangle mesh, with an optional per-triangle mask of the part whose samples count.
#[derive(Clone, Copy, Debug)]
pub struct Surface<'a> {
    pub positions: &'a [Vec3],
    pub triangles: &'a [[usize; 3]],
    /// One flag per triangle; None counts every triangle.
    pub mask: Option<&'a [bool]>,
}

/// Area-weighted distance statistics between two surfaces.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SurfaceDistance {
    /// Weighted mean distance (m).
    pub mean: Real,
    /// Weighted 95th percentile (m): the smallest sample distance at which the cumulative weight
    /// of the samples sorted by distance reaches 95 % of the total.
    pub p95: Real,
    /// Samples measured, both sides together.
    pub samples: usize,
}

/// Two-sided distance between two triangle meshes: every vertex and triangle centroid of each
/// (weighted as in the module doc) measures its unsigned distance to the other surface (closest
/// point, `MeshSdf`); mean and 95th percentile are weighted over both sides together.
///
/// With masks, only samples from triangles whose mask is true count (a vertex counts if any
/// adjacent triangle's mask is true, with the weight of those triangles only), and the other
/// surface is still the whole mesh. When every counted triangle has zero area the samples weigh
/// equally. No samples gives zeros; samples with no triangles on the other side give an infinite
/// mean and p95 (which serialise as JSON `null`).
///
/// # Panics
/// If a mask's length differs from its triangle count, or a triangle indexes outside positions.
pub fn surface_distance(a: Surface, b: Surface) -> SurfaceDistance {
    let (samples_a, mut weights) = quadrature(&a);
    let (samples_b, weights_b) = quadrature(&b);
    let mut dist = distances(&samples_a, b);
    dist.extend(distances(&samples_b, a));
    weights.extend(weights_b);
    let total: Real = weights.iter().sum();
    // Zero-area (or non-finite) counted triangles: fall back to equal weights.
    if total <= 0.0 || !total.is_finite() {
        weights.iter_mut().for_each(|w| *w = 1.0);
    }
    let (mean, p95) = weighted_mean_p95(&dist, &weights);
    SurfaceDistance { mean, p95, samples: dist.len() }
}

/// Triangles that cover at least one pixel of `image`, as a mask over `n_triangles`; face ids at or
/// above `n_triangles` are ignored.
pub fn visible_triangles(image: &Image, n_triangles: usize) -> Vec<bool> {
    let mut seen = vec![false; n_triangles];
    for &f in &image.face {
        if let Some(s) = seen.get_mut(f as usize) {
            *s = true;
        }
    }
    seen
}

/// Sample points of the counted part of `s` and their weights: centroids (3A/4), then vertices
/// (Σ A/12 over counted adjacent triangles) in index order.
fn quadrature(s: &Surface) -> (Vec<Vec3>, Vec<Real>) {
    if let Some(m) = s.mask {
        assert_eq!(m.len(), s.triangles.len(), "surface_distance: mask length differs from triangle count");
    }
    let counted = |f: usize| s.mask.is_none_or(|m| m[f]);
    let mut points = Vec::new();
    let mut weights = Vec::new();
    let mut vertex_weight = vec![0.0; s.positions.len()];
    let mut vertex_counted = vec![false; s.positions.len()];
    for t in s.triangles.iter().enumerate().filter(|&(f, _)| counted(f)).map(|(_, t)| t) {
        let [p, q, r] = t.map(|i| s.positions[i]);
        let area = 0.5 * (q - p).cross(&(r - p)).norm();
        points.push((p + q + r) / 3.0);
        weights.push(0.75 * area);
        for &i in t {
            vertex_weight[i] += area / 12.0;
            vertex_counted[i] = true;
        }
    }
    for (i, _) in vertex_counted.iter().enumerate().filter(|(_, c)| **c) {
        points.push(s.positions[i]);
        weights.push(vertex_weight[i]);
    }
    (points, weights)
}

/// Unsigned distance from each point to the whole of `other` (infinite when it has no triangles).
fn distances(points: &[Vec3], other: Surface) -> Vec<Real> {
    if points.is_empty() {
        return Vec::new();
    }
    let sdf = MeshSdf::new(other.triangles, other.positions);
    sdf.query_all(points).iter().map(|h| h.map_or(Real::INFINITY, |h| h.distance.abs())).collect()
}

/// Weighted mean and 95th percentile (see `SurfaceDistance::p95`) for positive finite total
/// weight; zeros for no samples.
fn weighted_mean_p95(dist: &[Real], weights: &[Real]) -> (Real, Real) {
    let total: Real = weights.iter().sum();
    if dist.is_empty() {
        return (0.0, 0.0);
    }
    let mean = dist.iter().zip(weights).map(|(d, w)| d * w).sum::<Real>() / total;
    let mut order: Vec<usize> = (0..dist.len()).collect();
    order.sort_by(|&i, &j| dist[i].total_cmp(&dist[j]).then(i.cmp(&j)));
    let mut cumulative = 0.0;
    let p95 = order
        .iter()
        .find(|&&i| {
            cumulative += weights[i];
            cumulative >= 0.95 * total
        })
        .map_or(dist[order[order.len() - 1]], |&i| dist[i]);
    (mean, p95)
}

#[cfg(test)]
mod tests {
    use super::super::raster::rasterize;
    use super::super::raster::tests::view;
    use super::*;

    /// The unit square [0, 1]² in the plane z = `z`, as an `n` × `n` grid of 2n² triangles.
    fn square(n: usize, z: Real) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        let x = (0..=n)
            .flat_map(|j| (0..=n).map(move |i| Vec3::new(i as Real / n as Real, j as Real / n as Real, z)))
            .collect();
        let id = |i: usize, j: usize| j * (n + 1) + i;
        let tris = (0..n)
            .flat_map(|j| {
                (0..n).flat_map(move |i| {
                    [[id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]]
                })
            })
            .collect();
        (x, tris)
    }

    fn surface<'a>(x: &'a [Vec3], tris: &'a [[usize; 3]], mask: Option<&'a [bool]>) -> Surface<'a> {
        Surface { positions: x, triangles: tris, mask }
    }

    #[test]
    fn identical_meshes_are_zero_apart() {
        let (x, tris) = square(8, 0.0);
        let d = surface_distance(surface(&x, &tris, None), surface(&x, &tris, None));
        // Zero up to the rounding of centroids and closest points.
        assert!(d.mean < 1e-15 && d.p95 < 1e-15, "{d:?}");
        // 81 vertices and 128 centroids per side.
        assert_eq!(d.samples, 2 * (81 + 128));
    }

    #[test]
    fn square_shifted_by_a_centimetre() {
        let (a, tris) = square(10, 0.0);
        let (b, _) = square(10, 0.01);
        let d = surface_distance(surface(&a, &tris, None), surface(&b, &tris, None));
        assert!((d.mean - 0.01).abs() < 1e-12, "{d:?}");
        assert!((d.p95 - 0.01).abs() < 1e-12, "{d:?}");
    }

    #[test]
    fn p95_follows_the_area_weights() {
        // The right half of b is lifted by 1 cm, the left half not: half the area is 1 cm away on
        // each side, so the mean is ≈ 5 mm and the 95th percentile 1 cm.
        let (a, tris) = square(20, 0.0);
        let (mut b, _) = square(20, 0.0);
        b.iter_mut().filter(|p| p.x > 0.5 + 1e-9).for_each(|p| p.z = 0.01);
        let d = surface_distance(surface(&a, &tris, None), surface(&b, &tris, None));
        assert!((d.mean - 0.005).abs() < 5e-4, "{d:?}");
        assert!((d.p95 - 0.01).abs() < 1e-3, "{d:?}");
    }

    #[test]
    fn masks_restrict_samples() {
        let (x, tris) = square(10, 0.0);
        let (y, _) = square(10, 0.01);
        let full = surface_distance(surface(&x, &tris, None), surface(&y, &tris, None));
        // Mask the left half of each mesh's faces.
        let left: Vec<bool> = tris.iter().map(|t| x[t[0]].x < 0.5).collect();
        let half = surface_distance(surface(&x, &tris, Some(&left)), surface(&y, &tris, Some(&left)));
        let ratio = half.samples as Real / full.samples as Real;
        assert!((0.45..0.6).contains(&ratio), "{ratio}: {half:?} vs {full:?}");
        assert!((half.mean - 0.01).abs() < 1e-12, "{half:?}");
        // A vertex counts if any adjacent face does: 6 columns of 11 vertices, 100 centroids.
        assert_eq!(half.samples, 2 * (66 + 100));
    }

    #[test]
    fn masked_samples_measure_against_the_whole_other_surface() {
        // Left half of a against the right half of an identical b: still zero apart.
        let (x, tris) = square(10, 0.0);
        let left: Vec<bool> = tris.iter().map(|t| x[t[0]].x < 0.5).collect();
        let right: Vec<bool> = left.iter().map(|m| !m).collect();
        let d = surface_distance(surface(&x, &tris, Some(&left)), surface(&x, &tris, Some(&right)));
        assert!(d.mean < 1e-15 && d.p95 < 1e-15, "{d:?}");
        assert!(d.samples > 0);
    }

    #[test]
    fn empty_surfaces() {
        let (x, tris) = square(2, 0.0);
        let empty = surface(&x, &[], None);
        assert_eq!(surface_distance(empty, empty), SurfaceDistance::default());
        let d = surface_distance(surface(&x, &tris, None), empty);
        assert_eq!(d.mean, Real::INFINITY);
        assert_eq!(serde_json::to_value(d).unwrap()["mean"], serde_json::Value::Null);
    }

    #[test]
    fn visible_triangles_are_those_with_pixels() {
        // Triangle 0 hidden behind triangle 1, triangle 2 behind the eye.
        let v = Vec3::new;
        let x = [
            v(-0.5, 3.0, -0.5),
            v(0.5, 3.0, -0.5),
            v(0.0, 3.0, 0.5),
            v(-2.0, 2.0, -2.0),
            v(2.0, 2.0, -2.0),
            v(0.0, 2.0, 2.0),
            v(-1.0, -2.0, -1.0),
            v(1.0, -2.0, -1.0),
            v(0.0, -2.0, 1.0),
        ];
        let tris = [[0, 1, 2], [3, 4, 5], [6, 7, 8]];
        let image = rasterize(&x, &tris, &view(2.0), 64, 32);
        assert_eq!(visible_triangles(&image, 3), vec![false, true, false]);
    }
}
