//! The constraint stages of a step, between the implicit solve and collision handling: long
//! range attachments (stage `lra`; Kim et al. 2012, Algorithm 1) then strain limiting (stage
//! `strain_limit`). Each runs only when a cloth of the scene asks for it (`lra`,
//! `strain_limits`). Nodes they move get the velocity of their new motion, x₁ = x₀ + h v, as in
//! position based dynamics (the paper's §3.3), so collision handling sees a consistent state.
//!
//! The constraints are a function of the scene and the state: rebuilt after a remesh and when a
//! handle switches on or off, never checkpointed.

use crate::constraints::lra::{islands, Attachment, Lra, LraParams};
use crate::constraints::strain_limit::{faces_at_limit, StrainLimiter, TOLERANCE};
use crate::io::stats::{FrameStats, LraFrameStats, StrainLimitFrameStats};
use crate::math::{Real, Vec3};
use crate::scene::{HandleKind, Scene};

use super::state::SimState;
use super::timers::Stage;
use super::Simulation;

/// Long range attachments of the scene's cloths and what they did in the current frame.
pub struct LraStage {
    /// Per cloth.
    params: Vec<Option<LraParams>>,
    /// Per handle, per node of it: its island (Algorithm 2), from the scene's input mesh.
    islands: Vec<Vec<usize>>,
    /// Which handles were active when `lra` was built.
    active: Vec<bool>,
    pub lra: Lra,
    /// Constraint corrections (violated constraints projected) over the frame's steps.
    projected: usize,
}

/// Strain limits per material and what they did in the current frame.
pub struct StrainLimitStage {
    /// Per material (one per cloth).
    pub limits: Vec<Option<[Real; 2]>>,
    /// The projection's system, kept until a remesh changes the faces.
    limiter: Option<StrainLimiter>,
    iterations: usize,
    unconverged: usize,
    excess: Real,
}

/// The constraint stages a scene asks for (`Workspace::constraints`).
pub struct Constraints {
    pub lra: Option<LraStage>,
    pub strain: Option<StrainLimitStage>,
}

impl Constraints {
    /// `None` when no cloth has `lra` or `strain_limits`.
    pub fn build(scene: &Scene, state: &SimState) -> Option<Constraints> {
        let lra = scene.cloths.iter().any(|c| c.lra.is_some()).then(|| {
            let all: Vec<usize> = scene.handles.iter().flat_map(|h| h.nodes.iter().copied()).collect();
            let flat = islands(&scene.mesh, &all);
            let mut k = 0;
            let islands = scene
                .handles
                .iter()
                .map(|h| {
                    let v = flat[k..k + h.nodes.len()].to_vec();
                    k += h.nodes.len();
                    v
                })
                .collect();
            let mut stage = LraStage {
                params: scene.cloths.iter().map(|c| c.lra).collect(),
                islands,
                active: Vec::new(),
                lra: Lra::default(),
                projected: 0,
            };
            stage.rebuild(scene, state);
            stage
        });
        let strain = scene.cloths.iter().any(|c| c.strain_limits.is_some()).then(|| {
            let mut limits = vec![None; scene.materials.len()];
            for c in &scene.cloths {
                limits[c.material] = c.strain_limits;
            }
            StrainLimitStage { limits, limiter: None, iterations: 0, unconverged: 0, excess: 0.0 }
        });
        (lra.is_some() || strain.is_some()).then_some(Constraints { lra, strain })
    }
}

impl LraStage {
    /// The handles that attach at `time`: active ones that hold nodes on targets (a glue pair
    /// holds no node in place).
    fn active_handles(scene: &Scene, time: Real) -> Vec<bool> {
        scene.handles.iter().map(|h| h.active(time) && h.kind != HandleKind::Glue).collect()
    }

    /// The constraints of the state's mesh to the nodes of the handles active now.
    pub fn rebuild(&mut self, scene: &Scene, state: &SimState) {
        self.active = Self::active_handles(scene, state.time);
        let mut seen = vec![false; state.mesh.nodes.len()];
        let mut attachments = Vec::new();
        for (h, nodes) in state.handle_nodes.iter().enumerate() {
            if !self.active[h] {
                continue;
            }
            for (k, &node) in nodes.iter().enumerate() {
                // A circle's ring grows by splits of its own edges: its new nodes join its island.
                let island = self.islands[h].get(k).or(self.islands[h].first()).copied().unwrap_or(0);
                if !std::mem::replace(&mut seen[node], true) {
                    attachments.push(Attachment { node, island });
                }
            }
        }
        self.lra = Lra::build(&state.mesh, &attachments, &self.params);
    }
}

impl Simulation {
    /// After a remesh: the constraints of the new mesh (split nodes get rest lengths from their
    /// material position; collapsed ones are gone).
    pub(super) fn constraints_remeshed(&mut self) {
        if let Some(stage) = self.ws.constraints.as_mut().and_then(|c| c.lra.as_mut()) {
            stage.rebuild(&self.scene, &self.state);
        }
    }

    /// The constraint stages on a step's end positions `x` (from `x0` over `h`), before
    /// collision handling; nodes moved get v = (x − x₀)/h. `inv_mass` is 0 for nodes held by handles.
    pub(super) fn constrain(&mut self, x0: &[Vec3], inv_mass: &[Real], h: Real, x: &mut [Vec3], v: &mut [Vec3]) {
        let Some(mut c) = self.ws.constraints.take() else { return };
        let mut moved = vec![false; x.len()];
        if let Some(stage) = &mut c.lra {
            self.timed(Stage::Lra, |s| {
                if LraStage::active_handles(&s.scene, s.state.time) != stage.active {
                    stage.rebuild(&s.scene, &s.state);
                }
                stage.projected += stage.lra.project(x, inv_mass, &mut moved).violated;
            });
        }
        if let Some(stage) = &mut c.strain {
            self.timed(Stage::StrainLimit, |s| {
                let r = StrainLimiter::limit(
                    &mut stage.limiter,
                    &s.state.mesh,
                    &s.ws.rest.membrane,
                    &stage.limits,
                    x0,
                    x,
                    inv_mass,
                    &mut moved,
                );
                stage.iterations = stage.iterations.max(r.iterations);
                stage.unconverged += usize::from(!r.converged);
                stage.excess = stage.excess.max(r.excess);
            });
        }
        for i in 0..x.len() {
            if moved[i] {
                v[i] = (x[i] - x0[i]) / h;
            }
        }
        self.ws.constraints = Some(c);
    }

    /// The frame's constraint measurements into `fs`, resetting the frame's tallies.
    pub fn constraint_stats(&mut self, fs: &mut FrameStats) {
        let x = self.state.mesh.positions();
        let Some(c) = &mut self.ws.constraints else { return };
        if let Some(stage) = &mut c.lra {
            let (max_stretch, taut) = stage.lra.measure(&x);
            fs.lra = Some(LraFrameStats {
                lra_constraints: stage.lra.constraints.len(),
                lra_taut: taut,
                lra_projected: std::mem::take(&mut stage.projected),
                lra_max_stretch: max_stretch,
            });
        }
        if let Some(stage) = &mut c.strain {
            let at_limit = faces_at_limit(&self.state.mesh, &self.ws.rest.membrane, &stage.limits, &x, TOLERANCE);
            fs.strain_limit = Some(StrainLimitFrameStats {
                strain_limit_faces: at_limit,
                strain_limit_iterations: std::mem::take(&mut stage.iterations),
                strain_limit_unconverged: std::mem::take(&mut stage.unconverged),
                strain_limit_excess: std::mem::take(&mut stage.excess),
            });
        }
    }
}
