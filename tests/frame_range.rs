//! Issue 14: shot frame ranges and texture units. A scene's `start_frame` numbers the files
//! (`frame_1001.obj` first), stats.json and the USD time codes, and every reader of run
//! directories follows it (render, compare, resume, batch's skip of a finished shot); `preroll`
//! simulates whole frames before the first written one; output UVs are in the input's units
//! whatever `uv_scale`; bad values are refused in one line naming the file and field.

use std::path::{Path, PathBuf};

mod common;
use common::{temp_dir, viewcloth};
use serde_json::{json, Value};
use viewcloth::io::obj::parse_obj;

/// A coarse adaptive sheet pinned at two corners (no time-dependent input: handles hold
/// still), with a camera on its right half, numbered from 1001.
fn shot(dir: &Path, extra: Value) -> PathBuf {
    let mut scene = json!({
        "version": 1, "frame_time": 0.04, "steps_per_frame": 4, "frames": 3, "start_frame": 1001,
        "camera": "camera.json",
        "cloths": [{
            "rectangle": { "width": 1.0, "height": 1.0, "resolution": [6, 6] },
            "transform": { "translate": [-0.5, -1.0, 0.5] },
            "material": { "preset": "cotton" },
            "remesh": { "refine_angle": 0.3, "refine_compression": 0.01, "refine_velocity": 1.0, "size": [0.08, 0.3] },
            "handles": [{ "nodes": [42, 48] }]
        }],
        "collision": { "self_collision": false }
    });
    for (k, v) in extra.as_object().unwrap() {
        scene[k] = v.clone();
    }
    let camera = json!({ "version": 1, "keys": [{ "time": 0, "position": [0.25, -1.5, 0.2], "target": [0.25, 0.0, 0.0], "fov": 25 }] });
    std::fs::write(dir.join("camera.json"), camera.to_string()).unwrap();
    let file = dir.join("shot.json");
    std::fs::write(&file, scene.to_string()).unwrap();
    file
}

fn ok(args: &[&str]) -> String {
    let o = viewcloth(args);
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn names(dir: &Path, prefix: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(prefix))
        .collect();
    v.sort();
    v
}

#[test]
fn start_frame_numbers_files_and_every_reader_follows_it() {
    let dir = temp_dir("start_frame");
    let scene = shot(&dir, json!({}));
    let (s, run) = (scene.to_str().unwrap(), dir.join("run"));
    let o = run.to_str().unwrap();
    ok(&["simulate", s, "--out", o, "--quiet", "--format", "both", "--checkpoint-every", "2"]);
    assert_eq!(names(&run, "frame_"), ["frame_1001.obj", "frame_1002.obj", "frame_1003.obj", "frame_1004.obj"]);
    let stats: Value = serde_json::from_str(&std::fs::read_to_string(run.join("stats.json")).unwrap()).unwrap();
    let numbers: Vec<u64> = stats["frames"].as_array().unwrap().iter().map(|f| f["frame"].as_u64().unwrap()).collect();
    assert_eq!(numbers, [1001, 1002, 1003, 1004]);
    let layer = std::fs::read_to_string(run.join("cloth.usda")).unwrap();
    assert!(layer.contains("startTimeCode = 1001\n") && layer.contains("endTimeCode = 1004\n"));
    assert!(layer.contains("\n                1001: [") && !layer.contains("\n                1000: ["));

    // render: by frame number.
    let camera = dir.join("camera.json");
    ok(&[
        "render",
        o,
        "--camera",
        camera.to_str().unwrap(),
        "--size",
        "64x36",
        "--frames",
        "1002..1003",
        "--progress",
        "none",
    ]);
    assert_eq!(names(&run, "view_"), ["view_1002.png", "view_1003.png"]);
    let bad = viewcloth(&["render", o, "--camera", camera.to_str().unwrap(), "--frames", "0..2"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&bad.stderr).contains("frames 1001..1004"),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );

    // resume: a longer run from the last checkpoint, its frames the same as a fresh run's.
    ok(&["resume", o, "--frames", "5", "--quiet"]);
    assert_eq!(names(&run, "frame_").last().map(String::as_str), Some("frame_1006.obj"));
    let fresh = dir.join("fresh");
    ok(&["simulate", s, "--out", fresh.to_str().unwrap(), "--frames", "5", "--quiet", "--format", "both"]);
    for n in names(&fresh, "frame_") {
        assert!(std::fs::read(run.join(&n)).unwrap() == std::fs::read(fresh.join(&n)).unwrap(), "{n}");
    }
    assert!(std::fs::read(run.join("cloth.usda")).unwrap() == std::fs::read(fresh.join("cloth.usda")).unwrap());

    // compare: the run against itself as reference measures zero, frames by number.
    let cmp = dir.join("compare");
    ok(&[
        "compare",
        s,
        "--out",
        cmp.to_str().unwrap(),
        "--reference",
        o,
        "--modes",
        "adaptive",
        "--size",
        "64x36",
        "--quiet",
    ]);
    let r: Value = serde_json::from_str(&std::fs::read_to_string(cmp.join("compare.json")).unwrap()).unwrap();
    let per_frame = r["modes"][0]["errors"]["per_frame"].as_array().unwrap();
    let compared: Vec<u64> = per_frame.iter().map(|f| f["frame"].as_u64().unwrap()).collect();
    assert_eq!(compared, [1002, 1003, 1004], "{r}");
    assert!(per_frame.iter().all(|f| f["geometric"]["max"].as_f64() == Some(0.0)), "{r}");
    assert!(cmp.join("adaptive/strip_1002.png").is_file());

    // batch: the finished shot is skipped on a rerun.
    let shots = dir.join("shots.json");
    let b = json!({ "version": 1, "shots": [{ "scene": "shot.json", "out": "batch_run", "format": "both" }] });
    std::fs::write(&shots, b.to_string()).unwrap();
    let summary = dir.join("summary.json");
    let args = ["batch", shots.to_str().unwrap(), "--summary", summary.to_str().unwrap(), "--quiet"];
    ok(&args);
    assert_eq!(names(&dir.join("batch_run"), "frame_").first().map(String::as_str), Some("frame_1001.obj"));
    ok(&args);
    let sum: Value = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    assert_eq!(sum["shots"][0]["status"], "skipped", "{sum}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A preroll of two frames simulates them unwritten: with nothing in the scene keyed in time,
/// the first written frame is the no-preroll run's third, byte for byte, at time 0; progress
/// lines say which frames are preroll and number the others as their files.
#[test]
fn preroll_frames_are_simulated_and_not_written() {
    let dir = temp_dir("preroll");
    let plain = shot(&dir, json!({ "start_frame": 0, "frames": 4 }));
    let a = dir.join("a");
    ok(&["simulate", plain.to_str().unwrap(), "--out", a.to_str().unwrap(), "--quiet"]);
    let pre = shot(&dir, json!({ "start_frame": 1, "frames": 2, "preroll": 0.08 }));
    let b = dir.join("b");
    let o = viewcloth(&["simulate", pre.to_str().unwrap(), "--out", b.to_str().unwrap(), "--progress", "lines"]);
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{log}");
    // Progress lines name frames as the files do.
    assert!(
        log.contains(": preroll frame 1/2,") && log.contains(": frame 1/3,") && log.contains(": frame 3/3,"),
        "{log}"
    );
    assert_eq!(names(&b, "frame_"), ["frame_0001.obj", "frame_0002.obj", "frame_0003.obj"]);
    for k in 0..3 {
        let (x, y) = (format!("frame_{:04}.obj", k + 2), format!("frame_{:04}.obj", k + 1));
        assert!(std::fs::read(a.join(&x)).unwrap() == std::fs::read(b.join(&y)).unwrap(), "{x} vs {y}");
    }
    let stats: Value = serde_json::from_str(&std::fs::read_to_string(b.join("stats.json")).unwrap()).unwrap();
    assert!(stats["frames"][0]["time"].as_f64().unwrap().abs() < 1e-12, "{stats}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `uv_scale = 100` (texture units of 1 cm) and a cloth scaled by 2: the frames' `vt` and the
/// layer's st are the input's `vt`, not material metres.
#[test]
fn uvs_round_trip_in_the_inputs_units() {
    let dir = temp_dir("uv_units");
    let mut obj = String::new();
    let (n, cm) = (4, 0.25);
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f64 * cm / n as f64, j as f64 * cm / n as f64);
            obj += &format!("v {} {} 1\nvt {u} {v}\n", u * 100.0, v * 100.0);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let k = j * (n + 1) + i + 1;
            obj += &format!("f {k}/{k} {}/{} {}/{}\n", k + 1, k + 1, k + n + 2, k + n + 2);
            obj += &format!("f {k}/{k} {}/{} {}/{}\n", k + n + 2, k + n + 2, k + n + 1, k + n + 1);
        }
    }
    std::fs::write(dir.join("patch.obj"), &obj).unwrap();
    let scene = json!({
        "version": 1, "frame_time": 0.04, "frames": 1,
        "cloths": [{ "mesh": "patch.obj", "uv_scale": 100, "transform": { "scale": 2 },
                     "material": { "preset": "cotton" }, "handles": [{ "nodes": [0, 4] }] }]
    });
    let file = dir.join("scene.json");
    std::fs::write(&file, scene.to_string()).unwrap();
    let run = dir.join("run");
    ok(&["simulate", file.to_str().unwrap(), "--out", run.to_str().unwrap(), "--quiet", "--format", "both"]);
    let input = parse_obj(&obj).unwrap();
    for f in ["frame_0000.obj", "frame_0001.obj"] {
        let out = parse_obj(&std::fs::read_to_string(run.join(f)).unwrap()).unwrap();
        // Corner by corner: the output's vt of each face equal the input's.
        for (a, b) in input.triangles.iter().zip(&out.triangles) {
            for (ca, cb) in a.iter().zip(b) {
                let (ua, ub) = (input.texcoords[ca.vt.unwrap()], out.texcoords[cb.vt.unwrap()]);
                assert!((ua - ub).norm() < 1e-9, "{f}: vt {ub:?}, the input has {ua:?}");
            }
        }
    }
    // The layer's st: the largest coordinate is the input's 0.25, not 0.25 × 100 × 2 m.
    let samples = std::fs::read_to_string(run.join("usd_samples/frame_0001.txt")).unwrap();
    let st = samples.lines().find(|l| l.contains("\tt\ttexCoord2f[] primvars:st\t")).unwrap();
    let max = st
        .rsplit('\t')
        .next()
        .unwrap()
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .filter_map(|w| w.parse::<f64>().ok())
        .fold(0.0, f64::max);
    assert!((max - 0.25).abs() < 1e-7, "largest st coordinate {max}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad frame ranges, patterns and formats: exit 2, one line naming the file and field.
#[test]
fn bad_frame_ranges_patterns_and_formats_are_refused_in_one_line() {
    let dir = temp_dir("bad");
    for (extra, field, says) in [
        (json!({ "start_frame": -1 }), "start_frame", "0..=100000000"),
        (json!({ "start_frame": 1.5 }), "start_frame", "expected i64"),
        (json!({ "preroll": -0.04 }), "preroll", "≥ 0"),
        (json!({ "preroll": 0.05 }), "preroll", "whole number of frames"),
        (
            json!({ "obstacles": [{ "sequence": { "pattern": "b_%04d_####.obj", "count": 1, "fps": 25 } }] }),
            "obstacles[0].sequence.pattern",
            "$F4",
        ),
    ] {
        let scene = shot(&dir, extra);
        let o = viewcloth(&["check", scene.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{field}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("shot.json") && err.contains(field) && err.contains(says), "{field}: {err}");
    }
    let shots = dir.join("shots.json");
    std::fs::write(&shots, json!({ "version": 1, "shots": [{ "scene": "shot.json", "format": "usdz" }] }).to_string())
        .unwrap();
    shot(&dir, json!({}));
    let o = viewcloth(&["batch", shots.to_str().unwrap(), "--quiet"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("shots.json") && err.contains("shots[0].format") && err.contains("\"both\""), "{err}");
    let o = viewcloth(&["simulate", "--format", "usdz"]);
    assert_eq!(o.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

/// Obstacle sequences named with Houdini's `$F4` or `####` load as with `%04d`.
#[test]
fn sequence_patterns_accept_houdini_and_hash_tokens() {
    let dir = temp_dir("patterns");
    std::fs::create_dir_all(dir.join("seq")).unwrap();
    for k in 0..2 {
        let s = 0.1 + 0.01 * k as f64;
        let tet = format!("v 0 0 0\nv {s} 0 0\nv 0 {s} 0\nv 0 0 {s}\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
        std::fs::write(dir.join(format!("seq/b_{:04}.obj", 7 + k)), tet).unwrap();
    }
    for pattern in ["seq/b_%04d.obj", "seq/b_$F4.obj", "seq/b_####.obj"] {
        let seq = json!({ "obstacles": [{ "sequence": { "pattern": pattern, "first": 7, "count": 2, "fps": 25 } }] });
        let scene = shot(&dir, seq);
        ok(&["check", scene.to_str().unwrap()]);
    }
    std::fs::remove_dir_all(&dir).ok();
}
