//! Strain limiting: after the implicit solve, the faces' principal stretches (the singular values
//! σ₁ ≤ σ₂ of the 3×2 deformation gradient F with respect to material space) are brought back
//! into [min, max] (ARCSim's `strain_limits`; Narain, Samii & O'Brien 2012 §6 after Wang, O'Brien
//! & Ramamoorthi 2010, who limit σ per face).
//!
//! Where ARCSim solves one nonlinear least-squares problem over all faces, this is its
//! projective form (Gauss–Seidel over the faces, as in position based dynamics): a face outside
//! the limits gets the nearest deformation with clamped singular values,
//! F' = U clamp(Σ) Vᵀ = F V diag(σ'ᵢ/σᵢ) Vᵀ, and its corners move to the shape F' gives in the
//! mass-weighted least-squares sense (pinned corners do not move), each σ changing by at most a
//! factor `STEP` per projection. Sweeps repeat until every face is within the limits to
//! `TOLERANCE` or `MAX_SWEEPS` is reached; the result says which, and a projection that leaves
//! the worst face worse than before is undone.
//!
//! Known shortfall: on ARCSim's flag.json, once remeshed, the sweeps do not converge (the
//! worst face stays 0.2–0.9 beyond 1.05), with over-relaxation (1.5; 1.8 diverges), with
//! 2000 sweeps (2.6e-3 left at frame 2), with a stretch-only limit, or sweeping outwards from
//! the pinned nodes. A global solve, as ARCSim's, is the way forward.

use crate::forces::membrane::{deformation_gradient, MembraneRest};
use crate::math::{eigen_sym2, Mat2, Real, Vec2, Vec3};
use crate::mesh::Mesh;

/// Largest principal stretch outside the limits at which the projection stops.
pub const TOLERANCE: Real = 1e-3;
/// How far inside the limits a projected face is aimed.
const MARGIN: Real = 0.5 * TOLERANCE;
/// Largest change of a principal stretch in one face projection (a factor).
const STEP: Real = 1.25;
/// Over-relaxation of each face's correction (1: none; see the module's notes).
const OMEGA: Real = 1.0;
/// Sweeps over the faces per step at most.
pub const MAX_SWEEPS: usize = 100;

/// What one strain-limiting projection did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrainLimitReport {
    pub sweeps: usize,
    /// Face projections over all sweeps.
    pub projections: usize,
    /// Largest distance of a principal stretch outside its limits after the projection.
    pub excess: Real,
    pub converged: bool,
    /// The projection made the worst face worse and was undone.
    pub reverted: bool,
}

/// The principal stretches (σ₁ ≤ σ₂) of a face, and the eigenvectors of FᵀF (columns, matching).
fn stretches(f: &nalgebra::Matrix3x2<Real>) -> (Vec2, Mat2) {
    let (l, v) = eigen_sym2(&(f.transpose() * f));
    (Vec2::new(l[0].max(0.0).sqrt(), l[1].max(0.0).sqrt()), v)
}

/// How far the stretches `s` lie outside `[lo, hi]` (0 inside).
fn excess(s: Vec2, [lo, hi]: [Real; 2]) -> Real {
    (lo - s[0]).max(s[1] - hi).max(0.0)
}

/// The principal stretches of face `f` at positions `x`.
pub fn face_stretches(mesh: &Mesh, rest: &MembraneRest, f: usize, x: &[Vec3]) -> Vec2 {
    let xs = mesh.face_nodes(f).map(|n| x[n]);
    stretches(&deformation_gradient(&xs, rest)).0
}

/// Projects the faces whose material has limits (`limits[face.material]`) into them, moving
/// `x` (free nodes only: `inv_mass` > 0) and marking moved nodes in `moved`.
pub fn limit_strain(
    mesh: &Mesh,
    rest: &[MembraneRest],
    limits: &[Option<[Real; 2]>],
    x: &mut [Vec3],
    inv_mass: &[Real],
    moved: &mut [bool],
) -> StrainLimitReport {
    let mut report = StrainLimitReport::default();
    let faces: Vec<usize> = (0..mesh.faces.len())
        .filter(|&f| limits.get(mesh.faces[f].material as usize).is_some_and(|l| l.is_some()))
        .collect();
    let worst_excess = |x: &[Vec3]| {
        faces
            .iter()
            .map(|&f| excess(face_stretches(mesh, &rest[f], f, x), limits[mesh.faces[f].material as usize].unwrap()))
            .fold(0.0, Real::max)
    };
    let before = worst_excess(x);
    if before <= TOLERANCE {
        report.converged = true;
        report.excess = before;
        return report;
    }
    let (x_before, moved_before) = (x.to_vec(), moved.to_vec());
    for _ in 0..MAX_SWEEPS {
        let mut worst: Real = 0.0;
        report.sweeps += 1;
        for &f in &faces {
            let lim = limits[mesh.faces[f].material as usize].expect("filtered");
            let nodes = mesh.face_nodes(f);
            let xs = nodes.map(|n| x[n]);
            let fm = deformation_gradient(&xs, &rest[f]);
            let (s, v) = stretches(&fm);
            let e = excess(s, lim);
            if e <= 0.0 || s[0] <= 1e-9 {
                continue;
            }
            worst = worst.max(e);
            // Aim a little inside the limits, so that a neighbour's projection does not put the
            // face straight back outside them.
            let (lo, hi) = (lim[0] + MARGIN, lim[1] - MARGIN);
            // At most a factor STEP per projection: a nearly collapsed face (σ₁ ≪ min) would
            // otherwise throw its corners far in one move.
            let target = |si: Real| si.clamp(lo, hi).clamp(si / STEP, si * STEP) / si;
            let scale = Vec2::new(target(s[0]), target(s[1]));
            let g = fm * (v * Mat2::from_diagonal(&scale) * v.transpose());
            // Target shape relative to corner 0: x_j − x_0 = G (u_j − u_0), i.e. G D_m e_j.
            let dm = rest[f].dm_inv.try_inverse().unwrap_or_else(Mat2::zeros);
            let shape = [Vec3::zeros(), g * dm.column(0), g * dm.column(1)];
            // Translation: mass-weighted, or fixed by the pinned corners.
            let pinned: Vec<usize> = (0..3).filter(|&j| inv_mass[nodes[j]] <= 0.0).collect();
            if pinned.len() == 3 {
                continue;
            }
            let c = if pinned.is_empty() {
                let w = nodes.map(|n| 1.0 / inv_mass[n]);
                (0..3).map(|j| w[j] * (xs[j] - shape[j])).sum::<Vec3>() / (w[0] + w[1] + w[2])
            } else {
                pinned.iter().map(|&j| xs[j] - shape[j]).sum::<Vec3>() / pinned.len() as Real
            };
            for j in 0..3 {
                if inv_mass[nodes[j]] > 0.0 {
                    x[nodes[j]] += OMEGA * (c + shape[j] - xs[j]);
                    moved[nodes[j]] = true;
                }
            }
            report.projections += 1;
        }
        if worst <= TOLERANCE {
            report.converged = true;
            break;
        }
    }
    report.excess = worst_excess(x);
    // Sweeps that did not converge may leave some face worse than before: then the step keeps
    // its unprojected positions (counted as unconverged) rather than a tangle.
    if report.excess > before {
        x.copy_from_slice(&x_before);
        moved.copy_from_slice(&moved_before);
        report.excess = before;
        report.reverted = true;
    }
    report
}

/// Faces whose material has limits with a principal stretch at a limit (within `slack`) or
/// beyond it, at positions `x`.
pub fn faces_at_limit(
    mesh: &Mesh,
    rest: &[MembraneRest],
    limits: &[Option<[Real; 2]>],
    x: &[Vec3],
    slack: Real,
) -> usize {
    (0..mesh.faces.len())
        .filter(|&f| match limits.get(mesh.faces[f].material as usize).copied().flatten() {
            Some([lo, hi]) => {
                let s = face_stretches(mesh, &rest[f], f, x);
                s[0] <= lo + slack || s[1] >= hi - slack
            }
            None => false,
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::rectangle;

    fn rests(m: &Mesh) -> Vec<MembraneRest> {
        (0..m.faces.len()).map(|f| MembraneRest::new(m.face_uv(f)).unwrap()).collect()
    }

    #[test]
    fn a_stretched_and_sheared_sheet_is_brought_within_the_limits() {
        let mut m = rectangle(1.0, 1.0, 8, 8).unwrap();
        m.compute_masses(&[0.1]);
        let rest = rests(&m);
        // Stretch 20% along x, compress 10% along y, shear, plus a wobble.
        let mut x: Vec<Vec3> = m
            .nodes
            .iter()
            .map(|n| Vec3::new(1.2 * n.x.x + 0.1 * n.x.y, 0.9 * n.x.y, 0.05 * (7.0 * n.x.x).sin()))
            .collect();
        let inv: Vec<Real> = m.nodes.iter().map(|n| 1.0 / n.mass).collect();
        let mut moved = vec![false; x.len()];
        let lim = [Some([0.95, 1.05])];
        let r = limit_strain(&m, &rest, &lim, &mut x, &inv, &mut moved);
        assert!(r.converged, "{r:?}");
        assert!(r.excess <= TOLERANCE, "{r:?}");
        for f in 0..m.faces.len() {
            let s = face_stretches(&m, &rest[f], f, &x);
            assert!(s[0] >= 0.95 - TOLERANCE && s[1] <= 1.05 + TOLERANCE, "face {f}: {s:?}");
        }
    }

    #[test]
    fn faces_within_the_limits_are_left_alone_and_pinned_nodes_stay() {
        let mut m = rectangle(1.0, 1.0, 4, 4).unwrap();
        m.compute_masses(&[0.1]);
        let rest = rests(&m);
        let mut x: Vec<Vec3> = m.nodes.iter().map(|n| Vec3::new(1.01 * n.x.x, n.x.y, 0.0)).collect();
        let before = x.clone();
        let mut inv: Vec<Real> = m.nodes.iter().map(|n| 1.0 / n.mass).collect();
        let mut moved = vec![false; x.len()];
        let r = limit_strain(&m, &rest, &[Some([0.95, 1.05])], &mut x, &inv, &mut moved);
        assert_eq!(r.projections, 0);
        assert_eq!(x, before);
        // Now stretched 30% with the left column pinned.
        let mut x: Vec<Vec3> = m.nodes.iter().map(|n| Vec3::new(1.3 * n.x.x, n.x.y, 0.0)).collect();
        for (i, n) in m.nodes.iter().enumerate() {
            if n.x.x == 0.0 {
                inv[i] = 0.0;
            }
        }
        let pinned: Vec<(usize, Vec3)> = (0..x.len()).filter(|&i| inv[i] == 0.0).map(|i| (i, x[i])).collect();
        let r = limit_strain(&m, &rest, &[Some([0.95, 1.05])], &mut x, &inv, &mut moved);
        assert!(r.converged && r.excess <= TOLERANCE, "{r:?}");
        assert!(pinned.iter().all(|&(i, p)| x[i] == p));
    }
}
