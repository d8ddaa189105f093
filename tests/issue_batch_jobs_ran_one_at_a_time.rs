//! `viewcloth batch --jobs 2` ran its shots one after another (fixed in cd15bdf): each worker
//! popped the queue in a `while let` over the lock's guard, which held the lock across the shot.
//! Two equal shots run two at a time take about as long as one of them, not as long as both.

use std::path::Path;
use std::time::Instant;

mod common;

use common::{temp_dir, viewcloth};

#[test]
fn two_jobs_run_two_shots_at_once() {
    let dir = temp_dir("shots");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/flag_wind.json");
    let shots = format!(
        r#"{{ "version": 1, "shots": [
  {{ "scene": "{0}", "frames": 6, "out": "a" }},
  {{ "scene": "{0}", "frames": 6, "out": "b" }}
] }}"#,
        scene.display()
    );
    let file = dir.join("shots.json");
    std::fs::write(&file, shots).unwrap();
    let summary = dir.join("summary.json");
    let args = ["batch", file.to_str().unwrap(), "--jobs", "2", "--threads", "1", "--quiet"];
    let started = Instant::now();
    let o = viewcloth(&[&args[..], &["--summary", summary.to_str().unwrap()]].concat());
    let elapsed = started.elapsed().as_secs_f64();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    let walls: Vec<f64> = s["shots"].as_array().unwrap().iter().map(|r| r["wall_s"].as_f64().unwrap()).collect();
    let both: f64 = walls.iter().sum();
    // One after the other, the command takes at least the sum of the shots' times; at once, about
    // half of it (each shot's own time spans the time they share, on a loaded machine too).
    assert!(elapsed < 0.8 * both, "batch took {elapsed:.2} s for shots of {walls:?} s: they did not overlap");
}
