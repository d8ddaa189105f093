//! Properties of whole simulations (issue 2, "Tests"): the pinned sheet comes to rest, handles
//! are exactly where they are told, damping never creates energy, the stiff drape stays finite
//! at large steps, and the output does not depend on the run or on the thread count.

use std::path::{Path, PathBuf};

mod common;

use common::{temp_dir, Rng};
use serde_json::{json, Value};
use viewcloth::math::{Real, Vec3};
use viewcloth::scene::{self, Scene};
use viewcloth::sim::Simulation;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn read_scene_json(name: &str) -> Value {
    let path = scenes_dir().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    serde_json::from_str(&text).unwrap()
}

fn load(v: &Value, name: &str) -> Scene {
    let file = scenes_dir().join(format!("{name}.json"));
    scene::load_str(&v.to_string(), &file, &scenes_dir(), name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Rebuilds the scene's rectangle at `n × n` quads, moving the two corner handles of the top
/// row (nodes n(n+1) and n(n+1)+n) along.
fn coarsen(v: &mut Value, n: usize) {
    let cloth = &mut v["cloths"][0];
    cloth["rectangle"]["resolution"] = json!([n, n]);
    let top_left = n * (n + 1);
    cloth["handles"] = json!([{ "nodes": [top_left] }, { "nodes": [top_left + n] }]);
}

/// Asserts that every node held by a handle active at `t0` sits bitwise on its target at the
/// end of the step to `sim.state.time`.
fn assert_handles_on_target(sim: &Simulation, t0: Real) {
    for (h, (handle, nodes)) in sim.scene.handles.iter().zip(&sim.state.handle_nodes).enumerate() {
        if !handle.active(t0) {
            continue;
        }
        for (k, &n) in nodes.iter().enumerate() {
            let (x, target) = (sim.state.mesh.nodes[n].x, handle.target(k, sim.state.time));
            assert!(
                x.iter().zip(target.iter()).all(|(a, b)| a.to_bits() == b.to_bits()),
                "step {}: handle {h} node {n} at {x:?}, target {target:?}",
                sim.state.steps
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// (a) The hanging sheet (the default shot until issue 19) comes to rest, with its handles
// exactly in place.

#[test]
fn hanging_sheet_comes_to_rest_with_handles_in_place() {
    let mut v = read_scene_json("hanging_sheet.json");
    coarsen(&mut v, 8);
    let mut sim = Simulation::new(load(&v, "hanging_sheet")).unwrap();
    let anchors: Vec<(usize, Vec3)> =
        sim.state.handle_nodes.iter().flatten().map(|&n| (n, sim.state.mesh.nodes[n].x)).collect();
    assert_eq!(anchors.len(), 2);
    let h = sim.scene.time_step();
    // Peak kinetic energy over windows of 2 s (50 frames): the sheet swings like a pendulum, so
    // single frames can be near a turning point; the window maxima must decay.
    let window = 50;
    let mut peaks: Vec<Real> = Vec::new();
    let mut window_peak: Real = 0.0;
    let mut frame = 0;
    let rest_fraction = 1e-5;
    loop {
        for _ in 0..sim.scene.steps_per_frame {
            let t0 = sim.state.time;
            sim.step(h).unwrap();
            assert_handles_on_target(&sim, t0);
            for &(n, x0) in &anchors {
                assert!(
                    sim.state.mesh.nodes[n].x == x0,
                    "fixed handle node {n} moved to {:?} (from {x0:?})",
                    sim.state.mesh.nodes[n].x
                );
            }
        }
        frame += 1;
        let kinetic = sim.measure(frame).kinetic_energy.expect("a simulated frame has its energy");
        assert!(kinetic.is_finite());
        window_peak = window_peak.max(kinetic);
        if frame % window == 0 {
            peaks.push(window_peak);
            window_peak = 0.0;
            let first = peaks[0];
            if peaks.len() >= 2 && *peaks.last().unwrap() < rest_fraction * first {
                break;
            }
        }
        assert!(frame < 1500, "not at rest after {frame} frames: window peaks of kinetic energy {peaks:?}");
    }
    for w in peaks.windows(2) {
        assert!(w[1] < w[0], "kinetic energy does not decay: window peaks {peaks:?}");
    }
    let stats = sim.measure(frame);
    assert!(stats.mean_strain < 0.02, "mean strain at rest {:.4} ≥ 2%", stats.mean_strain);
    // At rest the sheet hangs below its handles.
    let top = sim.state.mesh.nodes.iter().map(|n| n.x.z).fold(Real::MIN, Real::max);
    assert!(top <= 1.0 + 1e-9);
}

#[test]
fn keyframed_handle_follows_its_motion_exactly() {
    let mut v = read_scene_json("hanging_sheet.json");
    coarsen(&mut v, 8);
    v["cloths"][0]["handles"][1]["motion"] = json!([
        { "time": 0.0 },
        { "time": 0.3, "translate": [0.2, 0.0, 0.1] },
        { "time": 0.6, "translate": [0.1, -0.1, 0.0], "rotate": [30, 0, 0, 1] }
    ]);
    let mut sim = Simulation::new(load(&v, "hanging_sheet")).unwrap();
    let moving = sim.state.handle_nodes[1][0];
    let x0 = sim.state.mesh.nodes[moving].x;
    let fixed = sim.state.handle_nodes[0][0];
    let fixed_x0 = sim.state.mesh.nodes[fixed].x;
    let h = sim.scene.time_step();
    let mut farthest: Real = 0.0;
    while sim.state.time < 0.8 {
        let t0 = sim.state.time;
        sim.step(h).unwrap();
        assert_handles_on_target(&sim, t0);
        assert!(sim.state.mesh.nodes[fixed].x == fixed_x0);
        farthest = farthest.max((sim.state.mesh.nodes[moving].x - x0).norm());
    }
    assert!(farthest > 0.1, "the keyframed handle barely moved ({farthest} m)");
    // After the last key the motion holds the last key's transform.
    let last = viewcloth::math::motion::Transform::new([0.1, -0.1, 0.0], Some([30.0, 0.0, 0.0, 1.0]), 1.0);
    let expected = last.apply(&x0);
    let got = sim.state.mesh.nodes[moving].x;
    assert!((got - expected).norm() < 1e-12, "after the last keyframe the handle is at {got:?}, expected {expected:?}");
}

// ---------------------------------------------------------------------------------------------
// (b) With damping and no external forcing, total energy never increases.

/// A free sheet (no gravity, no handles), stretched or compressed by `scale` in its plane and
/// bulged out of it, with random velocities; returns the simulation.
fn deformed_free_sheet(scale: Real, damping: Real) -> Simulation {
    let mut v = read_scene_json("hanging_sheet.json");
    coarsen(&mut v, 10);
    v["gravity"] = json!([0, 0, 0]);
    v["cloths"][0]["handles"] = json!([]);
    v["cloths"][0]["material"]["damping"] = json!(damping);
    let mut sim = Simulation::new(load(&v, "free_sheet")).unwrap();
    let pi = std::f64::consts::PI;
    let mut rng = Rng(12345);
    let mut noise = move || rng.uniform() - 0.5;
    for n in sim.state.mesh.nodes.iter_mut() {
        let p = n.x;
        let (u, w) = (p.x + 0.5, p.y + 0.5);
        let bulge = 0.05 * (pi * u).sin() * (pi * w).sin();
        n.x = Vec3::new(scale * p.x, scale * p.y, p.z + bulge) + 0.002 * Vec3::new(noise(), noise(), noise());
        n.v = 0.1 * Vec3::new(noise(), noise(), noise());
    }
    sim
}

#[test]
fn damped_free_sheet_never_gains_energy() {
    for (scale, h) in [(1.1, 1.0 / 240.0), (0.9, 1.0 / 240.0), (1.1, 1.0 / 24.0), (0.9, 1.0 / 24.0)] {
        for damping in [1e-3, 1e-2] {
            let mut sim = deformed_free_sheet(scale, damping);
            let energy = |sim: &Simulation| {
                let s = sim.measure(0);
                let (total, kinetic) = (s.total_energy.unwrap(), s.kinetic_energy.unwrap());
                // No gravity: total = kinetic + elastic.
                assert!((total - kinetic - sim.elastic_energy()).abs() <= 1e-12 * total);
                total
            };
            let e_start = energy(&sim);
            assert!(e_start > 1.0, "the initial deformation should store energy ({e_start} J)");
            let mut e_prev = e_start;
            for k in 0..150 {
                sim.step(h).unwrap();
                let e = energy(&sim);
                assert!(
                    e <= e_prev + 1e-13 * e_start,
                    "scale {scale}, h = {h:.4}, damping {damping}: energy rose from {e_prev:.15e} to {e:.15e} J at step {k}"
                );
                e_prev = e;
            }
            assert!(e_prev < 0.5 * e_start, "damping removed too little energy: {e_start} → {e_prev} J");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// (c) The stiff drape stays finite and bounded at small and large steps.

/// The stiff drape: `scenes/drape_stiff.json`, or the equivalent hanging sheet with a 1000×
/// stiffer membrane and 10× stiffer bending if that scene is missing.
fn drape_stiff_json() -> Value {
    if scenes_dir().join("drape_stiff.json").exists() {
        return read_scene_json("drape_stiff.json");
    }
    let mut v = read_scene_json("hanging_sheet.json");
    v["name"] = json!("drape_stiff");
    let m = &mut v["cloths"][0]["material"];
    m["stretching_mult"] = json!(1000);
    m["bending_mult"] = json!(10);
    v
}

/// Runs the stiff drape for `seconds` at h = 1/(24 · steps_per_frame) and checks every frame.
/// With `monotone`, total energy must never rise from frame to frame (fixed handles do no
/// work). At h = 1/24 it may not: the one linearised Newton step does not see the stretch that
/// the large rotation near the handles causes, so the first frames transiently store elastic
/// energy (measured: 1.5 J → 120 J at frame 2, max strain 9%) that later dissipates; the
/// test then asks for boundedness and for the energy to be back below its start at the end.
fn run_drape(steps_per_frame: usize, seconds: Real, monotone: bool) {
    let mut v = drape_stiff_json();
    v["frame_time"] = json!(1.0 / 24.0);
    v["steps_per_frame"] = json!(steps_per_frame);
    let mut sim = Simulation::new(load(&v, "drape_stiff")).unwrap();
    let h = sim.scene.time_step();
    assert!((h - 1.0 / (24.0 * steps_per_frame as Real)).abs() < 1e-15);
    // Handles are fixed: the sheet can hang at most its diagonal (1.118 m) from the midpoint of
    // the two top corners, plus a few percent of stretch.
    let anchors: Vec<Vec3> = sim.scene.handles.iter().flat_map(|h| h.anchors.clone()).collect();
    let mid = anchors.iter().fold(Vec3::zeros(), |a, p| a + p) / anchors.len() as Real;
    let mass: Real = sim.state.mesh.nodes.iter().map(|n| n.mass).sum();
    // The most kinetic energy the sheet could gain: all of it falling 1.2 m.
    let ke_max = mass * sim.scene.gravity.norm() * 1.2;
    let e_start = sim.measure(0).total_energy.unwrap();
    let mut e_prev = e_start;
    let frames = (seconds * 24.0).round() as usize;
    for f in 1..=frames {
        sim.advance_frame().unwrap_or_else(|e| panic!("h = {h}: frame {f}: {e}"));
        let s = sim.measure(f);
        let (total, kinetic) = (s.total_energy.unwrap(), s.kinetic_energy.unwrap());
        let what = format!("h = 1/{}, frame {f}", (1.0 / h).round());
        for (i, n) in sim.state.mesh.nodes.iter().enumerate() {
            assert!(n.x.iter().chain(n.v.iter()).all(|c| c.is_finite()), "{what}: node {i} non-finite");
            let d = (n.x - mid).norm();
            assert!(d < 1.2, "{what}: node {i} at {:?}, {d} m from the handles", n.x);
        }
        assert!(s.max_strain < 0.15, "{what}: max strain {}", s.max_strain);
        assert!(s.mean_strain < 0.02, "{what}: mean strain {}", s.mean_strain);
        assert!(kinetic < ke_max, "{what}: kinetic energy {kinetic} J");
        if monotone {
            assert!(total <= e_prev + 1e-12 * e_start, "{what}: total energy rose from {e_prev} to {total} J");
        }
        e_prev = total;
    }
    assert!(e_prev < e_start, "{frames} frames: energy {e_prev} J, above the initial {e_start} J");
}

#[test]
fn drape_stiff_is_bounded_at_h_1_240() {
    run_drape(10, 0.5, true);
}

#[test]
fn drape_stiff_is_bounded_at_h_1_24() {
    run_drape(1, 3.0, false);
}

// ---------------------------------------------------------------------------------------------
// (d) Determinism: same input, same bits, whatever the run or the thread count.

/// A small windy hanging sheet (so every force kernel runs).
fn determinism_scene() -> Value {
    let mut v = read_scene_json("hanging_sheet.json");
    coarsen(&mut v, 16);
    v["frames"] = json!(8);
    v["wind"] = json!({ "velocity": [3.0, 1.0, -0.5], "density": 1.225, "drag": 0.05 });
    v
}

/// Runs the CLI; returns the frame files (name, bytes) in name order.
fn cli_frames(scene: &Path, out: &Path, threads: usize) -> Vec<(String, Vec<u8>)> {
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_viewcloth"))
        .arg("simulate")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(["--threads", &threads.to_string(), "--quiet"])
        .status()
        .unwrap();
    assert!(status.success(), "viewcloth simulate failed: {status}");
    let mut frames: Vec<(String, Vec<u8>)> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".obj"))
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
        .collect();
    frames.sort();
    frames
}

#[test]
fn cli_output_is_identical_across_runs_and_thread_counts() {
    let dir = temp_dir("determinism");
    let scene = dir.join("windy_sheet.json");
    std::fs::write(&scene, determinism_scene().to_string()).unwrap();
    let runs: Vec<(usize, Vec<(String, Vec<u8>)>)> = [1, 1, 2, 2]
        .iter()
        .enumerate()
        .map(|(i, &t)| (t, cli_frames(&scene, &dir.join(format!("run{i}")), t)))
        .collect();
    let (_, reference) = &runs[0];
    let names: Vec<&str> = reference.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), 9, "frames 0..=8 expected, got {names:?}");
    assert_eq!(names[0], "frame_0000.obj");
    for (i, (threads, frames)) in runs.iter().enumerate().skip(1) {
        assert_eq!(frames.len(), reference.len(), "run {i} ({threads} threads)");
        for ((name, bytes), (ref_name, ref_bytes)) in frames.iter().zip(reference) {
            assert_eq!(name, ref_name);
            assert!(bytes == ref_bytes, "run {i} ({threads} threads): {name} differs from the first run (1 thread)");
        }
    }
    // The sheet moved: the comparison is not between identical initial states only.
    assert_ne!(reference[0].1, reference[8].1);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn state_is_bitwise_identical_across_thread_counts() {
    let state = |threads: usize| -> Vec<u64> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut sim = Simulation::new(load(&determinism_scene(), "windy_sheet")).unwrap();
            for _ in 0..4 {
                sim.advance_frame().unwrap();
            }
            sim.state
                .mesh
                .nodes
                .iter()
                .flat_map(|n| n.x.iter().chain(n.v.iter()).map(|c| c.to_bits()).collect::<Vec<_>>())
                .collect()
        })
    };
    let one = state(1);
    assert_eq!(one, state(1), "two serial runs differ");
    assert_eq!(one, state(2), "1 and 2 threads differ");
    assert_eq!(one, state(4), "1 and 4 threads differ");
}
