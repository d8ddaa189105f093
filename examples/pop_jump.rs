//! The kinetic-energy jump across remeshes with and without the pop filter (issue 16, item 8),
//! both runs in one process, one after the other:
//!
//!     cargo run --release --example pop_jump -- SCENE [FRAMES]
//!
//! SCENE is a viewcloth scene or an ARCSim conf (e.g. ../shared/arcsim/conf/square.json). At
//! every frame that remeshes, the jump is the kinetic energy after the first step of the frame
//! less the kinetic energy before the remesh. Prints, per run, the sum and the largest of the
//! positive jumps, the mean faces, retried steps, the pop filter's Newton steps and its wall
//! time, as Markdown.

use std::path::{Path, PathBuf};
use std::time::Instant;

use viewcloth::math::Real;
use viewcloth::scene;
use viewcloth::sim::Simulation;

struct Tally {
    jump_sum: Real,
    jump_max: Real,
    remeshes: usize,
    faces: f64,
    retries: usize,
    pop_iterations: usize,
    pop_s: f64,
    wall_s: f64,
}

fn kinetic(sim: &Simulation) -> Real {
    sim.mesh().nodes.iter().map(|n| 0.5 * n.mass * n.v.norm_squared()).sum()
}

fn run(path: &Path, frames: usize, pop: bool) -> Tally {
    let mut scene = scene::load_file(path).unwrap_or_else(|e| panic!("{e}"));
    scene.disabled.pop_filter = !pop;
    let h = scene.time_step();
    let steps = scene.steps_per_frame;
    let clock = Instant::now();
    let mut sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{e}"));
    let mut t = Tally {
        jump_sum: 0.0,
        jump_max: 0.0,
        remeshes: 0,
        faces: 0.0,
        retries: 0,
        pop_iterations: 0,
        pop_s: 0.0,
        wall_s: 0.0,
    };
    for _ in 0..frames {
        let before = kinetic(&sim);
        let ops = |s: &Simulation| s.ws.remesh_stats.splits + s.ws.remesh_stats.collapses + s.ws.remesh_stats.flips;
        let done = ops(&sim);
        sim.begin_frame().unwrap_or_else(|e| panic!("{e}"));
        let remeshed = ops(&sim) > done;
        for k in 0..steps {
            sim.step(h).unwrap_or_else(|e| panic!("{e}"));
            if k == 0 && remeshed {
                let jump = (kinetic(&sim) - before).max(0.0);
                t.jump_sum += jump;
                t.jump_max = t.jump_max.max(jump);
                t.remeshes += 1;
            }
        }
        t.faces += sim.mesh().faces.len() as f64 / frames as f64;
        t.pop_iterations += std::mem::take(&mut sim.ws.pop).iterations;
        t.pop_s += sim.ws.timers.take().get("pop_filter").copied().unwrap_or(0.0);
        t.retries += std::mem::take(&mut sim.ws.faults).retries;
    }
    t.wall_s = clock.elapsed().as_secs_f64();
    t
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = PathBuf::from(args.get(1).expect("usage: pop_jump SCENE [FRAMES]"));
    let frames: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(325);
    println!("`{}`, {frames} frames\n", path.display());
    println!("| pop filter | remeshes | KE jump sum (J) | largest (J) | mean faces | retries | Newton steps | pop s | wall s |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for pop in [true, false] {
        let t = run(&path, frames, pop);
        println!(
            "| {} | {} | {:.3e} | {:.3e} | {:.1} | {} | {} | {:.2} | {:.1} |",
            if pop { "on" } else { "off" },
            t.remeshes,
            t.jump_sum,
            t.jump_max,
            t.faces,
            t.retries,
            t.pop_iterations,
            t.pop_s,
            t.wall_s
        );
    }
}
