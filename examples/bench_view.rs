//! View-dependent vs adaptive on one shot, same frames, one run:
//!
//!     cargo run --release --example bench_view -- [SCENE] [CAMERA] [FRAMES]
//!
//! Prints, per mode, the wall time of frames 1.., mean faces, the share of the view-factor
//! stage, and the mean material-space face area inside and outside the camera's frame at the
//! last frame (how much finer the mesh is where the camera looks), as Markdown.

use std::path::{Path, PathBuf};

use viewcloth::camera::Camera;
use viewcloth::io::obj::read_obj;
use viewcloth::io::stats::RunStats;
use viewcloth::scene::{self, RemeshMode};
use viewcloth::sim::{run, RunOptions};

fn simulate(scene_path: &Path, camera: &Camera, mode: RemeshMode, frames: usize) -> (RunStats, PathBuf) {
    let mut scene = scene::load_file(scene_path).unwrap_or_else(|e| panic!("{e}"));
    scene.camera = Some(camera.clone());
    assert!(scene.set_remesh_mode(mode) > 0, "the scene has no remesh block");
    let out_dir = std::env::temp_dir().join(format!("viewcloth_bench_view_{mode:?}"));
    let opts = RunOptions {
        out_dir: out_dir.clone(),
        frames: Some(frames),
        quiet: true,
        export_obstacles: false,
        jitter: None,
    };
    (run(scene, &opts).unwrap_or_else(|e| panic!("{e}")), out_dir)
}

/// Mean material-space face area inside the frustum and beyond its margin at the last frame.
fn areas_in_and_out(dir: &Path, s: &RunStats, camera: &Camera) -> (f64, f64) {
    let Some(last) = s.frames.last() else { return (f64::NAN, f64::NAN) };
    let obj = read_obj(&dir.join(format!("frame_{:04}.obj", last.frame))).unwrap_or_else(|e| panic!("{e:?}"));
    let view = camera.view_at(last.time);
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    for tri in &obj.triangles {
        let (Some(a), Some(b), Some(c)) = (tri[0].vt, tri[1].vt, tri[2].vt) else { continue };
        let (a, b, c) = (obj.texcoords[a], obj.texcoords[b], obj.texcoords[c]);
        let area = 0.5 * (b - a).perp(&(c - a)).abs();
        let x = tri.map(|k| obj.positions[k.v]);
        let d = view.frustum_distance(&((x[0] + x[1] + x[2]) / 3.0));
        if d < 0.0 {
            inside.push(area);
        } else if d > 0.2 {
            outside.push(area);
        }
    }
    let mean = |v: &[f64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 };
    (mean(&inside), mean(&outside))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene_path = PathBuf::from(args.get(1).cloned().unwrap_or_else(|| "scenes/sheet_on_sphere.json".into()));
    let camera_path = PathBuf::from(args.get(2).cloned().unwrap_or_else(|| "cameras/sheet_on_sphere_pan.json".into()));
    let frames: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(40);
    let camera = Camera::load(&camera_path).unwrap_or_else(|e| panic!("{e}"));
    println!("scene `{}`, camera `{}`, {frames} frames\n", scene_path.display(), camera_path.display());
    println!(
        "| mode | wall s (frames 1..) | s/frame | mean faces | view stage | face area in frame | beyond the margin |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    let mut times = Vec::new();
    for mode in [RemeshMode::Adaptive, RemeshMode::View] {
        let (s, dir) = simulate(&scene_path, &camera, mode, frames);
        let wall: f64 = s.frames.iter().skip(1).map(|f| f.wall_s).sum();
        let faces = s.frames.iter().map(|f| f.faces as f64).sum::<f64>() / s.frames.len() as f64;
        let view: f64 = s.frames.iter().filter_map(|f| f.stage_s.get("view")).sum::<f64>() + 0.0;
        let (ai, ao) = areas_in_and_out(&dir, &s, &camera);
        println!(
            "| {mode:?} | {wall:.1} | {:.3} | {faces:.0} | {:.1}% | {:.2} cm² | {:.2} cm² |",
            wall / frames as f64,
            100.0 * view / wall,
            ai * 1e4,
            ao * 1e4
        );
        times.push((wall, faces));
    }
    println!("\nadaptive / view: wall time {:.2}×, faces {:.2}×", times[0].0 / times[1].0, times[0].1 / times[1].1);
}
