//! Deterministic randomness for the unit tests (xorshift64*), without a dependency.

use super::{Real, Vec3};

pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> Real {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as Real / (1u64 << 53) as Real
    }

    /// Uniform in the cube [−1, 1)³.
    pub fn vec(&mut self) -> Vec3 {
        Vec3::new(self.uniform(), self.uniform(), self.uniform()) * 2.0 - Vec3::repeat(1.0)
    }
}
