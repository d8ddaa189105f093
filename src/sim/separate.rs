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
//! walk switches itself off at the first step that finds no node inside any obstacle.
//!
//! **Pinches during the run.** Two obstacles that close on cloth between them (ARCSim's
//! `crush2.json`: two spheres that part and meet again on the sheet's edge tucked between them)
//! leave it no position outside both once their surfaces are nearer than the thickness, and none
//! at all once they overlap: the impact zones then meet constraints from both sides that no
//! motion satisfies, every step is retried to the smallest and the strain is driven up (13 at
//! t = 1.55 s, where the run stopped). ARCSim leaves such impacts unresolved after its iteration
//! cap and lets the cloth through. Here cloth caught in a pinch is *trapped* like cloth inside
//! two overlapping obstacles at the start, and for the same reason, held with the pinch's motion
//! (the mean velocity of the two surfaces at the closest points; zero between obstacles that
//! stand still) and exempt from obstacle contact and impacts for the step:
//! - a node within the thickness of two obstacles whose outward normals there are more than
//!   120° apart (`PINCH_COS`: the surfaces face each other across it; a floor meeting a wall at
//!   90° leaves a corner the cloth can rest in), or inside two;
//! - every node of a cloth face within the thickness of a *pinch point*: a point sampled on one
//!   obstacle's face (vertices, edge midpoints, centroid) within twice the thickness of another
//!   obstacle's surface (either side), whose normal there faces it (`PINCH_COS`), the two
//!   surfaces closing on each other (`CLOSING`). A cloth face larger than the pinch (3 cm faces
//!   between spheres whose gap is under 2 mm over a 3 cm disc) has its nodes outside it, and
//!   the obstacles' vertices pierce it from both sides. Parts of one body that overlap at its
//!   joints (ARCSim's dancer is 16 obstacles) cross at such angles along thousands of points;
//!   without the closing test the dress over them was held there and crossed by the body
//!   (`dress_dance`, 12 crossing pairs at frame 1);
//! - a node held at the last step that is still within the thickness of two facing surfaces or
//!   inside two (`SimState::pinched`): once the pinch has closed past it, it is deep inside
//!   both, far from where their surfaces meet.
//!
//! Both rules look only where two obstacles' faces face each other within twice the thickness
//! near the cloth (`pinch.rs`: *bands*, from local geometry on those faces; the faces that may
//! form them are found once per frame near the cloth, each with its own vertices' travel as
//! margin, again when the cloth moves beyond its margin, and kept per step where the cloth is).
//! So the stage runs at every step at which two present obstacles' bounding boxes come within
//! twice the thickness of each other, costing little where no band forms (`dress_dance` view:
//! 6 s of a 75 s run, its 16 body parts overlapping at every joint), and outside the start's
//! separation it only traps: a node released from a pinch
//! inside one obstacle is left to the contacts and impact zones, as anywhere else in a run
//! (walking it out, a projection no collision stage checks, pushed it through the cloth layers
//! beside it). Cloth held in a pinch crosses the obstacles there, as in ARCSim; nowhere else.

use rayon::prelude::*;

use crate::collision::sdf::SdfHit;
use crate::collision::world::CollisionWorld;
use crate::math::{Real, Vec3};

use super::pinch::{self, BandCache, StepEnd, PINCH_COS};
use super::Simulation;

/// Largest separation move of a node in one step, in repulsion thicknesses: less than the
/// thickness, so a node comes within the next step's proximity search of any cloth it nears.
pub const SEPARATION_STEP: Real = 0.5;

/// What one node's queries found: the bodies it is within the thickness of (or inside).
#[derive(Default)]
struct NodeHits {
    /// (body, hit) for every body with signed distance below the thickness.
    near: Vec<(usize, SdfHit)>,
}

impl NodeHits {
    fn inside(&self) -> usize {
        self.near.iter().filter(|(_, h)| h.distance < 0.0).count()
    }

    /// Inside two bodies, or within the thickness of two whose surfaces face each other.
    fn trapped(&self) -> bool {
        self.inside() > 1
            || self
                .near
                .iter()
                .enumerate()
                .any(|(k, (_, a))| self.near[k + 1..].iter().any(|(_, b)| a.normal.dot(&b.normal) < PINCH_COS))
    }
}

impl Simulation {
    /// Whether a step must run the separation stage: cloth is being separated, or two present
    /// obstacles come within the thickness of each other so that cloth between them may be
    /// pinched (see the module doc). False when the scene switches the stage off.
    fn separation_due(&self) -> bool {
        let Some(world) = &self.ws.collisions else { return false };
        if self.scene.disabled.separation {
            return false;
        }
        if self.state.separating || !self.state.pinched.is_empty() {
            return true;
        }
        let th = world.params.thickness;
        let t = self.state.time;
        let boxes: Vec<_> =
            (0..world.bodies.len()).filter_map(|b| world.body_box(b, t)).map(|b| b.inflate(th)).collect();
        boxes.iter().enumerate().any(|(k, a)| boxes[k + 1..].iter().any(|b| a.overlaps(b)))
    }

    /// One separation step of a step of length `h` (see the module doc), when
    /// `separation_due`. Returns how many nodes moved.
    pub(super) fn separate(&mut self, h: Real) -> usize {
        if !self.separation_due() {
            return 0;
        }
        let Some(world) = &self.ws.collisions else { return 0 };
        let separating = self.state.separating;
        let th = world.params.thickness;
        let t = self.state.time;
        let x = self.state.mesh.positions();
        let present: Vec<usize> = (0..world.bodies.len()).filter(|&b| world.present(b, t)).collect();
        let cloth: Vec<([usize; 3], [Vec3; 3])> = (0..self.state.mesh.faces.len())
            .map(|f| self.state.mesh.face_nodes(f))
            .map(|n| (n, n.map(|i| x[i])))
            .collect();
        let positions = pinch::body_positions(world, t);
        let present_now: Vec<bool> = positions.iter().map(Option::is_some).collect();
        let frame = self.state.frame;
        if !self.ws.pinch_faces.as_ref().is_some_and(|c| c.holds(frame, &present_now, &x)) {
            let speed = self.state.mesh.nodes.iter().map(|n| n.v.norm()).fold(0.0, Real::max);
            let ft = self.scene.frame_time;
            self.ws.pinch_faces = Some(BandCache::new(world, &positions, &x, &cloth, speed, t, ft, frame));
        }
        let cache = self.ws.pinch_faces.as_ref().expect("built above");
        let bands = pinch::bands(world, &positions, cache, &cloth);
        // Nodes near both sides of a band, from the band's faces; while separating, every node
        // within an obstacle's box (anywhere for an open one: its inside is a half-space) from
        // its distance field, as is a node held at the last step, wherever it is (the pinch may
        // have closed past it: inside both obstacles, far from where their surfaces meet).
        let mut hits: Vec<NodeHits> = match separating {
            true => (0..x.len()).map(|_| NodeHits::default()).collect(),
            false => pinch::node_hits(&bands, &x, th).into_iter().map(|near| NodeHits { near }).collect(),
        };
        let mut asked: Vec<Vec<bool>> = vec![vec![false; x.len()]; world.bodies.len()];
        for &b in &present {
            let bx = world.body_box(b, t).map(|bx| bx.inflate(th));
            let within = |p: &Vec3| bx.is_some_and(|bx| bx.distance_squared(p) == 0.0);
            if separating {
                let open = !world.with_sdf(b, t, |sdf| sdf.is_closed());
                asked[b] = x.iter().map(|p| open || within(p)).collect();
            }
            for &i in &self.state.pinched {
                asked[b][i] |= within(&x[i]);
            }
        }
        for &b in &present {
            if !asked[b].iter().any(|&r| r) {
                continue;
            }
            let found: Vec<Option<SdfHit>> = world.with_sdf(b, t, |sdf| {
                x.par_iter()
                    .zip(&asked[b])
                    .map(|(p, &asked)| match asked {
                        true => sdf.query(p).filter(|q| q.distance < th),
                        false => None,
                    })
                    .collect()
            });
            for (i, q) in found.into_iter().enumerate() {
                let Some(q) = q else { continue };
                match hits[i].near.iter_mut().find(|(k, _)| *k == b) {
                    Some((_, old)) => *old = q,
                    None => hits[i].near.push((b, q)),
                }
            }
        }
        let mut trapped: Vec<bool> = hits.iter().map(NodeHits::trapped).collect();
        let mut end = StepEnd::new(world, t + h);
        let mut velocity = pinch_velocities(world, &hits, &trapped, &mut end, h);
        // A cloth face the obstacles pinch between its nodes (a face larger than the pinch) is
        // held whole: the nodes alone do not see it.
        let pinches = pinch::pinch_points(world, &bands, &mut end, h);
        for (i, v) in pinch::faces_at_pinches(&pinches, &cloth, th) {
            if !trapped[i] {
                trapped[i] = true;
                velocity[i] = v;
            }
        }
        self.ws.trapped = (0..x.len()).filter(|&i| trapped[i]).map(|i| (i, velocity[i])).collect();
        self.state.pinched = self.ws.trapped.iter().map(|&(i, _)| i).collect();
        let held = &mut self.ws.counters.pinched_nodes;
        *held = (*held).max(self.state.pinched.len());
        let moved = if separating { self.walk_out(&hits, &trapped) } else { 0 };
        let exempt: Vec<bool> = hits
            .iter()
            .zip(&trapped)
            .map(|(n, &tr)| tr || (separating && n.near.iter().any(|(_, q)| -q.distance > th)))
            .collect();
        let any_trapped = trapped.iter().any(|&tr| tr);
        if let Some(world) = &mut self.ws.collisions {
            world.exempt = if separating || any_trapped { exempt } else { Vec::new() };
        }
        self.state.separating = separating && hits.iter().any(|n| n.inside() > 0);
        moved
    }

    /// Moves every free node inside exactly one obstacle a bounded step out of it (the module
    /// doc's gradient step); returns how many moved.
    fn walk_out(&mut self, hits: &[NodeHits], trapped: &[bool]) -> usize {
        let Some(world) = &self.ws.collisions else { return 0 };
        let th = world.params.thickness;
        // Nodes of handles that are on follow them; a handle that switches on later anchors its
        // nodes where the separation has put them.
        let mut held = vec![false; hits.len()];
        let on = self.state.handle_nodes.iter().zip(&self.state.handle_on).filter(|(_, on)| on.is_some());
        on.flat_map(|(nodes, _)| nodes).for_each(|&i| held[i] = true);
        let limit = SEPARATION_STEP * th;
        let mut moved = 0;
        for (i, node) in self.state.mesh.nodes.iter_mut().enumerate() {
            if trapped[i] || held[i] || node.mass <= 0.0 {
                continue;
            }
            let Some((_, q)) = hits[i].near.iter().find(|(_, q)| q.distance < 0.0) else { continue };
            let d = q.point + q.normal * th - node.x;
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
        moved
    }
}

/// Each trapped node with the velocity of the pinch over the step of length `h`: the mean of the
/// velocities of the surfaces it is near, at the closest points (zero between obstacles that
/// stand still).
fn pinch_velocities(
    world: &CollisionWorld,
    hits: &[NodeHits],
    trapped: &[bool],
    end: &mut StepEnd,
    h: Real,
) -> Vec<Vec3> {
    let mut out = vec![Vec3::zeros(); hits.len()];
    for (i, n) in hits.iter().enumerate().filter(|&(i, _)| trapped[i]) {
        let v: Vec3 = n
            .near
            .iter()
            .map(|(b, q)| end.velocity(world, *b, world.bodies[*b].triangles()[q.triangle], &q.bary, &q.point, h))
            .sum();
        out[i] = v / n.near.len() as Real;
    }
    out
}
