//! `viewcloth render` (DESIGN.md "What a user does", "Files"): PNG previews `view_NNNN.png` of a
//! run's frames, seen from a scripted camera at each frame's time.
//!
//! A frame's cloth and the obstacles the run exported for it are rasterised together
//! (`metrics::rasterize`), so each occludes the other. Colours:
//! - `Shade`: cloth light blue, obstacles light salmon;
//! - `View`: cloth by its view factor at that frame — μ₂ of Koh et al. 2014 (orientation and
//!   frustum, eqs. 1–4, default parameters, no lookahead) from each face's normal and centroid —
//!   on a ramp from blue at μ = 0.1 (seen from behind or out of frame: coarse) to red at μ = 1
//!   (facing the camera: fine); obstacles grey.
//!
//! Both are lit by a head light: colour · (0.25 + 0.75 |n · forward|), an ambient share and
//! Lambert's cosine (two-sided), on white. Each pixel is sampled once at its centre, so edges are
//! aliased; the images are previews. Output is deterministic (the rasteriser is).

pub mod png;
pub mod run_dir;

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::camera::{Camera, View};
use crate::error::InputError;
use crate::io::write_atomic;
use crate::math::{Real, Vec3};
use crate::metrics::rasterize;
use crate::sim::progress::ProgressMode;
use crate::sizing::view::{triangle_view_factor, ViewParams};

pub use run_dir::{read_stats, select_frames, FrameMeshes, RunFiles};

/// How the cloth is coloured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colouring {
    /// Flat colours, shaded.
    Shade,
    /// The view factor μ₂ on a blue → red ramp, shaded.
    View,
}

/// What `render_run` renders.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Image size (pixels). The camera's aspect is kept: a size of another aspect stretches the
    /// picture.
    pub width: usize,
    pub height: usize,
    /// Frame numbers to render, inclusive (default: every frame listed in `stats.json`).
    pub frames: Option<(usize, usize)>,
    /// Every this many frames, counted from the first of `frames`.
    pub every: usize,
    pub colouring: Colouring,
    /// Progress per image written (a bar, one stderr line, or nothing).
    pub progress: ProgressMode,
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// A run file missing or malformed, or frames the run does not have (bad input).
    #[error("{0}")]
    Input(#[from] InputError),
    /// An image could not be written.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
}

impl RenderError {
    /// True for bad input (nothing was written), false for an output failure.
    pub fn is_input(&self) -> bool {
        matches!(self, RenderError::Input(_))
    }
}

/// Background colour.
const WHITE: [u8; 3] = [255, 255, 255];
/// Cloth and obstacle colours (linear 0–1 scale of 8-bit values): CSS lightblue, lightsalmon,
/// and a mid grey for obstacles under view colouring.
const CLOTH: [Real; 3] = rgb(173, 216, 230);
const OBSTACLE: [Real; 3] = rgb(255, 160, 122);
const OBSTACLE_GREY: [Real; 3] = rgb(170, 170, 170);
/// Ends of the view-factor ramp: blue at `MU_BLUE` (μ_back = μ_out of the default parameters,
/// the smallest μ there is), red at μ = 1.
const BLUE: [Real; 3] = rgb(40, 80, 235);
const RED: [Real; 3] = rgb(225, 35, 30);
const MU_BLUE: Real = 0.1;
/// Share of the head light that is ambient; the rest is Lambert's |n · forward|.
const AMBIENT: Real = 0.25;

const fn rgb(r: u8, g: u8, b: u8) -> [Real; 3] {
    [r as Real / 255.0, g as Real / 255.0, b as Real / 255.0]
}

/// Renders the selected frames of the run in `dir` to `dir/view_NNNN.png`; returns how many
/// images were written. Every selected frame's files are read and checked before the first
/// image is written, so bad input writes nothing.
pub fn render_run(dir: &Path, camera: &Camera, opts: &RenderOptions) -> Result<usize, RenderError> {
    let stats = read_stats(dir)?;
    let frames = select_frames(&stats, opts.frames, opts.every, &dir.join("stats.json"))?;
    let last = stats.frames.iter().map(|f| f.frame).max().unwrap_or(0);
    let run = RunFiles::scan(dir, frames.first().map_or(0, |f| f.0), last)?;
    // Every frame is read once to check it before anything is written (a malformed frame
    // halfway writes nothing), then again to render it.
    let checked: Vec<Result<(), InputError>> = frames.par_iter().map(|&(f, _)| run.load(f).map(drop)).collect();
    checked.into_iter().collect::<Result<(), _>>()?;
    let (started, n) = (std::time::Instant::now(), frames.len());
    let bar = (opts.progress == ProgressMode::Bar).then(|| indicatif::ProgressBar::new(n as u64));
    for (k, &(f, t)) in frames.iter().enumerate() {
        let clock = std::time::Instant::now();
        let meshes = run.load(f)?;
        let rgb = render_frame(&meshes, &camera.view_at(t), opts.width, opts.height, opts.colouring);
        let path = run.image_path(f);
        let png = png::encode(opts.width, opts.height, &rgb);
        write_atomic(&path, &png).map_err(|source| RenderError::Io { path, source })?;
        if let Some(bar) = &bar {
            bar.set_position(k as u64 + 1);
        }
        if opts.progress == ProgressMode::Lines {
            let eta = started.elapsed().as_secs_f64() / (k + 1) as f64 * (n - k - 1) as f64;
            let s = clock.elapsed().as_secs_f64();
            eprintln!("render: image {}/{n} (frame {f}), {s:.2} s/image, ETA {eta:.0}s", k + 1);
        }
    }
    if let Some(bar) = bar {
        bar.finish();
    }
    Ok(frames.len())
}

/// The RGB image (8 bits per channel, row-major, row 0 at the top) of one frame's meshes seen
/// by `view`.
pub fn render_frame(meshes: &FrameMeshes, view: &View, width: usize, height: usize, colouring: Colouring) -> Vec<u8> {
    let image = rasterize(&meshes.positions, &meshes.triangles, view, width, height);
    let colours = face_colours(meshes, view, colouring);
    let mut rgb = vec![0; 3 * width * height];
    rgb.par_chunks_mut(3).enumerate().for_each(|(p, pixel)| {
        let colour = match image.face[p] {
            u32::MAX => WHITE,
            f => shade(colours[f as usize], &image.normal[p], &view.forward),
        };
        pixel.copy_from_slice(&colour);
    });
    rgb
}

/// Base colour of every triangle.
fn face_colours(meshes: &FrameMeshes, view: &View, colouring: Colouring) -> Vec<[Real; 3]> {
    let params = ViewParams::default();
    (0..meshes.triangles.len())
        .into_par_iter()
        .map(|f| match (colouring, f < meshes.cloth_triangles) {
            (Colouring::Shade, true) => CLOTH,
            (Colouring::Shade, false) => OBSTACLE,
            (Colouring::View, false) => OBSTACLE_GREY,
            (Colouring::View, true) => {
                view_ramp(triangle_view_factor(&meshes.triangles[f].map(|i| meshes.positions[i]), view, &params))
            }
        })
        .collect()
}

/// Blue at μ = 0.1 to red at μ = 1, linearly.
pub fn view_ramp(mu: Real) -> [Real; 3] {
    let s = ((mu - MU_BLUE) / (1.0 - MU_BLUE)).clamp(0.0, 1.0);
    [0, 1, 2].map(|k| (1.0 - s) * BLUE[k] + s * RED[k])
}

/// `colour` lit by a head light along `forward` at a surface of unit normal `n`.
fn shade(colour: [Real; 3], n: &Vec3, forward: &Vec3) -> [u8; 3] {
    let light = AMBIENT + (1.0 - AMBIENT) * n.dot(forward).abs();
    colour.map(|c| (255.0 * c * light).round().clamp(0.0, 255.0) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eye at the origin looking along +y, z up, 90° vertical fov, square image.
    fn view() -> View {
        crate::metrics::raster::tests::view(1.0)
    }

    /// A triangle at depth `y` facing the eye, its centroid on the view axis.
    fn facing(y: Real, half: Real) -> [Vec3; 3] {
        [Vec3::new(-half, y, -half), Vec3::new(half, y, -half), Vec3::new(0.0, y, 2.0 * half)]
    }

    fn meshes(cloth: &[[Vec3; 3]], obstacles: &[[Vec3; 3]]) -> FrameMeshes {
        let all: Vec<Vec3> = cloth.iter().chain(obstacles).flatten().copied().collect();
        let triangles = (0..all.len() / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        FrameMeshes { positions: all, triangles, cloth_triangles: cloth.len() }
    }

    fn pixel(rgb: &[u8], width: usize, i: usize, j: usize) -> [u8; 3] {
        let k = 3 * (j * width + i);
        [rgb[k], rgb[k + 1], rgb[k + 2]]
    }

    #[test]
    fn ramp_runs_from_blue_to_red() {
        assert_eq!(view_ramp(0.1), BLUE);
        assert_eq!(view_ramp(0.0), BLUE);
        assert_eq!(view_ramp(1.0), RED);
        let mid = view_ramp(0.55);
        assert!((0..3).all(|k| (mid[k] - 0.5 * (BLUE[k] + RED[k])).abs() < 1e-12));
    }

    #[test]
    fn facing_cloth_in_frame_has_view_factor_one_and_out_of_frame_mu_out() {
        let p = ViewParams::default();
        assert!((triangle_view_factor(&facing(2.0, 0.5), &view(), &p) - 1.0).abs() < 1e-12);
        // Edge-on (normal ⟂ the direction to the eye): μ_back + k_cos (1 − μ_back).
        let edge_on = [Vec3::new(0.0, 2.0, -0.5), Vec3::new(0.0, 3.0, -0.5), Vec3::new(0.0, 2.5, 0.5)];
        assert!((triangle_view_factor(&edge_on, &view(), &p) - 0.28).abs() < 1e-12);
        // Behind the eye, far beyond the margin.
        assert!((triangle_view_factor(&facing(-5.0, 0.5), &view(), &p) - p.mu_out).abs() < 1e-12);
    }

    #[test]
    fn obstacle_in_front_hides_cloth_and_takes_its_colour() {
        let (w, h) = (64, 64);
        // Cloth at depth 3, a smaller obstacle in front of it at depth 2 (rows 16–40).
        let m = meshes(&[facing(3.0, 2.0)], &[facing(2.0, 0.5)]);
        let rgb = render_frame(&m, &view(), w, h, Colouring::Shade);
        // Facing the head light: full brightness, the colours themselves.
        let full = |c: [Real; 3]| c.map(|x| (255.0 * x).round() as u8);
        assert_eq!(pixel(&rgb, w, 32, 32), full(OBSTACLE));
        assert_eq!(pixel(&rgb, w, 32, 50), full(CLOTH));
        assert_eq!(pixel(&rgb, w, 0, 0), WHITE);
        let rgb = render_frame(&m, &view(), w, h, Colouring::View);
        assert_eq!(pixel(&rgb, w, 32, 32), full(OBSTACLE_GREY));
        assert_eq!(pixel(&rgb, w, 32, 50), full(RED));
    }

    #[test]
    fn tilted_faces_are_darker_down_to_the_ambient_share() {
        let n = Vec3::new(1.0, 1.0, 0.0).normalize();
        let lit = shade([1.0; 3], &n, &Vec3::y());
        let expected = (255.0 * (AMBIENT + (1.0 - AMBIENT) * 0.5_f64.sqrt())).round() as u8;
        assert_eq!(lit, [expected; 3]);
        assert_eq!(shade([1.0; 3], &Vec3::x(), &Vec3::y()), [(255.0 * AMBIENT).round() as u8; 3]);
        assert_eq!(shade([1.0; 3], &-Vec3::y(), &Vec3::y()), [255; 3]);
    }
}
