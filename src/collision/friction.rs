//! Coulomb friction as a velocity filter after the implicit solve (Bridson, Fedkiw & Anderson
//! 2002, §7.2): the relative tangential velocity of each contact is reduced by μ times the
//! normal velocity change its repulsion produced this step, and set to zero when that is enough
//! (static friction). Contacts act on the generalised relative velocity v_rel = Σ wᵢ vᵢ, so the
//! same rule serves node–face and edge–edge, cloth–obstacle and cloth–cloth; an impulse J along
//! the contact changes vᵢ by wᵢ J / mᵢ (obstacles and pinned nodes have 1/m = 0).

use crate::math::{Real, Vec3};

/// The part of a repulsion contact friction needs: participants (cloth nodes below the cloth
/// node count, fixed points above), weights, normal, gap offset and stiffness.
#[derive(Clone, Copy, Debug)]
pub struct FrictionContact {
    pub nodes: [usize; 4],
    pub w: [Real; 4],
    pub n: Vec3,
    pub thickness: Real,
    pub stiffness: Real,
    pub mu: Real,
}

pub struct FrictionState<'a> {
    pub x: &'a [Vec3],
    pub v: &'a mut [Vec3],
    pub inv_mass: &'a [Real],
    /// Positions and velocities of fixed points (index − cloth node count).
    pub fixed_x: &'a [Vec3],
    pub fixed_v: &'a [Vec3],
}

impl FrictionState<'_> {
    fn get(&self, i: usize) -> (Vec3, Vec3, Real) {
        let n = self.x.len();
        if i < n {
            (self.x[i], self.v[i], self.inv_mass[i])
        } else {
            (self.fixed_x[i - n], self.fixed_v[i - n], 0.0)
        }
    }
}

/// Applies friction for every contact (Jacobi): each contact's impulse is computed from the
/// velocities as they come out of the solve, and a node in several contacts takes the mean of
/// the velocity changes of the contacts that act on it. Applying the contacts one after the other
/// (Gauss–Seidel) instead lets a node caught by several contacts, e.g. cloth folded over an
/// obstacle's edge, be stopped once per contact and thrown backwards; the mean never exceeds the
/// largest single change. `h` is the step length.
pub fn apply_friction(state: &mut FrictionState, contacts: &[FrictionContact], h: Real) {
    let n = state.x.len();
    let mut dv = vec![Vec3::zeros(); n];
    let mut count = vec![0u32; n];
    for c in contacts {
        let Some(impulse) = friction_impulse(state, c, h) else { continue };
        for j in 0..4 {
            let i = c.nodes[j];
            if i < n && state.inv_mass[i] > 0.0 && c.w[j] != 0.0 {
                dv[i] += c.w[j] * state.inv_mass[i] * impulse;
                count[i] += 1;
            }
        }
    }
    for i in 0..n {
        if count[i] > 0 {
            state.v[i] += dv[i] / count[i] as Real;
        }
    }
}

/// The friction impulse of one contact along its generalised relative velocity, `None` when it
/// is not compressed, has no moving node or does not slide.
fn friction_impulse(state: &FrictionState, c: &FrictionContact, h: Real) -> Option<Vec3> {
    if c.mu <= 0.0 {
        return None;
    }
    let (mut gap, mut vrel, mut w2m) = (-c.thickness, Vec3::zeros(), 0.0);
    for j in 0..4 {
        let (x, v, im) = state.get(c.nodes[j]);
        gap += c.w[j] * c.n.dot(&x);
        vrel += c.w[j] * v;
        w2m += c.w[j] * c.w[j] * im;
    }
    if gap >= 0.0 || w2m <= 0.0 {
        return None;
    }
    // Normal velocity change from the repulsion impulse h·k·|g| this step.
    let dvn = h * c.stiffness * (-gap) * w2m;
    let vt = vrel - c.n * c.n.dot(&vrel);
    let speed = vt.norm();
    if speed == 0.0 {
        return None;
    }
    let dvt = -(c.mu * dvn / speed).min(1.0) * vt;
    Some(dvt / w2m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contact(mu: Real) -> FrictionContact {
        // Node 0 on a fixed point (index 1) with normal +z, 1 mm inside a 2 mm thickness.
        FrictionContact {
            nodes: [0, 1, 0, 0],
            w: [1.0, -1.0, 0.0, 0.0],
            n: Vec3::z(),
            thickness: 2e-3,
            stiffness: 1000.0,
            mu,
        }
    }

    #[test]
    fn static_friction_stops_slow_sliding_and_kinetic_friction_slows_fast() {
        let x = [Vec3::new(0.0, 0.0, 1e-3)];
        let fixed_x = [Vec3::zeros()];
        let fixed_v = [Vec3::zeros()];
        let inv_mass = [1.0];
        // Normal Δv = h k |g| / m = 0.01 · 1000 · 1e-3 = 0.01 m/s; μ = 0.5 → 0.005 m/s.
        let mut v = [Vec3::new(0.004, 0.0, 0.0)];
        let mut s = FrictionState { x: &x, v: &mut v, inv_mass: &inv_mass, fixed_x: &fixed_x, fixed_v: &fixed_v };
        apply_friction(&mut s, &[contact(0.5)], 0.01);
        assert_eq!(v[0], Vec3::zeros());
        let mut v = [Vec3::new(0.1, 0.0, 0.02)];
        let mut s = FrictionState { x: &x, v: &mut v, inv_mass: &inv_mass, fixed_x: &fixed_x, fixed_v: &fixed_v };
        apply_friction(&mut s, &[contact(0.5)], 0.01);
        assert!((v[0].x - 0.095).abs() < 1e-12 && v[0].z == 0.02);
    }

    /// Regression (skirt_mannequin, tablecloth_pull: strain up to 0.8 where folds slid over legs
    /// and table edges): a node in two contacts took both velocity changes one after the other
    /// and was thrown backwards; it now takes their mean.
    #[test]
    fn node_in_two_contacts_takes_the_mean_change_not_both() {
        // Cloth edges 0–1 and 1–2 slide at 7 m/s along −x over a fixed edge (points 3, 4), pressed
        // hard enough for static friction; node 1 carries most of both contacts.
        let x = [Vec3::new(0.0, 0.0, 1e-3); 3];
        let (fixed_x, fixed_v) = ([Vec3::zeros(); 2], [Vec3::zeros(); 2]);
        let edge = |nodes: [usize; 4], w: [Real; 4]| FrictionContact {
            nodes,
            w,
            n: Vec3::z(),
            thickness: 2e-3,
            stiffness: 1e7,
            mu: 0.5,
        };
        let contacts = [edge([0, 1, 3, 4], [0.2, 0.8, -0.5, -0.5]), edge([1, 2, 3, 4], [0.76, 0.24, -0.5, -0.5])];
        let mut v = [Vec3::new(-7.0, 0.0, 0.0); 3];
        let mut s = FrictionState { x: &x, v: &mut v, inv_mass: &[1.0; 3], fixed_x: &fixed_x, fixed_v: &fixed_v };
        apply_friction(&mut s, &contacts, 0.01);
        // Each contact alone stops its edge point: node 1 changes by 0.8 · 7 / 0.68 and by
        // 0.76 · 7 / 0.6352 (least-norm impulses); one after the other they would add up to 9.1.
        let (d1, d2) = (0.8 * 7.0 / 0.68, 0.76 * 7.0 / (0.76 * 0.76 + 0.24 * 0.24));
        assert!((v[1].x - (-7.0 + 0.5 * (d1 + d2))).abs() < 1e-12, "{}", v[1].x);
        assert!((v[0].x - (-7.0 + 0.2 * 7.0 / 0.68)).abs() < 1e-12);
    }

    #[test]
    fn friction_is_relative_to_a_moving_obstacle() {
        let x = [Vec3::new(0.0, 0.0, 1e-3)];
        let (fixed_x, fixed_v) = ([Vec3::zeros()], [Vec3::new(1.0, 0.0, 0.0)]);
        let mut v = [Vec3::new(0.998, 0.0, 0.0)];
        let mut s = FrictionState { x: &x, v: &mut v, inv_mass: &[1.0], fixed_x: &fixed_x, fixed_v: &fixed_v };
        apply_friction(&mut s, &[contact(0.5)], 0.01);
        assert!((v[0].x - 1.0).abs() < 1e-15);
    }
}
