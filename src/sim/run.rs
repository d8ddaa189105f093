//! Running a shot: frames out to OBJ, stats to JSON, checkpoints, progress to the terminal.
//! Every file is written to a temporary name and renamed into place (`io::write_atomic`), in
//! the order frame → stats.json → checkpoint, so a run killed at any instant leaves complete
//! files only, and a checkpoint never refers to a frame that is not on disk.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::InputError;
use crate::io::obj::{frame_obj, obstacle_obj};
use crate::io::stats::{CollisionFrameStats, RemeshFrameStats, RunStats};
use crate::io::write_atomic;
use crate::scene::{RemeshMode, Scene};
use crate::shot::{self, ShotRequest};

use super::checkpoint::{self, CheckpointError, RunRecord};
use super::timers::Stage;
use super::{SimError, Simulation};

pub struct RunOptions {
    pub out_dir: PathBuf,
    /// Overrides the scene's frame count.
    pub frames: Option<usize>,
    pub quiet: bool,
    /// Also write each obstacle's world-space mesh per frame (`obstacle_<name>_NNNN.obj`).
    pub export_obstacles: bool,
}

/// Checkpointing of a run: every `every` frames (and at the last), with what `resume` needs to
/// reload the scene.
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
    let stats = RunStats { scene: sim.scene.name.clone(), mode: mode.into(), ..Default::default() };
    let out = Output { dir: &opts.out_dir, names, digits, export_obstacles: opts.export_obstacles, record, adaptive };
    out.frames(&mut sim, stats, 0, frames, opts.quiet, 0.0)
}

/// Options of `viewcloth resume`.
pub struct ResumeOptions {
    /// New last frame (default: the run's own).
    pub frames: Option<usize>,
    pub quiet: bool,
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
    out.frames(&mut sim, stats, first + 1, frames, opts.quiet, wall_before)
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

    /// Writes the checkpoint of frame `f` when due (every `every` frames and at the last),
    /// then removes all but it and the one before it.
    fn checkpoint(&self, sim: &mut Simulation, stats: &RunStats, f: usize, last: usize) -> Result<(), RunError> {
        let Some(record) = &self.record else { return Ok(()) };
        if f == 0 || (f % record.every != 0 && f != last) {
            return Ok(());
        }
        let clock = Instant::now();
        let path = checkpoint::checkpoint_path(self.dir, f, self.digits);
        write_atomic(&path, &checkpoint::encode(record, &sim.state, stats)).map_err(io_err(&path))?;
        let old = checkpoint::list(self.dir).map_err(io_err(self.dir))?;
        for (_, p) in old.iter().filter(|(k, _)| *k < f).skip(1) {
            let _ = std::fs::remove_file(p);
        }
        sim.ws.timers.since(Stage::Checkpoint, clock);
        Ok(())
    }

    /// Frames `first..=last` (frame 0 is the initial state, not simulated); `wall_before` is
    /// the wall time of earlier sessions of the run.
    fn frames(
        &self,
        sim: &mut Simulation,
        mut stats: RunStats,
        first: usize,
        last: usize,
        quiet: bool,
        wall_before: f64,
    ) -> Result<RunStats, RunError> {
        let started = Instant::now();
        let progress = (!quiet && std::io::stdout().is_terminal()).then(|| {
            let bar = indicatif::ProgressBar::new(last as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{msg} [{bar:40}] {pos}/{len} frames, {elapsed} elapsed, ETA {eta}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar.set_message(sim.scene.name.clone());
            bar.set_position(first as u64);
            bar
        });
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
            self.checkpoint(sim, &stats, f, last)?;
            if let Some(bar) = &progress {
                bar.set_position(f as u64);
            }
        }
        if let Some(bar) = progress {
            bar.finish();
        }
        Ok(stats)
    }
}

/// A name reduced to characters safe in a file name.
fn file_safe(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}
