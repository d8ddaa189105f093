//! The polynomial damping profile of §3.2, γ_n = a (1 + b (n−1)/N)^c for n = 1…N, with a and
//! b found from the bounds γ_1, γ_N and the exponent c as §6 does (paper defaults: γ_1 = 1,
//! γ_N = 10⁵, c = 4).

use super::UpsampleError;
use crate::math::Real;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Profile {
    pub a: Real,
    pub b: Real,
    pub c: Real,
    /// N, the number of fine nodes (the full harmonic count, even when fewer modes are kept).
    pub n: usize,
}

impl Profile {
    /// γ_1 = a; γ_N = a (1 + b (N−1)/N)^c ⇒ b = ((γ_N/γ_1)^{1/c} − 1) · N/(N−1).
    pub fn from_bounds(gamma1: Real, gamma_n: Real, c: Real, n: usize) -> Result<Profile, UpsampleError> {
        let ok = gamma1 > 0.0 && gamma_n >= gamma1 && c >= 0.0 && gamma_n.is_finite() && c.is_finite();
        if !ok {
            return Err(UpsampleError::BadProfile { gamma1, gamma_n, c });
        }
        // c = 0 or N = 1: the profile is flat (plain Tikhonov, Fig. 4) and b does not matter.
        let b = if c == 0.0 || n < 2 {
            0.0
        } else {
            ((gamma_n / gamma1).powf(1.0 / c) - 1.0) * n as Real / (n - 1) as Real
        };
        Ok(Profile { a: gamma1, b, c, n })
    }

    /// γ_n for the 1-based mode index `n`.
    pub fn gamma(&self, n: usize) -> Real {
        self.a * (1.0 + self.b * (n - 1) as Real / self.n as Real).powf(self.c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_are_reproduced_and_the_profile_rises() {
        let p = Profile::from_bounds(1.0, 1e5, 4.0, 7016).unwrap();
        assert!((p.gamma(1) - 1.0).abs() < 1e-12);
        assert!((p.gamma(7016) / 1e5 - 1.0).abs() < 1e-12);
        assert!((1..7016).all(|n| p.gamma(n) < p.gamma(n + 1)));
        // §3.2's example a = 0.8, b = 10, c = 4 gives γ_N = 0.8·(1 + 10(N−1)/N)^4.
        let q = Profile { a: 0.8, b: 10.0, c: 4.0, n: 100 };
        assert!((q.gamma(100) - 0.8 * (1.0 + 10.0 * 0.99f64).powi(4)).abs() < 1e-9);
    }

    #[test]
    fn bad_bounds_are_refused() {
        assert!(Profile::from_bounds(0.0, 1.0, 4.0, 10).is_err());
        assert!(Profile::from_bounds(2.0, 1.0, 4.0, 10).is_err());
        assert!(Profile::from_bounds(1.0, 10.0, -1.0, 10).is_err());
        assert_eq!(Profile::from_bounds(3.0, 3.0, 0.0, 10).unwrap().gamma(10), 3.0);
    }
}
