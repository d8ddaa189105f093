//! The separation stage (issue 18, "Hard starts"): cloth that starts deeper inside an obstacle
//! than `collision.push_out_tolerance`, or inside two obstacles that overlap, is moved out over
//! the first steps instead of being refused at load.
//!
//! ARCSim resolves a start where cloth and obstacles intersect in one go (`separateobs.cpp`): an
//! augmented-Lagrangian solve for the smallest mass-weighted displacement of the *obstacle*
//! nodes from their pose that separates every intersecting face pair by 1 mm, the obstacle then
//! easing back into its pose; it exits when that does not converge in 100 iterations (as it
//! cannot for cloth inside two obstacles that overlap, where no displacement separates both).
//! Here the obstacles are prescribed and stay where the scene puts them; the cloth moves. A start
//! that is centimetres deep cannot be separated in one go without tearing elements, and a node
//! inside two obstacles that overlap has no outside position at all. So each step, before the
//! physics, every free node inside an obstacle takes one bounded gradient step on the
//! separation objective
//!
//!   Φ(x) = ½ Σ_b ‖x − (p_b + τ n_b)‖² over the bodies b with signed distance φ_b(x) < 0,
//!
//! (p_b the closest point on b, n_b its outward normal, τ the repulsion thickness; p_b and n_b
//! held fixed over the step): Δx = −∇Φ,
//! shortened to at most `SEPARATION_STEP` × τ. Inside one body this walks the node out to τ
//! from the surface. Inside two that overlap there is no outside position, and the gradient of Φ
//! (or of the squared depths) points along the sum of both normals: out of the overlap
//! sideways, which drags the cloth there into the overlap's rim (a sheet between two spheres
//! stretched 60%). So a node inside two obstacles is not moved but *trapped*: held still for
//! the step, like a node of a handle (`Workspace::trapped`), the pinch of the two obstacles
//! gripping it, and the cloth around it hangs from it.
//!
//! A node deeper than τ inside an obstacle, or inside two, takes no repulsion or impact from
//! obstacles for the step (`CollisionWorld::exempt`): this stage moves it. A repulsion penalty
//! on a node centimetres deep stores ½ k d², which the solve releases as a kick (a sheet
//! separated from 3 cm inside a box flew 6 cm above it), and an impact with a face it already
//! crosses has no solution (the impact-zone cap). Within τ of the surface the repulsion acts as
//! it does on any contact: without it, cloth under tension (a stretched waistband) is pulled
//! back in as fast as the stage pushes it out. The move is a projection, not a force: the velocity
//! keeps no part of it, and loses any component against it (inelastic), so the stage adds no
//! kinetic energy, and the step's fault checks judge the physics that follows unchanged. The
//! stage switches itself off at the first step that finds no node inside any obstacle (never,
//! while nodes are trapped).

use crate::math::{Real, Vec3};

use super::Simulation;

/// Largest separation move of a node in one step, in repulsion thicknesses: less than the
/// thickness, so a node comes within the next step's proximity search of any cloth it nears.
pub const SEPARATION_STEP: Real = 0.5;

impl Simulation {
    /// One separation step (see the module doc), while `SimState::separating`. Returns how
    /// many nodes moved.
    pub(super) fn separate(&mut self) -> usize {
        let Some(world) = &self.ws.collisions else { return 0 };
        if !self.state.separating {
            return 0;
        }
        let th = world.params.thickness;
        let t = self.state.time;
        let x = self.state.mesh.positions();
        let mut push = vec![Vec3::zeros(); x.len()];
        let mut inside = vec![0usize; x.len()];
        let mut deep = vec![false; x.len()];
        for b in (0..world.bodies.len()).filter(|&b| world.present(b, t)) {
            let hits = world.with_sdf(b, t, |sdf| sdf.query_inside(&x));
            for (i, q) in hits.into_iter().enumerate() {
                let Some(q) = q else { continue };
                push[i] += q.point + q.normal * th - x[i];
                inside[i] += 1;
                deep[i] |= -q.distance > th;
            }
        }
        // Nodes of handles that are on follow them; a handle that switches on later anchors its
        // nodes where the separation has put them.
        let mut held = vec![false; x.len()];
        let on = self.state.handle_nodes.iter().zip(&self.state.handle_on).filter(|(_, on)| on.is_some());
        on.flat_map(|(nodes, _)| nodes).for_each(|&i| held[i] = true);
        let limit = SEPARATION_STEP * th;
        let mut moved = 0;
        for (i, node) in self.state.mesh.nodes.iter_mut().enumerate() {
            if inside[i] != 1 || held[i] || node.mass <= 0.0 {
                continue;
            }
            let d = push[i];
            let len = d.norm();
            if len == 0.0 {
                continue;
            }
            let dx = if len > limit { d * (limit / len) } else { d };
            node.x += dx;
            let into = node.v.dot(&d) / len;
            if into < 0.0 {
                node.v -= d * (into / len);
            }
            moved += 1;
        }
        self.ws.trapped = (0..x.len()).filter(|&i| inside[i] > 1).collect();
        if let Some(world) = &mut self.ws.collisions {
            world.exempt = inside.iter().zip(&deep).map(|(&k, &d)| k > 1 || d).collect();
        }
        self.state.separating = inside.iter().any(|&k| k > 0);
        moved
    }
}
