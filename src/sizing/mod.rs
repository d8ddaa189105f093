//! The sizing field (Narain, Samii & O'Brien 2012, §3): per face, a 2×2 metric M in material
//! space; an edge with material vector u is too long when √(uᵀ M̄ u) > 1, M̄ the mean of its
//! end vertices' metrics. Criteria: curvature, compression (buckling), velocity gradient and
//! obstacle proximity, combined by tensor max (or sum) and clamped to the size limits and the
//! minimum aspect ratio (eqs. 2–6 and §3.4; formulas as in DESIGN.md "Sizing field").

pub mod occlusion;
pub mod remesh_jump;
pub mod tensor_max;
pub mod view;
pub mod view_memory;

use crate::math::PAR_GRAIN;
use rayon::prelude::*;

use crate::forces::edge_angles;
use crate::math::{eigen_sym2, Mat2, Mat3x2, Real, Vec2, Vec3};
use crate::mesh::Mesh;
pub use tensor_max::tensor_max;
pub use view::{FaceView, ViewParams};

/// How criteria are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Combine {
    /// Smallest metric dominating every criterion (ARCSim).
    Max,
    /// Plain sum of the criteria.
    Sum,
}

/// Refinement criteria; a `None` criterion is off.
#[derive(Clone, Debug, PartialEq)]
pub struct SizingParams {
    /// Δθ (radians): angle a face may bend through.
    pub refine_angle: Option<Real>,
    /// c: compression (strain) a face may buckle through.
    pub refine_compression: Option<Real>,
    /// Δv (m/s): velocity difference allowed across a face.
    pub refine_velocity: Option<Real>,
    /// Refine near obstacles.
    pub refine_obstacle: bool,
    /// Edge length limits (m).
    pub size_min: Real,
    pub size_max: Real,
    /// Smallest allowed aspect ratio (0, 1].
    pub aspect_min: Real,
    pub combine: Combine,
}

/// A nearby obstacle feature, linearised as a plane: a point on it and its outward normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstaclePlane {
    pub point: Vec3,
    pub normal: Vec3,
}

/// What one face's sizing depends on.
pub struct FaceState {
    /// Material-space corners.
    pub u: [Vec2; 3],
    pub x: [Vec3; 3],
    pub v: [Vec3; 3],
    /// Unit node normals at the corners.
    pub n: [Vec3; 3],
    /// Dihedral angle θ of the edge opposite each corner (0 on a boundary).
    pub theta: [Real; 3],
    /// Nearest obstacle plane of each corner, if within range.
    pub planes: [Option<ObstaclePlane>; 3],
    /// The camera's view of the face, in view-dependent mode.
    pub view: Option<FaceView>,
    /// The plastic rest shape operator S_p of a face that yields (`forces::plasticity`).
    pub plastic: Option<Mat2>,
}

/// Gradient in material space of a field given at the corners: [f₁ − f₀, f₂ − f₀] D_m⁻¹.
fn material_gradient(dm_inv: &Mat2, f: [Vec3; 3]) -> Mat3x2 {
    Mat3x2::from_columns(&[f[1] - f[0], f[2] - f[0]]) * dm_inv
}

/// Signed square root of a symmetric 2×2 matrix: each eigenvalue λ becomes sign(λ)·√|λ|
/// (ARCSim 0.2.1 `dynamicremesh.cpp`, `sqrt`). A negative eigenvalue of the compression metric's
/// discriminant means the face is curved across its compression, so no buckling is expected
/// there; keeping −√|λ| (rather than 0) lets that curvature silence the criterion.
fn signed_sqrt(m: &Mat2) -> Mat2 {
    let (l, q) = eigen_sym2(m);
    let root = |x: Real| x.signum() * x.abs().sqrt();
    q * Mat2::from_diagonal(&Vec2::new(root(l[0]), root(l[1]))) * q.transpose()
}

fn pos(m: &Mat2) -> Mat2 {
    crate::math::pos_part2(m)
}

/// adj(A) for the compression metric's buckling term: [[a₁₁, −a₁₀], [−a₀₁, a₀₀]].
fn adjugate(a: &Mat2) -> Mat2 {
    Mat2::new(a[(1, 1)], -a[(1, 0)], -a[(0, 1)], a[(0, 0)])
}

/// The criteria metrics of one face (before combination and clamping).
pub fn face_criteria(s: &FaceState, p: &SizingParams) -> Vec<Mat2> {
    let dm = Mat2::from_columns(&[s.u[1] - s.u[0], s.u[2] - s.u[0]]);
    let area = 0.5 * dm.determinant();
    let Some(dm_inv) = dm.try_inverse() else { return Vec::new() };
    if area <= 0.0 {
        return Vec::new();
    }
    let grad_n = material_gradient(&dm_inv, s.n);
    let s2 = grad_n.transpose() * grad_n;
    let mut out = Vec::with_capacity(4);
    if let Some(dtheta) = p.refine_angle {
        // Shape operator from dihedral angles: S = (1/A) Σₑ ½ θₑ |eₑ| t̂ₑ t̂ₑᵀ, t̂ₑ the unit
        // material-space normal of edge e (opposite corner k).
        let mut shape = Mat2::zeros();
        for k in 0..3 {
            let e = s.u[(k + 2) % 3] - s.u[(k + 1) % 3];
            let len = e.norm();
            if len == 0.0 {
                continue;
            }
            let t = Vec2::new(e.y, -e.x) / len;
            shape += (0.5 * s.theta[k] * len / area) * t * t.transpose();
        }
        let m1 = shape.transpose() * shape / (dtheta * dtheta);
        let m2 = s2 / (dtheta * dtheta);
        let curvature = match s.plastic {
            // A crease stays resolved when it is pressed flat or opened: S_pᵀS_p / Δθ² (Narain
            // et al. 2013; ARCSim's `Mcurvp`).
            Some(sp) => tensor_max(&[m1, m2, sp.transpose() * sp / (dtheta * dtheta)]),
            None => tensor_max(&[m1, m2]),
        };
        out.push(curvature * view_scale(s));
    }
    if let Some(c) = p.refine_compression {
        let f = material_gradient(&dm_inv, s.x);
        let e = f.transpose() * f - Mat2::identity();
        let d = e.transpose() * e - 4.0 * c * c * adjugate(&s2);
        out.push(pos(&(-e + signed_sqrt(&d))) / (2.0 * c * c) * view_scale(s));
    }
    if let Some(dv) = p.refine_velocity {
        let gv = material_gradient(&dm_inv, s.v);
        out.push(gv.transpose() * gv / (dv * dv));
    }
    if p.refine_obstacle {
        // ARCSim's obstacle_metric: each corner's plane, scaled by that corner's own distance.
        let mut m = Mat2::zeros();
        for (k, plane) in s.planes.iter().enumerate() {
            let Some(plane) = plane else { continue };
            let h = s.x.map(|x| plane.normal.dot(&(x - plane.point)));
            let grad_h = dm_inv.transpose() * Vec2::new(h[1] - h[0], h[2] - h[0]);
            let hk = h[k].abs().max(1e-9);
            m += grad_h * grad_h.transpose() / (hk * hk);
        }
        out.push(m / 3.0);
    }
    out
}

/// μ² for the curvature and compression criteria in view-dependent mode (Koh et al. 2014,
/// eq. 5: M / (μ⁻¹ Δ)² = μ² M / Δ²), 1 otherwise.
fn view_scale(s: &FaceState) -> Real {
    s.view.map_or(1.0, |v| v.mu * v.mu)
}

/// Combines and clamps: eigenvalues into [1/size_max², 1/size_min²], then λ_min ≥ aspect_min²·λ_max.
pub fn clamp_metric(m: &Mat2, p: &SizingParams) -> Mat2 {
    clamp_metric_to(m, p, p.size_min)
}

/// `clamp_metric` with the smallest edge `size_min` (Koh et al. 2014, eqs. 11–13, where it is
/// the distance-dependent l_min,vd, at most size_max).
fn clamp_metric_to(m: &Mat2, p: &SizingParams, size_min: Real) -> Mat2 {
    let size_min = size_min.min(p.size_max);
    let (l, q) = eigen_sym2(m);
    let (lo, hi) = (1.0 / (p.size_max * p.size_max), 1.0 / (size_min * size_min));
    let mut l = Vec2::new(l[0].clamp(lo, hi), l[1].clamp(lo, hi));
    let floor = p.aspect_min * p.aspect_min * l[1].max(l[0]);
    l = Vec2::new(l[0].max(floor), l[1].max(floor));
    q * Mat2::from_diagonal(&l) * q.transpose()
}

/// The clamped sizing metric of one face.
pub fn face_sizing(s: &FaceState, p: &SizingParams) -> Mat2 {
    let criteria = face_criteria(s, p);
    let m = match p.combine {
        Combine::Max => tensor_max(&criteria),
        Combine::Sum => criteria.iter().fold(Mat2::zeros(), |a, b| a + b),
    };
    clamp_metric_to(&m, p, s.view.map_or(p.size_min, |v| v.size_min))
}

/// Sizing of every face of `mesh` (clamped) with the parameters of its material (cloth),
/// `params[material]`, zero for a cloth without; `planes[node]` is the nearest obstacle plane of
/// each node within range; `views[face]`, when given, the camera's view of each face;
/// `plastic[face]`, when given, the plastic rest shape of each face that yields.
pub fn face_metrics(
    mesh: &Mesh,
    params: &[Option<SizingParams>],
    planes: &[Option<ObstaclePlane>],
    views: &[Option<FaceView>],
    plastic: &[Option<Mat2>],
) -> Vec<Mat2> {
    let angles = edge_angles(mesh);
    let normals = mesh.node_normals();
    (0..mesh.faces.len())
        .into_par_iter()
        .with_min_len(PAR_GRAIN)
        .map(|f| {
            let Some(p) = params.get(mesh.faces[f].material as usize).and_then(Option::as_ref) else {
                return Mat2::zeros();
            };
            let ids = mesh.face_nodes(f);
            let fe = mesh.face_edges[f];
            let state = FaceState {
                u: mesh.face_uv(f),
                x: ids.map(|n| mesh.nodes[n].x),
                v: ids.map(|n| mesh.nodes[n].v),
                n: ids.map(|n| normals[n]),
                theta: fe.map(|e| angles[e.idx()]),
                planes: ids.map(|n| planes.get(n).copied().flatten()),
                view: views.get(f).copied().flatten(),
                plastic: plastic.get(f).copied().flatten(),
            };
            face_sizing(&state, p)
        })
        .collect()
}

/// Vertex metrics: the material-area-weighted mean of the adjacent faces' metrics.
pub fn vertex_metrics(mesh: &Mesh, face: &[Mat2]) -> Vec<Mat2> {
    let mut sum = vec![Mat2::zeros(); mesh.verts.len()];
    let mut area = vec![0.0; mesh.verts.len()];
    for (f, m) in face.iter().enumerate() {
        let a = mesh.material_area(f);
        for v in mesh.faces[f].v {
            sum[v.idx()] += a * m;
            area[v.idx()] += a;
        }
    }
    sum.iter().zip(&area).map(|(m, a)| if *a > 0.0 { m / *a } else { *m }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> SizingParams {
        SizingParams {
            refine_angle: Some(0.3),
            refine_compression: Some(0.005),
            refine_velocity: Some(0.5),
            refine_obstacle: true,
            size_min: 0.01,
            size_max: 0.2,
            aspect_min: 0.2,
            combine: Combine::Max,
        }
    }

    fn flat_face() -> FaceState {
        let u = [Vec2::new(0.0, 0.0), Vec2::new(0.1, 0.0), Vec2::new(0.0, 0.1)];
        FaceState {
            u,
            x: u.map(|p| Vec3::new(p.x, p.y, 0.0)),
            v: [Vec3::zeros(); 3],
            n: [Vec3::z(); 3],
            theta: [0.0; 3],
            planes: [None; 3],
            view: None,
            plastic: None,
        }
    }

    #[test]
    fn flat_resting_face_gets_the_coarsest_size() {
        let p = params();
        let m = face_sizing(&flat_face(), &p);
        assert!((m - Mat2::identity() / (0.2 * 0.2)).norm() < 1e-9);
    }

    #[test]
    fn bending_refines_across_the_fold_only() {
        let p = params();
        let mut f = flat_face();
        // Hypotenuse (opposite corner 0) bent by 0.6 rad: refine along its normal (1,1)/√2.
        f.theta = [0.6, 0.0, 0.0];
        let m = face_sizing(&f, &p);
        let across = Vec2::new(1.0, 1.0).normalize();
        let along = Vec2::new(1.0, -1.0).normalize();
        assert!(across.dot(&(m * across)) > 4.0 * along.dot(&(m * along)));
    }

    #[test]
    fn a_flat_face_with_a_plastic_crease_stays_refined_across_it() {
        // Pressed flat, a face whose plastic rest shape bends about the v axis (κ = 50 /m) is
        // refined along u only, to Δθ/κ.
        let p = SizingParams { refine_compression: None, refine_velocity: None, ..params() };
        let mut s = flat_face();
        assert_eq!(face_criteria(&s, &p)[0], Mat2::zeros());
        s.plastic = Some(Mat2::new(50.0, 0.0, 0.0, 0.0));
        let m = face_criteria(&s, &p)[0];
        let l = 0.3 / 50.0;
        assert!((m[(0, 0)] - 1.0 / (l * l)).abs() < 1e-9 / (l * l), "{m}");
        assert!(m[(1, 1)].abs() < 1e-9 && m[(0, 1)].abs() < 1e-9, "{m}");
    }

    #[test]
    fn compression_and_velocity_refine() {
        let p = params();
        let mut f = flat_face();
        f.x = f.u.map(|u| Vec3::new(0.9 * u.x, u.y, 0.0));
        let m = face_sizing(&f, &p);
        assert!(m[(0, 0)] > 1.0 / (0.2 * 0.2) * 2.0, "{m}");
        let mut f = flat_face();
        f.v = [Vec3::zeros(), Vec3::new(0.0, 0.0, 1.0), Vec3::zeros()];
        let m = face_sizing(&f, &p);
        assert!(m[(0, 0)] > m[(1, 1)] * 2.0, "{m}");
    }

    #[test]
    fn curvature_across_the_compression_silences_it() {
        // Compressed 2% along u (e₀₀ ≈ −0.04) with normals turning along v at 10 m⁻¹: the
        // discriminant's u eigenvalue is e₀₀² − 4c²κ² < 0, so ARCSim's signed root gives no
        // compression refinement (a clamped root would ask for e₀₀/(2c²) ≈ 800 m⁻²).
        let p = SizingParams { refine_angle: None, refine_velocity: None, ..params() };
        let mut f = flat_face();
        f.x = f.u.map(|u| Vec3::new(0.98 * u.x, u.y, 0.0));
        let compressed_flat = face_criteria(&f, &p)[0];
        assert!(compressed_flat[(0, 0)] > 700.0, "{compressed_flat}");
        let kappa = 10.0;
        f.n = f.u.map(|u| Vec3::new(0.0, (kappa * u.y).sin(), (kappa * u.y).cos()));
        let curved = face_criteria(&f, &p)[0];
        assert!(curved.norm() < 1e-9, "{curved}");
    }

    #[test]
    fn view_factor_scales_curvature_and_compression_by_mu_squared() {
        // Koh et al. 2014, eq. 5: M_crv / (μ⁻¹ Δn)² and M_cmp / (μ⁻¹ c)²; velocity unchanged.
        let p = params();
        let mut f = flat_face();
        f.theta = [0.3, 0.0, 0.0];
        f.x = f.u.map(|u| Vec3::new(0.98 * u.x, u.y, 0.0));
        f.v = [Vec3::zeros(), Vec3::new(0.0, 0.0, 1.0), Vec3::zeros()];
        let plain = face_criteria(&f, &p);
        f.view = Some(FaceView { mu: 0.5, size_min: p.size_min, visible: 1.0 });
        let seen = face_criteria(&f, &p);
        assert!(plain[0].norm() > 0.0 && plain[1].norm() > 0.0 && plain[2].norm() > 0.0);
        assert!((seen[0] - plain[0] * 0.25).norm() <= 1e-12 * plain[0].norm(), "{} vs {}", seen[0], plain[0]);
        assert!((seen[1] - plain[1] * 0.25).norm() <= 1e-12 * plain[1].norm(), "{} vs {}", seen[1], plain[1]);
        assert_eq!(seen[2], plain[2]);
    }

    #[test]
    fn view_minimum_edge_caps_the_metric() {
        // Eqs. 10–11: eigenvalues at most l_min,vd⁻², and never below size_max⁻².
        let p = params();
        let mut f = flat_face();
        f.theta = [3.0, 3.0, 3.0];
        let fine = face_sizing(&f, &p);
        assert!((eigen_sym2(&fine).0.max() - 1.0 / (p.size_min * p.size_min)).abs() < 1e-6);
        f.view = Some(FaceView { mu: 1.0, size_min: 0.05, visible: 1.0 });
        let far = face_sizing(&f, &p);
        assert!((eigen_sym2(&far).0.max() - 400.0).abs() < 1e-9, "{far}");
        f.view = Some(FaceView { mu: 1.0, size_min: 10.0, visible: 1.0 });
        let beyond = face_sizing(&f, &p);
        assert!((eigen_sym2(&beyond).0.max() - 1.0 / (p.size_max * p.size_max)).abs() < 1e-9, "{beyond}");
    }

    #[test]
    fn obstacle_metric_scales_each_plane_by_its_own_corners_distance() {
        // ARCSim's obstacle_metric: Σᵥ ∇h ∇hᵀ / h[v]², v the corner whose plane it is.
        let p = params();
        let mut f = flat_face();
        let n = Vec3::new(-0.3, 0.0, 1.0).normalize();
        let plane = ObstaclePlane { point: Vec3::new(0.0, 0.0, -0.002), normal: n };
        f.planes = [Some(plane), None, None];
        let m = face_criteria(&f, &p).pop().unwrap();
        let h0 = n.dot(&(f.x[0] - plane.point));
        let grad = Vec2::new(n.x, n.y);
        let expected = grad * grad.transpose() / (h0 * h0 * 3.0);
        assert!((m - expected).norm() < 1e-9 * expected.norm(), "{m} vs {expected}");
    }

    #[test]
    fn clamps_to_limits_and_aspect() {
        let p = params();
        let m = clamp_metric(&Mat2::new(1e9, 0.0, 0.0, 0.0), &p);
        assert!((m[(0, 0)] - 1e4).abs() < 1e-6);
        assert!((m[(1, 1)] - 0.04 * 1e4).abs() < 1e-6);
    }

    #[test]
    fn near_obstacle_refines_along_the_approach() {
        let p = params();
        let mut f = flat_face();
        // A plane tilted about y, 2 mm under the face's middle: h varies along u.
        let n = Vec3::new(-0.3, 0.0, 1.0).normalize();
        let plane = ObstaclePlane { point: Vec3::new(0.03, 0.03, -0.002), normal: n };
        f.planes = [Some(plane); 3];
        let m = face_sizing(&f, &p);
        assert!(m[(0, 0)] > m[(1, 1)], "{m}");
    }
}
