//! The commands behind `viewcloth`'s subcommands. Each returns `Result<(), CliError>`; the binary
//! prints an error as one line (`error: …`) and exits with its code: 2 for bad input (scene,
//! mesh, camera, checkpoint, command line), 1 for a simulation or output failure.

pub mod args;

use std::path::{Path, PathBuf};

use crate::camera::Camera;
use crate::compare::{compare, markdown, CompareOptions};
use crate::error::InputError;
use crate::render::{render_run, Colouring, RenderOptions};
use crate::scene::{self, RemeshMode};
use crate::shot::{self, ShotError, ShotRequest};
use crate::sim::{resume, run_with_checkpoints, CheckpointOptions, ResumeOptions, RunError, RunOptions, SimError};
use args::{CompareArgs, RenderArgs, ResumeArgs, SimulateArgs};

/// Exit code for bad input (scene, mesh, command line).
pub const EXIT_INPUT: u8 = 2;
/// Exit code for a simulation or output failure.
pub const EXIT_RUN: u8 = 1;

/// A failed command: its message (one line per problem) and exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad input: exit 2.
    #[error("{0}")]
    Input(String),
    /// A simulation or output failure: exit 1.
    #[error("{0}")]
    Run(String),
}

impl CliError {
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Input(_) => EXIT_INPUT,
            CliError::Run(_) => EXIT_RUN,
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
            _ => CliError::Run(e.to_string()),
        }
    }
}

/// Sets the worker thread count of the global pool.
fn set_threads(threads: Option<u64>) -> Result<(), CliError> {
    let Some(n) = threads else { return Ok(()) };
    rayon::ThreadPoolBuilder::new()
        .num_threads(n as usize)
        .build_global()
        .map_err(|e| CliError::Input(format!("--threads: cannot start {n} threads: {e}")))
}

fn print_warnings(file: &Path, warnings: &[String]) {
    for w in warnings {
        eprintln!("warning: {}: {w}", file.display());
    }
}

pub fn simulate(args: SimulateArgs) -> Result<(), CliError> {
    let SimulateArgs { scene, frames, out, threads, quiet, export_obstacles, mode, camera, checkpoint_every, base } =
        args;
    set_threads(threads)?;
    // clap admits only RemeshMode::NAMES.
    let mode = mode.as_deref().and_then(RemeshMode::parse);
    let request = ShotRequest { scene: scene.clone(), base, camera, mode, camera_implies_view: true };
    let shot = shot::resolve(&request)?;
    if let Some(path) = &scene {
        print_warnings(path, &shot.warnings);
    }
    let out_dir = out.unwrap_or_else(|| Path::new("out").join(&shot.stem));
    let opts = RunOptions { out_dir: out_dir.clone(), frames: frames.map(|f| f as usize), quiet, export_obstacles };
    let ck = checkpoint_every.map(|every| CheckpointOptions {
        every: every as usize,
        scene_file: shot.scene_file.clone(),
        mode: shot.mode,
        camera_file: shot.camera_file.clone(),
    });
    let stats = run_with_checkpoints(shot.scene, &opts, ck.as_ref())?;
    if !quiet {
        let frames = stats.frames.len().saturating_sub(1);
        println!("{}: {frames} frames in {:.2} s → {}", stats.scene, stats.total_wall_s, out_dir.display());
    }
    Ok(())
}

pub fn resume_run(args: ResumeArgs) -> Result<(), CliError> {
    set_threads(args.threads)?;
    let opts = ResumeOptions { frames: args.frames.map(|f| f as usize), quiet: args.quiet };
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
    set_threads(args.threads)?;
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
    let opts = RenderOptions { width, height, frames, every: args.every as usize, colouring };
    let n = render_run(&args.dir, &camera, &opts).map_err(|e| match e.is_input() {
        true => CliError::Input(e.to_string()),
        false => CliError::Run(e.to_string()),
    })?;
    println!("{n} images → {}", args.dir.join("view_*.png").display());
    Ok(())
}

pub fn batch(
    file: &Path,
    jobs: u64,
    threads: Option<u64>,
    summary: Option<PathBuf>,
    quiet: bool,
) -> Result<(), CliError> {
    let shots = crate::batch::load(file)?;
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let threads = threads.map(|t| t as usize).unwrap_or((cores / jobs as usize).max(1));
    let summary = summary.unwrap_or_else(|| {
        let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shots".into());
        Path::new("out").join(format!("{stem}.batch.json"))
    });
    let n = shots.len();
    let report = |r: &crate::batch::ShotResult| {
        if quiet {
            return;
        }
        match &r.error {
            None => {
                println!("ok: {}: {} frames in {:.1} s → {}", r.scene.display(), r.frames, r.wall_s, r.out.display())
            }
            Some(e) => println!("failed: {}: {e}", r.scene.display()),
        }
    };
    let results = crate::batch::run_shots(shots, jobs as usize, threads, &report);
    let failed = results.iter().filter(|r| !r.ok).count();
    let json = serde_json::to_string_pretty(&serde_json::json!({ "shots": results, "failed": failed }));
    let written = json.map_err(|e| e.to_string()).and_then(|j| {
        if let Some(dir) = summary.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        }
        crate::io::write_atomic(&summary, j.as_bytes()).map_err(|e| e.to_string())
    });
    written.map_err(|e| CliError::Run(format!("{}: {e}", summary.display())))?;
    if !quiet {
        println!("{} of {n} shots ok; summary → {}", n - failed, summary.display());
    }
    match failed {
        0 => Ok(()),
        // Each failure was reported as its shot finished; the summary says which.
        _ => Err(CliError::Run(format!("{failed} of {n} shots failed (summary: {})", summary.display()))),
    }
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
