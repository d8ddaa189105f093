//! Interpolation between camera keys as weights on the keys, so that points, directions and
//! scalars share one spline.
//!
//! Catmull–Rom here is the cubic Hermite spline with tangents
//! m_i = (x[i+1] − x[i−1]) / (t[i+1] − t[i−1]) at interior keys and zero at the first and last
//! key, as the scene's keyframed motions (`scene::motion`). On segment i with s = (t − t_i) / Δt,
//! Δt = t[i+1] − t[i]:
//!
//!   x(s) = h00 x_i + h10 Δt m_i + h01 x_{i+1} + h11 Δt m_{i+1},
//!
//! which is linear in the key values, so it is returned as weights on keys i−1 … i+2. The
//! weights sum to 1 (h00 + h01 = 1 and tangents are differences), so combining points is affine.

use super::spec::Interpolation;
use crate::math::Real;

/// Up to four (key index, weight) pairs; unused slots have weight 0.
pub(super) type Weights = [(usize, Real); 4];

/// Where time `t` falls among the key `times` (strictly increasing, non-empty): the weights of
/// the keys and the key nearest in time (the fallback for degenerate interpolated frames).
/// Before the first key (or for NaN) the first key holds; after the last, the last.
pub(super) fn weights_at(times: &[Real], t: Real, interpolation: Interpolation) -> (Weights, usize) {
    let n = times.len();
    let hold = |k: usize| ([(k, 1.0), (k, 0.0), (k, 0.0), (k, 0.0)], k);
    if n == 1 || t.is_nan() || t <= times[0] {
        return hold(0);
    }
    if t >= times[n - 1] {
        return hold(n - 1);
    }
    // times[i] ≤ t < times[i + 1]; i ≤ n − 2 because t < times[n − 1].
    let i = times.partition_point(|&tk| tk <= t) - 1;
    let dt = times[i + 1] - times[i];
    let s = ((t - times[i]) / dt).clamp(0.0, 1.0);
    let nearest = if s < 0.5 { i } else { i + 1 };
    let w = match interpolation {
        Interpolation::Linear => [(i, 1.0 - s), (i + 1, s), (i, 0.0), (i, 0.0)],
        Interpolation::CatmullRom => catmull_rom(times, i, s),
    };
    (w, nearest)
}

/// Hermite weights on segment i at parameter s ∈ [0, 1].
fn catmull_rom(times: &[Real], i: usize, s: Real) -> Weights {
    let n = times.len();
    let (s2, s3) = (s * s, s * s * s);
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    let dt = times[i + 1] - times[i];
    // Δt m_i = c_i (x[i+1] − x[i−1]); c ∈ (0, 1), zero at the end keys.
    let c_i = if i > 0 { dt / (times[i + 1] - times[i - 1]) } else { 0.0 };
    let c_j = if i + 2 < n { dt / (times[i + 2] - times[i]) } else { 0.0 };
    [(i.saturating_sub(1), -h10 * c_i), (i, h00 - h11 * c_j), (i + 1, h01 + h10 * c_i), ((i + 2).min(n - 1), h11 * c_j)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(times: &[Real], xs: &[Real], t: Real, interpolation: Interpolation) -> Real {
        weights_at(times, t, interpolation).0.iter().map(|&(k, w)| w * xs[k]).sum()
    }

    #[test]
    fn weights_sum_to_one() {
        let times = [0.0, 1.0, 3.0, 3.5, 7.0];
        for interpolation in [Interpolation::Linear, Interpolation::CatmullRom] {
            for k in 0..=80 {
                let t = -0.5 + 0.1 * k as Real;
                let sum: Real = weights_at(&times, t, interpolation).0.iter().map(|&(_, w)| w).sum();
                assert!((sum - 1.0).abs() < 1e-12, "{interpolation:?} t = {t}: {sum}");
            }
        }
    }

    #[test]
    fn catmull_rom_matches_hermite_with_central_tangents() {
        let times = [0.0, 1.0, 3.0, 4.0];
        let xs = [0.0, 2.0, 1.0, 5.0];
        // Segment 1 (t ∈ [1, 3]), s = 0.25: tangents m1 = (1 − 0)/3, m2 = (5 − 2)/3.
        let s: Real = 0.25;
        let (m1, m2, dt) = (1.0 / 3.0, 1.0, 2.0);
        let expected = (2.0 * s.powi(3) - 3.0 * s * s + 1.0) * 2.0
            + (s.powi(3) - 2.0 * s * s + s) * dt * m1
            + (-2.0 * s.powi(3) + 3.0 * s * s) * 1.0
            + (s.powi(3) - s * s) * dt * m2;
        let got = eval(&times, &xs, 1.5, Interpolation::CatmullRom);
        assert!((got - expected).abs() < 1e-12, "{got} vs {expected}");
    }

    #[test]
    fn end_tangents_are_zero() {
        let times = [0.0, 1.0];
        let xs = [0.0, 1.0];
        // Zero end tangents: smoothstep, flat at both ends.
        let eps = 1e-4;
        assert!(eval(&times, &xs, eps, Interpolation::CatmullRom) < 1e-7);
        assert!(eval(&times, &xs, 1.0 - eps, Interpolation::CatmullRom) > 1.0 - 1e-7);
        assert!((eval(&times, &xs, 0.5, Interpolation::CatmullRom) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn nan_time_holds_the_first_key() {
        let (w, nearest) = weights_at(&[0.0, 1.0], Real::NAN, Interpolation::CatmullRom);
        assert_eq!((w[0], nearest), ((0, 1.0), 0));
    }
}
