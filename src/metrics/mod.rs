//! Error measures for `viewcloth compare` (DESIGN.md "Error against run time"): how far a run
//! (adaptive, view-dependent, …) is from a reference run, to weigh against the time it saves.
//!
//! - `raster`: a deterministic CPU rasteriser giving depth, normal and triangle buffers from the
//!   shot camera;
//! - `visible`: what the audience sees, obstacles rasterised with the cloth: mean normal-angle
//!   difference (shading and flat normals), silhouette mismatch (XOR / union of cloth pixels)
//!   and depth error relative to the scene depth;
//! - `strain`: the principal membrane strain `stats.json` reports, also of OBJ frames;
//! - `geometric`: two-sided distance between the densely sampled surfaces (mean, RMS, 95th
//!   percentile, max), over all cloth or weighted by each triangle's visible pixel fraction.
//!
//! Cloth is chaotic, so these errors are read against the chaos floor (the reference against a
//! perturbed re-run of itself), which `compare` computes with the same functions.

pub mod geometric;
pub mod raster;
pub mod strain;
pub mod visible;

pub use geometric::{surface_distance, Surface, SurfaceDistance};
pub use raster::{coverage, rasterize, shading_normals, vertex_normals, Image};
pub use strain::{obj_strain, principal_strain, Strain};
pub use visible::{visible_error, FrameImage, VisibleError};

/// Test meshes: an `nx` × `nz` grid of 2 nx nz triangles whose node (i, j) is
/// `point(i / nx, j / nz)`.
#[cfg(test)]
pub(crate) fn test_grid(
    nx: usize,
    nz: usize,
    point: impl Fn(crate::math::Real, crate::math::Real) -> crate::math::Vec3,
) -> (Vec<crate::math::Vec3>, Vec<[usize; 3]>) {
    use crate::math::Real;
    let mut x = Vec::new();
    for j in 0..=nz {
        for i in 0..=nx {
            x.push(point(i as Real / nx as Real, j as Real / nz as Real));
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut tris = Vec::new();
    for j in 0..nz {
        for i in 0..nx {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (x, tris)
}
