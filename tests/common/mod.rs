//! Shared by the integration tests (`mod common;`): the binary, fresh temporary directories, the
//! deterministic random generator of the unit tests, scenes given inline, finite-difference
//! checks.
#![allow(dead_code)]

pub mod fd;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

// For the generator's module, which takes them from its parent (as in `src/math`).
use viewcloth::math::{Real, Vec2, Vec3};
use viewcloth::mesh::Mesh;
use viewcloth::scene::{self, Scene};

/// One generator for unit and integration tests: the unit tests' file, compiled here too.
#[path = "../../src/math/test_rng.rs"]
mod test_rng;
#[allow(unused_imports)] // for the crates that draw no random numbers
pub use test_rng::Rng;

/// The binary run with `args`.
pub fn viewcloth(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_viewcloth")).args(args).output().expect("run viewcloth")
}

/// A fresh, empty directory `<crate>_<name>` under the test target's temporary directory (the
/// test crate's name keeps crates run in parallel apart).
pub fn temp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{}_{name}", env!("CARGO_CRATE_NAME")));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
    d
}

/// A scene given inline as JSON, named `name`; relative paths resolve in `base`.
pub fn inline_scene(v: &serde_json::Value, base: &Path, name: &str) -> Scene {
    scene::load_str(&v.to_string(), Path::new(name), base, name).unwrap_or_else(|e| panic!("{e}"))
}

/// Writes `sim`'s state as the checkpoint of frame `frame` (of a `frames`-frame run of `scene`,
/// read from `scene_file`, a checkpoint every `frame` frames, OBJ output) into `dir`; returns
/// its run record and path.
pub fn write_checkpoint(
    dir: &Path,
    sim: &viewcloth::sim::Simulation,
    scene: &Scene,
    scene_file: Option<PathBuf>,
    frames: usize,
    frame: usize,
) -> (viewcloth::sim::checkpoint::RunRecord, PathBuf) {
    use viewcloth::sim::checkpoint;
    let run = checkpoint::RunRecord {
        scene_file,
        mode: None,
        camera_file: None,
        fingerprint: checkpoint::scene_fingerprint(scene),
        frames,
        digits: 4,
        export_obstacles: false,
        every: frame,
        format: Default::default(),
        obj_velocities: false,
    };
    let path = checkpoint::checkpoint_path(dir, frame, 4);
    std::fs::write(&path, checkpoint::encode(&run, &sim.state, &Default::default())).unwrap();
    (run, path)
}

/// Largest and material-area-weighted mean principal strain (largest principal stretch − 1) of
/// an OBJ frame whose `vt` are material metres, computed here from the file alone (closed-form
/// eigenvalue of FᵀF), to check what `stats.json` says.
pub fn strain_of_obj(path: &Path) -> (Real, Real) {
    let obj = viewcloth::io::obj::read_obj(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (mut max, mut sum, mut area) = (Real::NEG_INFINITY, 0.0, 0.0);
    for t in &obj.triangles {
        let x = t.map(|c| obj.positions[c.v]);
        let u = t.map(|c| obj.texcoords[c.vt.expect("material coordinates")]);
        let (du1, du2) = (u[1] - u[0], u[2] - u[0]);
        let det = du1.x * du2.y - du2.x * du1.y;
        // F = [x1 − x0, x2 − x0] Dm⁻¹, Dm⁻¹ = [[du2.y, −du2.x], [−du1.y, du1.x]] / det.
        let (e1, e2) = (x[1] - x[0], x[2] - x[0]);
        let f0 = (e1 * du2.y - e2 * du1.y) / det;
        let f1 = (e2 * du1.x - e1 * du2.x) / det;
        let (a, b, d) = (f0.dot(&f0), f0.dot(&f1), f1.dot(&f1));
        let stretch = (0.5 * (a + d + ((a - d).powi(2) + 4.0 * b * b).sqrt())).sqrt();
        max = max.max(stretch - 1.0);
        sum += (stretch - 1.0) * 0.5 * det.abs();
        area += 0.5 * det.abs();
    }
    (max, sum / area)
}

/// Checks `dir/stats.json` against its OBJ frames: every written frame listed, each frame's
/// `max_strain` and `mean_strain` what `strain_of_obj` computes (to 1e-6: the OBJ rounds positions
/// to nanometres), within `bound` (largest |max strain|, |mean strain|), and some frame strained
/// (a moving cloth is never exactly at rest). Returns the stats.
pub fn check_stats_strain(dir: &Path, frames: usize, bound: (Real, Real)) -> serde_json::Value {
    let path = dir.join("stats.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let stats: serde_json::Value = serde_json::from_str(&text).unwrap();
    let listed = stats["frames"].as_array().unwrap();
    assert_eq!(listed.len(), frames, "{}", path.display());
    let mut largest: Real = 0.0;
    for f in listed {
        let k = f["frame"].as_u64().unwrap();
        let (max, mean) = strain_of_obj(&dir.join(format!("frame_{k:04}.obj")));
        let (got_max, got_mean) = (f["max_strain"].as_f64().unwrap(), f["mean_strain"].as_f64().unwrap());
        assert!((got_max - max).abs() < 1e-6, "{} frame {k}: max strain {got_max}, the OBJ's {max}", path.display());
        assert!((got_mean - mean).abs() < 1e-6, "{} frame {k}: mean {got_mean}, the OBJ's {mean}", path.display());
        let plausible = max.abs() < bound.0 && mean.abs() < bound.1;
        assert!(plausible, "{} frame {k}: strain {max}, {mean} beyond {bound:?}", path.display());
        largest = largest.max(max.abs()).max(mean.abs());
    }
    assert!(largest > 1e-5, "{}: no frame strained ({largest})", path.display());
    stats
}

/// World position of material point `u` (metres), by barycentric interpolation in the face
/// that contains it.
pub fn at_material(mesh: &Mesh, u: Vec2) -> Vec3 {
    for f in 0..mesh.faces.len() {
        let [a, b, c] = mesh.face_uv(f);
        let det = (b - a).perp(&(c - a));
        let l1 = (u - a).perp(&(c - a)) / det;
        let l2 = (b - a).perp(&(u - a)) / det;
        if l1 >= -1e-9 && l2 >= -1e-9 && l1 + l2 <= 1.0 + 1e-9 {
            let x = mesh.face_nodes(f).map(|n| mesh.nodes[n].x);
            return x[0] * (1.0 - l1 - l2) + x[1] * l1 + x[2] * l2;
        }
    }
    panic!("material point {u} outside the cloth");
}
