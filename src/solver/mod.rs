//! The implicit system of one time step and its solution.
//!
//! Linearised backward Euler, one Newton step (Baraff & Witkin 1998, eq. 18):
//! (M − h ∂f/∂v − h² ∂f/∂x) Δv = h (f + h ∂f/∂x v).
//! With elastic Hessian K (projected PSD), stiffness-proportional damping f_d = −αKv and wind's
//! velocity Jacobian D: A = M + (hα + h²) K − h D, b = h (f − (α + h) K v).
//! Pinned nodes are eliminated (Dirichlet rows/columns), keeping the sparsity pattern fixed so
//! the symbolic factorisation is reused until the topology changes.

pub mod assembly;
pub mod cholesky;
pub mod pattern;
mod tail;

pub use assembly::StepInput;
pub use cholesky::SolveError;

use crate::math::{Mat3, Vec3};
use cholesky::Cholesky;
use pattern::{BlockPattern, ScalarCsc};

/// The global system for one mesh topology: pattern, symbolic factorisation and buffers.
pub struct ImplicitSystem {
    pub pattern: BlockPattern,
    csc: ScalarCsc,
    /// The pattern's fill-reducing order (new position → unknown).
    order: Vec<usize>,
    /// The nodes whose unknowns the factorisation orders last (`set_tail`), sorted.
    tail: Vec<usize>,
    chol: Cholesky,
    blocks: Vec<Mat3>,
    rhs: Vec<Vec3>,
    values: Vec<f64>,
    /// The step's system before friction and pinning, kept while friction re-solves it.
    base_blocks: Vec<Mat3>,
    base_rhs: Vec<Vec3>,
    base_saved: bool,
}

/// Time and work of a step's solves.
#[derive(Clone, Debug, Default)]
pub struct SolveTiming {
    pub assemble_s: f64,
    pub factor_s: f64,
    pub solve_s: f64,
    pub factorisations: usize,
    /// Of `factorisations`, those of the contact block alone (`solver::tail`).
    pub tail_factorisations: usize,
    pub solves: usize,
}

/// Tail blocks up to this many unknowns are refactorised alone (a dense Cholesky of n³/3 flops;
/// at 1,800, about a fifth of a full factorisation of the 51k-face reference).
pub const TAIL_MAX: usize = 1800;

impl ImplicitSystem {
    /// Builds the pattern of a mesh whose hinges are `hinges` and analyses it.
    pub fn new(pattern: BlockPattern) -> Result<Self, SolveError> {
        let csc = ScalarCsc::new(&pattern);
        let chol = Cholesky::analyse(&csc)?;
        let order = chol.order();
        let blocks = vec![Mat3::zeros(); pattern.num_blocks()];
        let rhs = vec![Vec3::zeros(); pattern.nodes];
        let values = vec![0.0; csc.row_idx.len()];
        Ok(ImplicitSystem {
            pattern,
            csc,
            order,
            tail: Vec::new(),
            chol,
            blocks,
            rhs,
            values,
            base_blocks: Vec::new(),
            base_rhs: Vec::new(),
            base_saved: false,
        })
    }
}

impl ImplicitSystem {
    /// Orders the unknowns of `nodes` (sorted: the cloth nodes of the step's contacts) last, so
    /// that the step's refactorisations for their friction and contact modes factorise their
    /// block alone (`solver::tail`). The analysis is kept while it covers `nodes` and is not
    /// more than twice their size; a set too large for a dense block goes back to the plain
    /// order. Without contacts nothing changes (no refactorisation will come).
    pub fn set_tail(&mut self, nodes: &[usize]) -> Result<(), SolveError> {
        if nodes.is_empty() {
            return Ok(());
        }
        let fits = 3 * nodes.len() <= TAIL_MAX;
        let covered = nodes.iter().all(|i| self.tail.binary_search(i).is_ok());
        let tight = self.tail.len() <= 2 * nodes.len() + 8;
        let wanted: &[usize] = if fits { nodes } else { &[] };
        if (fits && covered && tight) || (!fits && self.tail.is_empty()) {
            return Ok(());
        }
        let mut is_tail = vec![false; self.pattern.nodes];
        wanted.iter().for_each(|&i| is_tail[i] = true);
        let (mut fwd, mut last): (Vec<usize>, Vec<usize>) = self.order.iter().partition(|&&u| !is_tail[u / 3]);
        fwd.append(&mut last);
        self.chol = Cholesky::analyse_ordered(&self.csc, &fwd, 3 * wanted.len())?;
        self.tail = wanted.to_vec();
        Ok(())
    }
}
