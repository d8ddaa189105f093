//! Impact zones (Harmon, Vouga, Tamstorf & Grinspun 2008, as in ARCSim): the fail-safe that
//! makes the end-of-step positions collision-free.
//!
//! Each zone is a set of nodes tied together by impacts. Its positions are projected, with the
//! least mass-weighted change, onto the set where every impact's linearised gap is at least
//! its separation δ (an inelastic projection: momentum along the impact normals is shared):
//!
//!   min ½ Σᵢ mᵢ |xᵢ − x̃ᵢ|²   s.t.   cₖ(x) = nₖ · Σⱼ wₖⱼ xⱼ − δₖ ≥ 0.
//!
//! Obstacle nodes and pinned cloth nodes have infinite mass and do not move. The QP is solved
//! exactly through its dual, an LCP in the impulses λ ≥ 0: x = x̃ + M⁻¹Aᵀλ, c(λ) = c̃ + Qλ with
//! Q = A M⁻¹ Aᵀ, by a Lawson–Hanson active-set method.

use nalgebra::{DMatrix, DVector};

use crate::math::{Real, Vec3};

/// A linearised non-penetration constraint: `n · Σ w[j] x[nodes[j]] ≥ delta`. Node indices below
/// the cloth node count are cloth nodes; the others are fixed (obstacle) points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZoneConstraint {
    pub nodes: [usize; 4],
    pub w: [Real; 4],
    pub n: Vec3,
    pub delta: Real,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ZoneError {
    #[error("impact zone with {constraints} constraints has no collision-free solution (all its nodes are fixed or constraints conflict)")]
    Infeasible { constraints: usize },
}

/// Positions of cloth nodes (mutable) and of fixed points.
pub struct ZoneState<'a> {
    pub x: &'a mut [Vec3],
    /// Inverse masses of cloth nodes (0 for pinned nodes).
    pub inv_mass: &'a [Real],
    /// Positions of fixed points; constraint index `i ≥ x.len()` means `fixed[i − x.len()]`.
    pub fixed: &'a [Vec3],
}

impl ZoneState<'_> {
    pub(super) fn pos(&self, i: usize) -> Vec3 {
        if i < self.x.len() {
            self.x[i]
        } else {
            self.fixed[i - self.x.len()]
        }
    }

    fn inv_mass_of(&self, i: usize) -> Real {
        if i < self.x.len() {
            self.inv_mass[i]
        } else {
            0.0
        }
    }

    /// Current value of a constraint.
    pub fn value(&self, c: &ZoneConstraint) -> Real {
        let mut s = 0.0;
        for j in 0..4 {
            s += c.w[j] * c.n.dot(&self.pos(c.nodes[j]));
        }
        s - c.delta
    }
}

/// Zones with more constraints than this are solved iteratively (`resolve_zone_iterative`): the
/// exact active-set solve refactors a dense k × k matrix per step and grows like k⁴.
pub const DENSE_ZONE_LIMIT: usize = 64;

/// Projects the zone's nodes so that every constraint holds (to `tol`).
pub fn resolve_zone(state: &mut ZoneState, cons: &[ZoneConstraint], tol: Real) -> Result<(), ZoneError> {
    let k = cons.len();
    if k > DENSE_ZONE_LIMIT {
        return resolve_zone_iterative(state, cons, tol);
    }
    let mut q = DMatrix::<Real>::zeros(k, k);
    let c0 = DVector::from_fn(k, |a, _| state.value(&cons[a]));
    if c0.iter().all(|&v| v >= -tol) {
        return Ok(());
    }
    for a in 0..k {
        for b in a..k {
            let mut s = 0.0;
            for i in 0..4 {
                for j in 0..4 {
                    if cons[a].nodes[i] == cons[b].nodes[j] {
                        s += cons[a].w[i] * cons[b].w[j] * state.inv_mass_of(cons[a].nodes[i]);
                    }
                }
            }
            let v = s * cons[a].n.dot(&cons[b].n);
            q[(a, b)] = v;
            q[(b, a)] = v;
        }
    }
    let lambda = solve_lcp(&q, &c0, tol).ok_or(ZoneError::Infeasible { constraints: k })?;
    for (a, con) in cons.iter().enumerate() {
        if lambda[a] == 0.0 {
            continue;
        }
        for j in 0..4 {
            let i = con.nodes[j];
            if i < state.x.len() && state.inv_mass[i] > 0.0 {
                state.x[i] += lambda[a] * con.w[j] * state.inv_mass[i] * con.n;
            }
        }
    }
    Ok(())
}

/// The same projection for large zones, by projected Gauss–Seidel on the dual LCP carried out in
/// the primal variables: for each constraint in turn, λₐ ← max(0, λₐ − cₐ(x)/Qₐₐ) and the nodes
/// move by M⁻¹Aₐᵀ Δλₐ, so each update costs O(1) whatever the zone's size. Sweeps until every
/// constraint holds to max(`tol`, 10⁻³ δ) — a thousandth of the separation it asks for, which
/// leaves the gap continuous collision detection needs. Conflicting constraints make the
/// iterates cycle or grow instead of converging: a zone whose nodes move by more than 100 times
/// its largest violation, or still short of δ/2 on some constraint at the sweep cap, is restored
/// and reported infeasible, as the exact solver would.
pub fn resolve_zone_iterative(state: &mut ZoneState, cons: &[ZoneConstraint], tol: Real) -> Result<(), ZoneError> {
    const MAX_SWEEPS: usize = 2_000;
    let n = state.x.len();
    let diag: Vec<Real> = cons
        .iter()
        .map(|c| {
            // Qₐₐ = Σᵢ (Σ_{j: nodes[j] = i} w_j)² / mᵢ over distinct nodes.
            let mut q = 0.0;
            for j in 0..4 {
                let i = c.nodes[j];
                if (0..j).any(|k| c.nodes[k] == i) {
                    continue;
                }
                let w: Real = (j..4).filter(|&k| c.nodes[k] == i).map(|k| c.w[k]).sum();
                q += w * w * state.inv_mass_of(i);
            }
            q
        })
        .collect();
    let scale = diag.iter().copied().fold(0.0, Real::max).max(1e-300);
    let accept: Vec<Real> = cons.iter().map(|c| tol.max(1e-3 * c.delta)).collect();
    if cons.iter().zip(&diag).any(|(c, &q)| q <= 1e-12 * scale && state.value(c) < -tol) {
        return Err(ZoneError::Infeasible { constraints: cons.len() });
    }
    let mut lambda = vec![0.0; cons.len()];
    let mut nodes: Vec<usize> = cons.iter().flat_map(|c| c.nodes).filter(|&i| i < n).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let start: Vec<Vec3> = nodes.iter().map(|&i| state.x[i]).collect();
    let violation = cons.iter().map(|c| -state.value(c)).fold(0.0, Real::max);
    let bound = 100.0 * violation;
    for _ in 0..MAX_SWEEPS {
        let mut worst: Real = 0.0;
        for (a, c) in cons.iter().enumerate() {
            let v = state.value(c);
            worst = worst.max(-v - accept[a]);
            if diag[a] <= 1e-12 * scale {
                continue;
            }
            let step = (-v / diag[a]).max(-lambda[a]);
            if step == 0.0 {
                continue;
            }
            lambda[a] += step;
            for j in 0..4 {
                let i = c.nodes[j];
                if i < n && state.inv_mass[i] > 0.0 {
                    state.x[i] += step * c.w[j] * state.inv_mass[i] * c.n;
                }
            }
        }
        if worst <= 0.0 {
            return Ok(());
        }
        if nodes.iter().zip(&start).any(|(&i, x0)| (state.x[i] - x0).norm() > bound) {
            break;
        }
    }
    // Slow convergence is not infeasibility: PGS on nearly parallel constraints can stall a
    // few µm short of 10⁻³ δ. An iterate that keeps every gap at least δ/2 and moved no node
    // beyond the bound is still a collision-free projection (the CCD loop re-checks it);
    // restoring the zone would instead leave all its collisions in place.
    let within = nodes.iter().zip(&start).all(|(&i, x0)| (state.x[i] - x0).norm() <= bound);
    if within && cons.iter().all(|c| state.value(c) >= -0.5 * c.delta) {
        return Ok(());
    }
    for (&i, x0) in nodes.iter().zip(&start) {
        state.x[i] = *x0;
    }
    Err(ZoneError::Infeasible { constraints: cons.len() })
}

/// Solves the LCP  λ ≥ 0,  Qλ + c ≥ 0,  λᵀ(Qλ + c) = 0  for PSD Q (min ½λᵀQλ + cᵀλ over λ ≥ 0)
/// by the Lawson–Hanson active-set method. `None` if no λ satisfies Qλ + c ≥ −tol.
pub fn solve_lcp(q: &DMatrix<Real>, c: &DVector<Real>, tol: Real) -> Option<DVector<Real>> {
    let k = c.len();
    let mut lambda = DVector::<Real>::zeros(k);
    let mut passive = vec![false; k];
    let scale = (0..k).map(|i| q[(i, i)]).fold(0.0, Real::max).max(1e-300);
    let reg = 1e-12 * scale;
    for _ in 0..(3 * k + 10) {
        let w = q * &lambda + c;
        let Some(t) =
            (0..k).filter(|&i| !passive[i] && w[i] < -tol).min_by(|&a, &b| w[a].total_cmp(&w[b]).then(a.cmp(&b)))
        else {
            break; // every violated constraint is passive: feasible unless Q is singular on them
        };
        if q[(t, t)] <= reg {
            // A violated constraint that no free node can move: infeasible.
            return None;
        }
        passive[t] = true;
        for _ in 0..(3 * k + 10) {
            let p: Vec<usize> = (0..k).filter(|&i| passive[i]).collect();
            let qp = DMatrix::from_fn(p.len(), p.len(), |a, b| q[(p[a], p[b])] + if a == b { reg } else { 0.0 });
            let rhs = DVector::from_fn(p.len(), |a, _| -c[p[a]]);
            let z = match qp.clone().cholesky() {
                Some(ch) => ch.solve(&rhs),
                None => qp.lu().solve(&rhs)?,
            };
            if z.iter().all(|&v| v > 0.0) {
                for (a, &i) in p.iter().enumerate() {
                    lambda[i] = z[a];
                }
                break;
            }
            // Step toward z until the first passive λ hits zero, then drop the zeros.
            let mut alpha: Real = 1.0;
            for (a, &i) in p.iter().enumerate() {
                if z[a] <= 0.0 {
                    let denom = lambda[i] - z[a];
                    if denom > 0.0 {
                        alpha = alpha.min(lambda[i] / denom);
                    }
                }
            }
            for (a, &i) in p.iter().enumerate() {
                lambda[i] += alpha * (z[a] - lambda[i]);
                if lambda[i] <= 1e-300 || (z[a] <= 0.0 && (lambda[i]).abs() <= 1e-14 * scale) {
                    lambda[i] = 0.0;
                    passive[i] = false;
                }
            }
            if !passive.iter().any(|&b| b) {
                break;
            }
        }
    }
    // The regularisation leaves the passive constraints short by reg·λ, about 10⁻¹² of their
    // violation; a constraint that no λ can satisfy stays short by all of it.
    let slack = tol + 1e-9 * c.iter().fold(0.0, |m: Real, v| m.max(-v));
    let w = q * &lambda + c;
    w.iter().all(|&v| v >= -slack).then_some(lambda)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lcp_matches_known_solution() {
        // Two constraints sharing one node: Q = [[2,1],[1,2]], c = [-1, 0.2].
        let q = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
        let c = DVector::from_vec(vec![-1.0, 0.2]);
        let l = solve_lcp(&q, &c, 1e-12).unwrap();
        assert!((l[0] - 0.5).abs() < 1e-12 && l[1] == 0.0, "{l}");
        let w = &q * &l + &c;
        assert!(w.iter().all(|&v| v > -1e-12));
    }

    #[test]
    fn point_below_fixed_triangle_is_lifted_with_least_motion() {
        // Node 0 (cloth) is 1 cm below a fixed triangle at z = 0; constraint: z ≥ 1 mm.
        let mut x = vec![Vec3::new(0.2, 0.2, -0.01), Vec3::new(5.0, 0.0, 0.0)];
        let fixed = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let inv_mass = [1.0, 1.0];
        let con = ZoneConstraint { nodes: [0, 2, 3, 4], w: [1.0, -0.6, -0.2, -0.2], n: Vec3::z(), delta: 1e-3 };
        let mut st = ZoneState { x: &mut x, inv_mass: &inv_mass, fixed: &fixed };
        resolve_zone(&mut st, &[con], 1e-12).unwrap();
        assert!((x[0] - Vec3::new(0.2, 0.2, 1e-3)).norm() < 1e-12);
        assert_eq!(x[1], Vec3::new(5.0, 0.0, 0.0));
    }

    #[test]
    fn cloth_cloth_impact_shares_the_correction_by_mass() {
        // Node 0 (mass 1) must be 2 mm above node 1 (mass 3) along z; they are level.
        let mut x = vec![Vec3::zeros(), Vec3::zeros()];
        let inv_mass = [1.0, 1.0 / 3.0];
        let con = ZoneConstraint { nodes: [0, 1, 0, 0], w: [1.0, -1.0, 0.0, 0.0], n: Vec3::z(), delta: 2e-3 };
        let mut st = ZoneState { x: &mut x, inv_mass: &inv_mass, fixed: &[] };
        resolve_zone(&mut st, &[con], 1e-15).unwrap();
        assert!((x[0].z - 1.5e-3).abs() < 1e-12 && (x[1].z + 0.5e-3).abs() < 1e-12);
        // Momentum along the normal is conserved.
        assert!((x[0].z * 1.0 + x[1].z * 3.0).abs() < 1e-15);
    }

    #[test]
    fn fixed_nodes_only_is_infeasible() {
        let mut x = vec![Vec3::zeros()];
        let con = ZoneConstraint { nodes: [0, 0, 0, 0], w: [1.0, 0.0, 0.0, 0.0], n: Vec3::z(), delta: 1.0 };
        let mut st = ZoneState { x: &mut x, inv_mass: &[0.0], fixed: &[] };
        assert!(resolve_zone(&mut st, &[con], 1e-12).is_err());
    }

    #[test]
    fn large_zone_is_solved_iteratively_close_to_the_exact_projection() {
        // A row of nodes under a fixed plane, with two constraints each (a large zone).
        let n = 60;
        let fixed = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(100.0, 0.0, 0.0), Vec3::new(0.0, 100.0, 0.0)];
        let x0: Vec<Vec3> = (0..n).map(|i| Vec3::new(0.1 + 0.01 * i as Real, 0.2, -0.01 - 1e-4 * i as Real)).collect();
        let inv_mass = vec![1.0; n];
        let mut cons = Vec::new();
        for i in 0..n {
            cons.push(ZoneConstraint {
                nodes: [i, n, n + 1, n + 2],
                w: [1.0, -0.5, -0.25, -0.25],
                n: Vec3::z(),
                delta: 1e-3,
            });
            if i + 1 < n {
                let nz = Vec3::new(0.0, 0.6, 0.8);
                cons.push(ZoneConstraint { nodes: [i, i + 1, i, i], w: [1.0, -1.0, 0.0, 0.0], n: nz, delta: -1.0 });
            }
        }
        assert!(cons.len() > DENSE_ZONE_LIMIT);
        let mut x = x0.clone();
        let mut st = ZoneState { x: &mut x, inv_mass: &inv_mass, fixed: &fixed };
        resolve_zone(&mut st, &cons, 1e-12).unwrap();
        for c in &cons {
            assert!(st.value(c) >= -1e-3 * c.delta.abs() - 1e-12, "{}", st.value(c));
        }
        // The least-motion answer lifts each node straight up to z = δ.
        for (p, q) in x.iter().zip(&x0) {
            assert!((p - Vec3::new(q.x, q.y, 1e-3)).norm() < 2e-6, "{p} from {q}");
        }
    }

    #[test]
    fn conflicting_large_zone_is_infeasible_and_left_unchanged() {
        // One node asked to be both ≥ 1 cm above and ≥ 1 cm below a fixed point, many times over.
        let mut x = vec![Vec3::zeros()];
        let up = ZoneConstraint { nodes: [0, 1, 0, 0], w: [1.0, -1.0, 0.0, 0.0], n: Vec3::z(), delta: 0.01 };
        let down = ZoneConstraint { n: -Vec3::z(), ..up };
        let cons: Vec<ZoneConstraint> = (0..40).flat_map(|_| [up, down]).collect();
        assert!(cons.len() > DENSE_ZONE_LIMIT);
        let mut st = ZoneState { x: &mut x, inv_mass: &[1.0], fixed: &[Vec3::zeros()] };
        assert!(resolve_zone(&mut st, &cons, 1e-12).is_err());
        assert_eq!(x[0], Vec3::zeros());
    }

    #[test]
    fn many_random_constraints_are_satisfied() {
        let mut s = 7u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let n = 12;
        let mut x: Vec<Vec3> = (0..n).map(|_| Vec3::new(rnd(), rnd(), rnd())).collect();
        let inv_mass: Vec<Real> = (0..n).map(|_| 1.0 / (0.5 + rnd().abs())).collect();
        let mut cons = Vec::new();
        for _ in 0..20 {
            let a = ((rnd() + 0.5) * n as f64) as usize % n;
            let b = ((rnd() + 0.5) * n as f64) as usize % n;
            if a == b {
                continue;
            }
            let nrm = Vec3::new(rnd(), rnd(), rnd()).normalize();
            cons.push(ZoneConstraint { nodes: [a, b, a, a], w: [1.0, -1.0, 0.0, 0.0], n: nrm, delta: 0.01 });
        }
        let mut st = ZoneState { x: &mut x, inv_mass: &inv_mass, fixed: &[] };
        resolve_zone(&mut st, &cons, 1e-10).unwrap();
        for c in &cons {
            assert!(st.value(c) >= -1e-9, "{}", st.value(c));
        }
    }
}
