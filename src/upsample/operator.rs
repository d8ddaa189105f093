//! The upsampling operator U ∈ R^{N×M}: fine = U · coarse (§3, eq. 1), one dense product per
//! frame (nalgebra's gemm); and `Compact`, U in f32 for the per-frame hot path.

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

/// U stored in f32: the product is memory-bound (U is 11 MB in f64 for 7056 × 196), so halving
/// U's bytes roughly halves the time (`benches/upsample.rs`). The coarse points are taken
/// relative to their centroid c first: rows of U sum to one, so U(p − 1cᵀ) + 1cᵀ = U p, and the
/// f32 rounding then scales with the cloth's extent, not its distance from the origin.
#[derive(Clone, Debug)]
pub struct Compact {
    u: DMatrix<f32>,
    pc: DMatrix<f32>,
    pf: DMatrix<f32>,
}

impl Compact {
    pub fn new(op: &Operator) -> Compact {
        let (n, m) = (op.fine_nodes(), op.coarse_nodes());
        Compact { u: op.u.map(|x| x as f32), pc: DMatrix::zeros(m, 3), pf: DMatrix::zeros(n, 3) }
    }

    /// p_f = U p_c, eq. 1, in f32 about the coarse centroid. `coarse` has M entries.
    pub fn apply(&mut self, coarse: &[Vec3]) -> Vec<Vec3> {
        let c = coarse.iter().sum::<Vec3>() / coarse.len().max(1) as Real;
        for (i, p) in coarse.iter().enumerate() {
            for d in 0..3 {
                self.pc[(i, d)] = (p[d] - c[d]) as f32;
            }
        }
        self.pf.gemm(1.0, &self.u, &self.pc, 0.0);
        let pf = &self.pf;
        (0..pf.nrows()).map(|i| Vec3::new(pf[(i, 0)] as Real, pf[(i, 1)] as Real, pf[(i, 2)] as Real) + c).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compact_matches_f64_far_from_the_origin() {
        let (n, m) = (50, 12);
        let raw = DMatrix::from_fn(n, m, |i, j| (((i * 7 + j * 5) % 11) as Real - 3.0) / 10.0);
        let u = DMatrix::from_fn(n, m, |i, j| raw[(i, j)] + (1.0 - raw.row(i).sum()) / m as Real);
        let op = Operator::new(u);
        let far = Vec3::new(1e4, -2e4, 5e3);
        let pc: Vec<Vec3> = (0..m).map(|j| Vec3::new(j as Real * 0.1, (j % 3) as Real * 0.2, 0.05) + far).collect();
        let (exact, fast) = (op.apply(&pc), Compact::new(&op).apply(&pc));
        let worst = exact.iter().zip(&fast).map(|(a, b)| (a - b).norm()).fold(0.0, Real::max);
        // Extent ~1 m: f32 gives ~1e-7 relative; without centring it would be ~1e-3 m here.
        assert!(worst < 1e-5, "f32 apply off by {worst:e} m");
    }
}
