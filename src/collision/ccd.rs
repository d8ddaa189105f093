//! Continuous collision detection of linearly moving primitives over one step, t ∈ [0, 1].
//!
//! Four points moving linearly, xᵢ(t) = xᵢ⁰ + t (xᵢ¹ − xᵢ⁰), are coplanar when
//! (x₁ − x₀) × (x₂ − x₀) · (x₃ − x₀) = 0, a cubic in t (Provot 1997; Bridson, Fedkiw & Anderson
//! 2002, §4). Every root in [0, 1] is a candidate contact time; the first one at which the
//! primitives are within `tol` of touching is the impact (as ARCSim's `collision_test`).
//!
//! Robustness: the cubic's critical points split [0, 1] into monotone pieces, each bracketed root
//! is refined on the triple product evaluated directly from positions (no cancellation in the
//! expanded coefficients), near-double roots (a critical point within `tol` of coplanar) are
//! candidates too, and motion that stays coplanar throughout falls back to the in-plane times at
//! which a vertex crosses an edge's line.

use super::geometry::{any_perpendicular, closest_point_triangle, closest_segments, orient3d};
use crate::math::{Real, Vec3};

/// Distance (m) under which primitives count as touching at a root (ARCSim uses 1e-6).
pub const CCD_TOLERANCE: Real = 1e-6;

/// A contact found over the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Impact {
    /// Time of contact as a fraction of the step.
    pub t: Real,
    /// Signed weights, Σ wᵢ xᵢ(t) = separation vector: vertex–face `[1, −b₀, −b₁, −b₂]`,
    /// edge–edge `[1 − s, s, −(1 − u), −u]`.
    pub w: [Real; 4],
    /// Unit contact normal at `t`, with n · Σ wᵢ xᵢ(0) ≥ 0 (from the second primitive toward the
    /// first at the start of the step).
    pub n: Vec3,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    VertexFace,
    EdgeEdge,
}

/// Vertex–face CCD; points ordered `[p, a, b, c]`, `x0` at the start of the step, `x1` at the end.
pub fn vertex_face_ccd(x0: &[Vec3; 4], x1: &[Vec3; 4], tol: Real) -> Option<Impact> {
    ccd(Kind::VertexFace, x0, x1, tol)
}

/// Edge–edge CCD; points ordered `[a0, a1, b0, b1]` (edges a0–a1 and b0–b1).
pub fn edge_edge_ccd(x0: &[Vec3; 4], x1: &[Vec3; 4], tol: Real) -> Option<Impact> {
    ccd(Kind::EdgeEdge, x0, x1, tol)
}

/// Coefficients `[c0, c1, c2, c3]` of f(t) = Σ cₖ tᵏ = (x₁ − x₀) × (x₂ − x₀) · (x₃ − x₀).
pub fn coplanarity_cubic(x0: &[Vec3; 4], x1: &[Vec3; 4]) -> [Real; 4] {
    // Relative to point 0: pᵢ(t) = aᵢ + t bᵢ.
    let a = [1, 2, 3].map(|i| x0[i] - x0[0]);
    let b = [1, 2, 3].map(|i| (x1[i] - x0[i]) - (x1[0] - x0[0]));
    let t = |u: &Vec3, v: &Vec3, w: &Vec3| u.cross(v).dot(w);
    [
        t(&a[0], &a[1], &a[2]),
        t(&b[0], &a[1], &a[2]) + t(&a[0], &b[1], &a[2]) + t(&a[0], &a[1], &b[2]),
        t(&b[0], &b[1], &a[2]) + t(&b[0], &a[1], &b[2]) + t(&a[0], &b[1], &b[2]),
        t(&b[0], &b[1], &b[2]),
    ]
}

/// Roots in [0, 1] of c0 + c1 t + c2 t² + c3 t³, increasing. Double roots (a critical point
/// where |f| is within rounding of zero) are included; an identically zero cubic has none.
pub fn cubic_roots_unit(c: &[Real; 4]) -> Vec<Real> {
    if c.iter().all(|&v| v == 0.0) {
        return Vec::new();
    }
    let f = |t: Real| c[0] + t * (c[1] + t * (c[2] + t * c[3]));
    let crit = critical_points(c);
    let mut out = Times::default();
    monotone_roots(&f, &crit, &mut out);
    let bound = 8.0 * Real::EPSILON * c.iter().map(|v| v.abs()).sum::<Real>();
    for &t in crit.as_slice() {
        if f(t).abs() <= bound && bound > 0.0 {
            out.push(t);
        }
    }
    out.sorted().to_vec()
}

/// A few candidate times in [0, 1] (at most 3 roots + 2 critical points + 2 ends + 12 in-plane).
#[derive(Clone, Copy, Debug, Default)]
struct Times {
    t: [Real; 24],
    len: usize,
}

impl Times {
    fn push(&mut self, t: Real) {
        if (0.0..=1.0).contains(&t) && self.len < self.t.len() {
            self.t[self.len] = t;
            self.len += 1;
        }
    }
    fn as_slice(&self) -> &[Real] {
        &self.t[..self.len]
    }
    /// Sorted, with exact duplicates removed.
    fn sorted(mut self) -> Self {
        let s = &mut self.t[..self.len];
        s.sort_by(Real::total_cmp);
        let mut n = 0;
        for i in 0..self.len {
            if n == 0 || self.t[i] != self.t[n - 1] {
                self.t[n] = self.t[i];
                n += 1;
            }
        }
        self.len = n;
        self
    }
    fn to_vec(self) -> Vec<Real> {
        self.as_slice().to_vec()
    }
}

/// Real roots of A t² + B t + C in [0, 1] (stable form, Press et al. §5.6). A negative
/// discriminant still yields the vertex −B / 2A, which callers use as a near-double root.
fn quadratic_roots_unit(a: Real, b: Real, c: Real, out: &mut Times) {
    if a == 0.0 {
        if b != 0.0 {
            out.push(-c / b);
        }
        return;
    }
    let disc = b * b - 4.0 * a * c;
    if disc <= 0.0 {
        out.push(-b / (2.0 * a));
        return;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    out.push(q / a); // non-finite values fail the range check in `push`
    if q != 0.0 {
        out.push(c / q);
    }
}

/// Critical points of the cubic (roots of 3c₃t² + 2c₂t + c₁) strictly inside (0, 1), sorted.
fn critical_points(c: &[Real; 4]) -> Times {
    let mut crit = Times::default();
    quadratic_roots_unit(3.0 * c[3], 2.0 * c[2], c[1], &mut crit);
    let mut inner = Times::default();
    for &t in crit.sorted().as_slice() {
        if t > 0.0 && t < 1.0 {
            inner.push(t);
        }
    }
    inner
}

/// Roots of `f` on [0, 1], given sorted interior `breaks` between which `f` is monotone.
fn monotone_roots(f: &impl Fn(Real) -> Real, breaks: &Times, out: &mut Times) {
    let mut l = 0.0;
    let mut fl = f(l);
    let ends = breaks.as_slice().iter().copied().chain(std::iter::once(1.0));
    for r in ends {
        let fr = f(r);
        if fl == 0.0 {
            out.push(l);
        } else if fl * fr < 0.0 {
            out.push(bracketed_root(f, l, r, fl, fr));
        }
        (l, fl) = (r, fr);
    }
    if fl == 0.0 {
        out.push(1.0);
    }
}

/// Root in [l, r] with f(l)·f(r) < 0: Illinois false position interleaved with bisection, so
/// the bracket at least halves every two steps.
fn bracketed_root(f: &impl Fn(Real) -> Real, mut l: Real, mut r: Real, mut fl: Real, mut fr: Real) -> Real {
    let mut side = 0i8;
    for it in 0..160 {
        if r - l <= 2.0 * Real::EPSILON * r.abs().max(1e-300) {
            break;
        }
        let mut m = (l * fr - r * fl) / (fr - fl);
        if it % 2 == 1 || !(m > l && m < r) {
            m = 0.5 * (l + r);
        }
        let fm = f(m);
        if fm == 0.0 {
            return m;
        }
        if (fm < 0.0) == (fr < 0.0) {
            (r, fr) = (m, fm);
            if side == 1 {
                fl *= 0.5;
            }
            side = 1;
        } else {
            (l, fl) = (m, fm);
            if side == -1 {
                fr *= 0.5;
            }
            side = -1;
        }
    }
    0.5 * (l + r)
}

fn lerp(x0: &[Vec3; 4], x1: &[Vec3; 4], t: Real) -> [Vec3; 4] {
    std::array::from_fn(|i| x0[i] + (x1[i] - x0[i]) * t)
}

/// The normal of the primitive's plane and |f|'s magnitude bound: f = N · d for
/// vertex–face N = (b − a) × (c − a), d = p − a; edge–edge N = eₐ × e_b, d = b₀ − a₀.
fn plane_factors(kind: Kind, x: &[Vec3; 4]) -> (Vec3, Real) {
    let (u, v, d) = match kind {
        Kind::VertexFace => (x[2] - x[1], x[3] - x[1], x[0] - x[1]),
        Kind::EdgeEdge => (x[1] - x[0], x[3] - x[2], x[2] - x[0]),
    };
    (u.cross(&v), u.norm() * v.norm() * d.norm())
}

fn ccd(kind: Kind, x0: &[Vec3; 4], x1: &[Vec3; 4], tol: Real) -> Option<Impact> {
    if apart_throughout(kind, x0, x1, tol) {
        return None;
    }
    exact_ccd(kind, x0, x1, tol)
}

/// Whether the primitives stay farther apart than `tol` over the whole step, so that no candidate
/// time can be an impact (`impact_at` wants a distance within `tol`): a lower bound on their
/// distance. Distance is unchanged by a common translation, so every motion is taken relative
/// to point 0's; a point of a primitive (a convex combination of its corners) then moves by at
/// most its corners' largest relative displacement, and the distance
/// d(t) ≥ d(0) − t (reach of the first primitive + reach of the second). d(0) is the
/// closest-point distance (Ericson 2005), trusted to a millionth of the configuration's size,
/// orders of magnitude beyond its rounding. Most pairs the broad phase passes (cloth resting a
/// thickness away from a body and moving with it) are decided here, without the cubic.
fn apart_throughout(kind: Kind, x0: &[Vec3; 4], x1: &[Vec3; 4], tol: Real) -> bool {
    let rel: [Real; 4] = std::array::from_fn(|i| ((x1[i] - x0[i]) - (x1[0] - x0[0])).norm());
    let (reach, d0) = match kind {
        Kind::VertexFace => {
            (rel[1].max(rel[2]).max(rel[3]), closest_point_triangle(&x0[0], &x0[1], &x0[2], &x0[3]).dist)
        }
        Kind::EdgeEdge => (rel[1] + rel[2].max(rel[3]), closest_segments(&x0[0], &x0[1], &x0[2], &x0[3]).dist),
    };
    let size = (1..4).map(|i| (x0[i] - x0[0]).norm()).fold(0.0, Real::max) + reach;
    d0 - reach > tol + 1e-6 * size
}

/// The CCD itself (module doc), without `apart_throughout`'s shortcut.
fn exact_ccd(kind: Kind, x0: &[Vec3; 4], x1: &[Vec3; 4], tol: Real) -> Option<Impact> {
    let volume = |t: Real| {
        let x = lerp(x0, x1, t);
        orient3d(&x[0], &x[1], &x[2], &x[3])
    };
    // Necessary for a distance ≤ tol: |f| ≤ tol |N| (distance ≥ |f| / |N|), plus rounding slack.
    let near = |t: Real| {
        let (n, bound) = plane_factors(kind, &lerp(x0, x1, t));
        volume(t).abs() <= tol * n.norm() + 1e-12 * bound
    };
    let crit = critical_points(&coplanarity_cubic(x0, x1));
    let mut cand = Times::default();
    monotone_roots(&volume, &crit, &mut cand);
    let mut coplanar = near(0.0);
    for &t in crit.as_slice() {
        if near(t) {
            cand.push(t); // near-double root: tangential approach without a sign change
        } else {
            coplanar = false;
        }
    }
    if near(1.0) {
        cand.push(1.0);
    } else {
        coplanar = false;
    }
    if coplanar {
        // |f| peaks at an end or a critical point, so the motion stays coplanar throughout.
        cand.push(0.0);
        in_plane_crossings(kind, x0, x1, &mut cand);
    }
    cand.sorted().as_slice().iter().find_map(|&t| impact_at(kind, x0, x1, t, tol))
}

/// For coplanar motion: times at which a vertex crosses the line of an edge, from the
/// quadratics n̂ · ((v − u) × (q − u)) with the plane normal n̂ frozen at the start.
fn in_plane_crossings(kind: Kind, x0: &[Vec3; 4], x1: &[Vec3; 4], out: &mut Times) {
    let (n0, _) = plane_factors(kind, x0);
    let (n1, _) = plane_factors(kind, x1);
    let n = match kind {
        Kind::VertexFace => {
            if n0.norm() >= n1.norm() {
                n0
            } else {
                n1
            }
        }
        // Edges are often parallel here; the plane through edge a and b's endpoints is safer.
        Kind::EdgeEdge => [n0, (x0[1] - x0[0]).cross(&(x0[2] - x0[0])), (x0[1] - x0[0]).cross(&(x0[3] - x0[0]))]
            .into_iter()
            .max_by(|a, b| a.norm().total_cmp(&b.norm()))
            .expect("non-empty"),
    };
    let n = n.try_normalize(0.0).unwrap_or_else(|| any_perpendicular(&(x0[1] - x0[0])));
    // (edge u → v, vertex q) triples.
    let triples: &[(usize, usize, usize)] = match kind {
        Kind::VertexFace => &[(1, 2, 0), (2, 3, 0), (3, 1, 0)],
        Kind::EdgeEdge => &[(0, 1, 2), (0, 1, 3), (2, 3, 0), (2, 3, 1)],
    };
    for &(u, v, q) in triples {
        let (a0, a1) = (x0[v] - x0[u], (x1[v] - x1[u]) - (x0[v] - x0[u]));
        let (b0, b1) = (x0[q] - x0[u], (x1[q] - x1[u]) - (x0[q] - x0[u]));
        let (c0, c1, c2) = (n.dot(&a0.cross(&b0)), n.dot(&(a0.cross(&b1) + a1.cross(&b0))), n.dot(&a1.cross(&b1)));
        quadratic_roots_unit(c2, c1, c0, out);
        if c2 != 0.0 {
            out.push(-c1 / (2.0 * c2)); // tangential crossing
        }
    }
}

/// The impact at time `t` if the primitives are within `tol` there.
fn impact_at(kind: Kind, x0: &[Vec3; 4], x1: &[Vec3; 4], t: Real, tol: Real) -> Option<Impact> {
    let x = lerp(x0, x1, t);
    let (w, n) = match kind {
        Kind::VertexFace => {
            let cl = closest_point_triangle(&x[0], &x[1], &x[2], &x[3]);
            if cl.dist > tol {
                return None;
            }
            ([1.0, -cl.bary[0], -cl.bary[1], -cl.bary[2]], cl.normal)
        }
        Kind::EdgeEdge => {
            let sc = closest_segments(&x[0], &x[1], &x[2], &x[3]);
            if sc.dist > tol {
                return None;
            }
            let w = [1.0 - sc.s, sc.s, -(1.0 - sc.t), -sc.t];
            (w, edge_normal(&x, x0, &w))
        }
    };
    Some(Impact { t, w, n: orient_normal(n, x0, x1, &w) })
}

/// Edge–edge normal eₐ × e_b; for (nearly) parallel edges, the start separation made
/// perpendicular to edge a.
fn edge_normal(x: &[Vec3; 4], x0: &[Vec3; 4], w: &[Real; 4]) -> Vec3 {
    let (ea, eb) = (x[1] - x[0], x[3] - x[2]);
    let c = ea.cross(&eb);
    if c.norm() > 1e-6 * ea.norm() * eb.norm() {
        return c.normalize();
    }
    let sep = weighted(x0, w);
    let ahat = ea.try_normalize(0.0).unwrap_or_else(Vec3::zeros);
    (sep - ahat * ahat.dot(&sep)).try_normalize(0.0).unwrap_or_else(|| any_perpendicular(&ea))
}

fn weighted(x: &[Vec3; 4], w: &[Real; 4]) -> Vec3 {
    x.iter().zip(w).map(|(x, w)| x * *w).sum()
}

/// Orient `n` so that n · Σ wᵢ xᵢ(0) ≥ 0; primitives already touching at the start use the
/// relative motion instead (n against the approach).
fn orient_normal(n: Vec3, x0: &[Vec3; 4], x1: &[Vec3; 4], w: &[Real; 4]) -> Vec3 {
    let scale = x0.iter().map(|x| (x - x0[0]).norm()).fold(0.0, Real::max);
    let s0 = n.dot(&weighted(x0, w));
    let flip = if s0.abs() > 1e-12 * scale {
        s0 < 0.0
    } else {
        let dx: [Vec3; 4] = std::array::from_fn(|i| x1[i] - x0[i]);
        n.dot(&weighted(&dx, w)) > 0.0
    };
    if flip {
        -n
    } else {
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::geometry::closest_point_triangle;
    use crate::math::test_rng::Rng;

    fn v(x: Real, y: Real, z: Real) -> Vec3 {
        Vec3::new(x, y, z)
    }

    const TRI: [Vec3; 3] = [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(2.0, -1.0, 0.0), Vec3::new(-1.0, 2.0, 0.0)];

    /// A moving point against the static triangle `TRI`.
    fn point_vs_tri(p0: Vec3, p1: Vec3) -> Option<Impact> {
        let x0 = [p0, TRI[0], TRI[1], TRI[2]];
        let x1 = [p1, TRI[0], TRI[1], TRI[2]];
        vertex_face_ccd(&x0, &x1, CCD_TOLERANCE)
    }

    fn assert_roots(c: [Real; 4], want: &[Real], tol: Real) {
        let got = cubic_roots_unit(&c);
        assert_eq!(got.len(), want.len(), "{c:?}: {got:?} vs {want:?}");
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= tol, "{c:?}: {got:?} vs {want:?}");
        }
    }

    /// Coefficients of k (t − r₀)(t − r₁)(t − r₂).
    fn from_roots(k: Real, r: [Real; 3]) -> [Real; 4] {
        let s1 = r[0] + r[1] + r[2];
        let s2 = r[0] * r[1] + r[1] * r[2] + r[0] * r[2];
        [-k * r[0] * r[1] * r[2], k * s2, -k * s1, k]
    }

    #[test]
    fn cubic_roots() {
        assert_roots(from_roots(1.0, [0.1, 0.5, 0.9]), &[0.1, 0.5, 0.9], 1e-14);
        assert_roots(from_roots(-3.0, [-0.5, 0.25, 2.0]), &[0.25], 1e-14);
        assert_roots(from_roots(1.0, [0.0, 1.0, 7.0]), &[0.0, 1.0], 1e-14);
        // Double and triple roots (no sign change at the double root).
        assert_roots(from_roots(1.0, [0.5, 0.5, -1.0]), &[0.5], 1e-12);
        assert_roots(from_roots(2.0, [0.5, 0.5, 0.5]), &[0.5], 1e-12);
        // Roots 1e-4 apart are resolved; 1e-9 apart is below what an expanded cubic holds in
        // double precision (|f| ~ 1e-18 between them), so only "near 0.3" can be asked.
        assert_roots(from_roots(1.0, [0.3, 0.3 + 1e-4, 5.0]), &[0.3, 0.3 + 1e-4], 1e-11);
        let close = cubic_roots_unit(&from_roots(1.0, [0.3, 0.3 + 1e-9, 5.0]));
        assert!(!close.is_empty() && close.iter().all(|t| (t - 0.3).abs() < 1e-7), "{close:?}");
        // Degree drops: tiny or zero leading coefficients.
        assert_roots([-0.4, 1.0, 0.0, 1e-18], &[0.4], 1e-15);
        assert_roots([0.06, -0.5, 1.0, 0.0], &[0.2, 0.3], 1e-15);
        assert_roots([0.06, -0.5, 1.0, 1e-17], &[0.2, 0.3], 1e-15);
        assert_roots([-0.7, 1.0, 0.0, 0.0], &[0.7], 1e-15);
        assert_roots([1.0, 0.0, 0.0, 0.0], &[], 0.0);
        assert_roots([0.0; 4], &[], 0.0);
        // Badly scaled: tiny motions give tiny coefficients.
        assert_roots(from_roots(1e-30, [0.1, 0.5, 0.9]), &[0.1, 0.5, 0.9], 1e-14);
    }

    /// Issue 3: a point at 20 m/s passes straight through a triangle within one step.
    #[test]
    fn fast_point_through_triangle() {
        for h in [0.005, 0.04] {
            let d = 20.0 * h;
            let p0 = v(0.2, 0.1, 0.3 * d);
            let hit = point_vs_tri(p0, p0 - v(0.0, 0.0, d)).expect("tunnelling point missed");
            assert!((hit.t - 0.3).abs() < 1e-12, "t = {}", hit.t);
            assert!((hit.n - v(0.0, 0.0, 1.0)).norm() < 1e-12);
            let sep: Vec3 = [p0, TRI[0], TRI[1], TRI[2]].iter().zip(&hit.w).map(|(x, w)| x * *w).sum();
            assert!((sep - v(0.0, 0.0, 0.3 * d)).norm() < 1e-12, "w = {:?}", hit.w);
        }
        // From below: the normal points down, toward the point's start side.
        let hit = point_vs_tri(v(0.0, 0.0, -0.1), v(0.0, 0.0, 0.3)).unwrap();
        assert!((hit.t - 0.25).abs() < 1e-12 && (hit.n - v(0.0, 0.0, -1.0)).norm() < 1e-12);
    }

    #[test]
    fn grazing_and_parallel_misses() {
        // Through the plane 1e-4 outside the edge x = −1: a miss; 1e-4 inside: a hit.
        assert!(point_vs_tri(v(-1.0001, 0.0, 0.1), v(-1.0001, 0.0, -0.1)).is_none());
        let hit = point_vs_tri(v(-0.9999, 0.0, 0.1), v(-0.9999, 0.0, -0.1)).unwrap();
        assert!((hit.t - 0.5).abs() < 1e-12);
        // Parallel to the face at 1 mm: no contact; stopping short of it: none either.
        assert!(point_vs_tri(v(-3.0, 0.0, 1e-3), v(3.0, 0.0, 1e-3)).is_none());
        assert!(point_vs_tri(v(0.0, 0.0, 1e-2), v(0.0, 0.0, 1e-5)).is_none());
        // Ending exactly on the face counts (t = 1).
        let hit = point_vs_tri(v(0.0, 0.0, 1e-2), v(0.0, 0.0, 0.0)).unwrap();
        assert_eq!(hit.t, 1.0);
    }

    #[test]
    fn coplanar_motion() {
        // In the face's plane, entering across the edge x = −1 at t = 0.25.
        let hit = point_vs_tri(v(-2.0, 0.0, 0.0), v(2.0, 0.0, 0.0)).unwrap();
        assert!((hit.t - 0.25).abs() < 1e-12, "t = {}", hit.t);
        // Gliding within the tolerance above the plane: the same.
        let hit = point_vs_tri(v(-2.0, 0.0, 5e-7), v(2.0, 0.0, 5e-7)).unwrap();
        assert!((hit.t - 0.25).abs() < 1e-12);
        // Coplanar and already inside: t = 0; coplanar and beside the face: a miss.
        assert_eq!(point_vs_tri(v(0.0, 0.0, 0.0), v(0.1, 0.0, 0.0)).unwrap().t, 0.0);
        assert!(point_vs_tri(v(-2.0, -2.0, 0.0), v(3.0, -2.0, 0.0)).is_none());
        // Nothing moves at all.
        assert!(point_vs_tri(v(0.0, 0.0, 0.1), v(0.0, 0.0, 0.1)).is_none());
    }

    #[test]
    fn tiny_motions() {
        // 4 µm of travel through the face.
        let hit = point_vs_tri(v(0.0, 0.0, 2e-6), v(0.0, 0.0, -2e-6)).unwrap();
        assert!((hit.t - 0.5).abs() < 1e-9);
        assert!(point_vs_tri(v(0.0, 0.0, 1e-3), v(0.0, 0.0, 1e-3 - 1e-12)).is_none());
        // Within the tolerance of the face for the whole step: touching from the start.
        assert_eq!(point_vs_tri(v(0.0, 0.0, 1e-10), v(0.0, 0.0, -1e-10)).unwrap().t, 0.0);
        // A tiny world (0.1 mm triangle) moving 10 nm needs a tolerance to match.
        let s = 1e-4;
        let (a, b, c) = (TRI[0] * s, TRI[1] * s, TRI[2] * s);
        let (p0, p1) = (v(0.0, 0.0, 3e-8), v(0.0, 0.0, -7e-8));
        let hit = vertex_face_ccd(&[p0, a, b, c], &[p1, a, b, c], 1e-12).unwrap();
        assert!((hit.t - 0.3).abs() < 1e-9, "t = {}", hit.t);
    }

    /// A triangle translating with the point (cubic and quadratic terms vanish up to 1e-13)
    /// while it tilts slightly: the root must still be found accurately.
    #[test]
    fn near_degenerate_cubic() {
        let vel = v(0.3, -0.2, 1.0);
        let x0 = [v(0.1, 0.1, 0.2), TRI[0], TRI[1], TRI[2]];
        let mut x1 = x0.map(|x| x + vel);
        x1[0] -= v(0.0, 0.0, 0.4); // the point gains 0.4 on the face: contact at t = 0.5
        x1[3] += v(1e-13, 0.0, 0.0);
        let c = coplanarity_cubic(&x0, &x1);
        assert!(c[3].abs() < 1e-12 && c[1].abs() > 0.1, "{c:?}");
        let hit = vertex_face_ccd(&x0, &x1, CCD_TOLERANCE).unwrap();
        assert!((hit.t - 0.5).abs() < 1e-12, "t = {}", hit.t);
    }

    #[test]
    fn edges_crossing() {
        // Edge a along x at z = 0.1 drops to z = −0.1 through edge b along y at z = 0.
        let b = [v(0.0, -1.0, 0.0), v(0.0, 1.0, 0.0)];
        let x0 = [v(-1.0, 0.5, 0.1), v(1.0, 0.5, 0.1), b[0], b[1]];
        let x1 = [v(-1.0, 0.5, -0.1), v(1.0, 0.5, -0.1), b[0], b[1]];
        let hit = edge_edge_ccd(&x0, &x1, CCD_TOLERANCE).unwrap();
        assert!((hit.t - 0.5).abs() < 1e-12);
        let want = [0.5, 0.5, -0.25, -0.75];
        assert!(hit.w.iter().zip(want).all(|(w, e)| (w - e).abs() < 1e-12), "{:?}", hit.w);
        assert!((hit.n - v(0.0, 0.0, 1.0)).norm() < 1e-12);
        // Shifted past b's end: the lines meet, the segments do not.
        let shift = |x: [Vec3; 4]| [x[0], x[1], x[2] + v(0.0, 1.6, 0.0), x[3] + v(0.0, 1.6, 0.0)];
        assert!(edge_edge_ccd(&shift(x0), &shift(x1), CCD_TOLERANCE).is_none());
    }

    #[test]
    fn parallel_edges() {
        // Coplanar and parallel all step long (the cubic vanishes identically): contact at 0.5.
        let x0 = [v(0.0, 0.1, 0.0), v(1.0, 0.1, 0.0), v(0.5, 0.0, 0.0), v(1.5, 0.0, 0.0)];
        let x1 = [v(0.0, -0.1, 0.0), v(1.0, -0.1, 0.0), x0[2], x0[3]];
        let hit = edge_edge_ccd(&x0, &x1, CCD_TOLERANCE).unwrap();
        assert!((hit.t - 0.5).abs() < 1e-12, "t = {}", hit.t);
        assert!((hit.n - v(0.0, 1.0, 0.0)).norm() < 1e-12, "n = {}", hit.n);
        // Parallel in different planes passing each other: no contact.
        let lift = |x: [Vec3; 4]| [x[0] + v(0.0, 0.0, 0.01), x[1] + v(0.0, 0.0, 0.01), x[2], x[3]];
        assert!(edge_edge_ccd(&lift(x0), &lift(x1), CCD_TOLERANCE).is_none());
    }

    /// Reference by dense sampling of the directly evaluated signed volume: bracket each sign
    /// change, bisect, and keep the first root where the primitives touch.
    fn reference(kind: Kind, x0: &[Vec3; 4], x1: &[Vec3; 4]) -> Option<Real> {
        let f = |t: Real| {
            let x = lerp(x0, x1, t);
            orient3d(&x[0], &x[1], &x[2], &x[3])
        };
        let n = 4096;
        (0..n).find_map(|i| {
            let (mut l, mut r) = (i as Real / n as Real, (i + 1) as Real / n as Real);
            if f(l) * f(r) > 0.0 {
                return None;
            }
            for _ in 0..80 {
                let m = 0.5 * (l + r);
                if f(l) * f(m) <= 0.0 {
                    r = m
                } else {
                    l = m
                }
            }
            impact_at(kind, x0, x1, l, CCD_TOLERANCE).map(|_| l)
        })
    }

    /// Random motions: the point (or edge a) starts at height `z0` and drops by `drop` (plus a
    /// random fraction of `spread`) through a random face (or edge b) of thickness `zb`; every
    /// node also moves by a `shared` translation and its own `noise`. Checks each impact's
    /// invariants and its agreement with `reference`; returns the number of impacts.
    fn random_cases(seed: u64, z0: Real, zb: Real, drop: (Real, Real), shared: Real, noise: Real) -> usize {
        let mut rng = Rng(seed);
        let (mut hits, mut mismatches) = (0, 0);
        for i in 0..3000 {
            let kind = [Kind::VertexFace, Kind::EdgeEdge][i % 2];
            let first = |k: usize| k == 0 || (k == 1 && kind == Kind::EdgeEdge);
            let x0: [Vec3; 4] = std::array::from_fn(|k| {
                let r = rng.vec();
                let (xy, z) = if first(k) { (0.5, z0) } else { (1.0, 0.0) };
                v(xy * r.x, xy * r.y, z + if first(k) { 0.5 } else { zb } * r.z)
            });
            let (t, d) = (rng.vec() * shared, drop.0 + drop.1 * rng.uniform());
            let x1: [Vec3; 4] =
                std::array::from_fn(|k| x0[k] + t + rng.vec() * noise - v(0.0, 0.0, if first(k) { d } else { 0.0 }));
            let got = ccd(kind, &x0, &x1, CCD_TOLERANCE);
            if let Some(hit) = got {
                hits += 1;
                let x = lerp(&x0, &x1, hit.t);
                assert!(weighted(&x, &hit.w).norm() <= CCD_TOLERANCE, "case {i}: apart at t");
                assert!(hit.n.dot(&weighted(&x0, &hit.w)) >= 0.0 && (hit.n.norm() - 1.0).abs() < 1e-12);
                if kind == Kind::VertexFace {
                    let cl = closest_point_triangle(&x[0], &x[1], &x[2], &x[3]);
                    assert!(cl.normal.cross(&hit.n).norm() < 1e-9, "normal is the face's");
                }
            }
            match (got, reference(kind, &x0, &x1)) {
                (Some(g), Some(w)) if (g.t - w).abs() < 1e-9 => {}
                (None, None) => {}
                _ => mismatches += 1,
            }
        }
        assert_eq!(mismatches, 0, "{mismatches} disagreements with sampling ({hits} impacts)");
        hits
    }

    /// The distance bound skips only pairs the exact CCD finds no impact for: random pairs
    /// near a thickness apart, moving together plus a relative motion of the same size (some
    /// closing through each other), far from the origin and nearly parallel too.
    #[test]
    fn the_distance_bound_skips_only_pairs_without_an_impact() {
        let mut rng = Rng(17);
        let (mut skipped, mut hits) = (0, 0);
        for i in 0..20_000 {
            let kind = [Kind::VertexFace, Kind::EdgeEdge][i % 2];
            let origin = v(100.0 * rng.uniform(), -30.0, 7.0) * if i % 3 == 0 { 1.0 } else { 0.0 };
            let gap = 5e-3 * rng.uniform();
            let first = |k: usize| k == 0 || (k == 1 && kind == Kind::EdgeEdge);
            let flat = i % 5 == 0; // nearly parallel edges, a point near the face's plane
            let x0: [Vec3; 4] = std::array::from_fn(|k| {
                let r = rng.vec();
                let z = if first(k) { gap } else { 0.0 };
                let tilt = if flat { 1e-9 } else { 0.02 };
                origin + v(0.05 * r.x, 0.05 * r.y, z + tilt * r.z)
            });
            let shared = rng.vec() * 0.01;
            let close = v(0.0, 0.0, -(0.5 + 2.0 * rng.uniform()) * gap);
            let x1: [Vec3; 4] = std::array::from_fn(|k| {
                x0[k] + shared + rng.vec() * 1e-3 + if first(k) { close } else { Vec3::zeros() }
            });
            let exact = exact_ccd(kind, &x0, &x1, CCD_TOLERANCE);
            if apart_throughout(kind, &x0, &x1, CCD_TOLERANCE) {
                skipped += 1;
                assert_eq!(exact, None, "case {i}: skipped a pair with an impact");
            }
            assert_eq!(ccd(kind, &x0, &x1, CCD_TOLERANCE), exact, "case {i}");
            hits += usize::from(exact.is_some());
        }
        assert!(skipped > 5_000 && hits > 500, "{skipped} skipped, {hits} impacts: the test is too easy");
    }

    #[test]
    fn random_against_sampling() {
        let hits = random_cases(42, 1.0, 0.3, (2.0, 0.0), 0.0, 0.3);
        assert!(hits > 400, "only {hits} impacts: the test is too easy");
    }

    /// Near-degenerate cubics: a shared translation with 1e-9 noise, so only the dropping
    /// primitive's motion is relative and the t³ (and t²) terms nearly vanish.
    #[test]
    fn random_near_degenerate_against_sampling() {
        let hits = random_cases(9, 0.2, 0.1, (0.3, 1.0), 3.0, 1e-9);
        assert!(hits > 200, "only {hits} impacts: the test is too easy");
    }
}
