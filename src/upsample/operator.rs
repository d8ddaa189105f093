//! The upsampling operator U ∈ R^{N×M}: fine = U · coarse (§3, eq. 1), one dense product per
//! frame (nalgebra's gemm).

use nalgebra::DMatrix;

use crate::math::{Real, Vec3};

#[derive(Clone, Debug, PartialEq)]
pub struct Operator {
    /// U, N fine rows × M coarse columns.
    pub u: DMatrix<Real>,
}

impl Operator {
    pub fn new(u: DMatrix<Real>) -> Operator {
        Operator { u }
    }

    pub fn fine_nodes(&self) -> usize {
        self.u.nrows()
    }

    pub fn coarse_nodes(&self) -> usize {
        self.u.ncols()
    }

    /// p_f = U p_c, eq. 1. `coarse` must have `coarse_nodes()` entries.
    pub fn apply(&self, coarse: &[Vec3]) -> Vec<Vec3> {
        let pc = DMatrix::from_fn(coarse.len(), 3, |i, d| coarse[i][d]);
        let mut pf = DMatrix::zeros(self.fine_nodes(), 3);
        self.apply_into(&pc, &mut pf);
        (0..pf.nrows()).map(|i| Vec3::new(pf[(i, 0)], pf[(i, 1)], pf[(i, 2)])).collect()
    }

    /// p_f = U p_c with `M × 3` and `N × 3` matrices, allocation-free (the per-frame hot path).
    pub fn apply_into(&self, pc: &DMatrix<Real>, pf: &mut DMatrix<Real>) {
        pf.gemm(1.0, &self.u, pc, 0.0);
    }
}
