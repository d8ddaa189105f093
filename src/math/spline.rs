//! The spline through values keyed in time, shared by keyframed motions (`math::motion`) and
//! camera paths (`camera`).
//!
//! It is the cubic Hermite spline with tangents m_i = (x[i+1] − x[i−1]) / (t[i+1] − t[i−1]) at
//! interior keys and zero at the first and last key (ARCSim's motion splines; Catmull–Rom for
//! evenly spaced keys). On segment i, with Δt = t[i+1] − t[i] and s = (t − t[i]) / Δt,
//!
//!   x(s) = h00 x_i + h10 Δt m_i + h01 x_{i+1} + h11 Δt m_{i+1}.
//!
//! Before the first key and after the last the value holds. Motions evaluate it on the key values
//! (their keys may also state tangents); cameras take it as weights on the keys, since it is
//! linear in the key values, so that points, directions and scalars share one spline. The weights
//! sum to 1 (h00 + h01 = 1 and tangents are differences), so combining points is affine.

use super::Real;

/// Where a time falls among the keys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    /// Key k holds: before the first key, at or after the last, or a single key.
    Hold(usize),
    /// Between keys i and i + 1, at s = (t − t[i]) / Δt ∈ [0, 1].
    Between { i: usize, s: Real },
}

/// Where time `t` falls among `keys` (non-empty, `time` strictly increasing). A NaN `t` holds
/// the first key.
pub fn locate<K>(keys: &[K], time: impl Fn(&K) -> Real, t: Real) -> Segment {
    let n = keys.len();
    let at = |i: usize| time(&keys[i]);
    if n == 1 || t.is_nan() || t <= at(0) {
        return Segment::Hold(0);
    }
    if t >= at(n - 1) {
        return Segment::Hold(n - 1);
    }
    // t[i] ≤ t < t[i + 1]; i ≤ n − 2 because t < t[n − 1].
    let i = keys.partition_point(|k| time(k) <= t) - 1;
    let dt = at(i + 1) - at(i);
    Segment::Between { i, s: ((t - at(i)) / dt).clamp(0.0, 1.0) }
}

/// The cubic Hermite basis [h00, h10, h01, h11] at s ∈ [0, 1]:
/// h00 = 2s³ − 3s² + 1, h10 = s³ − 2s² + s, h01 = −2s³ + 3s², h11 = s³ − s².
pub fn hermite_basis(s: Real) -> [Real; 4] {
    let (s2, s3) = (s * s, s * s * s);
    [2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2]
}

/// `hermite_basis` rounded as keyframed motions have always evaluated it ((3s)·s where that has
/// 3·s²; the two can differ in the last bit). Motions keep it so that runs with moving obstacles
/// and handles stay bit-identical.
pub fn hermite_basis_motion(s: Real) -> [Real; 4] {
    [
        2.0 * s.powi(3) - 3.0 * s * s + 1.0,
        s.powi(3) - 2.0 * s * s + s,
        -2.0 * s.powi(3) + 3.0 * s * s,
        s.powi(3) - s * s,
    ]
}

/// Up to four (key index, weight) pairs; unused slots have weight 0.
pub type Weights = [(usize, Real); 4];

/// Key k alone.
pub fn hold_weights(k: usize) -> Weights {
    [(k, 1.0), (k, 0.0), (k, 0.0), (k, 0.0)]
}

/// Linear interpolation on segment i at s: keys i and i + 1.
pub fn linear_weights(i: usize, s: Real) -> Weights {
    [(i, 1.0 - s), (i + 1, s), (i, 0.0), (i, 0.0)]
}

/// The Hermite spline with central-difference tangents on segment i at s, as weights on keys
/// i − 1 … i + 2.
pub fn catmull_rom_weights(times: &[Real], i: usize, s: Real) -> Weights {
    let n = times.len();
    let [h00, h10, h01, h11] = hermite_basis(s);
    let dt = times[i + 1] - times[i];
    // Δt m_i = c_i (x[i+1] − x[i−1]); c ∈ (0, 1), zero at the end keys.
    let c_i = if i > 0 { dt / (times[i + 1] - times[i - 1]) } else { 0.0 };
    let c_j = if i + 2 < n { dt / (times[i + 2] - times[i]) } else { 0.0 };
    [(i.saturating_sub(1), -h10 * c_i), (i, h00 - h11 * c_j), (i + 1, h01 + h10 * c_i), ((i + 2).min(n - 1), h11 * c_j)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spline (or linear interpolation) through (times, xs) at t, from its weights.
    fn eval(times: &[Real], xs: &[Real], t: Real, linear: bool) -> Real {
        let w = match locate(times, |&tk| tk, t) {
            Segment::Hold(k) => hold_weights(k),
            Segment::Between { i, s } if linear => linear_weights(i, s),
            Segment::Between { i, s } => catmull_rom_weights(times, i, s),
        };
        w.iter().map(|&(k, w)| w * xs[k]).sum()
    }

    #[test]
    fn weights_sum_to_one() {
        let times = [0.0, 1.0, 3.0, 3.5, 7.0];
        for linear in [true, false] {
            for k in 0..=80 {
                let t = -0.5 + 0.1 * k as Real;
                let sum = eval(&times, &[1.0; 5], t, linear);
                assert!((sum - 1.0).abs() < 1e-12, "linear {linear}, t = {t}: {sum}");
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
        let got = eval(&times, &xs, 1.5, false);
        assert!((got - expected).abs() < 1e-12, "{got} vs {expected}");
    }

    #[test]
    fn end_tangents_are_zero() {
        let times = [0.0, 1.0];
        let xs = [0.0, 1.0];
        // Zero end tangents: smoothstep, flat at both ends.
        let eps = 1e-4;
        assert!(eval(&times, &xs, eps, false) < 1e-7);
        assert!(eval(&times, &xs, 1.0 - eps, false) > 1.0 - 1e-7);
        assert!((eval(&times, &xs, 0.5, false) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn both_roundings_of_the_basis_agree() {
        for k in 0..=100 {
            let s = k as Real / 100.0;
            let (a, b) = (hermite_basis(s), hermite_basis_motion(s));
            for j in 0..4 {
                assert!((a[j] - b[j]).abs() < 1e-15, "s = {s}: {a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn nan_time_holds_the_first_key() {
        assert_eq!(locate(&[0.0, 1.0], |&tk| tk, Real::NAN), Segment::Hold(0));
    }
}
