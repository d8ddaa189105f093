//! Sparse Cholesky (faer) with the symbolic analysis kept across numeric refactorisations.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use super::pattern::ScalarCsc;

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
    l_values: Vec<f64>,
    buffer: MemBuffer,
}

impl Cholesky {
    /// Analyses the pattern (fill-reducing AMD ordering, elimination tree, supernodes).
    pub fn analyse(csc: &ScalarCsc) -> Result<Self, SolveError> {
        let sym = SymbolicSparseColMatRef::new_checked(
            csc.dim,
            csc.dim,
            &csc.col_ptr,
            None,
            &csc.row_idx,
        );
        let symbolic =
            factorize_symbolic_cholesky(sym, Side::Lower, Default::default(), Default::default())
                .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?;
        let req = symbolic
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let l_values = vec![0.0; symbolic.len_val()];
        Ok(Cholesky {
            symbolic,
            l_values,
            buffer: MemBuffer::new(req),
        })
    }

    /// Numeric factorisation of `values` (laid out as `csc`). Sequential, so the result does not
    /// depend on the thread count.
    pub fn factor(&mut self, csc: &ScalarCsc, values: &[f64]) -> Result<(), SolveError> {
        let sym = SymbolicSparseColMatRef::new_checked(
            csc.dim,
            csc.dim,
            &csc.col_ptr,
            None,
            &csc.row_idx,
        );
        let a = SparseColMatRef::new(sym, values);
        let stack = MemStack::new(&mut self.buffer);
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map(|_| ())
            .map_err(|e| SolveError::NotPositiveDefinite(format!("{e:?}")))
    }

    /// Solves A x = rhs in place with the last factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        let n = rhs.len();
        let rhs_mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        llt.solve_in_place_with_conj(Conj::No, rhs_mat, Par::Seq, MemStack::new(&mut self.buffer));
    }

    /// Number of stored values in the factor (a measure of fill).
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }
}
