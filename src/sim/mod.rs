//! The simulation: the scene (read-only), the state a checkpoint holds (`state`), the workspace
//! derived from them (`workspace`), the step as a list of named, timed stages (`step`) with its
//! fault checks (`checks`) and retries (`recover`), the plasticity stage (`plastic`), the
//! remeshing stage (`adapt`) and its pop filter (`pop`), the separation of cloth that starts
//! inside obstacles (`separate`) and of cloth that has crossed itself (`untangle`), checkpoints and the run that writes frames (`run`).

mod adapt;
pub mod checkpoint;
pub mod checks;
pub mod constrain;
mod handles;
pub mod interrupt;
pub mod output;
mod pinch;
mod plastic;
pub mod pop;
pub mod progress;
pub mod recover;
mod run;
mod separate;
pub mod state;
mod step;
pub mod timers;
mod untangle;
pub mod workspace;

pub use run::{
    check_output, claim_output, clear_output, resume, run, run_shot, run_with_checkpoints, CheckpointOptions, Jitter,
    ResumeOptions, RunError, RunOptions,
};
pub use state::SimState;
pub use workspace::Workspace;

use crate::collision::crossings::{find_crossings, Crossings, Soup};
use crate::collision::params::InitialIntersections;
use crate::collision::world::CollisionWorld;
use crate::error::InputError;
use crate::io::stats::FrameStats;
use crate::math::Real;
use crate::mesh::Mesh;
use crate::metrics::principal_strain;
use crate::scene::{RemeshMode, Scene};
use crate::solver::SolveError;
use checks::Elastic;
use run::{file_safe, io_err};

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("step {step} (t = {time:.6} s): {source}")]
    Solve { step: u64, time: Real, source: SolveError },
    /// A step that failed its fault checks at every step size down to `h` (`recover`).
    #[error("step {step} (t = {time:.6} s): {fault}, still at h = {h:.3e} s after {halvings} halvings of the step")]
    StepFailed { step: u64, time: Real, h: Real, halvings: u32, fault: String },
    #[error("invalid mesh: {0}")]
    Mesh(String),
    /// The initial state is not usable (e.g. cloth deep inside an obstacle).
    #[error("{0}")]
    Input(InputError),
}

/// A running shot: the scene as loaded (never changed by the run), the state a checkpoint
/// holds, and the workspace derived from both.
pub struct Simulation {
    pub scene: Scene,
    pub state: SimState,
    pub ws: Workspace,
}

impl Simulation {
    /// A fresh start: the input mesh refined once where a cloth asks for it (uniform mode: to
    /// its minimum edge; adaptive modes remesh at each frame start), and cloth registered
    /// slightly inside an obstacle pushed out. Cloth deeper inside is left to the separation
    /// stage (`separate.rs`), or refused (`collision.initial_intersections`).
    pub fn new(scene: Scene) -> Result<Self, SimError> {
        scene.require_camera_for_view().map_err(SimError::Input)?;
        let state = SimState::initial(&scene);
        let mut sim = Simulation::build(scene, state)?;
        sim.remesh(RemeshMode::Uniform)?;
        let tolerance = sim.scene.collision.push_out_tolerance;
        let (pushed, deep) = sim.push_out(tolerance)?;
        sim.state.pushed_out = pushed;
        sim.state.separating = deep > 0;
        if sim.scene.initial_relax {
            sim.relax_initial_state()?;
        }
        Ok(sim)
    }

    /// ARCSim's `relax_initial_state`: equilibrate, remesh adaptively (its initialising remesh),
    /// equilibrate again (`pop::equilibrate`), and then cloths that rest in their input's shape
    /// rest in the relaxed one (`retake_rest_shape`). The remesh's counts join frame 1's.
    fn relax_initial_state(&mut self) -> Result<(), SimError> {
        let Some(first) = self.equilibrate()? else { return Ok(()) };
        let adaptive = self.scene.cloths.iter().any(|c| c.remesh.as_ref().is_some_and(|r| r.mode.is_adaptive()));
        let mut iterations = first.iterations;
        if adaptive {
            self.remesh_counted()?;
            iterations += self.equilibrate()?.map_or(0, |s| s.iterations);
        }
        self.ws.pop.iterations += iterations;
        self.retake_rest_shape()
    }

    /// After the initial relaxation, the rest embedding and the rest dihedral angles of cloths
    /// that rest in their input's shape (`rest_angles: "input"`) become the relaxed shape's, and
    /// their plastic shape follows with no damage: ARCSim's `reset_plasticity` after `relax_initial_state` under
    /// `preserve_creases`, the one case in which its rest angles are not flat. A folded model
    /// (dart.json's paper plane) is then at rest in the shape the relaxation gave it, its folds
    /// sharp on the remeshed creases.
    fn retake_rest_shape(&mut self) -> Result<(), SimError> {
        if self.scene.cloths.iter().all(|c| c.flat_rest) {
            return Ok(());
        }
        let state = &mut self.state;
        if self.scene.rest_embedded() {
            state.rest_x = state.mesh.positions();
        }
        state.rest_angles = self.scene.rest_angles(&state.mesh);
        if let Some(plastic) = &mut state.plastic {
            plastic.shapes = crate::remesh::rest_shape::face_shapes(&state.mesh, &state.rest_angles);
            plastic.damage = vec![0.0; state.mesh.faces.len()];
        }
        self.ws.remeshed(&self.state, &self.scene.materials)
    }

    /// An adaptive remesh whose operation counts join the next frame's statistics.
    pub(super) fn remesh_counted(&mut self) -> Result<(), SimError> {
        let s = self.remesh(RemeshMode::Adaptive)?;
        self.ws.remesh_stats.splits += s.splits;
        self.ws.remesh_stats.flips += s.flips;
        self.ws.remesh_stats.collapses += s.collapses;
        Ok(())
    }

    /// A simulation of `scene` (as loaded from its file) at a checkpointed state.
    pub fn restore(scene: Scene, state: SimState) -> Result<Self, SimError> {
        let state = state.fit(&scene)?;
        Simulation::build(scene, state)
    }

    /// The one place a simulation is assembled, for a fresh start and a resume alike.
    fn build(scene: Scene, state: SimState) -> Result<Self, SimError> {
        let ws = Workspace::build(&scene, &state)?;
        Ok(Simulation { scene, state, ws })
    }

    pub fn mesh(&self) -> &Mesh {
        &self.state.mesh
    }

    pub fn time(&self) -> Real {
        self.state.time
    }

    /// The collision world, when the scene has obstacles or self-collision.
    pub fn collisions(&self) -> Option<&CollisionWorld> {
        self.ws.collisions.as_ref()
    }

    /// The elastic model of the current mesh.
    fn elastic(&self) -> Elastic<'_> {
        Elastic { mesh: &self.state.mesh, rest: &self.ws.rest, materials: &self.scene.materials }
    }

    /// Nodes inside an obstacle are moved out along its surface normal to the repulsion
    /// thickness: at load for garments registered slightly inside a body, and after a remesh
    /// (`tolerance` infinite). Nodes deeper than `tolerance`, and nodes inside two obstacles
    /// (pushed out of one they would land in the other), stay where they are for the separation
    /// stage, or (deeper than `tolerance`) are an error when the scene refuses initial
    /// intersections. Returns how many nodes moved and how many were left inside.
    fn push_out(&mut self, tolerance: Real) -> Result<(usize, usize), SimError> {
        let Some(world) = &self.ws.collisions else { return Ok((0, 0)) };
        let th = world.params.thickness;
        let refuse = world.params.initial_intersections == InitialIntersections::Refuse;
        let t = self.state.time;
        let x = self.state.mesh.positions();
        let hits: Vec<(usize, Vec<_>)> = (0..world.bodies.len())
            .filter(|&b| world.present(b, t))
            .map(|b| (b, world.with_sdf(b, t, |sdf| sdf.query_inside(&x))))
            .collect();
        let mut bodies_inside = vec![0usize; x.len()];
        for (_, h) in &hits {
            for (i, q) in h.iter().enumerate() {
                bodies_inside[i] += q.is_some() as usize;
            }
        }
        let (mut pushed, mut left) = (0, 0);
        for (b, h) in hits {
            let mut too_deep = vec![0usize; self.scene.cloths.len()];
            let mut moves = Vec::new();
            for (i, (node, q)) in self.state.mesh.nodes.iter().zip(h).enumerate() {
                let Some(q) = q else { continue };
                if -q.distance > tolerance {
                    too_deep[node.cloth as usize] += 1;
                } else if bodies_inside[i] > 1 && !refuse {
                    left += 1;
                } else {
                    moves.push((i, q.point + q.normal * th));
                }
            }
            if let Some(c) = too_deep.iter().position(|&k| k > 0).filter(|_| refuse) {
                return Err(SimError::Input(InputError {
                    file: self.scene.file.clone(),
                    location: Some(format!("cloths[{c}]")),
                    msg: format!(
                        "cloth '{}' has {} nodes inside obstacle '{}' deeper than the push-out tolerance {} m (collision.push_out_tolerance; collision.initial_intersections is \"refuse\")",
                        self.scene.cloths[c].name, too_deep[c], self.scene.obstacles[b].name, tolerance
                    ),
                }));
            }
            left += too_deep.iter().sum::<usize>();
            pushed += moves.len();
            for (i, p) in moves {
                self.state.mesh.nodes[i].x = p;
            }
        }
        Ok((pushed, left))
    }

    /// Elastic energy (membrane + bending) of the current state.
    pub fn elastic_energy(&self) -> Real {
        self.elastic().energy_serial(&self.state.mesh.positions())
    }

    /// Cloth nodes deeper than half the thickness inside an obstacle (should be 0).
    pub fn penetrations(&self) -> usize {
        let Some(world) = &self.ws.collisions else { return 0 };
        let x = self.state.mesh.positions();
        (0..world.bodies.len())
            .filter(|&b| world.present(b, self.state.time))
            .map(|b| world.with_sdf(b, self.state.time, |sdf| sdf.count_deeper_than(&x, 0.5 * world.params.thickness)))
            .sum()
    }

    /// The triangle pairs that cross now (`collision::crossings`): cloth with cloth, and cloth
    /// with the obstacles posed at the current time.
    pub fn crossings(&self) -> Crossings {
        let m = &self.state.mesh;
        let x = m.positions();
        let tris: Vec<[usize; 3]> = (0..m.faces.len()).map(|f| m.face_nodes(f)).collect();
        let (mut obs_x, mut obs_tris) = (Vec::new(), Vec::new());
        for body in self.ws.collisions.iter().flat_map(|w| &w.bodies).filter(|b| b.present_at(self.state.time)) {
            let base = obs_x.len();
            obs_x.extend(body.positions_at(self.state.time));
            obs_tris.extend(body.triangles().iter().map(|t| t.map(|i| i + base)));
        }
        find_crossings(Soup { x: &x, tris: &tris }, Soup { x: &obs_x, tris: &obs_tris })
    }

    /// Per-frame measurements (without timings).
    pub fn measure(&self, frame: usize) -> FrameStats {
        let m = &self.state.mesh;
        let kinetic: Real = m.nodes.iter().map(|n| 0.5 * n.mass * n.v.norm_squared()).sum();
        let potential: Real = m.nodes.iter().map(|n| -n.mass * self.scene.gravity.dot(&n.x)).sum();
        let faces = (0..m.faces.len()).map(|f| (m.face_nodes(f).map(|n| m.nodes[n].x), self.ws.rest.membrane[f]));
        let strain = principal_strain(faces);
        FrameStats {
            frame,
            time: self.state.time,
            nodes: m.nodes.len(),
            faces: m.faces.len(),
            kinetic_energy: Some(kinetic),
            total_energy: Some(kinetic + potential + self.elastic_energy()),
            max_strain: strain.max,
            mean_strain: strain.mean,
            ..Default::default()
        }
    }
}
