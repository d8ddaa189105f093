//! `viewcloth batch`: shots from one list run two at a time give the same frames as `simulate`
//! (bit for bit); the summary lists every shot; a bad shot is refused before anything runs.

use std::path::Path;

mod common;
use common::{temp_dir, viewcloth};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn shots_run_two_at_a_time_match_simulate_bit_for_bit() {
    let dir = temp_dir("shots");
    let scenes = root().join("scenes");
    let cameras = root().join("cameras");
    let shots = format!(
        r#"{{ "version": 1, "shots": [
  {{ "scene": "{s}/hanging_sheet.json", "frames": 4, "out": "a" }},
  {{ "scene": "{s}/sheet_on_sphere.json", "frames": 3, "out": "b", "camera": "{c}/sheet_on_sphere_pan.json" }},
  {{ "scene": "{s}/crumple_square.json", "frames": 2, "out": "c", "mode": "uniform" }}
] }}"#,
        s = scenes.display(),
        c = cameras.display()
    );
    let file = dir.join("shots.json");
    std::fs::write(&file, shots).unwrap();
    let summary = dir.join("summary.json");
    let o = viewcloth(&["batch", file.to_str().unwrap(), "--jobs", "2", "--summary", summary.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    assert_eq!(s["failed"], 0);
    let frames: Vec<u64> = s["shots"].as_array().unwrap().iter().map(|r| r["frames"].as_u64().unwrap()).collect();
    assert_eq!(frames, [4, 3, 2], "results in the shots' order");

    // The same shots one by one through `simulate`.
    let cases: [(&str, &str, &[&str], usize); 3] = [
        ("hanging_sheet.json", "a", &[], 4),
        ("sheet_on_sphere.json", "b", &["--camera", "CAMERA"], 3),
        ("crumple_square.json", "c", &["--mode", "uniform"], 2),
    ];
    let camera = cameras.join("sheet_on_sphere_pan.json");
    for (scene, out, extra, n) in cases {
        let alone = dir.join(format!("{out}_alone"));
        let scene = scenes.join(scene);
        let frames = n.to_string();
        let mut args =
            vec!["simulate", scene.to_str().unwrap(), "--quiet", "--frames", &frames, "--out", alone.to_str().unwrap()];
        args.extend(extra.iter().map(|a| if *a == "CAMERA" { camera.to_str().unwrap() } else { a }));
        let o = viewcloth(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for f in 0..=n {
            let name = format!("frame_{f:04}.obj");
            let (x, y) = (std::fs::read(dir.join(out).join(&name)).unwrap(), std::fs::read(alone.join(&name)).unwrap());
            assert!(x == y, "{out}/{name} differs from simulate's");
        }
    }
}

#[test]
fn a_bad_shot_is_refused_before_anything_runs() {
    let dir = temp_dir("bad");
    let scene = root().join("scenes/hanging_sheet.json");
    let shots = format!(
        r#"{{ "version": 1, "shots": [ {{ "scene": "{}", "out": "a" }}, {{ "scene": "missing.json", "out": "b" }} ] }}"#,
        scene.display()
    );
    let file = dir.join("shots.json");
    std::fs::write(&file, shots).unwrap();
    let o = viewcloth(&["batch", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("shots[1].scene"), "{e}");
    assert!(!dir.join("a").exists(), "shot 0 must not have run");

    let dup = format!(
        r#"{{ "version": 1, "shots": [ {{ "scene": "{0}", "out": "a" }}, {{ "scene": "{0}", "out": "a" }} ] }}"#,
        scene.display()
    );
    std::fs::write(&file, dup).unwrap();
    let o = viewcloth(&["batch", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("shots[1].out"));
}
