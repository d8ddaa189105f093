//! Constant-strain triangle membrane on the Green strain in material space.
//!
//! Orthotropic Saint Venant–Kirchhoff (plane stress), as in ARCSim's linear stretching model:
//! ψ = A · ½ εᵀ C ε with ε = (E₁₁, E₂₂, 2E₁₂), E = ½(FᵀF − I), F = D_s D_m⁻¹ the 3×2 deformation
//! gradient and C = [[k₁₁, k₁₂, 0], [k₁₂, k₂₂, 0], [0, 0, k₃₃]] in N/m (warp, coupling, weft,
//! shear). Isotropic StVK is k₁₁ = k₂₂ = Et/(1−ν²), k₁₂ = νk₁₁, k₃₃ = Et/(2(1+ν)).

use crate::math::{pos_part2, Mat2, Mat3, Mat3x2, Mat9, Real, Vec2, Vec3, Vec9};

use super::Projection;

/// Per-face rest data, computed once per topology.
#[derive(Clone, Copy, Debug)]
pub struct MembraneRest {
    /// D_m⁻¹, the inverse of the material-space edge matrix [u₁−u₀, u₂−u₀].
    pub dm_inv: Mat2,
    /// Material-space area (m²).
    pub area: Real,
    /// Stiffness factor 1/(1 + w·d) of plastic damage (`plasticity`); 1 when undamaged.
    pub weakened: Real,
    /// L⁻¹ of the rest shape's slack under unresolved buckling (`buckling`): the membrane sees
    /// F L⁻¹. The identity but on coarsened, compressed faces in view mode.
    pub slack: Mat2,
}

impl MembraneRest {
    pub fn new(u: [Vec2; 3]) -> Option<Self> {
        let dm = Mat2::from_columns(&[u[1] - u[0], u[2] - u[0]]);
        let area = 0.5 * dm.determinant();
        let dm_inv = dm.try_inverse()?;
        (area > 0.0).then_some(MembraneRest { dm_inv, area, weakened: 1.0, slack: Mat2::identity() })
    }

    /// The rest data the membrane kernels see: D_m⁻¹ L⁻¹, so that F becomes F L⁻¹ (`buckling`).
    #[inline]
    pub fn slackened(&self) -> MembraneRest {
        MembraneRest { dm_inv: self.dm_inv * self.slack, slack: Mat2::identity(), ..*self }
    }

    /// The shape-function gradients b₀, b₁, b₂ (F = Σ xᵢ bᵢᵀ).
    #[inline]
    pub fn b(&self) -> [Vec2; 3] {
        let b1 = Vec2::new(self.dm_inv[(0, 0)], self.dm_inv[(0, 1)]);
        let b2 = Vec2::new(self.dm_inv[(1, 0)], self.dm_inv[(1, 1)]);
        [-b1 - b2, b1, b2]
    }
}

/// Membrane stiffness in N/m on the Voigt strain (E₁₁, E₂₂, 2E₁₂).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MembraneStiffness {
    pub k11: Real,
    pub k12: Real,
    pub k22: Real,
    pub k33: Real,
}

/// Deformation gradient F = D_s D_m⁻¹.
#[inline]
pub fn deformation_gradient(x: &[Vec3; 3], rest: &MembraneRest) -> Mat3x2 {
    Mat3x2::from_columns(&[x[1] - x[0], x[2] - x[0]]) * rest.dm_inv
}

/// Largest principal stretch − 1 (the strain reported in stats).
pub fn max_principal_strain(f: &Mat3x2) -> Real {
    let c = f.transpose() * f;
    crate::math::eigen_sym2(&c).0[1].max(0.0).sqrt() - 1.0
}

/// J = ∂ε/∂x for ε = (E₁₁, E₂₂, 2E₁₂): one row per component, a 3-column block per node, from
/// F and the shape-function gradients `b` (`MembraneRest::b`).
pub fn strain_jacobian(f: &Mat3x2, b: &[Vec2; 3]) -> nalgebra::SMatrix<Real, 3, 9> {
    let (f0, f1) = (f.column(0), f.column(1));
    let mut jac = nalgebra::SMatrix::<Real, 3, 9>::zeros();
    for i in 0..3 {
        let (bi0, bi1) = (b[i].x, b[i].y);
        jac.fixed_view_mut::<1, 3>(0, 3 * i).copy_from(&(bi0 * f0).transpose());
        jac.fixed_view_mut::<1, 3>(1, 3 * i).copy_from(&(bi1 * f1).transpose());
        jac.fixed_view_mut::<1, 3>(2, 3 * i).copy_from(&(bi0 * f1 + bi1 * f0).transpose());
    }
    jac
}

/// F, the second Piola–Kirchhoff stress σ = C ε in Voigt form and the energy of one membrane
/// triangle: the part of `membrane` that `membrane_energy` shares.
#[inline]
fn stressed(x: &[Vec3; 3], rest: &MembraneRest, k: &MembraneStiffness) -> (Mat3x2, Vec3, Real) {
    let f = deformation_gradient(x, rest);
    let (f0, f1) = (f.column(0).into_owned(), f.column(1).into_owned());
    let e11 = 0.5 * (f0.dot(&f0) - 1.0);
    let e22 = 0.5 * (f1.dot(&f1) - 1.0);
    let g12 = f0.dot(&f1); // 2E₁₂
    let s1 = k.k11 * e11 + k.k12 * e22;
    let s2 = k.k12 * e11 + k.k22 * e22;
    let s3 = k.k33 * g12;
    let energy = rest.area * 0.5 * (e11 * s1 + e22 * s2 + g12 * s3);
    (f, Vec3::new(s1, s2, s3), energy)
}

/// The energy of one membrane triangle alone, bit for bit `membrane`'s (the fault checks and the
/// pop filter's line search evaluate energies only; issue 17 item 3).
pub fn membrane_energy(x: &[Vec3; 3], rest: &MembraneRest, k: &MembraneStiffness) -> Real {
    stressed(x, rest, k).2
}

/// Energy, gradient (w.r.t. x₀, x₁, x₂ stacked) and Hessian of one membrane triangle.
pub fn membrane(x: &[Vec3; 3], rest: &MembraneRest, k: &MembraneStiffness, proj: Projection) -> (Real, Vec9, Mat9) {
    let (f, sigma, energy) = stressed(x, rest, k);
    let (s1, s2, s3) = (sigma.x, sigma.y, sigma.z);
    let a = rest.area;
    let b = rest.b();
    let jac = strain_jacobian(&f, &b);
    let grad = a * jac.transpose() * sigma;
    if proj == Projection::Gradient {
        return (energy, grad, Mat9::zeros());
    }
    let c = Mat3::new(k.k11, k.k12, 0.0, k.k12, k.k22, 0.0, 0.0, 0.0, k.k33);
    let mut hess = a * jac.transpose() * c * jac;
    // Geometric term (bᵢᵀ S bⱼ) I₃; its indefinite part comes from compressive stress, so the
    // PSD form keeps only the positive part of S (C is SPD, so the sum is then PSD).
    let s = Mat2::new(s1, s3, s3, s2);
    let s = match proj {
        Projection::Exact => s,
        Projection::Psd | Projection::Gradient => pos_part2(&s),
    };
    for i in 0..3 {
        for j in 0..3 {
            let gij = a * b[i].dot(&(s * b[j]));
            for d in 0..3 {
                hess[(3 * i + d, 3 * j + d)] += gij;
            }
        }
    }
    (energy, grad, hess)
}
