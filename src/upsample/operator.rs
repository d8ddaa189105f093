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
///
/// U is held in panels of `LANES` fine rows, each panel column-major, so one contiguous pass
/// over U gives all three coordinates with a panel's x, y, z sums in registers. (nalgebra's
/// `gemm` with a 3-column right-hand side runs three `gemv`s, streaming U three times and
/// loading and storing the sums for every column.) Each sum runs over j = 0..M in order,
/// u_i0 q_0 first, as `gemv` does, so the result is that of `DMatrix<f32>::gemm` to the bit
/// (`matches_gemm_to_the_bit`).
#[derive(Clone, Debug)]
pub struct Compact {
    /// Panel p, entry (j, k): U[p·LANES + k, j] at `u[(p M + j) LANES + k]`; rows past N are 0.
    u: Vec<f32>,
    n: usize,
    /// The coarse points' x, y and z about their centroid, in f32 (scratch, M entries each;
    /// apart, so that the compiler's SIMD runs along a panel's rows, not across x, y, z).
    pc: [Vec<f32>; 3],
}

/// Fine rows per panel: 3 × 8 f32 sums fill six SSE registers (the baseline x86-64 target),
/// leaving room for U's column and the three coarse coordinates.
const LANES: usize = 8;

impl Compact {
    pub fn new(op: &Operator) -> Compact {
        let (n, m) = (op.fine_nodes(), op.coarse_nodes());
        let mut u = vec![0.0f32; n.div_ceil(LANES) * m * LANES];
        for ((i, j), &x) in op.u.iter().enumerate().map(|(e, x)| ((e % n, e / n), x)) {
            u[((i / LANES) * m + j) * LANES + i % LANES] = x as f32;
        }
        Compact { u, n, pc: [0; 3].map(|_| vec![0.0; m]) }
    }

    /// p_f = U p_c, eq. 1, in f32 about the coarse centroid. `coarse` has M entries.
    pub fn apply(&mut self, coarse: &[Vec3]) -> Vec<Vec3> {
        let mut fine = vec![Vec3::zeros(); self.n];
        self.apply_into(coarse, &mut fine);
        fine
    }

    /// `apply` into `fine` (N entries), allocation-free: the per-frame hot path.
    pub fn apply_into(&mut self, coarse: &[Vec3], fine: &mut [Vec3]) {
        let m = self.pc[0].len();
        assert_eq!((coarse.len(), fine.len()), (m, self.n), "Compact::apply_into: M and N");
        let c = coarse.iter().sum::<Vec3>() / m.max(1) as Real;
        for (d, q) in self.pc.iter_mut().enumerate() {
            for (qj, p) in q.iter_mut().zip(coarse) {
                *qj = (p[d] - c[d]) as f32;
            }
        }
        if m == 0 {
            fine.fill(c);
            return;
        }
        for (panel, out) in self.u.chunks_exact(m * LANES).zip(fine.chunks_mut(LANES)) {
            let s = panel_product(panel.as_chunks::<LANES>().0, &self.pc);
            for (k, p) in out.iter_mut().enumerate() {
                *p = Vec3::new(s[0][k] as Real, s[1][k] as Real, s[2][k] as Real) + c;
            }
        }
    }
}

/// One panel's rows of U q, q the M (≥ 1) coarse points: s_d[k] = Σ_j u_kj q_jd, summed in
/// order of j. The fixed-size inner loop is what the compiler turns into SIMD along k. Not
/// inlined: inlined into `apply_into`, whose output reads (s_x[k], s_y[k], s_z[k]) together, the
/// SIMD went across x, y, z instead, with a shuffle per multiply (1.9× slower, 2026-12-02).
#[inline(never)]
fn panel_product(columns: &[[f32; LANES]], q: &[Vec<f32>; 3]) -> [[f32; LANES]; 3] {
    let [mut sx, mut sy, mut sz] = [0, 1, 2].map(|d| columns[0].map(|u| u * q[d][0]));
    for (((col, &x), &y), &z) in columns[1..].iter().zip(&q[0][1..]).zip(&q[1][1..]).zip(&q[2][1..]) {
        for k in 0..LANES {
            sx[k] += col[k] * x;
            sy[k] += col[k] * y;
            sz[k] += col[k] * z;
        }
    }
    [sx, sy, sz]
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

    /// The blocked single pass gives the bits of the f32 `gemm` it replaced (centring as before),
    /// for N not a multiple of the panel height and a coarse mesh far from the origin.
    #[test]
    fn matches_gemm_to_the_bit() {
        let (n, m) = (5 * LANES + 3, 23);
        let u = DMatrix::from_fn(n, m, |i, j| (((i * 13 + j * 7) % 29) as Real - 9.0) / 37.0);
        let pc: Vec<Vec3> = (0..m)
            .map(|j| {
                Vec3::new((j as Real * 0.37).sin(), (j as Real * 0.11).cos(), j as Real * 0.013)
                    + Vec3::new(3e3, -7.0, 0.5)
            })
            .collect();
        let op = Operator::new(u);
        let c = pc.iter().sum::<Vec3>() / m as Real;
        let q = DMatrix::from_fn(m, 3, |j, d| (pc[j][d] - c[d]) as f32);
        let mut pf = DMatrix::<f32>::zeros(n, 3);
        pf.gemm(1.0, &op.u.map(|x| x as f32), &q, 0.0);
        let mut fast = vec![Vec3::zeros(); n];
        Compact::new(&op).apply_into(&pc, &mut fast);
        for (i, p) in fast.iter().enumerate() {
            let want = Vec3::new(pf[(i, 0)] as Real, pf[(i, 1)] as Real, pf[(i, 2)] as Real) + c;
            assert_eq!(p.map(Real::to_bits), want.map(Real::to_bits), "row {i}");
        }
    }
}
