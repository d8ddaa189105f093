//! Where a split puts its new node (ARCSim 0.2.1's `split_edge`, `set_midpoint_position`;
//! Narain, Samii & O'Brien 2012 §4.1 split the edge at its midpoint, ARCSim then relaxes it).
//!
//! The midpoint of a curved surface's edge lies on the chord, inside the curve, so the new
//! faces are stretched and the hinges around the new node kinked: the next step turns that
//! into a pop. ARCSim moves the node by one Newton step of a local energy of unit stiffness
//! over the faces and hinges around it, the other nodes fixed:
//!
//! - each new face's Green–Lagrange stretching ½ G₀₀² + ½ G₁₁² + ½ G₀₁²·2 with ARCSim's
//!   Jacobian (k₀ = k₂ = k₃ = 1, k₁ = 0; geometric terms of the clamped strains, the G₀₁ one
//!   left out), weighted by the face's material area;
//! - each hinge with the new node on it (the new edges, the split edge's halves, the edges
//!   opposite it) ¼ (A₀ + A₁) θ²/2 about a flat rest angle, Gauss–Newton, A the wings' world
//!   areas;
//! - a regularisation 10⁻³ I,
//!
//! and x ← x − A⁻¹ b. A flat sheet's midpoint is the minimum (b = 0), so only a curved or
//! strained surface moves it. The rest angle is flat, as ARCSim's new edges' are: the
//! relaxation is used only where the faces rest flat (no rest shape operator, no rest
//! embedding), and a curved rest shape keeps the midpoint.

use crate::forces::bending::{dihedral_angle, dihedral_gradient};
use crate::forces::membrane::{deformation_gradient, MembraneRest};
use crate::math::dual::V3;
use crate::math::{Mat2, Mat3, Real, Vec2, Vec3};

use super::ops::Op;
use super::work::Work;

/// ARCSim's regularisation of the local Newton step.
const REGULARISATION: Real = 1e-3;

/// The position of a split's new node (`op.new_nodes[0]`, at `x`) after ARCSim's local
/// relaxation, or `x` where the faces do not rest flat or the step is not finite.
pub fn relaxed(w: &Work, op: &Op, x: Vec3) -> Vec3 {
    let flat = |f: usize| w.fdata[f].shape == Mat2::zeros();
    if !w.y.is_empty() || !op.remove_faces.iter().all(|&f| flat(f)) {
        return x;
    }
    let new_vert = |v: usize| v >= w.u.len();
    let pos = |v: usize| if new_vert(v) { x } else { w.x[w.vnode[v]] };
    let mut a = REGULARISATION * Mat3::identity();
    let mut b = Vec3::zeros();
    for (t, _) in &op.add_faces {
        let Some(k) = (0..3).find(|&k| new_vert(t[k])) else { continue };
        let (ak, bk) = stretching(t.map(|v| op.u(w, v)), t.map(pos), k);
        a += ak;
        b += bk;
    }
    // Per split face: (s, p, k) and (p, t, k) replaced it (`split_face`).
    let sides: Vec<([usize; 3], usize)> = op
        .remove_faces
        .iter()
        .zip(op.add_faces.chunks(2))
        .map(|(&f, pair)| ([pair[0].0[0], pair[0].0[2], pair[1].0[1]], f))
        .collect();
    let mut hinge = |x4: [Vec3; 4], at: usize| {
        let (ak, bk) = bending(x4, at);
        a += ak;
        b += bk;
    };
    for &([s, k, t], f) in &sides {
        hinge([x, pos(k), pos(s), pos(t)], 0);
        for e in [s, t] {
            let across = w.edge_faces(e, k).into_iter().find(|&g| g != f);
            if let Some(g) = across {
                hinge([pos(e), pos(k), x, pos(w.opposite(g, e, k))], 2);
            }
        }
    }
    if let [(side0, _), (side1, _)] = sides.as_slice() {
        for end in [side0[0], side0[2]] {
            hinge([pos(end), x, pos(side0[1]), pos(side1[1])], 1);
        }
    }
    match a.try_inverse() {
        Some(inv) => {
            let moved = x - inv * b;
            if moved.iter().all(|c| c.is_finite()) {
                moved
            } else {
                x
            }
        }
        None => x,
    }
}

/// The block of corner `k` of ARCSim's unit stretching quadratic of a face with material
/// corners `u` at world positions `x` (`remesh.cpp`'s `stretching`).
fn stretching(u: [Vec2; 3], x: [Vec3; 3], k: usize) -> (Mat3, Vec3) {
    // A face a split made is positively oriented in material space; anything else adds nothing.
    let Some(rest) = MembraneRest::new(u) else { return (Mat3::zeros(), Vec3::zeros()) };
    let f = deformation_gradient(&x, &rest);
    let (xu, xv): (Vec3, Vec3) = (f.column(0).into(), f.column(1).into());
    let (du, dv) = (rest.b()[k].x, rest.b()[k].y);
    let (g00, g11, g01) = (0.5 * (xu.dot(&xu) - 1.0), 0.5 * (xv.dot(&xv) - 1.0), 0.5 * xu.dot(&xv));
    let fuu = du * xu;
    let fvv = dv * xv;
    let fuv = 0.5 * (du * xv + dv * xu);
    let grad = g00 * fuu + g11 * fvv + g01 * fuv;
    let hess = fuu * fuu.transpose()
        + fvv * fvv.transpose()
        + fuv * fuv.transpose()
        + (g00.max(0.0) * du * du + g11.max(0.0) * dv * dv) * Mat3::identity();
    (rest.area * hess, rest.area * grad)
}

/// The block of node `at` of ARCSim's unit hinge quadratic (`remesh.cpp`'s `bending`, rest
/// angle 0): ¼ (A₀ + A₁) (½ ∇θ ∇θᵀ, ½ θ ∇θ). Edge x₀–x₁, wings x₂ and x₃.
fn bending(x: [Vec3; 4], at: usize) -> (Mat3, Vec3) {
    let xv = x.map(|p| V3([p.x, p.y, p.z]));
    let e = x[1] - x[0];
    let (a0, a1) = (0.5 * e.cross(&(x[2] - x[0])).norm(), 0.5 * e.cross(&(x[3] - x[0])).norm());
    if e.norm() == 0.0 || a0 == 0.0 || a1 == 0.0 {
        return (Mat3::zeros(), Vec3::zeros());
    }
    let theta = dihedral_angle(&xv);
    let g = dihedral_gradient(&xv)[at].0;
    let g = Vec3::new(g[0], g[1], g[2]);
    let c = 0.125 * (a0 + a1);
    (c * g * g.transpose(), c * theta * g)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ½ (G₀₀² + G₁₁² + G₀₁²) · A, the energy whose gradient the stretching block's b is.
    fn unit_energy(u: [Vec2; 3], x: [Vec3; 3]) -> Real {
        let dm = Mat2::from_columns(&[u[1] - u[0], u[2] - u[0]]);
        let m = dm.try_inverse().unwrap();
        let e = [x[1] - x[0], x[2] - x[0]];
        let xu = e[0] * m[(0, 0)] + e[1] * m[(1, 0)];
        let xv = e[0] * m[(0, 1)] + e[1] * m[(1, 1)];
        let (g00, g11, g01) = (0.5 * (xu.dot(&xu) - 1.0), 0.5 * (xv.dot(&xv) - 1.0), 0.5 * xu.dot(&xv));
        0.5 * dm.determinant().abs() * 0.5 * (g00 * g00 + g11 * g11 + g01 * g01)
    }

    /// The stretching block's b is the corner's gradient of the unit energy (central
    /// differences), and its A the Gauss–Newton part of the Hessian, positive definite here.
    #[test]
    fn the_stretching_block_is_the_unit_energys_gradient() {
        let u = [Vec2::new(0.1, 0.0), Vec2::new(1.0, 0.2), Vec2::new(0.3, 0.9)];
        let x = [Vec3::new(0.0, 0.05, 0.1), Vec3::new(1.3, 0.1, -0.2), Vec3::new(0.2, 1.1, 0.3)];
        for k in 0..3 {
            let (a, b) = stretching(u, x, k);
            let h = 1e-6;
            for d in 0..3 {
                let (mut xp, mut xm) = (x, x);
                xp[k][d] += h;
                xm[k][d] -= h;
                let fd = (unit_energy(u, xp) - unit_energy(u, xm)) / (2.0 * h);
                assert!((fd - b[d]).abs() < 1e-7 * (1.0 + fd.abs()), "corner {k}, axis {d}: b {} against {fd}", b[d]);
            }
            assert!(a.symmetric_eigenvalues().min() > 0.0, "corner {k}: {a}");
        }
    }

    /// An unstrained face leaves its corner where it is; a stretched one pulls it back.
    #[test]
    fn a_flat_sheet_keeps_the_midpoint_and_a_stretched_face_pulls_back() {
        let u = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
        let x = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let (_, b) = stretching(u, x, 1);
        assert!(b.norm() < 1e-15);
        let x = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.2, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let (a, b) = stretching(u, x, 1);
        let step = -a.try_inverse().unwrap() * b;
        assert!(step.x < 0.0, "a corner stretched outward moves back: {step:?}");
    }

    /// A hinge kinked by its node's offset straightens under the step: a wing pushed below
    /// the plane of a flat hinge moves back up, and a flat hinge gives no push.
    #[test]
    fn a_kinked_hinge_straightens() {
        let flat =
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.5, -1.0, 0.0)];
        assert!(bending(flat, 2).1.norm() < 1e-15);
        let mut kinked = flat;
        kinked[2].z = -0.1;
        let (a, b) = bending(kinked, 2);
        let step = -(a + REGULARISATION * Mat3::identity()).try_inverse().unwrap() * b;
        assert!(step.z > 0.0 && step.z < 0.1 + 1e-9, "{step:?}");
    }
}
