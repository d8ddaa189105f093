//! Adaptive remeshing in whole simulations (issue 4, "Tests"): the mesh stays valid and keeps
//! its material area frame after frame, handles stay on target, and the adaptive sphere shot uses
//! ≥ 3× fewer faces than the uniform reference with zero penetrations. That a squeezed sheet
//! refines where it buckles and coarsens back when released is tested on ARCSim's own
//! `square.json` against ARCSim's face counts (`tests/arcsim.rs`, issue 16).

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::temp_dir;
use serde_json::Value;
use viewcloth::scene::{self, RemeshMode};
use viewcloth::sim::Simulation;

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

fn run_cli(scene: &Path, out: &Path, extra: &[&str]) -> Value {
    let status = Command::new(env!("CARGO_BIN_EXE_viewcloth"))
        .arg("simulate")
        .arg(scene)
        .arg("--quiet")
        .arg("--out")
        .arg(out)
        .args(extra)
        .status()
        .expect("run viewcloth");
    assert!(status.success(), "viewcloth failed on {scene:?}");
    serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap()
}

fn total_material_area(sim: &Simulation) -> f64 {
    (0..sim.state.mesh.faces.len()).map(|f| sim.state.mesh.material_area(f)).sum()
}

#[test]
fn crumple_square_stays_valid_and_keeps_area_and_handles() {
    let scene = scene::load_file(&scene_path("crumple_square.json")).unwrap();
    let mut sim = Simulation::new(scene).unwrap();
    let area0 = total_material_area(&sim);
    let mut changed = false;
    for _ in 0..90 {
        let faces_before = sim.state.mesh.faces.len();
        sim.advance_frame().unwrap();
        changed |= sim.state.mesh.faces.len() != faces_before;
        sim.state.mesh.validate().unwrap();
        let area = total_material_area(&sim);
        assert!((area - area0).abs() <= 1e-9 * area0, "material area {area} vs {area0}");
        for (h, nodes) in sim.scene.handles.iter().zip(&sim.state.handle_nodes) {
            for (k, &n) in nodes.iter().enumerate() {
                assert_eq!(sim.state.mesh.nodes[n].x, h.target(k, sim.state.time), "handle node moved off target");
            }
        }
    }
    assert!(changed, "the mesh never changed");
}

#[test]
fn sheet_on_sphere_adaptive_uses_3x_fewer_faces_than_uniform_without_penetrating() {
    let frames = 25;
    let adaptive =
        run_cli(&scene_path("sheet_on_sphere.json"), &temp_dir("sos_adaptive"), &["--frames", &frames.to_string()]);
    assert_eq!(adaptive["mode"], "adaptive");
    let fr = adaptive["frames"].as_array().unwrap();
    assert!(fr.iter().all(|f| f["penetrations"].as_u64() == Some(0)), "adaptive run penetrated");
    let mean_adaptive = fr.iter().map(|f| f["faces"].as_f64().unwrap()).sum::<f64>() / fr.len() as f64;
    // The uniform reference never remeshes, so its face count is that of its initial mesh.
    let mut scene = scene::load_file(&scene_path("sheet_on_sphere.json")).unwrap();
    assert_eq!(scene.set_remesh_mode(RemeshMode::Uniform), 1);
    let uniform_faces = Simulation::new(scene).unwrap().state.mesh.faces.len() as f64;
    assert!(uniform_faces >= 3.0 * mean_adaptive, "uniform {uniform_faces} vs adaptive mean {mean_adaptive}");
}
