//! The simulation: state, the time step as a list of named, timed stages (`step`), and frame
//! measurements.

mod adapt;
pub mod checkpoint;
pub mod recover;
mod run;
mod step;
pub mod timers;

pub use run::{resume, run, run_with_checkpoints, CheckpointOptions, ResumeOptions, RunError, RunOptions};

use crate::collision::obstacle::ObstacleBody;
use crate::collision::world::{CollisionCounters, CollisionWorld};
use crate::forces::membrane::{deformation_gradient, max_principal_strain};
use crate::forces::RestState;
use crate::io::stats::FrameStats;
use crate::math::Real;
use crate::mesh::Mesh;
use crate::scene::{InputError, RemeshMode, Scene};
use crate::solver::pattern::BlockPattern;
use crate::solver::{ImplicitSystem, SolveError};
use timers::StageTimers;

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

pub struct Simulation {
    pub scene: Scene,
    pub mesh: Mesh,
    /// Rest dihedral angle of each edge (from the input shape).
    rest_angles: Vec<Real>,
    rest: RestState,
    system: ImplicitSystem,
    /// The pattern of a remeshed cloth, analysed only at the next step (`ensure_pattern`): that
    /// step's self contacts usually extend it, and each analysis is a fill-reducing ordering and
    /// a symbolic factorisation.
    pending_pattern: Option<BlockPattern>,
    /// Cloth–cloth node pairs added to the base pattern for self contacts; those recorded
    /// within a frame enter the pattern at the next frame start (`add_recorded_pairs`).
    extra_pairs: Vec<(usize, usize)>,
    /// Present when the scene has obstacles or self-collision.
    pub collisions: Option<CollisionWorld>,
    /// Per node: a third of the adjacent faces' material area (m²), scaling contact stiffness.
    node_area: Vec<Real>,
    pub counters: CollisionCounters,
    pub time: Real,
    pub steps: u64,
    pub timers: StageTimers,
    /// Cloth nodes pushed out of obstacles at load.
    pub pushed_out: usize,
    /// Frames completed.
    pub frame: usize,
    /// Remeshing work since last taken (for stats).
    pub remesh_stats: crate::remesh::RemeshStats,
    /// Accepted steps and rolled-back attempts since last taken (for stats).
    pub faults: recover::FaultStats,
}

/// The collision stages' world, when the scene has obstacles or self-collision.
fn collision_world(scene: &Scene, t: Real) -> Option<CollisionWorld> {
    (!scene.obstacles.is_empty() || scene.collision.self_collision).then(|| {
        let bodies = scene.obstacles.iter().map(ObstacleBody::new).collect();
        CollisionWorld::new(scene.collision.clone(), bodies, t)
    })
}

impl Simulation {
    pub fn new(mut scene: Scene) -> Result<Self, SimError> {
        if let Some(c) = scene.view_cloth_without_camera() {
            return Err(SimError::Input(InputError {
                file: scene.file.clone(),
                location: Some(format!("cloths[{c}].remesh.mode")),
                msg: "\"view\" needs a camera: give the scene a \"camera\" file or pass --camera".into(),
            }));
        }
        let mesh = std::mem::take(&mut scene.mesh);
        let rest_angles = scene.rest_angles(&mesh);
        let rest = RestState::new(&mesh, |e| rest_angles[e])
            .map_err(|f| SimError::Mesh(format!("face {f} is degenerate in material space")))?;
        let system = ImplicitSystem::new(BlockPattern::new(&mesh, &rest.hinges, &[]))
            .map_err(|source| SimError::Solve { step: 0, time: 0.0, source })?;
        let node_area = adapt::node_areas(&mesh, &rest);
        let collisions = collision_world(&scene, 0.0);
        let mut sim = Simulation {
            scene,
            mesh,
            rest_angles,
            rest,
            system,
            pending_pattern: None,
            extra_pairs: Vec::new(),
            collisions,
            node_area,
            counters: CollisionCounters::default(),
            time: 0.0,
            steps: 0,
            timers: StageTimers::default(),
            pushed_out: 0,
            frame: 0,
            remesh_stats: Default::default(),
            faults: Default::default(),
        };
        sim.remesh(RemeshMode::Uniform)?;
        let tolerance = sim.scene.collision.push_out_tolerance;
        sim.pushed_out = sim.push_out(Some(tolerance))?;
        Ok(sim)
    }

    pub fn rest_angles(&self) -> &[Real] {
        &self.rest_angles
    }

    /// Nodes inside an obstacle are moved out along its surface normal to the repulsion
    /// thickness: at load for garments registered slightly inside a body (deeper than
    /// `tolerance` is an error), and after a remesh. Returns how many moved.
    fn push_out(&mut self, tolerance: Option<Real>) -> Result<usize, SimError> {
        let Some(world) = &self.collisions else { return Ok(0) };
        let th = world.params.thickness;
        let tol = tolerance.unwrap_or(Real::INFINITY);
        let mut pushed = 0;
        for b in 0..world.bodies.len() {
            let mut too_deep = vec![0usize; self.scene.cloths.len()];
            let mut moves = Vec::new();
            let inside = world.with_sdf(b, self.time, |sdf| sdf.query_inside(&self.mesh.positions()));
            for (i, (node, q)) in self.mesh.nodes.iter().zip(inside).enumerate() {
                let Some(q) = q else { continue };
                if -q.distance > tol {
                    too_deep[node.cloth as usize] += 1;
                } else {
                    moves.push((i, q.point + q.normal * th));
                }
            }
            if let Some(c) = too_deep.iter().position(|&k| k > 0) {
                return Err(SimError::Input(InputError {
                    file: self.scene.file.clone(),
                    location: Some(format!("cloths[{c}]")),
                    msg: format!(
                        "cloth '{}' has {} nodes inside obstacle '{}' deeper than the push-out tolerance {} m (collision.push_out_tolerance)",
                        self.scene.cloths[c].name, too_deep[c], self.scene.obstacles[b].name, tol
                    ),
                }));
            }
            pushed += moves.len();
            for (i, p) in moves {
                self.mesh.nodes[i].x = p;
            }
        }
        Ok(pushed)
    }

    /// Elastic energy (membrane + bending) of the current state.
    pub fn elastic_energy(&self) -> Real {
        use crate::forces::Projection;
        let m = &self.mesh;
        let mut e = 0.0;
        for f in 0..m.faces.len() {
            let x = m.face_nodes(f).map(|n| m.nodes[n].x);
            let mat = &self.scene.materials[m.faces[f].material as usize];
            e += mat.stretch(&x, &self.rest.membrane[f], Projection::Psd).0;
        }
        for hg in &self.rest.hinges {
            let x = hg.nodes.map(|n| m.nodes[n].x);
            e += self.scene.materials[hg.material].bend(&x, hg, Projection::Psd).0;
        }
        e
    }

    /// Cloth nodes deeper than half the thickness inside an obstacle (should be 0).
    pub fn penetrations(&self) -> usize {
        let Some(world) = &self.collisions else { return 0 };
        let x = self.mesh.positions();
        (0..world.bodies.len())
            .map(|b| world.with_sdf(b, self.time, |sdf| sdf.count_deeper_than(&x, 0.5 * world.params.thickness)))
            .sum()
    }

    /// Per-frame measurements (without timings).
    pub fn measure(&self, frame: usize) -> FrameStats {
        let m = &self.mesh;
        let kinetic: Real = m.nodes.iter().map(|n| 0.5 * n.mass * n.v.norm_squared()).sum();
        let potential: Real = m.nodes.iter().map(|n| -n.mass * self.scene.gravity.dot(&n.x)).sum();
        let (mut max_strain, mut sum, mut area) = (Real::NEG_INFINITY, 0.0, 0.0);
        for f in 0..m.faces.len() {
            let x = m.face_nodes(f).map(|n| m.nodes[n].x);
            let r = &self.rest.membrane[f];
            let s = max_principal_strain(&deformation_gradient(&x, r));
            max_strain = max_strain.max(s);
            sum += s * r.area;
            area += r.area;
        }
        FrameStats {
            frame,
            time: self.time,
            nodes: m.nodes.len(),
            faces: m.faces.len(),
            kinetic_energy: kinetic,
            total_energy: kinetic + potential + self.elastic_energy(),
            max_strain,
            mean_strain: sum / area,
            ..Default::default()
        }
    }
}
