//! The collision stages' parameters: repulsion thickness and stiffness, friction, self-collision,
//! the impact-zone iteration cap, the load-time push-out depth and what becomes of cloth that
//! starts deeper inside an obstacle.

use super::proximity::Law;
use crate::math::Real;

/// Collision parameters (scene `collision` block, with defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct CollisionParams {
    /// Repulsion thickness (m).
    pub thickness: Real,
    /// Repulsion stiffness per unit area (N/m³).
    pub stiffness: Real,
    /// The repulsion's law and its area rule (scene `collision.penalty`).
    pub penalty: Law,
    pub friction: Real,
    pub self_friction: Real,
    pub self_collision: bool,
    pub max_iterations: usize,
    pub push_out_tolerance: Real,
    pub initial_intersections: InitialIntersections,
}

/// What becomes of cloth nodes deeper than `push_out_tolerance` inside an obstacle at load
/// (scene `collision.initial_intersections`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitialIntersections {
    /// Moved out over the first steps by the separation stage (`sim::separate`).
    Resolve,
    /// An input error, as before issue 18.
    Refuse,
}

impl Default for CollisionParams {
    fn default() -> Self {
        CollisionParams {
            thickness: 5e-3,
            stiffness: 1e6,
            penalty: Law::Quadratic,
            friction: 0.3,
            self_friction: 0.3,
            self_collision: true,
            max_iterations: 100,
            push_out_tolerance: 15e-3,
            initial_intersections: InitialIntersections::Resolve,
        }
    }
}
