//! Rigid impact zones: the last resort when an impact zone's projection has no solution
//! (Provot 1997, §4; Bridson, Fedkiw & Anderson 2002, §7.4 "rigid collisions").
//!
//! The zone's free nodes stop deforming for the step: they move by one affine map of their
//! start positions, x = x₀ + T + θ × (x₀ − c₀) (c₀ the zone's centre of mass at the start), the
//! linearised rigid motion. Its linear part I + [θ]× has singular values 1, √(1 + |θ|²),
//! √(1 + |θ|²), and so has (1 − s)I + s(I + [θ]×) = I + s[θ]× at every s along the step: no
//! distance inside the zone shrinks at any point of the step, and the zone's nodes cannot
//! cross one another however tangled the impacts that tied them were. Only the zone's
//! constraints against infinite-mass points (obstacle vertices, pinned cloth) are left; over
//! the six unknowns q = (T, θ) they are linear, and the motion is the one closest to the
//! solver's in the mass norm that satisfies them:
//!
//!   min ½ Σᵢ mᵢ |x₀ᵢ + Jᵢ q − x̃ᵢ|²   s.t.   cₖ(q) ≥ 0,   Jᵢ = [I | −[rᵢ]×],  rᵢ = x₀ᵢ − c₀,
//!
//! whose unconstrained minimiser keeps the zone's linear and (linearised) angular momentum
//! (Bridson et al.'s choice). The constrained one is found through the dual LCP, as for
//! ordinary zones (`impact_zones::solve_lcp`). A zone squeezed between infinite-mass points
//! that close in on it has no rigid solution either; it is left where it started.

use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x6, Matrix6, Vector6};

use super::impact_zones::{solve_lcp, ZoneConstraint, ZoneError, ZoneState};
use crate::math::{Real, Vec3};

/// Moves the free nodes `nodes` of a zone (cloth nodes with a positive inverse mass) rigidly
/// from their start positions `x0`, toward the positions `state.x` holds on entry (the
/// solver's), subject to the zone's constraints against infinite-mass points. On error
/// (no rigid motion satisfies them) the nodes are left at `x0`.
pub fn resolve_zone_rigid(
    state: &mut ZoneState,
    x0: &[Vec3],
    nodes: &[usize],
    cons: &[ZoneConstraint],
    tol: Real,
) -> Result<(), ZoneError> {
    let mass = |i: usize| 1.0 / state.inv_mass[i];
    let total: Real = nodes.iter().map(|&i| mass(i)).sum();
    let c0 = nodes.iter().map(|&i| mass(i) * x0[i]).sum::<Vec3>() / total;
    // Normal equations H q = g of the mass-weighted fit, H = Σ mᵢ JᵢᵀJᵢ, g = Σ mᵢ Jᵢᵀ dᵢ.
    let mut h = Matrix6::<Real>::zeros();
    let mut g = Vector6::<Real>::zeros();
    for &i in nodes {
        let j = jacobian(x0[i] - c0);
        let m = mass(i);
        h += m * j.transpose() * j;
        g += m * j.transpose() * (state.x[i] - x0[i]);
    }
    // A zone of one node, or of nodes on one line, has no rotation about that line:
    // regularise the rotational block by a 10⁻⁹ of its scale (and of the zone's extent).
    let rot_scale = (h[(3, 3)] + h[(4, 4)] + h[(5, 5)]) / 3.0;
    for k in 3..6 {
        h[(k, k)] += 1e-9 * rot_scale + 1e-12 * total;
    }
    let Some(chol) = h.cholesky() else {
        return freeze(state, x0, nodes, cons.len());
    };
    let q_free = chol.solve(&g);
    // Constraints that touch an infinite-mass point: cₖ(q) = aₖ · q + bₖ.
    let free = |i: usize| i < state.x.len() && state.inv_mass[i] > 0.0;
    let mut rows: Vec<(Vector6<Real>, Real)> = Vec::new();
    for c in cons {
        if c.nodes.iter().zip(&c.w).all(|(&i, &w)| free(i) || w == 0.0) {
            continue; // inside the zone: kept by the rigid motion itself
        }
        let (mut a, mut b) = (Vector6::zeros(), -c.delta);
        for j in 0..4 {
            let i = c.nodes[j];
            if free(i) {
                a += c.w[j] * jacobian(x0[i] - c0).transpose() * c.n;
                b += c.w[j] * c.n.dot(&x0[i]);
            } else {
                b += c.w[j] * c.n.dot(&state.pos(i));
            }
        }
        rows.push((a, b));
    }
    let q = if rows.is_empty() {
        q_free
    } else {
        // Dual: λ ≥ 0, (A H⁻¹ Aᵀ) λ + (A q* + b) ≥ 0, complementary; q = q* + H⁻¹ Aᵀ λ.
        let k = rows.len();
        let hinv_at: Vec<Vector6<Real>> = rows.iter().map(|(a, _)| chol.solve(a)).collect();
        let qm = DMatrix::from_fn(k, k, |r, s| rows[r].0.dot(&hinv_at[s]));
        let cv = DVector::from_fn(k, |r, _| rows[r].0.dot(&q_free) + rows[r].1);
        let Some(lambda) = solve_lcp(&qm, &cv, tol) else {
            return freeze(state, x0, nodes, cons.len());
        };
        hinv_at.iter().zip(lambda.iter()).fold(q_free, |q, (d, &l)| q + l * d)
    };
    let (t, theta) = (Vec3::new(q[0], q[1], q[2]), Vec3::new(q[3], q[4], q[5]));
    for &i in nodes {
        let r = x0[i] - c0;
        state.x[i] = x0[i] + t + theta.cross(&r);
    }
    Ok(())
}

/// ∂x/∂q for a node at offset `r` from the centre: [I | −[r]×] (θ × r = −r × θ).
fn jacobian(r: Vec3) -> Matrix3x6<Real> {
    let cross = Matrix3::new(0.0, -r.z, r.y, r.z, 0.0, -r.x, -r.y, r.x, 0.0);
    let mut j = Matrix3x6::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
    j.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-cross));
    j
}

fn freeze(state: &mut ZoneState, x0: &[Vec3], nodes: &[usize], constraints: usize) -> Result<(), ZoneError> {
    for &i in nodes {
        state.x[i] = x0[i];
    }
    Err(ZoneError::Infeasible { constraints })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_free_zone_keeps_its_momentum_and_its_shape() {
        // Two nodes of masses 1 and 3 whose solved motions would pass through each other.
        let x0 = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        let mut x = vec![Vec3::new(2.0, 0.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)];
        let inv_mass = [1.0, 1.0 / 3.0];
        let mut st = ZoneState { x: &mut x, inv_mass: &inv_mass, fixed: &[] };
        resolve_zone_rigid(&mut st, &x0, &[0, 1], &[], 1e-12).unwrap();
        // Linear momentum: 1·2 + 3·(−2) = −4 over a mass of 4 → both move by −1 along x.
        assert!((x[0] - Vec3::new(-1.0, 0.0, 0.0)).norm() < 1e-9, "{:?}", x[0]);
        assert!((x[1] - Vec3::new(0.0, 0.0, 0.0)).norm() < 1e-9, "{:?}", x[1]);
    }

    #[test]
    fn a_spinning_zone_turns_without_shrinking() {
        // Four nodes in a square whose solved motion is a quarter of a small turn about z.
        let x0: Vec<Vec3> =
            [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)].iter().map(|&(a, b)| Vec3::new(a, b, 0.0)).collect();
        let w = 0.01;
        let mut x: Vec<Vec3> = x0.iter().map(|p| p + w * Vec3::z().cross(p)).collect();
        let inv_mass = [1.0; 4];
        let mut st = ZoneState { x: &mut x, inv_mass: &inv_mass, fixed: &[] };
        resolve_zone_rigid(&mut st, &x0, &[0, 1, 2, 3], &[], 1e-12).unwrap();
        for (a, b) in x.iter().zip(&x0) {
            assert!((a - (b + w * Vec3::z().cross(b))).norm() < 1e-9);
        }
        for a in 0..4 {
            for b in 0..4 {
                assert!((x[a] - x[b]).norm() >= (x0[a] - x0[b]).norm() - 1e-15);
            }
        }
    }

    #[test]
    fn a_zone_on_a_floor_moves_with_the_solver_but_stays_above_it() {
        // Two nodes resting on a fixed triangle at z = 0 whose solved motion sinks and slides.
        let x0 = vec![Vec3::new(0.1, 0.1, 1e-3), Vec3::new(0.2, 0.1, 1e-3)];
        let mut x = vec![Vec3::new(0.15, 0.1, -2e-3), Vec3::new(0.25, 0.1, -2e-3)];
        let fixed = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let inv_mass = [1.0, 1.0];
        let con = |i| ZoneConstraint { nodes: [i, 2, 3, 4], w: [1.0, -0.8, -0.1, -0.1], n: Vec3::z(), delta: 4e-4 };
        let mut st = ZoneState { x: &mut x, inv_mass: &inv_mass, fixed: &fixed };
        resolve_zone_rigid(&mut st, &x0, &[0, 1], &[con(0), con(1)], 1e-12).unwrap();
        for i in 0..2 {
            assert!(x[i].z >= 4e-4 - 1e-12, "{:?}", x[i]);
            assert!((x[i].x - x0[i].x - 0.05).abs() < 1e-6, "slides with the solver: {:?}", x[i]);
        }
        assert!(((x[0] - x[1]).norm() - 0.1).abs() < 1e-9);
    }

    #[test]
    fn a_zone_squeezed_between_closing_points_stays_where_it_started() {
        // One node between two fixed points 1 mm apart that ask for 2 mm on either side.
        let x0 = vec![Vec3::zeros()];
        let mut x = vec![Vec3::new(0.0, 0.0, 0.0)];
        let fixed = [Vec3::new(0.0, 0.0, -5e-4), Vec3::new(0.0, 0.0, 5e-4)];
        let inv_mass = [1.0];
        let below = ZoneConstraint { nodes: [0, 1, 0, 0], w: [1.0, -1.0, 0.0, 0.0], n: Vec3::z(), delta: 2e-3 };
        let above = ZoneConstraint { nodes: [0, 2, 0, 0], w: [1.0, -1.0, 0.0, 0.0], n: -Vec3::z(), delta: 2e-3 };
        let mut st = ZoneState { x: &mut x, inv_mass: &inv_mass, fixed: &fixed };
        assert!(resolve_zone_rigid(&mut st, &x0, &[0], &[below, above], 1e-12).is_err());
        assert_eq!(x[0], x0[0]);
    }
}
