//! skirt_mannequin blew up when a leg swung into the skirt (fixed in 9276f57, "contact and
//! friction fixes"): the far-side faces of a thin obstacle made contacts that pushed nodes through
//! it. Moved here from tests/collisions.rs.

use std::path::Path;

mod common;

use common::inline_scene;
use serde_json::json;
use viewcloth::math::Vec3;
use viewcloth::sim::Simulation;

/// A node just in front of a thin tilted obstacle lies inside the bounding box of the obstacle's
/// far-side face and behind it. That face must not make a contact (nor win over the near face as
/// "more penetrating"), or the repulsion pushes the node through the obstacle toward it.
#[test]
fn far_side_faces_of_a_thin_obstacle_do_not_push_nodes_through() {
    let v = json!({
        "version": 1, "frame_time": 0.04, "frames": 1,
        "cloths": [{
            "name": "patch",
            "rectangle": { "width": 0.02, "height": 0.02, "resolution": [1, 1] },
            // Lengthwise along the plank's long axis: parallel to its faces.
            "transform": { "translate": [0.0, -0.01, 0.0], "rotate": [-68, 0, 1, 0] },
            "material": { "preset": "cotton" }
        }],
        // A 2 cm plank, 1 m long, tilted by 22° like a swinging leg.
        "obstacles": [{ "name": "plank", "box": { "size": [0.02, 0.3, 1.0] }, "transform": { "rotate": [22, 0, 1, 0] } }],
        "collision": { "thickness": 0.004 }
    });
    let mut scene = inline_scene(&v, Path::new("."), "plank");
    // The patch 2 mm in front of the plank's +x face, 30 cm below its middle.
    let (s, c) = 22.0_f64.to_radians().sin_cos();
    let (out, axis) = (Vec3::new(c, 0.0, -s), Vec3::new(s, 0.0, c));
    for node in &mut scene.mesh.nodes {
        node.x += out * (0.01 + 0.002) - axis * 0.3;
    }
    let mut sim = Simulation::new(scene).unwrap();
    assert_eq!(sim.state.pushed_out, 0);
    let n = sim.state.mesh.nodes.len();
    let mesh = sim.state.mesh.clone();
    let h = sim.scene.time_step();
    let contacts =
        sim.ws.collisions.as_mut().unwrap().proximity(&mesh, &vec![1e-4; n], &vec![5e-5; mesh.faces.len()], h);
    let node_face: Vec<_> = contacts.iter().filter(|c| c.nodes[0] < n && c.nodes[1] >= n && c.w[0] == 1.0).collect();
    assert_eq!(node_face.len(), n, "one contact per node with the plank: {node_face:?}");
    for c in node_face {
        assert!(c.n.dot(&out) > 0.99, "node {} is pushed into the plank (n = {:?})", c.nodes[0], c.n);
    }
}
