//! The `viewcloth` command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use viewcloth::camera::Camera;
use viewcloth::compare::{compare, markdown, CompareOptions};
use viewcloth::error::InputError;
use viewcloth::render::{render_run, Colouring, RenderOptions};
use viewcloth::scene::{self, RemeshMode, Scene};
use viewcloth::sim::{resume, run_with_checkpoints, CheckpointOptions, ResumeOptions, RunError, RunOptions, SimError};

#[derive(Parser)]
#[command(name = "viewcloth", version, about = "Film cloth simulator: scene files in, one OBJ mesh per frame out")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene (the built-in default shot when no SCENE is given).
    Simulate(SimulateArgs),
    /// Continue a run from the last checkpoint in its output directory (the frames are
    /// identical to an uninterrupted run's).
    Resume(ResumeArgs),
    /// Validate scene files (or ARCSim confs, or camera files) and the files they reference, without simulating.
    Check {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Base directory for an ARCSim conf's paths (default: the conf's grand-parent directory).
        #[arg(long)]
        base: Option<PathBuf>,
    },
    /// Run a shot in several remeshing modes and report each one's error against a reference,
    /// seen from the shot camera, with its run time (compare.json, compare.md, compare.svg).
    Compare(CompareArgs),
    /// Render PNG previews of a run's frames (RUN_DIR/view_NNNN.png) from a camera, shaded or
    /// coloured by the cloth's view factor.
    Render(RenderArgs),
    /// Run many shots from a shots file (JSON list of scenes with per-shot options), several at a
    /// time; a failed shot does not stop the others.
    Batch {
        shots: PathBuf,
        /// Shots run at once (each gets an equal share of the cores).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=256))]
        jobs: u64,
        /// Worker threads per shot (default: the cores divided by --jobs).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
        threads: Option<u64>,
        /// The summary JSON (default: out/<shots file stem>.batch.json).
        #[arg(long)]
        summary: Option<PathBuf>,
        /// No line per finished shot.
        #[arg(long)]
        quiet: bool,
    },
    /// Convert an ARCSim conf into a viewcloth scene file.
    Convert {
        conf: PathBuf,
        /// The scene file to write; its paths are relative to its directory.
        #[arg(long)]
        out: PathBuf,
        /// Base directory for the conf's paths (default: the conf's grand-parent directory).
        #[arg(long)]
        base: Option<PathBuf>,
    },
}

#[derive(clap::Args)]
struct SimulateArgs {
    /// Scene file (JSON).
    scene: Option<PathBuf>,
    /// Number of frames to simulate (overrides the scene).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// Output directory (default: out/<scene file stem>/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (default: all cores). Results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    threads: Option<u64>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Also write each obstacle's world-space mesh per frame beside the cloth frames.
    #[arg(long)]
    export_obstacles: bool,
    /// Override the remeshing mode of every cloth with a `remesh` block: `adaptive`, `uniform`
    /// (refined once to the minimum edge length, never remeshed) or `view` (adaptive, scaled by
    /// the camera's view factors; needs a camera).
    #[arg(long, value_parser = RemeshMode::NAMES)]
    mode: Option<String>,
    /// The shot camera (a camera JSON file) for view-dependent remeshing; implies `--mode view`
    /// unless `--mode` is given.
    #[arg(long, value_name = "FILE")]
    camera: Option<PathBuf>,
    /// Write a checkpoint every N frames (and at the last), for `viewcloth resume`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    checkpoint_every: Option<u64>,
    /// Base directory for an ARCSim conf's paths (default: the conf's grand-parent directory).
    #[arg(long)]
    base: Option<PathBuf>,
}

#[derive(clap::Args)]
struct ResumeArgs {
    /// Output directory of a run started with --checkpoint-every.
    dir: PathBuf,
    /// Last frame of the continued run (default: the run's own).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// Worker threads (default: all cores). Results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    threads: Option<u64>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

#[derive(clap::Args)]
struct CompareArgs {
    /// Scene file (JSON).
    scene: PathBuf,
    /// The shot camera (default: the scene's `camera`).
    #[arg(long, value_name = "FILE")]
    camera: Option<PathBuf>,
    /// Number of frames to simulate (overrides the scene).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// Output directory (default: out/<scene file stem>-compare/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Modes compared with the reference, comma-separated.
    #[arg(long, default_value = "adaptive,view", value_delimiter = ',', value_parser = RemeshMode::NAMES)]
    modes: Vec<String>,
    /// An existing run directory to use as the reference (default: a uniform run at the
    /// adaptive minimum edge length, simulated here). No chaos floor is run then.
    #[arg(long, value_name = "DIR")]
    reference: Option<PathBuf>,
    /// Skip the chaos-floor run (the reference re-run from perturbed positions).
    #[arg(long)]
    no_floor: bool,
    /// Image size of the visible error, WIDTHxHEIGHT.
    #[arg(long, default_value = "960x540")]
    size: String,
    /// Compare every N-th frame.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    every: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    threads: Option<u64>,
    /// Only the table at the end.
    #[arg(long)]
    quiet: bool,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Output directory of a run (its stats.json and frame_NNNN.obj; obstacle_<name>_NNNN.obj
    /// too when the run exported them).
    #[arg(value_name = "RUN_DIR")]
    dir: PathBuf,
    /// The camera to render from (a camera JSON file), at each frame's time.
    #[arg(long, value_name = "FILE")]
    camera: PathBuf,
    /// Frames A..B, both included (default: every frame of the run).
    #[arg(long, value_name = "A..B")]
    frames: Option<String>,
    /// Every N-th frame, counted from the first.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    every: u64,
    /// Image size, WIDTHxHEIGHT (the camera's aspect is kept).
    #[arg(long, default_value = "960x540")]
    size: String,
    /// `shade`: cloth light blue, obstacles salmon; `view`: cloth by its view factor, blue (0.1)
    /// to red (1), obstacles grey.
    #[arg(long, default_value = "shade", value_parser = ["shade", "view"])]
    color: String,
}

/// Exit code for bad input (scene, mesh, command line).
const EXIT_INPUT: u8 = 2;
/// Exit code for a simulation or output failure.
const EXIT_RUN: u8 = 1;

/// Loads a scene or ARCSim conf, printing the conversion's warnings (one line each).
fn load_warn(path: &Path, base: Option<&Path>) -> Result<Scene, InputError> {
    let loaded = scene::load_path(path, base)?;
    for w in &loaded.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    Ok(loaded.scene)
}

fn load(scene: &Option<PathBuf>, base: Option<&Path>) -> Result<(Scene, String), InputError> {
    match scene {
        Some(path) => {
            let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
            Ok((load_warn(path, base)?, stem))
        }
        None => {
            let name = scene::DEFAULT_SCENE_NAME;
            let file = PathBuf::from(format!("<built-in {name}>"));
            Ok((scene::load_str(scene::DEFAULT_SCENE, &file, Path::new("."), name)?, name.to_string()))
        }
    }
}

/// Sets the worker thread count; false (after printing the error) when it cannot.
fn set_threads(threads: Option<u64>) -> bool {
    if let Some(n) = threads {
        if let Err(e) = rayon::ThreadPoolBuilder::new().num_threads(n as usize).build_global() {
            eprintln!("error: --threads: cannot start {n} threads: {e}");
            return false;
        }
    }
    true
}

/// Exit code and one stderr line for a failed run: bad input (including an unusable initial
/// state or checkpoint) is 2, a simulation or output failure 1.
fn run_failed(e: RunError) -> ExitCode {
    eprintln!("error: {e}");
    match e {
        RunError::Sim(SimError::Input(_)) | RunError::Input(_) | RunError::Checkpoint(_) => ExitCode::from(EXIT_INPUT),
        _ => ExitCode::from(EXIT_RUN),
    }
}

fn simulate(args: SimulateArgs) -> ExitCode {
    let SimulateArgs { scene, frames, out, threads, quiet, export_obstacles, mode, camera, checkpoint_every, base } =
        args;
    if !set_threads(threads) {
        return ExitCode::from(EXIT_INPUT);
    }
    let scene_file = match &scene {
        Some(p) => match std::path::absolute(p) {
            Ok(abs) => Some(abs),
            Err(e) => {
                eprintln!("error: {}: {e}", p.display());
                return ExitCode::from(EXIT_INPUT);
            }
        },
        None => None,
    };
    let (mut scene, stem) = match load(&scene, base.as_deref()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_INPUT);
        }
    };
    let camera_file = match camera.as_deref().map(std::path::absolute).transpose() {
        Ok(file) => file,
        Err(e) => {
            eprintln!("error: --camera: {e}");
            return ExitCode::from(EXIT_INPUT);
        }
    };
    if let Some(file) = &camera_file {
        match Camera::load(file) {
            Ok(cam) => scene.camera = Some(cam),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(EXIT_INPUT);
            }
        }
    }
    // clap admits only RemeshMode::NAMES; a view mode without a camera is refused by
    // Simulation::new before anything is written.
    let mode = match mode.as_deref() {
        Some(name) => RemeshMode::parse(name),
        None => camera_file.as_ref().map(|_| RemeshMode::View),
    };
    if let Some(mode) = mode {
        if scene.set_remesh_mode(mode) == 0 {
            eprintln!("error: --mode: scene '{}' has no cloth with a remesh block", scene.name);
            return ExitCode::from(EXIT_INPUT);
        }
    }
    let out_dir = out.unwrap_or_else(|| Path::new("out").join(&stem));
    let opts = RunOptions { out_dir: out_dir.clone(), frames: frames.map(|f| f as usize), quiet, export_obstacles };
    let ck = checkpoint_every.map(|every| CheckpointOptions { every: every as usize, scene_file, mode, camera_file });
    match run_with_checkpoints(scene, &opts, ck.as_ref()) {
        Ok(stats) => {
            if !quiet {
                println!(
                    "{}: {} frames in {:.2} s → {}",
                    stats.scene,
                    stats.frames.len().saturating_sub(1),
                    stats.total_wall_s,
                    out_dir.display()
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => run_failed(e),
    }
}

fn resume_run(args: ResumeArgs) -> ExitCode {
    if !set_threads(args.threads) {
        return ExitCode::from(EXIT_INPUT);
    }
    let opts = ResumeOptions { frames: args.frames.map(|f| f as usize), quiet: args.quiet };
    match resume(&args.dir, &opts) {
        Ok(stats) => {
            if !args.quiet {
                let resumed = stats.resumed_at.last().copied().unwrap_or(0);
                println!(
                    "{}: resumed at frame {resumed}, {} frames in all → {}",
                    stats.scene,
                    stats.frames.len().saturating_sub(1),
                    args.dir.display()
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => run_failed(e),
    }
}

fn check(files: &[PathBuf], base: Option<&Path>) -> ExitCode {
    let mut ok = true;
    for f in files {
        let checked = if is_camera_file(f) { Camera::load(f).map(|_| ()) } else { load_warn(f, base).map(|_| ()) };
        match checked {
            Ok(()) => println!("{}: ok", f.display()),
            Err(e) => {
                eprintln!("error: {e}");
                ok = false;
            }
        }
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(EXIT_INPUT)
    }
}

fn compare_modes(args: CompareArgs) -> ExitCode {
    if !set_threads(args.threads) {
        return ExitCode::from(EXIT_INPUT);
    }
    let Some((width, height)) = parse_size(&args.size) else {
        return ExitCode::from(EXIT_INPUT);
    };
    let (mut scene, stem) = match load(&Some(args.scene.clone()), None) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_INPUT);
        }
    };
    if let Some(file) = &args.camera {
        match Camera::load(file) {
            Ok(cam) => scene.camera = Some(cam),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(EXIT_INPUT);
            }
        }
    }
    let modes = args.modes.iter().filter_map(|m| RemeshMode::parse(m)).collect();
    let opts = CompareOptions {
        out_dir: args.out.unwrap_or_else(|| Path::new("out").join(format!("{stem}-compare"))),
        frames: args.frames.map(|f| f as usize),
        modes,
        reference: args.reference,
        floor: !args.no_floor,
        width,
        height,
        every: args.every as usize,
        quiet: args.quiet,
    };
    match compare(scene, &opts) {
        Ok(report) => {
            print!("{}", markdown(&report));
            ExitCode::SUCCESS
        }
        Err(e) => run_failed(e),
    }
}

/// `--size WIDTHxHEIGHT`, each in 16..=8192; None after printing the error.
fn parse_size(text: &str) -> Option<(usize, usize)> {
    let size = text.split_once('x').and_then(|(w, h)| Some((w.parse::<usize>().ok()?, h.parse::<usize>().ok()?)));
    let size = size.filter(|&(w, h)| (16..=8192).contains(&w) && (16..=8192).contains(&h));
    if size.is_none() {
        eprintln!("error: --size: expected WIDTHxHEIGHT with each in 16..=8192, got \"{text}\"");
    }
    size
}

/// `--frames A..B` (both included, A ≤ B); None after printing the error.
fn parse_frames(text: &str) -> Option<(usize, usize)> {
    let range = text.split_once("..").and_then(|(a, b)| Some((a.parse::<usize>().ok()?, b.parse::<usize>().ok()?)));
    let range = range.filter(|(a, b)| a <= b);
    if range.is_none() {
        eprintln!("error: --frames: expected A..B, frame numbers with A ≤ B (both included), got \"{text}\"");
    }
    range
}

fn render(args: RenderArgs) -> ExitCode {
    let Some((width, height)) = parse_size(&args.size) else {
        return ExitCode::from(EXIT_INPUT);
    };
    let frames = match args.frames.as_deref().map(parse_frames) {
        Some(None) => return ExitCode::from(EXIT_INPUT),
        range => range.flatten(),
    };
    let camera = match Camera::load(&args.camera) {
        Ok(camera) => camera,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_INPUT);
        }
    };
    let colouring = if args.color == "view" { Colouring::View } else { Colouring::Shade };
    let opts = RenderOptions { width, height, frames, every: args.every as usize, colouring };
    match render_run(&args.dir, &camera, &opts) {
        Ok(n) => {
            println!("{n} images → {}", args.dir.join("view_*.png").display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(if e.is_input() { EXIT_INPUT } else { EXIT_RUN })
        }
    }
}

fn batch(file: &Path, jobs: u64, threads: Option<u64>, summary: Option<PathBuf>, quiet: bool) -> ExitCode {
    let shots = match viewcloth::batch::load(file) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_INPUT);
        }
    };
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let threads = threads.map(|t| t as usize).unwrap_or((cores / jobs as usize).max(1));
    let summary = summary.unwrap_or_else(|| {
        let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shots".into());
        Path::new("out").join(format!("{stem}.batch.json"))
    });
    let n = shots.len();
    let report = |r: &viewcloth::batch::ShotResult| {
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
    let results = viewcloth::batch::run_shots(shots, jobs as usize, threads, &report);
    let failed = results.iter().filter(|r| !r.ok).count();
    let json = serde_json::to_string_pretty(&serde_json::json!({ "shots": results, "failed": failed }));
    let written = json.map_err(|e| e.to_string()).and_then(|j| {
        if let Some(dir) = summary.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        }
        viewcloth::io::write_atomic(&summary, j.as_bytes()).map_err(|e| e.to_string())
    });
    if let Err(e) = written {
        eprintln!("error: {}: {e}", summary.display());
        return ExitCode::from(EXIT_RUN);
    }
    if !quiet {
        println!("{} of {n} shots ok; summary → {}", n - failed, summary.display());
    }
    if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(EXIT_RUN)
    }
}

/// A camera file (`cameras/*.json`): a JSON object with `keys` and no `cloths`.
fn is_camera_file(path: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else { return false };
    let Ok(serde_json::Value::Object(m)) = serde_json::from_str::<serde_json::Value>(&text) else { return false };
    m.contains_key("keys") && !m.contains_key("cloths")
}

fn convert(conf: &Path, out: &Path, base: Option<&Path>) -> ExitCode {
    let (json, warnings) = match scene::arcsim::convert_file(conf, base, out) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_INPUT);
        }
    };
    for w in &warnings {
        eprintln!("warning: {}: {w}", conf.display());
    }
    let dir = out.parent().filter(|d| !d.as_os_str().is_empty());
    if let Err(e) =
        dir.map_or(Ok(()), std::fs::create_dir_all).and_then(|()| viewcloth::io::write_atomic(out, json.as_bytes()))
    {
        eprintln!("error: {}: {e}", out.display());
        return ExitCode::from(EXIT_RUN);
    }
    println!("{} → {}", conf.display(), out.display());
    ExitCode::SUCCESS
}

/// Command-line errors as one line on stderr, exit code 2, like every input error; help and
/// version print as clap formats them.
fn parse_cli() -> Result<Cli, ExitCode> {
    Cli::try_parse().map_err(|e| {
        use clap::error::ErrorKind;
        let display =
            [ErrorKind::DisplayHelp, ErrorKind::DisplayVersion, ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand];
        if display.contains(&e.kind()) {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { EXIT_INPUT } else { 0 });
        }
        let text = e.render().to_string();
        let parts: Vec<&str> = text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with("Usage:") && !l.starts_with("For more information"))
            .collect();
        eprintln!("{}", parts.join(" "));
        ExitCode::from(EXIT_INPUT)
    })
}

fn main() -> ExitCode {
    let cli = match parse_cli() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    match cli.command {
        Command::Simulate(args) => simulate(args),
        Command::Resume(args) => resume_run(args),
        Command::Check { files, base } => check(&files, base.as_deref()),
        Command::Compare(args) => compare_modes(args),
        Command::Render(args) => render(args),
        Command::Batch { shots, jobs, threads, summary, quiet } => batch(&shots, jobs, threads, summary, quiet),
        Command::Convert { conf, out, base } => convert(&conf, &out, base.as_deref()),
    }
}
