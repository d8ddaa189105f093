//! Finite-difference errors of element kernels, for the crates that check derivatives.

use nalgebra::{SMatrix, SVector};
use viewcloth::math::Real;

pub fn max_abs<const R: usize, const C: usize>(m: &SMatrix<Real, R, C>) -> Real {
    m.iter().fold(0.0, |a, b| a.max(b.abs()))
}

/// Central-difference errors of an element kernel `f(x) = (energy, gradient, Hessian)` at `x`,
/// one per step in `steps`: the gradient against differences of the energy, the Hessian against
/// differences of the gradient (max abs entry).
pub struct FdErrors<const N: usize> {
    pub gradient: Vec<Real>,
    pub hessian: Vec<Real>,
    /// The kernel's own gradient and Hessian at `x`.
    pub g: SVector<Real, N>,
    pub h: SMatrix<Real, N, N>,
}

pub fn fd_errors<const N: usize>(
    x: &SVector<Real, N>,
    steps: impl IntoIterator<Item = Real>,
    f: impl Fn(&SVector<Real, N>) -> (Real, SVector<Real, N>, SMatrix<Real, N, N>),
) -> FdErrors<N> {
    let (_, g, h) = f(x);
    let (mut gradient, mut hessian) = (Vec::new(), Vec::new());
    for eps in steps {
        let mut g_fd = SVector::<Real, N>::zeros();
        let mut h_fd = SMatrix::<Real, N, N>::zeros();
        for i in 0..N {
            let (mut xp, mut xm) = (*x, *x);
            xp[i] += eps;
            xm[i] -= eps;
            let (ep, gp, _) = f(&xp);
            let (em, gm, _) = f(&xm);
            g_fd[i] = (ep - em) / (2.0 * eps);
            h_fd.set_column(i, &((gp - gm) / (2.0 * eps)));
        }
        gradient.push(max_abs(&(g_fd - g)));
        hessian.push(max_abs(&(h_fd - h)));
    }
    FdErrors { gradient, hessian, g, h }
}
