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

pub use assembly::StepInput;
pub use cholesky::SolveError;

use crate::math::{Mat3, Vec3};
use cholesky::Cholesky;
use pattern::{BlockPattern, ScalarCsc};

/// The global system for one mesh topology: pattern, symbolic factorisation and buffers.
pub struct ImplicitSystem {
    pub pattern: BlockPattern,
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
    pub solves: usize,
}

impl ImplicitSystem {
    /// Builds the pattern of a mesh whose hinges are `hinges` and analyses it.
    pub fn new(pattern: BlockPattern) -> Result<Self, SolveError> {
        let csc = ScalarCsc::new(&pattern);
        let chol = Cholesky::analyse(&csc)?;
        let blocks = vec![Mat3::zeros(); pattern.num_blocks()];
        let rhs = vec![Vec3::zeros(); pattern.nodes];
        let values = vec![0.0; csc.row_idx.len()];
        Ok(ImplicitSystem {
            pattern,
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
