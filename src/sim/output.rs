//! What a run writes, frame by frame: OBJ frames (and exported obstacles), USD samples, stats,
//! checkpoints; and the USD layer assembled from the samples when the run stops.
//!
//! Frames are counted two ways. The loop counts frames simulated since the run's start, preroll
//! included (`k`, what checkpoints and `SimState::frame` count); written frames are numbered
//! from the scene's `start_frame` (`Scene::frame_number`), in file names, stats.json and USD
//! time codes. Preroll frames are simulated and not written.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::io::obj::{frame_obj, obstacle_obj, ClothOut};
use crate::io::stats::{CollisionFrameStats, FrameStats, RemeshFrameStats, RunStats};
use crate::io::usd::{self, ObstacleFrame, StageInfo};
use crate::io::{write_atomic, write_atomic_with, OutputFormat};

use super::checkpoint::{self, RunRecord};
use super::progress::{Progress, Reporter};
use super::timers::Stage;
use super::{file_safe, io_err, RunError, Simulation};

/// The USD layer of a run, in its output directory.
pub const USD_FILE: &str = "cloth.usda";
/// The folder of the per-frame USD samples the layer is assembled from.
pub const USD_SAMPLES: &str = usd::SAMPLES_DIR;

/// The longest a running simulation leaves frames out of its stats.json (`Output::frames`).
pub const STATS_INTERVAL: std::time::Duration = std::time::Duration::from_secs(1);

/// Where and how a run writes.
pub(super) struct Output<'a> {
    pub dir: &'a Path,
    pub cloths: Vec<ClothOut>,
    pub digits: usize,
    pub export_obstacles: bool,
    pub format: OutputFormat,
    pub obj_velocities: bool,
    /// Present when checkpointing.
    pub record: Option<RunRecord>,
    pub adaptive: bool,
}

/// The samples file of frame `number` in `dir`.
pub fn usd_samples_path(dir: &Path, number: usize, digits: usize) -> PathBuf {
    dir.join(USD_SAMPLES).join(format!("frame_{number:0digits$}.txt"))
}

impl Output<'_> {
    fn frame_path(&self, number: usize) -> PathBuf {
        self.dir.join(format!("frame_{number:0w$}.obj", w = self.digits))
    }

    /// Readies the directory: the samples folder when writing USD.
    pub fn prepare(&self) -> Result<(), RunError> {
        std::fs::create_dir_all(self.dir).map_err(io_err(self.dir))?;
        if self.format.usd() {
            let samples = self.dir.join(USD_SAMPLES);
            std::fs::create_dir_all(&samples).map_err(io_err(&samples))?;
        }
        Ok(())
    }

    /// Writes frame `number`: the OBJ (and obstacles) and the USD samples, as asked.
    fn write_frame(&self, sim: &mut Simulation, number: usize) -> Result<(), RunError> {
        let clock = Instant::now();
        if self.format.obj() {
            let path = self.frame_path(number);
            let text = frame_obj(&sim.state.mesh, &self.cloths, self.obj_velocities);
            write_atomic(&path, text.as_bytes()).map_err(io_err(&path))?;
        }
        let mut obstacles = Vec::new();
        if self.export_obstacles {
            if let Some(world) = &sim.ws.collisions {
                for (body, obstacle) in world.bodies.iter().zip(&sim.scene.obstacles) {
                    let positions = body.positions_at(sim.state.time);
                    // An obstacle outside its window has no OBJ that frame (readers skip missing
                    // files) and is invisible in USD.
                    let present = body.present_at(sim.state.time);
                    if self.format.obj() && present {
                        let name = format!("obstacle_{}_{number:0w$}.obj", file_safe(&obstacle.name), w = self.digits);
                        let path = self.dir.join(name);
                        let text = obstacle_obj(&positions, body.triangles());
                        write_atomic(&path, text.as_bytes()).map_err(io_err(&path))?;
                    }
                    let velocities = (!body.is_static()).then(|| obstacle_velocities(body, sim));
                    let triangles = body.triangles();
                    let visible = body.has_window().then_some(present);
                    obstacles.push(ObstacleFrame { name: &obstacle.name, positions, velocities, triangles, visible });
                }
            }
        }
        if self.format.usd() {
            let path = usd_samples_path(self.dir, number, self.digits);
            let text = usd::frame_samples(&sim.state.mesh, &self.cloths, &obstacles);
            write_atomic(&path, text.as_bytes()).map_err(io_err(&path))?;
        }
        sim.ws.timers.since(Stage::Output, clock);
        Ok(())
    }

    /// Assembles the USD layer of the frames written up to frame `k` of the run (nothing when
    /// the run is not writing USD or has written no frame yet).
    fn write_usd(&self, sim: &Simulation, k: usize) -> Result<(), RunError> {
        let (scene, dir) = (&sim.scene, self.dir);
        let Some(end) = scene.frame_number(k).filter(|_| self.format.usd()) else { return Ok(()) };
        let frames: Vec<(usize, PathBuf)> =
            (scene.start_frame..=end).map(|n| (n, usd_samples_path(dir, n, self.digits))).collect();
        let info = StageInfo { scene: scene.name.clone(), fps: 1.0 / scene.frame_time, start: scene.start_frame, end };
        let path = dir.join(USD_FILE);
        write_atomic_with(&path, |f| usd::assemble(f, &info, &frames)).map_err(|e| match e {
            usd::AssembleError::Write(source) => RunError::Io { path: path.clone(), source },
            other => RunError::Output(other.to_string()),
        })
    }

    fn write_stats(&self, stats: &RunStats) -> Result<(), RunError> {
        write_stats(self.dir, stats)
    }

    /// Whether frame `k` of a run ending at `last` gets a checkpoint (every `every` frames and
    /// at the last).
    fn checkpoint_due(&self, k: usize, last: usize) -> bool {
        self.record.as_ref().is_some_and(|r| r.every > 0 && k > 0 && (k.is_multiple_of(r.every) || k == last))
    }

    /// Writes the checkpoint of frame `k` when due (`checkpoint_due`) or `now`, then removes
    /// all but it and the one before it. Returns its path when written.
    fn checkpoint(
        &self,
        sim: &mut Simulation,
        stats: &RunStats,
        k: usize,
        last: usize,
        now: bool,
    ) -> Result<Option<PathBuf>, RunError> {
        let Some(record) = &self.record else { return Ok(None) };
        if !self.checkpoint_due(k, last) && !now {
            return Ok(None);
        }
        let clock = Instant::now();
        let path = checkpoint::checkpoint_path(self.dir, k, self.digits);
        write_atomic(&path, &checkpoint::encode(record, &sim.state, stats)).map_err(io_err(&path))?;
        let old = checkpoint::list(self.dir).map_err(io_err(self.dir))?;
        for (_, p) in old.iter().filter(|(j, _)| *j < k).skip(1) {
            let _ = std::fs::remove_file(p);
        }
        sim.ws.timers.since(Stage::Checkpoint, clock);
        Ok(Some(path))
    }

    /// Frames `first..=last` of the run (counted from its start, preroll included; frame 0 is
    /// the initial state, not simulated); `wall_before` is the wall time of earlier sessions.
    pub fn frames(
        &self,
        sim: &mut Simulation,
        mut stats: RunStats,
        first: usize,
        last: usize,
        progress: &Progress,
        wall_before: f64,
    ) -> Result<RunStats, RunError> {
        let started = Instant::now();
        let mut stats_written: Option<Instant> = None;
        let scene = &sim.scene;
        let report = Reporter::start(progress, &scene.name, (first, last), scene.start_frame, scene.preroll_frames);
        for k in first..=last {
            let clock = Instant::now();
            if k > 0 {
                if let Err(e) = sim.advance_frame() {
                    // The frames written so far stay; stats.json says why the run stopped.
                    let at = sim.scene.frame_number(k).map_or(format!("preroll frame {k}"), |n| format!("frame {n}"));
                    stats.error = Some(format!("{at}: {e}"));
                    stats.total_wall_s = wall_before + started.elapsed().as_secs_f64();
                    self.write_stats(&stats)?;
                    self.write_usd(sim, k - 1)?;
                    return Err(e.into());
                }
            }
            let number = sim.scene.frame_number(k);
            if let Some(n) = number {
                self.write_frame(sim, n)?;
            }
            let mut fs = frame_stats(sim, number.unwrap_or(0), self.adaptive);
            fs.wall_s = clock.elapsed().as_secs_f64();
            record(&mut stats, fs, k, number.is_some(), sim.ws.timers.ran());
            stats.total_wall_s = wall_before + started.elapsed().as_secs_f64();
            // stats.json holds every frame so far, so rewriting it each frame costs the run's
            // length squared: it is rewritten at the first and last frame, before each
            // checkpoint (frame → stats.json → checkpoint), and otherwise at most every
            // `STATS_INTERVAL`.
            let due = stats_written.is_none_or(|t| t.elapsed() >= STATS_INTERVAL)
                || k == last
                || self.checkpoint_due(k, last);
            if due {
                self.write_stats(&stats)?;
                stats_written = Some(Instant::now());
            }
            self.checkpoint(sim, &stats, k, last, false)?;
            report.frame(k, fs_wall(&stats), sim.state.mesh.faces.len());
            if k < last && super::interrupt::requested() {
                report.finish();
                return self.interrupted(sim, stats, k, last);
            }
        }
        report.finish();
        self.write_usd(sim, last)?;
        Ok(stats)
    }

    /// Stops the run after frame `k` (a signal): its checkpoint, then stats.json saying so,
    /// then the USD layer of the frames so far.
    fn interrupted(
        &self,
        sim: &mut Simulation,
        mut stats: RunStats,
        k: usize,
        last: usize,
    ) -> Result<RunStats, RunError> {
        let checkpoint = self.checkpoint(sim, &stats, k, last, true)?;
        let scene = &sim.scene;
        let at = match (scene.frame_number(k), scene.frame_number(last)) {
            (Some(n), Some(end)) => format!("frame {n} of {}..={end}", scene.start_frame),
            _ => format!("preroll frame {k} of {}", scene.preroll_frames),
        };
        stats.error = Some(format!("interrupted after {at} (SIGTERM or SIGINT)"));
        self.write_stats(&stats)?;
        self.write_usd(sim, k)?;
        Err(RunError::Interrupted { dir: self.dir.to_path_buf(), at, checkpoint })
    }
}

/// The measurements and counters of the frame just simulated, as frame `number`.
fn frame_stats(sim: &mut Simulation, number: usize, adaptive: bool) -> FrameStats {
    let mut fs = sim.measure(number);
    if adaptive {
        let r = std::mem::take(&mut sim.ws.remesh_stats);
        let pop = std::mem::take(&mut sim.ws.pop);
        fs.remesh = Some(RemeshFrameStats {
            splits: r.splits,
            flips: r.flips,
            collapses: r.collapses,
            pop_iterations: pop.iterations,
            pop_max_move: pop.max_move,
        });
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
            flung_reverted: c.flung_reverted,
            spread_pushes: c.spread_pushes,
            failed_zones: c.failed_zones,
            rigid_zones: c.rigid_zones,
            yielded_nodes: c.yielded_nodes,
            pinched_nodes: c.pinched_nodes,
            untangled_nodes: c.untangled_nodes,
            penetrations: sim.penetrations(),
            sticking: c.sticking,
            sliding: c.sliding,
            friction_resolves: c.friction_resolves,
            friction_refactors: c.friction_refactors,
            tail_refactors: c.tail_refactors,
            friction_unconverged: c.friction_unconverged,
        });
        sim.ws.timers.since(Stage::PenetrationCheck, clock);
    }
    let check = Instant::now();
    let crossings = sim.crossings();
    (fs.crossings_self, fs.crossings_obstacle) = (crossings.cloth.len(), crossings.obstacle.len());
    sim.ws.timers.since(Stage::CrossingCheck, check);
    sim.constraint_stats(&mut fs);
    fs.view = sim.view_stats();
    let faults = std::mem::take(&mut sim.ws.faults);
    fs.steps = faults.steps;
    fs.retries = faults.retries;
    fs.min_step = faults.min_step;
    fs.faults = faults.kinds;
    fs.stage_s = sim.ws.timers.take();
    fs
}

/// Adds frame `k`'s stats to the run's: its retries and smallest step to the totals (preroll
/// frames included), the stages that `ran` so far, and the frame itself when it is `listed`
/// (written; a preroll frame is not).
fn record<'a>(stats: &mut RunStats, fs: FrameStats, k: usize, listed: bool, ran: impl Iterator<Item = &'a str>) {
    stats.retries += fs.retries;
    if k > 0 && (stats.min_step == 0.0 || fs.min_step < stats.min_step) {
        stats.min_step = fs.min_step;
    }
    if listed {
        stats.frames.push(fs);
    }
    for stage in ran {
        if !stats.stages.iter().any(|s| s == stage) {
            stats.stages.push(stage.to_string());
        }
    }
}

/// Writes `dir/stats.json` (atomically: it is valid at any instant).
fn write_stats(dir: &Path, stats: &RunStats) -> Result<(), RunError> {
    let path = dir.join("stats.json");
    let json = serde_json::to_vec_pretty(stats).map_err(|e| RunError::Io { path: path.clone(), source: e.into() })?;
    write_atomic(&path, &json).map_err(io_err(&path))
}

/// `stats.json` of a run whose frames its caller steps (`upsample trace` steps two in lockstep):
/// the frame stats, totals and file `simulate` writes (`Output::frames`), rewritten per frame.
/// Its `total_wall_s` is the sum of its frames' wall times (the caller's other work apart).
pub struct StatsLog {
    dir: PathBuf,
    stats: RunStats,
    adaptive: bool,
}

impl StatsLog {
    /// The log of `sim`'s run into `dir`, as `mode` (`simulate` says `uniform`, `adaptive` or
    /// `view`).
    pub fn new(dir: &Path, sim: &Simulation, mode: &str) -> StatsLog {
        let stats = RunStats { scene: sim.scene.name.clone(), mode: mode.into(), ..Default::default() };
        StatsLog { dir: dir.to_path_buf(), stats, adaptive: super::run::is_adaptive(&sim.scene) }
    }

    /// Records frame `k` of the run (counted from its start, preroll included), which took
    /// `wall_s` of its own (measuring it is added, as `simulate`'s frames include it), plus the
    /// caller's `extra` stages (name, seconds), and rewrites stats.json.
    pub fn frame(
        &mut self,
        sim: &mut Simulation,
        k: usize,
        wall_s: f64,
        extra: &[(&str, f64)],
    ) -> Result<(), RunError> {
        let (number, clock) = (sim.scene.frame_number(k), Instant::now());
        let mut fs = frame_stats(sim, number.unwrap_or(0), self.adaptive);
        fs.wall_s = wall_s + clock.elapsed().as_secs_f64();
        self.stats.total_wall_s += fs.wall_s;
        for &(stage, t) in extra {
            *fs.stage_s.entry(stage.to_string()).or_insert(0.0) += t;
        }
        let mut ran: Vec<&str> = sim.ws.timers.ran().collect();
        ran.extend(extra.iter().map(|e| e.0));
        record(&mut self.stats, fs, k, number.is_some(), ran.into_iter());
        write_stats(&self.dir, &self.stats)
    }

    /// Ends the log with why the run stopped (as `simulate` does when a frame fails).
    pub fn fail(&mut self, why: String) -> Result<(), RunError> {
        self.stats.error = Some(why);
        write_stats(&self.dir, &self.stats)
    }
}

/// An obstacle's vertex velocities at the frame just simulated: its displacement over the last
/// step, (x(t) − x(t − h)) / h. The scripted motion has no analytic derivative in the code, and
/// this is the velocity the step gave it (collision handling, `ObstacleBody::velocities`), as
/// the cloth's written velocities are its end-of-step ones, so cloth carried by an obstacle
/// moves with it in a renderer's motion blur.
fn obstacle_velocities(body: &crate::collision::obstacle::ObstacleBody, sim: &Simulation) -> Vec<crate::math::Vec3> {
    let (t, h) = (sim.state.time, sim.scene.time_step());
    body.velocities(t - h, t)
}

/// The wall time of the last frame recorded.
fn fs_wall(stats: &RunStats) -> f64 {
    stats.frames.last().map_or(0.0, |f| f.wall_s)
}
