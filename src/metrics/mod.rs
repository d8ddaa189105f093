//! Error measures for `viewcloth compare` (DESIGN.md "Error against run time"): how far a run
//! (adaptive, view-dependent, …) is from a reference run, to weigh against the time it saves.
//!
//! - `raster`: a deterministic CPU rasteriser giving depth, normal and triangle buffers from the
//!   shot camera;
//! - `visible`: what the audience sees: mean normal-angle difference, silhouette mismatch
//!   (XOR / union of coverage) and depth error relative to the scene depth;
//! - `geometric`: two-sided area-weighted mean and 95th-percentile distance between the
//!   surfaces, over all cloth or only its visible triangles.
//!
//! Cloth is chaotic, so these errors are read against the chaos floor (the reference against a
//! perturbed re-run of itself), which `compare` computes with the same functions.

pub mod geometric;
pub mod raster;
pub mod visible;

pub use geometric::{surface_distance, visible_triangles, Surface, SurfaceDistance};
pub use raster::{rasterize, Image};
pub use visible::{visible_error, VisibleError};
