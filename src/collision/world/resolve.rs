//! Continuous collision detection over a step and the impact-zone loop that makes the step's
//! end positions collision-free (Harmon et al. 2008; rigid zones as the last resort,
//! `rigid_zone.rs`).

use super::{exempt_against_obstacle, CollisionCounters, CollisionWorld, ZONE_SEPARATION};
use crate::collision::broad::{Candidate, Interval, VF};
use crate::collision::ccd::{edge_edge_ccd, vertex_face_ccd, Impact, CCD_TOLERANCE};
use crate::collision::impact_zones::{resolve_zone, ZoneConstraint, ZoneState};
use crate::collision::rigid_zone::resolve_zone_rigid;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;

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
        let exempt = &self.exempt;
        let narrow = |(kind, nodes): Candidate| {
            if exempt_against_obstacle(exempt, &nodes, n) {
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
        let (tris, edges) = (&self.obs_tris, &self.obs_edges);
        let found = broad.search(mesh, tris, edges, &iv, CCD_TOLERANCE, self.params.self_collision, narrow);
        self.broad = broad;
        found.into_iter().map(|((_, nodes), imp)| (nodes, imp)).collect()
    }

    /// Makes the end-of-step cloth positions `x` collision-free relative to `x0` by iterated CCD
    /// and impact-zone projection. `inv_mass` is 0 for pinned nodes.
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
        inv_mass: &[Real],
        rigid_beyond: Option<Real>,
        counters: &mut CollisionCounters,
    ) {
        let n = mesh.nodes.len();
        let delta = ZONE_SEPARATION * self.params.thickness;
        let target: Vec<Vec3> = x.to_vec();
        let mut constraints: Vec<ZoneConstraint> = Vec::new();
        let mut rigid = vec![false; n];
        let mut rigid_grew = false;
        // Handles win over collisions: an impact whose moving side is all pinned cloth (a handle
        // driven into an obstacle) has no solution, and would otherwise be met again on every
        // iteration until the cap.
        let movable = |(nodes, imp): &([usize; 4], Impact)| {
            (0..4).any(|j| nodes[j] < n && inv_mass[nodes[j]] > 0.0 && imp.w[j] != 0.0)
        };
        for _ in 0..self.params.max_iterations {
            let impacts: Vec<_> = self.detect_impacts(mesh, x0, x).into_iter().filter(movable).collect();
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
                let mut state = ZoneState { x, inv_mass, fixed: &self.obs_x1 };
                let free: Vec<usize> = zone_nodes.iter().copied().filter(|&i| inv_mass[i] > 0.0).collect();
                let already_rigid = rigid_beyond.is_some() && free.iter().any(|&i| rigid[i]);
                let projected = !already_rigid
                    && resolve_zone(&mut state, &cons, 1e-12).is_ok()
                    && rigid_beyond.is_none_or(|limit| free.iter().all(|&i| (state.x[i] - x0[i]).norm() <= limit));
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
        if self.detect_impacts(mesh, x0, x).iter().any(movable) {
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
