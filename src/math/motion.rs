//! Rigid (similarity) transforms and keyframed motions.
//!
//! Keys hold translation, rotation (unit quaternion) and uniform scale. Between keys each
//! component follows the spline of `math::spline`: cubic Hermite, tangents central differences of
//! the neighbouring keys, (x[i+1] − x[i−1]) / (t[i+1] − t[i−1]), zero at the first and last key
//! (ARCSim's motion splines; Catmull–Rom for evenly spaced keys), unless a key states its own.
//! Quaternions are interpolated componentwise after aligning signs with the previous key, then
//! normalised. Before the first key and after the last the motion holds.

use nalgebra::{Quaternion, Unit, UnitQuaternion};

use super::spline::{hermite_basis_motion, locate, Segment};
use super::{Real, Vec3};

/// p ↦ translate + rotate · (scale · p).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub translate: Vec3,
    pub rotate: UnitQuaternion<Real>,
    pub scale: Real,
}

impl Default for Transform {
    fn default() -> Self {
        Transform { translate: Vec3::zeros(), rotate: UnitQuaternion::identity(), scale: 1.0 }
    }
}

impl Transform {
    /// From ARCSim-style fields: rotation `[degrees, axis x, y, z]`.
    pub fn new(translate: [f64; 3], rotate: Option<[f64; 4]>, scale: f64) -> Self {
        let rotate = match rotate {
            Some([deg, x, y, z]) => {
                let axis = Vec3::new(x, y, z);
                if axis.norm() > 0.0 {
                    UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), deg.to_radians())
                } else {
                    UnitQuaternion::identity()
                }
            }
            None => UnitQuaternion::identity(),
        };
        Transform { translate: Vec3::from(translate), rotate, scale }
    }

    #[inline]
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        self.translate + self.rotate * (self.scale * p)
    }

    /// The inverse map p ↦ R⁻¹(p − translate) / scale.
    pub fn inverse(&self) -> Transform {
        let rotate = self.rotate.inverse();
        let scale = 1.0 / self.scale;
        Transform { translate: -(rotate * self.translate) * scale, rotate, scale }
    }

    /// `self ∘ inner`: apply `inner` first.
    pub fn compose(&self, inner: &Transform) -> Transform {
        Transform {
            translate: self.apply(&inner.translate),
            rotate: self.rotate * inner.rotate,
            scale: self.scale * inner.scale,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Keyframe {
    pub time: Real,
    pub transform: Transform,
}

/// An explicit tangent at a key (ARCSim's keyframe `velocity`): translation and scale rates;
/// the rotation's tangent is then zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyVelocity {
    pub translate: Vec3,
    pub scale: Real,
}

/// A keyframed motion; keys are strictly increasing in time (checked at load).
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    keys: Vec<Keyframe>,
    /// Quaternion coefficients per key, sign-aligned with the previous key.
    quats: Vec<nalgebra::Vector4<Real>>,
    /// Explicit tangents, per key (empty: all central differences).
    velocities: Vec<Option<KeyVelocity>>,
}

impl Motion {
    pub fn new(keys: Vec<Keyframe>) -> Self {
        let mut quats: Vec<nalgebra::Vector4<Real>> = Vec::with_capacity(keys.len());
        for k in &keys {
            let mut q = k.transform.rotate.quaternion().coords;
            if let Some(prev) = quats.last() {
                if prev.dot(&q) < 0.0 {
                    q = -q;
                }
            }
            quats.push(q);
        }
        Motion { keys, quats, velocities: Vec::new() }
    }

    /// A motion whose keys may carry explicit tangents (`velocities[i]` for key i).
    pub fn with_velocities(keys: Vec<Keyframe>, velocities: Vec<Option<KeyVelocity>>) -> Self {
        Motion { velocities, ..Motion::new(keys) }
    }

    pub fn keys(&self) -> &[Keyframe] {
        &self.keys
    }

    /// The transform at time `t`.
    pub fn eval(&self, t: Real) -> Transform {
        let k = &self.keys;
        let n = k.len();
        if n == 0 {
            return Transform::default();
        }
        let (i, s) = match locate(k, |key| key.time, t) {
            Segment::Hold(j) => return k[j].transform,
            Segment::Between { i, s } => (i, s),
        };
        let dt = k[i + 1].time - k[i].time;
        let [h00, h10, h01, h11] = hermite_basis_motion(s);
        let given = |j: usize| self.velocities.get(j).copied().flatten();
        let tangent = |j: usize, get: &dyn Fn(usize) -> nalgebra::DVector<Real>| {
            if let Some(v) = given(j) {
                // Which component `get` reads follows from its length (3, 1 or 4).
                match get(j).len() {
                    3 => nalgebra::DVector::from_column_slice(v.translate.as_slice()),
                    1 => nalgebra::DVector::from_element(1, v.scale),
                    len => nalgebra::DVector::zeros(len),
                }
            } else if j == 0 || j == n - 1 {
                get(j) * 0.0
            } else {
                (get(j + 1) - get(j - 1)) / (k[j + 1].time - k[j - 1].time)
            }
        };
        let spline = |get: &dyn Fn(usize) -> nalgebra::DVector<Real>| {
            get(i) * h00 + tangent(i, get) * (h10 * dt) + get(i + 1) * h01 + tangent(i + 1, get) * (h11 * dt)
        };
        let tr = spline(&|j| nalgebra::DVector::from_column_slice(k[j].transform.translate.as_slice()));
        let sc = spline(&|j| nalgebra::DVector::from_element(1, k[j].transform.scale));
        let q = spline(&|j| nalgebra::DVector::from_column_slice(self.quats[j].as_slice()));
        let quat = Quaternion::new(q[3], q[0], q[1], q[2]);
        Transform {
            translate: Vec3::new(tr[0], tr[1], tr[2]),
            rotate: UnitQuaternion::from_quaternion(quat),
            scale: sc[0],
        }
    }
}

impl Motion {
    /// `outer ∘ self(t + time_offset)` as a motion of its own: keys `time_offset` earlier, each
    /// composed with `outer`, explicit tangents carried through it (translation rates rotated
    /// and scaled, scale rates scaled). Exact up to rounding, because every component of
    /// `outer ∘ key` is an affine function of the key's (the rotation's quaternion a linear,
    /// norm-preserving one, so normalising and sign alignment commute with it), and the
    /// Hermite spline commutes with affine maps.
    pub fn placed(&self, outer: &Transform, time_offset: Real) -> Motion {
        let keys = self
            .keys
            .iter()
            .map(|k| Keyframe { time: k.time - time_offset, transform: outer.compose(&k.transform) })
            .collect();
        let velocities = self
            .velocities
            .iter()
            .map(|v| {
                v.map(|v| KeyVelocity {
                    translate: outer.rotate * (outer.scale * v.translate),
                    scale: outer.scale * v.scale,
                })
            })
            .collect();
        Motion::with_velocities(keys, velocities)
    }
}

/// The transform at `t` of something placed by `transform` and then moved by `motion`:
/// `motion(t) ∘ transform`.
pub fn transform_at(transform: &Transform, motion: Option<&Motion>, t: Real) -> Transform {
    match motion {
        Some(m) => m.eval(t).compose(transform),
        None => *transform,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(time: f64, x: f64, deg: f64) -> Keyframe {
        Keyframe { time, transform: Transform::new([x, 0.0, 0.0], Some([deg, 0.0, 0.0, 1.0]), 1.0) }
    }

    #[test]
    fn interpolates_keys_and_holds_outside() {
        let m = Motion::new(vec![key(0.0, 0.0, 0.0), key(1.0, 1.0, 90.0), key(2.0, 0.0, 0.0)]);
        assert_eq!(m.eval(-1.0), m.keys()[0].transform);
        let mid = m.eval(1.0);
        assert!((mid.translate.x - 1.0).abs() < 1e-12);
        assert!((mid.rotate.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(m.eval(5.0), m.keys()[2].transform);
        // Smooth: the middle key has zero tangent by symmetry, so x peaks there.
        assert!(m.eval(0.9).translate.x < 1.0 && m.eval(1.1).translate.x < 1.0);
    }

    #[test]
    fn placed_motion_is_the_outer_transform_of_the_shifted_motion() {
        let mut m =
            Motion::new(vec![key(0.0, 0.0, 0.0), key(0.7, 1.0, 90.0), key(1.5, -0.5, 30.0), key(2.0, 0.2, 0.0)]);
        m.velocities = vec![None, Some(KeyVelocity { translate: Vec3::new(0.3, -1.0, 2.0), scale: 0.5 }), None, None];
        let outer = Transform::new([3.0, -2.0, 0.5], Some([120.0, 0.3, 1.0, -0.2]), 1.3);
        let tau = 0.45;
        let placed = m.placed(&outer, tau);
        let p = Vec3::new(0.2, -0.7, 1.1);
        for i in 0..=40 {
            let t = -1.0 + 0.1 * i as f64;
            let want = outer.apply(&m.eval(t + tau).apply(&p));
            let got = placed.eval(t).apply(&p);
            assert!((got - want).norm() < 1e-12, "t = {t}: {got} vs {want}");
        }
        // Different without the offset: the test can fail.
        assert!((placed.eval(0.5).apply(&p) - outer.apply(&m.eval(0.5).apply(&p))).norm() > 1e-3);
    }

    #[test]
    fn inverse_undoes_the_transform() {
        let t = Transform::new([0.3, -1.0, 2.0], Some([37.0, 1.0, 2.0, -0.5]), 1.7);
        let p = Vec3::new(0.2, -0.4, 0.9);
        assert!((t.inverse().apply(&t.apply(&p)) - p).norm() < 1e-12);
        assert!((t.compose(&t.inverse()).apply(&p) - p).norm() < 1e-12);
    }

    #[test]
    fn transform_order_is_scale_rotate_translate() {
        let t = Transform::new([1.0, 0.0, 0.0], Some([90.0, 0.0, 0.0, 1.0]), 2.0);
        let p = t.apply(&Vec3::new(1.0, 0.0, 0.0));
        assert!((p - Vec3::new(1.0, 2.0, 0.0)).norm() < 1e-12);
    }
}
