//! Soft handles: penalty springs that hold a node on its target or two nodes together.
//!
//! ARCSim 0.2.1 holds every handle this way (`handle.cpp`: one `EqCon` per axis for a node,
//! one `GlueCon` per axis for a glue pair, each with energy ½ k c², c the axis component of
//! the offset; `physics.cpp`'s `add_constraint_forces` puts −k c ∇c and its Jacobian −k ∇c ∇cᵀ
//! into the implicit system). Summed over the three axes:
//!
//! - anchor: E = ½ k |x − p|², ∇E = k (x − p), ∇²E = k I (p the target at the step's end);
//! - glue: E = ½ k |x_b − x_a|², ∇E = k (−d, d) with d = x_b − x_a, ∇²E = k [[I, −I], [−I, I]].
//!
//! Both Hessians are PSD, so they enter the system as they are.

use nalgebra::{SMatrix, SVector};

use crate::math::{Mat3, Real, Vec3};

/// A handle spring of one step, with its stiffness already scaled by the handle's strength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spring {
    /// Node `node` towards `target`.
    Anchor { node: usize, target: Vec3, k: Real },
    /// Node `nodes[1]` towards node `nodes[0]` and back.
    Glue { nodes: [usize; 2], k: Real },
}

/// Energy, gradient and Hessian of ½ k |x − p|².
pub fn anchor_spring(x: &Vec3, target: &Vec3, k: Real) -> (Real, Vec3, Mat3) {
    let d = x - target;
    (0.5 * k * d.norm_squared(), k * d, k * Mat3::identity())
}

/// Energy, gradient and Hessian of ½ k |x_b − x_a|² over (x_a, x_b).
pub fn glue_spring(xa: &Vec3, xb: &Vec3, k: Real) -> (Real, SVector<Real, 6>, SMatrix<Real, 6, 6>) {
    let d = xb - xa;
    let mut grad = SVector::<Real, 6>::zeros();
    grad.fixed_rows_mut::<3>(0).copy_from(&(-k * d));
    grad.fixed_rows_mut::<3>(3).copy_from(&(k * d));
    let mut hess = SMatrix::<Real, 6, 6>::zeros();
    for (a, b, s) in [(0, 0, 1.0), (3, 3, 1.0), (0, 3, -1.0), (3, 0, -1.0)] {
        hess.fixed_view_mut::<3, 3>(a, b).copy_from(&(s * k * Mat3::identity()));
    }
    (0.5 * k * d.norm_squared(), grad, hess)
}

impl Spring {
    /// The spring's energy with the cloth at `x`.
    pub fn energy(&self, x: &[Vec3]) -> Real {
        match *self {
            Spring::Anchor { node, target, k } => anchor_spring(&x[node], &target, k).0,
            Spring::Glue { nodes: [a, b], k } => glue_spring(&x[a], &x[b], k).0,
        }
    }
}
