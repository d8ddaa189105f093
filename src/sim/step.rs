//! One time step as a list of named, timed stages (DESIGN.md "Pipeline of one time step", after
//! ARCSim's `advance_step`): handles → proximity → assembly / factorisation / solve →
//! integration → friction → collision, with the fault checks of `checks.rs` after the solve and
//! at the end. A stage the scene does not need does not run. An attempt whose result fails a
//! check is not committed; `Simulation::step` (`recover.rs`) retries it in halves.

use std::time::Instant;

use crate::collision::friction::{apply_friction, FrictionContact, FrictionState};
use crate::collision::proximity::Contact;
use crate::math::{Real, Vec3};
use crate::scene::RemeshMode;
use crate::solver::{SolveError, StepInput, StepOutput};

use super::checks::{self, Elastic, StepContext};
use super::recover::{Fault, StepFault};
use super::timers::Stage;
use super::{SimError, Simulation};

/// What an attempt has fixed before its checks: the step, its start and its contacts.
struct StepData {
    h: Real,
    t1: Real,
    /// Start positions.
    x0: Vec<Vec3>,
    /// Per node: the handle's prescribed velocity over the step.
    pinned: Vec<Option<Vec3>>,
    contacts: Vec<Contact>,
    /// 0 for pinned nodes and massless ones (they do not move in projections).
    inv_mass: Vec<Real>,
    /// Elastic energy at the start (from the assembly).
    u0: Real,
    /// The fastest obstacle vertex's speed over the step.
    obstacle_speed: Real,
}

impl Simulation {
    /// Advances one frame (the scene's steps per frame), remeshing adaptive cloths first when due.
    pub fn advance_frame(&mut self) -> Result<(), SimError> {
        self.begin_frame()?;
        let h = self.scene.time_step();
        for _ in 0..self.scene.steps_per_frame {
            self.step(h)?;
        }
        Ok(())
    }

    /// The frame-start work of `advance_frame` (remeshing when due, the sparsity pattern), after
    /// which the caller takes the frame's steps itself (`upsample trace` interleaves two runs).
    pub fn begin_frame(&mut self) -> Result<(), SimError> {
        let every = self
            .scene
            .cloths
            .iter()
            .filter_map(|c| c.remesh.as_ref().filter(|r| r.mode.is_adaptive()).map(|r| r.every))
            .min();
        if every.is_some_and(|e| self.state.frame % e == 0) {
            let s = self.remesh(RemeshMode::Adaptive)?;
            self.ws.remesh_stats.splits += s.splits;
            self.ws.remesh_stats.flips += s.flips;
            self.ws.remesh_stats.collapses += s.collapses;
        }
        let clock = Instant::now();
        if self.ws.pattern_at_frame_start(&self.state)? {
            self.ws.timers.since(Stage::Factorisation, clock);
        }
        self.state.frame += 1;
        Ok(())
    }

    /// Runs `f` as `stage`, adding its wall time to the stage's timer.
    pub(super) fn timed<T>(&mut self, stage: Stage, f: impl FnOnce(&mut Self) -> T) -> T {
        let clock = Instant::now();
        let r = f(self);
        self.ws.timers.since(stage, clock);
        r
    }

    /// One attempt at an implicit step of size `h` from the current time to `t1`. The state is
    /// committed only when every fault check passes; otherwise it is left as it was (caches
    /// such as the contact pattern may have grown). With `accept_unresolved`, collisions left
    /// at the impact-zone iteration cap do not fail the attempt (the last, smallest retry).
    pub(super) fn attempt(&mut self, h: Real, t1: Real, accept_unresolved: bool) -> Result<(), StepFault> {
        let pinned = self.timed(Stage::Handles, |s| s.pinned_velocities(t1, h));
        let contacts = match self.ws.collisions.is_some() {
            true => self.timed(Stage::Proximity, |s| s.proximity(t1)),
            false => Vec::new(),
        };
        self.timed(Stage::Factorisation, |s| s.ws.pattern_for_step(&mut s.state, &contacts))?;
        let out = self.implicit_solve(h, &pinned, &contacts)?;
        let (step, v) = self.timed(Stage::Integration, |s| s.step_data(h, t1, pinned, contacts, &out));
        let solved = self.timed(Stage::FaultChecks, |s| checks::after_solve(&s.context(&step), v))?;
        let mut v = solved.v.clone();
        if !step.contacts.is_empty() {
            self.timed(Stage::Friction, |s| s.friction(&step, &mut v));
        }
        let mut x = self.timed(Stage::Integration, |s| s.end_positions(&step, &v));
        self.constrain(&step.x0, &step.inv_mass, step.h, &mut x, &mut v);
        if self.ws.collisions.is_some() {
            let capped = self.timed(Stage::Collision, |s| s.resolve_collisions(&step, &mut x, &mut v));
            if capped && !accept_unresolved {
                return Err(StepFault::Retry(Fault::Collisions));
            }
        }
        self.timed(Stage::FaultChecks, |s| checks::end_of_step(&s.context(&step), &solved, &x, &v))?;
        self.commit(x, v, t1);
        Ok(())
    }

    /// Target velocity of every node held by an active handle at the end of a step to `t1`.
    fn pinned_velocities(&self, t1: Real, h: Real) -> Vec<Option<Vec3>> {
        let mut pinned = vec![None; self.state.mesh.nodes.len()];
        for (handle, nodes) in self.scene.handles.iter().zip(&self.state.handle_nodes) {
            if handle.active(self.state.time) {
                for (k, &n) in nodes.iter().enumerate() {
                    pinned[n] = Some((handle.target(k, t1) - self.state.mesh.nodes[n].x) / h);
                }
            }
        }
        pinned
    }

    /// Moves the obstacles to the step and finds the repulsion contacts.
    fn proximity(&mut self, t1: Real) -> Vec<Contact> {
        let Some(world) = &mut self.ws.collisions else { return Vec::new() };
        world.advance(self.state.time, t1);
        let contacts = world.proximity(&self.state.mesh, &self.ws.node_area);
        self.ws.counters.contacts += contacts.len();
        contacts
    }

    /// Assembles, factorises and solves the linearised backward-Euler system (each part timed
    /// by the solver). A matrix that is not positive definite is a fault to retry.
    fn implicit_solve(
        &mut self,
        h: Real,
        pinned: &[Option<Vec3>],
        contacts: &[Contact],
    ) -> Result<StepOutput, StepFault> {
        let fixed: &[Vec3] = self.ws.collisions.as_ref().map(|w| w.obs_x1.as_slice()).unwrap_or(&[]);
        let input = StepInput {
            mesh: &self.state.mesh,
            rest: &self.ws.rest,
            materials: &self.scene.materials,
            h,
            gravity: self.scene.gravity,
            wind: self.scene.wind.as_ref(),
            pinned,
            contacts,
            fixed,
        };
        let out = self.ws.system.solve_step(&input).map_err(|source| match source {
            SolveError::NotPositiveDefinite(_) => StepFault::Retry(Fault::Factorisation(source)),
            _ => StepFault::Fatal(SimError::Solve { step: self.state.steps, time: self.state.time, source }),
        })?;
        self.ws.timers.add(Stage::Assembly, out.assemble_s);
        self.ws.timers.add(Stage::Factorisation, out.factor_s);
        self.ws.timers.add(Stage::Solve, out.solve_s);
        Ok(out)
    }

    /// The solved end-of-step velocities (handles: their prescribed ones) and what the later
    /// stages need of the step.
    fn step_data(
        &self,
        h: Real,
        t1: Real,
        pinned: Vec<Option<Vec3>>,
        contacts: Vec<Contact>,
        out: &StepOutput,
    ) -> (StepData, Vec<Vec3>) {
        let nodes = &self.state.mesh.nodes;
        let v: Vec<Vec3> = nodes.iter().zip(&out.dv).zip(&pinned).map(|((n, dv), p)| p.unwrap_or(n.v + dv)).collect();
        let inv_mass = nodes
            .iter()
            .zip(&pinned)
            .map(|(n, p)| if p.is_some() || n.mass <= 0.0 { 0.0 } else { 1.0 / n.mass })
            .collect();
        let obstacle_speed = match &self.ws.collisions {
            Some(w) => w.obstacle_velocities(h).iter().map(|v| v.norm()).fold(0.0, Real::max),
            None => 0.0,
        };
        let x0 = self.state.mesh.positions();
        let u0 = out.elastic_energy;
        (StepData { h, t1, x0, pinned, contacts, inv_mass, u0, obstacle_speed }, v)
    }

    /// What the fault checks judge the step by.
    fn context<'a>(&'a self, step: &'a StepData) -> StepContext<'a> {
        let world = self.ws.collisions.as_ref();
        StepContext {
            elastic: Elastic { mesh: &self.state.mesh, rest: &self.ws.rest, materials: &self.scene.materials },
            gravity: self.scene.gravity,
            wind: self.scene.wind.as_ref(),
            h: step.h,
            x0: &step.x0,
            pinned: &step.pinned,
            contacts: &step.contacts,
            fixed: world.map(|w| w.obs_x1.as_slice()).unwrap_or(&[]),
            thickness: world.map_or(0.0, |w| w.params.thickness),
            obstacle_speed: step.obstacle_speed,
            u0: step.u0,
        }
    }

    /// Coulomb friction on the step's contacts, evaluated at the tentative end positions
    /// (Bridson et al. 2002, §7.2: a velocity filter after the solve).
    fn friction(&self, step: &StepData, v: &mut [Vec3]) {
        let Some(world) = &self.ws.collisions else { return };
        let (n, h) = (self.state.mesh.nodes.len(), step.h);
        let x_end: Vec<Vec3> = step.x0.iter().zip(v.iter()).map(|(x, v)| x + h * v).collect();
        let fixed_v = world.obstacle_velocities(h);
        let fc: Vec<FrictionContact> = step
            .contacts
            .iter()
            .map(|c| {
                let against_obstacle = c.nodes.iter().any(|&i| i >= n);
                let mu = if against_obstacle { world.params.friction } else { world.params.self_friction };
                FrictionContact { nodes: c.nodes, w: c.w, n: c.n, thickness: c.thickness, stiffness: c.stiffness, mu }
            })
            .collect();
        let mut state =
            FrictionState { x: &x_end, v, inv_mass: &step.inv_mass, fixed_x: &world.obs_x1, fixed_v: &fixed_v };
        apply_friction(&mut state, &fc, h);
    }

    /// x₁ = x₀ + h v, with handle nodes exactly on their targets (no rounding drift).
    fn end_positions(&self, step: &StepData, v: &[Vec3]) -> Vec<Vec3> {
        let mut x: Vec<Vec3> = step.x0.iter().zip(v).map(|(x, v)| x + step.h * v).collect();
        for (handle, nodes) in self.scene.handles.iter().zip(&self.state.handle_nodes) {
            if handle.active(self.state.time) {
                for (k, &n) in nodes.iter().enumerate() {
                    x[n] = handle.target(k, step.t1);
                }
            }
        }
        x
    }

    /// Makes the end positions collision-free (CCD and impact zones); nodes the projection moved
    /// get the velocity of their new motion. Returns whether the iteration cap was hit with
    /// collisions left.
    fn resolve_collisions(&mut self, step: &StepData, x: &mut [Vec3], v: &mut [Vec3]) -> bool {
        let Some(world) = &mut self.ws.collisions else { return false };
        let cap_hits = self.ws.counters.cap_hits;
        let before = x.to_vec();
        world.resolve(&self.state.mesh, &step.x0, x, &step.inv_mass, &mut self.ws.counters);
        for i in 0..x.len() {
            if x[i] != before[i] {
                v[i] = (x[i] - step.x0[i]) / step.h;
            }
        }
        self.ws.counters.cap_hits > cap_hits
    }

    /// Takes the checked end-of-step state.
    fn commit(&mut self, x: Vec<Vec3>, v: Vec<Vec3>, t1: Real) {
        for (node, (x, v)) in self.state.mesh.nodes.iter_mut().zip(x.into_iter().zip(v)) {
            node.x = x;
            node.v = v;
        }
        self.state.time = t1;
        self.state.steps += 1;
    }
}
