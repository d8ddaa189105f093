//! The pop filter against its definition (`pop.rs`): a state whose forces already give every
//! node its acceleration is not moved, and from any other state the filter reaches a stationary
//! point of its objective (gradient by central differences, not from the assembly it solves).

use std::path::Path;

use super::*;
use crate::scene::load_str;

/// A 0.5 m cotton sheet pinned at two corners, remeshed every frame, after a few frames of
/// hanging (so it is curved and the filter has run before).
fn hanging() -> Simulation {
    let text = r#"{
        "version": 1, "frame_time": 0.04, "steps_per_frame": 4, "frames": 10, "gravity": [0, 0, -9.81],
        "cloths": [{
            "rectangle": {"width": 0.5, "height": 0.5, "resolution": [6, 6]},
            "material": {"preset": "cotton"},
            "remesh": {"mode": "adaptive", "size": [0.02, 0.1]},
            "handles": [{"nodes": [42]}, {"nodes": [48]}]
        }]
    }"#;
    let scene = load_str(text, Path::new("pop.json"), Path::new("."), "pop").unwrap();
    let mut sim = Simulation::new(scene).unwrap();
    for _ in 0..4 {
        sim.advance_frame().unwrap();
    }
    sim
}

/// `hanging()` with every acceleration zero (as if held still), and its positions.
fn hanging_still() -> (Simulation, Vec<Vec3>) {
    let mut sim = hanging();
    sim.state.mesh.nodes.iter_mut().for_each(|n| n.a = Vec3::zeros());
    let x0 = sim.state.mesh.positions();
    (sim, x0)
}

/// The objective's gradient at the state's positions by central differences, per node, with
/// every node's load (f_ext − m a₀) as the filter forms it and x₀ = `x0`.
fn objective_gradient(sim: &Simulation, x0: &[Vec3]) -> Vec<Vec3> {
    let pinned: Vec<Option<Vec3>> = vec![None; x0.len()];
    let load = sim.pop_load(&pinned);
    let objective =
        Objective { elastic: sim.elastic(), contacts: &[], fixed: &[], springs: &[], x0, load: &load, mu: RUBBER_BAND };
    let x = sim.state.mesh.positions();
    let delta = 1e-6;
    let mut grad = vec![Vec3::zeros(); x.len()];
    let mut probe = x.clone();
    for i in 0..x.len() {
        for d in 0..3 {
            probe[i][d] = x[i][d] + delta;
            let up = objective.value(&probe);
            probe[i][d] = x[i][d] - delta;
            let down = objective.value(&probe);
            probe[i][d] = x[i][d];
            grad[i][d] = (up - down) / (2.0 * delta);
        }
    }
    grad
}

/// Nodes the handles hold (the filter keeps them).
fn held_nodes(sim: &Simulation) -> Vec<bool> {
    let mut held = vec![false; sim.state.mesh.nodes.len()];
    for (n, _) in sim.held(sim.state.time).unwrap().exact {
        held[n] = true;
    }
    held
}

fn largest(v: &[Vec3], skip: &[bool]) -> Real {
    v.iter().zip(skip).filter(|(_, &s)| !s).map(|(g, _)| g.norm()).fold(0.0, Real::max)
}

#[test]
fn a_state_whose_forces_give_each_node_its_acceleration_does_not_move() {
    let (mut sim, x0) = hanging_still();
    // a₀ := (F + m g) / m, F = −∇E by central differences: the gradient at x₀ with a₀ = 0 is
    // −F − m g, so the acceleration that makes it vanish is −grad / m.
    let grad = objective_gradient(&sim, &x0);
    let held = held_nodes(&sim);
    assert!(largest(&grad, &held) > 1e-4, "the hanging sheet is loaded: {}", largest(&grad, &held));
    for (n, g) in sim.state.mesh.nodes.iter_mut().zip(&grad) {
        n.a = -g / n.mass;
    }
    let stats = sim.pop_filter().unwrap().expect("the filter runs after the first step");
    assert!(stats.max_move < 1e-9, "a node in balance moved {} m", stats.max_move);
}

#[test]
fn the_filter_reaches_a_stationary_point_of_its_objective() {
    // At rest, as if the sheet had been held still: gravity and the forces unbalanced.
    let (mut sim, x0) = hanging_still();
    let held = held_nodes(&sim);
    let before = largest(&objective_gradient(&sim, &x0), &held);
    let stats = sim.pop_filter().unwrap().expect("the filter runs");
    let after = largest(&objective_gradient(&sim, &x0), &held);
    assert!(stats.max_move > 1e-6, "the unbalanced sheet moved only {} m", stats.max_move);
    assert!(after < 1e-2 * before, "objective gradient {before:.3e} N → {after:.3e} N");
    // Held nodes stay exactly where they were.
    for (i, _) in held.iter().enumerate().filter(|(_, &h)| h) {
        assert_eq!(sim.state.mesh.nodes[i].x, x0[i]);
    }
}

#[test]
fn switched_off_or_before_the_first_step_the_filter_does_nothing() {
    let text = r#"{"version": 1, "frame_time": 0.04, "steps_per_frame": 2, "frames": 2,
        "cloths": [{"rectangle": {"width": 0.2, "height": 0.2, "resolution": [2, 2]},
                    "material": {"preset": "cotton"},
                    "remesh": {"mode": "adaptive", "size": [0.02, 0.1]}}]}"#;
    let scene = load_str(text, Path::new("p.json"), Path::new("."), "p").unwrap();
    let mut sim = Simulation::new(scene).unwrap();
    assert_eq!(sim.pop_filter().unwrap(), None, "no step taken yet");
    sim.advance_frame().unwrap();
    sim.scene.disabled.pop_filter = true;
    assert_eq!(sim.pop_filter().unwrap(), None, "disabled");
}

/// A 0.5 m cotton sheet on a fixed mesh with the given gravity and handles; `relax` sets
/// `initial_relax`.
fn free_sheet(relax: bool, gravity: [f64; 3], handles: &str) -> Simulation {
    let text = format!(
        r#"{{"version": 1, "frame_time": 0.04, "steps_per_frame": 4, "frames": 2, "gravity": {gravity:?},
            "initial_relax": {relax},
            "cloths": [{{"rectangle": {{"width": 0.5, "height": 0.5, "resolution": [6, 6]}},
                         "material": {{"preset": "cotton"}}, "handles": [{handles}]}}]}}"#
    );
    let scene = load_str(&text, Path::new("relax.json"), Path::new("."), "relax").unwrap();
    Simulation::new(scene).unwrap()
}

#[test]
fn the_initial_relaxation_releases_a_stretched_start() {
    // The sheet given stretched by 20% across (a garment panel placed stretched towards its
    // seam): relaxed, its elastic energy falls to a small part of what it was.
    let mut sim = free_sheet(false, [0.0; 3], "");
    sim.state.mesh.nodes.iter_mut().for_each(|n| n.x.x *= 1.2);
    let x0 = sim.state.mesh.positions();
    let before = sim.elastic().energy_at(&x0);
    sim.relax_initial_state().unwrap();
    let x1 = sim.state.mesh.positions();
    let after = sim.elastic().energy_at(&x1);
    assert!(before > 1e-3, "the stretched sheet stores energy: {before} J");
    assert!(after < 0.01 * before, "elastic energy {before:.3e} J → {after:.3e} J");
    // No load: the relaxation moves the sheet about its middle, not as a whole.
    let centre = |x: &[Vec3]| x.iter().sum::<Vec3>() / x.len() as Real;
    assert!((centre(&x1) - centre(&x0)).norm() < 1e-6, "the sheet drifted {} m", (centre(&x1) - centre(&x0)).norm());
}

#[test]
fn the_initial_relaxation_leaves_a_sheet_at_rest_where_it_is() {
    // Hanging from two corners under gravity but unstrained: gravity is not in the objective
    // (ARCSim's equilibration zeroes the accelerations and leaves it out), so nothing moves.
    let handles = r#"{"nodes": [42]}, {"nodes": [48]}"#;
    let plain = free_sheet(false, [0.0, 0.0, -9.81], handles);
    let relaxed = free_sheet(true, [0.0, 0.0, -9.81], handles);
    assert!(relaxed.ws.pop.iterations > 0 && plain.ws.pop.iterations == 0, "`initial_relax` runs the relaxation");
    assert_eq!(plain.state.mesh.positions(), relaxed.state.mesh.positions());
}
