//! Stiff cloth pushed by a moving obstacle (ARCSim's crumple-pnas: aluminium foil crushed inside
//! a shrinking sphere stopped at frame 50). The repulsion cannot hold a stiff sheet edge-on, so
//! the solve puts its edge into the obstacle and the impact zones push the edge nodes back
//! alone, storing the sheet's compression in its last elements: energy the end-of-step check
//! refuses at every step size. Spread through the step's system (`solver::spread`), the push
//! moves the strip as a whole and the run goes on.
//!
//! The scene: a 100 mm × 10 mm strip of foil (E·t = 1.8 MN/m, 71 g/m², ARCSim's
//! `materials/aluminium.json` typed in), flat, its left end held, no gravity; a wall (a box) 1.5 mm
//! from its right end moves 3 mm towards it over 1 s. A thin strip compressed end-on buckles: at
//! the end it bows out of its plane and holds little energy.

mod common;

use common::{temp_dir, viewcloth};
use serde_json::json;
use viewcloth::math::Real;

const FRAMES: usize = 50;

#[test]
fn a_foil_strip_pushed_end_on_by_a_wall_buckles_without_stopping_the_run() {
    let dir = temp_dir("wall");
    let scene = json!({
        "version": 1, "name": "wall", "frame_time": 0.02, "steps_per_frame": 5, "frames": FRAMES,
        "gravity": [0, 0, 0],
        "collision": { "thickness": 1e-3, "friction": 0.0, "self_collision": false },
        "cloths": [{
            "rectangle": { "width": 0.1, "height": 0.01, "resolution": [40, 4] },
            "material": { "density": 0.071, "youngs_modulus": 70e9, "thickness": 25.4e-6,
                          "poisson_ratio": 0.0, "bending": 8e-6 },
            "rest_angles": "flat",
            "handles": [{ "region": { "min": [-1, -1], "max": [0.001, 1] } }]
        }],
        "obstacles": [{
            "box": { "size": [0.02, 0.1, 0.1] },
            "transform": { "translate": [0.1115, 0.005, 0] },
            "motion": [{ "time": 0 }, { "time": 1.0, "translate": [-0.003, 0, 0] }]
        }]
    });
    let file = dir.join("wall.json");
    std::fs::write(&file, scene.to_string()).unwrap();
    let out = dir.join("out");
    let run = viewcloth(&[
        "simulate",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "1",
        "--quiet",
        "--export-obstacles",
    ]);
    assert!(run.status.success(), "the run stopped: {}", String::from_utf8_lossy(&run.stderr));
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap();
    let frames = stats["frames"].as_array().unwrap();
    assert_eq!(frames.len(), FRAMES + 1);
    let sum = |key: &str| frames.iter().map(|f| f[key].as_u64().unwrap()).sum::<u64>();
    assert!(sum("spread_pushes") > 0, "no push was spread: the scene no longer exercises the recovery");
    let steps = sum("steps");
    assert!(sum("retries") * 10 < steps, "{} of {steps} steps retried", sum("retries"));
    // No crossing, counted from the written files.
    let crossings = viewcloth(&["crossings", out.to_str().unwrap()]);
    assert!(crossings.status.success(), "{}", String::from_utf8_lossy(&crossings.stdout));
    // The strip buckled: its right end is where the wall pushed it (3 mm travel, 1.5 mm gap, the
    // wall's face then at 98.5 mm) and its middle bows out of the plane; the energy of its
    // compression went into bending (a flat strip shortened by 1.5 mm would hold
    // ½·(E·t·w/L)·δ² = 0.2 J).
    let last = viewcloth::io::obj::read_obj(&out.join(format!("frame_{FRAMES:04}.obj"))).unwrap();
    let x: Vec<[Real; 3]> = last.positions.iter().map(|p| [p.x, p.y, p.z]).collect();
    let x_max = x.iter().map(|p| p[0]).fold(Real::MIN, Real::max);
    let bow = x.iter().map(|p| p[2].abs()).fold(0.0, Real::max);
    assert!(x_max < 0.0985, "the right end at {x_max} m, inside the wall's thickness band");
    assert!(bow > 5e-3, "the strip did not buckle: out of plane by {bow} m");
    let energy = frames[FRAMES]["total_energy"].as_f64().unwrap();
    assert!(energy < 1e-4, "the strip holds {energy} J at the end");
    let strain = frames[FRAMES]["max_strain"].as_f64().unwrap();
    assert!(strain < 1e-3, "largest strain {strain} at the end");
}
