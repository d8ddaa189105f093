//! The collision stages of a step, for one scene: obstacle motion, proximity contacts for the
//! implicit solve, Coulomb friction, and continuous collision detection with impact zones.
//!
//! Index space: cloth nodes are `0..n`; obstacle vertices follow, body after body, as fixed
//! points `n + k` (infinite mass, prescribed motion).
//!
//! Each body's signed distance field is kept between queries (`with_sdf`): built at its first
//! query, brought to a new time only when the body has moved.

use std::sync::Mutex;

mod resolve;

pub use resolve::InvMasses;

use super::areas::ElementAreas;
use super::broad::{BroadPhase, Candidate, Interval, VF};
use super::bvh::Aabb;
use super::geometry::closest_point_triangle;
use super::obstacle::ObstacleBody;
use super::params::CollisionParams;
use super::proximity::{
    edge_edge_contact, node_face_contact, obstacle_edge_contact, obstacle_vertex_contact, Contact, Law,
};
use super::sdf::MeshSdf;
use super::untangle::exempt_pair;
use crate::math::{same_bits, Real, Vec3};
use crate::mesh::Mesh;

/// Separation the impact-zone projection enforces, as a fraction of the thickness.
const ZONE_SEPARATION: Real = 0.1;

/// What the collision stages did in one step (summed over a frame by the caller).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CollisionCounters {
    pub contacts: usize,
    pub impacts: usize,
    pub impact_zones: usize,
    pub ccd_iterations: usize,
    /// Steps whose impact-zone loop stopped at the iteration cap with collisions left.
    pub cap_hits: usize,
    /// Nodes the collision projection would have flung past the speed cap at the smallest step
    /// size, which kept their solved motion instead (`sim::checks`, "Collisions left").
    pub flung_reverted: usize,
    /// Steps whose impact-zone pushes stored too much elastic energy and were spread through the
    /// step's system instead (`solver::spread`).
    pub spread_pushes: usize,
    /// Zones whose projection had no solution (rigid zones included).
    pub failed_zones: usize,
    /// Zones that became rigid, or rigid zones that took in more nodes, at the smallest step
    /// (`CollisionWorld::resolve`).
    pub rigid_zones: usize,
    /// Nodes trapped in a pinch that yielded to a zone with no solution while they were held
    /// (`CollisionWorld::resolve`).
    pub yielded_nodes: usize,
    /// The most cloth nodes held in a pinch at one step (`sim::separate`; a maximum, not a sum).
    pub pinched_nodes: usize,
    /// Cloth nodes moved back through cloth they had crossed (`sim::untangle`; summed over the
    /// steps).
    pub untangled_nodes: usize,
    /// Friction contacts sticking and sliding at the accepted solves.
    pub sticking: usize,
    pub sliding: usize,
    /// Solves and factorisations beyond the first that friction's mode changes took.
    pub friction_resolves: usize,
    pub friction_refactors: usize,
    /// Of `friction_refactors`, those of the contact block alone (`solver::tail`).
    pub tail_refactors: usize,
    /// Steps ending with friction contacts not in the mode Coulomb's law gives them
    /// (`friction::MAX_REFACTORS`, `friction::MAX_SOLVES`).
    pub friction_unconverged: usize,
}

pub struct CollisionWorld {
    pub params: CollisionParams,
    pub bodies: Vec<ObstacleBody>,
    /// Which bodies take part in the current step: those present at its end (ARCSim updates
    /// its obstacles to the step's end time before anything else).
    present: Vec<bool>,
    /// Obstacle triangles of the present bodies in fixed-point numbering (offset by body, not
    /// by cloth node count).
    obs_tris: Vec<[usize; 3]>,
    /// First fixed-point index of each body (an absent body has an empty range), and the total
    /// at the end.
    body_start: Vec<usize>,
    /// Vertex positions of the present bodies at the start and end of the current step.
    pub obs_x0: Vec<Vec3>,
    pub obs_x1: Vec<Vec3>,
    /// Outward unit normals of the obstacle vertices at `obs_x1`.
    obs_normals: Vec<Vec3>,
    obs_edges: Vec<[usize; 2]>,
    /// Per obstacle edge (same order as `obs_edges`), the third vertex of each adjacent triangle.
    obs_edge_opposite: Vec<Vec<usize>>,
    /// Per obstacle vertex, the vertices it shares an edge with.
    obs_neighbours: Vec<Vec<usize>>,
    broad: BroadPhase,
    /// Per body, its signed distance field as of the last query (`with_sdf`); empty until then.
    sdfs: Vec<Mutex<Option<BodySdf>>>,
    /// Cloth nodes whose elements take no obstacle contact or impact: nodes inside an obstacle
    /// while `sim::separate` moves them out (or holds them, inside two that overlap).
    pub exempt: Vec<bool>,
    /// Per cloth node, the region masks of the cloth the untangling stage is taking back through
    /// itself this step (`untangle::Tangle::masks`): a region takes no contact or impact with the
    /// faces it passes through. Empty when nothing is tangled.
    pub untangling: Vec<(u64, u64)>,
}

/// A body's signed distance field and the time of the positions it holds.
struct BodySdf {
    time: Real,
    sdf: MeshSdf,
}

impl CollisionWorld {
    pub fn new(params: CollisionParams, bodies: Vec<ObstacleBody>, t: Real) -> Self {
        let present = bodies.iter().map(|b| b.present_at(t)).collect();
        let mut w = CollisionWorld {
            params,
            bodies,
            present,
            obs_tris: Vec::new(),
            body_start: Vec::new(),
            obs_x0: Vec::new(),
            obs_x1: Vec::new(),
            obs_normals: Vec::new(),
            obs_edges: Vec::new(),
            obs_edge_opposite: Vec::new(),
            obs_neighbours: Vec::new(),
            broad: BroadPhase::default(),
            sdfs: Vec::new(),
            exempt: Vec::new(),
            untangling: Vec::new(),
        };
        w.sdfs = w.bodies.iter().map(|_| Mutex::new(None)).collect();
        w.lay_out();
        w.obs_x1 = w.positions_at(t);
        w.obs_normals = w.obstacle_vertex_normals();
        w.obs_x0 = w.obs_x1.clone();
        w
    }

    /// The fixed-point numbering of the present bodies: triangles, edges and each edge's
    /// opposite vertices.
    fn lay_out(&mut self) {
        let mut obs_tris = Vec::new();
        let mut body_start = vec![0];
        for (b, body) in self.bodies.iter().enumerate() {
            let offset = body_start[body_start.len() - 1];
            if !self.present[b] {
                body_start.push(offset);
                continue;
            }
            obs_tris.extend(body.triangles().iter().map(|t| t.map(|i| i + offset)));
            body_start.push(offset + body.vertex_count());
        }
        let mut obs_edges: Vec<[usize; 2]> = obs_tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
            .collect();
        obs_edges.sort_unstable();
        obs_edges.dedup();
        let mut obs_edge_opposite = vec![Vec::new(); obs_edges.len()];
        for t in &obs_tris {
            for k in 0..3 {
                let e = [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])];
                if let Ok(i) = obs_edges.binary_search(&e) {
                    obs_edge_opposite[i].push(t[(k + 2) % 3]);
                }
            }
        }
        let mut obs_neighbours = vec![Vec::new(); body_start[body_start.len() - 1]];
        for &[a, b] in &obs_edges {
            obs_neighbours[a].push(b);
            obs_neighbours[b].push(a);
        }
        (self.obs_tris, self.body_start, self.obs_edges, self.obs_edge_opposite, self.obs_neighbours) =
            (obs_tris, body_start, obs_edges, obs_edge_opposite, obs_neighbours);
    }

    /// Vertex positions of the bodies taking part in the current step, at `t`.
    fn positions_at(&self, t: Real) -> Vec<Vec3> {
        self.bodies.iter().zip(&self.present).filter(|(_, &p)| p).flat_map(|(b, _)| b.positions_at(t)).collect()
    }

    /// Moves the obstacles to the step `[t0, t1]`; the bodies present at `t1` take part.
    pub fn advance(&mut self, t0: Real, t1: Real) {
        let present: Vec<bool> = self.bodies.iter().map(|b| b.present_at(t1)).collect();
        if present != self.present {
            self.present = present;
            self.lay_out();
        }
        self.obs_x0 = self.positions_at(t0);
        self.obs_x1 = self.positions_at(t1);
        self.obs_normals = self.obstacle_vertex_normals();
    }

    /// Whether body `b` is present at `t` (its window; only present bodies are queried).
    pub fn present(&self, b: usize, t: Real) -> bool {
        self.bodies[b].present_at(t)
    }

    /// World positions of body `b`'s vertices at the current step's end (where the last
    /// `advance` moved it), when it takes part in the step.
    pub fn body_positions(&self, b: usize) -> Option<&[Vec3]> {
        (self.present.get(b) == Some(&true) && self.body_start.len() > b + 1)
            .then(|| &self.obs_x1[self.body_start[b]..self.body_start[b + 1]])
    }

    /// The bounding box of body `b` at the current step's end (the positions the last `advance`
    /// moved it to), or at `t` when it was not present then; `None` when absent at `t`.
    pub fn body_box(&self, b: usize, t: Real) -> Option<Aabb> {
        if !self.present(b, t) {
            return None;
        }
        Some(match self.body_positions(b) {
            Some(x) => Aabb::from_points(x),
            None => Aabb::from_points(&self.bodies[b].positions_at(t)),
        })
    }

    /// Calls `f` with the signed distance field of body `b` at time `t`. The field is built at
    /// the body's first query and kept (topology, pseudo-normals, tree): a static body's is used
    /// as it is; a moving body's is brought to `t` (`MeshSdf::update`) when its positions there
    /// differ from those the field holds. The answers are bit for bit those of a `MeshSdf` built
    /// from `positions_at(t)`. The body's field is locked while `f` runs: `f` must not ask for it
    /// again.
    pub fn with_sdf<R>(&self, b: usize, t: Real, f: impl FnOnce(&MeshSdf) -> R) -> R {
        let body = &self.bodies[b];
        let mut slot = self.sdfs[b].lock().unwrap_or_else(|poisoned| {
            // A panic during an update may have left the field half-way: start over.
            self.sdfs[b].clear_poison();
            let mut slot = poisoned.into_inner();
            *slot = None;
            slot
        });
        let cached = match slot.take() {
            Some(c) if body.is_static() || c.time == t => c,
            Some(mut c) => {
                let x = body.positions_at(t);
                if !same_bits(&x, c.sdf.positions()) {
                    c.sdf.update(&x);
                }
                BodySdf { time: t, sdf: c.sdf }
            }
            None => BodySdf { time: t, sdf: MeshSdf::new(body.triangles(), &body.positions_at(t)) },
        };
        f(&slot.insert(cached).sdf)
    }

    /// Velocities of obstacle vertices over the current step of length `h`.
    pub fn obstacle_velocities(&self, h: Real) -> Vec<Vec3> {
        self.obs_x0.iter().zip(&self.obs_x1).map(|(a, b)| (b - a) / h).collect()
    }

    /// Repulsion contacts at the start of a step: cloth against obstacles (at the end of the
    /// step, so an obstacle moving in is felt) and, with self-collision on, cloth against cloth.
    ///
    /// An obstacle can move farther in one step than the thickness (the sphere scene sweeps
    /// 5–10 mm per step through a sheet 5 mm thick): cloth it sweeps over during the step lies
    /// behind its end-of-step surface, deeper than the thickness. Such cloth still gets a contact,
    /// pushing it out along the obstacle's outward normal: the search reaches the obstacle's
    /// travel over the step beyond the thickness. ARCSim searches a fixed 2 × thickness
    /// (`proximity.cpp`, `dmin`); without this the implicit solve carries hundreds of nodes into
    /// the obstacle and leaves them all to the impact zones.
    ///
    /// Likewise cloth that moves faster than the thickness per step (a light fabric falling
    /// onto a ball at 2 m/s moves 5 mm in a step of 1/400 s, past a 4 mm thickness) would reach
    /// deep inside the thickness unseen, and the next step's penalty would release ½ k g² that no
    /// work paid for. So a pair that would come within the thickness during the step at its start
    /// velocities (the search reaches h times the fastest node of each side beyond it) is a
    /// contact too, *speculative* while its gap at the start is positive: the step's active set
    /// (`collision::speculative`) switches it on only where the solved motion crosses the
    /// thickness.
    ///
    /// `node_area` and `face_area` are the cloth's material areas; a contact's stiffness is the
    /// scene's times the largest cloth node area of the pair (quadratic law) or the smaller of
    /// its two elements' areas (ARCSim's cubic law, `collision::areas`).
    pub fn proximity(&mut self, mesh: &Mesh, node_area: &[Real], face_area: &[Real], h: Real) -> Vec<Contact> {
        let th = self.params.thickness;
        let law = self.params.penalty;
        let arcsim_areas =
            (law == Law::Cubic).then(|| ElementAreas::new(mesh, node_area, face_area, &self.obs_tris, &self.obs_x1));
        let n = mesh.nodes.len();
        let x: Vec<Vec3> = mesh.positions();
        let xh: Vec<Vec3> = mesh.nodes.iter().map(|node| node.x + h * node.v).collect();
        let speed: Vec<Real> = mesh.nodes.iter().map(|node| node.v.norm()).collect();
        // Obstacle boxes span the step, so cloth the obstacle sweeps over is a candidate; cloth
        // boxes span the motion at the start velocities.
        let iv = Interval { cloth0: &x, cloth1: &xh, obs0: &self.obs_x0, obs1: &self.obs_x1 };
        let pos = |i: usize| if i < n { x[i] } else { self.obs_x1[i - n] };
        let travel: Vec<Real> = self.obs_x0.iter().zip(&self.obs_x1).map(|(a, b)| (b - a).norm()).collect();
        let outward = &self.obs_normals;
        let k_area = self.params.stiffness;
        // The trees are taken out while the narrow phase borrows the world.
        let mut broad = std::mem::take(&mut self.broad);
        let this = &*self;
        let narrow = |(kind, nodes): Candidate| {
            if exempt_against_obstacle(&this.exempt, &nodes, n) || exempt_pair(&this.untangling, kind == VF, &nodes) {
                return None;
            }
            let xs = nodes.map(pos);
            let area = nodes.iter().filter(|&&i| i < n).map(|&i| node_area[i]).fold(0.0, Real::max);
            let k = k_area * area;
            let obstacle = || nodes.iter().filter(|&&i| i >= n).map(|&i| i - n);
            let reach = th + obstacle().map(|i| travel[i]).fold(0.0, Real::max);
            let out: Vec3 = obstacle().map(|i| outward[i]).sum();
            // Within the thickness plus what the pair can close in the step at its start
            // velocities (each side at most h times its fastest node).
            let fastest = |ids: &[usize]| ids.iter().filter(|&&i| i < n).map(|&i| speed[i]).fold(0.0, Real::max);
            let split = if kind == VF { 1 } else { 2 };
            let detect = th + h * (fastest(&nodes[..split]) + fastest(&nodes[split..]));
            let found = match kind {
                VF if nodes[0] < n && nodes[1] >= n => {
                    let face = [nodes[1] - n, nodes[2] - n, nodes[3] - n];
                    this.obstacle_face_contact(nodes, face, &xs, k, reach, detect)
                }
                VF if nodes[0] >= n => obstacle_vertex_contact(nodes, &xs, detect, k, reach.max(detect), &out),
                VF => node_face_contact(nodes, &xs, detect, k),
                _ if nodes[2] >= n => {
                    let e = [(nodes[2] - n).min(nodes[3] - n), (nodes[2] - n).max(nodes[3] - n)];
                    // Looked up only for a pair within reach (most candidates are not).
                    let opposite = std::iter::once(e).flat_map(|e| {
                        let ids: &[usize] =
                            this.obs_edges.binary_search(&e).map_or(&[], |i| &this.obs_edge_opposite[i]);
                        ids.iter().map(|&o| this.obs_x1[o])
                    });
                    obstacle_edge_contact(nodes, &xs, detect, k, reach.max(detect), &out, opposite)
                }
                _ => edge_edge_contact(nodes, &xs, detect, k),
            };
            // A contact within the thickness now, or one the start velocities carry within it
            // by the end of the step (speculative).
            let stiffness = |c: &Contact| match &arcsim_areas {
                Some(areas) => k_area * areas.pair(kind, &nodes),
                None => c.stiffness,
            };
            found.map(|c| Contact { thickness: th, stiffness: stiffness(&c), law, ..c }).filter(|c| {
                let ph = |i: usize| if i < n { xh[i] } else { this.obs_x1[i - n] };
                c.gap(&nodes.map(pos)) < 0.0 || c.gap(&nodes.map(ph)) < 0.0
            })
        };
        let found =
            broad.search(mesh, &self.obs_tris, &self.obs_edges, &iv, th, th, self.params.self_collision, narrow);
        self.broad = broad;
        let mut contacts: Vec<Contact> = found.into_iter().map(|(_, c)| c).collect();
        // One node–face contact per (cloth node, obstacle body) is enough (ARCSim keeps the
        // nearest face per node): faces sharing an edge would otherwise push twice. Nearest by
        // unsigned distance |n · sep| = |gap + thickness|: the most negative gap would be the
        // face on the far side of a thin obstacle.
        let body = |c: &Contact| {
            let is_node_obstacle = c.nodes[0] < n && c.nodes[1] >= n && c.w[0] == 1.0;
            is_node_obstacle.then(|| self.body_start.partition_point(|&s| s <= c.nodes[1] - n))
        };
        contacts.dedup_by(|b, a| {
            let same = a.nodes[0] == b.nodes[0] && body(a).is_some() && body(a) == body(b);
            let dist = |c: &Contact| (c.gap(&c.nodes.map(pos)) + c.thickness).abs();
            if same && dist(b) < dist(a) {
                *a = *b;
            }
            same
        });
        // Likewise one contact per cloth edge and obstacle body against obstacle edges, and one
        // per cloth face and body against obstacle vertices: the nearest (ARCSim's
        // `proximity_constraints` keeps the nearest per element and side). Several frozen
        // planes with slightly different normals at one place make a corner that the cloth
        // cannot slide out of: on ARCSim's sphere.json the sheet stayed on the moving sphere
        // 8 frames longer and stretched 40%, with obstacle friction off.
        let key = |c: &Contact| -> Option<(u8, [usize; 3], usize)> {
            let body_of = |i: usize| self.body_start.partition_point(|&s| s <= i - n);
            if c.nodes[0] >= n {
                Some((0, [c.nodes[1], c.nodes[2], c.nodes[3]], body_of(c.nodes[0])))
            } else if c.w[0] != 1.0 && c.nodes[2] >= n {
                Some((1, [c.nodes[0], c.nodes[1], 0], body_of(c.nodes[2])))
            } else {
                None
            }
        };
        let dist = |c: &Contact| (c.gap(&c.nodes.map(pos)) + c.thickness).abs();
        let mut nearest: std::collections::HashMap<(u8, [usize; 3], usize), usize> = std::collections::HashMap::new();
        for (i, c) in contacts.iter().enumerate() {
            if let Some(k) = key(c) {
                let e = nearest.entry(k).or_insert(i);
                if dist(c) < dist(&contacts[*e]) {
                    *e = i;
                }
            }
        }
        let keep: Vec<bool> =
            contacts.iter().enumerate().map(|(i, c)| key(c).is_none_or(|k| nearest[&k] == i)).collect();
        let mut i = 0;
        contacts.retain(|_| {
            i += 1;
            keep[i - 1]
        });
        contacts
    }

    /// Outward unit normals of the obstacle vertices at the end of the step (area-weighted
    /// face normals).
    fn obstacle_vertex_normals(&self) -> Vec<Vec3> {
        let x = &self.obs_x1;
        let mut normals = vec![Vec3::zeros(); x.len()];
        for t in &self.obs_tris {
            let area_normal = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]]));
            for &i in t {
                normals[i] += area_normal;
            }
        }
        normals.iter().map(|v| v.try_normalize(0.0).unwrap_or_else(Vec3::zeros)).collect()
    }

    /// Cloth node against an obstacle face: the obstacle's outward normal decides the side, so a
    /// node that is slightly inside is pushed out, not further in. In front of the face a node
    /// counts within `detect` (the thickness plus what the pair closes in the step at its start
    /// velocities); behind it, within `reach` (thickness plus the obstacle's
    /// travel over the step), and only over the face's interior: a long face's bounding box
    /// reaches far, and a node in front of a slender obstacle (a leg) is also "behind" the faces
    /// on its far side. `face` is the face's obstacle vertices (`nodes[1..4]` less the cloth
    /// node count).
    #[allow(clippy::too_many_arguments)]
    fn obstacle_face_contact(
        &self,
        nodes: [usize; 4],
        face: [usize; 3],
        x: &[Vec3; 4],
        k: Real,
        reach: Real,
        detect: Real,
    ) -> Option<Contact> {
        let th = self.params.thickness;
        let cl = closest_point_triangle(&x[0], &x[1], &x[2], &x[3]);
        let outward = (x[2] - x[1]).cross(&(x[3] - x[1])).try_normalize(0.0)?;
        let side = (x[0] - cl.point).dot(&outward);
        if cl.dist >= if side >= 0.0 { detect } else { reach } {
            return None;
        }
        // Behind the face but beside it: another face of the obstacle is nearer. (Behind an
        // edge or a vertex of the face, within rounding, still counts: the node is under the
        // face's boundary, where no neighbouring face is strictly nearer.)
        let beside = (cl.dist * cl.dist - side * side).max(0.0).sqrt();
        if side < 0.0 && !cl.interior && beside > 1e-3 * th {
            return None;
        }
        let beside_in_front = !cl.interior && side >= 0.0 && cl.dist > 0.0;
        // In front of the face but beside it (nearest to one of its edges or corners): a contact
        // only where that edge or corner is the nearest part of the obstacle, in its Voronoi
        // region. Elsewhere another face is nearer (the node is over its interior), and a
        // frozen point contact at this face's edge, its normal tilted from the surface's by up
        // to the angle the edge subtends, resists sliding: with the obstacle's curve ahead, the
        // node's tangential motion closes its linearised gap, so it switched on as a speculative
        // contact and pushed the node back (a frictionless strip sliding over a ball at 5 ms
        // steps moved half as far as it should in 0.4 s). ARCSim takes node–face proximities
        // over the interior only (`proximity.cpp`, `add_proximity`) and leaves edges and corners
        // to its edge–edge and vertex–face ones.
        if beside_in_front && !self.in_feature_region(face, &cl.bary, &x[0]) {
            return None;
        }
        let n = if beside_in_front { (x[0] - cl.point) / cl.dist } else { outward };
        Some(Contact {
            nodes,
            w: [1.0, -cl.bary[0], -cl.bary[1], -cl.bary[2]],
            n,
            thickness: th,
            stiffness: k,
            law: Law::Quadratic,
        })
    }

    /// Whether `p` lies in the Voronoi region of the edge or corner of obstacle face `face`
    /// (obstacle vertex indices) that its barycentric closest point `bary` lies on: beside every triangle at
    /// that edge (outside the slabs over their interiors), or behind every edge at that corner.
    fn in_feature_region(&self, face: [usize; 3], bary: &[Real; 3], p: &Vec3) -> bool {
        let on: Vec<usize> = (0..3).filter(|&k| bary[k] != 0.0).map(|k| face[k]).collect();
        let x = &self.obs_x1;
        match on[..] {
            [v] => self.obs_neighbours[v].iter().all(|&u| (p - x[v]).dot(&(x[u] - x[v])) <= 0.0),
            [a, b] => {
                let e = [a.min(b), a.max(b)];
                let opposite: &[usize] = self.obs_edges.binary_search(&e).map_or(&[], |i| &self.obs_edge_opposite[i]);
                let ev = x[e[1]] - x[e[0]];
                opposite.iter().all(|&o| ev.cross(&(x[o] - x[e[0]])).cross(&ev).dot(&(p - x[e[0]])) <= 0.0)
            }
            _ => true,
        }
    }
}

/// Whether a candidate pairs an obstacle with cloth that has an `exempt` node (`n` cloth nodes).
fn exempt_against_obstacle(exempt: &[bool], nodes: &[usize; 4], n: usize) -> bool {
    !exempt.is_empty() && nodes.iter().any(|&i| i >= n) && nodes.iter().any(|&i| i < n && exempt[i])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::sdf::SdfHit;
    use crate::collision::shape::{Obstacle, ObstacleShape};
    use crate::math::motion::{Keyframe, Motion, Transform};
    use crate::math::test_rng::Rng;

    fn same_hit(a: &Option<SdfHit>, b: &Option<SdfHit>) -> bool {
        match (a, b) {
            (Some(a), Some(b)) => {
                let bits = |v: &Vec3| v.map(Real::to_bits);
                a.distance.to_bits() == b.distance.to_bits()
                    && bits(&a.point) == bits(&b.point)
                    && bits(&a.normal) == bits(&b.normal)
                    && a.triangle == b.triangle
                    && a.bary.map(Real::to_bits) == b.bary.map(Real::to_bits)
            }
            (None, None) => true,
            _ => false,
        }
    }

    /// The kept field of a rotating capsule and of a static box answers, bit for bit and ties
    /// included, as a field built from scratch at each time, whatever the order of the times
    /// (back in time, the same time twice). Half of the points are just off the bodies' edge
    /// midpoints, where two triangles are about as near and the tree's order decides.
    #[test]
    fn kept_sdf_answers_as_a_fresh_one() {
        let key = |time: Real, angle: Real| Keyframe {
            time,
            transform: Transform::new([0.1 * time, 0.0, 0.0], Some([angle, 1.0, 2.0, 0.5]), 1.0),
        };
        let capsule = Obstacle {
            name: "capsule".into(),
            shape: ObstacleShape::Capsule { radius: 0.2, length: 0.5 },
            transform: Transform::default(),
            motion: Some(Motion::new(vec![key(0.0, 0.0), key(1.0, 75.0)])),
            window: Default::default(),
        };
        let block = Obstacle {
            name: "box".into(),
            shape: ObstacleShape::Box { size: [0.3, 0.4, 0.5] },
            transform: Transform::new([0.0, 0.0, 0.6], Some([30.0, 0.0, 0.0, 1.0]), 1.0),
            motion: None,
            window: Default::default(),
        };
        let bodies: Vec<ObstacleBody> = [capsule, block].iter().map(ObstacleBody::new).collect();
        let world = CollisionWorld::new(CollisionParams::default(), bodies, 0.0);
        let mut rng = Rng(11);
        for t in [0.0, 0.35, 0.35, 0.8, 0.1, 2.0] {
            for (b, body) in world.bodies.iter().enumerate() {
                let x = body.positions_at(t);
                let mut pts: Vec<Vec3> = (0..400).map(|_| rng.vec() * 0.8).collect();
                for tri in body.triangles() {
                    let mid = 0.5 * (x[tri[0]] + x[tri[1]]);
                    pts.push(mid + (mid - x[tri[2]]) * (0.02 * rng.uniform()));
                }
                let fresh = MeshSdf::new(body.triangles(), &x).query_all(&pts);
                let kept = world.with_sdf(b, t, |sdf| sdf.query_all(&pts));
                let differ = fresh.iter().zip(&kept).filter(|(f, k)| !same_hit(f, k)).count();
                assert_eq!(differ, 0, "{}, t = {t}: {differ} of {} answers differ", body.name, pts.len());
            }
        }
    }
}
