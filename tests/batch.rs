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

fn summary_statuses(path: &Path) -> Vec<String> {
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    s["shots"].as_array().unwrap().iter().map(|r| r["status"].as_str().unwrap().to_string()).collect()
}

fn frames_of(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_name().to_string_lossy().starts_with("frame_"))
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
        .collect();
    v.sort();
    v
}

/// Issue 15: a rerun skips a finished shot and resumes an unfinished one from its checkpoint
/// (frames identical to an uninterrupted run); `--shot N` and `--shot-from-env VAR` run one shot.
#[test]
fn rerun_skips_finished_shots_and_resumes_unfinished_ones() {
    let dir = temp_dir("idempotent");
    let s = root().join("scenes");
    let shots = format!(
        r#"{{ "version": 1, "shots": [
  {{ "scene": "{s}/hanging_sheet.json", "frames": 4, "out": "a" }},
  {{ "scene": "{s}/flag_wind.json", "frames": 4, "out": "b", "checkpoint_every": 2 }}
] }}"#,
        s = s.display()
    );
    let file = dir.join("shots.json");
    std::fs::write(&file, shots).unwrap();
    let (f, summary) = (file.to_str().unwrap(), dir.join("summary.json"));
    let sum = summary.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["batch", f, "--summary", sum, "--progress", "none"];
        args.extend(extra);
        let o = viewcloth(&args);
        assert!(o.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&o.stderr));
    };
    // Shot 1 stopped at frame 2 (as a run interrupted there leaves it).
    let b = dir.join("b");
    let flag = s.join("flag_wind.json");
    let o = viewcloth(&[
        "simulate",
        flag.to_str().unwrap(),
        "--frames",
        "2",
        "--checkpoint-every",
        "2",
        "--out",
        b.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    run(&["--shot", "1"]);
    assert_eq!(summary_statuses(&summary), ["resumed"]);
    assert!(!dir.join("a").exists(), "--shot 1 ran shot 0");
    let alone = dir.join("b_alone");
    let o =
        viewcloth(&["simulate", flag.to_str().unwrap(), "--frames", "4", "--out", alone.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success());
    assert!(frames_of(&b) == frames_of(&alone), "the resumed shot differs from simulate's");

    run(&[]);
    assert_eq!(summary_statuses(&summary), ["done", "skipped"]);
    let a = frames_of(&dir.join("a"));
    assert_eq!(a.len(), 5);
    // SHOT_INDEX picks shot 0, which is finished.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_viewcloth"))
        .args(["batch", f, "--summary", sum, "--shot-from-env", "SHOT_INDEX"])
        .env("SHOT_INDEX", "0")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary_statuses(&summary), ["skipped"]);
    assert!(frames_of(&dir.join("a")) == a);

    for (args, env, want) in [
        (vec!["--shot", "2"], None, "has 2 shots"),
        (vec!["--shot-from-env", "SHOT_INDEX"], Some("x"), "expected a shot index"),
        (vec!["--shot-from-env", "NO_SUCH_VARIABLE_15"], None, "is not set"),
    ] {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_viewcloth"));
        c.args(["batch", f]).args(&args);
        if let Some(v) = env {
            c.env("SHOT_INDEX", v);
        }
        let o = c.output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.trim_end().lines().count() == 1 && e.contains(want), "{args:?}: {e}");
    }

    // An output directory holding another scene's run is refused before anything runs.
    let other = format!(
        r#"{{ "version": 1, "shots": [ {{ "scene": "{s}/crumple_square.json", "frames": 1, "out": "c" }},
           {{ "scene": "{s}/crumple_square.json", "frames": 1, "out": "a" }} ] }}"#,
        s = s.display()
    );
    std::fs::write(&file, other).unwrap();
    let o = viewcloth(&["batch", f, "--summary", sum]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("shots[1].out") && e.contains("--force") && e.trim_end().lines().count() == 1, "{e}");
    assert!(!dir.join("c").exists() && frames_of(&dir.join("a")) == a);
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 15: `--emit slurm` writes an array script (one task per shot, per-task logs, requeue,
/// a signal before the kill) that the shell parses, and each task's command line.
#[test]
fn emit_slurm_writes_an_array_script_and_the_command_lines() {
    let dir = temp_dir("emit");
    let s = root().join("scenes");
    let shots = format!(
        r#"{{ "version": 1, "shots": [ {{ "scene": "{s}/hanging_sheet.json", "frames": 3, "out": "a" }},
           {{ "scene": "{s}/flag_wind.json", "frames": 2, "out": "b" }} ] }}"#,
        s = s.display()
    );
    let file = dir.join("farm shots.json");
    std::fs::write(&file, shots).unwrap();
    let out = dir.join("slurm");
    let o = viewcloth(&[
        "batch",
        file.to_str().unwrap(),
        "--emit",
        "slurm",
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "3",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let script = std::fs::read_to_string(out.join("farm shots.sbatch")).unwrap();
    for want in [
        "#SBATCH --array=0-1\n",
        "#SBATCH --cpus-per-task=3\n",
        "#SBATCH --requeue\n",
        "#SBATCH --signal=B:TERM@120\n",
        "_%A_%a.log\n",
        "--shot-from-env SLURM_ARRAY_TASK_ID",
        "--progress lines",
        "scontrol requeue",
    ] {
        assert!(script.contains(want), "no {want:?} in\n{script}");
    }
    let ok = std::process::Command::new("bash").arg("-n").arg(out.join("farm shots.sbatch")).status().unwrap();
    assert!(ok.success(), "bash cannot parse the script");
    let commands = std::fs::read_to_string(out.join("farm shots.commands")).unwrap();
    let lines: Vec<&str> = commands.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(lines.len(), 2, "{commands}");
    assert!(lines[1].contains(" batch ") && lines[1].contains("--shot 1"), "{commands}");
    assert!(!commands.contains("--format"), "{commands}");
    assert!(!dir.join("a").exists(), "--emit ran a shot");
    // Issue 14: `--format` reaches the tasks.
    let f = file.to_str().unwrap();
    let o = viewcloth(&["batch", f, "--emit", "slurm", "--out", out.to_str().unwrap(), "--format", "usd"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let script = std::fs::read_to_string(out.join("farm shots.sbatch")).unwrap();
    assert!(script.contains("SLURM_ARRAY_TASK_ID") && script.contains(" --format usd"), "{script}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 15: SIGTERM stops a batch at the end of the running shot's frame with a checkpoint
/// (exit 75, the shot `interrupted` in the summary, no further shot started); the same batch
/// again resumes it to frames identical to `simulate`'s.
#[test]
fn sigterm_stops_a_batch_and_the_rerun_resumes_it() {
    let dir = temp_dir("sigterm");
    let s = root().join("scenes");
    let shots = format!(
        r#"{{ "version": 1, "shots": [ {{ "scene": "{s}/hanging_sheet.json", "frames": 40, "out": "a" }},
           {{ "scene": "{s}/flag_wind.json", "frames": 2, "out": "b" }} ] }}"#,
        s = s.display()
    );
    let file = dir.join("shots.json");
    std::fs::write(&file, shots).unwrap();
    let (f, summary) = (file.to_str().unwrap(), dir.join("summary.json"));
    let args = ["batch", f, "--summary", summary.to_str().unwrap(), "--threads", "1", "--progress", "lines"];
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_viewcloth"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !dir.join("a/frame_0005.obj").exists() {
        assert!(start.elapsed().as_secs() < 120, "shot 0 did not reach frame 5");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let pid = child.id().to_string();
    assert!(std::process::Command::new("kill").args(["-TERM", &pid]).status().unwrap().success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(75), "{err}");
    assert!(err.contains("shot 0 (hanging_sheet): frame 5/40"), "no progress line of frame 5: {err}");
    assert_eq!(summary_statuses(&summary), ["interrupted"]);
    let sum: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    assert_eq!((&sum["interrupted"], &sum["pending"]), (&serde_json::json!(1), &serde_json::json!(1)), "{sum}");
    assert!(!dir.join("b").exists(), "shot 1 started after the signal");

    let o = viewcloth(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary_statuses(&summary), ["resumed", "done"]);
    let alone = dir.join("a_alone");
    let sheet = s.join("hanging_sheet.json");
    let o = viewcloth(&[
        "simulate",
        sheet.to_str().unwrap(),
        "--frames",
        "40",
        "--out",
        alone.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success());
    assert!(frames_of(&dir.join("a")) == frames_of(&alone), "the resumed shot differs from simulate's");
    std::fs::remove_dir_all(&dir).ok();
}
