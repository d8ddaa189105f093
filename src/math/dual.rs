//! Forward-mode dual numbers with an N-dimensional derivative part.
//!
//! Used to differentiate hand-written analytic gradients once more, giving exact Hessians for the
//! finite-difference tests and for `Projection::Exact` (the simulation itself uses the cheaper
//! PSD forms).

use std::ops::{Add, Div, Mul, Neg, Sub};

/// `re + Σ eps[i] εᵢ` with εᵢεⱼ = 0.
#[derive(Clone, Copy, Debug)]
pub struct Dual<const N: usize> {
    pub re: f64,
    pub eps: [f64; N],
}

/// The arithmetic an analytic kernel needs, implemented by `f64` and `Dual`.
pub trait Num:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    fn cst(v: f64) -> Self;
    fn re(self) -> f64;
    fn sqrt(self) -> Self;
    fn atan2(self, x: Self) -> Self;
}

impl Num for f64 {
    fn cst(v: f64) -> Self {
        v
    }
    fn re(self) -> f64 {
        self
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
}

impl<const N: usize> Dual<N> {
    /// The `i`-th independent variable with value `re`.
    pub fn var(re: f64, i: usize) -> Self {
        let mut eps = [0.0; N];
        eps[i] = 1.0;
        Dual { re, eps }
    }
    fn chain(self, re: f64, d: f64) -> Self {
        Dual { re, eps: self.eps.map(|e| d * e) }
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Dual { re: self.re + o.re, eps: std::array::from_fn(|i| self.eps[i] + o.eps[i]) }
    }
}
impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Dual { re: self.re - o.re, eps: std::array::from_fn(|i| self.eps[i] - o.eps[i]) }
    }
}
impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Dual { re: self.re * o.re, eps: std::array::from_fn(|i| self.eps[i] * o.re + self.re * o.eps[i]) }
    }
}
impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.re;
        Dual { re: self.re * inv, eps: std::array::from_fn(|i| (self.eps[i] - self.re * inv * o.eps[i]) * inv) }
    }
}
impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    fn neg(self) -> Self {
        Dual { re: -self.re, eps: self.eps.map(|e| -e) }
    }
}

impl<const N: usize> Num for Dual<N> {
    fn cst(v: f64) -> Self {
        Dual { re: v, eps: [0.0; N] }
    }
    fn re(self) -> f64 {
        self.re
    }
    fn sqrt(self) -> Self {
        let s = self.re.sqrt();
        self.chain(s, 0.5 / s)
    }
    fn atan2(self, x: Self) -> Self {
        let (y, xr) = (self.re, x.re);
        let r2 = y * y + xr * xr;
        Dual { re: y.atan2(xr), eps: std::array::from_fn(|i| (xr * self.eps[i] - y * x.eps[i]) / r2) }
    }
}

/// A 3-vector over any `Num`, with just the operations the kernels use.
#[derive(Clone, Copy, Debug)]
pub struct V3<T>(pub [T; 3]);

impl<T: Num> V3<T> {
    pub fn sub(self, o: Self) -> Self {
        V3(std::array::from_fn(|i| self.0[i] - o.0[i]))
    }
    pub fn scale(self, s: T) -> Self {
        V3(self.0.map(|c| c * s))
    }
    pub fn add(self, o: Self) -> Self {
        V3(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
    pub fn dot(self, o: Self) -> T {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    pub fn cross(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        V3([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_of_elementary_functions() {
        let g = |a: f64, b: f64| (a * b / (a + 2.0)).sqrt().atan2(b - a);
        let x = Dual::<2>::var(0.7, 0);
        let y = Dual::<2>::var(1.3, 1);
        let f = (x * y / (x + Dual::cst(2.0))).sqrt().atan2(y - x);
        let h = 1e-6;
        let fd0 = (g(0.7 + h, 1.3) - g(0.7 - h, 1.3)) / (2.0 * h);
        let fd1 = (g(0.7, 1.3 + h) - g(0.7, 1.3 - h)) / (2.0 * h);
        assert!((f.re - g(0.7, 1.3)).abs() < 1e-14);
        assert!((f.eps[0] - fd0).abs() < 1e-8, "{} {}", f.eps[0], fd0);
        assert!((f.eps[1] - fd1).abs() < 1e-8);
    }
}
