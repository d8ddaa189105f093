//! Adaptive vs uniform on one shot, same frames, one run (issue 4 benchmark):
//!
//!     cargo run --release --example bench_modes -- [SCENE] [FRAMES]
//!
//! Prints wall time of each mode, their ratio, the remeshing share (sizing + remesh stages) of
//! the adaptive run's frame time, and the face count over time, as Markdown.

use std::path::{Path, PathBuf};

use viewcloth::io::stats::RunStats;
use viewcloth::scene::{self, RemeshMode};
use viewcloth::sim::{run, RunOptions};

fn simulate(scene_path: &Path, mode: RemeshMode, frames: usize) -> RunStats {
    let mut scene = scene::load_file(scene_path).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.set_remesh_mode(mode) > 0, "the scene has no remesh block");
    let out_dir = std::env::temp_dir().join(format!("viewcloth_bench_modes_{mode:?}"));
    let opts = RunOptions { out_dir, frames: Some(frames), quiet: true, export_obstacles: false, jitter: None };
    run(scene, &opts).unwrap_or_else(|e| panic!("{e}"))
}

fn stage_total(s: &RunStats, names: &[&str]) -> f64 {
    s.frames.iter().flat_map(|f| f.stage_s.iter()).filter(|(k, _)| names.contains(&k.as_str())).map(|(_, v)| v).sum()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene_path = PathBuf::from(args.get(1).cloned().unwrap_or_else(|| "scenes/sheet_on_sphere.json".into()));
    let frames: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(40);
    let adaptive = simulate(&scene_path, RemeshMode::Adaptive, frames);
    let uniform = simulate(&scene_path, RemeshMode::Uniform, frames);
    let frame_time = |s: &RunStats| s.frames.iter().skip(1).map(|f| f.wall_s).sum::<f64>();
    let mean_faces = |s: &RunStats| s.frames.iter().map(|f| f.faces as f64).sum::<f64>() / s.frames.len() as f64;
    let (ta, tu) = (frame_time(&adaptive), frame_time(&uniform));
    let remesh = stage_total(&adaptive, &["sizing", "remesh"]);
    println!("scene `{}`, {frames} frames\n", scene_path.display());
    println!("| mode | wall s (frames 1..) | s/frame | mean faces | remeshing share |");
    println!("|---|---|---|---|---|");
    println!(
        "| adaptive | {ta:.1} | {:.3} | {:.0} | {:.1}% |",
        ta / frames as f64,
        mean_faces(&adaptive),
        100.0 * remesh / ta
    );
    println!("| uniform | {tu:.1} | {:.3} | {:.0} | – |", tu / frames as f64, mean_faces(&uniform));
    println!(
        "\nuniform / adaptive wall time: {:.2}×; faces {:.2}×\n",
        tu / ta,
        mean_faces(&uniform) / mean_faces(&adaptive)
    );
    println!("| frame | adaptive faces | adaptive s | uniform s |");
    println!("|---|---|---|---|");
    for (a, u) in adaptive.frames.iter().zip(&uniform.frames).step_by(5) {
        println!("| {} | {} | {:.3} | {:.3} |", a.frame, a.faces, a.wall_s, u.wall_s);
    }
    let mut stages: Vec<(String, f64)> = Vec::new();
    for f in &adaptive.frames {
        for (k, v) in &f.stage_s {
            match stages.iter_mut().find(|(n, _)| n == k) {
                Some(e) => e.1 += v,
                None => stages.push((k.clone(), *v)),
            }
        }
    }
    stages.sort_by(|a, b| b.1.total_cmp(&a.1));
    println!(
        "\nadaptive stage shares: {}",
        stages.iter().map(|(k, v)| format!("{k} {:.0}%", 100.0 * v / ta)).collect::<Vec<_>>().join(", ")
    );
}
