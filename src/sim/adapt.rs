//! The adaptive mesh stage: sizing from the current state, remeshing, and everything that
//! depends on the topology rebuilt afterwards (rest data, masses, the system's pattern and
//! symbolic factorisation, handle node ids).

use std::time::Instant;

use crate::forces::buckling::compensation;
use crate::io::stats::ViewFrameStats;
use crate::math::{Mat2, Real};
use crate::mesh::Mesh;
use crate::remesh::rest_shape::{edge_angles_from_shapes, face_shape, face_shapes};
use crate::remesh::{remesh, Finished, RemeshLimits, RemeshStats};
use crate::scene::RemeshMode;
use crate::sizing::remesh_jump::{pixel_world_size, remesh_jump, Jump};
use crate::sizing::view::{face_views, view_summary};
use crate::sizing::view_memory;
use crate::sizing::{face_metrics, vertex_metrics, FaceView, ObstaclePlane, SizingParams};

use super::state::glue_pairs;
use super::state::PlasticState;
use super::timers::Stage;
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
        let mut keep = vec![false; self.state.mesh.nodes.len()];
        for &n in self.state.handle_nodes.iter().flatten() {
            keep[n] = true;
        }
        let cloth_material: Vec<usize> = self.scene.cloths.iter().map(|c| c.material).collect();
        for (k, n) in self.state.mesh.nodes.iter().enumerate() {
            if params[cloth_material[n.cloth as usize]].is_none() {
                keep[k] = true;
            }
        }
        keep
    }

    /// Nearest obstacle plane of every node within range (only when a cloth asks for it).
    fn obstacle_planes(&self, params: &[Option<SizingParams>]) -> Vec<Option<ObstaclePlane>> {
        let Some(world) = &self.ws.collisions else { return Vec::new() };
        if !params.iter().flatten().any(|p| p.refine_obstacle) || world.bodies.is_empty() {
            return Vec::new();
        }
        let range = OBSTACLE_RANGE * world.params.thickness;
        let x = self.state.mesh.positions();
        let mut best: Vec<Option<(Real, ObstaclePlane)>> = vec![None; x.len()];
        for b in (0..world.bodies.len()).filter(|&b| world.present(b, self.state.time)) {
            for (i, hit) in
                world.with_sdf(b, self.state.time, |sdf| sdf.query_all_within(&x, range)).into_iter().enumerate()
            {
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
        let key = self.view_fingerprint();
        if let Some((k, views)) = &self.ws.views {
            if *k == key {
                return views.clone();
            }
        }
        let clock = Instant::now();
        let dt = self.scene.frame_time * every as Real;
        let bodies = self.ws.collisions.as_ref().map_or(&[][..], |w| &w.bodies[..]);
        let obstacles_at = |t: Real| {
            let (mut x, mut tris) = (Vec::new(), Vec::new());
            for body in bodies.iter().filter(|b| b.present_at(t)) {
                let base = x.len();
                x.extend(body.positions_at(t));
                tris.extend(body.triangles().iter().map(|tri| tri.map(|i| i + base)));
            }
            (x, tris)
        };
        let kept = &mut self.ws.obstacle_depths;
        let mut views = face_views(&self.state.mesh, camera, self.state.time, dt, &params, &obstacles_at, kept);
        // Smoothed coarsening: μ falls by at most Δt / T_c per remesh (`view_memory`).
        let drop: Vec<Real> = params
            .iter()
            .map(|p| match p {
                Some((v, _)) if v.coarsen_time > 0.0 => dt / v.coarsen_time,
                _ => Real::INFINITY,
            })
            .collect();
        view_memory::apply_floor(&self.state.mesh, &mut views, &self.state.view_memory, &drop);
        self.ws.timers.since(Stage::View, clock);
        self.ws.views = Some((key, views.clone()));
        views
    }

    /// FNV-1a over everything the view factors depend on that changes during a run: the time,
    /// the cloth's positions and faces, and the view memory.
    fn view_fingerprint(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: u64| {
            h ^= x;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        };
        eat(self.state.time.to_bits());
        for n in &self.state.mesh.nodes {
            n.x.iter().for_each(|c| eat(c.to_bits()));
        }
        for f in 0..self.state.mesh.faces.len() {
            self.state.mesh.face_nodes(f).iter().for_each(|&i| eat(i as u64));
        }
        self.state.view_memory.iter().for_each(|m| eat(m.to_bits()));
        h
    }

    /// The view-dependent cloths' view at the frame end, for stats.json (`None` outside view
    /// mode), with the on-screen jump of the frame's remeshes.
    pub(super) fn view_stats(&mut self) -> Option<ViewFrameStats> {
        let views = self.face_views();
        let jump = self.ws.remesh_jump.take().unwrap_or_default();
        let camera = self.scene.camera.as_ref()?;
        let mut stats = (!views.is_empty()).then(|| view_summary(&self.state.mesh, camera, self.state.time, &views))?;
        (stats.view_remesh_jump_px, stats.view_remesh_jump_p99_px) = (jump.max_px, jump.p99_px);
        Some(stats)
    }

    /// Per node, how far a flip or collapse may move the cloth near it (m): the world size of
    /// its cloth's `max_jump_pixels` at the node's depth, for a node of a face the camera sees
    /// now (`FaceView::visible` ≥ ½) that is in frame; unbounded elsewhere. Empty outside view
    /// mode or when no cloth bounds the jump.
    fn jump_bounds(&self, views: &[Option<FaceView>]) -> Vec<Real> {
        let Some(camera) = &self.scene.camera else { return Vec::new() };
        let mut pixels = vec![0.0; self.scene.materials.len()];
        for c in &self.scene.cloths {
            if let Some(r) = c.remesh.as_ref().filter(|r| r.mode == RemeshMode::View) {
                pixels[c.material] = r.view.max_jump_pixels;
            }
        }
        if views.is_empty() || pixels.iter().all(|&p| p == 0.0) {
            return Vec::new();
        }
        let height = self.view_image_height();
        let view = camera.view_at(self.state.time);
        let mesh = &self.state.mesh;
        let mut bound = vec![Real::INFINITY; mesh.nodes.len()];
        for (f, v) in views.iter().enumerate() {
            let px = pixels.get(mesh.faces[f].material as usize).copied().unwrap_or(0.0);
            if px == 0.0 || !v.as_ref().is_some_and(|v| v.visible >= 0.5) {
                continue;
            }
            for n in mesh.face_nodes(f) {
                if let Some(size) = pixel_world_size(&view, height, &mesh.nodes[n].x) {
                    bound[n] = bound[n].min(px * size);
                }
            }
        }
        bound
    }

    /// The image height of the view-dependent cloths (the largest, if they differ).
    fn view_image_height(&self) -> Real {
        self.scene
            .cloths
            .iter()
            .filter_map(|c| c.remesh.as_ref().filter(|r| r.mode == RemeshMode::View))
            .map(|r| r.view.image_height)
            .fold(0.0, Real::max)
    }

    /// How far the remesh from `before` (seen as `views` say) moved the view-dependent cloth on
    /// screen, seen by the camera now in an image of the cloths' `image_height`
    /// (`sizing::remesh_jump`).
    fn screen_jump(&self, before: &Mesh, views: &[Option<FaceView>]) -> Jump {
        let Some(camera) = &self.scene.camera else { return Jump::default() };
        let height = self.view_image_height();
        remesh_jump(before, views, &self.state.mesh, &camera.view_at(self.state.time), height)
    }

    /// Remeshes the cloths in `mode` to their sizing field (for `Uniform`: once, to the
    /// minimum edge length). Rebuilds the topology-dependent state when anything changed.
    pub fn remesh(&mut self, mode: RemeshMode) -> Result<RemeshStats, SimError> {
        let params = self.sizing_params(mode);
        if params.iter().all(Option::is_none) {
            return Ok(RemeshStats::default());
        }
        let views = if mode.is_adaptive() { self.face_views() } else { Vec::new() };
        let clock = Instant::now();
        let face = match mode {
            RemeshMode::Adaptive | RemeshMode::View => {
                let plastic = self.plastic_shapes();
                face_metrics(&self.state.mesh, &params, &self.obstacle_planes(&params), &views, &plastic)
            }
            RemeshMode::Uniform => (0..self.state.mesh.faces.len())
                .map(|f| match &params[self.state.mesh.faces[f].material as usize] {
                    Some(p) => Mat2::identity() / (p.size_min * p.size_min),
                    None => Mat2::zeros(),
                })
                .collect(),
        };
        let vsize = vertex_metrics(&self.state.mesh, &face);
        self.ws.timers.since(Stage::Sizing, clock);
        let clock = Instant::now();
        let size_min = params.iter().flatten().map(|p| p.size_min).fold(Real::INFINITY, Real::min);
        let aspect_min = params.iter().flatten().map(|p| p.aspect_min).fold(1.0, Real::min);
        let relax_splits =
            self.scene.cloths.iter().map(|c| c.remesh.as_ref().is_some_and(|r| r.relax_splits)).collect();
        let limits = RemeshLimits { size_min, aspect_min, coarsen: mode.is_adaptive(), relax_splits };
        let preserved = self.preserved_nodes(&params);
        let groups = self.circle_groups();
        let (shapes, damage) = self.shapes_to_carry();
        let jump = self.jump_bounds(&views);
        let state = &self.state;
        let (finished, stats) =
            remesh(&state.mesh, vsize, preserved, &groups, &shapes, &damage, &state.rest_x, &limits, &jump)
                .map_err(|e| SimError::Mesh(format!("remeshing failed: {e}")))?;
        let changed = stats.splits + stats.collapses + stats.flips > 0;
        let memory = match views.is_empty() {
            true => Vec::new(),
            false => view_memory::remember(&self.state.mesh, &views),
        };
        self.state.view_memory = match changed && !memory.is_empty() {
            true => view_memory::carry(&memory, &finished.node_map, &finished.mesh),
            false => memory,
        };
        // The mesh the camera saw just before, to measure how far the remesh moves it on screen.
        let before = (changed && !views.is_empty()).then(|| self.state.mesh.clone());
        if changed {
            self.adopt(finished)?;
        }
        self.ws.timers.since(Stage::Remesh, clock);
        if !views.is_empty() {
            let clock = Instant::now();
            let buckle = self.buckling_factors(&params);
            if !buckle.is_empty() || !self.state.buckle.is_empty() {
                self.state.buckle = buckle;
                self.ws.rest.set_slack(&self.state.mesh, &self.state.buckle, &self.scene.materials);
                self.ws.timers.since(Stage::Buckling, clock);
            }
        }
        if changed && mode.is_adaptive() {
            if let Some(pop) = self.pop_filter()? {
                let tally = &mut self.ws.pop;
                tally.iterations += pop.iterations;
                tally.max_move = tally.max_move.max(pop.max_move);
            }
        }
        if let Some(before) = before {
            let clock = Instant::now();
            let jump = self.screen_jump(&before, &views);
            self.ws.timers.since(Stage::View, clock);
            let kept = self.ws.remesh_jump.get_or_insert_with(Jump::default);
            (kept.max_px, kept.p99_px) = (kept.max_px.max(jump.max_px), kept.p99_px.max(jump.p99_px));
            kept.points += jump.points;
        }
        Ok(stats)
    }

    /// Per face, κ of buckling compensation (`forces::buckling`): from the longest edge r of the
    /// face in the view-independent sizing (every criterion, no view factor, the plain minimum
    /// edge), the remesher's edge metric; 1 on cloths without it. Empty when no cloth has it.
    fn buckling_factors(&self, params: &[Option<SizingParams>]) -> Vec<Real> {
        let mut on = vec![false; self.scene.materials.len()];
        for c in &self.scene.cloths {
            if let Some(r) = &c.remesh {
                on[c.material] = r.mode == RemeshMode::View && r.view.buckling_compensation;
            }
        }
        if !on.contains(&true) {
            return Vec::new();
        }
        let mesh = &self.state.mesh;
        let plastic = self.plastic_shapes();
        let face = face_metrics(mesh, params, &self.obstacle_planes(params), &[], &plastic);
        let vsize = vertex_metrics(mesh, &face);
        (0..mesh.faces.len())
            .map(|f| {
                if !on[mesh.faces[f].material as usize] {
                    return 1.0;
                }
                let (u, v) = (mesh.face_uv(f), mesh.faces[f].v.map(|v| v.idx()));
                let r2 = (0..3)
                    .map(|k| {
                        let (a, b) = (k, (k + 1) % 3);
                        let du = u[b] - u[a];
                        0.5 * (du.dot(&(vsize[v[a]] * du)) + du.dot(&(vsize[v[b]] * du)))
                    })
                    .fold(0.0, Real::max);
                compensation(r2.sqrt())
            })
            .collect()
    }

    /// Per face, the plastic rest shape of a face whose material yields (Narain et al. 2013
    /// refine where it is curved, ARCSim's `Mcurvp`); empty without plasticity.
    fn plastic_shapes(&self) -> Vec<Option<Mat2>> {
        let Some(plastic) = &self.state.plastic else { return Vec::new() };
        let faces = &self.state.mesh.faces;
        let yields = |f: usize| self.scene.materials[faces[f].material as usize].plasticity.is_some();
        (0..faces.len()).map(|f| yields(f).then_some(plastic.shapes[f])).collect()
    }

    /// What the faces carry through a remesh (`remesh::rest_shape`): with a rest embedding
    /// (`SimState::rest_x`), the new mesh's rest angles come from it, so the faces carry only the
    /// plastic state's departure from it (ARCSim's residuals, `back_up_residuals`); without
    /// one, the plastic state as it is, or the rest angles' shape operators; a flat rest shape
    /// (every angle zero) stays flat without carrying anything.
    fn shapes_to_carry(&self) -> (Vec<Mat2>, Vec<Real>) {
        let state = &self.state;
        let embedded = !state.rest_x.is_empty();
        match &state.plastic {
            Some(p) if embedded => {
                let angles = self.scene.rest_angles_at(&state.mesh, &state.rest_x);
                let residual = (0..p.shapes.len()).map(|f| p.shapes[f] - face_shape(&state.mesh, f, &angles)).collect();
                (residual, p.damage.clone())
            }
            Some(p) => (p.shapes.clone(), p.damage.clone()),
            None if !embedded && state.rest_angles.iter().any(|&a| a != 0.0) => {
                (face_shapes(&state.mesh, &state.rest_angles), Vec::new())
            }
            None => (Vec::new(), Vec::new()),
        }
    }

    /// Takes a remeshed mesh: handles renumbered (circle rings: the nodes of their group), rest
    /// angles solved from the rest shape the faces carried through the remesh
    /// (`remesh::rest_shape`; all zero for a flat rest shape), the plastic state taken over,
    /// masses and rest data rebuilt, the implicit system's new pattern left for the next step to
    /// analyse, cloth pushed back out of obstacles (the `separation` stage, unless switched off).
    fn adopt(&mut self, finished: Finished) -> Result<(), SimError> {
        let Finished { mesh, node_map, face_shapes, face_damage, groups, rest_x } = finished;
        let state = &mut self.state;
        let curved = state.plastic.is_some() || state.rest_angles.iter().any(|&a| a != 0.0);
        let embedded = !state.rest_x.is_empty();
        for n in state.handle_nodes.iter_mut().flatten() {
            *n = node_map[*n].ok_or_else(|| SimError::Mesh("remeshing removed a handle node".into()))?;
        }
        state.mesh = mesh;
        let density: Vec<Real> = self.scene.materials.iter().map(|m| m.density).collect();
        state.mesh.compute_masses(&density);
        // With a rest embedding the faces carried plastic residuals (`shapes_to_carry`): the
        // plastic shape is the embedding's plus the residual (ARCSim's `restore_residuals`), and
        // the rest angles of elastic cloth are the embedding's own, exactly (a fold stays on its
        // edges; the faces beside it stay flat).
        let embedding = embedded.then(|| self.scene.rest_angles_at(&state.mesh, &rest_x));
        state.rest_x = rest_x;
        let plastic_shapes: Vec<Mat2> = match (&embedding, &state.plastic) {
            (Some(angles), Some(_)) => {
                (0..face_shapes.len()).map(|f| face_shapes[f] + face_shape(&state.mesh, f, angles)).collect()
            }
            _ => face_shapes,
        };
        state.rest_angles = match embedding {
            Some(angles) if state.plastic.is_none() => angles,
            _ if curved => edge_angles_from_shapes(&state.mesh, &plastic_shapes),
            _ => vec![0.0; state.mesh.edges.len()],
        };
        if let Some(plastic) = &mut state.plastic {
            *plastic = PlasticState { shapes: plastic_shapes, damage: face_damage };
        }
        state.stuck.clear();
        state.pinched = state.pinched.iter().filter_map(|&i| node_map[i]).collect();
        state.pinched.sort_unstable();
        if !groups.iter().all(|&g| g == 0) {
            self.rings_remeshed(&groups);
        }
        let state = &mut self.state;
        state.extra_pairs = glue_pairs(&self.scene, &state.handle_nodes);
        self.ws.remeshed(state, &self.scene.materials)?;
        self.constraints_remeshed();
        if !self.scene.disabled.separation {
            let (_, left) = self.push_out(Real::INFINITY)?;
            self.state.separating |= left > 0;
        }
        Ok(())
    }
}
