//! Sparse Cholesky (faer) with the symbolic analysis kept across numeric refactorisations.
//!
//! faer's `factorize_numeric_llt` permutes A into the fill-reducing order on every call. The
//! permuted pattern depends only on the symbolic analysis, so it is computed once here, with a
//! map from each permuted entry back to the caller's CSC layout; the caller then writes the
//! values straight into that order and the numeric kernel runs on them directly. The kernel sees
//! the same values in the same places as through faer's own path, so the factor is bit-identical.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use super::pattern::ScalarCsc;
use super::tail::Tail;

#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SolveError {
    #[error("the system matrix is not positive definite (Cholesky failed: {0})")]
    NotPositiveDefinite(String),
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
}

/// A symbolic factorisation of one sparsity pattern, refactorised numerically every step.
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    /// P A Pᵀ in the lower triangle the supernodal kernel reads, columns not sorted.
    perm_col_ptr: Vec<usize>,
    perm_row_idx: Vec<usize>,
    /// For each stored entry of P A Pᵀ, the `ScalarCsc::src` of the A entry it holds.
    value_src: Vec<usize>,
    l_values: Vec<f64>,
    buffer: MemBuffer,
    /// The contact block refactorised alone (`solver::tail`), when the ordering has one.
    tail: Option<Tail>,
}

impl Cholesky {
    /// Analyses the pattern (fill-reducing AMD ordering, elimination tree, supernodes).
    pub fn analyse(csc: &ScalarCsc) -> Result<Self, SolveError> {
        let sym = SymbolicSparseColMatRef::new_checked(csc.dim, csc.dim, &csc.col_ptr, None, &csc.row_idx);
        let symbolic = factorize_symbolic_cholesky(sym, Side::Lower, Default::default(), symbolic_params())
            .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?;
        Self::with_symbolic(csc, symbolic)
    }

    /// The fill-reducing order of the analysis (new position → unknown).
    pub fn order(&self) -> Vec<usize> {
        match self.symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..self.symbolic.nrows()).collect(),
        }
    }

    /// Analyses the pattern in the order `fwd` (new position → unknown) whose last `tail`
    /// unknowns form the block refactorised alone (`solver::tail`).
    pub fn analyse_ordered(csc: &ScalarCsc, fwd: &[usize], tail: usize) -> Result<Self, SolveError> {
        let n = csc.dim;
        let mut inv = vec![0; n];
        for (k, &i) in fwd.iter().enumerate() {
            inv[i] = k;
        }
        let perm = faer::perm::PermRef::new_checked(fwd, &inv, n);
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &csc.col_ptr, None, &csc.row_idx);
        let symbolic =
            factorize_symbolic_cholesky(sym, Side::Lower, SymmetricOrdering::Custom(perm), symbolic_params())
                .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?;
        let mut chol = Self::with_symbolic(csc, symbolic)?;
        if let (SymbolicCholeskyRaw::Supernodal(s), true) = (chol.symbolic.raw(), tail > 0) {
            chol.tail = Some(Tail::new(s, &chol.perm_col_ptr, &chol.perm_row_idx, n - tail)?);
        }
        Ok(chol)
    }

    fn with_symbolic(csc: &ScalarCsc, symbolic: SymbolicCholesky<usize>) -> Result<Self, SolveError> {
        let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
            return Err(SolveError::Symbolic("the analysis is not supernodal".into()));
        };
        let factor_req =
            supernodal::factorize_supernodal_numeric_llt_scratch::<usize, f64>(s, Par::Seq, Default::default());
        let (perm_col_ptr, perm_row_idx, value_src) = permuted_pattern(&symbolic, csc);
        let req = factor_req.or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let l_values = vec![0.0; symbolic.len_val()];
        Ok(Cholesky {
            symbolic,
            perm_col_ptr,
            perm_row_idx,
            value_src,
            l_values,
            buffer: MemBuffer::new(req),
            tail: None,
        })
    }

    /// For each value the numeric factorisation takes (`factor`), the `ScalarCsc::src` of the
    /// entry of A it must hold.
    pub fn value_sources(&self) -> &[usize] {
        &self.value_src
    }

    /// Numeric factorisation of the permuted values: `values[k]` is the entry of A that
    /// `value_sources()[k]` names. Sequential, so the result does not depend on the
    /// thread count.
    pub fn factor(&mut self, values: &[f64]) -> Result<(), SolveError> {
        let n = self.symbolic.nrows();
        let sym = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &self.perm_col_ptr, None, &self.perm_row_idx);
        let a = SparseColMatRef::new(sym, values);
        let stack = MemStack::new(&mut self.buffer);
        let reg = LltRegularization::default();
        let SymbolicCholeskyRaw::Supernodal(s) = self.symbolic.raw() else {
            return Err(SolveError::Symbolic("the analysis is not supernodal".into()));
        };
        supernodal::factorize_supernodal_numeric_llt(
            &mut self.l_values,
            a,
            reg,
            s,
            Par::Seq,
            stack,
            Default::default(),
        )
        .map(|_| ())
        .map_err(|e| SolveError::NotPositiveDefinite(format!("{e:?}")))?;
        if let Some(t) = &mut self.tail {
            t.full(values);
        }
        Ok(())
    }

    /// Refactorisation for `values` that differ from the last factorisation's: of the tail
    /// block alone when they differ only there (returns true), else in full.
    pub fn refactor(&mut self, values: &[f64]) -> Result<bool, SolveError> {
        match &mut self.tail {
            Some(t) if t.applies(values) => t.refactor(values, &mut self.l_values).map(|_| true),
            _ => self.factor(values).map(|_| false),
        }
    }

    /// Unknowns in the tail block (0 without one).
    #[cfg(test)]
    pub fn tail_len(&self) -> usize {
        self.tail.as_ref().map_or(0, |t| t.dim)
    }

    /// Solves A x = rhs in place with the last factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        let n = rhs.len();
        let rhs_mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        llt.solve_in_place_with_conj(Conj::No, rhs_mat, Par::Seq, MemStack::new(&mut self.buffer));
    }
}

/// The analysis always picks faer's supernodal kernel. faer's default chooses the scalar
/// simplicial kernel when the factor's flops per nonzero are low, which cloth systems of a few
/// hundred to a thousand nodes are (planar meshes, little fill); but their unknowns come in 3×3
/// node blocks, so every supernode has at least three columns and the blocked kernel wins there
/// too. Measured (issue 17, one thread, same sitting): ARCSim's square.json, 325 frames at ~286
/// faces, factorisation 1.49 → 0.60 s of the run; sphere.json's frames of 800–1,100 faces
/// 2.5 → 1.0 ms per factorisation. Above that faer picked the supernodal kernel already.
pub(super) fn symbolic_params() -> CholeskySymbolicParams<'static> {
    CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    }
}

/// P A Pᵀ's pattern exactly as faer's `factorize_numeric_llt` lays it out (a counting sort
/// over the columns of A in order, as `faer::sparse::utils::permute_self_adjoint_to_unsorted`),
/// each entry tagged with the `src` of the A entry it takes its value from.
fn permuted_pattern(symbolic: &SymbolicCholesky<usize>, csc: &ScalarCsc) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let n = csc.dim;
    let identity: Vec<usize> = (0..n).collect();
    let perm_inv = symbolic.perm().map(|p| p.arrays().1).unwrap_or(&identity);
    // Destination (column, row) of A's lower entry (i, j) in the output's lower triangle.
    let dest = |i: usize, j: usize| {
        let (pi, pj) = (perm_inv[i], perm_inv[j]);
        (pi.min(pj), pi.max(pj))
    };
    let mut col_ptr = vec![0; n + 1];
    for j in 0..n {
        for &i in &csc.row_idx[csc.col_ptr[j]..csc.col_ptr[j + 1]] {
            col_ptr[dest(i, j).0 + 1] += 1;
        }
    }
    for j in 0..n {
        col_ptr[j + 1] += col_ptr[j];
    }
    let nnz = col_ptr[n];
    let (mut row_idx, mut src) = (vec![0; nnz], vec![0; nnz]);
    let mut next = col_ptr[..n].to_vec();
    for j in 0..n {
        for k in csc.col_ptr[j]..csc.col_ptr[j + 1] {
            let (c, r) = dest(csc.row_idx[k], j);
            row_idx[next[c]] = r;
            src[next[c]] = csc.src[k];
            next[c] += 1;
        }
    }
    (col_ptr, row_idx, src)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::forces::RestState;
    use crate::mesh::rectangle;
    use crate::solver::pattern::BlockPattern;
    use faer::sparse::linalg::cholesky::CholeskySymbolicParams;
    use faer::sparse::linalg::SupernodalThreshold;

    /// The pattern of an `nx` × `ny` rectangle's system and an SPD matrix on it with irregular
    /// values (diagonally dominant), indexed by `src` tag.
    pub(crate) fn spd_system(nx: usize, ny: usize) -> (ScalarCsc, Vec<f64>) {
        let mesh = rectangle(1.0, 1.0, nx, ny).unwrap();
        let rest = RestState::new(&mesh, |_| 0.0).unwrap();
        let csc = ScalarCsc::new(&BlockPattern::new(&mesh, &rest.hinges, &[]));
        let mut by_src = vec![0.0; 9 * csc.row_idx.len()];
        for j in 0..csc.dim {
            for k in csc.col_ptr[j]..csc.col_ptr[j + 1] {
                let t = ((k * 7919) % 101) as f64 / 97.0;
                by_src[csc.src[k]] = if csc.row_idx[k] == j { 60.0 + t } else { -t };
            }
        }
        (csc, by_src)
    }

    /// Writing the values pre-permuted gives the factor faer's own `factorize_numeric_llt` gives,
    /// bit for bit, on the supernodal path (the one the analysis keeps, small systems included).
    /// A simplicial analysis is refused, not factorised wrongly.
    #[test]
    fn prepermuted_factor_matches_faer_bitwise() {
        for (nx, ny) in [(9, 7), (2, 2)] {
            let (csc, by_src) = spd_system(nx, ny);
            let a: Vec<f64> = csc.src.iter().map(|&s| by_src[s]).collect();
            let sym = SymbolicSparseColMatRef::new_checked(csc.dim, csc.dim, &csc.col_ptr, None, &csc.row_idx);
            let symbolic =
                factorize_symbolic_cholesky(sym, Side::Lower, Default::default(), symbolic_params()).unwrap();
            let mut reference = vec![0.0; symbolic.len_val()];
            let req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
            symbolic
                .factorize_numeric_llt::<f64>(
                    &mut reference,
                    SparseColMatRef::new(sym, &a),
                    Side::Lower,
                    LltRegularization::default(),
                    Par::Seq,
                    MemStack::new(&mut MemBuffer::new(req)),
                    Default::default(),
                )
                .unwrap();
            let mut chol = Cholesky::with_symbolic(&csc, symbolic).unwrap();
            let values: Vec<f64> = chol.value_sources().iter().map(|&s| by_src[s]).collect();
            chol.factor(&values).unwrap();
            assert!(reference.iter().any(|&x| x != 0.0));
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&chol.l_values), bits(&reference), "{nx}×{ny}");
        }
        let (csc, _) = spd_system(9, 7);
        let sym = SymbolicSparseColMatRef::new_checked(csc.dim, csc.dim, &csc.col_ptr, None, &csc.row_idx);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let simplicial = factorize_symbolic_cholesky(sym, Side::Lower, Default::default(), params).unwrap();
        assert!(matches!(Cholesky::with_symbolic(&csc, simplicial), Err(SolveError::Symbolic(_))));
    }
}
