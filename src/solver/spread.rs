//! Spreading collision push-outs through the step's system (the recovery of `sim::step` for a
//! collision stage whose impact zones add elastic energy).
//!
//! Impact zones (Harmon et al. 2008) move the colliding nodes alone, with the least
//! mass-weighted change. In a stiff cloth (foil, paper) one node pushed a few µm against its
//! neighbours stores more elastic energy than the whole sheet carries — ARCSim's crumple-pnas:
//! a foil rim node pushed 6 µm out of a shrinking sphere, +0.1 mJ against the foil's 0.5 mJ — and
//! since the push is the solve's own overshoot into the obstacle, halving the step does not
//! shrink it. Otaduy, Tamstorf, Steinemann & Gross 2009 ("Implicit contact handling for
//! deformable objects", §4) measure contact responses in the metric of the implicit system
//! A = M − h ∂f/∂v − h² ∂f/∂x instead: the cloth around a pushed node then moves with it as the
//! step's own dynamics would have moved it. Here, given the pushes dₖ at nodes aₖ, the change δ of
//! every node with the least δᵀAδ whose component along each push is that push:
//!
//!   min ½ δᵀAδ   s.t.   d̂ₖ · δ_{aₖ} = |dₖ|,
//!
//! δ = A⁻¹Pᵀμ with (P A⁻¹ Pᵀ) μ = (|dₖ|), P the k × 3n selector of the pushes' directions: k
//! solves with the step's factor and a dense k × k system (SPD: a principal part of A⁻¹ seen
//! through unit vectors on distinct nodes).

use nalgebra::{DMatrix, DVector};

use crate::math::{Real, Vec3};

/// Pushes at most this many nodes: each costs a solve with the step's factor.
pub const SPREAD_LIMIT: usize = 64;

/// The least-δᵀAδ change of `nodes` nodes meeting the pushes `d` at the distinct nodes `at` (module
/// doc); `solve` solves A y = b in place (3 unknowns per node). None when there are no pushes,
/// more than `SPREAD_LIMIT`, or the k × k system is not numerically SPD.
pub fn spread(mut solve: impl FnMut(&mut [f64]), nodes: usize, at: &[usize], d: &[Vec3]) -> Option<Vec<Vec3>> {
    let k = at.len();
    if k == 0 || k > SPREAD_LIMIT || d.iter().any(|d| d.norm() == 0.0) {
        return None;
    }
    let dir: Vec<Vec3> = d.iter().map(|d| d.normalize()).collect();
    // Columns of A⁻¹Pᵀ.
    let cols: Vec<Vec<f64>> = at
        .iter()
        .zip(&dir)
        .map(|(&a, u)| {
            let mut y = vec![0.0; 3 * nodes];
            y[3 * a..3 * a + 3].copy_from_slice(u.as_slice());
            solve(&mut y);
            y
        })
        .collect();
    let pick = |y: &[f64], r: usize| dir[r].dot(&Vec3::new(y[3 * at[r]], y[3 * at[r] + 1], y[3 * at[r] + 2]));
    let s = DMatrix::from_fn(k, k, |r, c| 0.5 * (pick(&cols[c], r) + pick(&cols[r], c)));
    let rhs = DVector::from_iterator(k, d.iter().map(|d| d.norm()));
    let mu = s.cholesky()?.solve(&rhs);
    let mut delta = vec![Vec3::zeros(); nodes];
    for (col, m) in cols.iter().zip(mu.iter()) {
        for (i, dl) in delta.iter_mut().enumerate() {
            *dl += *m * Vec3::new(col[3 * i], col[3 * i + 1], col[3 * i + 2]);
        }
    }
    delta.iter().all(|v| v.iter().all(|c: &Real| c.is_finite())).then_some(delta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::cholesky::tests::spd_system;
    use crate::solver::cholesky::Cholesky;

    /// The spread meets every push along its direction, and it is the least-A-norm change that
    /// does: A δ vanishes away from the pushed nodes and points along the push at each of them
    /// (the optimality condition A δ = Pᵀμ), and its A-norm is below the push alone's.
    #[test]
    fn spread_meets_the_pushes_at_least_energy() {
        let (csc, by_src) = spd_system(12, 10);
        let mut chol = Cholesky::analyse(&csc).unwrap();
        let values: Vec<f64> = chol.value_sources().iter().map(|&s| by_src[s]).collect();
        chol.factor(&values).unwrap();
        let nodes = csc.dim / 3;
        // A x from the stored lower triangle.
        let apply = |x: &[f64]| {
            let mut y = vec![0.0; x.len()];
            for j in 0..csc.dim {
                for p in csc.col_ptr[j]..csc.col_ptr[j + 1] {
                    let (i, a) = (csc.row_idx[p], by_src[csc.src[p]]);
                    y[i] += a * x[j];
                    if i != j {
                        y[j] += a * x[i];
                    }
                }
            }
            y
        };
        let at = [5, 40, 41, 97];
        let d = [
            Vec3::new(0.0, 0.0, 2e-6),
            Vec3::new(1e-6, -3e-6, 0.5e-6),
            Vec3::new(0.0, 1e-6, 0.0),
            Vec3::new(-4e-6, 0.0, 1e-6),
        ];
        let delta = spread(|b| chol.solve(b), nodes, &at, &d).unwrap();
        for (&a, d) in at.iter().zip(&d) {
            let got = d.normalize().dot(&delta[a]);
            assert!((got - d.norm()).abs() < 1e-12 * d.norm().max(1e-6), "push at {a}: {got} vs {}", d.norm());
        }
        let flat: Vec<f64> = delta.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
        let ad = apply(&flat);
        let scale = ad.iter().map(|v| v.abs()).fold(0.0, f64::max);
        for i in 0..nodes {
            let r = Vec3::new(ad[3 * i], ad[3 * i + 1], ad[3 * i + 2]);
            match at.iter().position(|&a| a == i) {
                None => assert!(r.norm() < 1e-9 * scale, "A δ at free node {i}: {r}"),
                Some(k) => assert!(r.cross(&d[k].normalize()).norm() < 1e-9 * scale, "A δ at {i} off the push"),
            }
        }
        // The pushes alone (every other node still) cost more in the A-norm.
        let mut alone = vec![0.0; csc.dim];
        for (&a, d) in at.iter().zip(&d) {
            alone[3 * a..3 * a + 3].copy_from_slice(d.as_slice());
        }
        let norm = |x: &[f64]| apply(x).iter().zip(x).map(|(a, b)| a * b).sum::<f64>();
        assert!(norm(&flat) < norm(&alone));
        // No pushes, or too many: nothing to spread.
        assert!(spread(|b| chol.solve(b), nodes, &[], &[]).is_none());
        let many: Vec<usize> = (0..=SPREAD_LIMIT).collect();
        assert!(spread(|b| chol.solve(b), nodes, &many, &vec![Vec3::x(); many.len()]).is_none());
    }
}
