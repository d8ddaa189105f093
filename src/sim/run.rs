//! Running a shot: frames out to OBJ, stats to JSON, progress to the terminal.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use crate::io::obj::{frame_obj, obstacle_obj};
use crate::io::stats::{CollisionFrameStats, RemeshFrameStats, RunStats};
use crate::scene::RemeshMode;
use crate::io::write_atomic;
use crate::scene::Scene;

use super::{SimError, Simulation};

pub struct RunOptions {
    pub out_dir: PathBuf,
    /// Overrides the scene's frame count.
    pub frames: Option<usize>,
    pub quiet: bool,
    /// Also write each obstacle's world-space mesh per frame (`obstacle_<name>_NNNN.obj`).
    pub export_obstacles: bool,
}

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Sim(#[from] SimError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

fn io_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Simulates `scene`, writing `frame_NNNN.obj` (frame 0 is the initial state) and `stats.json`
/// (rewritten after every frame, so it is valid at any instant) into `opts.out_dir`.
pub fn run(scene: Scene, opts: &RunOptions) -> Result<RunStats, RunError> {
    let started = Instant::now();
    let frames = opts.frames.unwrap_or(scene.frames);
    let names: Vec<String> = scene.cloths.iter().map(|c| c.name.clone()).collect();
    let mut sim = Simulation::new(scene)?;
    std::fs::create_dir_all(&opts.out_dir).map_err(io_err(&opts.out_dir))?;
    let digits = frames.to_string().len().max(4);
    let frame_path = |f: usize| opts.out_dir.join(format!("frame_{f:0digits$}.obj"));
    let stats_path = opts.out_dir.join("stats.json");
    let adaptive = sim.scene.cloths.iter().any(|c| c.remesh.as_ref().is_some_and(|r| r.mode == RemeshMode::Adaptive));
    let mode = if adaptive { "adaptive" } else { "uniform" };
    let mut stats = RunStats { scene: sim.scene.name.clone(), mode: mode.into(), ..Default::default() };

    let write_frame = |sim: &mut Simulation, f: usize| -> Result<(), RunError> {
        let path = frame_path(f);
        let clock = Instant::now();
        write_atomic(&path, frame_obj(&sim.mesh, &names).as_bytes()).map_err(io_err(&path))?;
        if opts.export_obstacles {
            if let Some(world) = &sim.collisions {
                for (body, obstacle) in world.bodies.iter().zip(&sim.scene.obstacles) {
                    let path = opts.out_dir.join(format!("obstacle_{}_{f:0digits$}.obj", file_safe(&obstacle.name)));
                    let text = obstacle_obj(&body.positions_at(sim.time), body.triangles());
                    write_atomic(&path, text.as_bytes()).map_err(io_err(&path))?;
                }
            }
        }
        sim.timers.add("output", clock.elapsed().as_secs_f64());
        Ok(())
    };
    let progress = (!opts.quiet && std::io::stdout().is_terminal()).then(|| {
        let bar = indicatif::ProgressBar::new(frames as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg} [{bar:40}] {pos}/{len} frames, {elapsed} elapsed, ETA {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.set_message(sim.scene.name.clone());
        bar
    });

    for f in 0..=frames {
        let clock = Instant::now();
        if f > 0 {
            sim.advance_frame()?;
        }
        write_frame(&mut sim, f)?;
        let mut fs = sim.measure(f);
        if adaptive {
            let r = std::mem::take(&mut sim.remesh_stats);
            fs.remesh = Some(RemeshFrameStats { splits: r.splits, flips: r.flips, collapses: r.collapses });
        }
        if sim.collisions.is_some() {
            let clock = Instant::now();
            let c = std::mem::take(&mut sim.counters);
            fs.collision = Some(CollisionFrameStats {
                contacts: c.contacts,
                impacts: c.impacts,
                impact_zones: c.impact_zones,
                ccd_iterations: c.ccd_iterations,
                ccd_cap_hits: c.cap_hits,
                failed_zones: c.failed_zones,
                penetrations: sim.penetrations(),
            });
            sim.timers.add("penetration_check", clock.elapsed().as_secs_f64());
        }
        fs.steps = if f > 0 { sim.scene.steps_per_frame } else { 0 };
        fs.stage_s = sim.timers.take();
        fs.wall_s = clock.elapsed().as_secs_f64();
        stats.frames.push(fs);
        stats.stages = sim.timers.ran.clone();
        stats.total_wall_s = started.elapsed().as_secs_f64();
        let json = serde_json::to_vec_pretty(&stats).map_err(|e| RunError::Io {
            path: stats_path.clone(),
            source: e.into(),
        })?;
        write_atomic(&stats_path, &json).map_err(io_err(&stats_path))?;
        if let Some(bar) = &progress {
            bar.set_position(f as u64);
        }
    }
    if let Some(bar) = progress {
        bar.finish();
    }
    Ok(stats)
}

/// A name reduced to characters safe in a file name.
fn file_safe(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}
