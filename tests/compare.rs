//! `viewcloth compare` (DESIGN.md "Error against run time") on a small hanging sheet: the report
//! has the reference, three independent floor runs with their band, and every mode with
//! per-frame errors and a verdict per measure that follows from the band; a run identical to the
//! reference measures exactly zero in every measure and frame while the perturbed floors do not;
//! the view mode, whose camera sees half the sheet, uses fewer faces than adaptive; without a
//! camera the command is refused in one line. With `--upsample`, the derived runs' stats.json
//! carry their frames' strain and no energies, and `upsample trace` writes `simulate`'s
//! stats.json for both its runs.

use std::path::{Path, PathBuf};

mod common;
use common::{check_stats_strain, temp_dir, viewcloth};

use serde_json::Value;

/// A 1 m sheet pinned at two corners, coarse enough that the uniform reference is cheap, and a
/// camera looking at its right half from 1.5 m.
fn shot(dir: &Path) -> PathBuf {
    let scene = r#"{
  "version": 1,
  "frame_time": 0.04,
  "steps_per_frame": 4,
  "frames": 12,
  "camera": "camera.json",
  "cloths": [{
    "rectangle": { "width": 1.0, "height": 1.0, "resolution": [6, 6] },
    "transform": { "translate": [-0.5, -1.0, 0.5] },
    "material": { "preset": "cotton" },
    "remesh": { "refine_angle": 0.3, "refine_compression": 0.01, "refine_velocity": 1.0, "size": [0.04, 0.3] },
    "handles": [{ "nodes": [42, 48] }]
  }],
  "collision": { "self_collision": false }
}"#;
    let camera = r#"{
  "version": 1,
  "keys": [{ "time": 0, "position": [0.25, -1.5, 0.2], "target": [0.25, 0.0, 0.0], "fov": 25 }]
}"#;
    std::fs::write(dir.join("camera.json"), camera).unwrap();
    let file = dir.join("shot.json");
    std::fs::write(&file, scene).unwrap();
    file
}

fn compare(args: &[&str]) -> Value {
    let o = viewcloth(args);
    assert!(o.status.success(), "compare {args:?}: {}", String::from_utf8_lossy(&o.stderr));
    let out = args.iter().position(|a| *a == "--out").map(|i| PathBuf::from(args[i + 1])).unwrap();
    assert!(std::fs::read_to_string(out.join("compare.md")).unwrap().contains("| reference |"));
    for svg in ["compare.svg", "compare_frames_normal_deg.svg", "compare_frames_distance_mean.svg"] {
        assert!(std::fs::read_to_string(out.join(svg)).unwrap().starts_with("<svg"), "{svg}");
    }
    serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap()).unwrap()
}

fn err(run: &Value, field: &str, measure: &str) -> f64 {
    run["errors"][field][measure].as_f64().unwrap()
}

#[test]
fn compare_reports_errors_against_time_with_a_chaos_floor() {
    let dir = temp_dir("shot");
    let scene = shot(&dir);
    let out = dir.join("out");
    let r =
        compare(&["compare", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--size", "320x180", "--quiet"]);
    assert_eq!(r["frames"], 12);
    let modes = r["modes"].as_array().unwrap();
    let names: Vec<&str> = modes.iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["adaptive", "view"]);
    let floors = r["floors"].as_array().unwrap();
    let floor_names: Vec<&str> = floors.iter().map(|f| f["name"].as_str().unwrap()).collect();
    assert_eq!(floor_names, ["floor_1", "floor_2", "floor_3"], "three floor runs by default");
    for run in modes.iter().chain(floors) {
        assert!(run["wall_s"].as_f64().unwrap() > 0.0);
        assert_eq!(run["errors"]["frames_compared"], 12);
        assert_eq!(run["errors"]["per_frame"].as_array().unwrap().len(), 12);
    }
    // Independent jitters: the floor runs differ from each other, and a 1 µm perturbation grows
    // but stays far below a centimetre on this calm shot.
    let floor_means: Vec<f64> = floors.iter().map(|f| err(f, "geometric", "mean")).collect();
    assert!(floor_means.iter().all(|&m| m > 0.0 && m < 0.01), "{floor_means:?}");
    assert!(floor_means[0] != floor_means[1] && floor_means[1] != floor_means[2], "{floor_means:?}");
    // The band is the floor runs' mean and spread, and every mode's verdict follows from it.
    let band = &r["floor_band"];
    assert_eq!(band["runs"], 3);
    let measures = band["measures"].as_array().unwrap();
    let distance = measures.iter().find(|m| m["measure"] == "distance_mean").unwrap();
    let mean = floor_means.iter().sum::<f64>() / 3.0;
    let std = (floor_means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
    assert!((distance["mean"].as_f64().unwrap() - mean).abs() < 1e-12 * mean, "{distance}");
    assert!((distance["std"].as_f64().unwrap() - std).abs() < 1e-9 * mean, "{distance}");
    for mode in modes {
        let verdicts = mode["verdicts"].as_array().unwrap();
        assert_eq!(verdicts.len(), measures.len(), "a verdict for every measure");
        for (v, b) in verdicts.iter().zip(measures) {
            let (e, mu, sd) = (v["error"].as_f64().unwrap(), b["mean"].as_f64().unwrap(), b["std"].as_f64().unwrap());
            assert_eq!(v["within"].as_bool().unwrap(), e <= mu + 2.0 * sd, "{v} against {b}");
            if mu > 0.0 {
                assert!((v["multiple"].as_f64().unwrap() - e / mu).abs() < 1e-9 * (e / mu), "{v}");
            }
        }
    }
    // Strips for the first, middle and last compared frames: reference | run | heat map.
    for f in [1, 6, 12] {
        let png = std::fs::read(out.join("adaptive").join(format!("strip_{f:04}.png"))).unwrap();
        // IHDR: width and height, big-endian, at bytes 16..24.
        assert_eq!(png[16..24], [0, 0, 3, 192, 0, 0, 0, 180], "960 × 180");
    }
    let md = std::fs::read_to_string(out.join("compare.md")).unwrap();
    assert!(md.contains("| floor |") && md.contains("| adaptive |"), "{md}");
    // Run again into the same folder: every finished run is reused, not re-simulated.
    let o = viewcloth(&["compare", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--size", "320x180"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let log = String::from_utf8_lossy(&o.stderr);
    for name in ["reference", "floor_1", "floor_2", "floor_3", "adaptive", "view"] {
        assert!(log.contains(&format!("compare: {name}: reusing the finished run")), "{name}: {log}");
    }
    assert!(!log.contains(" run → "), "nothing simulated: {log}");
    let again: Value = serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap()).unwrap();
    assert_eq!(again["reference"]["wall_s"], r["reference"]["wall_s"]);
    assert_eq!(again["modes"], r["modes"], "same runs, same errors");

    // The reference against a deterministic re-run of itself: exactly zero.
    let same = dir.join("same");
    let reference = out.join("reference");
    let r = compare(&[
        "compare",
        scene.to_str().unwrap(),
        "--out",
        same.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
        "--modes",
        "uniform",
        "--sweep",
        "--size",
        "320x180",
        "--quiet",
    ]);
    // The sweep: uniform meshes at 2x and 4x the minimum edge, about 4x fewer faces each, with
    // an error.
    let names: Vec<&str> = r["modes"].as_array().unwrap().iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["uniform", "uniform_2x", "uniform_4x"]);
    let faces: Vec<f64> = r["modes"].as_array().unwrap().iter().map(|m| m["mean_faces"].as_f64().unwrap()).collect();
    assert!((2.5..6.0).contains(&(faces[0] / faces[1])) && (2.5..6.0).contains(&(faces[1] / faces[2])), "{faces:?}");
    assert!(err(&r["modes"][2], "geometric", "mean") > err(&r["modes"][1], "geometric", "mean"), "{r}");
    assert!(err(&r["modes"][1], "geometric", "mean") > 0.0);
    assert_eq!(r["floors"].as_array().unwrap().len(), 0, "no floor with a given reference");
    assert!(r["floor_band"].is_null());
    let run = &r["modes"][0];
    // Identical frames: every measure exactly zero, in every frame.
    assert_every_error_is_zero(run);
}

/// Every measure of `run`, mean and per frame, is exactly 0.
fn assert_every_error_is_zero(run: &Value) {
    let e = &run["errors"];
    let frames = e["per_frame"].as_array().unwrap();
    assert!(!frames.is_empty());
    for set in [e].into_iter().chain(frames) {
        for m in ["normal_deg", "normal_flat_deg", "silhouette", "depth"] {
            assert_eq!(set["visible"][m].as_f64(), Some(0.0), "visible.{m}: {set}");
        }
        for field in ["geometric", "geometric_visible"] {
            for m in ["mean", "rms", "p95", "max"] {
                assert_eq!(set[field][m].as_f64(), Some(0.0), "{field}.{m}: {set}");
            }
        }
    }
}

#[test]
fn compare_without_a_camera_is_refused_in_one_line() {
    let dir = temp_dir("no_camera");
    let scene = shot(&dir);
    let text = std::fs::read_to_string(&scene).unwrap().replace("  \"camera\": \"camera.json\",\n", "");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let o = viewcloth(&["compare", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("camera"), "{e}");
    let o = viewcloth(&["compare", scene.to_str().unwrap(), "--size", "wide", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--size"));
}

/// The shot's sheet on a uniform `cells` × `cells` mesh (no remesh block), held at the same
/// two corners.
fn uniform_shot(dir: &Path, cells: usize) -> PathBuf {
    let text = std::fs::read_to_string(shot(dir)).unwrap();
    let remesh = text.lines().find(|l| l.contains("\"remesh\"")).unwrap().to_owned() + "\n";
    let (left, right) = (cells * (cells + 1), (cells + 1) * (cells + 1) - 1);
    let text = text
        .replace(&remesh, "")
        .replace("[6, 6]", &format!("[{cells}, {cells}]"))
        .replace("[42, 48]", &format!("[{left}, {right}]"));
    let file = dir.join(format!("uniform_{cells}.json"));
    std::fs::write(&file, text).unwrap();
    file
}

/// `--upsample MODEL --coarse SCENE` adds a uniform coarse run, its upsampling by the model and
/// its Loop subdivision as modes, each timed as the coarse run plus its own pass; a coarse
/// scene on another mesh than the model's is refused in one line that says why.
#[test]
fn compare_measures_upsampled_and_loop_runs_beside_the_modes() {
    let dir = temp_dir("upsample");
    let [coarse, fine] = [3, 12].map(|n| uniform_shot(&dir, n));
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let (pair, model) = (dir.join("pair"), dir.join("model.bin"));
    let (pc, pf, m) = (s(&pair.join("coarse")), s(&pair.join("fine")), s(&model));
    for args in [
        vec!["upsample", "trace", &s(&coarse), &s(&fine), "--test-functions", "10", "--out", &s(&pair)],
        vec!["upsample", "train", "--coarse", &pc, "--fine", &pf, "--gamma1", "0.01", "--gammaN", "10", "--out", &m],
    ] {
        let o = viewcloth(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    // `trace` writes `simulate`'s stats.json for both runs: initial state and 12 frames.
    for (run, mode) in [("coarse", "uniform"), ("fine", "tracked")] {
        // Cotton on a 1 m sheet hanging from two corners: a few % at most.
        let stats = check_stats_strain(&pair.join(run), 13, (0.1, 0.02));
        assert_eq!(stats["mode"], mode);
        let last = &stats["frames"][12];
        assert!(last["total_energy"].as_f64().is_some() && last["steps"] == 4, "{run}: {last}");
        assert_eq!(last["stage_s"]["tracking"].is_number(), run == "fine", "{run}: {last}");
    }
    let out = dir.join("out");
    let base = ["compare", &s(&shot(&dir)), "--modes", "adaptive", "--no-floor", "--size", "160x90", "--quiet"];
    let r = compare(&[&base[..], &["--out", &s(&out), "--upsample", &s(&model), "--coarse", &s(&coarse)]].concat());
    let modes = r["modes"].as_array().unwrap();
    let names: Vec<&str> = modes.iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["adaptive", "coarse", "upsampled", "loop"]);
    let faces: Vec<f64> = modes[1..].iter().map(|m| m["mean_faces"].as_f64().unwrap()).collect();
    // 3 × 3 cells: 18 faces; the model's 12 × 12: 288; two Loop levels: 18 · 16 = 288.
    assert_eq!(faces, [18.0, 288.0, 288.0]);
    let wall = |k: usize| modes[k]["wall_s"].as_f64().unwrap();
    assert!(wall(2) > wall(1) && wall(3) > wall(1), "derived runs cost the coarse run and more");
    for m in modes {
        assert_eq!(m["errors"]["frames_compared"], 12, "{}", m["name"]);
        assert!(err(m, "geometric", "mean") > 0.0 && err(m, "geometric", "mean") < 0.1, "{}", m["name"]);
    }
    assert!(std::fs::read_to_string(out.join("compare.md")).unwrap().contains("| upsampled |"));
    // The derived runs' stats: the strain of their own frames against the material coordinates
    // they carry; no energies (no velocities). Loop moves points along the surface away from
    // their (linearly subdivided) material coordinates, at the irregular nodes of this 3 × 3 mesh
    // by tens of % (0.53 max at frame 0; README, `compare`), so its bound is loose.
    for (run, bound) in [("upsampled", (0.15, 0.05)), ("loop", (1.0, 0.3))] {
        let stats = check_stats_strain(&out.join(run), 13, bound);
        for f in stats["frames"].as_array().unwrap() {
            assert!(f.get("kinetic_energy").is_none() && f.get("total_energy").is_none(), "{run}: {f}");
        }
    }
    // The model applied to a run on another coarse mesh.
    let other = uniform_shot(&dir, 4);
    let bad = dir.join("bad");
    let o = viewcloth(&[&base[..], &["--out", &s(&bad), "--upsample", &s(&model), "--coarse", &s(&other)]].concat());
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("25 nodes, the model was trained on 16") && e.contains("an adaptive run?"), "{e}");
}
