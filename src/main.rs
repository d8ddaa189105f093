//! The `viewcloth` command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use viewcloth::scene::{self, InputError, RemeshMode, Scene};
use viewcloth::sim::{run, RunError, RunOptions, SimError};

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
    /// Validate scene files (or ARCSim confs) and the files they reference, without simulating.
    Check {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Base directory for an ARCSim conf's paths (default: the conf's grand-parent directory).
        #[arg(long)]
        base: Option<PathBuf>,
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
    /// Override the remeshing mode of every cloth with a `remesh` block: `adaptive`, or
    /// `uniform` (refined once to the minimum edge length, never remeshed).
    #[arg(long, value_parser = ["uniform", "adaptive"])]
    mode: Option<String>,
    /// Base directory for an ARCSim conf's paths (default: the conf's grand-parent directory).
    #[arg(long)]
    base: Option<PathBuf>,
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

fn simulate(args: SimulateArgs) -> ExitCode {
    let SimulateArgs { scene, frames, out, threads, quiet, export_obstacles, mode, base } = args;
    if let Some(n) = threads {
        if let Err(e) = rayon::ThreadPoolBuilder::new().num_threads(n as usize).build_global() {
            eprintln!("error: --threads: cannot start {n} threads: {e}");
            return ExitCode::from(EXIT_INPUT);
        }
    }
    let (mut scene, stem) = match load(&scene, base.as_deref()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_INPUT);
        }
    };
    if let Some(mode) = mode {
        let mode = if mode == "uniform" { RemeshMode::Uniform } else { RemeshMode::Adaptive };
        if scene.set_remesh_mode(mode) == 0 {
            eprintln!("error: --mode: scene '{}' has no cloth with a remesh block", scene.name);
            return ExitCode::from(EXIT_INPUT);
        }
    }
    let out_dir = out.unwrap_or_else(|| Path::new("out").join(&stem));
    let opts = RunOptions { out_dir: out_dir.clone(), frames: frames.map(|f| f as usize), quiet, export_obstacles };
    match run(scene, &opts) {
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
        // An unusable initial state (e.g. cloth deep inside an obstacle) is bad input.
        Err(e @ RunError::Sim(SimError::Input(_))) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_INPUT)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_RUN)
        }
    }
}

fn check(files: &[PathBuf], base: Option<&Path>) -> ExitCode {
    let mut ok = true;
    for f in files {
        match load_warn(f, base) {
            Ok(_) => println!("{}: ok", f.display()),
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
    if let Err(e) = viewcloth::io::write_atomic(out, json.as_bytes()) {
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
        Command::Check { files, base } => check(&files, base.as_deref()),
        Command::Convert { conf, out, base } => convert(&conf, &out, base.as_deref()),
    }
}
