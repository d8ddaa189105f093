//! Dihedral-angle bending on interior edges (Grinspun et al. 2003, Bridson et al. 2003).
//!
//! ψ = ½ k_b · 3|ē|²/(Ā₁+Ā₂) · (θ − θ̄)², the discrete form of ½ k_b ∫ (κ − κ̄)² dA with
//! κ ≈ θ/h, h = (Ā₁+Ā₂)/(3|ē|); |ē| and Āᵢ are material-space lengths and areas, k_b in N·m.
//! Hinge: edge x₀–x₁, x₂ opposite in face 1, x₃ opposite in face 2.

use crate::math::dual::{Dual, Num, V3};
use crate::math::{Mat12, Real, Vec12, Vec3};

use super::Projection;

/// Per-edge rest data.
#[derive(Clone, Copy, Debug)]
pub struct BendingRest {
    /// 3|ē|²/(Ā₁+Ā₂), dimensionless.
    pub shape: Real,
    /// Rest dihedral angle θ̄ (radians).
    pub theta0: Real,
}

/// Signed dihedral angle θ of the hinge: the rotation from n₁ to n₂ about the edge direction,
/// with n₁ = e × (x₂ − x₀), n₂ = (x₃ − x₀) × e. Zero when flat.
pub fn dihedral_angle<T: Num>(x: &[V3<T>; 4]) -> T {
    let e = x[1].sub(x[0]);
    let n1 = e.cross(x[2].sub(x[0]));
    let n2 = x[3].sub(x[0]).cross(e);
    let le = e.dot(e).sqrt();
    let sin = n1.cross(n2).dot(e) / le;
    let cos = n1.dot(n2);
    sin.atan2(cos)
}

/// The dihedral angle `theta` taken within π of `reference` (a multiple of 2π added): a hinge
/// folded past ±π, as a flattened crease is, stays on the side of its rest angle instead of
/// jumping to the other (ARCSim's `unwrap_angle` about the edge's reference angle). The same
/// value when |θ − reference| ≤ π, so a flat rest shape is untouched.
pub fn unwrap_angle(theta: Real, reference: Real) -> Real {
    use std::f64::consts::PI;
    if theta - reference > PI {
        theta - 2.0 * PI
    } else if theta - reference < -PI {
        theta + 2.0 * PI
    } else {
        theta
    }
}

/// ∂θ/∂x (Bridson et al. 2003, eqs. 4–7): the wing vertices move along their face normals with
/// magnitude 1/height; the edge vertices take the rest so that translations and rotations leave
/// θ unchanged.
pub fn dihedral_gradient<T: Num>(x: &[V3<T>; 4]) -> [V3<T>; 4] {
    let e = x[1].sub(x[0]);
    let n1 = e.cross(x[2].sub(x[0]));
    let n2 = x[3].sub(x[0]).cross(e);
    let le2 = e.dot(e);
    let le = le2.sqrt();
    let g2 = n1.scale(-le / n1.dot(n1));
    let g3 = n2.scale(-le / n2.dot(n2));
    let t2 = x[2].sub(x[0]).dot(e) / le2;
    let t3 = x[3].sub(x[0]).dot(e) / le2;
    let one = T::cst(1.0);
    let g0 = g2.scale(-(one - t2)).add(g3.scale(-(one - t3)));
    let g1 = g2.scale(-t2).add(g3.scale(-t3));
    [g0, g1, g2, g3]
}

fn to_v3(x: &[Vec3; 4]) -> [V3<f64>; 4] {
    x.map(|p| V3([p.x, p.y, p.z]))
}

/// ∂²θ/∂x², exact, by forward-mode differentiation of `dihedral_gradient`.
pub fn dihedral_hessian(x: &[Vec3; 4]) -> Mat12 {
    let xd: [V3<Dual<12>>; 4] = std::array::from_fn(|i| V3(std::array::from_fn(|d| Dual::var(x[i][d], 3 * i + d))));
    let g = dihedral_gradient(&xd);
    Mat12::from_fn(|r, c| g[r / 3].0[r % 3].eps[c])
}

/// c, θ − θ̄ and the energy c (θ − θ̄)² of one hinge: the part of `bending` that
/// `bending_energy` shares.
#[inline]
fn bent(xv: &[V3<f64>; 4], rest: &BendingRest, kb: Real) -> (Real, Real, Real) {
    let theta = unwrap_angle(dihedral_angle(xv), rest.theta0);
    let c = 0.5 * kb * rest.shape;
    let d = theta - rest.theta0;
    (c, d, c * d * d)
}

/// The energy of one hinge alone, bit for bit `bending`'s (issue 17 item 3).
pub fn bending_energy(x: &[Vec3; 4], rest: &BendingRest, kb: Real) -> Real {
    bent(&to_v3(x), rest, kb).2
}

/// Energy, gradient and Hessian of one hinge; `kb` is the bending stiffness (N·m).
pub fn bending(x: &[Vec3; 4], rest: &BendingRest, kb: Real, proj: Projection) -> (Real, Vec12, Mat12) {
    let xv = to_v3(x);
    let (c, d, energy) = bent(&xv, rest, kb);
    let g = dihedral_gradient(&xv);
    let grad_theta = Vec12::from_fn(|r, _| g[r / 3].0[r % 3]);
    let grad = 2.0 * c * d * grad_theta;
    if proj == Projection::Gradient {
        return (energy, grad, Mat12::zeros());
    }
    // Gauss–Newton form 2c ∇θ∇θᵀ is PSD; the exact Hessian adds 2c (θ − θ̄) ∇²θ.
    let mut hess = 2.0 * c * grad_theta * grad_theta.transpose();
    if proj == Projection::Exact {
        hess += 2.0 * c * d * dihedral_hessian(x);
    }
    (energy, grad, hess)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hinge of unit edge along x whose second wing is turned by `phi` from flat (θ = φ,
    /// wrapped into (−π, π]).
    fn hinge(phi: Real) -> [Vec3; 4] {
        [Vec3::zeros(), Vec3::x(), Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.5, -phi.cos(), -phi.sin())]
    }

    #[test]
    fn a_crease_folded_past_flat_stays_on_its_rest_side() {
        // Rest angle 3 rad; folded to 3.2 rad, atan2 reads 3.2 − 2π, and the hinge must cost
        // (0.2)², not (6.08)², and push back the way it pushes when short of its rest angle.
        let x = hinge(3.2);
        assert!((dihedral_angle(&to_v3(&x)) - (3.2 - 2.0 * std::f64::consts::PI)).abs() < 1e-12);
        let rest = BendingRest { shape: 1.0, theta0: 3.0 };
        let (e, g, _) = bending(&x, &rest, 2.0, Projection::Psd);
        assert!((e - 0.2 * 0.2).abs() < 1e-12, "{e}");
        let (_, g_short, _) = bending(&hinge(2.9), &rest, 2.0, Projection::Psd);
        assert!(g.dot(&g_short) < 0.0, "past and short of the rest angle, the forces must oppose");
        // Within π of the rest angle nothing changes.
        assert_eq!(unwrap_angle(1.0, 0.0), 1.0);
        assert_eq!(unwrap_angle(-3.1, 0.0), -3.1);
    }
}
