//! Deterministic randomness for the tests (xorshift64*, Vigna 2016), without a dependency: the
//! unit tests' `math::test_rng`, and the integration tests' `common::Rng` (`tests/common`
//! compiles this file too), so that failures reproduce.
#![allow(dead_code)] // not every test crate uses every method

use super::{Real, Vec3};

/// The state; any seed but 0 (which xorshift keeps at 0).
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> Real {
        (self.next_u64() >> 11) as Real / (1u64 << 53) as Real
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: Real, hi: Real) -> Real {
        lo + (hi - lo) * self.uniform()
    }

    /// An integer in 0..n (0 when n is 0), by remainder (a slight bias, no matter here).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    /// Uniform in the cube [−1, 1)³.
    pub fn vec(&mut self) -> Vec3 {
        Vec3::new(self.uniform(), self.uniform(), self.uniform()) * 2.0 - Vec3::repeat(1.0)
    }
}
