//! The untangling stage: cloth that has passed through itself is taken back (Baraff, Witkin &
//! Kass 2003, "Untangling Cloth"; the analysis is `collision::untangle`).
//!
//! At the first step of every frame (after its remesh), with self-collision on, the cloth's
//! crossing triangle pairs are found exactly (`collision::crossings`). Where they cut off a
//! region of the cloth (a part poked through another part), or where a few of them cut off
//! nothing (a hem's tip pushed through the fold beside it while the arm held it against the
//! torso), the region's nodes, or one layer's nodes at the piercing edges
//! (`collision::untangle`), are moved back along the pierced face's normal, at most
//! `SEPARATION_STEP` thicknesses per step, and the region takes no contact or impact with the
//! faces it passes through for the step; the velocity loses any component against the move
//! (inelastic, like the separation stage's walk out of obstacles: the stage adds no kinetic
//! energy). The search is repeated at
//! each following step while it finds a region, and stops for the frame at the first step that
//! finds none. Nodes held by a handle are not moved. Nodes held in a pinch are: the move shifts
//! where the hold carries them from (on `dress_dance` the hem's tip through the fold is held in
//! the armpit from frame 55 to 65; left alone there, the crossing lasted as long).
//!
//! Why not leave crossings to the collision stages: they keep cloth from passing through
//! cloth, and so they keep a crossing that is there. Its pierced faces' contacts push the
//! poked node back to the side it is on, and the impact zones stop it from coming back through.
//! On `dress_dance` four crossing pairs made in the armpit pinch at frame 55 stayed to the
//! end of the shot.
//!
//! `disable: ["separation"]` switches this stage off with the separation stage (ARCSim's
//! `separate` too removes cloth–cloth intersections after a remesh).

use crate::collision::crossings::{find_self_crossings, Soup};
use crate::collision::untangle::analyse;
use crate::math::{Real, Vec3};

use super::separate::SEPARATION_STEP;
use super::Simulation;

/// How far past a pierced face's plane a region's node is taken back, in thicknesses: the
/// contacts of the next steps push it on to the full thickness.
pub const UNTANGLE_MARGIN: Real = 0.5;

impl Simulation {
    /// One untangling step (see the module doc), when due. Returns how many nodes moved.
    pub(super) fn untangle(&mut self) -> usize {
        if !self.ws.untangle_due {
            return 0;
        }
        let due = self.scene.collision.self_collision && !self.scene.disabled.separation;
        let Some(world) = self.ws.collisions.as_ref().filter(|_| due) else {
            self.ws.untangle_due = false;
            return 0;
        };
        let th = world.params.thickness;
        let mesh = &self.state.mesh;
        let x = mesh.positions();
        let tris: Vec<[usize; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).collect();
        let crossing = find_self_crossings(Soup { x: &x, tris: &tris });
        let tangle = analyse(mesh, &x, &crossing, UNTANGLE_MARGIN * th);
        if tangle.is_empty() {
            self.ws.untangle_due = false;
            return 0;
        }
        let mut fixed = vec![false; x.len()];
        let on = self.state.handle_nodes.iter().zip(&self.state.handle_on).filter(|(_, on)| on.is_some());
        on.flat_map(|(nodes, _)| nodes).for_each(|&i| fixed[i] = true);
        let limit = SEPARATION_STEP * th;
        let mut moved = 0;
        for &(i, d) in &tangle.moves {
            let node = &mut self.state.mesh.nodes[i];
            let len = d.norm();
            if fixed[i] || node.mass <= 0.0 || len == 0.0 {
                continue;
            }
            let dx: Vec3 = if len > limit { d * (limit / len) } else { d };
            node.x += dx;
            let into = node.v.dot(&d) / len;
            if into < 0.0 {
                node.v -= d * (into / len);
            }
            moved += 1;
        }
        if moved == 0 {
            // All of it on handles: the next frame looks again.
            self.ws.untangle_due = false;
            return 0;
        }
        let masks = tangle.masks(x.len());
        if let Some(world) = &mut self.ws.collisions {
            world.untangling = masks;
        }
        self.ws.counters.untangled_nodes += moved;
        moved
    }
}
