//! Geometric error: the two-sided distance between two cloth surfaces, over the whole cloth or
//! the part a camera sees.
//!
//! Both surfaces are sampled at one uniform density, fine enough for the finer mesh: sample
//! area a_s = (the smaller of the two meshes' mean triangle areas) / `SAMPLES_PER_TRIANGLE`. A
//! triangle of area A is split into k² congruent sub-triangles, k = ⌈√(A / a_s)⌉ (midpoint
//! subdivision of its barycentric lattice), and sampled at their centroids, each weighing A / k²
//! (the midpoint rule for ∫ d(x, other) dA). Each sample's distance to the other surface is the
//! exact point–triangle distance to its nearest triangle (`MeshSdf`'s tree, Ericson 2005
//! §5.1.5). The two sides pool their samples: the mean is (∫_A d(·, B) + ∫_B d(·, A)) /
//! (|A| + |B|), and RMS, 95th percentile and max are of the same weighted distribution.
//!
//! For the visible part, each triangle's samples are weighted also by its visible pixel fraction
//! (`FrameImage::visible_fraction`), and measured against the whole other surface.

use crate::collision::sdf::MeshSdf;
use crate::math::{Real, Vec3};

/// Samples per triangle of mean area on the finer mesh (k = 2: four).
pub const SAMPLES_PER_TRIANGLE: Real = 4.0;
/// Largest subdivision of one triangle (k² samples), so a degenerate finer mesh cannot ask for
/// unbounded samples.
const MAX_SPLIT: usize = 1024;
/// Distances below this fraction of the surfaces' bounding-box diagonal are the rounding of the
/// closest-point computation for a sample lying on the other surface, and count as 0.
const ROUNDING: Real = 1e-12;

/// A triangle mesh, with optional per-triangle weights in [0, 1] (the visible fractions).
#[derive(Clone, Copy, Debug)]
pub struct Surface<'a> {
    pub positions: &'a [Vec3],
    pub triangles: &'a [[usize; 3]],
    /// One weight per triangle; None weighs every triangle 1. Triangles of weight 0 give no
    /// samples.
    pub weight: Option<&'a [Real]>,
}

/// Area-weighted distance statistics between two surfaces.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SurfaceDistance {
    /// Weighted mean distance (m).
    pub mean: Real,
    /// Weighted root mean square distance (m).
    pub rms: Real,
    /// Weighted 95th percentile (m): the smallest sample distance at which the cumulative weight
    /// of the samples sorted by distance reaches 95 % of the total.
    pub p95: Real,
    /// Largest sample distance (m).
    pub max: Real,
    /// Samples measured, both sides together.
    pub samples: usize,
}

/// Two-sided distance between two triangle meshes, densely sampled (module doc). No samples
/// gives zeros; samples with no triangles on the other side give infinite distances (which
/// serialise as JSON `null`).
///
/// # Panics
/// If a weight slice's length differs from its triangle count, or a triangle indexes outside
/// positions.
pub fn surface_distance(a: Surface, b: Surface) -> SurfaceDistance {
    let sample_area =
        [&a, &b].iter().filter_map(|s| mean_area(s)).fold(Real::INFINITY, Real::min) / SAMPLES_PER_TRIANGLE;
    let (samples_a, mut weights) = samples(&a, sample_area);
    let (samples_b, weights_b) = samples(&b, sample_area);
    let mut dist = distances(&samples_a, b);
    dist.extend(distances(&samples_b, a));
    weights.extend(weights_b);
    let scale = diagonal(a.positions.iter().chain(b.positions));
    dist.iter_mut().filter(|d| **d < ROUNDING * scale).for_each(|d| *d = 0.0);
    let total: Real = weights.iter().sum();
    // Zero-area (or non-finite) counted triangles: fall back to equal weights.
    if total <= 0.0 || !total.is_finite() {
        weights.iter_mut().for_each(|w| *w = 1.0);
    }
    weighted_stats(&dist, &weights)
}

/// Mean area of the triangles of positive area (None when there are none).
fn mean_area(s: &Surface) -> Option<Real> {
    let areas: Vec<Real> = s.triangles.iter().map(|t| area(s.positions, t)).filter(|&a| a > 0.0).collect();
    (!areas.is_empty()).then(|| areas.iter().sum::<Real>() / areas.len() as Real)
}

fn area(x: &[Vec3], t: &[usize; 3]) -> Real {
    let [p, q, r] = t.map(|i| x[i]);
    0.5 * (q - p).cross(&(r - p)).norm()
}

/// Length of the diagonal of the points' bounding box (0 for none).
fn diagonal<'a>(points: impl Iterator<Item = &'a Vec3>) -> Real {
    let (lo, hi) = points
        .fold((Vec3::repeat(Real::INFINITY), Vec3::repeat(Real::NEG_INFINITY)), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    if lo.x <= hi.x {
        (hi - lo).norm()
    } else {
        0.0
    }
}

/// Sample points of `s` and their weights (area / k² × the triangle's weight), triangle by
/// triangle, for sample area `sample_area`.
fn samples(s: &Surface, sample_area: Real) -> (Vec<Vec3>, Vec<Real>) {
    if let Some(w) = s.weight {
        assert_eq!(w.len(), s.triangles.len(), "surface_distance: weight length differs from triangle count");
    }
    let mut points = Vec::new();
    let mut weights = Vec::new();
    for (f, t) in s.triangles.iter().enumerate() {
        let w = s.weight.map_or(1.0, |w| w[f]);
        if w <= 0.0 {
            continue;
        }
        let a = area(s.positions, t);
        let k = if sample_area > 0.0 && sample_area.is_finite() {
            ((a / sample_area).sqrt().ceil() as usize).clamp(1, MAX_SPLIT)
        } else {
            1
        };
        let [p, q, r] = t.map(|i| s.positions[i]);
        let at = |u: Real, v: Real| p + (q - p) * (u / k as Real) + (r - p) * (v / k as Real);
        let n = points.len();
        // Upward sub-triangles (i, j), (i + 1, j), (i, j + 1): centroid (i + ⅓, j + ⅓) / k;
        // downward (i + 1, j), (i, j + 1), (i + 1, j + 1): (i + ⅔, j + ⅔) / k.
        for i in 0..k {
            for j in 0..k - i {
                points.push(at(i as Real + 1.0 / 3.0, j as Real + 1.0 / 3.0));
                if i + j + 2 <= k {
                    points.push(at(i as Real + 2.0 / 3.0, j as Real + 2.0 / 3.0));
                }
            }
        }
        weights.resize(points.len(), w * a / (points.len() - n) as Real);
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

/// Weighted mean, RMS, 95th percentile (see `SurfaceDistance::p95`) and max for positive
/// finite total weight; zeros for no samples.
fn weighted_stats(dist: &[Real], weights: &[Real]) -> SurfaceDistance {
    if dist.is_empty() {
        return SurfaceDistance::default();
    }
    let total: Real = weights.iter().sum();
    let mean = dist.iter().zip(weights).map(|(d, w)| d * w).sum::<Real>() / total;
    let rms = (dist.iter().zip(weights).map(|(d, w)| d * d * w).sum::<Real>() / total).sqrt();
    let mut order: Vec<usize> = (0..dist.len()).collect();
    order.sort_by(|&i, &j| dist[i].total_cmp(&dist[j]).then(i.cmp(&j)));
    let max = dist[order[order.len() - 1]];
    let mut cumulative = 0.0;
    let p95 = order
        .iter()
        .find(|&&i| {
            cumulative += weights[i];
            cumulative >= 0.95 * total
        })
        .map_or(max, |&i| dist[i]);
    SurfaceDistance { mean, rms, p95, max, samples: dist.len() }
}

#[cfg(test)]
mod tests {
    use super::super::raster::tests::wavy_grid;
    use super::super::raster::vertex_normals;
    use super::*;

    /// The unit square [0, 1]² in the plane z = `z`, as an `n` × `n` grid of 2n² triangles.
    fn square(n: usize, z: Real) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        crate::metrics::test_grid(n, n, |i, j| Vec3::new(i, j, z))
    }

    fn surface<'a>(x: &'a [Vec3], tris: &'a [[usize; 3]], weight: Option<&'a [Real]>) -> Surface<'a> {
        Surface { positions: x, triangles: tris, weight }
    }

    #[test]
    fn identical_meshes_are_exactly_zero_apart() {
        let (x, tris) = wavy_grid(8);
        let d = surface_distance(surface(&x, &tris, None), surface(&x, &tris, None));
        assert_eq!((d.mean, d.rms, d.p95, d.max), (0.0, 0.0, 0.0, 0.0), "{d:?}");
        let (x, tris) = square(8, 0.0);
        let d = surface_distance(surface(&x, &tris, None), surface(&x, &tris, None));
        assert_eq!((d.mean, d.rms, d.p95, d.max), (0.0, 0.0, 0.0, 0.0), "{d:?}");
        // 128 triangles of the mean area: four samples each, per side.
        assert_eq!(d.samples, 2 * 4 * 128);
    }

    #[test]
    fn square_shifted_by_a_centimetre() {
        let (a, tris) = square(10, 0.0);
        let (b, _) = square(10, 0.01);
        let d = surface_distance(surface(&a, &tris, None), surface(&b, &tris, None));
        for m in [d.mean, d.rms, d.p95, d.max] {
            assert!((m - 0.01).abs() < 1e-12, "{d:?}");
        }
    }

    #[test]
    fn every_node_moved_a_centimetre_along_its_normal() {
        // A rippled 2 m sheet (curvature radius ≥ 0.12 m) and its offset by 1 cm along the
        // area-weighted vertex normals: the surfaces are 1 cm apart.
        let (a, tris) = wavy_grid(80);
        let n = vertex_normals(&a, &tris);
        let b: Vec<Vec3> = a.iter().zip(&n).map(|(p, n)| p + n * 0.01).collect();
        let d = surface_distance(surface(&a, &tris, None), surface(&b, &tris, None));
        assert!((d.mean - 0.01).abs() < 0.02 * 0.01, "{d:?}");
        assert!(d.max < 0.0105, "{d:?}");
    }

    #[test]
    fn a_coarse_mesh_is_sampled_as_densely_as_the_fine_one() {
        // Two triangles of the plane z = 0 against a fine sine wrinkle z = A sin(2πx/λ): both
        // sides' distances are ≈ A |sin kx| (to O((Ak)²)), whose mean is 2A/π. Sampling the
        // coarse side at its own vertices and centroids would miss the wrinkle's shape.
        let (amp, lambda) = (0.005, 0.2);
        let k = 2.0 * std::f64::consts::PI / lambda;
        let (flat, coarse) = square(1, 0.0);
        let (mut wrinkled, fine) = square(100, 0.0);
        wrinkled.iter_mut().for_each(|p| p.z = amp * (k * p.x).sin());
        let d = surface_distance(surface(&flat, &coarse, None), surface(&wrinkled, &fine, None));
        let expected = 2.0 * amp / std::f64::consts::PI;
        assert!((d.mean - expected).abs() < 0.02 * expected, "{} vs {expected}", d.mean);
        assert!((d.max - amp).abs() < 0.01 * amp, "{d:?}");
        // Both sides sampled alike: the coarse side's two triangles get as many samples as the
        // fine side's 20 000.
        assert!(d.samples >= 2 * 4 * 20_000, "{d:?}");
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
        assert!((d.rms - 0.005_f64.sqrt() * 0.1).abs() < 5e-4, "{d:?}");
    }

    #[test]
    fn weights_restrict_and_scale_samples() {
        let (x, tris) = square(40, 0.0);
        let (mut y, _) = square(40, 0.01);
        let full = surface_distance(surface(&x, &tris, None), surface(&y, &tris, None));
        // Weight 0 on the right half of each mesh's faces.
        let left: Vec<Real> = tris.iter().map(|t| if x[t[0]].x < 0.5 { 1.0 } else { 0.0 }).collect();
        let half = surface_distance(surface(&x, &tris, Some(&left)), surface(&y, &tris, Some(&left)));
        assert_eq!(2 * half.samples, full.samples);
        assert!((half.mean - 0.01).abs() < 1e-12, "{half:?}");
        // Lift y's right half by another centimetre: weight ½ there halves its share.
        y.iter_mut().filter(|p| p.x > 0.5 + 1e-9).for_each(|p| p.z = 0.02);
        let halves: Vec<Real> = tris.iter().map(|t| if x[t[0]].x < 0.5 { 1.0 } else { 0.5 }).collect();
        let d = surface_distance(surface(&x, &tris, Some(&halves)), surface(&y, &tris, Some(&halves)));
        // Weights 1 : ½ for distances 1 cm : 2 cm (the one column of the step between them
        // aside: 1/20 of the right half, halfway between, moves the mean by ≈ 2·10⁻⁴).
        assert!((d.mean - (0.01 + 0.5 * 0.02) / 1.5).abs() < 3e-4, "{d:?}");
    }

    #[test]
    fn weighted_samples_measure_against_the_whole_other_surface() {
        // Left half of a against the right half of an identical b: still zero apart.
        let (x, tris) = square(10, 0.0);
        let left: Vec<Real> = tris.iter().map(|t| if x[t[0]].x < 0.5 { 1.0 } else { 0.0 }).collect();
        let right: Vec<Real> = left.iter().map(|m| 1.0 - m).collect();
        let d = surface_distance(surface(&x, &tris, Some(&left)), surface(&x, &tris, Some(&right)));
        assert_eq!((d.mean, d.max), (0.0, 0.0), "{d:?}");
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
        let none = vec![0.0; tris.len()];
        assert_eq!(
            surface_distance(surface(&x, &tris, Some(&none)), surface(&x, &tris, Some(&none))),
            SurfaceDistance::default()
        );
    }
}
