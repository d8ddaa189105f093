//! Buckling compensation (Koh, Narain & O'Brien 2015, "View-dependent adaptive cloth simulation
//! with buckling compensation": coarsened regions lock because a face cannot buckle inside
//! itself, so their resistance to compression is reduced). The formula here is ours.
//!
//! A face that view-dependent sizing leaves r times longer than the view-independent sizing
//! asks for (r = its longest edge measured in the view-independent metric, the remesher's edge
//! metric) stands for about r unresolved wrinkles across it: finer cloth there would shorten by
//! buckling at almost no membrane energy, while the coarse face resists with its full
//! stiffness. It keeps κ = max(1/r², κ_min) of its compressive stress (1 where r ≤ 1, where the
//! mesh resolves the buckles itself): continuous in r, so a face that coarsens or refines by
//! one remesh does not jump. Buckled cloth carries almost no compressive stress, so the floor
//! κ_min = 0.01 is low; it only keeps a coarse face from being crushed flat with nothing but
//! bending to stop it (a floor of 0.1 left the coarse drape of a sheet over a ball as high as
//! without compensation).
//!
//! The reduction is a slack in the face's rest shape, set after each step from the state (so a
//! function of the state: a resumed run gets the same bits). Buckling follows compressive
//! *stress* (a face that only narrows by Poisson's effect under tension is not compressed):
//! with the rest shape shrunk by δ along a material direction d (rest map L = I − δ ddᵀ, the
//! membrane sees F L⁻¹), the energy's first derivatives dE/dδ = dᵀΣd give Σ, the stress in
//! material space; where its least eigenvalue σ < 0 (direction q), the rest shrinks along q by
//! δ = (1 − κ)·(−σ/k), k = d²E/dδ² along q: the step the energy's quadratic model along q needs
//! to keep κ of the stress, a fraction 1 − κ of the way to its minimum, so the energy falls.
//! Derivatives are taken on the fabric's own kernel by central differences (any fabric model).
//! Within a step the energy is the fabric's energy of F L⁻¹ with L fixed: smooth, exact
//! derivatives, the implicit step and the fault checks unchanged. Tension is untouched, and
//! faces that are not coarsened (κ = 1) carry no slack.

use crate::math::{eigen_sym2, Mat2, Real, Vec2};

use super::membrane::MembraneRest;

/// The compressive stress a coarsened face keeps at least.
pub const KAPPA_MIN: Real = 0.01;

/// Largest rest shrink per direction (a coarse face under extreme compression keeps half its
/// rest length).
const DELTA_MAX: Real = 0.5;

/// Step of the central differences in δ.
const EPS: Real = 1e-5;

/// Newton steps for each direction's shrink (it converges in 3–4).
const NEWTON_STEPS: usize = 8;

/// κ of a face whose longest edge is `r` edges of the view-independent sizing.
pub fn compensation(r: Real) -> Real {
    if r <= 1.0 {
        1.0
    } else {
        (1.0 / (r * r)).max(KAPPA_MIN)
    }
}

/// The slack L⁻¹ (rest data `slack`) of a face that keeps `kappa` of its compressive stress;
/// `energy(rest)` is the fabric's membrane energy of the face at its current positions with
/// rest data `rest`. The identity when κ = 1 or nothing is under compression.
pub fn slack(rest: &MembraneRest, kappa: Real, energy: impl Fn(&MembraneRest) -> Real) -> Mat2 {
    if kappa >= 1.0 {
        return Mat2::identity();
    }
    // Σ from dE/dδ at δ = 0 along x, y and the diagonal: dᵀΣd with L⁻¹ = I + δ ddᵀ + O(δ²).
    let along = |d: Vec2, delta: Real| {
        energy(&MembraneRest { dm_inv: rest.dm_inv * (Mat2::identity() + delta * d * d.transpose()), ..*rest })
    };
    let slope0 = |d: Vec2| (along(d, EPS) - along(d, -EPS)) / (2.0 * EPS);
    let (ex, ey) = (Vec2::x(), Vec2::y());
    let (gx, gy, gd) = (slope0(ex), slope0(ey), slope0((ex + ey) / Real::sqrt(2.0)));
    let off = gd - 0.5 * (gx + gy);
    let (sigma, q) = eigen_sym2(&Mat2::new(gx, off, off, gy));
    // Shrinks δ₀, δ₁ along q₀, q₁: L⁻¹ = Q diag(1/(1 − δᵢ)) Qᵀ.
    let slack_of =
        |d: [Real; 2]| q * Mat2::from_diagonal(&Vec2::new(1.0 / (1.0 - d[0]), 1.0 / (1.0 - d[1]))) * q.transpose();
    let mut delta = [0.0; 2];
    for i in 0..2 {
        if sigma[i] >= 0.0 {
            continue;
        }
        let e = |x: Real| {
            let mut d = delta;
            d[i] = x;
            energy(&MembraneRest { dm_inv: rest.dm_inv * slack_of(d), ..*rest })
        };
        // The stress along qᵢ is ∝ (1 − δ)³ dE/dδ (the Green strain along qᵢ goes as
        // c/(1 − δ)², c = qᵢᵀFᵀFqᵢ): Newton on h(δ) = (1 − δ)³ E′(δ) − κ E′(0) = 0.
        let derivatives = |x: Real| {
            let (em, e0, ep) = (e(x - EPS), e(x), e(x + EPS));
            ((ep - em) / (2.0 * EPS), (ep - 2.0 * e0 + em) / (EPS * EPS))
        };
        let (g0, _) = derivatives(0.0);
        if g0 >= 0.0 {
            continue;
        }
        let target = kappa * g0;
        let mut x: Real = 0.0;
        for _ in 0..NEWTON_STEPS {
            let (g, k) = derivatives(x);
            let c = (1.0 - x).powi(3);
            let h = c * g - target;
            let dh = c * k - 3.0 * (1.0 - x).powi(2) * g;
            if h.abs() <= 1e-6 * target.abs() || dh <= 0.0 {
                break;
            }
            x = (x - h / dh).clamp(0.0, DELTA_MAX);
        }
        delta[i] = x;
    }
    slack_of(delta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::membrane::{membrane, MembraneStiffness};
    use crate::forces::Projection;
    use crate::math::test_rng::Rng;
    use crate::math::Vec3;

    fn rest() -> MembraneRest {
        MembraneRest::new([Vec2::zeros(), Vec2::new(0.1, 0.0), Vec2::new(0.0, 0.1)]).unwrap()
    }

    fn stiffness() -> MembraneStiffness {
        MembraneStiffness { k11: 100.0, k12: 30.0, k22: 80.0, k33: 20.0 }
    }

    /// The triangle stretched by `a` along x and `b` along y, sheared by `shear`.
    fn deformed(a: Real, b: Real, shear: Real) -> [Vec3; 3] {
        [Vec3::zeros(), Vec3::new(0.1 * a, 0.0, 0.0), Vec3::new(0.1 * shear, 0.1 * b, 0.0)]
    }

    fn energy(x: &[Vec3; 3]) -> impl Fn(&MembraneRest) -> Real + '_ {
        move |r: &MembraneRest| membrane(x, r, &stiffness(), Projection::Exact).0
    }

    fn slacked(r: &MembraneRest, slack: Mat2) -> MembraneRest {
        MembraneRest { dm_inv: r.dm_inv * slack, ..*r }
    }

    #[test]
    fn a_face_keeps_kappa_of_its_compressive_stress() {
        let r = rest();
        let x = deformed(0.95, 1.0, 0.0);
        for kappa in [1.0, 0.5, 0.1] {
            // Force on node 1 along x, from the compressive stress.
            let full = membrane(&x, &r, &stiffness(), Projection::Exact).1[3];
            let kept = membrane(&x, &slacked(&r, slack(&r, kappa, energy(&x))), &stiffness(), Projection::Exact).1[3];
            assert!((kept / full - kappa).abs() < 0.05 * kappa + 1e-3, "κ {kappa}: force ratio {}", kept / full);
        }
    }

    #[test]
    fn tension_and_poisson_narrowing_are_untouched() {
        let r = rest();
        let x = deformed(1.1, 1.05, 0.0);
        assert_eq!(slack(&r, 0.1, energy(&x)), Mat2::identity());
        // Stretched along y and narrowed along x by less than Poisson's ratio k₁₂/k₁₁ = 0.3
        // would give: compressive strain along x, but tensile stress.
        let x = deformed(0.99, 1.1, 0.0);
        assert_eq!(slack(&r, 0.1, energy(&x)), Mat2::identity());
    }

    #[test]
    fn slack_never_raises_the_energy() {
        let mut rng = Rng(7);
        let r = rest();
        for _ in 0..500 {
            let (a, b, shear) = (rng.range(0.6, 1.3), rng.range(0.6, 1.3), rng.range(-0.3, 0.3));
            let x = deformed(a, b, shear);
            let kappa = rng.range(KAPPA_MIN, 1.0);
            let e0 = energy(&x)(&r);
            let e1 = energy(&x)(&slacked(&r, slack(&r, kappa, energy(&x))));
            assert!(e1 <= e0 * (1.0 + 1e-9), "a {a} b {b} shear {shear} κ {kappa}: {e0} → {e1}");
        }
    }

    #[test]
    fn compensation_is_continuous_from_resolved_to_the_floor() {
        assert_eq!(compensation(0.5), 1.0);
        assert_eq!(compensation(1.0), 1.0);
        assert!((compensation(1.0 + 1e-9) - 1.0).abs() < 1e-8);
        assert!((compensation(2.0) - 0.25).abs() < 1e-15);
        assert_eq!(compensation(1000.0), KAPPA_MIN);
    }
}
