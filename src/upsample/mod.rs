//! Physics-inspired upsampling (Kavan, Gerszewski, Bargteil & Sloan 2011): a learned dense
//! linear operator U (N fine × M coarse) with fine = U · coarse (§3, eq. 1), fitted to aligned
//! coarse/fine training frames with harmonic regularisation and rows summing to one (eqs. 3–5).
//!
//! One idea per file: `surface` (a fixed-topology triangle mesh with material coordinates),
//! `embed` (the barycentric embedding B of §4), `laplacian` (cotangent Laplacian and lumped
//! mass), `harmonics` (its lowest mass-orthonormal eigenvectors), `profile` (the polynomial
//! damping γ_n of §3.2 and §6), `fit` (the per-row constrained least squares, eq. 5),
//! `operator` (U and its application), `oscillatory` (the travelling-wave modes of §5), `model` (the versioned model file), `subdivision` (Loop
//! subdivision, the baseline U is measured against) and `run` (training, applying and
//! subdividing over run directories) `track` (tracked training runs, §4) and `validate` (choosing the
//! damping profile by cross-validation on the training frames).
//!
//! Everything assumes one coarse and one fine topology for the whole shot: train and apply on
//! uniform (fixed-mesh) runs.

mod embed;
mod fit;
mod harmonics;
mod laplacian;
mod model;
mod operator;
pub mod oscillatory;
mod profile;
pub mod run;
pub mod subdivision;
mod surface;
pub mod track;
pub mod validate;

pub use embed::{embedding, Embedding};
pub use fit::{fit, fit_towards, Prior, TrainingSet};
pub use harmonics::Harmonics;
pub use laplacian::Laplacian;
pub use model::{Model, ModelError};
pub use operator::{Compact, Operator};
pub use oscillatory::OscillatoryMode;
pub use profile::Profile;
pub use subdivision::{levels_to_match, Subdivision};
pub use surface::Surface;

/// What can go wrong building an operator; each displays as one line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UpsampleError {
    #[error("node {node} touches no face of positive material area (isolated or degenerate)")]
    ZeroMass { node: usize },
    #[error("mesh has no faces")]
    Empty,
    #[error("faces without texture coordinates (material space is needed)")]
    NoMaterialCoords,
    #[error("asked for {asked} harmonics but the fine mesh has {nodes} nodes")]
    TooManyModes { asked: usize, nodes: usize },
    #[error("regularisation needs 0 < gamma1 <= gammaN and c >= 0 (got gamma1 {gamma1}, gammaN {gamma_n}, c {c})")]
    BadProfile { gamma1: f64, gamma_n: f64, c: f64 },
    #[error("training frame {frame}: {what}")]
    BadFrame { frame: usize, what: String },
    #[error("no training frames")]
    NoFrames,
    #[error("{levels} subdivision levels asked, at most {max} (4^levels faces per coarse face)")]
    TooManyLevels { levels: usize, max: usize },
    #[error("{folds} cross-validation folds for {frames} training frames: expected 2..={frames}")]
    Folds { folds: usize, frames: usize },
    #[error("non-finite value in {what}")]
    NonFinite { what: &'static str },
}
