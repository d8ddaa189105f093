//! Issue 13's held-out test (Kavan et al. 2011, §6, Figs. 10–11): on a motion of the training
//! garment it was not trained on, the learned upsampling is closer to the fine simulation than
//! Loop subdivision of the same coarse run; and the tracked training runs (§4) hold eq. 6,
//! T p_f = T B p_c, after every step.
//!
//! The shipped `scenes/hanging_sheet.json` at two uniform resolutions, 6 × 6 cells (49 nodes, 72
//! faces) and 24 × 24 (625 nodes, 1152 faces), so two levels of Loop give exactly the fine face
//! count. Training: both held corners swing in and out of the sheet's plane for 2 s. Held out:
//! one corner held still while the other is carried inwards, up and back along another path.
//! Both pairs are tracked runs (`upsample trace`), as in the paper: untracked, the 6 × 6 and
//! 24 × 24 sheets drift 30–45 mm apart (mean node distance) within 2 s and there is nothing
//! consistent to learn.
//!
//! Parameters, none chosen by looking at the held-out runs: T = 60 test functions, `trace`'s
//! default (the paper's Table 1 uses 50–80). T is not cross-validated: it changes the training
//! target itself (T → N makes the fine run the coarse surface), and on the training motion the
//! validation error falls monotonically with T (9.24, 7.31, 4.25, 3.35, 2.40 mm for T = 10, 20,
//! 40, 60, 80; `bench/upsample_tune.sh`), so a CV choice would just be the largest T offered.
//! The prior and γ_1, γ_N, c come from `upsample train --cross-validate` (5 folds over blocks of
//! the 51 training frames, the default grid); it picks the barycentric prior with γ_1 = γ_N = 1.
//!
//! Error: the two-sided mean surface distance (`metrics::geometric`, what `compare` reports) to
//! the held-out fine run, over its 50 frames. Measured (2026-12-02): upsampled 1.67 mm, Loop
//! 4.35 mm, the coarse mesh itself 1.68 mm; mean distance between points of equal material
//! coordinates 2.44 mm upsampled, 11.47 mm Loop. On this sheet, held out, the learned operator
//! is the coarse surface plus little (README, `upsample`; `examples/upsample_diagnose.rs`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

mod common;
use common::{temp_dir, viewcloth};

use serde_json::{json, Value};
use viewcloth::io::obj::read_obj;
use viewcloth::metrics::{surface_distance, Surface};

const FRAMES: usize = 50;

/// `scenes/hanging_sheet.json` at `cells` × `cells`, held at its two top corners (node indices
/// follow the resolution), moved along `motions` (left, right; null: held still).
fn scene(dir: &Path, name: &str, cells: usize, motions: [&Value; 2]) -> PathBuf {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hanging_sheet.json");
    let mut s: Value = serde_json::from_str(&std::fs::read_to_string(shipped).unwrap()).unwrap();
    s["frames"] = json!(FRAMES);
    let cloth = &mut s["cloths"][0];
    cloth["rectangle"]["resolution"] = json!([cells, cells]);
    let (left, right) = (cells * (cells + 1), (cells + 1) * (cells + 1) - 1);
    cloth["handles"] = json!([{ "nodes": [left] }, { "nodes": [right] }]);
    for (k, m) in motions.iter().enumerate().filter(|(_, m)| !m.is_null()) {
        cloth["handles"][k]["motion"] = (*m).clone();
    }
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, s.to_string()).unwrap();
    file
}

/// Mean distance (m) between the nodes of frame `k` of `fine` and the points of run `b` at the
/// same material coordinates (every fine node has a node of `b` there: both 24 × 24 lattices).
fn node_distance(fine: &Path, b: &Path, k: usize) -> f64 {
    let read = |d: &Path| read_obj(&d.join(format!("frame_{k:04}.obj"))).unwrap();
    let (f, c) = (read(fine), read(b));
    let key = |m: &viewcloth::io::obj::ObjData, corner: &viewcloth::io::obj::Corner| {
        let t = m.texcoords[corner.vt.unwrap()];
        ((t.x * 1e6).round() as i64, (t.y * 1e6).round() as i64)
    };
    let at: HashMap<_, _> = c.triangles.iter().flatten().map(|corner| (key(&c, corner), corner.v)).collect();
    let pairs: HashMap<_, _> = f.triangles.iter().flatten().map(|corner| (corner.v, at[&key(&f, corner)])).collect();
    pairs.iter().map(|(&i, &j)| (f.positions[i] - c.positions[j]).norm()).sum::<f64>() / pairs.len() as f64
}

fn run(args: &[&str]) {
    let o = viewcloth(args);
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// Mean surface distance (m) between frame `k` of two runs.
fn distance(a: &Path, b: &Path, k: usize) -> f64 {
    let read = |d: &Path| {
        let m = read_obj(&d.join(format!("frame_{k:04}.obj"))).unwrap();
        (m.positions, m.triangles.iter().map(|t| t.map(|c| c.v)).collect::<Vec<[usize; 3]>>())
    };
    let (ma, mb) = (read(a), read(b));
    let sa = Surface { positions: &ma.0, triangles: &ma.1, weight: None };
    surface_distance(sa, Surface { positions: &mb.0, triangles: &mb.1, weight: None }).mean
}

#[test]
fn upsampling_beats_loop_subdivision_on_a_held_out_motion() {
    let dir = temp_dir("held_out");
    // Training: both corners swing in and out of the sheet's plane, in opposite phase.
    let left = json!([
        { "time": 0.0, "translate": [0, 0, 0] },
        { "time": 0.7, "translate": [0.25, 0.25, -0.1] },
        { "time": 1.4, "translate": [0.1, -0.25, 0.1] },
        { "time": 2.0, "translate": [0, 0, 0] }
    ]);
    let right = json!([
        { "time": 0.0, "translate": [0, 0, 0] },
        { "time": 0.7, "translate": [-0.2, -0.25, 0.1] },
        { "time": 1.4, "translate": [-0.05, 0.25, -0.1] },
        { "time": 2.0, "translate": [0, 0, 0] }
    ]);
    let moving = json!([
        { "time": 0.0, "translate": [0, 0, 0] },
        { "time": 1.0, "translate": [-0.35, 0.2, 0.15] },
        { "time": 2.0, "translate": [-0.1, -0.2, 0.0] }
    ]);
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    // The training pair through the library, to check eq. 6 at every step.
    let load = |p: &Path| viewcloth::scene::load_path(p, None).unwrap().scene;
    let [train_c, train_f] = [6, 24].map(|n| load(&scene(&dir, &format!("train_{n}"), n, [&left, &right])));
    let train = dir.join("train");
    let r = viewcloth::upsample::track::trace(train_c, train_f, 60, &train).unwrap();
    assert_eq!((r.steps, r.residual_after.len()), (250, 250));
    let after = r.residual_after.iter().copied().fold(0.0, f64::max);
    let before = r.residual_before.iter().copied().fold(0.0, f64::max);
    assert!(after < 1e-12, "|T p_f − T B p_c| = {after:e} m after a projection");
    assert!(before > 1e-3, "the fine run never drifted ({before:e} m): the check would be empty");
    // The held-out pair through the CLI.
    let [held_c, held_f] = [6, 24].map(|n| scene(&dir, &format!("held_{n}"), n, [&Value::Null, &moving]));
    let held = dir.join("held");
    run(&["upsample", "trace", &s(&held_c), &s(&held_f), "--test-functions", "60", "--out", &s(&held)]);
    let model = dir.join("model.bin");
    let (tc, tf) = (train.join("coarse"), train.join("fine"));
    let o = viewcloth(&[
        "upsample",
        "train",
        "--coarse",
        &s(&tc),
        "--fine",
        &s(&tf),
        "--cross-validate",
        "--out",
        &s(&model),
    ]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The table scores every candidate of the default grid: 2 priors × 24 (γ_1 ≤ γ_N) pairs × 4 c.
    let rows = said.lines().filter(|l| l.starts_with("| zero |") || l.starts_with("| barycentric |")).count();
    assert_eq!(rows, 192, "{said}");
    eprintln!("{}", said.lines().last().unwrap_or_default());
    let (up, sub, coarse, fine) = (dir.join("upsampled"), dir.join("loop"), held.join("coarse"), held.join("fine"));
    run(&["upsample", "apply", &s(&model), "--coarse", &s(&coarse), "--out", &s(&up)]);
    run(&["upsample", "loop", "--coarse", &s(&coarse), "--model", &s(&model), "--out", &s(&sub)]);
    let faces = |d: &Path| read_obj(&d.join("frame_0001.obj")).unwrap().triangles.len();
    assert_eq!((faces(&up), faces(&sub), faces(&fine)), (1152, 1152, 1152), "matched face counts");
    let mean = |d: &Path| (1..=FRAMES).map(|k| distance(&fine, d, k)).sum::<f64>() / FRAMES as f64;
    let (e_up, e_loop, e_coarse) = (mean(&up), mean(&sub), mean(&coarse));
    eprintln!(
        "held-out mean surface distance to the tracked fine run over {FRAMES} frames: upsampled {:.2} mm, \
         Loop {:.2} mm, coarse {:.2} mm",
        1e3 * e_up,
        1e3 * e_loop,
        1e3 * e_coarse
    );
    assert!(e_up < e_loop, "upsampled {e_up:e} m, Loop {e_loop:e} m");
    // Per material point (what U is fitted to): Loop's points also slide along the surface.
    let nodes = |d: &Path| (1..=FRAMES).map(|k| node_distance(&fine, d, k)).sum::<f64>() / FRAMES as f64;
    let (n_up, n_loop) = (nodes(&up), nodes(&sub));
    eprintln!(
        "held-out mean distance between points of equal material coordinates: upsampled {:.2} mm, Loop {:.2} mm",
        1e3 * n_up,
        1e3 * n_loop
    );
    assert!(n_up < n_loop, "upsampled {n_up:e} m, Loop {n_loop:e} m");
}

/// Bad input to `upsample trace` and `upsample loop`: exit 2, one line naming the file or option
/// and what was expected, nothing written.
#[test]
fn trace_and_loop_refuse_bad_input_in_one_line() {
    let dir = temp_dir("bad_input");
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let (coarse, fine) = (scene(&dir, "c", 3, [&Value::Null; 2]), scene(&dir, "f", 6, [&Value::Null; 2]));
    let shorter = std::fs::read_to_string(&fine).unwrap().replace("\"frames\":50", "\"frames\":7");
    std::fs::write(&fine, shorter).unwrap();
    let adaptive = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sheet_on_sphere.json");
    let out = dir.join("out");
    let cases: [(Vec<String>, &str); 4] = [
        (vec![s(&coarse), s(&fine)], "frame_time, steps_per_frame, frames, preroll and start_frame must equal"),
        (vec![s(&adaptive), s(&coarse)], "remeshes adaptively; tracking needs uniform runs"),
        (
            vec![s(&coarse), s(&coarse), "--test-functions".into(), "99".into()],
            "asked for 99 harmonics but the fine mesh has 16 nodes",
        ),
        (vec!["--levels".into(), "9".into()], "--levels: expected 0..=6"),
    ];
    for (args, want) in cases {
        let cmd = if args[0] == "--levels" { vec!["loop", "--coarse", "nowhere"] } else { vec!["trace"] };
        let mut all: Vec<&str> = ["upsample"].into_iter().chain(cmd).chain(args.iter().map(|a| a.as_str())).collect();
        all.extend(["--out", out.to_str().unwrap()]);
        let o = viewcloth(&all);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{all:?}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{e}");
        assert!(e.contains(want), "{all:?}: {e}");
    }
    assert!(!out.exists(), "a refused command wrote its output folder");
}
