//! viewcloth: a film cloth simulator.
//!
//! Scene files → implicit cloth integration (Baraff & Witkin 1998) → one OBJ mesh per frame.
//! Modules follow the pipeline: `scene` and `camera` (input), `mesh` (material and world space),
//! `forces` (element kernels, and the fabrics that pick them), `solver` (global implicit system),
//! `collision`, `sizing` and `remesh`, `sim` (the step and the run), `io`, `metrics` (error
//! against a reference run, for `compare`) and `render` (PNG previews). `math` holds the scalar
//! and small matrix types, rigid transforms and keyframed motions, and the spline motions share
//! with camera paths; `error` the input error every reader of user files returns.
//!
//! `scene` sits above the stages: it parses and validates scene files and assembles a `Scene` out
//! of their types (`forces::material::Material`, `collision::shape::Obstacle`,
//! `collision::params::CollisionParams`, `math::motion::Motion`, `camera::Camera`). Nothing below
//! it imports `scene`; `sim`, `batch`, `compare` and the binary, above it, do.

pub mod batch;
pub mod camera;
pub mod cli;
pub mod collision;
pub mod compare;
pub mod constraints;
pub mod error;
pub mod farm;
pub mod forces;
pub mod io;
pub mod math;
pub mod mesh;
pub mod metrics;
pub mod remesh;
pub mod render;
pub mod resample;
pub mod scene;
pub mod shot;
pub mod sim;
pub mod sizing;
pub mod solver;
pub mod upsample;
