//! The untangling stage (`sim::untangle`, Baraff, Witkin & Kass 2003): cloth that has passed
//! through itself is taken back. Two floating sheets 6 mm apart (thickness 4 mm), one node of
//! the upper one pushed 3 mm through the lower one: a crossing the collision stages alone keep.
//! With the stage, no frame after the first has a crossing triangle pair (counted from the
//! written files by `viewcloth crossings`) and the total energy does not grow; with the
//! separation stages disabled the crossing stays (what the stage is for).

mod common;

use std::fmt::Write;
use std::path::Path;

use common::{temp_dir, viewcloth};
use viewcloth::io::stats::RunStats;

/// An n×n grid of nodes over a 0.4 m square at `offset`, as OBJ lines (flat material
/// coordinates), with node `poke.0` (row-major, 0-based) at height `poke.1`; `base` is the OBJ
/// index of its first vertex.
fn grid(obj: &mut String, n: usize, offset: [f64; 3], poke: Option<(usize, f64)>, base: usize) {
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            let (x, y) = (0.4 * i as f64 / (n - 1) as f64, 0.4 * j as f64 / (n - 1) as f64);
            let z = match poke {
                Some((p, z)) if p == k => z,
                _ => offset[2],
            };
            writeln!(obj, "v {} {} {z}\nvt {x} {y}", x + offset[0], y + offset[1]).unwrap();
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v = |i: usize, j: usize| base + j * n + i;
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            writeln!(obj, "f {a}/{a} {b}/{b} {c}/{c}\nf {a}/{a} {c}/{c} {d}/{d}").unwrap();
        }
    }
}

/// Writes the two sheets and a scene for them (`disable` as given) under `dir`; returns the
/// scene's path.
fn tangled_scene(dir: &Path, disable: &[&str]) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let n = 9;
    let mut obj = String::new();
    grid(&mut obj, n, [0.0, 0.0, 0.0], None, 1);
    // The upper sheet offset so that none of its nodes lies over a lower node or edge; its
    // centre node 3 mm below the lower sheet.
    grid(&mut obj, n, [0.013, 0.007, 0.006], Some((4 * n + 4, -0.003)), 1 + n * n);
    std::fs::write(dir.join("sheets.obj"), obj).unwrap();
    let scene = serde_json::json!({
        "version": 1,
        "name": "tangled",
        "frame_time": 0.04,
        "steps_per_frame": 8,
        "frames": 4,
        "gravity": [0.0, 0.0, 0.0],
        "cloths": [{ "name": "sheets", "mesh": "sheets.obj", "material": { "preset": "cotton" } }],
        "collision": { "thickness": 0.004, "friction": 0.3, "self_collision": true },
        "disable": disable,
    });
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path
}

/// Runs the scene; returns its stats and (frame, crossings_self) counted from the files.
fn run(scene: &Path, out: &Path) -> (RunStats, Vec<(usize, usize)>) {
    let done = viewcloth(&["simulate", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--quiet"]);
    assert!(done.status.success(), "{}", String::from_utf8_lossy(&done.stderr));
    let stats: RunStats = serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap();
    let counted = viewcloth(&["crossings", out.to_str().unwrap()]);
    let rows = String::from_utf8_lossy(&counted.stdout)
        .lines()
        .filter_map(|l| {
            let f: Vec<usize> = l.split('\t').map(|w| w.parse().ok()).collect::<Option<_>>()?;
            (f.len() == 3).then(|| (f[0], f[1]))
        })
        .collect();
    (stats, rows)
}

#[test]
fn a_node_poked_through_the_other_sheet_comes_back() {
    let root = temp_dir("untangle");
    let (stats, rows) = run(&tangled_scene(&root.join("on"), &[]), &root.join("on/out"));
    assert_eq!(rows.len(), 5, "frames 0-4 counted: {rows:?}");
    assert!(rows[0].1 > 0, "the input crosses itself: {rows:?}");
    for &(frame, crossings) in &rows[1..] {
        assert_eq!(crossings, 0, "frame {frame} still crosses (from the files): {rows:?}");
    }
    let frames = &stats.frames;
    let moved: usize = frames.iter().filter_map(|f| f.collision.as_ref()).map(|c| c.untangled_nodes).sum();
    assert!(moved > 0, "the stage moved nothing");
    assert!(frames[1..].iter().all(|f| f.crossings_self == 0), "stats.json: crossings after frame 0");
    let energy = |k: usize| frames[k].total_energy.expect("energies are written");
    for k in 1..frames.len() {
        assert!(energy(k) <= energy(0) * 1.001 + 1e-9, "frame {k}: energy {} from {}", energy(k), energy(0));
    }

    // Without the stage the collision stages keep the crossing.
    let (_, rows) = run(&tangled_scene(&root.join("off"), &["separation"]), &root.join("off/out"));
    assert!(rows.last().is_some_and(|r| r.1 > 0), "the crossing went away by itself: {rows:?}");
}
