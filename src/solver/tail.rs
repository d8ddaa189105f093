//! Refactorising only the contact block of the system within a step.
//!
//! Within one step the friction and contact active-set iteration (`collision::friction`,
//! `collision::speculative`) changes the system matrix only in the couplings among the cloth
//! nodes of the step's contacts. With those nodes' unknowns ordered last (the tail), the
//! Cholesky factor splits as (block Cholesky; Golub & Van Loan, Matrix Computations, §4.2)
//!
//! ```text
//!   P A Pᵀ = [A₁₁ A₁₂; A₂₁ A₂₂] = [L₁₁ 0; L₂₁ L₂₂] [L₁₁ 0; L₂₁ L₂₂]ᵀ,  L₂₂ L₂₂ᵀ = S = A₂₂ − L₂₁ L₂₁ᵀ,
//! ```
//!
//! and a change Δ confined to A₂₂ leaves L₁₁ and L₂₁ as they are: the new factor's last block is
//! the Cholesky factor of S + Δ = L₂₂ L₂₂ᵀ + Δ. S is formed once per full factorisation, at its
//! first refactorisation, from the stored L₂₂ (in L₂₂'s own pattern: a Cholesky factor's pattern
//! holds the pattern of L Lᵀ and of its own factor); each refactorisation is then a sparse
//! Cholesky of the tail alone (faer's supernodal kernel, identity order), written back into the
//! full factor's storage, so the solve is unchanged. Entries the tail's own symbolic analysis
//! stores beyond L₂₂'s pattern (relaxed supernodes) are structurally zero, computed as exact
//! zeros, and dropped.
//!
//! The ordering is the pattern's fill-reducing (AMD) order with the tail's unknowns moved to the
//! end, their relative order kept; `ImplicitSystem::set_tail` decides when it is worth it.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::matmul::matmul;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, Mat, Par, Side};

use super::SolveError;

/// The part of one supernode of the full factor in the tail's columns: its values start at
/// `offset` in L's values, column-major with `stride` rows; its tail columns are the `cols`
/// from local column `first` on, and their rows are local rows `first..stride`, `rows` (global
/// in `Tail::new`'s argument, within the tail after). The top `cols` × `cols` part is the
/// supernode's diagonal block: lower triangular (its upper part is not the factor's).
pub(super) struct Block {
    pub offset: usize,
    pub stride: usize,
    pub first: usize,
    pub cols: usize,
    pub rows: Vec<usize>,
}

/// The tail block of one symbolic factorisation.
pub(super) struct Tail {
    /// Its size (unknowns); it ends the permuted order.
    pub dim: usize,
    /// Where the tail block's values begin in the permuted values (every value from here on has
    /// its column in the tail).
    first_value: usize,
    /// Per permuted value of the tail block: its position in L₂₂'s pattern.
    a_pos: Vec<usize>,
    /// L₂₂'s pattern (lower, columns in order, rows sorted, within the block).
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// The full factor's supernodes in the tail (`Block`), rows within the block.
    blocks: Vec<Block>,
    /// The tail's own analysis, and per value of its factor the full factor's index (or
    /// `usize::MAX` for a structural zero of L₂₂).
    symbolic: SymbolicCholesky<usize>,
    out_idx: Vec<usize>,
    /// The values of the last full factorisation.
    base: Vec<f64>,
    /// S = L₂₂ L₂₂ᵀ of the last full factorisation in L₂₂'s pattern (formed at its first
    /// refactorisation), the matrix refactorised and its factor.
    schur: Option<Vec<f64>>,
    a: Vec<f64>,
    l: Vec<f64>,
    buffer: MemBuffer,
}

/// Calls `f(row, column, index in the values)` for each stored entry of a supernodal factor's
/// columns from `from` on, by column, rows ascending (the diagonal block's lower part, then the
/// supernode's row pattern); returns the supernodes' `Block`s over those columns.
fn for_each_entry(
    s: &SymbolicSupernodalCholesky<usize>,
    from: usize,
    mut f: impl FnMut(usize, usize, usize),
) -> Vec<Block> {
    let mut blocks = Vec::new();
    for sn in 0..s.n_supernodes() {
        let (b, e) = (s.supernode_begin()[sn], s.supernode_end()[sn]);
        if e <= from {
            continue;
        }
        let pattern = s.supernode(sn).pattern();
        let stride = e - b + pattern.len();
        let row = |r: usize| if r < e - b { b + r } else { pattern[r - (e - b)] };
        let offset = s.col_ptr_for_val()[sn];
        for c in b.max(from)..e {
            for r in c - b..stride {
                f(row(r), c, offset + (c - b) * stride + r);
            }
        }
        let first = b.max(from) - b;
        blocks.push(Block { offset, stride, first, cols: e - b - first, rows: (first..stride).map(row).collect() });
    }
    blocks
}

impl Tail {
    /// The tail from column `start` on of the full factor `s`, whose input P A Pᵀ has the lower
    /// pattern `col_ptr`, `row_idx` (permuted numbering).
    pub fn new(
        s: &SymbolicSupernodalCholesky<usize>,
        a_col_ptr: &[usize],
        a_row_idx: &[usize],
        start: usize,
    ) -> Result<Tail, SolveError> {
        let n = s.nrows();
        let mut l_entries = Vec::new();
        let mut blocks = for_each_entry(s, start, |r, c, k| l_entries.push((r, c, k)));
        blocks.iter_mut().for_each(|b| b.rows.iter_mut().for_each(|r| *r -= start));
        let first_value = a_col_ptr[start];
        let dim = n - start;
        let mut col_ptr = vec![0; dim + 1];
        let (mut row_idx, mut l_idx) = (Vec::with_capacity(l_entries.len()), Vec::with_capacity(l_entries.len()));
        for &(r, c, k) in &l_entries {
            let (r, c) = (r - start, c - start);
            col_ptr[c + 1] += 1;
            row_idx.push(r);
            l_idx.push(k);
        }
        for c in 0..dim {
            col_ptr[c + 1] += col_ptr[c];
        }
        let position = |r: usize, c: usize| {
            let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            rows.binary_search(&r).map(|p| col_ptr[c] + p)
        };
        let a_pos = (start..n)
            .flat_map(|c| a_row_idx[a_col_ptr[c]..a_col_ptr[c + 1]].iter().map(move |&r| (r, c)))
            .map(|(r, c)| position(r - start, c - start))
            .collect::<Result<Vec<usize>, usize>>()
            .map_err(|_| SolveError::Symbolic("a contact coupling outside the tail factor's pattern".into()))?;
        let identity: Vec<usize> = (0..dim).collect();
        let perm = faer::perm::PermRef::new_checked(&identity, &identity, dim);
        let sym = SymbolicSparseColMatRef::new_checked(dim, dim, &col_ptr, None, &row_idx);
        let symbolic = factorize_symbolic_cholesky(
            sym,
            Side::Lower,
            SymmetricOrdering::Custom(perm),
            super::cholesky::symbolic_params(),
        )
        .map_err(|e| SolveError::Symbolic(format!("{e:?} (tail block)")))?;
        let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
            return Err(SolveError::Symbolic("the tail block's analysis is not supernodal".into()));
        };
        let mut out_idx = vec![usize::MAX; symbolic.len_val()];
        for_each_entry(s, 0, |r, c, k| {
            if let Ok(p) = position(r, c) {
                out_idx[k] = l_idx[p];
            }
        });
        let req = supernodal::factorize_supernodal_numeric_llt_scratch::<usize, f64>(s, Par::Seq, Default::default());
        let (len, nnz) = (symbolic.len_val(), row_idx.len());
        Ok(Tail {
            dim,
            first_value,
            a_pos,
            col_ptr,
            row_idx,
            blocks,
            symbolic,
            out_idx,
            base: Vec::new(),
            schur: None,
            a: vec![0.0; nnz],
            l: vec![0.0; len],
            buffer: MemBuffer::new(req),
        })
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

    /// S = L₂₂ L₂₂ᵀ in L₂₂'s pattern from the full factor's values, supernode by supernode:
    /// each adds B Bᵀ, B its tail columns (dense, `Block`), at its rows.
    fn schur(&self, l_values: &[f64]) -> Vec<f64> {
        let (cp, ri) = (&self.col_ptr, &self.row_idx);
        let mut s = vec![0.0; ri.len()];
        for blk in &self.blocks {
            let m = blk.rows.len();
            let b = Mat::<f64>::from_fn(m, blk.cols, |r, c| match r >= c {
                true => l_values[blk.offset + (blk.first + c) * blk.stride + blk.first + r],
                false => 0.0,
            });
            let mut p = Mat::<f64>::zeros(m, m);
            matmul(p.as_mut(), Accum::Replace, b.as_ref(), b.transpose(), 1.0, Par::Seq);
            for (c, &j) in blk.rows.iter().enumerate() {
                // Column j of the pattern holds every row of the block from j on (a Cholesky
                // factor's pattern holds that of L Lᵀ): a merge of the two sorted lists.
                let mut q = cp[j];
                for (r, &i) in blk.rows.iter().enumerate().skip(c) {
                    while q + 1 < cp[j + 1] && ri[q] < i {
                        q += 1;
                    }
                    debug_assert_eq!(ri[q], i, "L₂₂'s pattern holds L₂₂ L₂₂ᵀ's");
                    s[q] += p[(r, c)];
                }
            }
        }
        s
    }

    /// Refactorises the tail block for `values` (which `applies`), overwriting L₂₂ in `l_values`.
    pub fn refactor(&mut self, values: &[f64], l_values: &mut [f64]) -> Result<(), SolveError> {
        if self.schur.is_none() {
            self.schur = Some(self.schur(l_values));
        }
        self.a.copy_from_slice(self.schur.as_ref().expect("formed above"));
        let (now, base) = (&values[self.first_value..], &self.base[self.first_value..]);
        for (&p, (v, b)) in self.a_pos.iter().zip(now.iter().zip(base)) {
            self.a[p] += v - b;
        }
        let SymbolicCholeskyRaw::Supernodal(s) = self.symbolic.raw() else { unreachable!("checked in Tail::new") };
        let sym = SymbolicSparseColMatRef::new_checked(self.dim, self.dim, &self.col_ptr, None, &self.row_idx);
        supernodal::factorize_supernodal_numeric_llt(
            &mut self.l,
            SparseColMatRef::new(sym, &self.a),
            LltRegularization::default(),
            s,
            Par::Seq,
            MemStack::new(&mut self.buffer),
            Default::default(),
        )
        .map_err(|e| SolveError::NotPositiveDefinite(format!("{e:?} (tail block)")))?;
        for (&k, &x) in self.out_idx.iter().zip(&self.l) {
            if k != usize::MAX {
                l_values[k] = x;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::mesh::rectangle;
    use crate::solver::cholesky::tests::spd_system;
    use crate::solver::cholesky::Cholesky;

    /// A refactorisation of the tail block alone solves the changed system as a full
    /// factorisation does (to rounding), and a change outside the block falls back to a full one.
    #[test]
    fn tail_refactorisation_solves_the_changed_system() {
        let mesh = rectangle(1.0, 1.0, 40, 40).unwrap();
        let (csc, by_src) = spd_system(40, 40);
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
