//! The tensor max of 2×2 metrics (Narain, Samii & O'Brien 2012, §3.4; ARCSim's `tensor_max`):
//! the smallest metric M with M ⪰ Mᵢ for every i.
//!
//! A symmetric 2×2 matrix M is a disk in the plane: centre c = ((M₀₀ − M₁₁)/2, M₀₁), radius
//! r = (M₀₀ + M₁₁)/2 (its eigenvalues are r ± |c|). A − B is PSD exactly when B's disk lies in
//! A's, so the tensor max is the smallest disk enclosing all the disks: determined by one, two
//! or three of them (the last case an Apollonius problem).

use crate::math::{Mat2, Real, Vec2};

#[derive(Clone, Copy, Debug, PartialEq)]
struct Disk {
    c: Vec2,
    r: Real,
}

fn to_disk(m: &Mat2) -> Disk {
    let off = 0.5 * (m[(0, 1)] + m[(1, 0)]);
    Disk { c: Vec2::new(0.5 * (m[(0, 0)] - m[(1, 1)]), off), r: 0.5 * (m[(0, 0)] + m[(1, 1)]) }
}

fn to_mat(d: &Disk) -> Mat2 {
    Mat2::new(d.r + d.c.x, d.c.y, d.c.y, d.r - d.c.x)
}

fn encloses(outer: &Disk, inner: &Disk, tol: Real) -> bool {
    (outer.c - inner.c).norm() + inner.r <= outer.r + tol
}

fn enclosing_two(a: &Disk, b: &Disk) -> Disk {
    let d = (b.c - a.c).norm();
    if d + b.r <= a.r {
        return *a;
    }
    if d + a.r <= b.r {
        return *b;
    }
    let r = 0.5 * (d + a.r + b.r);
    let c = a.c + (b.c - a.c) * ((r - a.r) / d);
    Disk { c, r }
}

/// The disk internally tangent to three disks: |c − cᵢ| = r − rᵢ. Subtracting the equations
/// pairwise gives c as a linear function of r; the first equation is then a quadratic in r.
fn enclosing_three(d: [&Disk; 3]) -> Option<Disk> {
    let (c1, r1) = (d[0].c, d[0].r);
    // Rows: 2(cᵢ − c₁)·c − 2(rᵢ − r₁) r = |cᵢ|² − |c₁|² − rᵢ² + r₁².
    let a = Mat2::from_rows(&[(2.0 * (d[1].c - c1)).transpose(), (2.0 * (d[2].c - c1)).transpose()]);
    let inv = a.try_inverse()?;
    let k = Vec2::new(
        d[1].c.norm_squared() - c1.norm_squared() - d[1].r * d[1].r + r1 * r1,
        d[2].c.norm_squared() - c1.norm_squared() - d[2].r * d[2].r + r1 * r1,
    );
    let g = Vec2::new(2.0 * (d[1].r - r1), 2.0 * (d[2].r - r1));
    // c = p + q r
    let (p, q) = (inv * k, inv * g);
    // |p + q r − c₁|² = (r − r₁)²
    let w = p - c1;
    let (qa, qb, qc) = (q.norm_squared() - 1.0, 2.0 * (w.dot(&q) + r1), w.norm_squared() - r1 * r1);
    let roots: Vec<Real> = if qa.abs() < 1e-14 {
        if qb == 0.0 {
            return None;
        }
        vec![-qc / qb]
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        vec![(-qb - s) / (2.0 * qa), (-qb + s) / (2.0 * qa)]
    };
    let rmax = d.iter().map(|x| x.r).fold(Real::NEG_INFINITY, Real::max);
    roots
        .into_iter()
        .filter(|&r| r >= rmax - 1e-12 * rmax.abs().max(1.0))
        .map(|r| Disk { c: p + q * r, r })
        .min_by(|a, b| a.r.total_cmp(&b.r))
}

/// The smallest metric that dominates every metric in `ms` (all symmetric).
pub fn tensor_max(ms: &[Mat2]) -> Mat2 {
    let disks: Vec<Disk> = ms.iter().map(to_disk).collect();
    let Some(first) = disks.first() else { return Mat2::zeros() };
    let scale = disks.iter().map(|d| d.r.abs() + d.c.norm()).fold(0.0, Real::max);
    let tol = 1e-12 * scale.max(1e-300);
    let all = |cand: &Disk| disks.iter().all(|d| encloses(cand, d, tol));
    let consider = |best: &mut Option<Disk>, cand: Disk| {
        if all(&cand) && best.is_none_or(|b| cand.r < b.r) {
            *best = Some(cand);
        }
    };
    let mut best: Option<Disk> = None;
    for a in &disks {
        consider(&mut best, *a);
    }
    for i in 0..disks.len() {
        for j in i + 1..disks.len() {
            consider(&mut best, enclosing_two(&disks[i], &disks[j]));
        }
    }
    if best.is_none() {
        for i in 0..disks.len() {
            for j in i + 1..disks.len() {
                for k in j + 1..disks.len() {
                    if let Some(d) = enclosing_three([&disks[i], &disks[j], &disks[k]]) {
                        consider(&mut best, d);
                    }
                }
            }
        }
    }
    // Fallback (numerically degenerate triples): the largest disk grown to enclose the rest.
    let d = best.unwrap_or_else(|| {
        let mut d = *first;
        for x in &disks {
            d.r = d.r.max((x.c - d.c).norm() + x.r);
        }
        d
    });
    to_mat(&d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::eigen_sym2;
    use crate::math::test_rng::Rng;

    fn psd(m: &Mat2) -> bool {
        eigen_sym2(m).0[0] >= -1e-9 * (1.0 + m.norm())
    }

    #[test]
    fn dominates_inputs_and_is_exact_for_comparable_ones() {
        let a = Mat2::new(4.0, 0.0, 0.0, 1.0);
        let b = Mat2::new(1.0, 0.0, 0.0, 4.0);
        let m = tensor_max(&[a, b]);
        assert!(psd(&(m - a)) && psd(&(m - b)));
        // Diagonal case: the smallest dominating metric is isotropic 4 (disks (1.5,0) r 2.5 and
        // (−1.5,0) r 2.5 → centre 0, radius 4).
        assert!((m - Mat2::new(4.0, 0.0, 0.0, 4.0)).norm() < 1e-12);
        let small = Mat2::new(0.5, 0.1, 0.1, 0.3);
        assert_eq!(tensor_max(&[a, small]), a);
    }

    #[test]
    fn random_sets_dominated_minimally() {
        let mut rng = Rng(3);
        let mut rnd = || rng.uniform();
        for _ in 0..200 {
            let ms: Vec<Mat2> = (0..4)
                .map(|_| {
                    let th: f64 = rnd() * std::f64::consts::PI;
                    let (c, sn) = (th.cos(), th.sin());
                    let q = Mat2::new(c, -sn, sn, c);
                    q * Mat2::new(rnd() * 10.0, 0.0, 0.0, rnd()) * q.transpose()
                })
                .collect();
            let m = tensor_max(&ms);
            for x in &ms {
                assert!(psd(&(m - x)), "{m} vs {x}");
            }
            // Minimal: shrinking the trace by 1e-6 relative breaks domination.
            let shrunk = m - Mat2::identity() * (1e-6 * m.trace());
            assert!(ms.iter().any(|x| !psd(&(shrunk - x))));
        }
    }
}
