//! Running a shot: frames out to OBJ, stats to JSON, checkpoints, progress to the terminal.
//! Every file is written to a temporary name and renamed into place (`io::write_atomic`), in
//! the order frame → stats.json → checkpoint, so a run killed at any instant leaves complete
//! files only, and a checkpoint never refers to a frame that is not on disk.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::InputError;
use crate::io::obj::{frame_obj, obstacle_obj};
use crate::io::stats::{CollisionFrameStats, RemeshFrameStats, RunStats};
use crate::io::write_atomic;
use crate::math::Real;
use crate::scene::{RemeshMode, Scene};
use crate::shot::{self, ShotRequest};

use super::checkpoint::{self, CheckpointError, RunRecord};
use super::progress::{Progress, ProgressMode, Reporter};
use super::timers::Stage;
use super::{SimError, Simulation};

pub struct RunOptions {
    pub out_dir: PathBuf,
    /// Overrides the scene's frame count.
    pub frames: Option<usize>,
    pub quiet: bool,
    /// Also write each obstacle's world-space mesh per frame (`obstacle_<name>_NNNN.obj`).
    pub export_obstacles: bool,
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
    /// SIGTERM or SIGINT: the run stopped after frame `frame`, checkpointed when it could be.
    #[error("{}", interrupted_message(.dir, *.frame, *.last, .checkpoint.as_deref()))]
    Interrupted { dir: PathBuf, frame: usize, last: usize, checkpoint: Option<PathBuf> },
}

fn interrupted_message(dir: &Path, frame: usize, last: usize, checkpoint: Option<&Path>) -> String {
    match checkpoint {
        Some(ck) => format!(
            "interrupted after frame {frame} of {last}; checkpoint {}: continue with `viewcloth resume {}`",
            ck.display(),
            dir.display()
        ),
        None => format!("interrupted after frame {frame} of {last} (no checkpoint: the run was not checkpointed)"),
    }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io { path: path.to_path_buf(), source }
}

/// Simulates `scene`, writing `frame_NNNN.obj` (frame 0 is the initial state) and `stats.json`
/// (rewritten after every frame, so it is valid at any instant) into `opts.out_dir`.
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
    let digits = frames.to_string().len().max(4);
    let record = ck.map(|c| RunRecord {
        scene_file: c.scene_file.clone(),
        mode: c.mode,
        camera_file: c.camera_file.clone(),
        fingerprint: checkpoint::scene_fingerprint(&scene),
        frames,
        digits,
        export_obstacles: opts.export_obstacles,
        every: c.every,
    });
    // After the fingerprint: `resume` reloads the scene as it is in its file, and the jittered
    // positions live on in the checkpointed state.
    if let Some(j) = &opts.jitter {
        scene.jitter_positions(j.seed, j.amplitude);
    }
    let names: Vec<String> = scene.cloths.iter().map(|c| c.name.clone()).collect();
    let mut sim = Simulation::new(scene)?;
    std::fs::create_dir_all(&opts.out_dir).map_err(io_err(&opts.out_dir))?;
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
    let out = Output { dir: &opts.out_dir, names, digits, export_obstacles: opts.export_obstacles, record, adaptive };
    out.frames(&mut sim, stats, 0, frames, progress, 0.0)
}

/// Options of `viewcloth resume`.
pub struct ResumeOptions {
    /// New last frame (default: the run's own).
    pub frames: Option<usize>,
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
    let first = ck.state.frame;
    let frames = opts.frames.unwrap_or(record.frames);
    if frames <= first {
        return Err(RunError::Input(InputError {
            file: path.clone(),
            location: None,
            msg: format!("--frames {frames}: the checkpoint is at frame {first}; expected a last frame after it"),
        }));
    }
    record.frames = frames;
    remove_stale_temporaries(dir);
    let names: Vec<String> = scene.cloths.iter().map(|c| c.name.clone()).collect();
    let mut sim = Simulation::restore(scene, ck.state)?;
    let mut stats = ck.stats;
    stats.frames.truncate(first + 1);
    stats.resumed_at.push(first);
    stats.error = None;
    let adaptive = is_adaptive(&sim.scene);
    let out = Output {
        dir,
        names,
        digits: record.digits,
        export_obstacles: record.export_obstacles,
        record: Some(record),
        adaptive,
    };
    let wall_before = stats.total_wall_s;
    out.frames(&mut sim, stats, first + 1, frames, &opts.progress, wall_before)
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

/// Removes the files of a run in `dir` (frames, obstacle meshes, checkpoints, stats.json).
pub fn clear_output(dir: &Path) -> Result<(), RunError> {
    for p in run_files(dir) {
        std::fs::remove_file(&p).map_err(io_err(&p))?;
    }
    Ok(())
}

fn run_files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    entries.flatten().map(|e| e.path()).filter(|p| is_run_file(p)).collect()
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

/// A file a run writes: frame, obstacle mesh, checkpoint, stats.json.
fn is_run_file(path: &Path) -> bool {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else { return false };
    let numbered = |prefix: &str, suffix: &str| {
        name.strip_prefix(prefix).and_then(|n| n.strip_suffix(suffix)).is_some_and(|n| !n.is_empty())
    };
    name == "stats.json"
        || numbered("frame_", ".obj")
        || numbered("obstacle_", ".obj")
        || numbered("checkpoint_", ".bin")
}

fn is_adaptive(scene: &Scene) -> bool {
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

/// Where and how a run writes.
struct Output<'a> {
    dir: &'a Path,
    names: Vec<String>,
    digits: usize,
    export_obstacles: bool,
    /// Present when checkpointing.
    record: Option<RunRecord>,
    adaptive: bool,
}

impl Output<'_> {
    fn frame_path(&self, f: usize) -> PathBuf {
        self.dir.join(format!("frame_{f:0w$}.obj", w = self.digits))
    }

    fn write_frame(&self, sim: &mut Simulation, f: usize) -> Result<(), RunError> {
        let path = self.frame_path(f);
        let clock = Instant::now();
        write_atomic(&path, frame_obj(&sim.state.mesh, &self.names).as_bytes()).map_err(io_err(&path))?;
        if self.export_obstacles {
            if let Some(world) = &sim.ws.collisions {
                for (body, obstacle) in world.bodies.iter().zip(&sim.scene.obstacles) {
                    let path =
                        self.dir.join(format!("obstacle_{}_{f:0w$}.obj", file_safe(&obstacle.name), w = self.digits));
                    let text = obstacle_obj(&body.positions_at(sim.state.time), body.triangles());
                    write_atomic(&path, text.as_bytes()).map_err(io_err(&path))?;
                }
            }
        }
        sim.ws.timers.since(Stage::Output, clock);
        Ok(())
    }

    fn write_stats(&self, stats: &RunStats) -> Result<(), RunError> {
        let path = self.dir.join("stats.json");
        let json =
            serde_json::to_vec_pretty(stats).map_err(|e| RunError::Io { path: path.clone(), source: e.into() })?;
        write_atomic(&path, &json).map_err(io_err(&path))
    }

    /// Writes the checkpoint of frame `f` when due (every `every` frames and at the last) or
    /// `now`, then removes all but it and the one before it. Returns its path when written.
    fn checkpoint(
        &self,
        sim: &mut Simulation,
        stats: &RunStats,
        f: usize,
        last: usize,
        now: bool,
    ) -> Result<Option<PathBuf>, RunError> {
        let Some(record) = &self.record else { return Ok(None) };
        let due = record.every > 0 && f > 0 && (f.is_multiple_of(record.every) || f == last);
        if !due && !now {
            return Ok(None);
        }
        let clock = Instant::now();
        let path = checkpoint::checkpoint_path(self.dir, f, self.digits);
        write_atomic(&path, &checkpoint::encode(record, &sim.state, stats)).map_err(io_err(&path))?;
        let old = checkpoint::list(self.dir).map_err(io_err(self.dir))?;
        for (_, p) in old.iter().filter(|(k, _)| *k < f).skip(1) {
            let _ = std::fs::remove_file(p);
        }
        sim.ws.timers.since(Stage::Checkpoint, clock);
        Ok(Some(path))
    }

    /// Frames `first..=last` (frame 0 is the initial state, not simulated); `wall_before` is
    /// the wall time of earlier sessions of the run.
    fn frames(
        &self,
        sim: &mut Simulation,
        mut stats: RunStats,
        first: usize,
        last: usize,
        progress: &Progress,
        wall_before: f64,
    ) -> Result<RunStats, RunError> {
        let started = Instant::now();
        let report = Reporter::start(progress, &sim.scene.name, first, last);
        for f in first..=last {
            let clock = Instant::now();
            if f > 0 {
                if let Err(e) = sim.advance_frame() {
                    // The frames written so far stay; stats.json says why the run stopped.
                    stats.error = Some(format!("frame {f}: {e}"));
                    stats.total_wall_s = wall_before + started.elapsed().as_secs_f64();
                    self.write_stats(&stats)?;
                    return Err(e.into());
                }
            }
            self.write_frame(sim, f)?;
            let mut fs = sim.measure(f);
            if self.adaptive {
                let r = std::mem::take(&mut sim.ws.remesh_stats);
                fs.remesh = Some(RemeshFrameStats { splits: r.splits, flips: r.flips, collapses: r.collapses });
            }
            if sim.ws.collisions.is_some() {
                let clock = Instant::now();
                let c = std::mem::take(&mut sim.ws.counters);
                fs.collision = Some(CollisionFrameStats {
                    contacts: c.contacts,
                    impacts: c.impacts,
                    impact_zones: c.impact_zones,
                    ccd_iterations: c.ccd_iterations,
                    ccd_cap_hits: c.cap_hits,
                    failed_zones: c.failed_zones,
                    penetrations: sim.penetrations(),
                });
                sim.ws.timers.since(Stage::PenetrationCheck, clock);
            }
            let check = Instant::now();
            let crossings = sim.crossings();
            (fs.crossings_self, fs.crossings_obstacle) = (crossings.cloth.len(), crossings.obstacle.len());
            sim.ws.timers.since(Stage::CrossingCheck, check);
            let faults = std::mem::take(&mut sim.ws.faults);
            fs.steps = faults.steps;
            fs.retries = faults.retries;
            fs.min_step = faults.min_step;
            fs.faults = faults.kinds;
            stats.retries += fs.retries;
            if f > 0 && (stats.min_step == 0.0 || fs.min_step < stats.min_step) {
                stats.min_step = fs.min_step;
            }
            fs.stage_s = sim.ws.timers.take();
            fs.wall_s = clock.elapsed().as_secs_f64();
            stats.frames.push(fs);
            for stage in sim.ws.timers.ran() {
                if !stats.stages.iter().any(|s| s == stage) {
                    stats.stages.push(stage.to_string());
                }
            }
            stats.total_wall_s = wall_before + started.elapsed().as_secs_f64();
            self.write_stats(&stats)?;
            self.checkpoint(sim, &stats, f, last, false)?;
            report.frame(f, fs_wall(&stats), sim.state.mesh.faces.len());
            if f < last && super::interrupt::requested() {
                report.finish();
                return self.interrupted(sim, stats, f, last);
            }
        }
        report.finish();
        Ok(stats)
    }

    /// Stops the run after frame `f` (a signal): its checkpoint, then stats.json saying so.
    fn interrupted(
        &self,
        sim: &mut Simulation,
        mut stats: RunStats,
        f: usize,
        last: usize,
    ) -> Result<RunStats, RunError> {
        let checkpoint = self.checkpoint(sim, &stats, f, last, true)?;
        stats.error = Some(format!("interrupted after frame {f} (SIGTERM or SIGINT)"));
        self.write_stats(&stats)?;
        Err(RunError::Interrupted { dir: self.dir.to_path_buf(), frame: f, last, checkpoint })
    }
}

/// The wall time of the last frame recorded.
fn fs_wall(stats: &RunStats) -> f64 {
    stats.frames.last().map_or(0.0, |f| f.wall_s)
}

/// A name reduced to characters safe in a file name.
fn file_safe(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}
