//! `stats.json`: what ran, how long each stage took, and the state of each frame.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize, Debug, Clone, Default)]
pub struct FrameStats {
    pub frame: usize,
    pub time: f64,
    pub wall_s: f64,
    pub stage_s: BTreeMap<String, f64>,
    pub nodes: usize,
    pub faces: usize,
    /// Kinetic energy (J). Absent for a run derived from another's frames (`compare`'s
    /// `upsampled` and `loop`): it has no velocities, and no material to weigh them with.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinetic_energy: Option<f64>,
    /// Total energy: kinetic + elastic + gravitational potential (J); absent as `kinetic_energy`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub total_energy: Option<f64>,
    /// Largest principal stretch − 1 over the faces, and its material-area-weighted mean
    /// (`metrics::strain`; a derived run's from its frames and their material coordinates).
    pub max_strain: f64,
    pub mean_strain: f64,
    /// Steps taken (more than the scene's steps per frame when steps were retried).
    pub steps: usize,
    /// Attempted steps rolled back and retried at half the size (`sim::recover`).
    #[serde(default)]
    pub retries: usize,
    /// Smallest step taken in the frame (s); 0 for frame 0.
    #[serde(default)]
    pub min_step: f64,
    /// Cloth triangle pairs (sharing no node) that cross at the frame end: one cloth through
    /// itself or through another (`collision::crossings`; must be 0).
    #[serde(default)]
    pub crossings_self: usize,
    /// Cloth–obstacle triangle pairs that cross at the frame end, against the obstacles as posed
    /// (and exported) at the frame's time (must be 0).
    #[serde(default)]
    pub crossings_obstacle: usize,
    /// Retries by fault kind (absent when none).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub faults: BTreeMap<String, usize>,
    /// Present when the collision stages ran.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub collision: Option<CollisionFrameStats>,
    /// Present when a cloth remeshes adaptively.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub remesh: Option<RemeshFrameStats>,
    /// Present when a cloth has long range attachments.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub lra: Option<LraFrameStats>,
    /// Present when a cloth has strain limits.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub strain_limit: Option<StrainLimitFrameStats>,
    /// Present in view mode (a cloth remeshes with view factors and the shot has a camera).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub view: Option<ViewFrameStats>,
}

/// The camera's view of the view-dependent cloths' faces at the frame end, seen from the
/// camera at the frame's time (`sizing::view::view_summary`).
#[derive(Serialize, Deserialize, Debug, Clone, Default, PartialEq)]
pub struct ViewFrameStats {
    /// Mean of the view factor μ′₃ the sizing uses (Koh et al. 2014, eq. 9: the lookahead
    /// window's weighted maximum), weighted by world-space face area.
    pub view_mean_mu: f64,
    /// Faces whose centroid is inside the view frustum (signed distance to its planes ≤ 0).
    pub view_faces_in_frame: usize,
    /// The other view-dependent faces: centroid outside the frustum.
    pub view_faces_out_of_frame: usize,
    /// Faces in frame that are mostly hidden from the camera behind obstacles or cloth: less
    /// than half of their sample points seen (`sizing::occlusion`); 0 when occlusion is off.
    #[serde(default)]
    pub view_faces_occluded: usize,
    /// How far the frame's remesh moved the visible cloth on screen (`sizing::remesh_jump`): the
    /// largest jump of a material point seen before it, and the 99th percentile, in pixels of
    /// an image `image_height` high; 0 when nothing was remeshed.
    #[serde(default)]
    pub view_remesh_jump_px: f64,
    #[serde(default)]
    pub view_remesh_jump_p99_px: f64,
}

/// Long range attachments at the frame end (`constraints::lra`).
#[derive(Serialize, Deserialize, Debug, Clone, Default, PartialEq)]
pub struct LraFrameStats {
    /// Node–attachment constraints in force (to active handles).
    pub lra_constraints: usize,
    /// Constraints taut at the frame end (node on its sphere).
    pub lra_taut: usize,
    /// Violated constraints projected, summed over the frame's steps.
    pub lra_projected: usize,
    /// Largest stretch along an attachment path at the frame end: |x − x_attachment| / rest − 1.
    pub lra_max_stretch: f64,
}

/// Strain limiting (`constraints::strain_limit`).
#[derive(Serialize, Deserialize, Debug, Clone, Default, PartialEq)]
pub struct StrainLimitFrameStats {
    /// Faces with a principal stretch at a limit (within 1e-3, the solver tolerance) or beyond it at the frame end.
    pub strain_limit_faces: usize,
    /// Most Gauss–Newton iterations (factorisations) of a step's projection in the frame.
    pub strain_limit_iterations: usize,
    /// Steps whose projection stopped short of the tolerance (iteration cap) or was undone.
    pub strain_limit_unconverged: usize,
    /// Largest principal stretch outside the limits right after a projection (before collisions).
    pub strain_limit_excess: f64,
}

/// Remeshing work done at the start of a frame.
#[derive(Serialize, Deserialize, Debug, Clone, Default, PartialEq)]
pub struct RemeshFrameStats {
    pub splits: usize,
    pub flips: usize,
    pub collapses: usize,
    /// Newton steps of the pop filter after the remesh (`sim::pop`; 0 when it did not run).
    #[serde(default)]
    pub pop_iterations: usize,
    /// The largest distance the pop filter moved a node (m).
    #[serde(default)]
    pub pop_max_move: f64,
}

/// Collision counters of one frame (summed over its steps).
#[derive(Serialize, Deserialize, Debug, Clone, Default, PartialEq)]
pub struct CollisionFrameStats {
    /// Repulsion contacts in the implicit solves.
    pub contacts: usize,
    /// Impacts found by continuous collision detection.
    pub impacts: usize,
    pub impact_zones: usize,
    pub ccd_iterations: usize,
    /// Steps whose impact-zone loop hit `collision.max_iterations` with collisions left.
    pub ccd_cap_hits: usize,
    /// Nodes that kept their solved motion at a step of the smallest size because the collision
    /// projection flung them past the speed cap (the run would have stopped).
    #[serde(default)]
    pub flung_reverted: usize,
    /// Steps whose collision pushes stored more elastic energy than the end-of-step check
    /// allows, spread through the step's implicit system and collided again instead of retried.
    #[serde(default)]
    pub spread_pushes: usize,
    /// Zones whose projection had no solution (rigid zones that had none included).
    pub failed_zones: usize,
    /// Impact zones made rigid at a step of the smallest size because their projection had no
    /// solution or flung a node past the speed cap (a rigid zone that takes in more nodes
    /// counts again).
    #[serde(default)]
    pub rigid_zones: usize,
    /// Nodes trapped in a pinch that an impact zone with no solution while they were held
    /// moved like free cloth (a node counts once per zone that moved it).
    #[serde(default)]
    pub yielded_nodes: usize,
    /// The most cloth nodes held in a pinch between two obstacles at one step of the frame (the
    /// separation stage's hold: they cross the obstacles there, as in ARCSim).
    #[serde(default)]
    pub pinched_nodes: usize,
    /// Cloth nodes the untangling stage moved back through cloth they had crossed, summed over
    /// the frame's steps (`sim::untangle`).
    #[serde(default)]
    pub untangled_nodes: usize,
    /// Cloth nodes deeper than thickness/2 inside an obstacle at the frame end (must be 0).
    pub penetrations: usize,
    /// Friction contacts sticking and sliding at the accepted solves (summed over the steps).
    #[serde(default)]
    pub sticking: usize,
    #[serde(default)]
    pub sliding: usize,
    /// Solves and factorisations beyond one per step that friction's mode changes took.
    #[serde(default)]
    pub friction_resolves: usize,
    #[serde(default)]
    pub friction_refactors: usize,
    /// Of `friction_refactors`, those that refactorised the contact nodes' block alone.
    #[serde(default)]
    pub tail_refactors: usize,
    /// Steps ending with friction contacts not in the mode Coulomb's law gives them (mode changes
    /// beyond the refactorisation limit wait for the next step; sliding forces beyond the solve
    /// limit keep their last value).
    #[serde(default)]
    pub friction_unconverged: usize,
}

#[derive(Serialize, Deserialize, Debug, Clone, Default)]
pub struct RunStats {
    pub scene: String,
    pub mode: String,
    pub stages: Vec<String>,
    pub total_wall_s: f64,
    /// Retried steps over the run, and the smallest step taken (s).
    #[serde(default)]
    pub retries: usize,
    #[serde(default)]
    pub min_step: f64,
    /// The seed and amplitude (m) of the jitter of the initial cloth positions
    /// (`simulate --jitter-seed`, `compare`'s chaos-floor runs); absent for an unjittered run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jitter_seed: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jitter_m: Option<f64>,
    /// Frames from which the run was resumed (`viewcloth resume`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub resumed_at: Vec<usize>,
    /// Why the run stopped early, when it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub frames: Vec<FrameStats>,
}
