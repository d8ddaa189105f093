//! Choosing the damping profile (γ_1, γ_N, c) by k-fold cross-validation on the training frames
//! alone (§6 leaves it to an artist and notes that "automatic cross-validation techniques would
//! also be possible"). The frames are cut into `folds` contiguous blocks; each block in turn is
//! held out, U is fitted to the others and its error measured on the block. Blocks rather than
//! every k-th frame because neighbouring frames are nearly equal: a validation frame between
//! two training frames would reward an operator that merely interpolates in time.
//!
//! The error is what eq. 5 minimises, the mass-weighted distance between U p_c and p_f over the
//! held-out frames, reported as an RMS node distance (m). It is evaluated in the harmonic basis
//! without forming U: with Φᵀ V Φ = I, ‖Φ Û P_c − P_f‖²_V = ‖Û P_c‖² − 2⟨Û P_c, Φᵀ V P_f⟩ +
//! ‖P_f‖²_V, exact for any number of kept modes. Each fold's `NormalEquations` serve every
//! candidate, so a grid costs one M × M eigendecomposition per fold plus O(M K F) per candidate.

use nalgebra::DMatrix;

use super::fit::{mass_weighted, NormalEquations};
use super::{Embedding, Harmonics, Prior, Profile, TrainingSet, UpsampleError};
use crate::math::Real;

/// One profile of the grid, given by its bounds as on the command line (§6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    pub gamma1: Real,
    pub gamma_n: Real,
    pub c: Real,
    pub prior: Prior,
}

/// A candidate's validation error: RMS node distance (m) over all held-out frames, and per fold.
#[derive(Clone, Debug, PartialEq)]
pub struct Scored {
    pub candidate: Candidate,
    pub rms: Real,
    pub per_fold: Vec<Real>,
}

/// Every combination of the given priors and bounds with γ_1 ≤ γ_N, in the order given (the
/// prior outermost, then γ_1).
pub fn grid(priors: &[Prior], gamma1: &[Real], gamma_n: &[Real], c: &[Real]) -> Vec<Candidate> {
    let mut out = Vec::new();
    for &prior in priors {
        for &g1 in gamma1 {
            for &gn in gamma_n.iter().filter(|&&gn| gn >= g1) {
                out.extend(c.iter().map(|&c| Candidate { gamma1: g1, gamma_n: gn, c, prior }));
            }
        }
    }
    out
}

/// Scores every candidate of `grid` by `folds`-fold cross-validation over contiguous blocks of
/// `data`'s frames; `h` are the fine mesh's harmonics, `b` the embedding candidates with
/// `Prior::Barycentric` are damped towards. Scores come back in the grid's order.
pub fn cross_validate(
    h: &Harmonics,
    b: &Embedding,
    data: &TrainingSet,
    folds: usize,
    grid: &[Candidate],
) -> Result<Vec<Scored>, UpsampleError> {
    let frames = data.coarse.len();
    if folds < 2 || folds > frames {
        return Err(UpsampleError::Folds { folds, frames });
    }
    let n = h.modes.nrows();
    let profiles =
        grid.iter().map(|c| Profile::from_bounds(c.gamma1, c.gamma_n, c.c, n)).collect::<Result<Vec<_>, _>>()?;
    let (pc, pf) = data.stacked(n)?;
    let vphi = mass_weighted(h);
    let block = |f: usize| f * folds / frames;
    let mut sq = vec![vec![0.0; folds]; grid.len()];
    for k in 0..folds {
        let (train, held): (Vec<usize>, Vec<usize>) = (0..frames).partition(|&f| block(f) != k);
        let columns = |m: &DMatrix<Real>, fs: &[usize]| {
            DMatrix::from_fn(m.nrows(), 3 * fs.len(), |i, j| m[(i, 3 * fs[j / 3] + j % 3)])
        };
        let prior = grid.iter().any(|c| c.prior == Prior::Barycentric).then_some(b);
        let normal = NormalEquations::new(h, &columns(&pc, &train), &columns(&pf, &train), prior);
        let (pc_v, pf_v) = (columns(&pc, &held), columns(&pf, &held));
        let y = vphi.transpose() * &pf_v; // Φᵀ V P_f over the held-out frames (K × 3F_v)
        let pf_norm: Real = (0..n).map(|i| h.mass[i] * pf_v.row(i).norm_squared()).sum();
        let wt_pc = normal.wt_times(&pc_v); // Wᵀ P_c, so that Û P_c = Ũᵀ Wᵀ P_c
        for ((scores, profile), cand) in sq.iter_mut().zip(&profiles).zip(grid) {
            let towards = cand.prior == Prior::Barycentric;
            let pred = normal.coefficients_in_eigenbasis(profile, towards).transpose() * &wt_pc;
            let e = pred.norm_squared() - 2.0 * pred.dot(&y) + pf_norm;
            if !e.is_finite() {
                return Err(UpsampleError::NonFinite { what: "a cross-validation error" });
            }
            scores[k] = e.max(0.0);
        }
    }
    // Mean-1 mass: Σ V = N, so the RMS node distance over F frames is √(Σ e / (N F)).
    let counts: Vec<usize> = (0..folds).map(|k| (0..frames).filter(|&f| block(f) == k).count()).collect();
    Ok(grid
        .iter()
        .zip(sq)
        .map(|(&candidate, e)| Scored {
            candidate,
            rms: (e.iter().sum::<Real>() / (n * frames) as Real).sqrt(),
            per_fold: e.iter().zip(&counts).map(|(e, &c)| (e / (n * c) as Real).sqrt()).collect(),
        })
        .collect())
}

/// The RMS node distance (m) between B p_c and p_f over all of `data`'s frames: the coarse
/// surface itself at the fine nodes, what `Prior::Barycentric` tends to as γ grows, and the
/// figure a learned U has to beat to be worth its cost. Nothing is fitted, so nothing is held out.
pub fn barycentric_rms(b: &Embedding, mass: &[Real], data: &TrainingSet) -> Real {
    let mut e = 0.0;
    for (pc, pf) in data.coarse.iter().zip(&data.fine) {
        let x = b.apply(pc);
        e += x.iter().zip(pf).zip(mass).map(|((a, b), m)| m * (a - b).norm_squared()).sum::<Real>();
    }
    (e / (mass.iter().sum::<Real>() * data.fine.len().max(1) as Real)).sqrt()
}

/// The candidate of least validation error (the first of equals); None for an empty grid.
pub fn best(scores: &[Scored]) -> Option<&Scored> {
    scores.iter().min_by(|a, b| a.rms.total_cmp(&b.rms))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::upsample::fit::tests::frames;
    use crate::upsample::{embedding, fit_towards, Laplacian, Surface};

    /// The harmonic-basis error equals the one measured on the fitted U's output, node by node.
    #[test]
    fn validation_error_matches_the_fitted_operator() {
        let (coarse, fine) = (Surface::grid(4, 3, 1.0, 0.75), Surface::grid(12, 9, 1.0, 0.75));
        let times: Vec<Real> = (0..12).map(|f| 0.3 * f as Real).collect();
        let data = TrainingSet { coarse: frames(&coarse, &times), fine: frames(&fine, &times) };
        for modes in [fine.nodes, 30] {
            let h = Harmonics::new(&Laplacian::new(&fine).unwrap(), modes).unwrap();
            let b = embedding(&coarse, &fine);
            let scored =
                cross_validate(&h, &b, &data, 3, &grid(&[Prior::Zero, Prior::Barycentric], &[1e-3], &[1.0], &[2.0]))
                    .unwrap();
            // Fold 1 (frames 4..8) by hand.
            let keep =
                |v: &Vec<Vec<Vec3>>| v.iter().enumerate().filter(|(f, _)| f / 4 != 1).map(|x| x.1.clone()).collect();
            let train = TrainingSet { coarse: keep(&data.coarse), fine: keep(&data.fine) };
            let profile = Profile::from_bounds(1e-3, 1.0, 2.0, fine.nodes).unwrap();
            for (s, prior) in scored.iter().zip([None, Some(&b)]) {
                let op = fit_towards(&h, &profile, &train, prior).unwrap();
                let mut e = 0.0;
                for f in 4..8 {
                    let x = op.apply(&data.coarse[f]);
                    let d = x.iter().zip(&data.fine[f]).zip(h.mass.iter());
                    e += d.map(|((a, b), m)| m * (a - b).norm_squared()).sum::<Real>();
                }
                let want = (e / (4 * fine.nodes) as Real).sqrt();
                let got = s.per_fold[1];
                assert!(
                    (got - want).abs() < 1e-9 * want,
                    "{modes} modes, {:?}: {got:e} vs {want:e}",
                    s.candidate.prior
                );
            }
        }
    }

    /// On data with a detail U can learn, over-damping is caught: γ_N = 10⁵ with c = 0 (flat,
    /// every mode damped hard) scores worse than a profile that lets the low modes through.
    #[test]
    fn over_damping_scores_worse() {
        let (coarse, fine) = (Surface::grid(4, 3, 1.0, 0.75), Surface::grid(12, 9, 1.0, 0.75));
        let times: Vec<Real> = (0..20).map(|f| 0.3 * f as Real).collect();
        let data = TrainingSet { coarse: frames(&coarse, &times), fine: frames(&fine, &times) };
        let h = Harmonics::new(&Laplacian::new(&fine).unwrap(), fine.nodes).unwrap();
        let g = grid(&[Prior::Zero], &[1e-3, 1e5], &[1e5], &[0.0, 4.0]);
        assert_eq!(g.len(), 4, "γ_1 = 1e5 pairs only with γ_N = 1e5");
        let s = cross_validate(&h, &embedding(&coarse, &fine), &data, 4, &g).unwrap();
        let flat = s.iter().find(|s| s.candidate.gamma1 == 1e5 && s.candidate.c == 0.0).unwrap();
        assert!(best(&s).unwrap().rms < 0.5 * flat.rms, "{s:?}");
    }

    #[test]
    fn folds_must_fit_the_frames() {
        let fine = Surface::grid(2, 2, 1.0, 1.0);
        let h = Harmonics::new(&Laplacian::new(&fine).unwrap(), 9).unwrap();
        let data = TrainingSet { coarse: vec![vec![Vec3::zeros(); 4]; 3], fine: vec![vec![Vec3::zeros(); 9]; 3] };
        let g = grid(&[Prior::Zero], &[1.0], &[10.0], &[4.0]);
        let b = embedding(&Surface::grid(1, 1, 1.0, 1.0), &fine);
        assert_eq!(cross_validate(&h, &b, &data, 4, &g), Err(UpsampleError::Folds { folds: 4, frames: 3 }));
        assert_eq!(cross_validate(&h, &b, &data, 1, &g), Err(UpsampleError::Folds { folds: 1, frames: 3 }));
    }
}
