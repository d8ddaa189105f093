//! Scalar type and the small fixed-size linear algebra used by element kernels; rigid transforms
//! and keyframed motions (`motion`) and the spline they share with camera paths (`spline`).
//!
//! nalgebra for element-sized blocks; the global sparse system lives in `solver` (faer).

pub type Real = f64;
pub type Vec2 = nalgebra::Vector2<Real>;
pub type Vec3 = nalgebra::Vector3<Real>;
pub type Mat2 = nalgebra::Matrix2<Real>;
pub type Mat3 = nalgebra::Matrix3<Real>;
pub type Mat3x2 = nalgebra::Matrix3x2<Real>;
pub type Vec9 = nalgebra::SVector<Real, 9>;
pub type Vec12 = nalgebra::SVector<Real, 12>;
pub type Mat9 = nalgebra::SMatrix<Real, 9, 9>;
pub type Mat12 = nalgebra::SMatrix<Real, 12, 12>;

/// Fewest elements (faces, hinges, nodes) a parallel loop hands to one task. A loop over fewer
/// runs on the calling thread: waking a pool thread costs tens of microseconds, more than
/// a small mesh's whole loop (issue 17 item 4). Results do not depend on it (every parallel
/// loop combines its results in element order).
pub const PAR_GRAIN: usize = 256;

/// Eigen-decomposition of a symmetric 2×2 matrix: `(λ₀ ≤ λ₁, unit eigenvectors as columns)`.
/// Closed form, so it is cheap enough to call per face per step.
pub fn eigen_sym2(m: &Mat2) -> (Vec2, Mat2) {
    let (a, b, d) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
    let mean = 0.5 * (a + d);
    let r = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (l0, l1) = (mean - r, mean + r);
    // Eigenvector of the larger eigenvalue, picked from the better-conditioned formula.
    let v1 = if b.abs() < 1e-300 * (a.abs() + d.abs()).max(1e-300) || r == 0.0 {
        if a >= d {
            Vec2::new(1.0, 0.0)
        } else {
            Vec2::new(0.0, 1.0)
        }
    } else if a >= d {
        Vec2::new(l1 - d, b).normalize()
    } else {
        Vec2::new(b, l1 - a).normalize()
    };
    let v0 = Vec2::new(-v1.y, v1.x);
    (Vec2::new(l0, l1), Mat2::from_columns(&[v0, v1]))
}

/// The positive part of a symmetric 2×2 matrix (negative eigenvalues set to zero).
pub fn pos_part2(m: &Mat2) -> Mat2 {
    let (l, q) = eigen_sym2(m);
    let d = Mat2::from_diagonal(&Vec2::new(l[0].max(0.0), l[1].max(0.0)));
    q * d * q.transpose()
}

/// 2D cross product (signed parallelogram area).
#[inline]
pub fn cross2(a: &Vec2, b: &Vec2) -> Real {
    a.x * b.y - a.y * b.x
}

/// Bitwise equality of two point lists (a signed zero counts as a change).
pub fn same_bits(a: &[Vec3], b: &[Vec3]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(p, q)| p.iter().zip(q.iter()).all(|(x, y)| x.to_bits() == y.to_bits()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_sym2_reconstructs() {
        for m in [
            Mat2::new(2.0, 1.0, 1.0, -3.0),
            Mat2::new(1.0, 0.0, 0.0, 1.0),
            Mat2::new(0.0, 0.0, 0.0, 5.0),
            Mat2::new(1e-8, 3.0, 3.0, 1e-8),
        ] {
            let (l, q) = eigen_sym2(&m);
            let r = q * Mat2::from_diagonal(&l) * q.transpose();
            assert!((r - m).norm() < 1e-12 * (1.0 + m.norm()), "{m} vs {r}");
            assert!(l[0] <= l[1]);
        }
    }
}

pub mod dual;
pub mod motion;
pub mod spline;
#[cfg(test)]
pub(crate) mod test_rng;
