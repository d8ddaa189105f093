//! Issue 19, item 4: buckling compensation (`forces::buckling`) in whole runs. A sheet hanging
//! from two corners that close in while the camera looks away, so view-dependent sizing keeps
//! it coarse: with compensation the coarsened, compressed faces carry a slack (their compressive
//! stress is reduced, the run differs from one without), the result does not depend on the
//! thread count, and a resumed run matches an uninterrupted one (κ is in the checkpoint, the
//! slack is a function of the state).

use std::path::{Path, PathBuf};

mod common;

use common::{temp_dir, viewcloth};
use serde_json::{json, Value};

fn squeeze(dir: &Path, compensation: bool) -> PathBuf {
    let cam = json!({ "version": 1, "aspect": 1.7778, "near": 0.05, "far": 100.0,
        "keys": [{ "time": 0.0, "position": [0, -3, 0.5], "target": [0, -6, 0.5], "fov": 30 }] });
    std::fs::write(dir.join("away.json"), cam.to_string()).unwrap();
    let scene = json!({
        "version": 1, "frame_time": 0.04, "steps_per_frame": 5, "frames": 12, "camera": "away.json",
        "collision": { "self_collision": true },
        "cloths": [{
            "rectangle": { "width": 1.0, "height": 1.0, "resolution": [10, 10] },
            "transform": { "rotate": [90, 1, 0, 0], "translate": [-0.5, 0, 0] },
            "material": { "preset": "cotton" },
            "handles": [
                { "nodes": [110], "motion": [{ "time": 0, "translate": [0, 0, 0] }, { "time": 1, "translate": [0.35, 0, 0] }] },
                { "nodes": [120], "motion": [{ "time": 0, "translate": [0, 0, 0] }, { "time": 1, "translate": [-0.35, 0, 0] }] }
            ],
            "remesh": {
                "mode": "view", "refine_angle": 0.3, "refine_compression": 0.005, "refine_velocity": 0.5,
                "size": [0.01, 0.2], "aspect_min": 0.2, "view": { "buckling_compensation": compensation }
            }
        }]
    });
    let file = dir.join(format!("squeeze_{compensation}.json"));
    std::fs::write(&file, scene.to_string()).unwrap();
    file
}

fn simulate(scene: &Path, out: &Path, extra: &[&str]) -> Value {
    let mut args = vec!["simulate", scene.to_str().unwrap(), "--quiet", "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = viewcloth(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap()
}

fn frame(dir: &Path, f: usize) -> Vec<u8> {
    std::fs::read(dir.join(format!("frame_{f:04}.obj"))).unwrap()
}

#[test]
fn compensation_acts_on_coarse_compressed_cloth_and_is_deterministic() {
    let dir = temp_dir("squeeze");
    let (on, off) = (squeeze(&dir, true), squeeze(&dir, false));
    let a = simulate(&on, &dir.join("on1"), &["--threads", "1"]);
    simulate(&on, &dir.join("on2"), &["--threads", "2"]);
    let b = simulate(&off, &dir.join("off"), &["--threads", "1"]);
    let stages =
        |s: &Value| s["stages"].as_array().unwrap().iter().map(|x| x.as_str().unwrap().to_string()).collect::<Vec<_>>();
    assert!(stages(&a).iter().any(|s| s == "buckling"), "{:?}", stages(&a));
    assert!(!stages(&b).iter().any(|s| s == "buckling"), "off: no buckling stage {:?}", stages(&b));
    assert!(frame(&dir.join("on1"), 12) != frame(&dir.join("off"), 12), "compensation changed nothing");
    for f in 0..=12 {
        assert!(frame(&dir.join("on1"), f) == frame(&dir.join("on2"), f), "frame {f} differs between 1 and 2 threads");
    }
    let crossings =
        |s: &Value| s["frames"].as_array().unwrap().iter().map(|f| f["crossings_self"].as_u64().unwrap()).max();
    assert_eq!(crossings(&a), Some(0));
}

#[test]
fn a_resumed_run_with_compensation_matches_an_uninterrupted_one() {
    let dir = temp_dir("resume");
    let scene = squeeze(&dir, true);
    let whole = dir.join("whole");
    simulate(&scene, &whole, &["--frames", "10", "--threads", "1"]);
    let parts = dir.join("parts");
    simulate(&scene, &parts, &["--frames", "5", "--threads", "1", "--checkpoint-every", "5"]);
    let o = viewcloth(&["resume", parts.to_str().unwrap(), "--frames", "10", "--quiet", "--threads", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in 6..=10 {
        assert!(frame(&whole, f) == frame(&parts, f), "frame {f} differs after the resume");
    }
}
