//! Continuous collision detection over a step and the impact-zone loop that makes the step's
//! end positions collision-free (Harmon et al. 2008; rigid zones as the last resort,
//! `rigid_zone.rs`).

use super::{exempt_against_obstacle, CollisionCounters, CollisionWorld, ZONE_SEPARATION};
use crate::collision::broad::{Candidate, Interval, VF};
use crate::collision::ccd::{edge_edge_ccd, vertex_face_ccd, Impact, CCD_TOLERANCE};
use crate::collision::impact_zones::{resolve_zone, ZoneConstraint, ZoneState};
use crate::collision::rigid_zone::resolve_zone_rigid;
use crate::collision::untangle::exempt_pair;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;

/// Inverse masses of the cloth nodes in the impact-zone projection (`CollisionWorld::resolve`).
#[derive(Clone, Copy)]
pub struct InvMasses<'a> {
    /// 0 for pinned nodes and massless ones.
    pub held: &'a [Real],
    /// What a held node takes when its zone has no solution while it is held (the nodes trapped
    /// in a pinch: their mass; pinned nodes: 0).
    pub yielding: &'a [Real],
}

impl CollisionWorld {
    /// Continuous collision detection from `x0` to `x1` (cloth), obstacles from `obs_x0` to
    /// `obs_x1`. Returns impacts with their nodes, in a deterministic order.
    pub fn detect_impacts(&mut self, mesh: &Mesh, x0: &[Vec3], x1: &[Vec3]) -> Vec<([usize; 4], Impact)> {
        let n = mesh.nodes.len();
        let iv = Interval { cloth0: x0, cloth1: x1, obs0: &self.obs_x0, obs1: &self.obs_x1 };
        let (p0, p1) = (
            |i: usize| if i < n { x0[i] } else { self.obs_x0[i - n] },
            |i: usize| if i < n { x1[i] } else { self.obs_x1[i - n] },
        );
        let outward = &self.obs_normals;
        let (exempt, untangling) = (&self.exempt, &self.untangling);
        let narrow = |(kind, nodes): Candidate| {
            if exempt_against_obstacle(exempt, &nodes, n) || exempt_pair(untangling, kind == VF, &nodes) {
                return None;
            }
            let (a, b) = (nodes.map(p0), nodes.map(p1));
            let hit =
                if kind == VF { vertex_face_ccd(&a, &b, CCD_TOLERANCE) } else { edge_edge_ccd(&a, &b, CCD_TOLERANCE) };
            let imp = hit.map(|imp| outside_obstacle(imp, &nodes, n, outward))?;
            // Cloth leaving an obstacle it was inside of has nothing to be stopped.
            let obstacle = nodes.iter().any(|&i| i >= n);
            let sep = |x: &[Vec3; 4]| (0..4).map(|j| imp.w[j] * imp.n.dot(&x[j])).sum::<Real>();
            (!(obstacle && sep(&a) < 0.0 && sep(&b) >= 0.0)).then_some(imp)
        };
        let mut broad = std::mem::take(&mut self.broad);
        let (tris, edges, reach) = (&self.obs_tris, &self.obs_edges, self.params.thickness);
        let found = broad.search(mesh, tris, edges, &iv, CCD_TOLERANCE, reach, self.params.self_collision, narrow);
        self.broad = broad;
        found.into_iter().map(|((_, nodes), imp)| (nodes, imp)).collect()
    }

    /// Makes the end-of-step cloth positions `x` collision-free relative to `x0` by iterated CCD
    /// and impact-zone projection. `masses.held` is 0 for pinned nodes.
    ///
    /// `masses.yielding` is each node's inverse mass when a zone cannot be solved with it held: the
    /// nodes trapped in a pinch (`sim::separate`) are held with the pinch, but two trapped
    /// layers closing on a free node between them leave its zone no solution but a fling. Such
    /// a zone is solved again with its held nodes yielding, and they stay movable while the
    /// loop runs (zones merge through them).
    ///
    /// With `rigid_beyond` (the last, smallest retry of a step), a zone whose projection has no
    /// solution, or moves one of its nodes farther than `rigid_beyond` from its start, becomes
    /// a rigid impact zone (`rigid_zone.rs`) and stays one while the loop runs: every zone it
    /// later merges into moves rigidly too (Bridson et al. 2002, §7.4).
    pub fn resolve(
        &mut self,
        mesh: &Mesh,
        x0: &[Vec3],
        x: &mut [Vec3],
        masses: InvMasses,
        rigid_beyond: Option<Real>,
        counters: &mut CollisionCounters,
    ) {
        let n = mesh.nodes.len();
        let delta = ZONE_SEPARATION * self.params.thickness;
        let target: Vec<Vec3> = x.to_vec();
        let mut constraints: Vec<ZoneConstraint> = Vec::new();
        let mut rigid = vec![false; n];
        let mut rigid_grew = false;
        let (mut inv_mass, yielding) = (masses.held.to_vec(), masses.yielding);
        // Handles win over collisions: an impact whose moving side is all pinned cloth (a handle
        // driven into an obstacle) has no solution, and would otherwise be met again on every
        // iteration until the cap.
        let movable = |inv_mass: &[Real], (nodes, imp): &([usize; 4], Impact)| {
            (0..4).any(|j| nodes[j] < n && inv_mass[nodes[j]] > 0.0 && imp.w[j] != 0.0)
        };
        for _ in 0..self.params.max_iterations {
            let impacts: Vec<_> =
                self.detect_impacts(mesh, x0, x).into_iter().filter(|i| movable(&inv_mass, i)).collect();
            counters.ccd_iterations += 1;
            if impacts.is_empty() {
                return;
            }
            counters.impacts += impacts.len();
            // Constraints accumulate over iterations (Harmon et al. 2008, §4; ARCSim's
            // `add_impacts`): a zone keeps every impact it has met, including earlier
            // linearisations of the same primitives. Replacing those instead lets the projection
            // satisfy one linearisation at a time and cycle between two until the cap.
            let known = constraints.len();
            for (nodes, imp) in impacts {
                let c = ZoneConstraint { nodes, w: imp.w, n: imp.n, delta };
                if !constraints.contains(&c) {
                    constraints.push(c);
                }
            }
            // Each iteration solves its zones afresh from `target`: with no constraint new it
            // would repeat the last iteration exactly, and so every one after it, to the cap.
            if constraints.len() == known && !std::mem::take(&mut rigid_grew) {
                break;
            }
            // Zones: connected components of cloth nodes tied by constraints.
            let mut uf = UnionFind::new(n);
            for c in &constraints {
                let cloth: Vec<usize> = c.nodes.iter().copied().filter(|&i| i < n && inv_mass[i] > 0.0).collect();
                for w in cloth.windows(2) {
                    uf.union(w[0], w[1]);
                }
            }
            let mut zones: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
            for (k, c) in constraints.iter().enumerate() {
                if let Some(&i) = c.nodes.iter().find(|&&i| i < n && inv_mass[i] > 0.0) {
                    zones.entry(uf.find(i)).or_default().push(k);
                }
            }
            counters.impact_zones += zones.len();
            // Each zone restarts from the solver's positions and satisfies all its constraints.
            for members in zones.values() {
                let cons: Vec<ZoneConstraint> = members.iter().map(|&k| constraints[k]).collect();
                let mut zone_nodes: Vec<usize> = cons.iter().flat_map(|c| c.nodes).filter(|&i| i < n).collect();
                zone_nodes.sort_unstable();
                zone_nodes.dedup();
                for &i in &zone_nodes {
                    x[i] = target[i];
                }
                if std::env::var_os("VIEWCLOTH_DEBUG_ZONES").is_some() {
                    eprintln!("zone: {} constraints, {} nodes", cons.len(), zone_nodes.len());
                }
                let within = |x: &[Vec3], free: &[usize]| {
                    rigid_beyond.is_none_or(|limit| free.iter().all(|&i| (x[i] - x0[i]).norm() <= limit))
                };
                let mut free: Vec<usize> = zone_nodes.iter().copied().filter(|&i| inv_mass[i] > 0.0).collect();
                let already_rigid = rigid_beyond.is_some() && free.iter().any(|&i| rigid[i]);
                let mut state = ZoneState { x, inv_mass: &inv_mass, fixed: &self.obs_x1 };
                let mut projected =
                    !already_rigid && resolve_zone(&mut state, &cons, 1e-12).is_ok() && within(state.x, &free);
                let yields = |i: &usize| inv_mass[*i] == 0.0 && yielding[*i] > 0.0;
                if !projected && !already_rigid && zone_nodes.iter().any(yields) {
                    let yielders: Vec<usize> = zone_nodes.iter().copied().filter(yields).collect();
                    for &i in &yielders {
                        inv_mass[i] = yielding[i];
                    }
                    for &i in &zone_nodes {
                        x[i] = target[i];
                    }
                    free = zone_nodes.iter().copied().filter(|&i| inv_mass[i] > 0.0).collect();
                    state = ZoneState { x, inv_mass: &inv_mass, fixed: &self.obs_x1 };
                    projected = resolve_zone(&mut state, &cons, 1e-12).is_ok() && within(state.x, &free);
                    counters.yielded_nodes += yielders.len();
                    rigid_grew = true;
                }
                if projected {
                    continue;
                }
                if rigid_beyond.is_none() {
                    counters.failed_zones += 1;
                    continue;
                }
                if !free.iter().all(|&i| rigid[i]) {
                    free.iter().for_each(|&i| rigid[i] = true);
                    rigid_grew = true;
                    counters.rigid_zones += 1;
                }
                for &i in &free {
                    state.x[i] = target[i];
                }
                if resolve_zone_rigid(&mut state, x0, &free, &cons, 1e-12).is_err() {
                    counters.failed_zones += 1;
                }
            }
        }
        if self.detect_impacts(mesh, x0, x).iter().any(|i| movable(&inv_mass, i)) {
            counters.cap_hits += 1;
        }
    }
}

/// Against an obstacle, the side the cloth must end on is known: outside (obstacles are closed
/// and their faces point out). CCD orients an impact's normal by the side at the start of the
/// step, which preserves any penetration already there: a remesh that flips or collapses an edge
/// over a convex obstacle vertex leaves it poking a few µm through the new face, and the zone
/// projection would then hold it through. So the normal of a cloth–obstacle impact is oriented
/// out of the obstacle (the separation Σ wᵢ xᵢ runs from the obstacle to the cloth when the
/// obstacle's weights are negative), which undoes such a penetration instead. Bridson et al.
/// 2002 (§7) and ARCSim's `separateobs` likewise separate cloth from obstacles by the
/// obstacle's inside.
fn outside_obstacle(mut imp: Impact, nodes: &[usize; 4], n: usize, outward: &[Vec3]) -> Impact {
    let (mut dir, mut w_obstacle) = (Vec3::zeros(), 0.0);
    for j in 0..4 {
        if nodes[j] >= n {
            dir += outward[nodes[j] - n];
            w_obstacle += imp.w[j];
        }
    }
    // Cloth minus obstacle (obstacle weights negative) should point along `dir`.
    if w_obstacle != 0.0 && imp.n.dot(&dir) * w_obstacle > 0.0 {
        imp.n = -imp.n;
    }
    imp
}

struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind { parent: (0..n).collect() }
    }
    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            self.parent[hi] = lo;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::params::CollisionParams;
    use crate::math::Vec2;
    use crate::mesh::{Face, Node, NodeId, Vert, VertId};

    /// Three separate triangles of cloth (nodes 3k..3k+3), each stacked at height `z[k]`: a
    /// small one (the free layer between two held ones) and two larger ones over and under it.
    fn layers(z: [Real; 3]) -> (Mesh, Vec<Vec3>) {
        let mut mesh = Mesh::default();
        let mut x = Vec::new();
        for (k, z) in z.into_iter().enumerate() {
            let corners: [[Real; 2]; 3] = match k {
                0 => [[0.0, 0.0], [0.1, 0.0], [0.0, 0.1]],
                _ => [[-0.05, -0.05], [0.2, -0.05], [-0.05, 0.2]],
            };
            for c in corners {
                let id = mesh.nodes.len() as u32;
                let p = Vec3::new(c[0], c[1], z);
                mesh.nodes.push(Node { x: p, v: Vec3::zeros(), a: Vec3::zeros(), mass: 1e-3, cloth: 0 });
                mesh.verts.push(Vert { u: Vec2::new(c[0], c[1]), node: NodeId(id) });
                x.push(p);
            }
            let v = [0, 1, 2].map(|j| VertId(3 * k as u32 + j));
            mesh.faces.push(Face { v, material: 0 });
        }
        mesh.rebuild_topology().unwrap();
        (mesh, x)
    }

    /// Whether the layers keep their order: the first (free) above the third and below the
    /// second, everywhere (they stay flat and parallel to within the gaps checked).
    fn stacked(x: &[Vec3]) -> bool {
        let lo = |k: usize| x[3 * k..3 * k + 3].iter().map(|p| p.z).fold(Real::MAX, Real::min);
        let hi = |k: usize| x[3 * k..3 * k + 3].iter().map(|p| p.z).fold(Real::MIN, Real::max);
        hi(2) < lo(0) && hi(0) < lo(1)
    }

    /// Two held layers (trapped in a pinch) close through a free layer between them: held
    /// immovable, the free layer's zone has no solution (impacts left at the cap); yielding,
    /// the held layers stop on it and they keep their order.
    #[test]
    fn held_layers_closing_on_free_cloth_yield_to_it() {
        let (mesh, x0) = layers([0.0, 0.01, -0.01]);
        let (_, target) = layers([0.0, -0.01, 0.01]);
        let held: Vec<Real> = (0..9).map(|i| if i < 3 { 1e3 } else { 0.0 }).collect();
        let yielding = vec![1e3; 9];
        for (yields, expect_free) in [(&held, false), (&yielding, true)] {
            let mut world = CollisionWorld::new(CollisionParams::default(), Vec::new(), 0.0);
            assert!(!world.detect_impacts(&mesh, &x0, &target).is_empty());
            let mut x = target.clone();
            let mut counters = CollisionCounters::default();
            world.resolve(&mesh, &x0, &mut x, InvMasses { held: &held, yielding: yields }, None, &mut counters);
            let left = world.detect_impacts(&mesh, &x0, &x).len();
            assert_eq!(stacked(&x) && left == 0, expect_free, "yielding {expect_free}: {left} impacts left");
            if expect_free {
                assert_eq!(counters.yielded_nodes, 6);
                // The free layer is pushed no farther than the held layers' travel.
                assert!(x[..3].iter().zip(&x0).all(|(p, q)| (p - q).norm() < 0.01));
            }
        }
    }
}
