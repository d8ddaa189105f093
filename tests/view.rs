//! View-dependent remeshing (Koh et al. 2014) in whole runs: with a camera panning across the
//! sphere shot, the mesh is finer where the camera looks than where it does not, the run uses
//! fewer faces than plain adaptive remeshing without penetrating, results do not depend on the
//! thread count, a resumed run matches an uninterrupted one, and a run without a camera does no
//! view work (and `--mode view` without one is refused).

use std::path::{Path, PathBuf};

mod common;

use common::{temp_dir, viewcloth};
use serde_json::Value;
use viewcloth::camera::Camera;
use viewcloth::io::obj::read_obj;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn scene() -> PathBuf {
    root().join("scenes/sheet_on_sphere.json")
}

fn camera() -> PathBuf {
    root().join("cameras/sheet_on_sphere_pan.json")
}

fn simulate(out: &Path, extra: &[&str]) -> Value {
    let scene = scene();
    let mut args = vec!["simulate", scene.to_str().unwrap(), "--quiet", "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = viewcloth(&args);
    assert!(o.status.success(), "viewcloth {args:?}: {}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap()
}

fn faces(stats: &Value) -> Vec<f64> {
    stats["frames"].as_array().unwrap().iter().map(|f| f["faces"].as_f64().unwrap()).collect()
}

fn stages(stats: &Value) -> Vec<String> {
    stats["stages"].as_array().unwrap().iter().map(|s| s.as_str().unwrap().to_string()).collect()
}

#[test]
fn the_mesh_follows_the_camera_and_costs_fewer_faces_than_adaptive() {
    let frames = "40";
    let cam_file = camera();
    let pan = temp_dir("pan");
    let view = simulate(&pan, &["--frames", frames, "--camera", cam_file.to_str().unwrap()]);
    let adaptive = simulate(&temp_dir("adaptive"), &["--frames", frames]);
    assert_eq!(view["mode"], "view");
    assert!(stages(&view).iter().any(|s| s == "view"), "{:?}", stages(&view));
    assert!(!stages(&adaptive).iter().any(|s| s == "view"), "no camera, no view factors: {:?}", stages(&adaptive));
    let fr = view["frames"].as_array().unwrap();
    assert!(fr.iter().all(|f| f["penetrations"].as_u64() == Some(0)), "view run penetrated");
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (fv, fa) = (mean(&faces(&view)), mean(&faces(&adaptive)));
    assert!(fv < 0.8 * fa, "view mean faces {fv} vs adaptive {fa}");

    // Where the camera looks at the last frame, faces are smaller (in material space) than
    // where it does not.
    let cam = Camera::load(&cam_file).unwrap();
    let t = fr.last().unwrap()["time"].as_f64().unwrap();
    let v = cam.view_at(t);
    let obj = read_obj(&pan.join(format!("frame_{frames:0>4}.obj"))).unwrap();
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    for tri in &obj.triangles {
        let x = tri.map(|c| obj.positions[c.v]);
        let Some(uv) = tri.iter().map(|c| c.vt.map(|k| obj.texcoords[k])).collect::<Option<Vec<_>>>() else {
            panic!("frame without material coordinates")
        };
        let area = 0.5 * ((uv[1] - uv[0]).perp(&(uv[2] - uv[0]))).abs();
        let centroid = (x[0] + x[1] + x[2]) / 3.0;
        if v.frustum_distance(&centroid) < 0.0 {
            inside.push(area);
        } else if v.frustum_distance(&centroid) > 0.2 {
            outside.push(area);
        }
    }
    assert!(!inside.is_empty() && !outside.is_empty(), "{} faces in frame, {} out", inside.len(), outside.len());
    let (ai, ao) = (mean(&inside), mean(&outside));
    assert!(ao > 2.0 * ai, "mean face area out of frame {ao} vs in frame {ai}");
}

#[test]
fn view_mode_gives_the_same_bits_on_one_and_two_threads() {
    let cam = camera();
    let cam = cam.to_str().unwrap();
    let a = temp_dir("t1");
    let b = temp_dir("t2");
    simulate(&a, &["--frames", "6", "--camera", cam, "--threads", "1"]);
    simulate(&b, &["--frames", "6", "--camera", cam, "--threads", "2"]);
    for f in 0..=6 {
        let name = format!("frame_{f:04}.obj");
        assert!(std::fs::read(a.join(&name)).unwrap() == std::fs::read(b.join(&name)).unwrap(), "{name} differs");
    }
}

#[test]
fn a_resumed_view_run_matches_an_uninterrupted_one() {
    let cam = camera();
    let cam = cam.to_str().unwrap();
    let whole = temp_dir("whole");
    simulate(&whole, &["--frames", "6", "--camera", cam]);
    let parts = temp_dir("parts");
    simulate(&parts, &["--frames", "3", "--camera", cam, "--checkpoint-every", "3"]);
    let o = viewcloth(&["resume", parts.to_str().unwrap(), "--frames", "6", "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in 4..=6 {
        let name = format!("frame_{f:04}.obj");
        assert!(
            std::fs::read(whole.join(&name)).unwrap() == std::fs::read(parts.join(&name)).unwrap(),
            "{name} differs"
        );
    }
}

#[test]
fn check_validates_camera_files() {
    let cam = camera();
    let o = viewcloth(&["check", cam.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dir = temp_dir("bad_camera");
    let bad = dir.join("cam.json");
    let text = std::fs::read_to_string(&cam).unwrap().replacen("\"fov\": 25", "\"fov\": 180", 1);
    std::fs::write(&bad, text).unwrap();
    let o = viewcloth(&["check", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("keys[0].fov"), "{err}");
}

#[test]
fn view_mode_without_a_camera_is_refused_in_one_line() {
    let out = temp_dir("no_camera").join("out");
    let scene = scene();
    let o = viewcloth(&["simulate", scene.to_str().unwrap(), "--mode", "view", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("--camera"), "{err}");
    assert!(!out.exists(), "nothing is written");

    // The same from a scene file that asks for view mode.
    let dir = temp_dir("scene_mode");
    let text = std::fs::read_to_string(&scene).unwrap().replace("\"mode\": \"adaptive\"", "\"mode\": \"view\"");
    let file = dir.join("scene.json");
    std::fs::write(&file, text).unwrap();
    let o = viewcloth(&["check", file.to_str().unwrap()]);
    let o2 = viewcloth(&["simulate", file.to_str().unwrap(), "--out", dir.join("out").to_str().unwrap()]);
    assert!(o.status.success(), "the scene itself is valid: {}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(o2.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o2.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("cloths[0].remesh.mode") && err.contains("camera"), "{err}");
}

#[test]
fn view_runs_report_view_factor_and_frame_counts_per_frame_and_other_runs_do_not() {
    // Issue 19: stats.json's per-frame view fields, present only in view mode.
    let cam_file = camera();
    let view = simulate(&temp_dir("view_stats"), &["--frames", "12", "--camera", cam_file.to_str().unwrap()]);
    let mut out_seen = false;
    for f in view["frames"].as_array().unwrap() {
        let mu = f["view_mean_mu"].as_f64().expect("view_mean_mu in view mode");
        assert!(mu > 0.0 && mu <= 1.0, "mean μ {mu}");
        let (inside, outside) =
            (f["view_faces_in_frame"].as_u64().unwrap(), f["view_faces_out_of_frame"].as_u64().unwrap());
        assert_eq!(inside + outside, f["faces"].as_u64().unwrap(), "every face is in or out of frame");
        out_seen |= outside > 0;
    }
    assert!(out_seen, "the pan leaves part of the sheet out of frame");
    let adaptive = simulate(&temp_dir("adaptive_stats"), &["--frames", "2"]);
    assert!(adaptive["frames"][1].get("view_mean_mu").is_none());
}
