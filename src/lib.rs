//! viewcloth: a film cloth simulator.
//!
//! Scene files → implicit cloth integration (Baraff & Witkin 1998) → one OBJ mesh per frame.
//! Modules follow the pipeline: `scene` and `camera` (input), `mesh` (material and world space),
//! `forces` (element kernels), `solver` (global implicit system), `sim` (the step and the run),
//! `io`, `metrics` (error against a reference run, for `compare`) and `render` (PNG previews).

pub mod batch;
pub mod camera;
pub mod collision;
pub mod compare;
pub mod error;
pub mod forces;
pub mod io;
pub mod math;
pub mod mesh;
pub mod metrics;
pub mod remesh;
pub mod render;
pub mod scene;
pub mod sim;
pub mod sizing;
pub mod solver;
