//! Checkpoint and resume (issue 5): a run killed with SIGKILL at arbitrary instants leaves only
//! complete files, and `viewcloth resume` continues it to frames byte-identical to an
//! uninterrupted run's. The scene remeshes adaptively, collides with a moving obstacle and has
//! handles (renumbered by remeshing), so every kind of state a checkpoint holds is exercised.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::{temp_dir, write_checkpoint};
use serde_json::{json, Value};
use viewcloth::io::obj::parse_obj;
use viewcloth::scene;
use viewcloth::sim::checkpoint;
use viewcloth::sim::Simulation;

const FRAMES: usize = 14;

/// sheet_on_sphere, coarser and shorter, with the sphere moving from the start.
fn scene_json() -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sheet_on_sphere.json");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["frames"] = json!(FRAMES);
    v["cloths"][0]["remesh"]["size"] = json!([0.03, 0.2]);
    v["obstacles"][0]["motion"] = json!([
        { "time": 0.0, "translate": [0, 0, 0] },
        { "time": 0.6, "translate": [0, -0.2, 0.05] }
    ]);
    v
}

fn viewcloth(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_viewcloth"));
    c.args(args).stdout(Stdio::null()).stderr(Stdio::piped());
    c
}

/// The test scene written into `dir` and its uninterrupted run in `dir/reference`: the scene
/// file, the directory for the run under test (`dir/run`) and the reference frames.
fn reference_run(dir: &Path) -> (PathBuf, PathBuf, Vec<(String, Vec<u8>)>) {
    let scene = dir.join("scene.json");
    std::fs::write(&scene, scene_json().to_string()).unwrap();
    let reference_dir = dir.join("reference");
    let out = viewcloth(&["simulate", scene.to_str().unwrap(), "--out", reference_dir.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(out.status.success(), "reference run: {}", String::from_utf8_lossy(&out.stderr));
    (scene, dir.join("run"), frame_files(&reference_dir))
}

fn frame_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| {
            let n = e.file_name().to_string_lossy().into_owned();
            n.starts_with("frame_") && n.ends_with(".obj")
        })
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
        .collect();
    v.sort();
    v
}

/// Kills `child` once `ready(dir)` holds and `extra` has passed (or the child has exited).
fn kill_when(mut child: Child, dir: &Path, ready: impl Fn(&Path) -> bool, extra: Duration) -> bool {
    let start = Instant::now();
    while !ready(dir) {
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "run did not get far enough");
        std::thread::sleep(Duration::from_millis(2));
    }
    std::thread::sleep(extra);
    let killed = child.try_wait().unwrap().is_none();
    let _ = child.kill();
    let _ = child.wait();
    killed
}

fn has_checkpoint_at_least(frame: usize) -> impl Fn(&Path) -> bool {
    move |dir: &Path| checkpoint::list(dir).map(|l| l.iter().any(|(f, _)| *f >= frame)).unwrap_or(false)
}

/// Every file present is complete: frames parse, have faces and equal the reference run's
/// frame; stats.json is valid JSON; checkpoints read back. Temporaries of interrupted writes
/// are the only exception (they are hidden and `resume` removes them).
fn check_complete(dir: &Path, reference: &[(String, Vec<u8>)], what: &str) {
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().to_string_lossy().into_owned();
        let path = e.path();
        if viewcloth::io::is_temp_name(&name) {
            continue;
        }
        if name.starts_with("frame_") {
            let bytes = std::fs::read(&path).unwrap();
            let obj =
                parse_obj(std::str::from_utf8(&bytes).unwrap()).unwrap_or_else(|e| panic!("{what}: {name}: {e:?}"));
            assert!(!obj.triangles.is_empty(), "{what}: {name} has no faces");
            let r = reference.iter().find(|(n, _)| *n == name).unwrap_or_else(|| panic!("{what}: unexpected {name}"));
            assert!(r.1 == bytes, "{what}: {name} differs from the uninterrupted run");
        } else if name == "stats.json" {
            let v: Value = serde_json::from_slice(&std::fs::read(&path).unwrap())
                .unwrap_or_else(|e| panic!("{what}: stats.json: {e}"));
            assert!(v["frames"].as_array().is_some_and(|f| !f.is_empty()), "{what}: stats.json without frames");
        } else if name.starts_with("checkpoint_") {
            checkpoint::read(&path).unwrap_or_else(|e| panic!("{what}: {e}"));
        } else {
            panic!("{what}: unexpected file {name}");
        }
    }
}

#[test]
fn killed_run_resumes_to_identical_frames() {
    let dir = temp_dir("kill-resume");
    let (scene, run_dir, reference) = reference_run(&dir);
    let (s, o) = (scene.to_str().unwrap(), run_dir.to_str().unwrap());
    assert_eq!(reference.len(), FRAMES + 1);

    // Killed right after its second checkpoint (frame 4), then twice more while resuming, the
    // last time a few milliseconds into a frame.
    let child = viewcloth(&["simulate", s, "--out", o, "--quiet", "--checkpoint-every", "2"]).spawn().unwrap();
    assert!(kill_when(child, &run_dir, has_checkpoint_at_least(4), Duration::ZERO), "run finished before the kill");
    check_complete(&run_dir, &reference, "after the first kill");
    let latest = checkpoint::list(&run_dir).unwrap()[0].0;
    let child = viewcloth(&["resume", o, "--quiet"]).spawn().unwrap();
    assert!(kill_when(child, &run_dir, has_checkpoint_at_least(latest + 2), Duration::from_millis(30)));
    check_complete(&run_dir, &reference, "after the second kill");
    let latest = checkpoint::list(&run_dir).unwrap()[0].0;
    let child = viewcloth(&["resume", o, "--quiet"]).spawn().unwrap();
    kill_when(child, &run_dir, has_checkpoint_at_least(latest + 2), Duration::from_millis(7));
    check_complete(&run_dir, &reference, "after the third kill");

    let out = viewcloth(&["resume", o, "--quiet"]).output().unwrap();
    assert!(out.status.success(), "resume: {}", String::from_utf8_lossy(&out.stderr));
    check_complete(&run_dir, &reference, "after the resume");
    assert!(
        std::fs::read_dir(&run_dir)
            .unwrap()
            .all(|e| !viewcloth::io::is_temp_name(&e.unwrap().file_name().to_string_lossy())),
        "temporaries left after resume"
    );
    let resumed = frame_files(&run_dir);
    assert_eq!(resumed.len(), reference.len());
    for ((name, bytes), (_, want)) in resumed.iter().zip(&reference) {
        assert!(bytes == want, "{name} differs from the uninterrupted run");
    }
    let stats: Value = serde_json::from_slice(&std::fs::read(run_dir.join("stats.json")).unwrap()).unwrap();
    assert_eq!(stats["frames"].as_array().unwrap().len(), FRAMES + 1);
    assert!(!stats["resumed_at"].as_array().unwrap().is_empty());
    std::fs::remove_dir_all(&dir).ok();
}

/// The state after restoring a checkpoint and stepping on equals, bit for bit, the state of
/// the run that never stopped (positions, velocities, masses, material coordinates, topology,
/// handle nodes, time).
#[test]
fn restored_state_continues_bitwise() {
    let dir = temp_dir("restore-bits");
    let file = dir.join("scene.json");
    let text = scene_json().to_string();
    std::fs::write(&file, &text).unwrap();
    let load = || scene::load_file(&file).unwrap();
    let mut a = Simulation::new(load()).unwrap();
    let faces0 = a.state.mesh.faces.len();
    for _ in 0..5 {
        a.advance_frame().unwrap();
    }
    let (run, path) = write_checkpoint(&dir, &a, &load(), Some(file.clone()), FRAMES, 5);
    let ck = checkpoint::read(&path).unwrap();
    assert_eq!(ck.run, run);
    let mut b = Simulation::restore(load(), ck.state).unwrap();
    for f in 6..=9 {
        a.advance_frame().unwrap();
        b.advance_frame().unwrap();
        let bits = |s: &Simulation| -> Vec<u64> {
            let m = &s.state.mesh;
            let mut v: Vec<u64> = m
                .nodes
                .iter()
                .flat_map(|n| {
                    n.x.iter().chain(n.v.iter()).chain([n.mass].iter()).map(|c| c.to_bits()).collect::<Vec<_>>()
                })
                .collect();
            v.extend(m.verts.iter().flat_map(|x| [x.u.x.to_bits(), x.u.y.to_bits(), x.node.0 as u64]));
            v.extend(m.faces.iter().flat_map(|x| x.v.map(|i| i.0 as u64)));
            v.extend(s.state.handle_nodes.iter().flatten().map(|&n| n as u64));
            v.extend(s.state.rest_angles.iter().map(|a| a.to_bits()));
            v.push(s.state.time.to_bits());
            v.push(s.state.steps);
            v
        };
        assert!(bits(&a) == bits(&b), "frame {f}: the restored run differs");
    }
    // The comparison covered a remeshed state.
    assert_ne!(a.state.mesh.faces.len(), faces0);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn resume_rejects_missing_and_damaged_checkpoints_and_changed_scenes() {
    let dir = temp_dir("resume-bad");
    let out = viewcloth(&["resume", dir.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("no checkpoint") && err.lines().count() == 1, "{err}");

    let scene = dir.join("scene.json");
    let mut v = scene_json();
    v["frames"] = json!(3);
    std::fs::write(&scene, v.to_string()).unwrap();
    let run = dir.join("run");
    let (s, o) = (scene.to_str().unwrap(), run.to_str().unwrap());
    let out = viewcloth(&["simulate", s, "--out", o, "--quiet", "--checkpoint-every", "1"]).output().unwrap();
    assert!(out.status.success());
    // Damaged newest checkpoint: resume falls back to the one before it.
    let list = checkpoint::list(&run).unwrap();
    assert_eq!(list.iter().map(|(f, _)| *f).collect::<Vec<_>>(), vec![3, 2]);
    let mut bytes = std::fs::read(&list[0].1).unwrap();
    let k = bytes.len() / 2;
    bytes[k] ^= 1;
    std::fs::write(&list[0].1, &bytes).unwrap();
    let out = viewcloth(&["resume", o, "--quiet"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // Both damaged: exit 2 naming the file.
    for (_, p) in checkpoint::list(&run).unwrap() {
        std::fs::write(&p, b"VCLOTHCK garbage").unwrap();
    }
    let out = viewcloth(&["resume", o, "--quiet"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("checkpoint_") && !err.contains("panicked"), "{err}");
    // A changed scene is refused.
    let out = viewcloth(&["simulate", s, "--out", o, "--quiet", "--checkpoint-every", "1"]).output().unwrap();
    assert!(out.status.success());
    v["gravity"] = json!([0, 0, -9.7]);
    std::fs::write(&scene, v.to_string()).unwrap();
    let out = viewcloth(&["resume", o, "--frames", "5", "--quiet"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("changed"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 15: SIGTERM stops a run at the end of its frame with a checkpoint of it and exit 75
/// (even without --checkpoint-every), and `resume` finishes it byte-identically.
#[test]
fn sigterm_checkpoints_exits_75_and_resume_finishes_identically() {
    let dir = temp_dir("sigterm");
    let (scene, run_dir, reference) = reference_run(&dir);
    let (s, o) = (scene.to_str().unwrap(), run_dir.to_str().unwrap());

    for (what, extra) in [("no periodic checkpoints", &[][..]), ("every 5", &["--checkpoint-every", "5"][..])] {
        let _ = std::fs::remove_dir_all(&run_dir);
        let mut args = vec!["simulate", s, "--out", o, "--progress", "lines"];
        args.extend(extra);
        let child = viewcloth(&args).spawn().unwrap();
        let start = Instant::now();
        while !run_dir.join("frame_0003.obj").exists() {
            assert!(start.elapsed() < Duration::from_secs(120), "{what}: run did not get to frame 3");
            std::thread::sleep(Duration::from_millis(2));
        }
        let pid = child.id().to_string();
        assert!(Command::new("kill").args(["-TERM", &pid]).status().unwrap().success());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(75), "{what}: {err}");
        let last = err.lines().last().unwrap_or("");
        assert!(last.starts_with("error: interrupted after frame") && last.contains("resume"), "{what}: {err}");
        let at = checkpoint::list(&run_dir).unwrap()[0].0;
        assert!((3..FRAMES).contains(&at), "{what}: checkpoint at {at}");
        assert!(err.contains(&format!("frame {at}/{FRAMES}")), "{what}: no progress line of frame {at}: {err}");
        check_complete(&run_dir, &reference, what);
        let stats: Value = serde_json::from_slice(&std::fs::read(run_dir.join("stats.json")).unwrap()).unwrap();
        assert!(stats["error"].as_str().is_some_and(|e| e.contains("interrupted")), "{what}: {stats}");

        let out = viewcloth(&["resume", o, "--quiet"]).output().unwrap();
        assert!(out.status.success(), "{what}: resume: {}", String::from_utf8_lossy(&out.stderr));
        let resumed = frame_files(&run_dir);
        assert_eq!(resumed.len(), reference.len(), "{what}");
        for ((name, bytes), (_, want)) in resumed.iter().zip(&reference) {
            assert!(bytes == want, "{what}: {name} differs from the uninterrupted run");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 15: a fresh `simulate` into a directory holding another scene's run is refused (exit
/// 2, one line, nothing touched) unless --force, which also removes that run's checkpoints (a
/// stale checkpoint must never be resumed into the new run's output).
#[test]
fn simulate_refuses_another_scenes_output_without_force() {
    let dir = temp_dir("claim");
    let run = dir.join("run");
    let o = run.to_str().unwrap();
    let sheet = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hanging_sheet.json");
    let flag = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/flag_wind.json");
    let (sheet, flag) = (sheet.to_str().unwrap(), flag.to_str().unwrap());
    let ok = |args: &[&str]| {
        let out = viewcloth(args).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    };
    ok(&["simulate", sheet, "--frames", "2", "--out", o, "--quiet", "--checkpoint-every", "1"]);
    // The same scene again: allowed (a rerun), the old run's files replaced.
    ok(&["simulate", sheet, "--frames", "1", "--out", o, "--quiet"]);
    assert!(!run.join("frame_0002.obj").exists() && checkpoint::list(&run).unwrap().is_empty());
    ok(&["simulate", sheet, "--frames", "2", "--out", o, "--quiet", "--checkpoint-every", "1"]);
    let before = frame_files(&run);
    let out = viewcloth(&["simulate", flag, "--frames", "1", "--out", o, "--quiet"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("--force") && err.contains("another scene"), "{err}");
    assert!(frame_files(&run) == before, "a refused run touched the frames");
    ok(&["simulate", flag, "--frames", "1", "--out", o, "--quiet", "--force"]);
    assert!(checkpoint::list(&run).unwrap().is_empty(), "the other run's checkpoints were kept");
    assert_eq!(frame_files(&run).len(), 2);
    let out = viewcloth(&["resume", o, "--quiet"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "resume found a checkpoint of the replaced run");
    std::fs::remove_dir_all(&dir).ok();
}
