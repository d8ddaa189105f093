//! The mesh harmonics of §3.2: the lowest-frequency eigenvectors of the cotangent Laplacian,
//! K φ = λ V φ, orthonormal in the mass inner product (Φᵀ V Φ = I). Solved as the paper does,
//! through the symmetrised L = V^{-1/2} K V^{-1/2} = Q Λ Qᵀ, then Φ = V^{-1/2} Q.
//!
//! Dense: nalgebra's `SymmetricEigen` on the full N×N matrix, O(N³) time and N² memory, which
//! is seconds for N ≈ 1000 and minutes for a few thousand — once per fine mesh, reused for every
//! training set and every γ (§3.2). No sparse eigensolver (shift-invert Lanczos) is among the
//! pinned crates, and for N ≲ 5000 the dense solve is simpler and exact; beyond that the lowest
//! modes alone (Vallet & Lévy 2008) would be the way, or faer's blocked dense solver.
//!
//! V is the lumped mass normalised to mean 1 (weights sum to N): the mass-weighted norms of
//! `fit` then match the paper's unweighted Frobenius norms on a uniform mesh, so γ keeps the
//! scale of §6 (γ_1 = 1, γ_N = 10⁵). Because K·1 = 0, the constant is exactly the first mode,
//! which is what lets `fit` truncate to K modes and still have rows of U sum to one.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::{Laplacian, UpsampleError};
use crate::math::Real;

#[derive(Clone, Debug)]
pub struct Harmonics {
    /// Φ_K, N × K: mode n in column n, lowest frequency first.
    pub modes: DMatrix<Real>,
    /// λ_1 ≤ … ≤ λ_K (λ_1 = 0 for a connected mesh).
    pub values: Vec<Real>,
    /// The normalised lumped mass V (mean 1).
    pub mass: DVector<Real>,
}

impl Harmonics {
    /// The `k` lowest modes of `lap`.
    pub fn new(lap: &Laplacian, k: usize) -> Result<Harmonics, UpsampleError> {
        let n = lap.mass.len();
        if k == 0 || k > n {
            return Err(UpsampleError::TooManyModes { asked: k, nodes: n });
        }
        let scale = n as Real / lap.mass.iter().sum::<Real>();
        let mass = DVector::from_iterator(n, lap.mass.iter().map(|m| m * scale));
        let inv_sqrt = mass.map(|m| 1.0 / m.sqrt());
        let mut l = lap.dense_stiffness();
        // L = V^{-1/2} K V^{-1/2} (§3.2): symmetric, same spectrum as K φ = λ V φ.
        for j in 0..n {
            for i in 0..n {
                l[(i, j)] *= inv_sqrt[i] * inv_sqrt[j];
            }
        }
        let eig = SymmetricEigen::new(l);
        if eig.eigenvalues.iter().any(|v| !v.is_finite()) {
            return Err(UpsampleError::NonFinite { what: "Laplacian eigenvalues" });
        }
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let mut modes = DMatrix::zeros(n, k);
        for (c, &o) in order[..k].iter().enumerate() {
            let mut phi = eig.eigenvectors.column(o).component_mul(&inv_sqrt);
            // Fix the sign (eigenvectors have none) so results do not depend on the solver.
            if phi.iter().sum::<Real>() < 0.0 || (phi.iter().sum::<Real>() == 0.0 && phi[0] < 0.0) {
                phi.neg_mut();
            }
            modes.set_column(c, &phi);
        }
        let values = order[..k].iter().map(|&o| eig.eigenvalues[o]).collect();
        Ok(Harmonics { modes, values, mass })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::upsample::Surface;

    #[test]
    fn modes_are_mass_orthonormal_and_the_first_is_constant() {
        let lap = Laplacian::new(&Surface::grid(7, 5, 1.4, 1.0)).unwrap();
        let h = Harmonics::new(&lap, 12).unwrap();
        let gram = h.modes.transpose() * DMatrix::from_diagonal(&h.mass) * &h.modes;
        assert!((gram - DMatrix::identity(12, 12)).amax() < 1e-10);
        assert!(h.values[0].abs() < 1e-10 && h.values.windows(2).all(|w| w[0] <= w[1]));
        let c = h.modes[(0, 0)];
        assert!(h.modes.column(0).iter().all(|v| (v - c).abs() < 1e-10));
        // They are eigenvectors: K φ = λ V φ.
        let k = lap.dense_stiffness();
        for n in 0..12 {
            let r = &k * h.modes.column(n) - h.mass.component_mul(&h.modes.column(n)) * h.values[n];
            assert!(r.amax() < 1e-9, "mode {n}: residual {}", r.amax());
        }
    }

    #[test]
    fn too_many_modes_is_an_error() {
        let lap = Laplacian::new(&Surface::grid(1, 1, 1.0, 1.0)).unwrap();
        assert!(matches!(Harmonics::new(&lap, 5), Err(UpsampleError::TooManyModes { asked: 5, nodes: 4 })));
    }
}
