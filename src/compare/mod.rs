//! `viewcloth compare` (DESIGN.md "Error against run time"): one shot simulated in several
//! remeshing modes, each run's frames measured against a reference run from the shot camera.
//!
//! The reference is the uniform mesh at the adaptive minimum edge length (or a run the user
//! names). Cloth is chaotic: runs that differ by rounding grow different wrinkles, so the
//! reference is also re-run from positions perturbed by `FLOOR_PERTURBATION`, and that pair's
//! error, the chaos floor, is what an error should be compared with: each mode's error is also
//! given as a multiple of it.
//!
//! Per compared frame: visible error (both meshes rasterised from the camera at that frame's
//! time: normal angle, silhouette mismatch, relative depth) and geometric error (two-sided
//! surface distance, over all cloth and over the faces the camera sees); per run, their means
//! over the frames, with the wall time and mean face count.

mod report;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::camera::Camera;
use crate::error::InputError;
use crate::io::obj::read_obj;
use crate::io::stats::RunStats;
use crate::math::{Real, Vec3};
use crate::metrics::{rasterize, surface_distance, visible_error, visible_triangles, Surface};
use crate::metrics::{SurfaceDistance, VisibleError};
use crate::render::run_dir::{self, RunFiles};
use crate::scene::{RemeshMode, Scene};
use crate::sim::{run, RunError, RunOptions};

pub use report::{markdown, svg_plot};

/// Size (m) of the random displacement of every initial node in the chaos-floor run.
pub const FLOOR_PERTURBATION: Real = 1e-6;

/// What `compare` runs and measures.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    /// Runs go to `out_dir/<name>/`; the report to `out_dir/compare.{json,md,svg}`.
    pub out_dir: PathBuf,
    /// Overrides the scene's frame count.
    pub frames: Option<usize>,
    /// Modes compared with the reference.
    pub modes: Vec<RemeshMode>,
    /// An existing run directory to use as the reference instead of simulating one.
    pub reference: Option<PathBuf>,
    /// Also run the chaos floor (a perturbed reference).
    pub floor: bool,
    /// Rasterised image size (pixels).
    pub width: usize,
    pub height: usize,
    /// Compare every this many frames (frame 0, the shared initial state, is skipped).
    pub every: usize,
    pub quiet: bool,
}

/// The error of one run against the reference, averaged over the compared frames.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Errors {
    pub visible: VisibleError,
    /// Over all cloth.
    pub geometric: SurfaceDistance,
    /// Over the faces the camera sees (in either run).
    pub geometric_visible: SurfaceDistance,
    pub frames_compared: usize,
}

/// One run: its cost and, except for the reference, its error.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    pub name: String,
    pub dir: PathBuf,
    /// Wall time of the simulation (s).
    pub wall_s: Real,
    pub mean_faces: Real,
    pub errors: Option<Errors>,
}

#[derive(Clone, Debug, Serialize)]
pub struct CompareReport {
    pub scene: String,
    pub frames: usize,
    pub image: [usize; 2],
    pub reference: RunReport,
    /// The perturbed reference: its error is the chaos floor.
    pub floor: Option<RunReport>,
    pub modes: Vec<RunReport>,
}

impl CompareReport {
    /// `e / floor` for each error measure, when there is a floor.
    pub fn floor_multiple(&self, e: &Errors) -> Option<[Real; 3]> {
        let f = self.floor.as_ref()?.errors.as_ref()?;
        let ratio = |a: Real, b: Real| if b > 0.0 { a / b } else { Real::INFINITY };
        Some([
            ratio(e.visible.normal_deg, f.visible.normal_deg),
            ratio(e.visible.silhouette, f.visible.silhouette),
            ratio(e.geometric.mean, f.geometric.mean),
        ])
    }
}

/// Runs the shot in every mode (and the reference and floor unless given or off), measures the
/// errors and writes `compare.json`, `compare.md` and `compare.svg` into `opts.out_dir`.
pub fn compare(scene: Scene, opts: &CompareOptions) -> Result<CompareReport, RunError> {
    let Some(camera) = scene.camera.clone() else {
        return Err(RunError::Input(InputError {
            file: scene.file.clone(),
            location: None,
            msg: "compare needs the shot camera: give the scene a \"camera\" file or pass --camera".into(),
        }));
    };
    std::fs::create_dir_all(&opts.out_dir).map_err(|source| RunError::Io { path: opts.out_dir.clone(), source })?;
    let simulate = |name: &str, mode: RemeshMode, perturb: bool| -> Result<RunReport, RunError> {
        let mut s = scene.clone();
        if s.set_remesh_mode(mode) == 0 && mode != RemeshMode::Uniform {
            return Err(RunError::Input(InputError {
                file: s.file.clone(),
                location: None,
                msg: format!("scene '{}' has no cloth with a remesh block to run in {name} mode", s.name),
            }));
        }
        if perturb {
            perturb_positions(&mut s);
        }
        let dir = opts.out_dir.join(name);
        if !opts.quiet {
            eprintln!("compare: {name} run → {}", dir.display());
        }
        let run_opts = RunOptions { out_dir: dir.clone(), frames: opts.frames, quiet: true, export_obstacles: false };
        let stats = run(s, &run_opts)?;
        Ok(run_report(name, dir, &stats))
    };
    let reference = match &opts.reference {
        Some(dir) => run_report("reference", dir.clone(), &read_stats(dir)?),
        None => simulate("reference", RemeshMode::Uniform, false)?,
    };
    let ref_stats = read_stats(&reference.dir)?;
    let frames = ref_stats.frames.len().saturating_sub(1);
    let mut floor =
        if opts.floor && opts.reference.is_none() { Some(simulate("floor", RemeshMode::Uniform, true)?) } else { None };
    let mut modes = Vec::new();
    for &mode in &opts.modes {
        modes.push(simulate(mode.name(), mode, false)?);
    }
    for r in floor.iter_mut().chain(modes.iter_mut()) {
        r.errors = Some(errors(&reference.dir, &r.dir, &ref_stats, &camera, opts)?);
    }
    let report =
        CompareReport { scene: scene.name.clone(), frames, image: [opts.width, opts.height], reference, floor, modes };
    write_report(&report, &opts.out_dir)?;
    Ok(report)
}

/// Moves every initial node by `FLOOR_PERTURBATION` in a direction fixed by its index
/// (deterministic; no handle is exempt, the size is far below any tolerance).
fn perturb_positions(scene: &mut Scene) {
    for (i, node) in scene.mesh.nodes.iter_mut().enumerate() {
        let h = |k: u64| {
            let mut z = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(k);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) as Real / u64::MAX as Real) * 2.0 - 1.0
        };
        let d = Vec3::new(h(1), h(2), h(3));
        node.x += d.try_normalize(0.0).unwrap_or_else(Vec3::x) * FLOOR_PERTURBATION;
    }
}

fn read_stats(dir: &Path) -> Result<RunStats, RunError> {
    run_dir::read_stats(dir).map_err(RunError::Input)
}

fn run_report(name: &str, dir: PathBuf, stats: &RunStats) -> RunReport {
    let faces = stats.frames.iter().map(|f| f.faces as Real).sum::<Real>() / stats.frames.len().max(1) as Real;
    RunReport { name: name.into(), dir, wall_s: stats.total_wall_s, mean_faces: faces, errors: None }
}

/// A frame's cloth surface: positions and triangles (file names as the run numbers them).
fn frame_mesh(files: &RunFiles, frame: usize) -> Result<(Vec<Vec3>, Vec<[usize; 3]>), RunError> {
    let path = files.frame_path(frame);
    let obj = read_obj(&path).map_err(|msg| RunError::Input(InputError { file: path.clone(), location: None, msg }))?;
    let tris = obj.triangles.iter().map(|t| t.map(|c| c.v)).collect();
    Ok((obj.positions, tris))
}

/// Mean errors of the run in `dir` against the reference over the compared frames.
fn errors(
    reference: &Path,
    dir: &Path,
    ref_stats: &RunStats,
    camera: &Camera,
    opts: &CompareOptions,
) -> Result<Errors, RunError> {
    let stats = read_stats(dir)?;
    let last = stats.frames.len().min(ref_stats.frames.len()).saturating_sub(1);
    let ref_files = RunFiles::scan(reference, 1, last).map_err(RunError::Input)?;
    let files = RunFiles::scan(dir, 1, last).map_err(RunError::Input)?;
    let mut sum = Errors::default();
    let mut n = 0;
    for f in (opts.every.max(1)..=last).step_by(opts.every.max(1)) {
        let (xr, tr) = frame_mesh(&ref_files, f)?;
        let (xc, tc) = frame_mesh(&files, f)?;
        let view = camera.view_at(ref_stats.frames[f].time);
        let ir = rasterize(&xr, &tr, &view, opts.width, opts.height);
        let ic = rasterize(&xc, &tc, &view, opts.width, opts.height);
        let vis = visible_error(&ir, &ic);
        let (mr, mc) = (visible_triangles(&ir, tr.len()), visible_triangles(&ic, tc.len()));
        let all = surface_distance(
            Surface { positions: &xr, triangles: &tr, mask: None },
            Surface { positions: &xc, triangles: &tc, mask: None },
        );
        let seen = surface_distance(
            Surface { positions: &xr, triangles: &tr, mask: Some(&mr) },
            Surface { positions: &xc, triangles: &tc, mask: Some(&mc) },
        );
        accumulate(&mut sum, &vis, &all, &seen);
        n += 1;
    }
    Ok(mean(sum, n))
}

fn accumulate(sum: &mut Errors, vis: &VisibleError, all: &SurfaceDistance, seen: &SurfaceDistance) {
    sum.visible.normal_deg += vis.normal_deg;
    sum.visible.silhouette += vis.silhouette;
    sum.visible.depth += vis.depth;
    sum.visible.pixels += vis.pixels;
    for (s, d) in [(&mut sum.geometric, all), (&mut sum.geometric_visible, seen)] {
        s.mean += d.mean;
        s.p95 += d.p95;
        s.samples += d.samples;
    }
}

fn mean(mut sum: Errors, n: usize) -> Errors {
    let k = n.max(1) as Real;
    sum.visible.normal_deg /= k;
    sum.visible.silhouette /= k;
    sum.visible.depth /= k;
    sum.visible.pixels /= n.max(1);
    for s in [&mut sum.geometric, &mut sum.geometric_visible] {
        s.mean /= k;
        s.p95 /= k;
        s.samples /= n.max(1);
    }
    sum.frames_compared = n;
    sum
}

fn write_report(report: &CompareReport, dir: &Path) -> Result<(), RunError> {
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        crate::io::write_atomic(&path, bytes).map_err(|source| RunError::Io { path, source })
    };
    let json = serde_json::to_string_pretty(report)
        .map_err(|e| RunError::Io { path: dir.join("compare.json"), source: std::io::Error::other(e.to_string()) })?;
    write("compare.json", json.as_bytes())?;
    write("compare.md", markdown(report).as_bytes())?;
    write("compare.svg", svg_plot(report).as_bytes())
}
