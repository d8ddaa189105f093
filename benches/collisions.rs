//! Collision benchmark (issue 3, "Benchmark"): `sheet_on_sphere` on a uniform sheet of about 10k
//! and 40k faces, timed while the sphere pushes through it. Reports the share of step time spent
//! in collision handling (the `proximity`, `collision`, `friction` and `penetration_check`
//! stages) and the impact-zone work per step.
//!
//! The shipped scene spends its first two seconds letting the sheet fall onto the resting sphere;
//! to time the collision-heavy part without simulating that fall at 40k faces, the sheet starts
//! hanging vertically 2 cm in front of the sphere (pinned at its two top corners, as in the scene)
//! and the sphere's keyframes are shifted two seconds earlier, so it sweeps into the sheet at up
//! to 2 m/s from the first frame. Material, thickness, friction and step size are the scene's.
//!
//! `cargo bench --bench collisions` runs both sizes; `cargo bench --bench collisions -- 71` only
//! the given resolutions n (2n² faces).

use std::path::Path;
use std::time::Instant;

use serde_json::{json, Value};
use viewcloth::scene::load_str;
use viewcloth::sim::Simulation;

/// Resolution n (2n² faces) and frames timed (8 steps each).
const SIZES: &[(usize, usize)] = &[(71, 10), (141, 4)];

/// Stages that make up collision handling.
const COLLISION_STAGES: &[&str] = &["proximity", "collision", "friction", "penetration_check"];

fn scene_json(n: usize) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sheet_on_sphere.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut v: Value = serde_json::from_str(&text).expect("sheet_on_sphere.json");
    let cloth = &mut v["cloths"][0];
    cloth.as_object_mut().expect("cloth").remove("remesh");
    cloth["rectangle"]["resolution"] = json!([n, n]);
    // Material (u, v) → world (u, z): the sheet hangs in the plane y = −0.12, top edge at z = 0.5.
    cloth["transform"] = json!({ "rotate": [90, 1, 0, 0], "translate": [-0.5, -0.12, -0.5] });
    let top = n * (n + 1);
    cloth["handles"] = json!([{ "nodes": [top, top + n] }]);
    let keys = v["obstacles"][0]["motion"].as_array_mut().expect("sphere motion");
    keys.retain(|k| k["time"].as_f64().unwrap_or(0.0) >= 1.0);
    for k in keys.iter_mut() {
        k["time"] = json!(k["time"].as_f64().unwrap_or(0.0) - 2.0);
    }
    v["name"] = json!(format!("bench_collisions_{n}"));
    v.to_string()
}

struct Row {
    faces: usize,
    steps: u64,
    step_s: f64,
    stage_s: Vec<(String, f64)>,
    contacts: usize,
    impacts: usize,
    zones: usize,
    ccd_iterations: usize,
    cap_hits: usize,
    penetrations: usize,
}

fn run(n: usize, frames: usize) -> Row {
    let scene = load_str(&scene_json(n), Path::new("bench_collisions.json"), Path::new("."), "bench_collisions")
        .unwrap_or_else(|e| panic!("bench scene: {e}"));
    let mut sim = Simulation::new(scene).unwrap_or_else(|e| panic!("setup: {e}"));
    sim.ws.timers.take();
    let clock = Instant::now();
    let mut penetrations = 0;
    for f in 1..=frames {
        sim.advance_frame().unwrap_or_else(|e| panic!("frame {f}: {e}"));
        penetrations += sim.penetrations();
    }
    let wall = clock.elapsed().as_secs_f64();
    let steps = sim.state.steps;
    let mut stage_s: Vec<(String, f64)> = sim.ws.timers.take().into_iter().collect();
    stage_s.sort_by(|a, b| b.1.total_cmp(&a.1));
    let c = &sim.ws.counters;
    Row {
        faces: sim.state.mesh.faces.len(),
        steps,
        step_s: wall / steps as f64,
        stage_s,
        contacts: c.contacts,
        impacts: c.impacts,
        zones: c.impact_zones,
        ccd_iterations: c.ccd_iterations,
        cap_hits: c.cap_hits,
        penetrations,
    }
}

fn main() {
    let picked: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let sizes: Vec<(usize, usize)> = if picked.is_empty() {
        SIZES.to_vec()
    } else {
        picked.iter().map(|&n| *SIZES.iter().find(|s| s.0 == n).unwrap_or(&(n, 4))).collect()
    };
    eprintln!("collision benchmark: sheet_on_sphere, uniform sheet, sphere sweeping into it");
    let mut rows = Vec::new();
    for (n, frames) in sizes {
        let r = run(n, frames);
        eprintln!("  {} faces: {:.3} s/step over {} steps", r.faces, r.step_s, r.steps);
        rows.push(r);
    }
    println!(
        "| faces | steps | s/step | collision share | proximity | collision (CCD + zones) | contacts/step \
         | impacts/step | zones/step | CCD iterations/step | cap hits | penetrations | other stages |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|");
    for r in &rows {
        let total: f64 = r.stage_s.iter().map(|s| s.1).sum();
        let get = |k: &str| r.stage_s.iter().find(|s| s.0 == k).map_or(0.0, |s| s.1);
        let coll: f64 = COLLISION_STAGES.iter().map(|k| get(k)).sum();
        let pct = |x: f64| format!("{:.0}%", 100.0 * x / total);
        let others: Vec<String> = r
            .stage_s
            .iter()
            .filter(|s| !COLLISION_STAGES.contains(&s.0.as_str()))
            .take(4)
            .map(|s| format!("{} {}", s.0, pct(s.1)))
            .collect();
        let per = |x: usize| x as f64 / r.steps as f64;
        println!(
            "| {} | {} | {:.3} | **{}** | {} | {} | {:.0} | {:.1} | {:.2} | {:.2} | {} | {} | {} |",
            r.faces,
            r.steps,
            r.step_s,
            pct(coll),
            pct(get("proximity")),
            pct(get("collision")),
            per(r.contacts),
            per(r.impacts),
            per(r.zones),
            per(r.ccd_iterations),
            r.cap_hits,
            r.penetrations,
            others.join(", ")
        );
    }
}
