//! Distance queries and an intersection test on triangles and segments.
//!
//! Closest points follow Ericson, "Real-Time Collision Detection" (2005), §5.1.5 (point–triangle,
//! Voronoi regions) and §5.1.9 (segment–segment), with degenerate inputs handled explicitly so
//! that no query divides by zero. Point–mesh signed distance lives in `sdf`.

use crate::math::{Real, Vec2, Vec3};

/// Relative size below which a squared length or area counts as zero.
const DEGENERATE: Real = 1e-24;

/// The closest point of a triangle `(a, b, c)` to a query point.
#[derive(Clone, Copy, Debug)]
pub struct TriangleClosest {
    /// Barycentric weights of the closest point: each in [0, 1], summing to 1.
    pub bary: [Real; 3],
    pub point: Vec3,
    pub dist: Real,
    /// Unit triangle normal flipped to the query point's side (for a degenerate triangle, the
    /// direction to the point, or any unit vector perpendicular to its longest edge).
    pub normal: Vec3,
    /// True when the closest point is strictly inside the face (not on an edge or a vertex).
    pub interior: bool,
}

/// The closest points of two segments `p0 + s (p1 − p0)` and `q0 + t (q1 − q0)`.
#[derive(Clone, Copy, Debug)]
pub struct SegmentClosest {
    pub s: Real,
    pub t: Real,
    pub dist: Real,
}

/// Closest point of `p` on segment `a`–`b`, as the parameter in [0, 1].
pub fn point_segment_param(p: &Vec3, a: &Vec3, b: &Vec3) -> Real {
    let ab = b - a;
    let l2 = ab.norm_squared();
    if l2 == 0.0 {
        return 0.0;
    }
    ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
}

/// Any unit vector perpendicular to `v` (`v` need not be normalised; a zero `v` gives `e_z`).
pub fn any_perpendicular(v: &Vec3) -> Vec3 {
    let axis = if v.x.abs() <= v.y.abs() && v.x.abs() <= v.z.abs() {
        Vec3::x()
    } else if v.y.abs() <= v.z.abs() {
        Vec3::y()
    } else {
        Vec3::z()
    };
    v.cross(&axis).try_normalize(0.0).unwrap_or_else(Vec3::z)
}

/// Closest point on triangle `(a, b, c)` to `p` (Ericson 2005, §5.1.5).
pub fn closest_point_triangle(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> TriangleClosest {
    let (ab, ac) = (b - a, c - a);
    let cross = ab.cross(&ac);
    let scale2 = ab.norm_squared().max(ac.norm_squared()).max((c - b).norm_squared());
    if cross.norm_squared() <= DEGENERATE * scale2 * scale2 {
        return closest_point_degenerate(p, [a, b, c]);
    }
    let bary = triangle_region(p, a, b, c);
    let point = a * bary[0] + b * bary[1] + c * bary[2];
    let mut normal = cross.normalize();
    if normal.dot(&(p - a)) < 0.0 {
        normal = -normal;
    }
    TriangleClosest { bary, point, dist: (p - point).norm(), normal, interior: bary.iter().all(|&w| w > 0.0) }
}

/// Barycentrics of the closest point of a non-degenerate triangle, by Voronoi region. Every
/// denominator is a squared edge length or |ab × ac|² (Lagrange identity), hence positive.
fn triangle_region(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> [Real; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = va + vb + vc;
    let (v, w) = (vb / denom, vc / denom);
    [1.0 - v - w, v, w]
}

/// A degenerate (needle or point) triangle: the nearest of its three edges.
fn closest_point_degenerate(p: &Vec3, x: [&Vec3; 3]) -> TriangleClosest {
    let mut best: Option<(Real, [Real; 3])> = None;
    let mut longest = Vec3::zeros();
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        let s = point_segment_param(p, x[i], x[j]);
        let q = x[i] * (1.0 - s) + x[j] * s;
        let d2 = (p - q).norm_squared();
        if best.is_none_or(|(b, _)| d2 < b) {
            let mut bary = [0.0; 3];
            bary[i] += 1.0 - s;
            bary[j] += s;
            best = Some((d2, bary));
        }
        if (x[j] - x[i]).norm_squared() > longest.norm_squared() {
            longest = x[j] - x[i];
        }
    }
    let (_, bary) = best.expect("three edges were tried");
    let point = x[0] * bary[0] + x[1] * bary[1] + x[2] * bary[2];
    let dist = (p - point).norm();
    let normal = if dist > 0.0 { (p - point) / dist } else { any_perpendicular(&longest) };
    TriangleClosest { bary, point, dist, normal, interior: false }
}

/// Closest points of segments `p0`–`p1` and `q0`–`q1` (Ericson 2005, §5.1.9). Parallel overlapping
/// segments return the middle of the overlap, so the pair is well defined and symmetric.
pub fn closest_segments(p0: &Vec3, p1: &Vec3, q0: &Vec3, q1: &Vec3) -> SegmentClosest {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.norm_squared(), d2.norm_squared(), d2.dot(&r));
    // A segment shorter than 1e-10 of the other counts as a point.
    let tiny = 1e-20 * a.max(e);
    let (s, t) = if a <= tiny && e <= tiny {
        (0.0, 0.0)
    } else if a <= tiny {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= tiny {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            segment_params(a, d1.dot(&d2), c, e, f)
        }
    };
    let dist = ((p0 + d1 * s) - (q0 + d2 * t)).norm();
    SegmentClosest { s, t, dist }
}

/// The general case of `closest_segments`, both segments of positive length.
fn segment_params(a: Real, b: Real, c: Real, e: Real, f: Real) -> (Real, Real) {
    let denom = a * e - b * b; // = |d1 × d2|² ≥ 0
    let mut s = if denom > 1e-14 * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        // Parallel: q0, q1 project onto p's line at −c/a and (b − c)/a.
        let (u0, u1) = (-c / a, (b - c) / a);
        let (lo, hi) = (u0.min(u1).max(0.0), u0.max(u1).min(1.0));
        if lo <= hi {
            0.5 * (lo + hi)
        } else {
            0.0
        }
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Six times the signed volume of tetrahedron `(a, b, c, d)`: (b − a) × (c − a) · (d − a).
#[inline]
pub fn orient3d(a: &Vec3, b: &Vec3, c: &Vec3, d: &Vec3) -> Real {
    (b - a).cross(&(c - a)).dot(&(d - a))
}

/// Whether two triangles intersect (touching counts). Meant for non-adjacent triangles: two
/// triangles sharing a vertex always touch. Non-coplanar triangles intersect iff an edge of one
/// crosses the other (each end of the intersection segment lies on an edge); coplanar ones are
/// tested in 2D after dropping the normal's dominant axis.
pub fn triangles_intersect(t: &[Vec3; 3], u: &[Vec3; 3]) -> bool {
    let dt = u.map(|x| orient3d(&t[0], &t[1], &t[2], &x));
    let du = t.map(|x| orient3d(&u[0], &u[1], &u[2], &x));
    let same_side = |d: &[Real; 3]| d.iter().all(|&v| v > 0.0) || d.iter().all(|&v| v < 0.0);
    if same_side(&dt) || same_side(&du) {
        return false; // Möller 1997: one triangle strictly on one side of the other's plane
    }
    let nu = (u[1] - u[0]).cross(&(u[2] - u[0]));
    let scale = t.iter().chain(u).map(|x| (x - u[0]).norm()).fold(0.0, Real::max);
    if du.iter().all(|d| d.abs() <= 1e-12 * nu.norm() * scale) {
        return coplanar_intersect(t, u, &nu);
    }
    (0..3).any(|k| segment_triangle_intersect(&t[k], &t[(k + 1) % 3], u))
        || (0..3).any(|k| segment_triangle_intersect(&u[k], &u[(k + 1) % 3], t))
}

/// Whether segment `p`–`q` meets triangle `x` (touching counts).
pub fn segment_triangle_intersect(p: &Vec3, q: &Vec3, x: &[Vec3; 3]) -> bool {
    let dp = orient3d(&x[0], &x[1], &x[2], p);
    let dq = orient3d(&x[0], &x[1], &x[2], q);
    if dp * dq > 0.0 {
        return false;
    }
    if dp == 0.0 && dq == 0.0 {
        let n = (x[1] - x[0]).cross(&(x[2] - x[0]));
        let tri = x.map(|v| project(&v, &n));
        return segment_triangle_2d(&project(p, &n), &project(q, &n), &tri);
    }
    // The line pq passes through the triangle iff it turns the same way around all three edges.
    let s = [0, 1, 2].map(|k| orient3d(p, q, &x[k], &x[(k + 1) % 3]));
    s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
}

/// Drop the dominant axis of `n`.
fn project(x: &Vec3, n: &Vec3) -> Vec2 {
    let m = n.abs();
    if m.x >= m.y && m.x >= m.z {
        Vec2::new(x.y, x.z)
    } else if m.y >= m.z {
        Vec2::new(x.z, x.x)
    } else {
        Vec2::new(x.x, x.y)
    }
}

fn coplanar_intersect(t: &[Vec3; 3], u: &[Vec3; 3], n: &Vec3) -> bool {
    let (t2, u2) = (t.map(|x| project(&x, n)), u.map(|x| project(&x, n)));
    (0..3).any(|k| segment_triangle_2d(&t2[k], &t2[(k + 1) % 3], &u2)) || point_in_triangle_2d(&u2[0], &t2)
}

#[inline]
fn orient2d(a: &Vec2, b: &Vec2, c: &Vec2) -> Real {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

fn point_in_triangle_2d(p: &Vec2, x: &[Vec2; 3]) -> bool {
    let s = [0, 1, 2].map(|k| orient2d(&x[k], &x[(k + 1) % 3], p));
    s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
}

fn segments_intersect_2d(p: &Vec2, q: &Vec2, a: &Vec2, b: &Vec2) -> bool {
    let (d1, d2) = (orient2d(a, b, p), orient2d(a, b, q));
    let (d3, d4) = (orient2d(p, q, a), orient2d(p, q, b));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return true;
    }
    // Collinear touching cases: an endpoint on the other segment.
    let on = |x: &Vec2, y: &Vec2, z: &Vec2, o: Real| {
        o == 0.0 && z.x >= x.x.min(y.x) && z.x <= x.x.max(y.x) && z.y >= x.y.min(y.y) && z.y <= x.y.max(y.y)
    };
    on(a, b, p, d1) || on(a, b, q, d2) || on(p, q, a, d3) || on(p, q, b, d4)
}

fn segment_triangle_2d(p: &Vec2, q: &Vec2, x: &[Vec2; 3]) -> bool {
    point_in_triangle_2d(p, x) || (0..3).any(|k| segments_intersect_2d(p, q, &x[k], &x[(k + 1) % 3]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::test_rng::Rng;

    fn v(x: Real, y: Real, z: Real) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// Brute force: minimum distance over a fine barycentric grid.
    fn brute_triangle(p: &Vec3, x: &[Vec3; 3]) -> Real {
        let n = 200;
        let mut best = Real::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, w) = (i as Real / n as Real, j as Real / n as Real);
                let q = x[0] * (1.0 - u - w) + x[1] * u + x[2] * w;
                best = best.min((p - q).norm());
            }
        }
        best
    }

    #[test]
    fn point_triangle_regions() {
        let (a, b, c) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let cases = [
            (v(0.2, 0.3, 0.5), [0.5, 0.2, 0.3], 0.5, true),            // face interior
            (v(-1.0, -1.0, 0.0), [1.0, 0.0, 0.0], 2f64.sqrt(), false), // vertex a
            (v(2.0, -0.5, 0.0), [0.0, 1.0, 0.0], 1.25f64.sqrt(), false), // vertex b
            (v(0.5, -0.5, -0.1), [0.5, 0.5, 0.0], 0.26f64.sqrt(), false), // edge ab
            (v(1.0, 1.0, 0.0), [0.0, 0.5, 0.5], 0.5f64.sqrt(), false), // edge bc
            (v(-0.5, 0.25, 0.0), [0.75, 0.0, 0.25], 0.5, false),       // edge ca
        ];
        for (p, bary, dist, interior) in cases {
            let cl = closest_point_triangle(&p, &a, &b, &c);
            for k in 0..3 {
                assert!((cl.bary[k] - bary[k]).abs() < 1e-14, "{p}: {:?}", cl.bary);
            }
            assert!((cl.dist - dist).abs() < 1e-14);
            assert_eq!(cl.interior, interior);
        }
        // The normal is flipped toward the point's side.
        assert_eq!(closest_point_triangle(&v(0.2, 0.2, 0.3), &a, &b, &c).normal, v(0.0, 0.0, 1.0));
        assert_eq!(closest_point_triangle(&v(0.2, 0.2, -0.3), &a, &b, &c).normal, v(0.0, 0.0, -1.0));
    }

    #[test]
    fn point_triangle_matches_brute_force() {
        let mut rng = Rng(7);
        for _ in 0..200 {
            let x = [rng.vec(), rng.vec(), rng.vec()];
            let p = rng.vec() * 1.5;
            let cl = closest_point_triangle(&p, &x[0], &x[1], &x[2]);
            let brute = brute_triangle(&p, &x);
            // The grid point is never closer; the exact one is at most a grid cell away.
            assert!(cl.dist <= brute + 1e-12 && brute - cl.dist < 2e-2, "{} vs {brute}", cl.dist);
            let q = x[0] * cl.bary[0] + x[1] * cl.bary[1] + x[2] * cl.bary[2];
            assert!((q - cl.point).norm() < 1e-14 && ((p - q).norm() - cl.dist).abs() < 1e-14);
            assert!((cl.normal.norm() - 1.0).abs() < 1e-14 && cl.normal.dot(&(p - x[0])) >= 0.0);
        }
    }

    #[test]
    fn degenerate_triangles() {
        let p = v(0.5, 1.0, 0.0);
        // Needle (collinear) and point triangles: nearest edge or the point itself.
        let cl = closest_point_triangle(&p, &v(0.0, 0.0, 0.0), &v(1.0, 0.0, 0.0), &v(2.0, 0.0, 0.0));
        assert!((cl.dist - 1.0).abs() < 1e-15 && (cl.normal - v(0.0, 1.0, 0.0)).norm() < 1e-15);
        assert!((cl.point - v(0.5, 0.0, 0.0)).norm() < 1e-15);
        let o = v(0.0, 0.0, 0.0);
        let cl = closest_point_triangle(&p, &o, &o, &o);
        assert!((cl.dist - 1.25f64.sqrt()).abs() < 1e-15 && cl.bary.iter().sum::<Real>() == 1.0);
        let cl = closest_point_triangle(&o, &o, &o, &o);
        assert!(cl.dist == 0.0 && (cl.normal.norm() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn segments_closest() {
        let s = closest_segments(&v(-1.0, 0.0, 0.0), &v(1.0, 0.0, 0.0), &v(0.0, -1.0, 1.0), &v(0.0, 3.0, 1.0));
        assert!((s.s - 0.5).abs() < 1e-15 && (s.t - 0.25).abs() < 1e-15 && (s.dist - 1.0).abs() < 1e-15);
        // Parallel, overlapping on x ∈ [0.5, 1]: the middle of the overlap.
        let s = closest_segments(&v(0.0, 0.0, 0.0), &v(1.0, 0.0, 0.0), &v(0.5, 0.1, 0.0), &v(2.5, 0.1, 0.0));
        assert!((s.s - 0.75).abs() < 1e-15 && (s.t - 0.125).abs() < 1e-15 && (s.dist - 0.1).abs() < 1e-15);
        // Parallel and disjoint (anti-parallel): nearest ends.
        let s = closest_segments(&v(0.0, 0.0, 0.0), &v(1.0, 0.0, 0.0), &v(3.0, 1.0, 0.0), &v(2.0, 1.0, 0.0));
        assert!(s.s == 1.0 && s.t == 1.0 && (s.dist - 2f64.sqrt()).abs() < 1e-15);
        // Degenerate segments.
        let s = closest_segments(&v(0.5, 1.0, 0.0), &v(0.5, 1.0, 0.0), &v(0.0, 0.0, 0.0), &v(1.0, 0.0, 0.0));
        assert!(s.s == 0.0 && (s.t - 0.5).abs() < 1e-15 && (s.dist - 1.0).abs() < 1e-15);
        let o = v(0.0, 0.0, 0.0);
        assert_eq!(closest_segments(&o, &o, &o, &o).dist, 0.0);
    }

    #[test]
    fn segments_match_brute_force() {
        let mut rng = Rng(11);
        for i in 0..300 {
            let (p0, mut p1, q0, q1) = (rng.vec(), rng.vec(), rng.vec(), rng.vec());
            if i % 3 == 0 {
                p1 = p0 + (q1 - q0) * (0.3 + rng.uniform()); // parallel pairs too
            }
            let sc = closest_segments(&p0, &p1, &q0, &q1);
            let at = |s: Real, t: Real| ((p0 + (p1 - p0) * s) - (q0 + (q1 - q0) * t)).norm();
            assert!((at(sc.s, sc.t) - sc.dist).abs() < 1e-14 && (0.0..=1.0).contains(&sc.s));
            let n = 400;
            let brute = (0..=n)
                .flat_map(|i| (0..=n).map(move |j| (i as Real / n as Real, j as Real / n as Real)))
                .map(|(s, t)| at(s, t))
                .fold(Real::INFINITY, Real::min);
            assert!(sc.dist <= brute + 1e-12 && brute - sc.dist < 1e-2, "{} vs {brute}", sc.dist);
        }
    }

    #[test]
    fn triangle_pairs() {
        let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        // An edge of u pierces t's interior; t's edges miss u.
        let u = [v(0.2, 0.2, -1.0), v(0.2, 0.2, 1.0), v(3.0, 3.0, 0.5)];
        assert!(triangles_intersect(&t, &u) && triangles_intersect(&u, &t));
        // Lifted above t: disjoint.
        let up = u.map(|x| x + v(0.0, 0.0, 1.01));
        assert!(!triangles_intersect(&t, &up));
        // Crossing like two links of a chain.
        let u = [v(0.3, -0.5, -0.5), v(0.3, 0.5, 0.5), v(0.3, -0.5, 0.5)];
        assert!(triangles_intersect(&t, &u));
        // Straddling t's plane but beside it.
        let u = [v(2.0, 2.0, -1.0), v(2.0, 3.0, 1.0), v(3.0, 2.0, 1.0)];
        assert!(!triangles_intersect(&t, &u));
        // Touching at one point (a vertex of u on t's face).
        let u = [v(0.25, 0.25, 0.0), v(0.25, 0.0, 1.0), v(0.0, 0.25, 1.0)];
        assert!(triangles_intersect(&t, &u));
    }

    #[test]
    fn coplanar_triangle_pairs() {
        let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        let overlapping = [v(0.5, 0.5, 0.0), v(-0.5, 0.2, 0.0), v(0.2, -0.5, 0.0)];
        let inside = [v(0.1, 0.1, 0.0), v(0.3, 0.1, 0.0), v(0.1, 0.3, 0.0)];
        let disjoint = [v(0.6, 0.6, 0.0), v(1.6, 0.6, 0.0), v(0.6, 1.6, 0.0)];
        assert!(triangles_intersect(&t, &overlapping));
        assert!(triangles_intersect(&t, &inside) && triangles_intersect(&inside, &t));
        assert!(!triangles_intersect(&t, &disjoint));
        // A flat sheet: non-adjacent triangles of a grid never intersect, even rotated.
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let quad = |i: Real, j: Real| [v(i, j, 0.0), v(i + 1.0, j, 0.0), v(i, j + 1.0, 0.0)].map(|x| r * (x * 0.1));
        assert!(!triangles_intersect(&quad(0.0, 0.0), &quad(1.0, 1.0)));
        assert!(!triangles_intersect(&quad(0.0, 0.0), &quad(2.0, 0.0)));
    }

    /// Random pairs built to share a point intersect; pairs split by a plane do not.
    #[test]
    fn triangle_pairs_random() {
        let mut rng = Rng(3);
        for _ in 0..500 {
            let q = rng.vec();
            let mut tri = |q: Vec3| {
                let (e1, e2) = (rng.vec(), rng.vec());
                let (u, w) = (rng.uniform() * 0.5, rng.uniform() * 0.5);
                [q - e1 * u - e2 * w, q + e1 * (1.0 - u) - e2 * w, q - e1 * u + e2 * (1.0 - w)]
            };
            let (t, u) = (tri(q), tri(q));
            assert!(triangles_intersect(&t, &u), "{t:?} {u:?}");
            // Separate along a random direction beyond both triangles' extents.
            let d = rng.vec().normalize();
            let (tmin, umax) = (t.map(|x| x.dot(&d)), u.map(|x| x.dot(&d)));
            let gap = umax.iter().fold(Real::MIN, |m, &x| m.max(x)) - tmin.iter().fold(Real::MAX, |m, &x| m.min(x));
            let shifted = u.map(|x| x - d * (gap + 1e-3));
            assert!(!triangles_intersect(&t, &shifted));
        }
    }
}
