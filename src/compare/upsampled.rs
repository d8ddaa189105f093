//! The learned upsampling (Kavan et al. 2011) on the error-against-time plot: a uniform coarse
//! run of the shot (`coarse`), that run through the model (`upsampled`, §3 eq. 1) and through
//! Loop subdivision to about the model's fine face count (`loop`, the paper's baseline, Fig. 1b).
//! Each derived run's time is the coarse run's plus its own (reading, multiplying and writing
//! the frames), and its `stats.json` says so, so the derived runs are measured like any other.
//! Their frame stats carry the strain of the derived frames (from their positions and the
//! material coordinates they carry) and no energies: a derived frame has no velocities.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::{finished_run, read_stats, run_report, CompareOptions, RunReport};
use crate::error::InputError;
use crate::io::obj::{read_obj, uv_unit, ClothOut};
use crate::io::stats::{FrameStats, RunStats};
use crate::metrics::obj_strain;
use crate::scene::{RemeshMode, Scene};
use crate::sim::progress::Progress;
use crate::sim::{run_shot, RunError, RunOptions};
use crate::upsample::run::{apply, subdivide, RunError as UpsampleRunError};
use crate::upsample::{levels_to_match, Model};

/// `compare --upsample MODEL --coarse SCENE`.
#[derive(Clone, Debug)]
pub struct UpsampleOptions {
    pub model: PathBuf,
    /// The shot on the coarse mesh the model was trained on (run uniform).
    pub coarse: Scene,
}

/// Runs (or reuses) the coarse shot and derives the upsampled and Loop runs from it; returns
/// the three runs, not yet measured.
pub fn runs(up: &UpsampleOptions, opts: &CompareOptions) -> Result<Vec<RunReport>, RunError> {
    let bytes = std::fs::read(&up.model).map_err(|e| input(&up.model, format!("cannot read: {e}")))?;
    let model = Model::from_bytes(&bytes, "--upsample").map_err(|e| input(&up.model, e.to_string()))?;
    let coarse = coarse_run(up, opts)?;
    let stats = read_stats(&coarse.dir)?;
    // Both derived meshes carry the coarse cloth's texture coordinates (U's fine mesh was
    // embedded in its material space), in its units.
    let unit = uv_unit(&ClothOut::of(&up.coarse), 0);
    // `f` writes the derived frames into its folder and returns their node count.
    let derive = |name: &str, faces: usize, f: &dyn Fn(&Path) -> Result<usize, UpsampleRunError>| {
        let dir = opts.out_dir.join(name);
        if !opts.quiet {
            eprintln!("compare: {name} run from {} → {}", coarse.dir.display(), dir.display());
        }
        let clock = Instant::now();
        let nodes = f(&dir).map_err(|e| match e {
            UpsampleRunError::Input(m) => input(&up.model, m),
            UpsampleRunError::Output(m) => RunError::Output(m),
        })?;
        let extra_s = clock.elapsed().as_secs_f64();
        let derived = derived_stats(&stats, name, extra_s, nodes, faces, &dir, unit)?;
        write_stats(&dir, &derived)?;
        Ok::<_, RunError>(run_report(name, dir, &derived))
    };
    let (n, fine_faces) = (model.op.fine_nodes(), model.faces.len());
    let upsampled = derive("upsampled", fine_faces, &|dir| apply(&model, &coarse.dir, dir).map(|_| n))?;
    let coarse_faces = stats.frames.first().map_or(0, |f| f.faces);
    let levels = levels_to_match(coarse_faces, fine_faces);
    let looped = derive("loop", coarse_faces << (2 * levels), &|dir| subdivide(&coarse.dir, levels, dir).map(|r| r.1))?;
    Ok(vec![coarse, upsampled, looped])
}

/// The coarse shot, uniform, into `out/coarse` (a finished run there is reused).
fn coarse_run(up: &UpsampleOptions, opts: &CompareOptions) -> Result<RunReport, RunError> {
    let mut scene = up.coarse.clone();
    scene.set_remesh_mode(RemeshMode::Uniform);
    let dir = opts.out_dir.join("coarse");
    if let Some(stats) = finished_run(&dir, &scene, opts.frames.unwrap_or(scene.frames)) {
        if !opts.quiet {
            eprintln!("compare: coarse: reusing the finished run in {}", dir.display());
        }
        return Ok(run_report("coarse", dir, &stats));
    }
    if !opts.quiet {
        eprintln!("compare: coarse run → {}", dir.display());
    }
    let run_opts = RunOptions { out_dir: dir.clone(), frames: opts.frames, quiet: opts.quiet, ..Default::default() };
    let progress = Progress { label: Some("coarse run".into()), ..Progress::new(opts.progress) };
    let stats = run_shot(scene, &run_opts, None, &progress)?;
    Ok(run_report("coarse", dir, &stats))
}

/// The coarse run's stats with the derived run's mesh, the strain of its frames in `dir` (their
/// texture coordinates in units of `unit` metres) and its extra time spread over the frames;
/// no energies (`FrameStats::kinetic_energy`).
fn derived_stats(
    coarse: &RunStats,
    name: &str,
    extra_s: f64,
    nodes: usize,
    faces: usize,
    dir: &Path,
    unit: f64,
) -> Result<RunStats, RunError> {
    let per_frame = extra_s / coarse.frames.len().max(1) as f64;
    let mut frames = Vec::with_capacity(coarse.frames.len());
    for f in &coarse.frames {
        let path = dir.join(format!("frame_{:04}.obj", f.frame));
        let strain = read_obj(&path).and_then(|obj| obj_strain(&obj, unit));
        let strain = strain.map_err(|e| RunError::Output(format!("{}: {e}", path.display())))?;
        frames.push(FrameStats {
            frame: f.frame,
            time: f.time,
            wall_s: f.wall_s + per_frame,
            nodes,
            faces,
            max_strain: strain.max,
            mean_strain: strain.mean,
            ..Default::default()
        });
    }
    Ok(RunStats {
        scene: coarse.scene.clone(),
        mode: name.into(),
        stages: vec!["coarse run".into(), name.into()],
        total_wall_s: coarse.total_wall_s + extra_s,
        frames,
        ..Default::default()
    })
}

fn write_stats(dir: &Path, stats: &RunStats) -> Result<(), RunError> {
    let path = dir.join("stats.json");
    let json =
        serde_json::to_string_pretty(stats).map_err(|e| RunError::Io { path: path.clone(), source: e.into() })?;
    crate::io::write_atomic(&path, json.as_bytes()).map_err(|source| RunError::Io { path, source })
}

fn input(file: &Path, msg: String) -> RunError {
    RunError::Input(InputError { file: file.to_path_buf(), location: None, msg })
}
