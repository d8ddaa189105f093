//! sphere.json (ARCSim's scene) stopped at frame 52 (fixed in 43c8438): the sphere moved farther
//! in one step than the thickness, and proximity made no contacts for the cloth it swept over.
//! The whole-scene check is `sphere_clearance_is_never_negative` in tests/arcsim.rs (100 frames,
//! needs ../shared/arcsim); this is the short pin. Moved here from tests/collisions.rs.

use std::path::Path;

mod common;

use common::inline_scene;
use serde_json::json;
use viewcloth::math::Vec3;
use viewcloth::sim::Simulation;

/// An obstacle moving farther in one step than the thickness (the sphere sweeps 5–10 mm per step
/// through a 5 mm sheet) ends the step with the cloth in front of it behind its surface, deeper
/// than the thickness. That cloth must still get repulsion contacts pushing it out; without them
/// the implicit solve carried hundreds of nodes into the sphere and left them all to the impact
/// zones, which hit the iteration cap.
#[test]
fn obstacle_moving_farther_than_the_thickness_in_a_step_still_repels_the_cloth() {
    let v = json!({
        "version": 1, "frame_time": 0.04, "frames": 1,
        "cloths": [{
            "name": "patch",
            "rectangle": { "width": 0.04, "height": 0.04, "resolution": [2, 2] },
            "transform": { "translate": [-0.02, -0.02, 0.001] },
            "material": { "preset": "cotton" }
        }],
        "obstacles": [{ "name": "block", "box": { "size": [1.0, 1.0, 0.2] }, "transform": { "translate": [0, 0, -0.1] } }],
        "collision": { "thickness": 0.004 }
    });
    let mut sim = Simulation::new(inline_scene(&v, Path::new("."), "sweep")).unwrap();
    let n = sim.state.mesh.nodes.len();
    let mesh = sim.state.mesh.clone();
    let h = sim.scene.time_step();
    let world = sim.ws.collisions.as_mut().unwrap();
    // The block rises 9 mm over the step: the patch, 1 mm above it, ends 8 mm inside.
    world.obs_x1 = world.obs_x0.iter().map(|p| p + Vec3::new(0.0, 0.0, 0.009)).collect();
    let contacts = world.proximity(&mesh, &vec![1e-4; n], &vec![5e-5; mesh.faces.len()], h);
    let node_face: Vec<_> = contacts.iter().filter(|c| c.nodes[0] < n && c.nodes[1] >= n && c.w[0] == 1.0).collect();
    assert_eq!(node_face.len(), n, "one contact per node with the block: {node_face:?}");
    for c in node_face {
        assert!(c.n.dot(&Vec3::z()) > 0.99, "node {} is not pushed out of the block (n = {:?})", c.nodes[0], c.n);
        let x = c.nodes.map(|i| if i < n { mesh.nodes[i].x } else { world.obs_x1[i - n] });
        assert!((c.gap(&x) + 0.008 + 0.004).abs() < 1e-9, "gap {}", c.gap(&x));
    }
}
