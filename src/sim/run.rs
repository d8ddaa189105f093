//! Running a shot: frames out to OBJ and USD (`output`), stats to JSON, checkpoints, progress
//! to the terminal. Every file is written to a temporary name and renamed into place
//! (`io::write_atomic`), in the order frame (OBJ, USD samples) → stats.json → checkpoint, so a
//! run killed at any instant leaves complete files only, and a checkpoint never refers to a
//! frame that is not on disk.

use std::path::{Path, PathBuf};

use crate::error::InputError;
use crate::io::obj::ClothOut;
use crate::io::stats::RunStats;
use crate::io::OutputFormat;
use crate::math::Real;
use crate::scene::{RemeshMode, Scene};
use crate::shot::{self, ShotRequest};

use super::checkpoint::{self, CheckpointError, RunRecord};
use super::output::{Output, USD_FILE, USD_SAMPLES};
use super::progress::{Progress, ProgressMode};
use super::{SimError, Simulation};

#[derive(Default)]
pub struct RunOptions {
    pub out_dir: PathBuf,
    /// Overrides the scene's frame count.
    pub frames: Option<usize>,
    pub quiet: bool,
    /// Also write each obstacle's world-space mesh per frame (`obstacle_<name>_NNNN.obj`, and
    /// a prim in the USD layer).
    pub export_obstacles: bool,
    /// OBJ frames, the USD layer, or both.
    pub format: OutputFormat,
    /// OBJ frames carry each node's velocity on an `nv` line (ARCSim's).
    pub obj_velocities: bool,
    /// Move the initial cloth positions by a seeded jitter (`Scene::jitter_positions`).
    pub jitter: Option<Jitter>,
}

/// A seeded jitter of the initial cloth positions: every node moved by `amplitude` (m) in its
/// own direction drawn from `seed`. Recorded in stats.json (`jitter_seed`, `jitter_m`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jitter {
    pub seed: u64,
    pub amplitude: Real,
}

impl Jitter {
    /// The default amplitude of `simulate --jitter-seed` (m).
    pub const AMPLITUDE: Real = 1e-6;
}

/// Checkpointing of a run: every `every` frames (and at the last; `every` 0: only when the run
/// is interrupted), with what `resume` needs to reload the scene.
pub struct CheckpointOptions {
    pub every: usize,
    /// The scene file, `None` for the built-in shot.
    pub scene_file: Option<PathBuf>,
    /// The `--mode` override applied to the scene.
    pub mode: Option<RemeshMode>,
    /// The `--camera` file applied to the scene (absolute).
    pub camera_file: Option<PathBuf>,
}

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Sim(#[from] SimError),
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// No usable checkpoint, or one that does not fit its scene (bad input to `resume`).
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error("{0}")]
    Input(InputError),
    /// An output file could not be made from the run's own files (e.g. a damaged USD samples
    /// file).
    #[error("{0}")]
    Output(String),
    /// SIGTERM or SIGINT: the run stopped after the frame `at` describes, checkpointed when
    /// it could be.
    #[error("{}", interrupted_message(.dir, .at, .checkpoint.as_deref()))]
    Interrupted { dir: PathBuf, at: String, checkpoint: Option<PathBuf> },
}

fn interrupted_message(dir: &Path, at: &str, checkpoint: Option<&Path>) -> String {
    match checkpoint {
        Some(ck) => format!(
            "interrupted after {at}; checkpoint {}: continue with `viewcloth resume {}`",
            ck.display(),
            dir.display()
        ),
        None => format!("interrupted after {at} (no checkpoint: the run was not checkpointed)"),
    }
}

pub(super) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io { path: path.to_path_buf(), source }
}

/// Simulates `scene`, writing `frame_NNNN.obj` (numbered from the scene's `start_frame`, the
/// initial state first) and/or the USD layer, and `stats.json` (rewritten after every frame, so
/// it is valid at any instant) into `opts.out_dir`.
pub fn run(scene: Scene, opts: &RunOptions) -> Result<RunStats, RunError> {
    run_with_checkpoints(scene, opts, None)
}

/// `run`, also writing checkpoints when `ck` is given.
pub fn run_with_checkpoints(
    scene: Scene,
    opts: &RunOptions,
    ck: Option<&CheckpointOptions>,
) -> Result<RunStats, RunError> {
    let progress = Progress::new(ProgressMode::choose(None, opts.quiet));
    run_shot(scene, opts, ck, &progress)
}

/// `run_with_checkpoints`, reporting its frames to `progress` (`opts.quiet` is not looked at).
pub fn run_shot(
    mut scene: Scene,
    opts: &RunOptions,
    ck: Option<&CheckpointOptions>,
    progress: &Progress,
) -> Result<RunStats, RunError> {
    let frames = opts.frames.unwrap_or(scene.frames);
    let digits = (scene.start_frame + frames).to_string().len().max(4);
    let record = ck.map(|c| RunRecord {
        scene_file: c.scene_file.clone(),
        mode: c.mode,
        camera_file: c.camera_file.clone(),
        fingerprint: checkpoint::scene_fingerprint(&scene),
        frames,
        digits,
        export_obstacles: opts.export_obstacles,
        every: c.every,
        format: opts.format,
        obj_velocities: opts.obj_velocities,
    });
    // After the fingerprint: `resume` reloads the scene as it is in its file, and the jittered
    // positions live on in the checkpointed state.
    if let Some(j) = &opts.jitter {
        scene.jitter_positions(j.seed, j.amplitude);
    }
    let cloths = ClothOut::of(&scene);
    let last = scene.preroll_frames + frames;
    let mut sim = Simulation::new(scene)?;
    let adaptive = is_adaptive(&sim.scene);
    let view = sim.scene.cloths.iter().any(|c| c.remesh.as_ref().is_some_and(|r| r.mode == RemeshMode::View));
    let mode = if view {
        "view"
    } else if adaptive {
        "adaptive"
    } else {
        "uniform"
    };
    let stats = RunStats {
        scene: sim.scene.name.clone(),
        mode: mode.into(),
        jitter_seed: opts.jitter.map(|j| j.seed),
        jitter_m: opts.jitter.map(|j| j.amplitude),
        ..Default::default()
    };
    let out = Output {
        dir: &opts.out_dir,
        cloths,
        digits,
        export_obstacles: opts.export_obstacles,
        format: opts.format,
        obj_velocities: opts.obj_velocities,
        record,
        adaptive,
    };
    out.prepare()?;
    out.frames(&mut sim, stats, 0, last, progress, 0.0)
}

/// Options of `viewcloth resume`.
pub struct ResumeOptions {
    /// New frame count (default: the run's own).
    pub frames: Option<usize>,
    /// The output format asked for: it must be the run's own (a layer cannot gain the frames
    /// written before in another format).
    pub format: Option<OutputFormat>,
    pub progress: Progress,
}

/// Continues the run in `dir` from its newest intact checkpoint, to its last frame (or
/// `opts.frames`). The frames it writes are identical to an uninterrupted run's.
pub fn resume(dir: &Path, opts: &ResumeOptions) -> Result<RunStats, RunError> {
    let (path, ck) = checkpoint::latest(dir)?;
    let mut record = ck.run;
    let request = ShotRequest {
        scene: record.scene_file.clone(),
        base: None,
        camera: record.camera_file.clone(),
        mode: record.mode,
        camera_implies_view: false,
    };
    let scene = shot::resolve(&request).map_err(|e| RunError::Input(e.error))?.scene;
    if checkpoint::scene_fingerprint(&scene) != record.fingerprint {
        return Err(RunError::Input(InputError {
            file: scene.file.clone(),
            location: None,
            msg: format!(
                "the scene (or a file it references) changed since {} was written; resume needs the scene the run started with",
                path.display()
            ),
        }));
    }
    if let Some(format) = opts.format.filter(|&f| f != record.format) {
        return Err(RunError::Input(InputError {
            file: path.clone(),
            location: None,
            msg: format!(
                "--format {}: the run writes {}; resume continues it so (start a new run for another format)",
                format.name(),
                record.format.name()
            ),
        }));
    }
    let first = ck.state.frame;
    let frames = opts.frames.unwrap_or(record.frames);
    let last = scene.preroll_frames + frames;
    if last <= first {
        let at = scene.frame_number(first).map_or(format!("preroll frame {first}"), |n| format!("frame {n}"));
        return Err(RunError::Input(InputError {
            file: path.clone(),
            location: None,
            msg: format!("--frames {frames}: the checkpoint is at {at}; expected more frames than that"),
        }));
    }
    record.frames = frames;
    remove_stale_temporaries(dir);
    remove_stale_temporaries(&dir.join(USD_SAMPLES));
    let cloths = ClothOut::of(&scene);
    let mut sim = Simulation::restore(scene, ck.state)?;
    let mut stats = ck.stats;
    let kept = sim.scene.frame_number(first);
    stats.frames.retain(|f| kept.is_some_and(|n| f.frame <= n));
    stats.resumed_at.push(first);
    stats.error = None;
    let adaptive = is_adaptive(&sim.scene);
    let out = Output {
        dir,
        cloths,
        digits: record.digits,
        export_obstacles: record.export_obstacles,
        format: record.format,
        obj_velocities: record.obj_velocities,
        record: Some(record),
        adaptive,
    };
    out.prepare()?;
    let wall_before = stats.total_wall_s;
    out.frames(&mut sim, stats, first + 1, last, &opts.progress, wall_before)
}

/// Readies `dir` for a fresh run of the scene named `scene_name` (file `scene_file`): refused
/// when it holds another scene's run (its stats.json names another scene, a checkpoint another
/// scene file, or frames come with no stats.json) unless `force`; then the files of the run it
/// replaces (frames, obstacle meshes, checkpoints, stats.json) are removed, so that no stale
/// checkpoint can later be resumed into the new run's output.
pub fn claim_output(dir: &Path, scene_name: &str, scene_file: Option<&Path>, force: bool) -> Result<(), RunError> {
    if !force {
        check_output(dir, scene_name, scene_file)?;
    }
    clear_output(dir)
}

/// The refusal of `claim_output`, alone (nothing is removed).
pub fn check_output(dir: &Path, scene_name: &str, scene_file: Option<&Path>) -> Result<(), RunError> {
    if run_files(dir).is_empty() {
        return Ok(());
    }
    match other_run(dir, scene_name, scene_file) {
        None => Ok(()),
        Some(other) => Err(RunError::Input(InputError {
            file: dir.to_path_buf(),
            location: None,
            msg: format!("holds {other}; give --force to replace it, or another output directory"),
        })),
    }
}

/// Removes the files of a run in `dir` (frames, obstacle meshes, USD layer and samples,
/// checkpoints, stats.json).
pub fn clear_output(dir: &Path) -> Result<(), RunError> {
    for p in run_files(dir) {
        std::fs::remove_file(&p).map_err(io_err(&p))?;
    }
    let samples = dir.join(USD_SAMPLES);
    if samples.is_dir() {
        std::fs::remove_dir_all(&samples).map_err(io_err(&samples))?;
    }
    Ok(())
}

fn run_files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut files: Vec<PathBuf> = entries.flatten().map(|e| e.path()).filter(|p| is_run_file(p)).collect();
    if let Ok(samples) = std::fs::read_dir(dir.join(USD_SAMPLES)) {
        files.extend(samples.flatten().map(|e| e.path()).filter(|p| p.is_file()));
    }
    files
}

/// The run in `dir` when it is not one of this scene, described.
fn other_run(dir: &Path, scene_name: &str, scene_file: Option<&Path>) -> Option<String> {
    if let Ok((_, ck)) = checkpoint::latest(dir) {
        if ck.run.scene_file.as_deref() != scene_file {
            let name = ck.run.scene_file.map_or("the built-in shot".into(), |f| f.display().to_string());
            return Some(format!("a checkpointed run of another scene ({name})"));
        }
    }
    let stats = std::fs::read(dir.join("stats.json")).ok();
    let name = stats
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|v| v.get("scene").and_then(|s| s.as_str()).map(str::to_string));
    match name {
        Some(n) if n == scene_name => None,
        Some(n) => Some(format!("the frames of another scene ('{n}')")),
        None => Some("frames without a readable stats.json (another run's?)".into()),
    }
}

/// A file a run writes in its directory: frame, obstacle mesh, USD layer, checkpoint,
/// stats.json (the USD samples are in their own folder).
fn is_run_file(path: &Path) -> bool {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else { return false };
    let numbered = |prefix: &str, suffix: &str| {
        name.strip_prefix(prefix).and_then(|n| n.strip_suffix(suffix)).is_some_and(|n| !n.is_empty())
    };
    name == "stats.json"
        || name == USD_FILE
        || numbered("frame_", ".obj")
        || numbered("obstacle_", ".obj")
        || numbered("checkpoint_", ".bin")
}

pub(super) fn is_adaptive(scene: &Scene) -> bool {
    scene.cloths.iter().any(|c| c.remesh.as_ref().is_some_and(|r| r.mode.is_adaptive()))
}

/// Removes temporary files of interrupted atomic writes (`.<name>.tmp<pid>`).
fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if crate::io::is_temp_name(&name) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// A name reduced to characters safe in a file name.
pub(super) fn file_safe(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}
