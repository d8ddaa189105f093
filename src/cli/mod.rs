//! The commands behind `viewcloth`'s subcommands. Each returns `Result<(), CliError>`; the binary
//! prints an error as one line (`error: …`) and exits with its code: 2 for bad input (scene,
//! mesh, camera, checkpoint, command line), 1 for a simulation or output failure, 75 for a run
//! stopped by SIGTERM or SIGINT after checkpointing (resumable).

pub mod args;

use std::path::{Path, PathBuf};

use crate::camera::Camera;
use crate::collision::crossings::{find_crossings, Soup};
use crate::compare::{compare, markdown, CompareOptions, UpsampleOptions};
use crate::error::InputError;
use crate::io::OutputFormat;
use crate::math::Vec3;
use crate::render::{render_run, run_dir, Colouring, RenderOptions, RunFiles};
use crate::scene::{self, RemeshMode};
use crate::shot::{self, ShotError, ShotRequest};
use crate::sim::progress::{Progress, ProgressMode};
use crate::sim::SimError;
use crate::sim::{
    claim_output, interrupt, resume, run_shot, CheckpointOptions, Jitter, ResumeOptions, RunError, RunOptions,
};
use args::{
    BatchArgs, CompareArgs, CrossingsArgs, RenderArgs, ResampleArgs, ResumeArgs, SimulateArgs, UpsampleCommand,
};

/// Exit code for bad input (scene, mesh, command line).
pub const EXIT_INPUT: u8 = 2;
/// Exit code for a simulation or output failure.
pub const EXIT_RUN: u8 = 1;
/// Exit code for a run stopped by SIGTERM or SIGINT at a checkpoint: `resume` (or a rerun of
/// `batch`) continues it. 75 is `EX_TEMPFAIL` of sysexits.h: try again later.
pub const EXIT_INTERRUPTED: u8 = 75;

/// A failed command: its message (one line per problem) and exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad input: exit 2.
    #[error("{0}")]
    Input(String),
    /// A simulation or output failure: exit 1.
    #[error("{0}")]
    Run(String),
    /// Stopped by a signal after checkpointing: exit 75.
    #[error("{0}")]
    Interrupted(String),
}

impl CliError {
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Input(_) => EXIT_INPUT,
            CliError::Run(_) => EXIT_RUN,
            CliError::Interrupted(_) => EXIT_INTERRUPTED,
        }
    }
}

impl From<InputError> for CliError {
    fn from(e: InputError) -> Self {
        CliError::Input(e.to_string())
    }
}

impl From<ShotError> for CliError {
    fn from(e: ShotError) -> Self {
        CliError::Input(e.to_string())
    }
}

/// Bad input (including an unusable initial state or checkpoint) is 2, a simulation or output
/// failure 1.
impl From<RunError> for CliError {
    fn from(e: RunError) -> Self {
        match e {
            RunError::Sim(SimError::Input(_)) | RunError::Input(_) | RunError::Checkpoint(_) => {
                CliError::Input(e.to_string())
            }
            RunError::Interrupted { .. } => CliError::Interrupted(e.to_string()),
            _ => CliError::Run(e.to_string()),
        }
    }
}

/// The cores granted by Slurm (`SLURM_CPUS_PER_TASK`): under `task/none` the process sees every
/// core of the node, so `available_parallelism` would oversubscribe it. A value that is not a
/// positive integer is ignored with a warning.
fn slurm_cpus() -> Option<u64> {
    let text = std::env::var("SLURM_CPUS_PER_TASK").ok()?;
    match text.trim().parse::<u64>() {
        Ok(n) if (1..=1024).contains(&n) => Some(n),
        _ => {
            eprintln!("warning: SLURM_CPUS_PER_TASK=\"{text}\" is not a core count in 1..=1024; ignored");
            None
        }
    }
}

/// The cores a run may use: `SLURM_CPUS_PER_TASK` when set, else all.
fn cores() -> usize {
    slurm_cpus().map(|n| n as usize).unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// Handles SIGTERM and SIGINT as "checkpoint and stop" (exit 75).
fn install_interrupt() -> Result<(), CliError> {
    interrupt::install().map_err(|e| CliError::Run(format!("cannot install the SIGTERM/SIGINT handlers: {e}")))
}

/// Runs a command on a worker of its own thread pool (`--threads`, else `SLURM_CPUS_PER_TASK`,
/// else every core). The simulation's parallel loops then start from a pool thread: from the
/// main thread each one is handed to the pool and waited for, a wake-up and a sleep per loop
/// that cost small meshes a quarter of their run time (ARCSim's square.json, issue 17 item 4).
/// Worker stacks are as large as a main thread's.
pub fn on_workers<T>(threads: Option<u64>, run: impl FnOnce() -> Result<T, CliError> + Send) -> Result<T, CliError>
where
    T: Send,
{
    let n = threads.or_else(slurm_cpus).map_or(0, |n| n as usize);
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .stack_size(WORKER_STACK)
        .build()
        .map_err(|e| CliError::Input(format!("--threads: cannot start {n} threads: {e}")))?
        .install(run)
}

/// Stack of each worker thread (bytes): the main thread's usual 8 MiB.
const WORKER_STACK: usize = 8 << 20;

fn print_warnings(file: &Path, warnings: &[String]) {
    for w in warnings {
        eprintln!("warning: {}: {w}", file.display());
    }
}

pub fn simulate(args: SimulateArgs) -> Result<(), CliError> {
    let SimulateArgs {
        scene,
        frames,
        out,
        threads: _,
        quiet,
        progress,
        force,
        export_obstacles,
        format,
        obj_velocities,
        mode,
        camera,
        checkpoint_every,
        base,
        jitter_seed,
        jitter,
    } = args;
    let jitter = jitter_seed.map(|seed| Jitter { seed, amplitude: jitter.unwrap_or(Jitter::AMPLITUDE) });
    // clap admits only RemeshMode::NAMES.
    let mode = mode.as_deref().and_then(RemeshMode::parse);
    let request = ShotRequest { scene: scene.clone(), base, camera, mode, camera_implies_view: true };
    let shot = shot::resolve(&request)?;
    if let Some(path) = &scene {
        print_warnings(path, &shot.warnings);
    }
    let out_dir = out.unwrap_or_else(|| Path::new("out").join(&shot.stem));
    // clap admits only OutputFormat::NAMES.
    let format = format.as_deref().and_then(OutputFormat::parse).unwrap_or_default();
    let opts = RunOptions {
        out_dir: out_dir.clone(),
        frames: frames.map(|f| f as usize),
        quiet,
        // The built-in shot exports its obstacles, for its preview.
        export_obstacles: export_obstacles || scene.is_none(),
        format,
        obj_velocities,
        jitter,
    };
    // Without --checkpoint-every, a checkpoint is written only when a signal stops the run.
    let ck = CheckpointOptions {
        every: checkpoint_every.unwrap_or(0) as usize,
        scene_file: shot.scene_file.clone(),
        mode: shot.mode,
        camera_file: shot.camera_file.clone(),
    };
    claim_output(&out_dir, &shot.scene.name, shot.scene_file.as_deref(), force)?;
    install_interrupt()?;
    let progress = Progress::new(ProgressMode::choose(progress.as_deref(), quiet));
    let camera = shot.scene.camera.clone();
    let stats = run_shot(shot.scene, &opts, Some(&ck), &progress)?;
    if !quiet {
        let frames = stats.frames.len().saturating_sub(1);
        println!("{}: {frames} frames in {:.2} s → {}", stats.scene, stats.total_wall_s, out_dir.display());
    }
    // The built-in shot ends with a preview from its camera (OBJ frames only: USD is not read back).
    if let (None, Some(camera), true) = (&scene, camera, format != OutputFormat::Usd) {
        let numbers = || stats.frames.iter().map(|f| f.frame);
        let (first, last) = (numbers().min().unwrap_or(0), numbers().max().unwrap_or(0));
        let images = shot::write_preview(&out_dir, &camera, first, last).map_err(|e| CliError::Run(e.to_string()))?;
        if !quiet {
            let names: Vec<String> =
                images.iter().filter_map(|p| p.file_name()).map(|n| n.to_string_lossy().into()).collect();
            println!(
                "preview ({} frames from the shot camera): {} in {}",
                images.len(),
                names.join(", "),
                out_dir.display()
            );
        }
    }
    Ok(())
}

pub fn resume_run(args: ResumeArgs) -> Result<(), CliError> {
    install_interrupt()?;
    let progress = Progress::new(ProgressMode::choose(args.progress.as_deref(), args.quiet));
    let format = args.format.as_deref().and_then(OutputFormat::parse);
    let opts = ResumeOptions { frames: args.frames.map(|f| f as usize), format, progress };
    let stats = resume(&args.dir, &opts)?;
    if !args.quiet {
        let resumed = stats.resumed_at.last().copied().unwrap_or(0);
        let frames = stats.frames.len().saturating_sub(1);
        println!("{}: resumed at frame {resumed}, {frames} frames in all → {}", stats.scene, args.dir.display());
    }
    Ok(())
}

/// Validates each file (scene, ARCSim conf or camera); every bad one is reported.
pub fn check(files: &[PathBuf], base: Option<&Path>) -> Result<(), CliError> {
    let mut errors = Vec::new();
    for f in files {
        let checked = if is_camera_file(f) {
            Camera::load(f).map(|_| ())
        } else {
            scene::load_path(f, base).map(|loaded| print_warnings(f, &loaded.warnings))
        };
        match checked {
            Ok(()) => println!("{}: ok", f.display()),
            Err(e) => errors.push(e.to_string()),
        }
    }
    match errors.is_empty() {
        true => Ok(()),
        false => Err(CliError::Input(errors.join("\nerror: "))),
    }
}

/// A camera file (`cameras/*.json`): a JSON object with `keys` and no `cloths`.
fn is_camera_file(path: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else { return false };
    let Ok(serde_json::Value::Object(m)) = serde_json::from_str::<serde_json::Value>(&text) else { return false };
    m.contains_key("keys") && !m.contains_key("cloths")
}

pub fn compare_modes(args: CompareArgs) -> Result<(), CliError> {
    let (width, height) = parse_size(&args.size)?;
    let request = ShotRequest {
        scene: Some(args.scene.clone()),
        camera: args.camera.clone(),
        // compare runs the modes it is given itself.
        camera_implies_view: false,
        ..Default::default()
    };
    let shot = shot::resolve(&request)?;
    print_warnings(&args.scene, &shot.warnings);
    let upsample = match (&args.upsample, &args.coarse) {
        (Some(model), Some(coarse)) => {
            let loaded = scene::load_path(coarse, None).map_err(|e| CliError::Input(e.to_string()))?;
            print_warnings(coarse, &loaded.warnings);
            Some(UpsampleOptions { model: model.clone(), coarse: loaded.scene })
        }
        _ => None,
    };
    let opts = CompareOptions {
        out_dir: args.out.unwrap_or_else(|| Path::new("out").join(format!("{}-compare", shot.stem))),
        frames: args.frames.map(|f| f as usize),
        modes: args.modes.iter().filter_map(|m| RemeshMode::parse(m)).collect(),
        reference: args.reference,
        floor_runs: if args.no_floor { 0 } else { args.floor_runs as usize },
        sweep: args.sweep,
        width,
        height,
        every: args.every as usize,
        quiet: args.quiet,
        progress: ProgressMode::choose(args.progress.as_deref(), args.quiet),
        upsample,
    };
    let report = compare(shot.scene, &opts)?;
    print!("{}", markdown(&report));
    Ok(())
}

/// `--size WIDTHxHEIGHT`, each in 16..=8192.
fn parse_size(text: &str) -> Result<(usize, usize), CliError> {
    let size = text.split_once('x').and_then(|(w, h)| Some((w.parse::<usize>().ok()?, h.parse::<usize>().ok()?)));
    size.filter(|&(w, h)| (16..=8192).contains(&w) && (16..=8192).contains(&h))
        .ok_or_else(|| CliError::Input(format!("--size: expected WIDTHxHEIGHT with each in 16..=8192, got \"{text}\"")))
}

/// `--frames A..B` (both included, A ≤ B).
fn parse_frames(text: &str) -> Result<(usize, usize), CliError> {
    let range = text.split_once("..").and_then(|(a, b)| Some((a.parse::<usize>().ok()?, b.parse::<usize>().ok()?)));
    range.filter(|(a, b)| a <= b).ok_or_else(|| {
        CliError::Input(format!("--frames: expected A..B, frame numbers with A ≤ B (both included), got \"{text}\""))
    })
}

pub fn render(args: RenderArgs) -> Result<(), CliError> {
    let (width, height) = parse_size(&args.size)?;
    let frames = args.frames.as_deref().map(parse_frames).transpose()?;
    let camera = Camera::load(&args.camera)?;
    let colouring = if args.color == "view" { Colouring::View } else { Colouring::Shade };
    let progress = ProgressMode::choose(args.progress.as_deref(), false);
    let opts = RenderOptions { width, height, frames, every: args.every as usize, colouring, progress };
    let n = render_run(&args.dir, &camera, &opts).map_err(|e| match e.is_input() {
        true => CliError::Input(e.to_string()),
        false => CliError::Run(e.to_string()),
    })?;
    println!("{n} images → {}", args.dir.join("view_*.png").display());
    Ok(())
}

pub fn resample(args: ResampleArgs) -> Result<(), CliError> {
    use crate::resample::{resample, ResampleError, Target};
    let target = match args.auto {
        true => Target::Auto,
        false => Target::Meshes(args.mesh),
    };
    let r = resample(&args.dir, &target, &args.out).map_err(|e| match e {
        ResampleError::Input(e) => CliError::Input(e.to_string()),
        other => CliError::Run(other.to_string()),
    })?;
    let worst = r.frames.iter().map(|f| f.max).fold(0.0, f64::max);
    println!(
        "{} frames resampled onto {} faces (the run: mean {:.0}, max {}); error max {worst:.3e} m → {}",
        r.frames.len(),
        r.faces,
        r.run_mean_faces,
        r.run_max_faces,
        args.out.display()
    );
    Ok(())
}

/// `viewcloth crossings`: per frame, the crossing pairs counted from the run's files alone
/// (`collision::crossings`, as the run counts them into stats.json), one tab-separated line
/// each; an error when any frame has one.
pub fn crossings(args: CrossingsArgs) -> Result<(), CliError> {
    let dir = args.dir.as_path();
    let mut frames = run_dir::frame_numbers(dir)?;
    if let Some((a, b)) = args.frames.as_deref().map(parse_frames).transpose()? {
        frames.retain(|f| (a..=b).contains(f));
        if frames.is_empty() {
            return Err(CliError::Input(format!("{}: no frames in {a}..{b}", dir.display())));
        }
    }
    let (first, last) = (frames[0], frames[frames.len() - 1]);
    let files = RunFiles::scan(dir, first, last)?;
    if !args.quiet {
        println!("frame\tcrossings_self\tcrossings_obstacle");
    }
    let mut bad = Vec::new();
    for &f in &frames {
        let m = files.load(f)?;
        let (cloth, obstacles) = m.triangles.split_at(m.cloth_triangles);
        let found = find_crossings(Soup { x: &m.positions, tris: cloth }, Soup { x: &m.positions, tris: obstacles });
        let (s, o) = (found.cloth.len(), found.obstacle.len());
        if s + o > 0 {
            bad.push(f);
        }
        if !args.quiet || s + o > 0 {
            println!("{f}\t{s}\t{o}");
        }
        let found_pairs = found
            .cloth
            .iter()
            .map(|p| ("self", p, 0))
            .chain(found.obstacle.iter().map(|p| ("obstacle", p, cloth.len())));
        for (kind, &(a, b), offset) in found_pairs.filter(|_| args.pairs) {
            let c = cloth[a].iter().map(|&i| m.positions[i]).sum::<Vec3>() / 3.0;
            println!("pair\t{f}\t{kind}\t{a}\t{}\t{:.6} {:.6} {:.6}", b + offset, c.x, c.y, c.z);
        }
    }
    let what = match files.has_obstacles() {
        true => "cloth–cloth and cloth–obstacle",
        false => "cloth–cloth only: no obstacle files (the scene has none, or simulate ran without --export-obstacles)",
    };
    match bad.len() {
        0 => {
            println!("{}: {} frames, no crossings ({what})", dir.display(), frames.len());
            Ok(())
        }
        n => Err(CliError::Run(format!(
            "{}: {n} of {} frames have crossing triangle pairs (first: frame {}; {what})",
            dir.display(),
            frames.len(),
            bad[0]
        ))),
    }
}

/// The shot `--shot N` or `--shot-from-env VAR` picks, checked against the list's length.
fn chosen_shot(args: &BatchArgs, n: usize) -> Result<Option<usize>, CliError> {
    let (index, given) = match (&args.shot, &args.shot_from_env) {
        (Some(i), _) => (*i, format!("--shot {i}")),
        (None, Some(var)) => {
            let text = std::env::var(var).map_err(|_| {
                CliError::Input(format!("--shot-from-env {var}: {var} is not set (expected a shot index)"))
            })?;
            let i = text.trim().parse::<u64>().map_err(|_| {
                CliError::Input(format!("--shot-from-env {var}: expected a shot index (0, 1, …), got \"{text}\""))
            })?;
            (i, format!("--shot-from-env {var} ({var}={i})"))
        }
        (None, None) => return Ok(None),
    };
    match usize::try_from(index).ok().filter(|&i| i < n) {
        Some(i) => Ok(Some(i)),
        None => {
            Err(CliError::Input(format!("{given}: {} has {n} shots, numbered 0 to {}", args.shots.display(), n - 1)))
        }
    }
}

pub fn batch(args: BatchArgs) -> Result<(), CliError> {
    let file = args.shots.as_path();
    let format = args.format.as_deref().and_then(OutputFormat::parse).unwrap_or_default();
    let shots = crate::batch::load(file, args.force, format)?;
    let n = shots.len();
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shots".into());
    if args.emit.is_some() {
        let dir = args.out.clone().unwrap_or_else(|| Path::new("out").join(format!("{stem}-slurm")));
        let cpus = args.threads.or_else(slurm_cpus).unwrap_or(crate::farm::DEFAULT_CPUS_PER_TASK);
        let emitted = crate::farm::emit_slurm(file, &shots, &dir, cpus, format).map_err(CliError::Run)?;
        println!(
            "{} ({n} array tasks) and {} → sbatch {}",
            emitted.script.display(),
            emitted.commands.display(),
            emitted.script.display()
        );
        return Ok(());
    }
    let chosen = chosen_shot(&args, n)?;
    let jobs = args.jobs as usize;
    let threads = args.threads.map(|t| t as usize).unwrap_or((cores() / jobs).max(1));
    let summary = args.summary.clone().unwrap_or_else(|| match chosen {
        Some(i) => Path::new("out").join(format!("{stem}.shot{i}.batch.json")),
        None => Path::new("out").join(format!("{stem}.batch.json")),
    });
    let shots: Vec<(usize, crate::batch::Shot)> =
        shots.into_iter().enumerate().filter(|(i, _)| chosen.is_none_or(|c| c == *i)).collect();
    let listed = shots.len();
    install_interrupt()?;
    let quiet = args.quiet;
    let mode = ProgressMode::choose(args.progress.as_deref(), quiet);
    let bars = (mode == ProgressMode::Bar).then(indicatif::MultiProgress::new);
    let progress = Progress { mode, label: None, bars };
    let write_error: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);
    let done = |r: &crate::batch::ShotResult, all: &[Option<crate::batch::ShotResult>]| {
        if !quiet {
            match &r.error {
                None => println!(
                    "{}: {}: {} frames in {:.1} s → {}",
                    r.status,
                    r.scene.display(),
                    r.frames,
                    r.wall_s,
                    r.out.display()
                ),
                Some(e) => println!("{}: {}: {e}", r.status, r.scene.display()),
            }
        }
        // Rewritten after every shot, so a killed batch leaves a summary of what finished.
        if let Err(e) = write_summary(&summary, all) {
            if let Ok(mut w) = write_error.lock() {
                w.get_or_insert(e);
            }
        }
    };
    let results = crate::batch::run_shots(shots, jobs, threads, &progress, &done);
    // Shots start in the list's order, so those a signal kept from starting are the last ones.
    let mut all: Vec<_> = results.iter().cloned().map(Some).collect();
    all.resize(listed, None);
    write_summary(&summary, &all).map_err(CliError::Run)?;
    if let Some(e) = write_error.into_inner().ok().flatten() {
        return Err(CliError::Run(e));
    }
    let failed = results.iter().filter(|r| r.status == "failed").count();
    let interrupted = listed - results.len() + results.iter().filter(|r| r.status == "interrupted").count();
    if !quiet {
        println!("{} of {listed} shots ok; summary → {}", results.iter().filter(|r| r.ok).count(), summary.display());
    }
    if interrupted > 0 {
        return Err(CliError::Interrupted(format!(
            "interrupted: {interrupted} of {listed} shots not finished (checkpointed); run the same batch again to \
             continue (summary: {})",
            summary.display()
        )));
    }
    match failed {
        0 => Ok(()),
        // Each failure was reported as its shot finished; the summary says which.
        _ => Err(CliError::Run(format!("{failed} of {listed} shots failed (summary: {})", summary.display()))),
    }
}

/// The summary JSON: the results so far in the shots' order, written atomically.
fn write_summary(path: &Path, results: &[Option<crate::batch::ShotResult>]) -> Result<(), String> {
    let done: Vec<_> = results.iter().flatten().collect();
    let failed = done.iter().filter(|r| r.status == "failed").count();
    let interrupted = done.iter().filter(|r| r.status == "interrupted").count();
    let pending = results.len() - done.len();
    let json = serde_json::json!({ "shots": done, "failed": failed, "interrupted": interrupted, "pending": pending });
    let json = serde_json::to_string_pretty(&json).map_err(|e| e.to_string());
    json.and_then(|j| {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        }
        crate::io::write_atomic(path, j.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|e| format!("{}: {e}", path.display()))
}

pub fn convert(conf: &Path, out: &Path, base: Option<&Path>) -> Result<(), CliError> {
    let (json, warnings) = scene::arcsim::convert_file(conf, base, out)?;
    print_warnings(conf, &warnings);
    let dir = out.parent().filter(|d| !d.as_os_str().is_empty());
    dir.map_or(Ok(()), std::fs::create_dir_all)
        .and_then(|()| crate::io::write_atomic(out, json.as_bytes()))
        .map_err(|e| CliError::Run(format!("{}: {e}", out.display())))?;
    println!("{} → {}", conf.display(), out.display());
    Ok(())
}

/// The damping profiles `upsample train` is to use: the one given (paper defaults for what is
/// not), or with --cross-validate the grid of the listed values (defaults for lists not given).
fn profile_grid(
    a: &crate::cli::args::UpsampleTrainArgs,
) -> Result<Vec<crate::upsample::validate::Candidate>, CliError> {
    use crate::cli::args::PriorArg;
    use crate::upsample::{validate::grid, Prior};
    let several =
        |name: &str, n: usize| CliError::Input(format!("{name}: {n} values given; several need --cross-validate"));
    let lists = [
        ("--gamma1", &a.gamma1, [1.0].as_slice(), [1e-3, 1e-2, 0.1, 1.0, 10.0].as_slice()),
        ("--gammaN", &a.gamma_n, &[1e5], &[1.0, 10.0, 100.0, 1e3, 1e5]),
        ("--c", &a.c, &[4.0], &[1.0, 2.0, 4.0, 8.0]),
    ];
    let mut chosen = Vec::new();
    for (name, given, paper, searched) in lists {
        chosen.push(match (given, a.cross_validate) {
            (Some(v), false) if v.len() > 1 => return Err(several(name, v.len())),
            (Some(v), _) => v.clone(),
            (None, false) => paper.to_vec(),
            (None, true) => searched.to_vec(),
        });
    }
    let priors: Vec<Prior> = match (&a.prior, a.cross_validate) {
        (Some(v), false) if v.len() > 1 => return Err(several("--prior", v.len())),
        (Some(v), _) => v.iter().map(|p| if *p == PriorArg::Zero { Prior::Zero } else { Prior::Barycentric }).collect(),
        (None, false) => vec![Prior::Zero],
        (None, true) => vec![Prior::Zero, Prior::Barycentric],
    };
    let g = grid(&priors, &chosen[0], &chosen[1], &chosen[2]);
    if g.is_empty() {
        return Err(CliError::Input("--gamma1, --gammaN: no pair with gamma1 <= gammaN to try".into()));
    }
    Ok(g)
}

/// The cross-validation table, best first (nothing when there was one candidate).
fn print_validation(scores: &[crate::upsample::validate::Scored], folds: usize) {
    if scores.is_empty() {
        return;
    }
    let mut sorted: Vec<_> = scores.iter().collect();
    sorted.sort_by(|a, b| a.rms.total_cmp(&b.rms));
    println!("{folds}-fold cross-validation over blocks of training frames, RMS node distance (mm), best first:");
    println!("| prior | γ_1 | γ_N | c | all folds | per fold |");
    println!("|---|---|---|---|---|---|");
    for s in sorted {
        let folds: Vec<String> = s.per_fold.iter().map(|e| format!("{:.3}", 1e3 * e)).collect();
        let c = s.candidate;
        let prior = prior_name(c.prior);
        println!("| {prior} | {} | {} | {} | {:.3} | {} |", c.gamma1, c.gamma_n, c.c, 1e3 * s.rms, folds.join(" "));
    }
}

fn prior_name(p: crate::upsample::Prior) -> &'static str {
    match p {
        crate::upsample::Prior::Zero => "zero",
        crate::upsample::Prior::Barycentric => "barycentric",
    }
}

/// `upsample train`, `upsample apply` and `upsample loop`.
pub fn upsample(cmd: UpsampleCommand) -> Result<(), CliError> {
    use crate::upsample::run::{apply, coarse_faces, subdivide, train, RunError, TrainOptions};
    use crate::upsample::{levels_to_match, Model};
    let cli_error = |e: RunError| match e {
        RunError::Input(m) => CliError::Input(m),
        RunError::Output(m) => CliError::Run(m),
    };
    match cmd {
        UpsampleCommand::Train(a) => {
            let opts = TrainOptions {
                modes: a.modes,
                profiles: profile_grid(&a)?,
                folds: a.folds,
                oscillatory: a.oscillatory,
            };
            let start = std::time::Instant::now();
            let (model, r) = train(&a.coarse, &a.fine, &opts).map_err(cli_error)?;
            crate::io::write_atomic(&a.out, &model.to_bytes())
                .map_err(|e| CliError::Run(format!("{}: {e}", a.out.display())))?;
            print_validation(&r.validation, a.folds);
            if !r.validation.is_empty() {
                println!(
                    "barycentric embedding B p_c (the coarse surface; U's limit for large γ with --prior barycentric): {:.3} mm over all training frames",
                    1e3 * r.barycentric_rms
                );
            }
            let periods: Vec<String> =
                r.oscillatory.iter().map(|t| format!("{:.2}", 2.0 * std::f64::consts::PI / t)).collect();
            let osc = match periods.is_empty() {
                true => String::new(),
                false => format!(", oscillatory pairs of period {} frames", periods.join(", ")),
            };
            let p = r.profile;
            println!(
                "trained on {} frames: {} coarse → {} fine nodes, {} harmonics, prior {}, γ_1 {} γ_N {} c {}{osc}, {:.1} s → {}",
                r.frames,
                r.coarse_nodes,
                r.fine_nodes,
                r.modes,
                prior_name(p.prior),
                p.gamma1,
                p.gamma_n,
                p.c,
                start.elapsed().as_secs_f64(),
                a.out.display()
            );
        }
        UpsampleCommand::Apply(a) => {
            let model = Model::read(&a.model).map_err(|e| CliError::Input(e.to_string()))?;
            let n = apply(&model, &a.coarse, &a.out).map_err(cli_error)?;
            println!("{n} frames upsampled → {}", a.out.display());
        }
        UpsampleCommand::Loop(a) => {
            let levels = match (a.levels, &a.model) {
                (Some(l), _) if l > crate::upsample::subdivision::MAX_LEVELS => {
                    let max = crate::upsample::subdivision::MAX_LEVELS;
                    return Err(CliError::Input(format!(
                        "--levels: expected 0..={max} (4^L faces per coarse face), got {l}"
                    )));
                }
                (Some(l), _) => l,
                (None, Some(m)) => {
                    let model = Model::read(m).map_err(|e| CliError::Input(e.to_string()))?;
                    levels_to_match(coarse_faces(&a.coarse).map_err(cli_error)?, model.faces.len())
                }
                (None, None) => return Err(CliError::Input("upsample loop: give --levels L or --model MODEL".into())),
            };
            let (n, _) = subdivide(&a.coarse, levels, &a.out).map_err(cli_error)?;
            println!("{n} frames Loop-subdivided ({levels} levels) → {}", a.out.display());
        }
        UpsampleCommand::Trace(a) => {
            let load = |p: &Path| -> Result<crate::scene::Scene, CliError> {
                let loaded = scene::load_path(p, None).map_err(|e| CliError::Input(e.to_string()))?;
                print_warnings(p, &loaded.warnings);
                Ok(loaded.scene)
            };
            let (coarse, fine) = (load(&a.coarse)?, load(&a.fine)?);
            let r = crate::upsample::track::trace(coarse, fine, a.test_functions, &a.out).map_err(cli_error)?;
            let worst = r.residual_after.iter().copied().fold(0.0, f64::max);
            let pull = r.residual_before.iter().copied().fold(0.0, f64::max);
            println!(
                "tracked {} frames ({} steps): {} coarse, {} fine nodes, {} test functions; |T p_f − T B p_c| ≤ {worst:.1e} m after each step (up to {pull:.1e} m before) → {}",
                r.frames, r.steps, r.coarse_nodes, r.fine_nodes, a.test_functions, a.out.display()
            );
        }
    }
    Ok(())
}
