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
pub mod spread;
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

/// The contact nodes' block is refactorised alone (`solver::tail`) while they are at most this
/// fraction of the nodes. Moving their unknowns last costs the full factorisation fill: on the
/// uniform `sheet_on_sphere` reference (26k nodes) 0.86 s against 0.5 s with 3.5% of the nodes in
/// contact, while the block's refactorisations took 0.05–0.16 s against 0.5 s (README,
/// Performance).
pub const TAIL_FRACTION: f64 = 0.05;

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
    /// The change of every node with the least δᵀAδ, A the matrix last factorised (the step's
    /// system with its friction terms and pinned rows), that moves each node `at[k]` by `d[k]`
    /// along `d[k]` (`spread`).
    pub fn spread(&mut self, at: &[usize], d: &[Vec3]) -> Option<Vec<Vec3>> {
        spread::spread(|b| self.chol.solve(b), self.pattern.nodes, at, d)
    }

    /// Orders the unknowns of `nodes` (sorted: the cloth nodes of the step's contacts) last, so
    /// that the step's refactorisations for their friction and contact modes factorise their
    /// block alone (`solver::tail`); without contacts, or with more than `TAIL_FRACTION` of the
    /// nodes in contact, the plain fill-reducing order. The order depends on the step's contacts
    /// alone (not on earlier steps'), so a resumed run orders as the uninterrupted one did.
    pub fn set_tail(&mut self, nodes: &[usize]) -> Result<(), SolveError> {
        let fits = nodes.len() as f64 <= TAIL_FRACTION * self.pattern.nodes as f64;
        let wanted: &[usize] = if fits { nodes } else { &[] };
        if wanted == self.tail.as_slice() {
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
