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

/// Applies friction for every contact in order (Gauss–Seidel); `h` is the step length.
pub fn apply_friction(state: &mut FrictionState, contacts: &[FrictionContact], h: Real) {
    for c in contacts {
        if c.mu <= 0.0 {
            continue;
        }
        let (mut gap, mut vrel, mut w2m) = (-c.thickness, Vec3::zeros(), 0.0);
        for j in 0..4 {
            let (x, v, im) = state.get(c.nodes[j]);
            gap += c.w[j] * c.n.dot(&x);
            vrel += c.w[j] * v;
            w2m += c.w[j] * c.w[j] * im;
        }
        if gap >= 0.0 || w2m <= 0.0 {
            continue;
        }
        // Normal velocity change from the repulsion impulse h·k·|g| this step.
        let dvn = h * c.stiffness * (-gap) * w2m;
        let vt = vrel - c.n * c.n.dot(&vrel);
        let speed = vt.norm();
        if speed == 0.0 {
            continue;
        }
        let dvt = -(c.mu * dvn / speed).min(1.0) * vt;
        let impulse = dvt / w2m;
        let n = state.x.len();
        for j in 0..4 {
            let i = c.nodes[j];
            if i < n {
                state.v[i] += c.w[j] * state.inv_mass[i] * impulse;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contact(mu: Real) -> FrictionContact {
        // Node 0 on a fixed point (index 1) with normal +z, 1 mm inside a 2 mm thickness.
        FrictionContact { nodes: [0, 1, 0, 0], w: [1.0, -1.0, 0.0, 0.0], n: Vec3::z(), thickness: 2e-3, stiffness: 1000.0, mu }
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
