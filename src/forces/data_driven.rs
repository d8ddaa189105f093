//! Measured cloth (Wang, Ramamoorthi & O'Brien 2011, "Data-driven elastic models for cloth"),
//! evaluated as ARCSim 0.2.1 evaluates its material files.
//!
//! **Stretching.** A file gives 6 rows of 4 stiffnesses (k₀ warp, k₁ warp–weft coupling, k₂ weft,
//! k₃ shear, N/m): row 0 for the unstretched cloth, rows 1–5 for a largest principal stretch of
//! λ = 7/6 whose direction is 0°, 22.5°, 45°, 67.5° or 90° from the warp (material u axis). For a
//! Green strain G = ½(FᵀF − I) the sample is interpolated linearly in λ (row 0 at λ = 1 to the
//! direction rows at λ = 7/6, held beyond) and in the angle of λ's direction, clamped at zero and
//! doubled (`stretching_sample`). ARCSim tabulates the samples on a 30³ grid over
//! (G₀₀, G₁₁, |G₀₁|) ∈ [−0.25, 0.717]² × [0, 0.967] (held outside) and looks k up trilinearly
//! (`StretchingGrid::stiffness`); so does this module.
//!
//! The model is defined by its stress. With ε = (G₀₀, G₁₁, 2G₀₁) and
//! C(ε) = [[k₀, k₁, 0], [k₁, k₂, 0], [0, 0, k₃/2]], the second Piola–Kirchhoff stress is
//! σ = C(ε) ε and the nodal force −A (∂ε/∂x)ᵀ σ (ARCSim's `stretching_force`, whose shear term
//! 2k₃G₀₁ is the k₃/2 on 2G₀₁ here). Because C varies with ε this force field is not the gradient
//! of a potential, so the kernel returns:
//! - energy: the secant energy ½ A εᵀ C(ε) ε (exact when C is constant, e.g. paper);
//! - gradient: A (∂ε/∂x)ᵀ σ, ARCSim's stress (the negated force);
//! - `Projection::Exact`: the true Jacobian of that gradient, including ∂C/∂ε (not symmetric);
//! - `Projection::Psd`: ARCSim's Jacobian with ∂C/∂ε dropped, C's warp–weft block and the stress
//!   of the geometric term projected to their positive parts: symmetric positive semidefinite.
//!   ARCSim's own geometric term differs: it clamps the strains (k₀ max(G₀₀, 0) + k₁ max(G₁₁, 0)
//!   along u, k₂ max(G₁₁, 0) + k₁ max(G₀₀, 0) along v) and leaves the shear stress out
//!   (`Geometric::Arcsim`, the material's `geometric_stiffness: "arcsim"`, which converted
//!   ARCSim confs get).
//!
//! **Bending.** A file gives 3 rows of 5 stiffnesses (N·m): edge direction 0°, 45°, 90° from the
//! warp, at curvatures κ = 0, 10, 20, 30, 40 m⁻¹ with κ = |θ| ℓ/(A₁+A₂) (ℓ the material edge length,
//! Aᵢ the adjacent material areas). ke is interpolated bilinearly (held beyond 40 m⁻¹), clamped at
//! zero, the smaller of the two sides' values taken (each side sees the edge in its own
//! material coordinates), and the hinge energy is ke ℓ²/(8(A₁+A₂)) (θ − θ̄)² as in ARCSim (the
//! force is ke ℓ²/(4(A₁+A₂)) (θ − θ̄) ∂θ/∂x). ARCSim uses the signed angle for κ, so a fold
//! towards the back extrapolates below the first sample; this module uses |θ| by default, so
//! that both fold directions are equally stiff, and ARCSim's signed rule with `FoldSign::Signed`
//! (the material's `bending_curvature: "signed"`, which converted ARCSim confs get). As for
//! stretching: energy at the current ke, gradient as ARCSim's force, `Exact` with ∂ke/∂θ, `Psd`
//! the Gauss–Newton form.

use crate::math::dual::V3;
use crate::math::{pos_part2, Mat12, Mat2, Mat3, Real, Vec12, Vec2, Vec3, Vec9};

use super::bending::{dihedral_angle, dihedral_gradient, dihedral_hessian, unwrap_angle, BendingRest};
use super::membrane::{deformation_gradient, strain_jacobian, MembraneRest};
use super::Projection;

/// Grid points per axis of ARCSim's stiffness table.
pub const GRID: usize = 30;

/// The contents of a measured material file, before multipliers.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredData {
    /// kg/m².
    pub density: Real,
    /// `[k₀, k₁, k₂, k₃]` per row: row 0 at rest, rows 1–5 by direction (0° … 90°).
    pub stretching: [[Real; 4]; 6],
    /// Rows by edge direction (0°, 45°, 90°), columns by curvature (0 … 40 m⁻¹).
    pub bending: [[Real; 5]; 3],
}

/// A measured fabric ready to evaluate: the stiffness grid and the bending table, multipliers
/// applied.
#[derive(Clone, PartialEq)]
pub struct MeasuredMaterial {
    pub stretching: StretchingGrid,
    pub bending: [[Real; 5]; 3],
    /// How the bending lookup treats the direction of a fold.
    pub fold: FoldSign,
    /// The geometric stiffness of `Projection::Psd`'s membrane Jacobian.
    pub geometric: Geometric,
}

/// The geometric (stress) term of the membrane's PSD Jacobian, A Σᵢⱼ bᵢᵀ S bⱼ I per node pair
/// (bᵢ the shape-function gradients).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Geometric {
    /// S = the positive part of the second Piola–Kirchhoff stress tensor, shear included.
    #[default]
    Stress,
    /// ARCSim 0.2.1's (`stretching_force` in `physics.cpp`): the strains clamped instead of the
    /// stress and no shear term, S = diag(k₀ G₀₀⁺ + k₁ G₁₁⁺, k₂ G₁₁⁺ + k₁ G₀₀⁺). Both are
    /// positive semidefinite; the implicit step's damping differs by the choice, which is all
    /// that separates the two simulators' trajectories on a fixed mesh (README, "Where
    /// square.json's squeeze gap comes from").
    Arcsim,
}

/// How the curvature that looks a measured bending stiffness up treats the direction of the fold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FoldSign {
    /// κ = |θ| ℓ/(A₁+A₂): folds towards either side of the cloth are equally stiff.
    #[default]
    Absolute,
    /// ARCSim 0.2.1's: κ = θ_A ℓ/(A₁+A₂) with its signed angle θ_A = −θ (its edge vector runs
    /// from the edge's second node to its first, `dihedral_angle` in `geometry.cpp`, looked up in
    /// `bending_stiffness`, `dde.cpp`). A fold towards the back of the cloth (κ < 0) extrapolates
    /// the table's first two samples linearly, clamped at zero: for gray-interlock, 1.8× stiffer
    /// than the front at κ = −10 m⁻¹ across the weft, 0.6× along the warp.
    Signed,
}

impl std::fmt::Debug for MeasuredMaterial {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeasuredMaterial").field("bending", &self.bending).finish_non_exhaustive()
    }
}

impl MeasuredMaterial {
    /// ARCSim's multipliers: the stiffness samples are scaled by `stretching_mult` and the bending
    /// table by `bending_mult` (the caller folds `thicken` into both, and into the density).
    pub fn new(data: &MeasuredData, stretching_mult: Real, bending_mult: Real) -> Self {
        let mut grid = StretchingGrid::new(&data.stretching);
        grid.k.iter_mut().flatten().for_each(|k| *k *= stretching_mult);
        let bending = data.bending.map(|row| row.map(|k| k * bending_mult));
        MeasuredMaterial { stretching: grid, bending, fold: FoldSign::Absolute, geometric: Geometric::Stress }
    }
}

/// ARCSim's evaluation of one stretching sample at Green strain `g` (symmetric).
pub fn stretching_sample(g: &Mat2, data: &[[Real; 4]; 6]) -> [Real; 4] {
    // Principal stretches and the direction of the largest, from C = 2G + I = FᵀF.
    let c = g * 2.0 + Mat2::identity();
    let (a, b, d) = (c[(0, 0)], c[(1, 0)], c[(1, 1)]);
    let l1 = 0.5 * (a + d + (4.0 * b * b + (a - d) * (a - d)).sqrt());
    let dir = if b != 0.0 {
        Vec2::new(l1 - d, b)
    } else if a >= d {
        Vec2::new(1.0, 0.0)
    } else {
        Vec2::new(0.0, 1.0)
    };
    let stretch = l1.max(0.0).sqrt();
    let angle = ((dir.y.atan2(dir.x) / std::f64::consts::PI).abs() * 8.0).clamp(0.0, 4.0 - 1e-6);
    let ai = angle as usize;
    let aw = angle - ai as Real;
    let sw = ((stretch - 1.0) * 6.0).clamp(0.0, 1.0 - 1e-6);
    let row = |r: usize| data[if r == 0 { 0 } else { 1 + ai }];
    let row_next = |r: usize| data[if r == 0 { 0 } else { 2 + ai }];
    let mut k = [0.0; 4];
    for (l, kl) in k.iter_mut().enumerate() {
        let v = row(0)[l] * (1.0 - sw) * (1.0 - aw)
            + row(1)[l] * sw * (1.0 - aw)
            + row_next(0)[l] * (1.0 - sw) * aw
            + row_next(1)[l] * sw * aw;
        *kl = 2.0 * v.max(0.0);
    }
    k
}

/// Stiffness samples on ARCSim's grid: G₀₀ = −¼ + i/30, G₁₁ = −¼ + j/30, G₀₁ = k/30.
#[derive(Clone, PartialEq)]
pub struct StretchingGrid {
    /// Index `(i · GRID + j) · GRID + k`.
    k: Vec<[Real; 4]>,
}

/// Grid cell and fraction along one axis, with d(fraction)/d(coordinate) (zero where clamped).
fn grid_axis(value: Real) -> (usize, Real, Real) {
    let n = GRID as Real;
    let s = value * n;
    let c = s.clamp(0.0, n - 1.0 - 1e-5);
    let i = (c.floor() as usize).min(GRID - 2);
    (i, c - i as Real, if c == s { n } else { 0.0 })
}

impl StretchingGrid {
    pub fn new(data: &[[Real; 4]; 6]) -> Self {
        let n = GRID as Real;
        let mut k = Vec::with_capacity(GRID * GRID * GRID);
        for i in 0..GRID {
            for j in 0..GRID {
                for l in 0..GRID {
                    let g01 = l as Real / n;
                    let g = Mat2::new(-0.25 + i as Real / n, g01, g01, -0.25 + j as Real / n);
                    k.push(stretching_sample(&g, data));
                }
            }
        }
        StretchingGrid { k }
    }

    /// The stiffness `[k₀, k₁, k₂, k₃]` at Green strain (G₀₀, G₁₁, G₀₁), trilinear in the grid, and
    /// its derivatives with respect to G₀₀, G₁₁ and G₀₁.
    pub fn stiffness(&self, g00: Real, g11: Real, g01: Real) -> ([Real; 4], [[Real; 4]; 3]) {
        self.interpolate::<true>(g00, g11, g01)
    }

    /// `stiffness` without the derivatives (zero), the stiffness bit for bit the same.
    pub fn stiffness_alone(&self, g00: Real, g11: Real, g01: Real) -> [Real; 4] {
        self.interpolate::<false>(g00, g11, g01).0
    }

    #[inline]
    fn interpolate<const DERIVATIVES: bool>(&self, g00: Real, g11: Real, g01: Real) -> ([Real; 4], [[Real; 4]; 3]) {
        let (ai, fa, da) = grid_axis(g00 + 0.25);
        let (bi, fb, db) = grid_axis(g11 + 0.25);
        let (ci, fc, dc) = grid_axis(g01.abs());
        let dc = if g01 < 0.0 { -dc } else { dc };
        let (mut k, mut dk) = ([0.0; 4], [[0.0; 4]; 3]);
        for (i, wa, wa1) in [(0, 1.0 - fa, -1.0), (1, fa, 1.0)] {
            for (j, wb, wb1) in [(0, 1.0 - fb, -1.0), (1, fb, 1.0)] {
                for (l, wc, wc1) in [(0, 1.0 - fc, -1.0), (1, fc, 1.0)] {
                    let s = &self.k[((ai + i) * GRID + bi + j) * GRID + ci + l];
                    let (w, dw) = (wa * wb * wc, [wa1 * da * wb * wc, wa * wb1 * db * wc, wa * wb * wc1 * dc]);
                    for m in 0..4 {
                        k[m] += w * s[m];
                        if DERIVATIVES {
                            for (d, dwd) in dw.iter().enumerate() {
                                dk[d][m] += dwd * s[m];
                            }
                        }
                    }
                }
            }
        }
        (k, dk)
    }
}

/// C(ε) on ε = (G₀₀, G₁₁, 2G₀₁).
fn voigt_stiffness(k: &[Real; 4]) -> Mat3 {
    Mat3::new(k[0], k[1], 0.0, k[1], k[2], 0.0, 0.0, 0.0, 0.5 * k[3])
}

/// The Voigt strain ε = (G₀₀, G₁₁, 2G₀₁) of a triangle, with F.
#[inline]
fn green_strain(x: &[Vec3; 3], rest: &MembraneRest) -> (crate::math::Mat3x2, Vec3) {
    let f = deformation_gradient(x, rest);
    let (f0, f1) = (f.column(0).into_owned(), f.column(1).into_owned());
    (f, Vec3::new(0.5 * (f0.dot(&f0) - 1.0), 0.5 * (f1.dot(&f1) - 1.0), f0.dot(&f1)))
}

/// σ = C(ε) ε and the energy ½ A εᵀσ at strain `eps` and stiffness `k`.
#[inline]
fn measured_stress(eps: &Vec3, k: &[Real; 4], area: Real) -> (Mat3, Vec3, Real) {
    let c = voigt_stiffness(k);
    let sigma = c * eps;
    (c, sigma, 0.5 * area * eps.dot(&sigma))
}

/// The energy of one membrane triangle of measured cloth alone, bit for bit
/// `measured_membrane`'s (issue 17 item 3).
pub fn measured_membrane_energy(x: &[Vec3; 3], rest: &MembraneRest, grid: &StretchingGrid) -> Real {
    let (_, eps) = green_strain(x, rest);
    let k = grid.stiffness_alone(eps[0], eps[1], 0.5 * eps[2]);
    measured_stress(&eps, &k, rest.area).2
}

/// Energy, gradient and Jacobian of one membrane triangle of measured cloth (see the module
/// documentation for what each means in this stress-defined model).
pub fn measured_membrane(
    x: &[Vec3; 3],
    rest: &MembraneRest,
    grid: &StretchingGrid,
    proj: Projection,
) -> (Real, Vec9, crate::math::Mat9) {
    measured_membrane_with(x, rest, grid, proj, Geometric::Stress)
}

/// `measured_membrane` with the geometric term of `Projection::Psd` chosen (`Geometric`).
pub fn measured_membrane_with(
    x: &[Vec3; 3],
    rest: &MembraneRest,
    grid: &StretchingGrid,
    proj: Projection,
    geometric: Geometric,
) -> (Real, Vec9, crate::math::Mat9) {
    let (f, eps) = green_strain(x, rest);
    let (k, dk) = grid.stiffness(eps[0], eps[1], 0.5 * eps[2]);
    let (c, sigma, energy) = measured_stress(&eps, &k, rest.area);
    let a = rest.area;
    let b = rest.b();
    let jac = strain_jacobian(&f, &b);
    let grad = a * jac.transpose() * sigma;
    if proj == Projection::Gradient {
        return (energy, grad, crate::math::Mat9::zeros());
    }
    let (tangent, s) = match proj {
        Projection::Exact => {
            // dσ/dε = C + (∂C/∂εⱼ) ε; ∂/∂ε₂ = ½ ∂/∂G₀₁.
            let mut d = c;
            for (j, dkj) in dk.iter().enumerate() {
                let scale = if j == 2 { 0.5 } else { 1.0 };
                d[(0, j)] += scale * (eps[0] * dkj[0] + eps[1] * dkj[1]);
                d[(1, j)] += scale * (eps[0] * dkj[1] + eps[1] * dkj[2]);
                d[(2, j)] += scale * 0.5 * eps[2] * dkj[3];
            }
            (d, Mat2::new(sigma[0], sigma[2], sigma[2], sigma[1]))
        }
        Projection::Psd | Projection::Gradient => {
            let block = pos_part2(&Mat2::new(k[0], k[1], k[1], k[2]));
            let mut d = Mat3::zeros();
            d.fixed_view_mut::<2, 2>(0, 0).copy_from(&block);
            d[(2, 2)] = 0.5 * k[3];
            let s = match geometric {
                Geometric::Stress => pos_part2(&Mat2::new(sigma[0], sigma[2], sigma[2], sigma[1])),
                Geometric::Arcsim => {
                    let (g0, g1) = (eps[0].max(0.0), eps[1].max(0.0));
                    Mat2::new(k[0] * g0 + k[1] * g1, 0.0, 0.0, k[2] * g1 + k[1] * g0)
                }
            };
            (d, s)
        }
    };
    let mut hess = a * jac.transpose() * tangent * jac;
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

/// Per-hinge material-space data of the measured bending model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HingeRest {
    /// ℓ/(A₁+A₂) (1/m): curvature per radian of dihedral angle.
    pub curvature_per_angle: Real,
    /// Edge direction on each side as ARCSim's bias coordinate in [0, 2]: 0 along the warp,
    /// 1 on the bias (45°), 2 along the weft.
    pub bias: [Real; 2],
}

impl HingeRest {
    /// From the material-space edge vector as seen by each adjacent face, the edge length and
    /// the two faces' material areas summed.
    pub fn new(edge: [Vec2; 2], length: Real, area_sum: Real) -> Self {
        let bias = edge.map(|du| {
            let mut b = (du.y.atan2(du.x) * 4.0 / std::f64::consts::PI).abs();
            if b > 4.0 {
                b = 8.0 - b;
            }
            if b > 2.0 {
                b = 4.0 - b;
            }
            b
        });
        HingeRest { curvature_per_angle: length / area_sum, bias }
    }
}

/// ARCSim's bending stiffness at curvature `curv` (1/m) and bias coordinate `bias`, with its
/// derivative with respect to `curv`.
pub fn bending_stiffness(table: &[[Real; 5]; 3], curv: Real, bias: Real) -> (Real, Real) {
    // Samples every 10 m⁻¹ ("per 0.05 cm⁻¹" of half the curvature in ARCSim's note).
    let raw = curv * 0.1;
    let value = raw.min(4.0);
    let dvalue = if raw < 4.0 { 0.1 } else { 0.0 };
    let vi = (value.max(0.0) as usize).min(3);
    let vf = value - vi as Real;
    let bi = (bias.max(0.0) as usize).min(1);
    let bf = bias - bi as Real;
    let (d0, d1) = (&table[bi], &table[bi + 1]);
    let lo = d0[vi] * (1.0 - bf) + d1[vi] * bf;
    let hi = d0[vi + 1] * (1.0 - bf) + d1[vi + 1] * bf;
    let ke = lo * (1.0 - vf) + hi * vf;
    if ke < 0.0 {
        (0.0, 0.0)
    } else {
        (ke, (hi - lo) * dvalue)
    }
}

/// What `measured_bending` and `measured_bending_energy` share: the fold's sign, the stiffness
/// and its derivative in the curvature, ARCSim's shape factor, θ − θ̄ and the energy.
struct Folded {
    sign: Real,
    ke: Real,
    dke_dcurv: Real,
    shape: Real,
    d: Real,
    energy: Real,
}

#[inline]
fn folded(xv: &[V3<f64>; 4], rest: &BendingRest, hinge: &HingeRest, table: &[[Real; 5]; 3], fold: FoldSign) -> Folded {
    let theta = unwrap_angle(dihedral_angle(xv), rest.theta0);
    // dκ/dθ over ℓ/(A₁+A₂).
    let sign = match fold {
        FoldSign::Absolute => theta.signum(),
        FoldSign::Signed => -1.0,
    };
    let curv = sign * theta * hinge.curvature_per_angle;
    let (ke, dke_dcurv) = hinge
        .bias
        .iter()
        .map(|&b| bending_stiffness(table, curv, b))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap_or((0.0, 0.0));
    // ARCSim's shape factor ℓ²/(2(A₁+A₂)); `rest.shape` is 3ℓ²/(A₁+A₂).
    let shape = rest.shape / 6.0;
    let d = theta - rest.theta0;
    Folded { sign, ke, dke_dcurv, shape, d, energy: 0.25 * ke * shape * d * d }
}

/// The energy of one hinge of measured cloth alone, bit for bit `measured_bending`'s (issue 17
/// item 3).
pub fn measured_bending_energy(
    x: &[Vec3; 4],
    rest: &BendingRest,
    hinge: &HingeRest,
    table: &[[Real; 5]; 3],
    fold: FoldSign,
) -> Real {
    folded(&x.map(|p| V3([p.x, p.y, p.z])), rest, hinge, table, fold).energy
}

/// Energy, gradient and Jacobian of one hinge of measured cloth (see the module documentation).
pub fn measured_bending(
    x: &[Vec3; 4],
    rest: &BendingRest,
    hinge: &HingeRest,
    table: &[[Real; 5]; 3],
    fold: FoldSign,
    proj: Projection,
) -> (Real, Vec12, Mat12) {
    let xv = x.map(|p| V3([p.x, p.y, p.z]));
    let Folded { sign, ke, dke_dcurv, shape, d, energy } = folded(&xv, rest, hinge, table, fold);
    let g = dihedral_gradient(&xv);
    let grad_theta = Vec12::from_fn(|r, _| g[r / 3].0[r % 3]);
    let c = 0.5 * ke * shape;
    let grad = c * d * grad_theta;
    if proj == Projection::Gradient {
        return (energy, grad, Mat12::zeros());
    }
    let mut hess = c * grad_theta * grad_theta.transpose();
    if proj == Projection::Exact {
        hess += c * d * dihedral_hessian(x);
        let dke_dtheta = dke_dcurv * hinge.curvature_per_angle * sign;
        hess += (0.5 * shape * d * dke_dtheta) * grad_theta * grad_theta.transpose();
    }
    (energy, grad, hess)
}
