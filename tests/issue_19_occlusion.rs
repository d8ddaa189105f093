//! Issue 19, item 2: cloth hidden from the camera behind an obstacle over the whole lookahead
//! window is coarsened like cloth out of frame (`sizing::occlusion`), and `stats.json` counts
//! the hidden faces. Each property is checked against a control that must fail it: the same
//! shot with occlusion off, and the same sheet with the wall moved aside.

use std::f64::consts::PI;
use std::path::Path;

mod common;

use common::{temp_dir, viewcloth};
use serde_json::{json, Value};

fn run(dir: &Path, scene: &Value, name: &str, threads: &str) -> Value {
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, scene.to_string()).unwrap();
    let out = dir.join(name);
    let o = viewcloth(&[
        "simulate",
        file.to_str().unwrap(),
        "--quiet",
        "--threads",
        threads,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap()
}

fn column(stats: &Value, key: &str) -> Vec<u64> {
    stats["frames"].as_array().unwrap().iter().map(|f| f[key].as_u64().unwrap_or(0)).collect()
}

/// A 0.4 m square sheet corrugated along x (z = A sin(2πx/λ), λ = 10 cm, A = 1 cm) on a 1 cm
/// grid, material coordinates along the surface (at rest): refined by curvature where it is seen.
fn wavy_sheet(file: &Path) {
    let (a, k, n, w) = (0.01, 2.0 * PI / 0.1, 40, 0.4);
    let xs: Vec<f64> = (0..=n).map(|i| w * i as f64 / n as f64).collect();
    let mut u = vec![0.0];
    for i in 1..=n {
        let (x0, x1) = (xs[i - 1], xs[i]);
        let arc: f64 = (0..50)
            .map(|j| {
                let t = x0 + (x1 - x0) * (j as f64 + 0.5) / 50.0;
                (1.0 + (a * k * (k * t).cos()).powi(2)).sqrt() * (x1 - x0) / 50.0
            })
            .sum();
        u.push(u[i - 1] + arc);
    }
    let mut s = String::new();
    for j in 0..=n {
        for x in &xs {
            s += &format!("v {x} {} {}\n", w * j as f64 / n as f64, a * (k * x).sin());
        }
    }
    for j in 0..=n {
        for ui in &u {
            s += &format!("vt {ui} {}\n", w * j as f64 / n as f64);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let p = j * (n + 1) + i + 1;
            let (q, r, t) = (p + 1, p + n + 1, p + n + 2);
            s += &format!("f {p}/{p} {q}/{q} {t}/{t}\nf {p}/{p} {t}/{t} {r}/{r}\n");
        }
    }
    std::fs::write(file, s).unwrap();
}

/// The still sheet (no gravity) under a still camera 1 m above it, a 2 cm board between them
/// (0.7 m square, at height 0.5 m) centred on (`wall_x`, 0.2); `view` the remesh's view block.
fn shot(wall_x: f64, view: Value) -> Value {
    json!({
        "version": 1, "frame_time": 0.04, "steps_per_frame": 2, "frames": 8, "gravity": [0, 0, 0],
        "camera": "camera.json",
        "collision": { "thickness": 0.005 },
        "cloths": [{
            "mesh": "wavy.obj", "material": { "preset": "cotton" },
            "remesh": { "mode": "view", "refine_angle": 0.3, "size": [0.01, 0.2], "aspect_min": 0.2, "view": view }
        }],
        "obstacles": [{
            "name": "board", "box": { "size": [0.7, 0.7, 0.02] }, "transform": { "translate": [wall_x, 0.2, 0.5] }
        }]
    })
}

fn setup(dir: &Path, target: [f64; 3]) {
    wavy_sheet(&dir.join("wavy.obj"));
    let cam = json!({ "version": 1, "aspect": 1.7778, "near": 0.05, "far": 100.0, "keys": [
        { "time": 0.0, "position": [0.2, 0.2, 1.2], "target": target, "up": [0, 1, 0], "fov": 40 }
    ]});
    std::fs::write(dir.join("camera.json"), cam.to_string()).unwrap();
}

#[test]
fn cloth_behind_a_board_is_coarsened_like_cloth_out_of_frame() {
    let dir = temp_dir("occluded");
    let down = [0.2, 0.2, 0.0];
    setup(&dir, down);
    let hidden = run(&dir, &shot(0.2, json!({})), "hidden", "1");
    let control = run(&dir, &shot(0.2, json!({ "occlusion_pixels": 0 })), "control", "1");
    let aside = run(&dir, &shot(1.2, json!({})), "aside", "1");
    let (h, c, a) = (column(&hidden, "faces"), column(&control, "faces"), column(&aside, "faces"));
    let last = |v: &[u64]| *v.last().unwrap() as f64;
    // Seen, the corrugation refines the sheet; the board aside changes nothing.
    assert!(last(&c) > 500.0, "control should refine: {c:?}");
    assert!((last(&a) - last(&c)).abs() <= 0.05 * last(&c), "aside {a:?}\ncontrol {c:?}");
    // Hidden over the whole window: coarse, as μ_out makes it.
    assert!(last(&h) < 0.2 * last(&c), "hidden {h:?}\ncontrol {c:?}");
    // The same sheet out of frame (camera turned away) ends as coarse, within the mesh's
    // discreteness.
    let away = [5.0, 0.2, 1.2];
    std::fs::write(
        dir.join("camera.json"),
        json!({ "version": 1, "aspect": 1.7778, "near": 0.05, "far": 100.0, "keys": [
            { "time": 0.0, "position": [0.2, 0.2, 1.2], "target": away, "up": [0, 0, 1], "fov": 40 }
        ]})
        .to_string(),
    )
    .unwrap();
    let out = column(&run(&dir, &shot(1.2, json!({})), "out", "1"), "faces");
    assert!((last(&h) - last(&out)).abs() <= 0.25 * last(&out).max(20.0), "hidden {h:?}\nout of frame {out:?}");
    // Stats: the hidden faces are in frame and counted occluded; none when seen.
    let (occ, in_frame) = (column(&hidden, "view_faces_occluded"), column(&hidden, "view_faces_in_frame"));
    assert!(occ.iter().zip(&in_frame).skip(1).all(|(o, i)| *i > 0 && o == i), "occluded {occ:?} of {in_frame:?}");
    assert!(column(&aside, "view_faces_occluded").iter().all(|&o| o == 0));
    assert!(column(&control, "view_faces_occluded").iter().all(|&o| o == 0), "occlusion off counts none");
}

#[test]
fn a_partly_hidden_sheet_is_coarsened_where_hidden_and_the_same_on_any_thread_count() {
    let dir = temp_dir("half_hidden");
    let down = [0.2, 0.2, 0.0];
    setup(&dir, down);
    // The board covers the sheet's half x < 0.2 (its edge over the middle).
    let scene = |view: Value| shot(-0.15, view);
    let one = run(&dir, &scene(json!({})), "one", "1");
    let two = run(&dir, &scene(json!({})), "two", "2");
    let control = run(&dir, &scene(json!({ "occlusion_pixels": 0 })), "control", "1");
    let frame = |name: &str| std::fs::read(dir.join(name).join("frame_0008.obj")).unwrap();
    assert_eq!(frame("one"), frame("two"), "1 and 2 threads must write the same bytes");
    assert_eq!(column(&one, "view_faces_occluded"), column(&two, "view_faces_occluded"));
    let (f, c) = (column(&one, "faces"), column(&control, "faces"));
    let last = |v: &[u64]| *v.last().unwrap() as f64;
    // About half the refinement goes: between a third and two thirds of the control's faces.
    assert!(last(&f) > 0.3 * last(&c) && last(&f) < 0.7 * last(&c), "half hidden {f:?}\ncontrol {c:?}");
    // The hidden half's nodes are coarse, the seen half's fine: count vertices each side.
    let obj = String::from_utf8(frame("one")).unwrap();
    let xs: Vec<f64> = obj
        .lines()
        .filter(|l| l.starts_with("v "))
        .map(|l| l.split_whitespace().nth(1).unwrap().parse().unwrap())
        .collect();
    let hidden = xs.iter().filter(|&&x| x < 0.15).count();
    let seen = xs.iter().filter(|&&x| x > 0.25).count();
    assert!(seen > 4 * hidden, "seen side {seen} vertices, hidden side {hidden}");
}
