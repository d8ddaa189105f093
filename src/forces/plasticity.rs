//! Bending plasticity with damage (Narain, Pfaff & O'Brien 2013, "Folding and crumpling
//! adaptive sheets"); the behavioural reference is ARCSim 0.2.1 (`plasticity.cpp`:
//! `plastic_update`, `recompute_edge_plasticity`; `physics.cpp`: the weakened stiffnesses).
//!
//! Each face carries a plastic (rest) shape operator S_p and a scalar damage d. Its current shape
//! operator S is the one `remesh::rest_shape` builds from dihedral angles,
//!
//!   S = −(1/A) Σₑ ½ θₑ |eₑ| t̂ₑ t̂ₑᵀ   (θₑ the current angles, unwrapped about the rest angles),
//!
//! and the elastic part S_e = S − S_p may not exceed the yield curvature κ_y in Frobenius norm:
//!
//!   ‖S_e‖_F > κ_y  ⇒  S_p ← S_p + (1 − κ_y/‖S_e‖_F) S_e,   d ← d + ‖S_e‖_F/κ_y − 1,
//!
//! a return to the yield surface along S_e (S_p moves toward S by the excess, so afterwards
//! ‖S − S_p‖_F = κ_y exactly). Below the yield nothing changes. The edges' rest angles are then
//! solved back from the faces' S_p (`rest_shape::refresh_edge_angles`; an interior edge takes
//! the mean of its two faces' values, as ARCSim's `recompute_edge_plasticity`), and an edge's
//! damage is the mean of its faces'.
//!
//! Damage weakens the sheet: with weakening w the membrane stiffness of a face is divided by
//! 1 + w·d_face and the bending stiffness of a hinge by 1 + w·d_edge, w the larger of the two
//! faces' materials' (ARCSim's `stretching_*` and `bending_*` in physics.cpp; the conf comment
//! "reduce stiffnesses upon yielding").
//!
//! ARCSim runs the update once per time step, right after the implicit solve (`advance_step`:
//! physics → plasticity → strain limiting → collision), on the angles its `compute_ws_data` took
//! at the end of `implicit_update`, before the positions moved: the positions the previous step
//! ended with. viewcloth runs it at the end of every accepted step, on the positions that step
//! ended with (`sim::plastic`): the same sequence of states. ARCSim also keeps a 3-D "plastic
//! embedding" to resample S_p on remeshing; viewcloth hands S_p and d through the remesh
//! operations instead (`remesh::rest_shape`), and refines where S_p is curved as ARCSim's
//! sizing does (`sizing`, `Mcurvp`).

use crate::math::{Mat2, Real};

/// A material's plasticity parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plasticity {
    /// κ_y (1/m): the Frobenius norm of the elastic shape operator at which a face yields.
    pub yield_curv: Real,
    /// w ≥ 0: stiffnesses are divided by 1 + w·d, d the accumulated damage.
    pub weakening: Real,
}

/// The outcome of one face's yield test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Yield {
    /// The new plastic shape operator.
    pub shape: Mat2,
    /// The damage added (≥ 0).
    pub damage: Real,
}

/// The return to the yield surface of a face whose current shape operator is `current` and
/// plastic one `plastic`; `None` when ‖current − plastic‖_F ≤ κ_y (no flow, nothing changes).
pub fn yield_face(current: &Mat2, plastic: &Mat2, yield_curv: Real) -> Option<Yield> {
    let elastic = current - plastic;
    let ds = elastic.norm();
    if !(ds > yield_curv) {
        return None;
    }
    Some(Yield { shape: plastic + elastic * ((ds - yield_curv) / ds), damage: ds / yield_curv - 1.0 })
}

/// The stiffness factor 1/(1 + w·d) of damage `d` under weakening `w` (1 when undamaged).
pub fn weakened(weakening: Real, damage: Real) -> Real {
    1.0 / (1.0 + weakening * damage)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sym(a: Real, b: Real, c: Real) -> Mat2 {
        Mat2::new(a, c, c, b)
    }

    #[test]
    fn below_or_at_the_yield_nothing_flows() {
        let p = sym(3.0, -1.0, 0.5);
        let e = sym(0.6, 0.0, 0.8); // ‖e‖_F = √(0.36 + 2·0.64) = 1.28…
        let k = e.norm();
        assert_eq!(yield_face(&(p + e), &p, k * 1.000001), None);
        assert_eq!(yield_face(&(p + e * 0.5), &p, k), None);
        assert_eq!(yield_face(&p, &p, 1e-9), None);
    }

    #[test]
    fn flow_returns_to_the_yield_surface_and_is_idempotent() {
        let k = 200.0;
        let p = sym(50.0, 0.0, 10.0);
        let s = sym(900.0, -40.0, 250.0);
        let y = yield_face(&s, &p, k).expect("far past the yield");
        assert!(((s - y.shape).norm() - k).abs() < 1e-9 * k, "{}", (s - y.shape).norm());
        // Along the elastic direction: the new elastic part is parallel to the old one.
        let (e0, e1) = (s - p, s - y.shape);
        assert!((e0 / e0.norm() - e1 / e1.norm()).norm() < 1e-12);
        assert!((y.damage - ((s - p).norm() / k - 1.0)).abs() < 1e-15);
        // At the yield surface (up to the rounding of the return) a second update does nothing
        // that matters: no flow, or a flow of rounding size.
        match yield_face(&s, &y.shape, k) {
            None => {}
            Some(again) => {
                assert!((again.shape - y.shape).norm() < 1e-12 * k, "{}", again.shape - y.shape);
                assert!(again.damage < 1e-12, "{}", again.damage);
            }
        }
    }

    #[test]
    fn flow_is_monotone_in_the_excess() {
        // More bending past the yield moves the rest shape further (never past the current
        // shape) and adds more damage.
        let k = 100.0;
        let p = Mat2::zeros();
        let dir = sym(0.8, 0.0, 0.6 / 2f64.sqrt()) / sym(0.8, 0.0, 0.6 / 2f64.sqrt()).norm();
        let mut last = Yield { shape: p, damage: 0.0 };
        for i in 1..=20 {
            let s = dir * (k * (1.0 + 0.25 * i as Real));
            let y = yield_face(&s, &p, k).unwrap();
            assert!(y.shape.norm() > last.shape.norm() && y.damage > last.damage, "step {i}");
            assert!(y.shape.norm() < s.norm(), "step {i}: past the current shape");
            assert!((y.shape.norm() - (s.norm() - k)).abs() < 1e-9, "step {i}: by the excess");
            last = y;
        }
    }

    #[test]
    fn weakening_divides_the_stiffness() {
        assert_eq!(weakened(0.0, 7.0), 1.0);
        assert_eq!(weakened(2.0, 0.0), 1.0);
        assert!((weakened(2.0, 1.5) - 0.25).abs() < 1e-15);
    }
}
