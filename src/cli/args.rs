//! The command line's arguments (clap), as `viewcloth --help` shows them.

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use crate::io::OutputFormat;
use crate::scene::RemeshMode;
use crate::sim::progress::ProgressMode;

#[derive(Parser)]
#[command(name = "viewcloth", version, about = "Film cloth simulator: scene files in, one OBJ mesh per frame out")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
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
    /// Resample an adaptive run onto one fixed-topology mesh for the whole shot (OBJ frames, a
    /// PC2 point cache, a USD layer and the resampling error per frame).
    Resample(ResampleArgs),
    /// Run many shots from a shots file (JSON list of scenes with per-shot options), several at a
    /// time; a failed shot does not stop the others. A rerun skips finished shots and resumes
    /// interrupted ones.
    Batch(BatchArgs),
    /// Count the triangle pairs that cross in each frame of a run, from its files (frame_NNNN.obj
    /// and, when exported, obstacle_<name>_NNNN.obj): cloth–cloth and cloth–obstacle, pairs
    /// sharing a node skipped. Prints one line per frame; exits 1 if any pair crosses.
    Crossings(CrossingsArgs),
    /// Physics-inspired upsampling (Kavan et al. 2011): learn a linear coarse → fine operator
    /// from a coarse and a fine uniform run of the same shot, and apply it to coarse runs.
    #[command(subcommand)]
    Upsample(UpsampleCommand),
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

impl Command {
    /// The worker threads the command asks for (`--threads`); a batch's are per shot (its own
    /// pools), so none here.
    pub fn threads(&self) -> Option<u64> {
        match self {
            Command::Simulate(a) => a.threads,
            Command::Resume(a) => a.threads,
            Command::Compare(a) => a.threads,
            Command::Upsample(UpsampleCommand::Trace(a)) => a.threads,
            _ => None,
        }
    }
}

#[derive(clap::Args)]
pub struct SimulateArgs {
    /// Scene file (JSON).
    pub scene: Option<PathBuf>,
    /// Number of frames to simulate (overrides the scene).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub frames: Option<u64>,
    /// Output directory (default: out/<scene file stem>/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores). Results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// No progress report, no closing line.
    #[arg(long)]
    pub quiet: bool,
    /// Progress report: `bar`, `lines` (one stderr line per frame, for logs) or `none`
    /// (default: a bar on a terminal, lines otherwise; `none` with --quiet).
    #[arg(long, value_parser = ProgressMode::NAMES)]
    pub progress: Option<String>,
    /// Replace the run of another scene in the output directory (refused without it).
    #[arg(long)]
    pub force: bool,
    /// Also write each obstacle's world-space mesh per frame beside the cloth frames (and as
    /// prims of the USD layer).
    #[arg(long)]
    pub export_obstacles: bool,
    /// What is written per frame: `obj` (frame_NNNN.obj), `usd` (one cloth.usda layer with
    /// every frame as time samples, velocities included) or `both`.
    #[arg(long, value_parser = OutputFormat::NAMES)]
    pub format: Option<String>,
    /// OBJ frames carry each node's velocity (m/s) on an `nv` line after its `v` (ARCSim's).
    #[arg(long)]
    pub obj_velocities: bool,
    /// Override the remeshing mode of every cloth with a `remesh` block: `adaptive`, `uniform`
    /// (refined once to the minimum edge length, never remeshed) or `view` (adaptive, scaled by
    /// the camera's view factors; needs a camera).
    #[arg(long, value_parser = RemeshMode::NAMES)]
    pub mode: Option<String>,
    /// The shot camera (a camera JSON file) for view-dependent remeshing; implies `--mode view`
    /// unless `--mode` is given.
    #[arg(long, value_name = "FILE")]
    pub camera: Option<PathBuf>,
    /// Write a checkpoint every N frames (and at the last), for `viewcloth resume`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub checkpoint_every: Option<u64>,
    /// Base directory for an ARCSim conf's paths (default: the conf's grand-parent directory).
    #[arg(long)]
    pub base: Option<PathBuf>,
    /// Move every initial cloth node by --jitter metres in a direction drawn from seed N
    /// (independent per node; the same seed gives the same run). Recorded in stats.json.
    #[arg(long, value_name = "N")]
    pub jitter_seed: Option<u64>,
    /// Size of the --jitter-seed displacement, metres (default 1e-6: 1 µm).
    #[arg(long, value_name = "M", requires = "jitter_seed", value_parser = parse_jitter)]
    pub jitter: Option<f64>,
}

/// `--jitter M`: a finite length in metres, 0 ≤ M ≤ 0.01.
fn parse_jitter(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(m) if (0.0..=0.01).contains(&m) => Ok(m),
        _ => Err(format!("expected a length in metres from 0 to 0.01, got \"{text}\"")),
    }
}

#[derive(clap::Args)]
pub struct ResumeArgs {
    /// Output directory of a run started with --checkpoint-every.
    pub dir: PathBuf,
    /// Frames of the continued run after its first (default: the run's own).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub frames: Option<u64>,
    /// The run's output format (`obj`, `usd` or `both`): checked, a run continues in the
    /// format it started with.
    #[arg(long, value_parser = OutputFormat::NAMES)]
    pub format: Option<String>,
    /// Worker threads (default: all cores). Results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// No progress report, no closing line.
    #[arg(long)]
    pub quiet: bool,
    /// Progress report: `bar`, `lines` (one stderr line per frame, for logs) or `none`
    /// (default: a bar on a terminal, lines otherwise; `none` with --quiet).
    #[arg(long, value_parser = ProgressMode::NAMES)]
    pub progress: Option<String>,
}

#[derive(clap::Args)]
pub struct BatchArgs {
    pub shots: PathBuf,
    /// Shots run at once (each gets an equal share of the cores).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=256))]
    pub jobs: u64,
    /// Worker threads per shot (default: SLURM_CPUS_PER_TASK, else the cores, divided by --jobs).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// The summary JSON (default: out/<shots file stem>.batch.json; with --shot,
    /// out/<shots file stem>.shot<N>.batch.json).
    #[arg(long)]
    pub summary: Option<PathBuf>,
    /// No line per finished shot, no progress report.
    #[arg(long)]
    pub quiet: bool,
    /// Progress report: `bar`, `lines` (one stderr line per frame, for logs) or `none`
    /// (default: a bar on a terminal, lines otherwise; `none` with --quiet).
    #[arg(long, value_parser = ProgressMode::NAMES)]
    pub progress: Option<String>,
    /// Replace runs of other scenes in the shots' output directories (refused without it).
    #[arg(long)]
    pub force: bool,
    /// Output format of the shots that do not give their own `format`: `obj` (default), `usd`
    /// or `both`.
    #[arg(long, value_parser = OutputFormat::NAMES)]
    pub format: Option<String>,
    /// Run only shot N of the list (counted from 0), e.g. as one task of a job array.
    #[arg(long, value_name = "N", conflicts_with = "shot_from_env")]
    pub shot: Option<u64>,
    /// Run only the shot whose index is in environment variable VAR (e.g. SLURM_ARRAY_TASK_ID).
    #[arg(long, value_name = "VAR")]
    pub shot_from_env: Option<String>,
    /// Write a job script for a scheduler instead of running: `slurm` (an sbatch array, one
    /// task per shot) into --out.
    #[arg(long, value_parser = ["slurm"], conflicts_with_all = ["shot", "shot_from_env"])]
    pub emit: Option<String>,
    /// Where --emit writes (default: out/<shots file stem>-slurm/).
    #[arg(long, requires = "emit")]
    pub out: Option<PathBuf>,
}

#[derive(clap::Args)]
pub struct CompareArgs {
    /// Scene file (JSON).
    pub scene: PathBuf,
    /// The shot camera (default: the scene's `camera`).
    #[arg(long, value_name = "FILE")]
    pub camera: Option<PathBuf>,
    /// Number of frames to simulate (overrides the scene).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub frames: Option<u64>,
    /// Output directory (default: out/<scene file stem>-compare/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Modes compared with the reference, comma-separated.
    #[arg(long, default_value = "adaptive,view", value_delimiter = ',', value_parser = RemeshMode::NAMES)]
    pub modes: Vec<String>,
    /// An existing run directory to use as the reference (default: a uniform run at the
    /// adaptive minimum edge length, simulated here). No chaos floor is run then.
    #[arg(long, value_name = "DIR")]
    pub reference: Option<PathBuf>,
    /// Chaos-floor runs: the reference re-run from independently perturbed positions.
    #[arg(long, value_name = "K", default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    pub floor_runs: u64,
    /// Skip the chaos-floor runs.
    #[arg(long)]
    pub no_floor: bool,
    /// Also run uniform meshes at 2x and 4x the minimum edge length (points on the
    /// error-against-time plot that a coarser uniform mesh would give).
    #[arg(long)]
    pub sweep: bool,
    /// A model from `upsample train`: adds the modes `coarse`, `upsampled` and `loop`, built from
    /// a uniform run of --coarse.
    #[arg(long, value_name = "MODEL", requires = "coarse")]
    pub upsample: Option<PathBuf>,
    /// The shot on the model's coarse mesh (a scene file), for --upsample.
    #[arg(long, value_name = "SCENE", requires = "upsample")]
    pub coarse: Option<PathBuf>,
    /// Image size of the visible error, WIDTHxHEIGHT.
    #[arg(long, default_value = "960x540")]
    pub size: String,
    /// Compare every N-th frame.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub every: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Only the table at the end.
    #[arg(long)]
    pub quiet: bool,
    /// Progress of the runs: `bar`, `lines` (one stderr line per frame, for logs) or `none`
    /// (default: a bar on a terminal, lines otherwise; `none` with --quiet).
    #[arg(long, value_parser = ProgressMode::NAMES)]
    pub progress: Option<String>,
}

#[derive(clap::Args)]
pub struct CrossingsArgs {
    /// Output directory of a run.
    #[arg(value_name = "RUN_DIR")]
    pub dir: PathBuf,
    /// Frames A..B, both included (default: every frame in the directory).
    #[arg(long, value_name = "A..B")]
    pub frames: Option<String>,
    /// Only the closing line (and the frames with crossings).
    #[arg(long)]
    pub quiet: bool,
    /// Also list each crossing pair: `pair`, the frame, `self` or `obstacle`, the two triangles
    /// (0-based, in file order: cloth faces, then the obstacles' in name order) and a point of
    /// the first (its centroid, m).
    #[arg(long)]
    pub pairs: bool,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Output directory of a run (its stats.json and frame_NNNN.obj; obstacle_<name>_NNNN.obj
    /// too when the run exported them).
    #[arg(value_name = "RUN_DIR")]
    pub dir: PathBuf,
    /// The camera to render from (a camera JSON file), at each frame's time.
    #[arg(long, value_name = "FILE")]
    pub camera: PathBuf,
    /// Frames A..B, both included (default: every frame of the run).
    #[arg(long, value_name = "A..B")]
    pub frames: Option<String>,
    /// Every N-th frame, counted from the first.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub every: u64,
    /// Image size, WIDTHxHEIGHT (the camera's aspect is kept).
    #[arg(long, default_value = "960x540")]
    pub size: String,
    /// `shade`: cloth light blue, obstacles salmon; `view`: cloth by its view factor, blue (0.1)
    /// to red (1), obstacles grey.
    #[arg(long, default_value = "shade", value_parser = ["shade", "view"])]
    pub color: String,
    /// Progress report: `bar`, `lines` (one stderr line per image) or `none` (default: a bar
    /// on a terminal, lines otherwise).
    #[arg(long, value_parser = ProgressMode::NAMES)]
    pub progress: Option<String>,
}

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("target").required(true).args(["mesh", "auto"])))]
pub struct ResampleArgs {
    /// Output directory of a run with OBJ frames (`--format obj` or `both`), of one cloth or
    /// several.
    #[arg(value_name = "RUN_DIR")]
    pub dir: PathBuf,
    /// The fixed mesh: an OBJ whose texture coordinates (in the run's, i.e. the input's, units)
    /// are the material locations its vertices track (e.g. the garment the scene was made from).
    /// Once per cloth of the run, in the order of its frames' `o` groups.
    #[arg(long, value_name = "OBJ")]
    pub mesh: Vec<PathBuf>,
    /// Make the fixed meshes from the run: each cloth's first frame refined to the finest sizing
    /// the run ever had at each place.
    #[arg(long)]
    pub auto: bool,
    /// Where to write (frame_NNNN.obj, cloth.pc2, cloth.usda, resample.json).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Subcommand)]
pub enum UpsampleCommand {
    /// Learn the operator from paired frames (same numbers) of a coarse and a fine uniform run.
    Train(UpsampleTrainArgs),
    /// Upsample every frame of a coarse uniform run into fine OBJ frames.
    Apply(UpsampleApplyArgs),
    /// Loop-subdivide every frame of a coarse uniform run (the classical baseline).
    Loop(UpsampleLoopArgs),
    /// Run a coarse and a fine uniform shot in lockstep, the fine one tracked (paper §4).
    Trace(UpsampleTraceArgs),
}

#[derive(clap::Args)]
pub struct UpsampleTrainArgs {
    /// Output directory of the coarse run (frame_NNNN.obj, one topology).
    #[arg(long, value_name = "DIR")]
    pub coarse: PathBuf,
    /// Output directory of the fine run, with the same frame numbers.
    #[arg(long, value_name = "DIR")]
    pub fine: PathBuf,
    /// Harmonics kept (default: all, one per fine node).
    #[arg(long, value_name = "K")]
    pub modes: Option<usize>,
    /// Damping of the lowest harmonic, γ_1 (paper §6: 1). With --cross-validate, a
    /// comma-separated list to choose from (default 0.001,0.01,0.1,1,10).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub gamma1: Option<Vec<f64>>,
    /// Damping of the highest harmonic, γ_N (paper §6: 1e5). With --cross-validate, a list
    /// (default 1,10,100,1000,1e5).
    #[arg(long = "gammaN", alias = "gamma-n", value_delimiter = ',', num_args = 1..)]
    pub gamma_n: Option<Vec<f64>>,
    /// Exponent of the damping profile γ_n = a(1 + b(n−1)/N)^c (paper §6: 4). With
    /// --cross-validate, a list (default 1,2,4,8).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub c: Option<Vec<f64>>,
    /// What the regulariser damps U towards: `zero` (the paper's eq. 5) or `barycentric` (the
    /// embedding of the fine mesh in the coarse one, i.e. the coarse surface). With
    /// --cross-validate, a list (default both).
    #[arg(long, value_enum, value_delimiter = ',', num_args = 1..)]
    pub prior: Option<Vec<PriorArg>>,
    /// Choose the prior, γ_1, γ_N and c from the grid of the listed values by k-fold cross-validation over
    /// contiguous blocks of the training frames (the fine run's other frames are not looked at).
    #[arg(long)]
    pub cross_validate: bool,
    /// Cross-validation folds (blocks of frames).
    #[arg(long, default_value_t = 5, requires = "cross_validate")]
    pub folds: usize,
    /// Oscillatory mode pairs fitted to the residual travelling waves (paper §5; 0: none).
    #[arg(long, value_name = "K", default_value_t = 0)]
    pub oscillatory: usize,
    /// The model file to write.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PriorArg {
    Zero,
    Barycentric,
}

#[derive(clap::Args)]
pub struct UpsampleApplyArgs {
    /// A model written by `upsample train`.
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// Output directory of a coarse uniform run on the model's coarse mesh.
    #[arg(long, value_name = "DIR")]
    pub coarse: PathBuf,
    /// Where to write the fine frames (frame_NNNN.obj, the coarse frames' numbers).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("depth").required(true).args(["levels", "model"])))]
pub struct UpsampleLoopArgs {
    /// Output directory of a coarse uniform run.
    #[arg(long, value_name = "DIR")]
    pub coarse: PathBuf,
    /// Subdivision levels (each splits every face in four).
    #[arg(long, value_name = "L")]
    pub levels: Option<usize>,
    /// Or: as many levels as bring the face count nearest this model's fine mesh.
    #[arg(long, value_name = "MODEL")]
    pub model: Option<PathBuf>,
    /// Where to write the subdivided frames (frame_NNNN.obj, the coarse frames' numbers).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

#[derive(clap::Args)]
pub struct UpsampleTraceArgs {
    /// The coarse shot (scene file, uniform mesh).
    #[arg(value_name = "COARSE_SCENE")]
    pub coarse: PathBuf,
    /// The same shot on the fine mesh (same frame timing).
    #[arg(value_name = "FINE_SCENE")]
    pub fine: PathBuf,
    /// Harmonic test functions T (paper: 50–80).
    #[arg(long = "test-functions", value_name = "T", default_value_t = 60)]
    pub test_functions: usize,
    /// Writes DIR/coarse/ and DIR/fine/ (frame_NNNN.obj and stats.json), the training pair.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Worker threads (default: all cores). Results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
}
