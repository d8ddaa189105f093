//! Oscillatory modes (§5): travelling waves that the coarse run cannot explain (a flag in strong
//! wind), added back after U along the upsampled normals.
//!
//! The residual normal displacements d_i = (p_f − U p_c)_iᵀ n_i of every training frame are
//! stacked as D (N × F). One pair of modes is D ≈ E Ω(θ), E ∈ R^{N×2} and Ω's column j =
//! (sin jθ, cos jθ) for frame j, so vertex i moves as r_i sin(φ_i + jθ) (eq. 7). θ comes from
//! the autocorrelation of D's columns (the strongest period, refined to a fraction of a frame by
//! a parabola through the peak and then by minimising ‖D − E Ω(θ)‖ near it, the objective of
//! §5); E is then the linear regression of D on Ω(θ). Further pairs are fitted to the deflated
//! D − E Ω(θ) until its norm falls below a fraction of the original.
//!
//! At run time frame j (its number in the run) gets E Ω(θ)_j along the normals of U p_c.

use nalgebra::DMatrix;

use crate::math::{Real, Vec3};
use crate::metrics::vertex_normals;

/// Stop deflating once ‖D‖ has fallen below this fraction of the original.
pub const DEFLATION_STOP: Real = 0.05;

/// One pair of oscillatory modes.
#[derive(Clone, Debug, PartialEq)]
pub struct OscillatoryMode {
    /// Phase advance per frame (radians).
    pub theta: Real,
    /// E: per fine node, the (sin, cos) amplitudes (m).
    pub e: Vec<[Real; 2]>,
}

impl OscillatoryMode {
    /// This pair's displacement of node i in frame j: e_i1 sin jθ + e_i2 cos jθ (eq. 7).
    pub fn displacement(&self, i: usize, frame: usize) -> Real {
        let (s, c) = (frame as Real * self.theta).sin_cos();
        self.e[i][0] * s + self.e[i][1] * c
    }

    /// The same pair with frame `first` as j = `first` instead of j = 0: e₁ sin((j−n)θ) +
    /// e₂ cos((j−n)θ) rewritten in sin jθ and cos jθ.
    pub fn shifted(self, first: usize) -> OscillatoryMode {
        let (s, c) = (first as Real * self.theta).sin_cos();
        let e = self.e.iter().map(|&[a, b]| [a * c + b * s, b * c - a * s]).collect();
        OscillatoryMode { theta: self.theta, e }
    }
}

/// Up to `pairs` pairs fitted to `d` (N × F, frame j in column j), strongest first.
pub fn fit_modes(d: &DMatrix<Real>, pairs: usize) -> Vec<OscillatoryMode> {
    let total = d.norm();
    let mut rest = d.clone();
    let mut modes = Vec::new();
    while modes.len() < pairs && rest.norm() > DEFLATION_STOP * total && total > 0.0 {
        let Some(theta) = dominant_frequency(&rest) else { break };
        let (e, fitted) = regress(&rest, theta);
        rest -= fitted;
        modes.push(OscillatoryMode { theta, e });
    }
    modes
}

/// The frequency θ (radians per frame) of the strongest periodic component of `d`'s columns:
/// the autocorrelation's highest peak past its first zero crossing, interpolated, then refined
/// by the least-squares fit of §5. None when there is no such peak (fewer than ~2 periods).
pub fn dominant_frequency(d: &DMatrix<Real>) -> Option<Real> {
    let f = d.ncols();
    // R(τ) = mean over j of ⟨d_j, d_{j+τ}⟩, lags up to half the frames (enough overlap).
    let r: Vec<Real> = (0..=f / 2)
        .map(|tau| (0..f - tau).map(|j| d.column(j).dot(&d.column(j + tau))).sum::<Real>() / (f - tau) as Real)
        .collect();
    let zero = r.iter().position(|&x| x <= 0.0).filter(|&z| z > 0)?;
    // The first peak past the zero crossing that is at least half the highest: multiples of
    // the period peak about as high, and must not halve θ.
    let peaks: Vec<usize> =
        (zero..r.len() - 1).filter(|&t| r[t] > 0.0 && r[t] >= r[t - 1] && r[t] >= r[t + 1]).collect();
    let top = peaks.iter().map(|&t| r[t]).fold(0.0, Real::max);
    let peak = peaks.into_iter().find(|&t| r[t] >= 0.5 * top)?;
    // A parabola through the peak and its neighbours places it between lags.
    let (a, b, c) = (r[peak - 1], r[peak], r[peak + 1]);
    let den = a - 2.0 * b + c;
    let period = peak as Real + if den < 0.0 { 0.5 * (a - c) / den } else { 0.0 };
    let theta = 2.0 * std::f64::consts::PI / period;
    // Golden-section search of ‖D − E Ω(θ)‖ within a fifth of the peak's lag resolution.
    let width = theta * 0.5 / period;
    Some(golden(|t| misfit(d, t), theta - width, theta + width))
}

/// E = D Ωᵀ (Ω Ωᵀ)⁻¹ and E Ω, the least-squares fit of `d` by one pair at `theta`.
fn regress(d: &DMatrix<Real>, theta: Real) -> (Vec<[Real; 2]>, DMatrix<Real>) {
    let omega = DMatrix::from_fn(2, d.ncols(), |k, j| {
        let (s, c) = (j as Real * theta).sin_cos();
        if k == 0 {
            s
        } else {
            c
        }
    });
    let gram = &omega * omega.transpose();
    let Some(inv) = gram.try_inverse() else {
        return (vec![[0.0; 2]; d.nrows()], DMatrix::zeros(d.nrows(), d.ncols()));
    };
    let e = d * omega.transpose() * inv;
    let fitted = &e * omega;
    ((0..d.nrows()).map(|i| [e[(i, 0)], e[(i, 1)]]).collect(), fitted)
}

fn misfit(d: &DMatrix<Real>, theta: Real) -> Real {
    (d - regress(d, theta).1).norm_squared()
}

/// The minimiser of a unimodal `f` on [a, b], to 1e-12 of the interval.
fn golden(f: impl Fn(Real) -> Real, mut a: Real, mut b: Real) -> Real {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..60 {
        if fc < fd {
            (b, d, fd) = (d, c, fc);
            c = b - g * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

/// The residual normal displacement of each node, (p_f − u)ᵀ n with n the normals of the
/// upsampled surface `u` (§5): one column of D.
pub fn normal_residual(upsampled: &[Vec3], fine: &[Vec3], triangles: &[[usize; 3]]) -> Vec<Real> {
    let n = vertex_normals(upsampled, triangles);
    fine.iter().zip(upsampled).zip(&n).map(|((f, u), n)| (f - u).dot(n)).collect()
}

/// Adds the modes' displacements of frame `frame` to `x` (U p_c) along its normals: per node
/// Σ e_i1 sin jθ + e_i2 cos jθ, eq. 7, as `displacement` computes it, with each pair's
/// (sin jθ, cos jθ) evaluated once per frame rather than once per node.
pub fn add_modes(modes: &[OscillatoryMode], x: &mut [Vec3], triangles: &[[usize; 3]], frame: usize) {
    if modes.is_empty() {
        return;
    }
    let phase: Vec<(Real, Real)> = modes.iter().map(|m| (frame as Real * m.theta).sin_cos()).collect();
    let n = vertex_normals(x, triangles);
    for (i, (p, n)) in x.iter_mut().zip(n).enumerate() {
        *p += n * modes.iter().zip(&phase).map(|(m, &(s, c))| m.e[i][0] * s + m.e[i][1] * c).sum::<Real>();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// D for a travelling wave a sin(k x_i − θ j + φ) on N points over F frames, plus a second
    /// weaker wave when `second` is given.
    fn waves(theta: Real, second: Option<Real>) -> DMatrix<Real> {
        DMatrix::from_fn(300, 120, |i, j| {
            let x = i as Real / 300.0;
            let w1 = 0.02 * (9.0 * x - theta * j as Real + 0.4).sin() * (1.0 + x);
            w1 + second.map_or(0.0, |t2| 0.006 * (4.0 * x - t2 * j as Real).sin())
        })
    }

    #[test]
    fn recovers_a_travelling_waves_frequency_within_two_percent() {
        for period in [7.3, 12.9, 23.6] {
            let theta = 2.0 * std::f64::consts::PI / period;
            let modes = fit_modes(&waves(theta, None), 3);
            let got = modes[0].theta;
            assert!((got / theta - 1.0).abs() < 0.02, "period {period}: θ {got} vs {theta}");
            // One pair explains a single wave: deflation stops there.
            assert_eq!(modes.len(), 1, "period {period}");
            // E reproduces the amplitude: r_i = √(e₁² + e₂²) = 0.02 (1 + x_i).
            let r = |i: usize| modes[0].e[i][0].hypot(modes[0].e[i][1]);
            assert!((r(150) - 0.03).abs() < 1e-4, "{}", r(150));
        }
    }

    #[test]
    fn deflation_finds_a_second_wave() {
        let (t1, t2) = (2.0 * std::f64::consts::PI / 11.0, 2.0 * std::f64::consts::PI / 31.0);
        let d = waves(t1, Some(t2));
        let modes = fit_modes(&d, 4);
        assert!(modes.len() >= 2, "{} pairs", modes.len());
        assert!((modes[0].theta / t1 - 1.0).abs() < 0.02, "first {} vs {t1}", modes[0].theta);
        assert!((modes[1].theta / t2 - 1.0).abs() < 0.02, "second {} vs {t2}", modes[1].theta);
        // Added back frame by frame they reproduce D (to the deflation threshold).
        let rebuilt = DMatrix::from_fn(d.nrows(), d.ncols(), |i, j| modes.iter().map(|m| m.displacement(i, j)).sum());
        assert!((&d - rebuilt).norm() < DEFLATION_STOP * d.norm(), "rebuilt within the stop fraction");
    }

    #[test]
    fn shifting_keeps_the_displacements_and_add_modes_moves_along_normals() {
        let m = OscillatoryMode { theta: 0.7, e: vec![[0.01, -0.02], [0.0, 0.03]] };
        let s = m.clone().shifted(5);
        for j in 0..20 {
            for i in 0..2 {
                assert!((s.displacement(i, j + 5) - m.displacement(i, j)).abs() < 1e-15);
            }
        }
        // A flat square in the xy plane: normals ±z, so only z changes, by the displacement.
        let mut x = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let modes = [OscillatoryMode { theta: 0.3, e: vec![[0.01, 0.02]; 3] }];
        add_modes(&modes, &mut x, &[[0, 1, 2]], 4);
        let want = 0.01 * (1.2 as Real).sin() + 0.02 * (1.2 as Real).cos();
        assert!(x.iter().all(|p| (p.z - want).abs() < 1e-15), "{x:?}");
        assert_eq!((x[1].x, x[2].y), (1.0, 1.0));
    }

    /// `add_modes` (phases once per frame) adds exactly what `displacement` gives per node.
    #[test]
    fn add_modes_matches_displacement_to_the_bit() {
        let modes: Vec<OscillatoryMode> = (0..3)
            .map(|k| OscillatoryMode { theta: 0.37 + 0.21 * k as Real, e: vec![[0.013, -0.007 * k as Real]; 3] })
            .collect();
        let x0 = vec![Vec3::new(0.0, 0.0, 0.1), Vec3::new(1.0, 0.2, 0.0), Vec3::new(0.1, 1.0, 0.3)];
        let n = vertex_normals(&x0, &[[0, 1, 2]]);
        for frame in [0, 7, 123] {
            let mut x = x0.clone();
            add_modes(&modes, &mut x, &[[0, 1, 2]], frame);
            for i in 0..3 {
                let want = x0[i] + n[i] * modes.iter().map(|m| m.displacement(i, frame)).sum::<Real>();
                assert_eq!(x[i].map(Real::to_bits), want.map(Real::to_bits), "frame {frame}, node {i}");
            }
        }
    }

    #[test]
    fn no_oscillation_gives_no_modes() {
        assert!(fit_modes(&DMatrix::zeros(10, 40), 2).is_empty());
        // A static offset: its autocorrelation never crosses zero.
        assert!(fit_modes(&DMatrix::from_element(10, 40, 0.01), 2).is_empty());
    }
}
