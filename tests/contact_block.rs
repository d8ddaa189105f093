//! The contact block's refactorisation (`solver::tail`) in a run: a 3,200-face sheet dropped
//! on a ball with friction, its few contact nodes ordered last, so that the friction and contact
//! modes' refactorisations factorise their block alone. The run takes that path, ends its frames
//! without a crossing, and a run restored from a checkpoint continues with the uninterrupted
//! run's bits (the order and every step's first factorisation depend on the step alone).

mod common;

use common::{inline_scene, temp_dir, write_checkpoint};
use serde_json::json;
use viewcloth::math::Real;
use viewcloth::sim::checkpoint;
use viewcloth::sim::Simulation;

fn scene_json() -> serde_json::Value {
    json!({
        "version": 1,
        "name": "contact_block",
        "frame_time": 0.02,
        "steps_per_frame": 4,
        "frames": 8,
        "gravity": [0, 0, -9.8],
        "cloths": [{
            "name": "sheet",
            "rectangle": { "width": 0.6, "height": 0.6, "resolution": [40, 40] },
            "transform": { "translate": [-0.3, -0.3, 0.104] },
            "material": { "preset": "cotton" }
        }],
        "obstacles": [{ "name": "ball", "sphere": { "radius": 0.1 } }],
        "collision": { "thickness": 0.005, "friction": 0.3 }
    })
}

#[test]
fn contact_block_refactorisations_run_and_resume_bitwise() {
    let dir = temp_dir("resume");
    let load = || inline_scene(&scene_json(), &dir, "contact_block");
    let bits = |s: &Simulation| -> Vec<u64> {
        s.state
            .mesh
            .nodes
            .iter()
            .flat_map(|n| n.x.iter().chain(n.v.iter()).map(|x| x.to_bits()).collect::<Vec<_>>())
            .collect()
    };
    let mut a = Simulation::new(load()).unwrap();
    let mut block = 0;
    for _ in 0..3 {
        a.advance_frame().unwrap();
        block += std::mem::take(&mut a.ws.counters).tail_refactors;
    }
    let (_, path) = write_checkpoint(&dir, &a, &load(), None, 8, 3);
    let mut b = Simulation::restore(load(), checkpoint::read(&path).unwrap().state).unwrap();
    for f in 4..=6 {
        a.advance_frame().unwrap();
        b.advance_frame().unwrap();
        block += std::mem::take(&mut a.ws.counters).tail_refactors;
        assert!(bits(&a) == bits(&b), "frame {f}: the resumed run differs");
        let crossings = a.crossings();
        assert_eq!((crossings.cloth.len(), crossings.obstacle.len()), (0, 0), "frame {f}");
    }
    assert!(block > 0, "no refactorisation of the contact block");
    let lowest = a.state.mesh.nodes.iter().map(|n| n.x.z).fold(Real::INFINITY, Real::min);
    // Its edges fall freely around the ball: ½ g t² = 7 cm in 0.12 s.
    assert!(lowest < 0.104 - 0.05, "the sheet did not fall around the ball (lowest node at {lowest} m)");
}
