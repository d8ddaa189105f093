//! The workspace of a run: everything derived from the scene and the state (rest data, the
//! implicit system and its sparsity pattern, the collision world and its caches, node areas),
//! and the per-frame tallies (stage timers, collision counters, remeshing and retries). It is
//! rebuilt from (scene, state) by one function, for a fresh start and for a resume alike.

use crate::collision::obstacle::ObstacleBody;
use crate::collision::proximity::Contact;
use crate::collision::world::{CollisionCounters, CollisionWorld};
use crate::forces::material::Material;
use crate::forces::RestState;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;
use crate::remesh::RemeshStats;
use crate::scene::Scene;
use crate::sizing::remesh_jump::Jump;
use crate::sizing::view::ObstacleDepths;
use crate::sizing::FaceView;
use crate::solver::pattern::BlockPattern;
use crate::solver::ImplicitSystem;

use super::constrain::Constraints;
use super::pinch::BandCache;
use super::pop::PopStats;
use super::recover::FaultStats;
use super::state::SimState;
use super::timers::StageTimers;
use super::SimError;

pub struct Workspace {
    /// Per face and hinge: rest data of the state's mesh and rest angles.
    pub rest: RestState,
    pub system: ImplicitSystem,
    /// The pattern of a remeshed cloth, analysed only at the next step (`pattern_for_step`):
    /// that step's self contacts usually extend it, and each analysis is a fill-reducing
    /// ordering and a symbolic factorisation.
    pub pending_pattern: Option<BlockPattern>,
    /// Present when the scene has obstacles or self-collision.
    pub collisions: Option<CollisionWorld>,
    /// Per node: a third of the adjacent faces' material area (m²), scaling contact stiffness.
    pub node_area: Vec<Real>,
    /// Per face: its material area (m²), for ARCSim's contact stiffness (`collision::areas`).
    pub face_area: Vec<Real>,
    /// Per-frame tallies, taken by the run for stats.json.
    pub timers: StageTimers,
    pub counters: CollisionCounters,
    pub remesh_stats: RemeshStats,
    /// The pop filter's work this frame (`pop.rs`).
    pub pop: PopStats,
    pub faults: FaultStats,
    /// Present when a cloth has long range attachments or strain limits.
    pub constraints: Option<Constraints>,
    /// Cloth nodes pinched between two obstacles (or inside both) at the current step, each
    /// with the pinch's velocity, which holds them (`separate.rs`); empty unless the separation
    /// stage runs.
    pub trapped: Vec<(usize, Vec3)>,
    /// The obstacle faces that may pinch cloth this frame (`pinch::BandCache`).
    pub(super) pinch_faces: Option<BandCache>,
    /// The last view factors computed (`adapt::face_views`) and the fingerprint of the state
    /// they were computed for: the frame end's stats and the next frame's remesh see the same
    /// state, so the second reuses the first.
    pub views: Option<(u64, Vec<Option<FaceView>>)>,
    /// The obstacles' occlusion depth images of the last view factors, for the next
    /// (`sizing::view::ObstacleDepths`).
    pub(super) obstacle_depths: ObstacleDepths,
    /// The on-screen jump of the remeshes since the last frame's stats (`sizing::remesh_jump`;
    /// largest of each figure), in view mode.
    pub(super) remesh_jump: Option<Jump>,
    /// Whether the untangling stage looks for cloth crossing itself at the next step: set at
    /// every frame start, kept while it finds crossings it can take back (`untangle.rs`).
    pub untangle_due: bool,
}

impl Workspace {
    /// The workspace of `state` in `scene`.
    pub fn build(scene: &Scene, state: &SimState) -> Result<Workspace, SimError> {
        let rest = rest_state(state, &scene.materials)
            .map_err(|f| SimError::Mesh(format!("face {f} is degenerate in material space")))?;
        let system = ImplicitSystem::new(BlockPattern::new(&state.mesh, &rest.hinges, &state.extra_pairs))
            .map_err(|source| SimError::Solve { step: state.steps, time: state.time, source })?;
        let collisions = (!scene.obstacles.is_empty() || scene.collision.self_collision).then(|| {
            let bodies = scene.obstacles.iter().map(ObstacleBody::new).collect();
            CollisionWorld::new(scene.collision.clone(), bodies, state.time)
        });
        Ok(Workspace {
            node_area: node_areas(&state.mesh, &rest),
            face_area: rest.membrane.iter().map(|m| m.area).collect(),
            rest,
            system,
            pending_pattern: None,
            collisions,
            timers: StageTimers::default(),
            counters: CollisionCounters::default(),
            remesh_stats: RemeshStats::default(),
            pop: PopStats::default(),
            faults: FaultStats::default(),
            constraints: Constraints::build(scene, state),
            trapped: Vec::new(),
            pinch_faces: None,
            views: None,
            obstacle_depths: ObstacleDepths::default(),
            remesh_jump: None,
            untangle_due: true,
        })
    }

    /// After a remesh: rest data and node areas of the new mesh, its pattern left for the next
    /// step to analyse.
    pub fn remeshed(&mut self, state: &SimState, materials: &[Material]) -> Result<(), SimError> {
        self.rest =
            rest_state(state, materials).map_err(|f| SimError::Mesh(format!("remeshing left face {f} degenerate")))?;
        self.node_area = node_areas(&state.mesh, &self.rest);
        self.face_area = self.rest.membrane.iter().map(|m| m.area).collect();
        self.pending_pattern = Some(BlockPattern::new(&state.mesh, &self.rest.hinges, &state.extra_pairs));
        Ok(())
    }

    /// Analyses a remeshed cloth's pending pattern, and the pattern extended by this step's
    /// cloth–cloth contact couplings whenever a contact misses one (recorded in `extra_pairs`,
    /// kept until the next remesh). A contact whose coupling is missing could only enter the
    /// system as a diagonal majorizer (`assembly`), which resists the two sides' common motion
    /// and stops only 1/m of their relative motion (m its cloth nodes): on the uniform
    /// `sheet_on_sphere` reference, layers folding onto each other at 2.7 m/s were slowed to
    /// 1.6 m/s and ended through each other's thickness, 0.17 J of contact energy no work
    /// paid for, and 11 of 331 steps were retried; analysed at once, none (the analysis, a
    /// fill-reducing ordering and a symbolic factorisation, cost less than the retries).
    pub fn pattern_for_step(&mut self, state: &mut SimState, contacts: &[Contact]) -> Result<(), SimError> {
        let n = state.mesh.nodes.len();
        let pattern = self.pending_pattern.as_ref().unwrap_or(&self.system.pattern);
        let mut missing = Vec::new();
        for c in contacts {
            for a in 0..4 {
                for b in 0..a {
                    let (i, j) = (c.nodes[a], c.nodes[b]);
                    if i < n && j < n && i != j && pattern.block(i.max(j), i.min(j)).is_none() {
                        missing.push((i.max(j), i.min(j)));
                    }
                }
            }
        }
        if !missing.is_empty() {
            state.extra_pairs.extend(missing);
            state.extra_pairs.sort_unstable();
            state.extra_pairs.dedup();
            self.pending_pattern = Some(BlockPattern::new(&state.mesh, &self.rest.hinges, &state.extra_pairs));
        }
        if let Some(pattern) = self.pending_pattern.take() {
            self.analyse(pattern, state)?;
        }
        let mut tail: Vec<usize> = contacts.iter().flat_map(|c| c.nodes).filter(|&i| i < n).collect();
        tail.sort_unstable();
        tail.dedup();
        self.system.set_tail(&tail).map_err(|source| SimError::Solve { step: state.steps, time: state.time, source })
    }

    /// A new implicit system over `pattern`: fill-reducing ordering and symbolic factorisation.
    fn analyse(&mut self, pattern: BlockPattern, state: &SimState) -> Result<(), SimError> {
        self.system = ImplicitSystem::new(pattern).map_err(|source| SimError::Solve {
            step: state.steps,
            time: state.time,
            source,
        })?;
        Ok(())
    }
}

/// Rest data of the state's mesh, rest angles and plastic damage; the error is the first face
/// degenerate in material space.
fn rest_state(state: &SimState, materials: &[Material]) -> Result<RestState, usize> {
    let mut rest = RestState::new(&state.mesh, |e| state.rest_angles[e])?;
    if let Some(plastic) = &state.plastic {
        let weakening: Vec<Real> = materials.iter().map(Material::weakening).collect();
        if weakening.iter().any(|&w| w > 0.0) {
            rest.weaken(&state.mesh, &plastic.damage, &weakening);
        }
    }
    if !state.buckle.is_empty() {
        rest.set_slack(&state.mesh, &state.buckle, materials);
    }
    Ok(rest)
}

/// A third of the adjacent faces' material area per node (m²).
fn node_areas(mesh: &Mesh, rest: &RestState) -> Vec<Real> {
    let mut area = vec![0.0; mesh.nodes.len()];
    for f in 0..mesh.faces.len() {
        for n in mesh.face_nodes(f) {
            area[n] += rest.membrane[f].area / 3.0;
        }
    }
    area
}
