//! The adaptive mesh stage: sizing from the current state, remeshing, and everything that
//! depends on the topology rebuilt afterwards (rest data, masses, the system's pattern and
//! symbolic factorisation, handle node ids).

use std::collections::HashMap;

use crate::forces::RestState;
use crate::math::{Mat2, Real};
use crate::remesh::{remesh, Finished, RemeshLimits, RemeshStats};
use crate::scene::RemeshMode;
use crate::sizing::view::face_views;
use crate::sizing::{face_metrics, vertex_metrics, FaceView, ObstaclePlane, SizingParams};
use crate::solver::pattern::BlockPattern;

use super::{SimError, Simulation};

/// Obstacle features within this many collision thicknesses refine the cloth.
const OBSTACLE_RANGE: Real = 10.0;

impl Simulation {
    /// Per cloth (by material index), the sizing parameters of cloths that remesh in `mode`.
    fn sizing_params(&self, mode: RemeshMode) -> Vec<Option<SizingParams>> {
        let mut out = vec![None; self.scene.materials.len()];
        for c in &self.scene.cloths {
            let runs_in =
                |r: &&crate::scene::Remesh| r.mode == mode || (mode == RemeshMode::Adaptive && r.mode.is_adaptive());
            if let Some(r) = c.remesh.as_ref().filter(runs_in) {
                out[c.material] = Some(r.sizing.clone());
            }
        }
        out
    }

    /// Nodes the remesher must keep: handle nodes, and every node of a cloth not being remeshed.
    fn preserved_nodes(&self, params: &[Option<SizingParams>]) -> Vec<bool> {
        let mut keep = vec![false; self.mesh.nodes.len()];
        for h in &self.scene.handles {
            for &n in &h.nodes {
                keep[n] = true;
            }
        }
        let cloth_material: Vec<usize> = self.scene.cloths.iter().map(|c| c.material).collect();
        for (k, n) in self.mesh.nodes.iter().enumerate() {
            if params[cloth_material[n.cloth as usize]].is_none() {
                keep[k] = true;
            }
        }
        keep
    }

    /// Nearest obstacle plane of every node within range (only when a cloth asks for it).
    fn obstacle_planes(&self, params: &[Option<SizingParams>]) -> Vec<Option<ObstaclePlane>> {
        let Some(world) = &self.collisions else { return Vec::new() };
        if !params.iter().flatten().any(|p| p.refine_obstacle) || world.bodies.is_empty() {
            return Vec::new();
        }
        let range = OBSTACLE_RANGE * world.params.thickness;
        let x = self.mesh.positions();
        let mut best: Vec<Option<(Real, ObstaclePlane)>> = vec![None; x.len()];
        for b in 0..world.bodies.len() {
            for (i, hit) in world.with_sdf(b, self.time, |sdf| sdf.query_all(&x)).into_iter().enumerate() {
                let Some(hit) = hit else { continue };
                let d = hit.distance.abs();
                if d < range && best[i].is_none_or(|(b, _)| d < b) {
                    best[i] = Some((d, ObstaclePlane { point: hit.point, normal: hit.normal }));
                }
            }
        }
        best.into_iter().map(|b| b.map(|(_, p)| p)).collect()
    }

    /// The camera's view of every face of the view-dependent cloths (empty when there are none
    /// or no camera): Koh et al. 2014's view factors over the lookahead window.
    fn face_views(&mut self) -> Vec<Option<FaceView>> {
        let Some(camera) = &self.scene.camera else { return Vec::new() };
        let mut params = vec![None; self.scene.materials.len()];
        let mut every = usize::MAX;
        for c in &self.scene.cloths {
            if let Some(r) = c.remesh.as_ref().filter(|r| r.mode == RemeshMode::View) {
                params[c.material] = Some((r.view, r.sizing.size_min));
                every = every.min(r.every);
            }
        }
        if params.iter().all(Option::is_none) {
            return Vec::new();
        }
        let clock = std::time::Instant::now();
        let dt = self.scene.frame_time * every as Real;
        let views = face_views(&self.mesh, camera, self.time, dt, &params);
        self.timers.add("view", clock.elapsed().as_secs_f64());
        views
    }

    /// Remeshes the cloths in `mode` to their sizing field (for `Uniform`: once, to the
    /// minimum edge length). Rebuilds the topology-dependent state when anything changed.
    pub fn remesh(&mut self, mode: RemeshMode) -> Result<RemeshStats, SimError> {
        let params = self.sizing_params(mode);
        if params.iter().all(Option::is_none) {
            return Ok(RemeshStats::default());
        }
        let views = if mode.is_adaptive() { self.face_views() } else { Vec::new() };
        let clock = std::time::Instant::now();
        let face = match mode {
            RemeshMode::Adaptive | RemeshMode::View => {
                face_metrics(&self.mesh, &params, &self.obstacle_planes(&params), &views)
            }
            RemeshMode::Uniform => (0..self.mesh.faces.len())
                .map(|f| match &params[self.mesh.faces[f].material as usize] {
                    Some(p) => Mat2::identity() / (p.size_min * p.size_min),
                    None => Mat2::zeros(),
                })
                .collect(),
        };
        let vsize = vertex_metrics(&self.mesh, &face);
        self.timers.add("sizing", clock.elapsed().as_secs_f64());
        let clock = std::time::Instant::now();
        let size_min = params.iter().flatten().map(|p| p.size_min).fold(Real::INFINITY, Real::min);
        let aspect_min = params.iter().flatten().map(|p| p.aspect_min).fold(1.0, Real::min);
        let limits = RemeshLimits { size_min, aspect_min, coarsen: mode.is_adaptive() };
        let preserved = self.preserved_nodes(&params);
        let (finished, stats) = remesh(&self.mesh, vsize, preserved, &limits)
            .map_err(|e| SimError::Mesh(format!("remeshing failed: {e}")))?;
        if stats.splits + stats.collapses + stats.flips > 0 {
            self.adopt(finished)?;
        }
        self.timers.add("remesh", clock.elapsed().as_secs_f64());
        Ok(stats)
    }

    /// Takes a remeshed mesh: handles renumbered, rest angles carried over by node pair (new
    /// edges rest flat), masses and rest data rebuilt, the
    /// implicit system's new pattern left for the next step to analyse.
    fn adopt(&mut self, finished: Finished) -> Result<(), SimError> {
        let Finished { mesh, node_map } = finished;
        let mut old_angles: HashMap<(usize, usize), Real> = HashMap::new();
        for (e, edge) in self.mesh.edges.iter().enumerate() {
            if let (Some(a), Some(b)) = (node_map[edge.n[0].idx()], node_map[edge.n[1].idx()]) {
                old_angles.insert((a.min(b), a.max(b)), self.rest_angles[e]);
            }
        }
        for h in &mut self.scene.handles {
            for n in &mut h.nodes {
                *n = node_map[*n].ok_or_else(|| SimError::Mesh("remeshing removed a handle node".into()))?;
            }
        }
        self.mesh = mesh;
        let density: Vec<Real> = self.scene.materials.iter().map(|m| m.density).collect();
        self.mesh.compute_masses(&density);
        self.rest_angles = self
            .mesh
            .edges
            .iter()
            .map(|e| {
                let (a, b) = (e.n[0].idx(), e.n[1].idx());
                old_angles.get(&(a.min(b), a.max(b))).copied().unwrap_or(0.0)
            })
            .collect();
        let angles = &self.rest_angles;
        self.rest = RestState::new(&self.mesh, |e| angles[e])
            .map_err(|f| SimError::Mesh(format!("remeshing left face {f} degenerate")))?;
        self.node_area = node_areas(&self.mesh, &self.rest);
        self.extra_pairs.clear();
        self.pending_pattern = Some(BlockPattern::new(&self.mesh, &self.rest.hinges, &[]));
        self.push_out(None)?;
        Ok(())
    }
}

/// A third of the adjacent faces' material area per node (m²).
pub(super) fn node_areas(mesh: &crate::mesh::Mesh, rest: &RestState) -> Vec<Real> {
    let mut area = vec![0.0; mesh.nodes.len()];
    for f in 0..mesh.faces.len() {
        for n in mesh.face_nodes(f) {
            area[n] += rest.membrane[f].area / 3.0;
        }
    }
    area
}
