//! Learning U (§3): the partition-of-unity-constrained, harmonically regularised least squares
//! of eq. 5, solved row by row in the harmonic basis.
//!
//! We weight both norms by the (mean-1) lumped mass V, i.e. write U = Φ Û with Φ the
//! mass-orthonormal harmonics (the paper's Q = V^{1/2} Φ). Eq. 5 becomes, per mode n,
//!   min_û ‖û P_c − y_n‖² + γ_n² ‖û‖²   subject to   û·1_M = s_n,
//! with y_n = (Φᵀ V P_f)_n and s = Φᵀ V 1_N (U 1 = 1 ⇔ Û 1 = Φᵀ V 1, eq. 3's constraint set).
//! As the constant is the first mode, s = (√N, 0, …, 0): every mode past K has s_n = 0, and its
//! row's optimum tends to û_n = 0 as γ_n grows, which is what keeping only K < N modes assumes.
//! So rows of U sum to one (to round-off) however few modes are kept. Truncation is an
//! approximation, though: it drops whatever the high modes would have fitted (a linear ramp has
//! components in all of them), so use all N modes (the paper's choice, and free once the dense
//! eigensolve is done) unless γ is large past K.
//!
//! Each row's KKT system (S + γ_n² I) û + μ 1 = P_c y_nᵀ, 1ᵀ û = s_n shares S = P_c P_cᵀ; one
//! eigendecomposition S = W Σ Wᵀ makes every row O(M²) (the rows are independent, §3.2).
//!
//! `Prior::Barycentric` (ours, not the paper's) damps U towards the barycentric embedding B
//! instead of towards zero: γ_n² ‖û − b̂_n‖² with b̂ = Φᵀ V B, so the right-hand side gains
//! γ_n² b̂_nᵀ. As b̂_n · 1 = s_n (B's rows sum to one), the constraint is unchanged, and as γ
//! grows U tends to B — the coarse surface itself — rather than to every row averaging the
//! coarse nodes (what zero is, under the constraint). With few training motions the data
//! cannot pin the low modes of U down, and shrinking them to zero costs more than it saves
//! (`tests/upsample_loop.rs` measures both; cross-validation chooses, `validate`).

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::{Embedding, Harmonics, Operator, Profile, UpsampleError};
use crate::math::{Real, Vec3};

/// Aligned training frames (§3.1): coarse node positions and fine node positions per frame.
#[derive(Clone, Debug, Default)]
pub struct TrainingSet {
    pub coarse: Vec<Vec<Vec3>>,
    pub fine: Vec<Vec<Vec3>>,
}

/// What the regulariser damps U towards (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Prior {
    /// The paper's eq. 5: ‖Γ Qᵀ U‖².
    Zero,
    /// ‖Γ Qᵀ (U − B)‖², B the barycentric embedding of the fine nodes in the coarse mesh.
    Barycentric,
}

/// Learns U from `data` with the harmonics `h` of the fine mesh and the damping `profile`
/// (eq. 5, damped towards zero).
pub fn fit(h: &Harmonics, profile: &Profile, data: &TrainingSet) -> Result<Operator, UpsampleError> {
    fit_towards(h, profile, data, None)
}

/// As `fit`, damped towards the embedding `prior` when given (`Prior::Barycentric`).
pub fn fit_towards(
    h: &Harmonics,
    profile: &Profile,
    data: &TrainingSet,
    prior: Option<&Embedding>,
) -> Result<Operator, UpsampleError> {
    let (pc, pf) = data.stacked(h.modes.nrows())?;
    let normal = NormalEquations::new(h, &pc, &pf, prior);
    // U = Φ Û.
    let u = &h.modes * normal.coefficients(profile, prior.is_some());
    if u.iter().any(|v| !v.is_finite()) {
        return Err(UpsampleError::NonFinite { what: "the fitted operator" });
    }
    Ok(Operator::new(u))
}

impl TrainingSet {
    /// P_c (M × 3F) and P_f (N × 3F), checked: equal frame counts, `fine_nodes` fine nodes,
    /// one coarse node count, finite coordinates.
    pub fn stacked(&self, fine_nodes: usize) -> Result<(DMatrix<Real>, DMatrix<Real>), UpsampleError> {
        let m = self.coarse.first().ok_or(UpsampleError::NoFrames)?.len();
        let pc = stack(&self.coarse, m, "coarse")?;
        let pf = stack(&self.fine, fine_nodes, "fine")?;
        if pc.ncols() != pf.ncols() {
            let what = format!("{} coarse frames but {} fine", self.coarse.len(), self.fine.len());
            return Err(UpsampleError::BadFrame { frame: self.coarse.len().min(self.fine.len()), what });
        }
        Ok((pc, pf))
    }
}

/// What eq. 5 needs from one training set, shared by every damping profile (module doc):
/// S = P_c P_cᵀ = W Σ Wᵀ, and, in that eigenbasis, r̃_n = Wᵀ P_c y_nᵀ and ẽ = Wᵀ 1_M.
pub struct NormalEquations {
    /// b̃_n = Wᵀ b̂_nᵀ (M × K), the barycentric prior in S's eigenbasis, when one was given.
    prior: Option<DMatrix<Real>>,
    sigma: DVector<Real>,
    w: DMatrix<Real>,
    /// Column n: r̃_n (M × K).
    rt: DMatrix<Real>,
    et: DVector<Real>,
    /// s = Φᵀ V 1_N, the row sums Û must have.
    s: DVector<Real>,
}

impl NormalEquations {
    pub fn new(h: &Harmonics, pc: &DMatrix<Real>, pf: &DMatrix<Real>, prior: Option<&Embedding>) -> NormalEquations {
        let vphi = mass_weighted(h);
        let s = vphi.row_sum().transpose(); // Φᵀ V 1_N
        let r = pc * (pf.transpose() * &vphi); // column n: P_c y_nᵀ (M × K)
        let eig = SymmetricEigen::new(pc * pc.transpose());
        let w = eig.eigenvectors;
        let rt = w.transpose() * r;
        let et = w.transpose() * DVector::from_element(pc.nrows(), 1.0);
        let prior = prior.map(|b| {
            // b̂ᵀ = Bᵀ (Φᵀ V)ᵀ, M × K, from B's three entries per row.
            let mut bt = DMatrix::zeros(pc.nrows(), vphi.ncols());
            for (i, row) in b.rows.iter().enumerate() {
                for &(j, wj) in row {
                    for n in 0..vphi.ncols() {
                        bt[(j, n)] += wj * vphi[(i, n)];
                    }
                }
            }
            w.transpose() * bt
        });
        NormalEquations { prior, sigma: eig.eigenvalues, w, rt, et, s }
    }

    /// Û (K × M), row n from eq. 5 with γ_n of `profile`, damped towards the prior when
    /// `towards_prior` (and one was given).
    pub fn coefficients(&self, profile: &Profile, towards_prior: bool) -> DMatrix<Real> {
        self.w_times(&self.coefficients_in_eigenbasis(profile, towards_prior)).transpose()
    }

    /// Ũ = Wᵀ Ûᵀ (M × K), column n the row solve of mode n in S's eigenbasis.
    pub fn coefficients_in_eigenbasis(&self, profile: &Profile, towards_prior: bool) -> DMatrix<Real> {
        let mut ut = DMatrix::zeros(self.w.nrows(), self.rt.ncols());
        let prior = self.prior.as_ref().filter(|_| towards_prior);
        for n in 0..self.rt.ncols() {
            let gamma = profile.gamma(n + 1);
            let mut rhs = self.rt.column(n).into_owned();
            if let Some(b) = prior {
                rhs.axpy(gamma * gamma, &b.column(n), 1.0);
            }
            let col = row_in_eigenbasis(&self.sigma, &rhs, &self.et, self.s[n], gamma);
            ut.set_column(n, &col);
        }
        ut
    }

    /// W x, back from S's eigenbasis.
    pub fn w_times(&self, x: &DMatrix<Real>) -> DMatrix<Real> {
        &self.w * x
    }

    /// Wᵀ x, into S's eigenbasis.
    pub fn wt_times(&self, x: &DMatrix<Real>) -> DMatrix<Real> {
        self.w.transpose() * x
    }
}

/// Φᵀ V, the mass-weighted projection onto the harmonics, kept transposed (N × K).
pub fn mass_weighted(h: &Harmonics) -> DMatrix<Real> {
    DMatrix::from_fn(h.modes.nrows(), h.modes.ncols(), |i, n| h.mass[i] * h.modes[(i, n)])
}

/// One row of eq. 5 in S's eigenbasis: ũ = D (r̃ − μ ẽ), D = (Σ + γ² I)^{-1}, with the
/// multiplier μ chosen so that ẽᵀ ũ = 1ᵀ û = s (the partition-of-unity row constraint).
fn row_in_eigenbasis(
    sigma: &DVector<Real>,
    rt: &DVector<Real>,
    et: &DVector<Real>,
    s: Real,
    gamma: Real,
) -> DVector<Real> {
    // S is PSD; round-off can leave tiny negative eigenvalues, which must not cancel γ².
    let d = sigma.map(|x| 1.0 / (x.max(0.0) + gamma * gamma));
    let mu = (et.component_mul(&d).dot(rt) - s) / et.component_mul(&d).dot(et);
    (rt - et * mu).component_mul(&d)
}

/// Frames as columns of a `rows × 3F` matrix (frame f's x, y, z in columns 3f, 3f+1, 3f+2).
fn stack(frames: &[Vec<Vec3>], rows: usize, which: &str) -> Result<DMatrix<Real>, UpsampleError> {
    let mut p = DMatrix::zeros(rows, 3 * frames.len());
    for (f, x) in frames.iter().enumerate() {
        if x.len() != rows {
            return Err(UpsampleError::BadFrame {
                frame: f,
                what: format!("{which} frame has {} nodes, expected {rows}", x.len()),
            });
        }
        if x.iter().any(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(UpsampleError::BadFrame {
                frame: f,
                what: format!("{which} frame has a non-finite coordinate"),
            });
        }
        for (i, v) in x.iter().enumerate() {
            for d in 0..3 {
                p[(i, 3 * f + d)] = v[d];
            }
        }
    }
    Ok(p)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::upsample::{embedding, Laplacian, Surface};

    /// A smooth deformation of the material plane, different per frame `t`.
    pub(crate) fn shape(p: Vec2, t: Real) -> Vec3 {
        let z = 0.1 * (3.0 * p.x + t).sin() * (1.0 + p.y) + 0.05 * (2.0 * p.y - 0.5 * t).cos();
        Vec3::new(p.x + 0.02 * t * p.y, p.y, z)
    }

    /// The nodes of `s` deformed by `shape` at each of `times`.
    pub(crate) fn frames(s: &Surface, times: &[Real]) -> Vec<Vec<Vec3>> {
        let uv = s.node_uv();
        times.iter().map(|&t| uv.iter().map(|p| shape(p.unwrap(), t)).collect()).collect()
    }

    struct Case {
        coarse: Surface,
        fine: Surface,
        op: Operator,
    }

    /// Trained on 24 frames with `modes` harmonics (0: all). The profile is milder than §6's
    /// (γ_1 = 1, γ_N = 10⁵ for N ≈ 7000 and ~1000 frames): with N = 221 and 24 frames that one
    /// damps all but ~15 modes.
    fn trained(modes: usize) -> Case {
        let (coarse, fine) = (Surface::grid(4, 3, 1.0, 0.75), Surface::grid(16, 12, 1.0, 0.75));
        let modes = if modes == 0 { fine.nodes } else { modes };
        let h = Harmonics::new(&Laplacian::new(&fine).unwrap(), modes).unwrap();
        let times: Vec<Real> = (0..24).map(|f| 0.3 * f as Real).collect();
        let data = TrainingSet { coarse: frames(&coarse, &times), fine: frames(&fine, &times) };
        let profile = Profile::from_bounds(1e-3, 10.0, 4.0, fine.nodes).unwrap();
        Case { op: fit(&h, &profile, &data).unwrap(), coarse, fine }
    }

    #[test]
    fn rows_sum_to_one() {
        for modes in [1, 10, 60, 0] {
            let op = trained(modes).op;
            let worst = op.u.row_iter().map(|r| (r.sum() - 1.0).abs()).fold(0.0, Real::max);
            assert!(worst < 1e-9, "{modes} modes: worst row sum error {worst:e}");
        }
    }

    /// The exact property: rows summing to one make U commute with every affine map
    /// x ↦ A x + t of the coarse mesh, U(P_c Aᵀ + 1 tᵀ) = (U P_c) Aᵀ + 1 tᵀ (§3, after eq. 1).
    /// It maps the *upsampled* mesh, not the training fine mesh: U only approximates P_f.
    #[test]
    fn upsampling_commutes_with_affine_maps() {
        let case = trained(40);
        let a = nalgebra::Matrix3::new(0.8, -0.6, 0.3, 0.6, 0.8, -0.2, 0.1, 0.4, 1.7);
        let t = Vec3::new(12.0, -3.5, 40.0);
        let pc = frames(&case.coarse, &[1.7]).remove(0);
        let moved: Vec<Vec3> = pc.iter().map(|x| a * x + t).collect();
        let before = case.op.apply(&pc);
        for (y, x) in case.op.apply(&moved).iter().zip(&before) {
            assert!((y - (a * x + t)).norm() < 1e-9 * (1.0 + t.norm()), "{y} vs {}", a * x + t);
        }
    }

    /// The training frames span a few smooth functions of material space, which U can learn
    /// and barycentric embedding cannot: on a held-out frame U is ~4× closer (asserted: 2×).
    #[test]
    fn held_out_frame_is_closer_than_barycentric_embedding() {
        let case = trained(0);
        let b = embedding(&case.coarse, &case.fine);
        let (pc, pf) = (frames(&case.coarse, &[2.05]).remove(0), frames(&case.fine, &[2.05]).remove(0));
        let err = |x: &[Vec3]| x.iter().zip(&pf).map(|(a, b)| (a - b).norm_squared()).sum::<Real>().sqrt();
        let (eu, eb) = (err(&case.op.apply(&pc)), err(&b.apply(&pc)));
        eprintln!("held-out error: upsampled {eu:.4e}, barycentric {eb:.4e}");
        assert!(eu < 0.5 * eb, "upsampled {eu:e} vs barycentric {eb:e}");
    }

    #[test]
    fn mismatched_frames_are_refused() {
        let fine = Surface::grid(2, 2, 1.0, 1.0);
        let h = Harmonics::new(&Laplacian::new(&fine).unwrap(), 3).unwrap();
        let p = Profile::from_bounds(1.0, 10.0, 4.0, 9).unwrap();
        let data = TrainingSet { coarse: vec![vec![Vec3::zeros(); 4]], fine: vec![vec![Vec3::zeros(); 8]] };
        assert!(matches!(fit(&h, &p, &data), Err(UpsampleError::BadFrame { frame: 0, .. })));
        assert_eq!(fit(&h, &p, &TrainingSet::default()), Err(UpsampleError::NoFrames));
    }
}
