//! `viewcloth batch SHOTS.json`: many shots from one list, `jobs` at a time.
//!
//! Every shot's scene and camera are loaded and checked before the first simulation starts, so
//! a typo in shot 40 does not surface after 39 shots have run. Shots then run on `jobs` worker
//! threads, each with its own share of the cores (a run's result does not depend on its thread
//! count, so a shot's frames are the same as from `simulate`). A shot that fails is reported and
//! the others go on; the summary (`batch.json` in `out`) says which, rewritten after each shot.
//!
//! Runs are idempotent, so a requeued farm task or a rerun after a crash costs no finished
//! work: every shot is checkpointed (every 10 frames unless `checkpoint_every` says otherwise,
//! and when interrupted), a shot whose output holds its finished run (a checkpoint of this
//! scene at its last frame) is skipped, and one holding an unfinished run of this scene is
//! resumed from its checkpoint. An output directory holding another scene's run is refused
//! (without `force`) before anything runs.
//!
//! Format (paths relative to the shots file):
//! ```json
//! { "version": 1,
//!   "shots": [ { "scene": "scenes/a.json", "frames": 40, "out": "out/a", "mode": "view",
//!                "camera": "cameras/pan.json", "checkpoint_every": 10 } ] }
//! ```
//! Only `scene` is required; `out` defaults to `out/<scene stem>` beside the shots file, and two
//! shots may not share an output directory.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

use crate::error::InputError;
use crate::scene::RemeshMode;
use crate::shot::{self, ShotRequest};
use crate::sim::checkpoint;
use crate::sim::progress::Progress;
use crate::sim::{interrupt, resume, run_shot, CheckpointOptions, ResumeOptions, RunError, RunOptions};

/// Checkpoint interval of a shot that does not set one.
pub const DEFAULT_CHECKPOINT_EVERY: usize = 10;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BatchSpec {
    version: u32,
    shots: Vec<ShotSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShotSpec {
    scene: String,
    #[serde(default)]
    frames: Option<u64>,
    #[serde(default)]
    out: Option<String>,
    #[serde(default)]
    mode: Option<String>,
    #[serde(default)]
    camera: Option<String>,
    #[serde(default)]
    checkpoint_every: Option<u64>,
}

/// One validated shot, ready to run.
pub struct Shot {
    /// The scene file as the shots file names it (relative to the shots file's directory).
    pub scene_file: PathBuf,
    pub shot: shot::Shot,
    pub out: PathBuf,
    pub frames: Option<usize>,
    checkpoint_every: usize,
}

/// What a shot's output directory asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plan {
    /// It holds this shot's finished run.
    Skip,
    /// It holds an unfinished run of this shot, checkpointed at this frame.
    Resume(usize),
    /// Nothing of this shot (or a run of another version of its scene): start afresh.
    Fresh,
}

impl Shot {
    /// The shot's last frame.
    pub fn last_frame(&self) -> usize {
        self.frames.unwrap_or(self.shot.scene.frames)
    }

    /// Looks at the output directory: skip, resume or start afresh.
    pub fn plan(&self) -> Plan {
        let Ok((_, ck)) = checkpoint::latest(&self.out) else { return Plan::Fresh };
        let same = ck.run.scene_file == self.shot.scene_file
            && ck.run.fingerprint == checkpoint::scene_fingerprint(&self.shot.scene);
        let last = self.last_frame();
        match ck.state.frame {
            f if !same || f > last => Plan::Fresh,
            f if f == last && ck.run.frames == last => Plan::Skip,
            f if f == last => Plan::Fresh,
            f => Plan::Resume(f),
        }
    }
}

/// How one shot ended.
#[derive(Clone, Debug, Serialize)]
pub struct ShotResult {
    pub scene: PathBuf,
    pub out: PathBuf,
    pub ok: bool,
    /// `done`, `skipped` (already finished), `resumed` (finished from a checkpoint),
    /// `interrupted` (checkpointed; a rerun resumes it) or `failed`.
    pub status: &'static str,
    /// Frames written after frame 0.
    pub frames: usize,
    pub wall_s: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

fn err(file: &Path, location: String, msg: impl Into<String>) -> InputError {
    InputError { file: file.to_path_buf(), location: Some(location), msg: msg.into() }
}

/// Reads the shots file and loads and checks every shot's scene and camera, and (unless
/// `force`) that no output directory holds another scene's run.
pub fn load(path: &Path, force: bool) -> Result<Vec<Shot>, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError {
        file: path.to_path_buf(),
        location: None,
        msg: format!("cannot read shots file: {e}"),
    })?;
    let spec: BatchSpec = crate::io::json::parse(&text).map_err(|(loc, msg)| err(path, loc, msg))?;
    if spec.version != 1 {
        return Err(err(path, "version".into(), format!("expected 1, got {}", spec.version)));
    }
    if spec.shots.is_empty() {
        return Err(err(path, "shots".into(), "expected at least one shot"));
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let mut shots: Vec<Shot> = Vec::new();
    for (i, s) in spec.shots.into_iter().enumerate() {
        let at = |field: &str| format!("shots[{i}].{field}");
        let scene_file = base.join(&s.scene);
        let mode = match s.mode.as_deref() {
            None => None,
            Some(name) => Some(RemeshMode::parse(name).ok_or_else(|| {
                err(path, at("mode"), format!("expected \"uniform\", \"adaptive\" or \"view\", got \"{name}\""))
            })?),
        };
        let request = ShotRequest {
            scene: Some(scene_file.clone()),
            base: None,
            camera: s.camera.as_ref().map(|c| base.join(c)),
            mode,
            camera_implies_view: true,
        };
        let shot = shot::resolve(&request).map_err(|e| err(path, at(e.field.name()), e.error.to_string()))?;
        let positive = |v: Option<u64>, field: &str| match v {
            Some(0) => Err(err(path, at(field), "expected an integer ≥ 1, got 0")),
            v => Ok(v.map(|n| n as usize)),
        };
        let frames = positive(s.frames, "frames")?;
        let checkpoint_every = positive(s.checkpoint_every, "checkpoint_every")?.unwrap_or(DEFAULT_CHECKPOINT_EVERY);
        let out = base.join(s.out.unwrap_or_else(|| format!("out/{}", shot.stem)));
        if let Some(j) = shots.iter().position(|o| o.out == out) {
            return Err(err(path, at("out"), format!("{} is also shot {j}'s output directory", out.display())));
        }
        let shot = Shot { scene_file, shot, out, frames, checkpoint_every };
        if !force && shot.plan() == Plan::Fresh {
            crate::sim::check_output(&shot.out, &shot.shot.scene.name, shot.shot.scene_file.as_deref())
                .map_err(|e| err(path, at("out"), e.to_string()))?;
        }
        shots.push(shot);
    }
    Ok(shots)
}

/// Runs the shots, `jobs` at a time, each with `threads` worker threads and its progress
/// reported to `progress` (labelled `shot I`); `done` is called as each shot finishes, with
/// every result so far (in the shots' order; one call at a time). After a SIGTERM or SIGINT no
/// further shot starts. Results come back in the shots' order (shots not started are missing).
pub fn run_shots(
    shots: Vec<(usize, Shot)>,
    jobs: usize,
    threads: usize,
    progress: &Progress,
    done: &(dyn Fn(&ShotResult, &[Option<ShotResult>]) + Sync),
) -> Vec<ShotResult> {
    let n = shots.len();
    let queue: Mutex<Vec<(usize, (usize, Shot))>> = Mutex::new(shots.into_iter().enumerate().rev().collect());
    let results: Mutex<Vec<Option<ShotResult>>> = Mutex::new(vec![None; n]);
    let (queue, results_ref) = (&queue, &results);
    std::thread::scope(|s| {
        for _ in 0..jobs.clamp(1, n.max(1)) {
            // The queue's lock is taken and released in `pop`: held across a shot, it would
            // serialise the workers.
            let pop = || match interrupt::requested() {
                true => None,
                false => queue.lock().map(|mut q| q.pop()).unwrap_or(None),
            };
            s.spawn(move || {
                while let Some((k, (index, shot))) = pop() {
                    let mut p = progress.clone();
                    p.label = Some(format!("shot {index} ({})", shot.shot.stem));
                    let result = run_one(shot, threads, &p);
                    if let Ok(mut r) = results_ref.lock() {
                        r[k] = Some(result.clone());
                        done(&result, &r);
                    }
                }
            });
        }
    });
    results.into_inner().unwrap_or_default().into_iter().flatten().collect()
}

fn run_one(shot: Shot, threads: usize, progress: &Progress) -> ShotResult {
    let clock = std::time::Instant::now();
    let plan = shot.plan();
    let last = shot.last_frame();
    let Shot { scene_file, shot, out, frames, checkpoint_every } = shot;
    let result = |status, frames, error: Option<String>| ShotResult {
        scene: scene_file.clone(),
        out: out.clone(),
        ok: error.is_none(),
        status,
        frames,
        wall_s: clock.elapsed().as_secs_f64(),
        error,
    };
    if plan == Plan::Skip {
        return result("skipped", last, None);
    }
    let opts = RunOptions { out_dir: out.clone(), frames, quiet: true, export_obstacles: false, jitter: None };
    let ck = CheckpointOptions {
        every: checkpoint_every,
        scene_file: shot.scene_file.clone(),
        mode: shot.mode,
        camera_file: shot.camera_file.clone(),
    };
    let scene = shot.scene;
    let run = || match plan {
        Plan::Resume(_) => resume(&out, &ResumeOptions { frames: Some(last), progress: progress.clone() }),
        _ => crate::sim::clear_output(&out).and_then(|()| run_shot(scene, &opts, Some(&ck), progress)),
    };
    let outcome = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .map_err(|e| (false, e.to_string()))
        .and_then(|pool| pool.install(run).map_err(|e| (matches!(e, RunError::Interrupted { .. }), e.to_string())));
    let status = if matches!(plan, Plan::Resume(_)) { "resumed" } else { "done" };
    match outcome {
        Ok(stats) => result(status, stats.frames.len().saturating_sub(1), None),
        Err((true, e)) => result("interrupted", 0, Some(e)),
        Err((false, e)) => result("failed", 0, Some(e)),
    }
}
