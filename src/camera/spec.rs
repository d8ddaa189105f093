//! The camera file format (JSON, version 1), exactly as written by users. Unknown fields are
//! rejected; range checks are in `camera::build`. The format is documented in `camera`'s module
//! doc.

use serde::Deserialize;

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraSpec {
    pub version: u32,
    /// Width / height of the image.
    #[serde(default = "default_aspect")]
    pub aspect: f64,
    /// Near and far clipping distances (m).
    #[serde(default = "default_near")]
    pub near: f64,
    #[serde(default = "default_far")]
    pub far: f64,
    #[serde(default)]
    pub interpolation: Interpolation,
    pub keys: Vec<KeySpec>,
}

/// How the camera moves between keys.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub(super) enum Interpolation {
    /// Piecewise linear per component.
    Linear,
    /// Cubic Hermite per component, central-difference tangents, zero at the ends.
    #[default]
    CatmullRom,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct KeySpec {
    /// Seconds.
    pub time: f64,
    pub position: [f64; 3],
    pub target: [f64; 3],
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Vertical field of view (degrees).
    pub fov: f64,
}

fn default_aspect() -> f64 {
    16.0 / 9.0
}

fn default_near() -> f64 {
    0.05
}

fn default_far() -> f64 {
    100.0
}

fn default_up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}
