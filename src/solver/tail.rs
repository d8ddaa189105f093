//! Refactorising only the contact block of the system within a step.
//!
//! Within one step the friction and contact active-set iteration (`collision::friction`,
//! `collision::speculative`) changes the system matrix only in the couplings among the cloth
//! nodes of the step's contacts. With those nodes' unknowns ordered last (the tail T), the
//! Cholesky factor splits as
//!
//! ```text
//!   P A Pᵀ = [A₁₁ A₁₂; A₂₁ A₂₂] = [L₁₁ 0; L₂₁ L₂₂] [L₁₁ 0; L₂₁ L₂₂]ᵀ,  L₂₂ L₂₂ᵀ = S = A₂₂ − L₂₁ L₂₁ᵀ,
//! ```
//!
//! and a change Δ confined to A₂₂ leaves L₁₁ and L₂₁ as they are: the new factor's last block is
//! the Cholesky factor of S + Δ = L₂₂ L₂₂ᵀ + Δ (the block elimination of George & Liu 1981,
//! ch. 6; CHOLMOD's "update of the trailing block" in Davis 2006, §11). S is formed once per
//! full factorisation, at its first refactorisation, from the stored L₂₂; each refactorisation
//! is then one dense Cholesky of the tail's size, written back into the sparse factor's own
//! storage, so the solve is unchanged. Structurally zero entries of L₂₂ stay exact zeros in the
//! dense factor (each is a sum of products with an exact zero factor), so nothing is dropped.
//!
//! The ordering is the pattern's fill-reducing (AMD) order with the tail's unknowns moved to the
//! end, their relative order kept; `ImplicitSystem::set_tail` decides when it is worth it.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltRegularization};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

use super::SolveError;

/// The tail block of one symbolic factorisation.
pub(super) struct Tail {
    /// Its size (unknowns); it ends the permuted order.
    pub dim: usize,
    /// Where the tail block's values begin in the permuted values (every value from here on has
    /// its column in the tail).
    pub first_value: usize,
    /// Per permuted value of the tail block: its row and column within the block.
    a_entries: Vec<(usize, usize)>,
    /// Per stored entry of L₂₂: its row, column (within the block) and index in L's values.
    l_entries: Vec<(usize, usize, usize)>,
    /// The values of the last full factorisation.
    base: Vec<f64>,
    /// L₂₂ L₂₂ᵀ of the last full factorisation (formed at its first refactorisation).
    schur: Option<Mat<f64>>,
    work: Mat<f64>,
    buffer: MemBuffer,
}

impl Tail {
    /// The tail from column `start` on of a factor of dimension `n`: `a_entries` lists each
    /// permuted value from `first_value` on as (row, column); `l_entries` each stored entry of
    /// L in those columns as (row, column, index in L's values), all in permuted numbering.
    pub fn new(
        n: usize,
        start: usize,
        first_value: usize,
        a_entries: impl Iterator<Item = (usize, usize)>,
        l_entries: impl Iterator<Item = (usize, usize, usize)>,
    ) -> Tail {
        let dim = n - start;
        let a_entries = a_entries.map(|(r, c)| (r - start, c - start)).collect();
        let l_entries = l_entries.map(|(r, c, k)| (r - start, c - start, k)).collect();
        let req = cholesky_in_place_scratch::<f64>(dim, Par::Seq, Default::default());
        Tail {
            dim,
            first_value,
            a_entries,
            l_entries,
            base: Vec::new(),
            schur: None,
            work: Mat::zeros(dim, dim),
            buffer: MemBuffer::new(req),
        }
    }

    /// Records the values of a full factorisation.
    pub fn full(&mut self, values: &[f64]) {
        self.base.clear();
        self.base.extend_from_slice(values);
        self.schur = None;
    }

    /// Whether `values` differ from the last full factorisation's only in the tail block.
    pub fn applies(&self, values: &[f64]) -> bool {
        self.base.len() == values.len() && values[..self.first_value] == self.base[..self.first_value]
    }

    /// Refactorises the tail block for `values` (which `applies`), overwriting L₂₂ in `l_values`.
    pub fn refactor(&mut self, values: &[f64], l_values: &mut [f64]) -> Result<(), SolveError> {
        let dim = self.dim;
        if self.schur.is_none() {
            let mut l22 = Mat::<f64>::zeros(dim, dim);
            for &(r, c, k) in &self.l_entries {
                l22[(r, c)] = l_values[k];
            }
            let mut s = Mat::<f64>::zeros(dim, dim);
            matmul(s.as_mut(), Accum::Replace, l22.as_ref(), l22.transpose(), 1.0, Par::Seq);
            self.schur = Some(s);
        }
        let schur = self.schur.as_ref().expect("formed above");
        self.work.copy_from(schur);
        let tail_values = &values[self.first_value..];
        let base = &self.base[self.first_value..];
        for (&(r, c), (v, b)) in self.a_entries.iter().zip(tail_values.iter().zip(base)) {
            if v != b {
                let d = v - b;
                self.work[(r, c)] += d;
                if r != c {
                    self.work[(c, r)] += d;
                }
            }
        }
        cholesky_in_place(
            self.work.as_mut(),
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.buffer),
            Default::default(),
        )
        .map_err(|e| SolveError::NotPositiveDefinite(format!("{e:?} (tail block)")))?;
        for &(r, c, k) in &self.l_entries {
            l_values[k] = self.work[(r, c)];
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::RestState;
    use crate::mesh::rectangle;
    use crate::solver::cholesky::Cholesky;
    use crate::solver::pattern::{BlockPattern, ScalarCsc};

    /// A refactorisation of the tail block alone solves the changed system as a full
    /// factorisation does (to rounding), and a change outside the block falls back to a full one.
    #[test]
    fn tail_refactorisation_solves_the_changed_system() {
        let mesh = rectangle(1.0, 1.0, 40, 40).unwrap();
        let rest = RestState::new(&mesh, |_| 0.0).unwrap();
        let csc = ScalarCsc::new(&BlockPattern::new(&mesh, &rest.hinges, &[]));
        // SPD (diagonally dominant) values by `src` tag, as in cholesky.rs's test.
        let mut by_src = vec![0.0; 9 * csc.row_idx.len()];
        for j in 0..csc.dim {
            for k in csc.col_ptr[j]..csc.col_ptr[j + 1] {
                let t = ((k * 7919) % 101) as f64 / 97.0;
                by_src[csc.src[k]] = if csc.row_idx[k] == j { 60.0 + t } else { -t };
            }
        }
        // Two patches of contact nodes, one of them on the boundary.
        let n = mesh.nodes.len();
        let tail: Vec<usize> = (0..n)
            .filter(|&i| {
                let p = mesh.nodes[i].x;
                (p.x - 0.3).hypot(p.y - 0.6) < 0.12 || (p.x > 0.85 && p.y < 0.2)
            })
            .collect();
        assert!(tail.len() > 20 && 3 * tail.len() < 1800);
        let base = Cholesky::analyse(&csc).unwrap();
        let (mut first, mut last): (Vec<usize>, Vec<usize>) =
            base.order().into_iter().partition(|&u| tail.binary_search(&(u / 3)).is_err());
        first.append(&mut last);
        let mut chol = Cholesky::analyse_ordered(&csc, &first, 3 * tail.len()).unwrap();
        assert_eq!(chol.tail_len(), 3 * tail.len());
        let values =
            |chol: &Cholesky, by_src: &[f64]| -> Vec<f64> { chol.value_sources().iter().map(|&s| by_src[s]).collect() };
        chol.factor(&values(&chol, &by_src)).unwrap();
        // Friction-like change among the tail's couplings only.
        let mut changed = by_src.clone();
        for j in 0..csc.dim {
            for k in csc.col_ptr[j]..csc.col_ptr[j + 1] {
                let i = csc.row_idx[k];
                if tail.binary_search(&(i / 3)).is_ok() && tail.binary_search(&(j / 3)).is_ok() {
                    changed[csc.src[k]] += if i == j { 25.0 } else { -0.3 * ((k % 7) as f64 / 7.0) };
                }
            }
        }
        let rhs: Vec<f64> = (0..csc.dim).map(|i| ((i * 31) % 17) as f64 - 8.0).collect();
        let solve = |chol: &mut Cholesky| {
            let mut x = rhs.clone();
            chol.solve(&mut x);
            x
        };
        let mut reference = Cholesky::analyse(&csc).unwrap();
        for (by_src, tail_only) in [(&changed, true), (&by_src, true), (&changed, true)] {
            assert_eq!(chol.refactor(&values(&chol, by_src)).unwrap(), tail_only);
            reference.factor(&values(&reference, by_src)).unwrap();
            let (x, y) = (solve(&mut chol), solve(&mut reference));
            let err = x.iter().zip(&y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-12, "tail refactorisation off by {err}");
        }
        // A change outside the block: a full refactorisation.
        let mut outside = changed.clone();
        let k = csc.col_ptr[0];
        outside[csc.src[k]] += 1.0;
        assert!(tail.binary_search(&0).is_err());
        assert!(!chol.refactor(&values(&chol, &outside)).unwrap());
        reference.factor(&values(&reference, &outside)).unwrap();
        let (x, y) = (solve(&mut chol), solve(&mut reference));
        assert!(x.iter().zip(&y).all(|(a, b)| (a - b).abs() < 1e-12));
    }
}
