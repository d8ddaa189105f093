//! Golden regression frames (HOBAK's habit): three shipped scenes, each run to one frame and
//! compared with a record kept in `tests/golden/<scene>.json`, so that a change that alters
//! results is caught even where every property test still holds.
//!
//! - `sheet_on_sphere` frame 15: adaptive remeshing, obstacle contact, CCD and step retries;
//! - `flag_wind` frame 20: wind drag on a pinned flag (fixed mesh, no collisions);
//! - `sheet_fold` frame 9: self-collision (contacts and impact zones) on a fixed mesh.
//!
//! Node and face counts must match exactly; the sampled node coordinates to 1e-9 of the scene's
//! size (the diagonal of the frame's bounding box) and the total energy to 1e-9 of itself. A
//! hash of all positions' bits is printed when it differs (the same results on another
//! platform or compiler may differ in the last bits), not failed on.
//!
//! The records were made from the code at the time they were last blessed; re-bless after a
//! change that is meant to alter results, and say so in its commit:
//! `VIEWCLOTH_BLESS=1 cargo test --release --test golden` writes the files.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use viewcloth::math::{Real, Vec3};
use viewcloth::scene;
use viewcloth::sim::Simulation;

/// Relative tolerance on coordinates (of the scene's size) and on the total energy.
const TOLERANCE: Real = 1e-9;
/// How many nodes are sampled, evenly spread over the node numbering.
const SAMPLES: usize = 8;

/// What is kept of one frame.
#[derive(Debug, Serialize, Deserialize)]
struct Record {
    /// Scene file, relative to the crate root.
    scene: String,
    frame: usize,
    nodes: usize,
    faces: usize,
    /// FNV-1a 64 of every node position's coordinates' bits (little-endian), in node order.
    positions_hash: String,
    /// Diagonal of the positions' bounding box (m): the scale of the coordinate tolerance.
    size: Real,
    samples: Vec<Sample>,
    total_energy: Real,
}

/// A sampled node and its position.
#[derive(Debug, Serialize, Deserialize)]
struct Sample {
    node: usize,
    x: [Real; 3],
}

fn crate_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Runs `scene_file` to `frame` as `viewcloth simulate` does and records that frame.
fn record(scene_file: &str, frame: usize) -> Record {
    let scene = scene::load_file(&crate_path(scene_file)).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{scene_file}: {e}"));
    for f in 1..=frame {
        sim.advance_frame().unwrap_or_else(|e| panic!("{scene_file} frame {f}: {e}"));
    }
    let x = sim.state.mesh.positions();
    let stats = sim.measure(frame);
    let hash = x
        .iter()
        .flat_map(|p| p.iter())
        .flat_map(|c| c.to_bits().to_le_bytes())
        .fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    let (lo, hi) = x
        .iter()
        .fold((Vec3::repeat(Real::INFINITY), Vec3::repeat(Real::NEG_INFINITY)), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    let samples = (0..SAMPLES)
        .map(|k| k * (x.len() - 1) / (SAMPLES - 1))
        .map(|node| Sample { node, x: x[node].into() })
        .collect();
    Record {
        scene: scene_file.into(),
        frame,
        nodes: stats.nodes,
        faces: stats.faces,
        positions_hash: format!("{hash:016x}"),
        size: (hi - lo).norm(),
        samples,
        total_energy: stats.total_energy.expect("a simulated frame has its energy"),
    }
}

/// The record as JSON, a sample per line.
fn to_json(r: &Record) -> String {
    fn json<T: Serialize + ?Sized>(v: &T) -> String {
        serde_json::to_string(v).unwrap()
    }
    let samples: Vec<String> = r.samples.iter().map(|s| format!("    {}", json(s))).collect();
    let fields = [
        format!("\"scene\": {}", json(&r.scene)),
        format!("\"frame\": {}", r.frame),
        format!("\"nodes\": {}", r.nodes),
        format!("\"faces\": {}", r.faces),
        format!("\"positions_hash\": {}", json(&r.positions_hash)),
        format!("\"size\": {}", json(&r.size)),
        format!("\"samples\": [\n{}\n  ]", samples.join(",\n")),
        format!("\"total_energy\": {}", json(&r.total_energy)),
    ];
    format!("{{\n  {}\n}}\n", fields.join(",\n  "))
}

/// Re-runs the recorded frame of `name` and compares (or, with VIEWCLOTH_BLESS set, writes the
/// record, with `frame` for a new one).
fn check(name: &str, frame: usize) {
    let path = crate_path(&format!("tests/golden/{name}.json"));
    let scene_file = format!("scenes/{name}.json");
    if std::env::var_os("VIEWCLOTH_BLESS").is_some() {
        let new = record(&scene_file, frame);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, to_json(&new)).unwrap();
        eprintln!("{}: blessed frame {frame}", path.display());
        return;
    }
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let old: Record = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!((old.scene.as_str(), old.frame), (scene_file.as_str(), frame), "{}", path.display());
    let new = record(&old.scene, old.frame);
    let what = format!("{name} frame {}", old.frame);
    assert_eq!((new.nodes, new.faces), (old.nodes, old.faces), "{what}: (nodes, faces)");
    let tol = TOLERANCE * old.size;
    for (a, b) in new.samples.iter().zip(&old.samples) {
        assert_eq!(a.node, b.node, "{what}: sampled node numbers");
        let d = (Vec3::from(a.x) - Vec3::from(b.x)).amax();
        let (i, a, b) = (a.node, a.x, b.x);
        assert!(d <= tol, "{what}: node {i} at {a:?}, recorded {b:?} ({d:.3e} m apart, tolerance {tol:.1e} m)");
    }
    let de = (new.total_energy - old.total_energy).abs();
    assert!(
        de <= TOLERANCE * old.total_energy.abs(),
        "{what}: total energy {}, recorded {} (relative difference {:.3e})",
        new.total_energy,
        old.total_energy,
        de / old.total_energy.abs()
    );
    if new.positions_hash != old.positions_hash {
        println!(
            "{what}: positions' bits differ from the record (hash {} ≠ {}), within tolerance",
            new.positions_hash, old.positions_hash
        );
    }
}

#[test]
fn sheet_on_sphere_frame_15() {
    check("sheet_on_sphere", 15);
}

#[test]
fn flag_wind_frame_20() {
    check("flag_wind", 20);
}

#[test]
fn sheet_fold_frame_9() {
    check("sheet_fold", 9);
}
