//! `viewcloth compare` (DESIGN.md "Error against run time"): one shot simulated in several
//! remeshing modes, each run's frames measured against a reference run from the shot camera.
//!
//! The reference is the uniform mesh at the adaptive minimum edge length (or a run the user
//! names). Cloth is chaotic: runs that differ by rounding grow different wrinkles, so the
//! reference is also re-run K times from positions independently perturbed by
//! `FLOOR_PERTURBATION`, and those runs' errors, the chaos floor with its spread (`floor`), are
//! what an error should be compared with: each mode gets, per measure, a multiple of the floor
//! and a verdict (within the band, or how many standard deviations above).
//!
//! Per compared frame, the cloth and the obstacles (exported by the runs, or re-posed from the
//! scene) are rasterised from the camera at that frame's time: visible error over the pixels
//! where cloth is in front (shading and flat normal angle, silhouette mismatch, relative depth)
//! and geometric error (two-sided distance between the densely sampled surfaces, over all cloth
//! and weighted by each triangle's visible pixel fraction); per run, every frame's errors and
//! their means, with the wall time and mean face count.

mod floor;
mod report;
mod strip;
mod upsampled;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::camera::Camera;
use crate::collision::obstacle::ObstacleBody;
use crate::error::InputError;
use crate::io::stats::RunStats;
use crate::math::{Real, Vec3};
use crate::metrics::{surface_distance, visible_error, FrameImage, Surface};
use crate::metrics::{SurfaceDistance, VisibleError};
use crate::render::run_dir::{self, FrameMeshes, RunFiles};
use crate::scene::{RemeshMode, Scene};
use crate::sim::progress::{Progress, ProgressMode};
use crate::sim::{run_shot, Jitter, RunError, RunOptions};

pub use floor::{floor_band, verdicts, FloorBand, MeasureBand, Verdict, MEASURES};
pub use report::{markdown, svg_curves, svg_plot};
pub use upsampled::UpsampleOptions;

/// Size (m) of the random displacement of every initial node in the chaos-floor runs.
pub const FLOOR_PERTURBATION: Real = 1e-6;
/// Floor runs by default (`--floor-runs`).
pub const FLOOR_RUNS: usize = 3;
/// Edge-length multiples of the `--sweep` uniform runs.
pub const SWEEP: [Real; 2] = [2.0, 4.0];

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
    /// Chaos-floor runs (the reference from independently perturbed positions); 0 for none.
    pub floor_runs: usize,
    /// Also run uniform meshes at `SWEEP` times the minimum edge length (`uniform_2x`, …).
    pub sweep: bool,
    /// Rasterised image size (pixels).
    pub width: usize,
    pub height: usize,
    /// Compare every this many frames (frame 0, the shared initial state, is skipped).
    pub every: usize,
    pub quiet: bool,
    /// How the runs report their frames.
    pub progress: ProgressMode,
    /// Adds the modes `coarse`, `upsampled` and `loop` (`upsampled.rs`).
    pub upsample: Option<UpsampleOptions>,
}

/// The error of one run against the reference in one frame.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrameErrors {
    pub frame: usize,
    pub time: Real,
    pub visible: VisibleError,
    /// Over all cloth.
    pub geometric: SurfaceDistance,
    /// Each triangle weighted by its visible pixel fraction (in its own run's image).
    pub geometric_visible: SurfaceDistance,
}

/// The error of one run against the reference, averaged over the compared frames, and per frame.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Errors {
    pub visible: VisibleError,
    /// Over all cloth.
    pub geometric: SurfaceDistance,
    /// Each triangle weighted by its visible pixel fraction (in its own run's image).
    pub geometric_visible: SurfaceDistance,
    pub frames_compared: usize,
    pub per_frame: Vec<FrameErrors>,
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
    /// Every measure against the floor band (modes only, when there is a floor).
    pub verdicts: Option<Vec<Verdict>>,
}

#[derive(Clone, Debug, Serialize)]
pub struct CompareReport {
    pub scene: String,
    pub frames: usize,
    pub image: [usize; 2],
    pub reference: RunReport,
    /// The perturbed references (`floor_1`, `floor_2`, …): their errors are the chaos floor.
    pub floors: Vec<RunReport>,
    /// The floor's mean and spread per measure, per frame and over the run.
    pub floor_band: Option<FloorBand>,
    pub modes: Vec<RunReport>,
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
    // `edge` scales every cloth's minimum edge length (the uniform runs of the sweep).
    let simulate_scaled =
        |name: &str, mode: RemeshMode, perturb: Option<u64>, edge: Real| -> Result<RunReport, RunError> {
            let mut s = scene.clone();
            for r in s.cloths.iter_mut().filter_map(|c| c.remesh.as_mut()) {
                r.sizing.size_min *= edge;
                r.sizing.size_max = r.sizing.size_max.max(r.sizing.size_min);
            }
            if s.set_remesh_mode(mode) == 0 && mode != RemeshMode::Uniform {
                return Err(RunError::Input(InputError {
                    file: s.file.clone(),
                    location: None,
                    msg: format!("scene '{}' has no cloth with a remesh block to run in {name} mode", s.name),
                }));
            }
            let dir = opts.out_dir.join(name);
            if let Some(stats) = finished_run(&dir, &s, opts.frames.unwrap_or(s.frames)) {
                if !opts.quiet {
                    eprintln!("compare: {name}: reusing the finished run in {}", dir.display());
                }
                return Ok(run_report(name, dir, &stats));
            }
            if !opts.quiet {
                eprintln!("compare: {name} run → {}", dir.display());
            }
            // Obstacles exported: the frames are rasterised with them (and `render` shows them). The
            // run's progress bar (on a terminal) unless quiet.
            let run_opts = RunOptions {
                out_dir: dir.clone(),
                frames: opts.frames,
                quiet: opts.quiet,
                export_obstacles: true,
                jitter: perturb.map(|seed| Jitter { seed, amplitude: FLOOR_PERTURBATION }),
                ..Default::default()
            };
            let progress = Progress { label: Some(format!("{name} run")), ..Progress::new(opts.progress) };
            let stats = run_shot(s, &run_opts, None, &progress)?;
            Ok(run_report(name, dir, &stats))
        };
    let simulate = |name: &str, mode: RemeshMode, perturb: Option<u64>| -> Result<RunReport, RunError> {
        simulate_scaled(name, mode, perturb, 1.0)
    };
    let reference = match &opts.reference {
        Some(dir) => run_report("reference", dir.clone(), &read_stats(dir)?),
        None => simulate("reference", RemeshMode::Uniform, None)?,
    };
    let ref_stats = read_stats(&reference.dir)?;
    let frames = ref_stats.frames.len().saturating_sub(1);
    let floor_runs = if opts.reference.is_none() { opts.floor_runs } else { 0 };
    let mut floors = Vec::new();
    for k in 1..=floor_runs {
        floors.push(simulate(&format!("floor_{k}"), RemeshMode::Uniform, Some(k as u64))?);
    }
    let mut modes = Vec::new();
    for &mode in &opts.modes {
        modes.push(simulate(mode.name(), mode, None)?);
    }
    for k in SWEEP.iter().filter(|_| opts.sweep) {
        modes.push(simulate_scaled(&format!("uniform_{k}x"), RemeshMode::Uniform, None, *k)?);
    }
    if let Some(up) = &opts.upsample {
        modes.extend(upsampled::runs(up, opts)?);
    }
    let bodies: Vec<ObstacleBody> = scene.obstacles.iter().map(ObstacleBody::new).collect();
    for r in floors.iter_mut().chain(modes.iter_mut()) {
        if !opts.quiet {
            eprintln!("compare: measuring {} against the reference", r.name);
        }
        r.errors = Some(errors(&reference.dir, &r.dir, &ref_stats, &camera, &bodies, opts)?);
    }
    let floor_errors: Vec<&Errors> = floors.iter().filter_map(|r| r.errors.as_ref()).collect();
    let floor_band = floor_band(&floor_errors);
    if let Some(band) = &floor_band {
        for m in &mut modes {
            m.verdicts = m.errors.as_ref().map(|e| verdicts(band, e));
        }
    }
    let report = CompareReport {
        scene: scene.name.clone(),
        frames,
        image: [opts.width, opts.height],
        reference,
        floors,
        floor_band,
        modes,
    };
    write_report(&report, &opts.out_dir)?;
    Ok(report)
}

/// The stats of the run in `dir` when it is finished and matches the request: no error, the
/// scene's name and remeshing mode, frames 0..=`frames` all listed, and the last frame's
/// obstacles exported when the scene has obstacles. What the run's scene file held is not
/// checked: delete the folder to force a re-run.
fn finished_run(dir: &Path, scene: &Scene, frames: usize) -> Option<RunStats> {
    let stats = run_dir::read_stats(dir).ok()?;
    let mode = if scene.cloths.iter().any(|c| c.remesh.as_ref().is_some_and(|r| r.mode == RemeshMode::View)) {
        "view"
    } else if scene.cloths.iter().any(|c| c.remesh.as_ref().is_some_and(|r| r.mode.is_adaptive())) {
        "adaptive"
    } else {
        "uniform"
    };
    let numbered = |k: usize, f: &crate::io::stats::FrameStats| f.frame == scene.start_frame + k;
    let all_frames = stats.frames.len() == frames + 1 && stats.frames.iter().enumerate().all(|(k, f)| numbered(k, f));
    let matches = stats.error.is_none() && stats.scene == scene.name && stats.mode == mode && all_frames;
    let last = scene.start_frame + frames;
    let files = RunFiles::scan(dir, last, last).ok()?;
    let obstacles = scene.obstacles.is_empty() || files.obstacles(last).ok()?.is_some();
    (matches && obstacles && files.has_frame(last)).then_some(stats)
}

fn read_stats(dir: &Path) -> Result<RunStats, RunError> {
    run_dir::read_stats(dir).map_err(RunError::Input)
}

fn run_report(name: &str, dir: PathBuf, stats: &RunStats) -> RunReport {
    let faces = stats.frames.iter().map(|f| f.faces as Real).sum::<Real>() / stats.frames.len().max(1) as Real;
    RunReport { name: name.into(), dir, wall_s: stats.total_wall_s, mean_faces: faces, errors: None, verdicts: None }
}

/// A frame's cloth: positions and triangles.
type ClothMesh = (Vec<Vec3>, Vec<[usize; 3]>);

/// A frame's cloth surface: positions and triangles (file names as the run numbers them).
fn frame_mesh(files: &RunFiles, frame: usize) -> Result<ClothMesh, RunError> {
    let m = files.cloth(frame).map_err(RunError::Input)?;
    Ok((m.positions, m.triangles))
}

/// The obstacles of `frame` at `time`: those the reference run exported, or else the scene's
/// re-posed at that time (the same meshes: obstacles are scripted, not simulated).
fn obstacles(ref_files: &RunFiles, bodies: &[ObstacleBody], frame: usize, time: Real) -> Result<FrameMeshes, RunError> {
    if let Some(m) = ref_files.obstacles(frame).map_err(RunError::Input)? {
        return Ok(m);
    }
    let mut m = FrameMeshes::default();
    for b in bodies.iter().filter(|b| b.present_at(time)) {
        m.append(b.positions_at(time), b.triangles().to_vec());
    }
    Ok(m)
}

/// The cloth and the obstacles seen from `view`.
fn frame_image(
    cloth: &ClothMesh,
    obstacles: &FrameMeshes,
    view: &crate::camera::View,
    opts: &CompareOptions,
) -> FrameImage {
    let mut all = FrameMeshes::default();
    all.append(cloth.0.clone(), cloth.1.clone());
    all.append(obstacles.positions.clone(), obstacles.triangles.clone());
    FrameImage::render(&all.positions, &all.triangles, cloth.1.len(), view, opts.width, opts.height)
}

/// One frame's errors of `candidate` against `reference` (cloth meshes), with the obstacles.
fn frame_errors(
    reference: &ClothMesh,
    candidate: &ClothMesh,
    obstacles: &FrameMeshes,
    view: &crate::camera::View,
    opts: &CompareOptions,
) -> (VisibleError, SurfaceDistance, SurfaceDistance, [FrameImage; 2]) {
    let (ir, ic) = (frame_image(reference, obstacles, view, opts), frame_image(candidate, obstacles, view, opts));
    let vis = visible_error(&ir, &ic);
    let all = surface_distance(surface(reference, None), surface(candidate, None));
    let seen = surface_distance(
        surface(reference, Some(&ir.visible_fraction[..])),
        surface(candidate, Some(&ic.visible_fraction[..])),
    );
    (vis, all, seen, [ir, ic])
}

fn surface<'a>(m: &'a ClothMesh, weight: Option<&'a [Real]>) -> Surface<'a> {
    Surface { positions: &m.0, triangles: &m.1, weight }
}

/// Errors of the run in `dir` against the reference over the compared frames.
fn errors(
    reference: &Path,
    dir: &Path,
    ref_stats: &RunStats,
    camera: &Camera,
    bodies: &[ObstacleBody],
    opts: &CompareOptions,
) -> Result<Errors, RunError> {
    let stats = read_stats(dir)?;
    let last = stats.frames.len().min(ref_stats.frames.len()).saturating_sub(1);
    // Frames are compared by their place in the run; files are named by their numbers (from
    // the scene's start_frame).
    let number = |k: usize| ref_stats.frames.get(k).map_or(k, |f| f.frame);
    let ref_files = RunFiles::scan(reference, number(1), number(last)).map_err(RunError::Input)?;
    let files = RunFiles::scan(dir, number(1), number(last)).map_err(RunError::Input)?;
    let mut per_frame = Vec::new();
    let compared: Vec<usize> = (opts.every.max(1)..=last).step_by(opts.every.max(1)).collect();
    let strips = strip::strip_frames(&compared);
    for (k, &f) in compared.iter().enumerate() {
        if !opts.quiet && (k + 1) % compared.len().div_ceil(10).max(1) == 0 {
            eprintln!("compare: {}: frame {} ({}/{} compared)", dir.display(), number(f), k + 1, compared.len());
        }
        let (time, n) = (ref_stats.frames[f].time, number(f));
        let (r, c) = (frame_mesh(&ref_files, n)?, frame_mesh(&files, n)?);
        let obstacles = obstacles(&ref_files, bodies, n, time)?;
        let view = camera.view_at(time);
        let (visible, geometric, geometric_visible, [ir, ic]) = frame_errors(&r, &c, &obstacles, &view, opts);
        if strips.contains(&f) {
            write_strip(&files.frame_path(n), [&r, &c], &obstacles, &view, [&ir, &ic], opts)?;
        }
        per_frame.push(FrameErrors { frame: n, time, visible, geometric, geometric_visible });
    }
    Ok(mean(per_frame))
}

/// Writes `strip_NNNN.png` next to the run's frame `frame_obj`: reference | run | heat map.
fn write_strip(
    frame_obj: &Path,
    cloths: [&ClothMesh; 2],
    obstacles: &FrameMeshes,
    view: &crate::camera::View,
    images: [&FrameImage; 2],
    opts: &CompareOptions,
) -> Result<(), RunError> {
    let (w, h) = (opts.width, opts.height);
    let render = |cloth: &ClothMesh| {
        let mut all = FrameMeshes::default();
        all.append(cloth.0.clone(), cloth.1.clone());
        all.cloth_triangles = cloth.1.len();
        all.append(obstacles.positions.clone(), obstacles.triangles.clone());
        crate::render::render_frame(&all, view, w, h, crate::render::Colouring::Shade)
    };
    let (r, c, heat) = (render(cloths[0]), render(cloths[1]), strip::heat_map(images[0], images[1]));
    let png = crate::render::png::encode(3 * w, h, &strip::side_by_side([&r, &c, &heat], w, h));
    let name = frame_obj.file_name().map_or_else(String::new, |n| n.to_string_lossy().replace("frame_", "strip_"));
    let path = frame_obj.with_file_name(name.replace(".obj", ".png"));
    crate::io::write_atomic(&path, &png).map_err(|source| RunError::Io { path, source })
}

/// Means over the frames (counts too, rounded down), with the frames kept.
fn mean(per_frame: Vec<FrameErrors>) -> Errors {
    let n = per_frame.len();
    let k = n.max(1) as Real;
    let mut sum = Errors::default();
    for e in &per_frame {
        let (s, v) = (&mut sum.visible, &e.visible);
        s.normal_deg += v.normal_deg / k;
        s.normal_flat_deg += v.normal_flat_deg / k;
        s.silhouette += v.silhouette / k;
        s.depth += v.depth / k;
        s.pixels += v.pixels;
        for (s, d) in [(&mut sum.geometric, &e.geometric), (&mut sum.geometric_visible, &e.geometric_visible)] {
            s.mean += d.mean / k;
            s.rms += d.rms / k;
            s.p95 += d.p95 / k;
            s.max += d.max / k;
            s.samples += d.samples;
        }
    }
    sum.visible.pixels /= n.max(1);
    sum.geometric.samples /= n.max(1);
    sum.geometric_visible.samples /= n.max(1);
    sum.frames_compared = n;
    sum.per_frame = per_frame;
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
    write("compare.svg", svg_plot(report).as_bytes())?;
    for (k, m) in MEASURES.iter().enumerate().filter(|(_, m)| ["normal_deg", "distance_mean"].contains(&m.name)) {
        write(&format!("compare_frames_{}.svg", m.name), svg_curves(report, k).as_bytes())?;
    }
    Ok(())
}
