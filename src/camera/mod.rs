//! Scripted cameras (`cameras/*.json`): keyframes interpolated in time, and the view frustum the
//! view factor (Koh et al. 2014) measures faces against.
//!
//! # File format (JSON, version 1)
//!
//! ```json
//! {
//!   "version": 1,
//!   "aspect": 1.7778,
//!   "near": 0.05,
//!   "far": 100.0,
//!   "interpolation": "catmull-rom",
//!   "keys": [
//!     { "time": 0.0, "position": [0, -3, 1], "target": [0, 0, 0.5], "up": [0, 0, 1], "fov": 40 }
//!   ]
//! }
//! ```
//!
//! - `version` (required): 1.
//! - `aspect`: image width / height, > 0 (default 16/9).
//! - `near`, `far`: clipping distances (m) along the viewing direction, 0 < near < far (defaults
//!   0.05 and 100).
//! - `interpolation`: `"catmull-rom"` (default) or `"linear"`, per component of position, target,
//!   up and fov. Catmull–Rom is the cubic Hermite spline with tangents (x[i+1] − x[i−1]) /
//!   (t[i+1] − t[i−1]) at interior keys and zero at the first and last key: the spline of
//!   `math::spline`, shared with the scene's keyframed motions.
//! - `keys` (required, at least one; one key is a static camera): `time` (s, strictly
//!   increasing), `position` (the eye) and `target` (m, at least 1e-9 m apart), `up` (a direction
//!   not parallel to target − position, default [0, 0, 1]; only its direction matters), `fov` (the
//!   vertical field of view in degrees, strictly between 0 and 180).
//!
//! Every number must be finite and of magnitude at most 1e9. Unknown fields are errors; every
//! error names the file and the JSON path of the field (`keys[2].fov`). Before the first key and
//! after the last the camera holds.

mod load;
mod spec;

use std::path::Path;

use crate::error::InputError;
use crate::math::spline::{self, Segment, Weights};
use crate::math::{Real, Vec3};
use spec::Interpolation;

/// One validated key; `up` is a unit vector not parallel to `target − position`.
#[derive(Clone, Debug, PartialEq)]
struct Key {
    time: Real,
    position: Vec3,
    target: Vec3,
    up: Vec3,
    /// Vertical field of view (degrees).
    fov: Real,
}

/// A scripted camera.
#[derive(Clone, Debug)]
pub struct Camera {
    keys: Vec<Key>,
    /// Key times, for the spline.
    times: Vec<Real>,
    interpolation: Interpolation,
    /// Smallest and largest key fov: the Catmull–Rom fov is clamped to it, so an overshooting
    /// spline cannot leave (0°, 180°).
    fov_range: (Real, Real),
    /// Image width / height.
    pub aspect: Real,
    /// Near and far clipping distances (m).
    pub near: Real,
    pub far: Real,
}

/// The camera at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub eye: Vec3,
    /// Unit viewing direction (towards the target).
    pub forward: Vec3,
    /// Unit up, orthogonal to `forward` (the key's up made orthogonal by Gram–Schmidt).
    pub up: Vec3,
    /// Unit right = forward × up.
    pub right: Vec3,
    /// tan(vertical fov / 2).
    pub tan_half_fov: Real,
    pub aspect: Real,
    pub near: Real,
    pub far: Real,
}

impl Camera {
    /// Reads and validates a camera file.
    pub fn load(path: &Path) -> Result<Camera, InputError> {
        load::read(path)
    }

    /// Parses and validates camera JSON text; `file` names it in errors.
    pub fn from_json(text: &str, file: &Path) -> Result<Camera, InputError> {
        load::parse(text, file)
    }

    /// From validated keys (non-empty, strictly increasing times).
    fn new(keys: Vec<Key>, interpolation: Interpolation, aspect: Real, near: Real, far: Real) -> Camera {
        let times = keys.iter().map(|k| k.time).collect();
        let fov_range =
            keys.iter().fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), k| (lo.min(k.fov), hi.max(k.fov)));
        Camera { keys, times, interpolation, fov_range, aspect, near, far }
    }

    /// The camera at time `t` (s): interpolated between keys, holding the first/last key outside
    /// their range.
    pub fn view_at(&self, t: Real) -> View {
        let (weights, nearest) = self.weights_at(t);
        let mix =
            |get: fn(&Key) -> Vec3| weights.iter().fold(Vec3::zeros(), |acc, &(k, w)| acc + get(&self.keys[k]) * w);
        let eye = mix(|k| k.position);
        let target = mix(|k| k.target);
        let up = mix(|k| k.up);
        let fov: Real = weights.iter().map(|&(k, w)| self.keys[k].fov * w).sum();
        let fov = fov.clamp(self.fov_range.0, self.fov_range.1);
        let key = &self.keys[nearest];
        // The spline may bring eye and target together, or turn up along the view, between keys
        // that are valid: fall back to the nearest key's direction, which validation guarantees.
        let forward = unit(target - eye).or_else(|| unit(key.target - key.position)).unwrap_or(Vec3::y());
        let up =
            [up, key.up].iter().find_map(|u| orthogonal_unit(u, &forward)).unwrap_or_else(|| any_orthogonal(&forward));
        View {
            eye,
            forward,
            up,
            right: forward.cross(&up),
            tan_half_fov: (0.5 * fov.to_radians()).tan(),
            aspect: self.aspect,
            near: self.near,
            far: self.far,
        }
    }

    /// The spline's weights on the keys at time `t`, and the key nearest in time (the fallback
    /// for degenerate interpolated frames).
    fn weights_at(&self, t: Real) -> (Weights, usize) {
        match spline::locate(&self.times, |&tk| tk, t) {
            Segment::Hold(k) => (spline::hold_weights(k), k),
            Segment::Between { i, s } => {
                let weights = match self.interpolation {
                    Interpolation::Linear => spline::linear_weights(i, s),
                    Interpolation::CatmullRom => spline::catmull_rom_weights(&self.times, i, s),
                };
                (weights, if s < 0.5 { i } else { i + 1 })
            }
        }
    }

    /// Raw bytes-independent fingerprint input: a stable textual description of every parsed
    /// value (defaults applied, `up` normalised), for checkpoint fingerprints.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "camera v1 aspect={:?} near={:?} far={:?} interpolation={:?} keys=[",
            self.aspect, self.near, self.far, self.interpolation
        );
        for k in &self.keys {
            let a = |v: &Vec3| <[Real; 3]>::from(*v);
            s += &format!(
                "{{time={:?} position={:?} target={:?} up={:?} fov={:?}}}",
                k.time,
                a(&k.position),
                a(&k.target),
                a(&k.up),
                k.fov
            );
        }
        s + "]"
    }
}

/// v / |v|, or None when v is too short to give a direction (< 1e-12 m: validated keys are at
/// least 1e-9 m apart).
fn unit(v: Vec3) -> Option<Vec3> {
    let n = v.norm();
    (n > 1e-12 && n.is_finite()).then(|| v / n)
}

/// Gram–Schmidt: the unit part of `u` orthogonal to the unit vector `f`, or None when `u` is
/// (nearly) parallel to `f` (sine below 1e-6, the validation threshold) or zero.
fn orthogonal_unit(u: &Vec3, f: &Vec3) -> Option<Vec3> {
    let p = u - f * u.dot(f);
    let n = p.norm();
    (n > 1e-6 * u.norm() && n > 0.0).then(|| p / n)
}

/// Some unit vector orthogonal to the unit vector `f`: the world axis least aligned with it,
/// made orthogonal (its sine is at least √(2/3)).
fn any_orthogonal(f: &Vec3) -> Vec3 {
    let axis = (0..3).min_by(|&a, &b| f[a].abs().total_cmp(&f[b].abs())).unwrap_or(2);
    let p = Vec3::ith(axis, 1.0) - f * f[axis];
    p / p.norm()
}

impl View {
    /// Signed distance (m) from `p` to the view frustum, Koh et al. 2014 §"Inside or outside of
    /// the view frustum": the largest signed distance of `p` to the frustum's six planes (near,
    /// far, left, right, top, bottom), each plane's normal pointing out of the frustum: negative
    /// inside, positive outside.
    pub fn frustum_distance(&self, p: &Vec3) -> Real {
        let d = p - self.eye;
        // Camera coordinates: depth z along forward, x right, y up.
        let (x, y, z) = (d.dot(&self.right), d.dot(&self.up), d.dot(&self.forward));
        // Side planes through the eye: the right one has outward normal (right − tan_h forward) /
        // √(1 + tan_h²), and likewise for the others.
        let tan_v = self.tan_half_fov;
        let tan_h = self.aspect * tan_v;
        let side = |lateral: Real, tan: Real| (lateral.abs() - tan * z) / (1.0 + tan * tan).sqrt();
        (self.near - z).max(z - self.far).max(side(x, tan_h)).max(side(y, tan_v))
    }

    /// Distance from the eye (m).
    pub fn eye_distance(&self, p: &Vec3) -> Real {
        (p - self.eye).norm()
    }
}

#[cfg(test)]
mod tests;
