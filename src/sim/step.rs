//! One time step as a list of named, timed stages (DESIGN.md "Pipeline of one time step", after
//! ARCSim's `advance_step`): handles → proximity → assembly / factorisation / solve →
//! integration → collision → plasticity (`plastic.rs`, when a material yields), with Coulomb
//! friction inside the solve (`collision::friction`) and the fault checks of `checks.rs` after
//! the solve and at the end. A stage the scene does not need does not run, nor one it switches
//! off (`disable`: proximity, physics, collision). An attempt whose result fails a check is not
//! committed; `Simulation::step` (`recover.rs`) retries it in halves.

use std::time::Instant;

use crate::collision::friction::{self, Budget, Change, Friction, FrictionContact, FrictionFrame};
use crate::collision::proximity::Contact;
use crate::collision::speculative::Speculative;
use crate::collision::world::InvMasses;
use crate::forces::handle::Spring;
use crate::math::{Real, Vec3};
use crate::solver::{SolveError, SolveTiming, StepInput};

use super::checks::{self, Elastic, StepContext};
use super::handles::Held;
use super::recover::{Fault, StepFault};
use super::timers::Stage;
use super::{SimError, Simulation};

/// The implicit solve's result: end-of-step velocities (before handles are set exactly), the
/// elastic energy at the start and the work friction may do (`Friction::drag_work`).
struct Implicit {
    v: Vec<Vec3>,
    u0: Real,
    friction_work: Real,
    /// The contacts sticking at the solve (`SimState::stuck` once the step is taken).
    stuck: Vec<[usize; 4]>,
}

/// The step's repulsion contacts as friction contacts, with the cloth–obstacle or cloth–cloth
/// coefficient.
fn friction_contacts<'a>(
    contacts: &'a [Contact],
    n: usize,
    world: &'a crate::collision::world::CollisionWorld,
) -> impl Iterator<Item = FrictionContact> + 'a {
    contacts.iter().map(move |c| {
        let against_obstacle = c.nodes.iter().any(|&i| i >= n);
        let mu = if against_obstacle { world.params.friction } else { world.params.self_friction };
        FrictionContact::new(c.nodes, c.w, c.n, c.thickness, c.stiffness, mu).with_law(c.law)
    })
}

/// Per node 1/m, or 0 for a node whose motion is prescribed (`pinned`) or that has no mass:
/// neither moves in the solve's friction terms nor in a projection.
pub(super) fn inverse_masses(nodes: &[crate::mesh::Node], pinned: &[Option<Vec3>]) -> Vec<Real> {
    nodes.iter().zip(pinned).map(|(n, p)| if p.is_some() || n.mass <= 0.0 { 0.0 } else { 1.0 / n.mass }).collect()
}

/// What an attempt has fixed before its checks: the step, its start and its contacts.
struct StepData {
    h: Real,
    /// Start positions.
    x0: Vec<Vec3>,
    /// Per node: the handle's prescribed velocity over the step.
    pinned: Vec<Option<Vec3>>,
    /// The exact handles' targets (node, position at the step's end).
    exact: Vec<(usize, Vec3)>,
    /// The soft handles' springs.
    springs: Vec<Spring>,
    contacts: Vec<Contact>,
    /// 0 for pinned nodes and massless ones (they do not move in projections).
    inv_mass: Vec<Real>,
    /// `inv_mass`, with 0 also for the nodes soft handles pull to a target: the constraint
    /// stages keep them where the solve put them (ARCSim's strain limiting keeps every handle
    /// constraint's value, `strainlimiting.cpp`); collisions move them like free nodes.
    held_inv_mass: Vec<Real>,
    /// `inv_mass`, with the nodes trapped in a pinch (`separate.rs`) movable: what they take
    /// when an impact zone has no solution while they are held (`CollisionWorld::resolve`).
    /// None when nothing is trapped (then `inv_mass`).
    yield_inv_mass: Option<Vec<Real>>,
    /// Elastic energy at the start (from the assembly).
    u0: Real,
    /// The work friction may do on the cloth over the step (a moving obstacle's drag).
    friction_work: Real,
    /// The contacts that stuck.
    stuck: Vec<[usize; 4]>,
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
        if every.is_some_and(|e| self.state.frame.is_multiple_of(e)) {
            self.remesh_counted()?;
        }
        self.ws.untangle_due = true;
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
        let held = self.timed(Stage::Handles, |s| {
            s.switch_on_handles();
            s.held(t1)
        })?;
        let pinned = self.pinned_velocities(&held.exact, h);
        let contacts = match self.ws.collisions.is_some() {
            true if !self.scene.disabled.proximity => self.timed(Stage::Proximity, |s| s.proximity(t1)),
            true => {
                let t0 = self.state.time;
                self.ws.collisions.iter_mut().for_each(|w| w.advance(t0, t1));
                Vec::new()
            }
            false => Vec::new(),
        };
        self.timed(Stage::Factorisation, |s| s.ws.pattern_for_step(&mut s.state, &contacts))?;
        let out = match self.scene.disabled.physics {
            false => self.implicit_solve(h, &pinned, &held.springs, &contacts)?,
            true => self.still(),
        };
        let (step, v) = self.timed(Stage::Integration, |s| s.step_data(h, pinned, held, contacts, &out));
        let solved = self.timed(Stage::FaultChecks, |s| checks::after_solve(&s.context(&step), v))?;
        let mut v = solved.v.clone();
        let mut x = self.timed(Stage::Integration, |s| s.end_positions(&step, &v));
        self.constrain(&step.x0, &step.held_inv_mass, step.h, &mut x, &mut v);
        if self.ws.collisions.is_some() && !self.scene.disabled.collision {
            let (pre_x, pre_v) = (x.clone(), v.clone());
            self.collide(&step, &solved, &mut x, &mut v, accept_unresolved)?;
            let checked = self.timed(Stage::FaultChecks, |s| checks::end_of_step(&s.context(&step), &solved, &x, &v));
            match checked {
                Err(Fault::EnergyGain { .. }) if !self.scene.disabled.physics => {
                    // The impact zones' pushes stored elastic energy: spread them through the
                    // step's system and collide again (`solver::spread`); the check judges that.
                    let spread = self.timed(Stage::Collision, |s| s.spread_pushes(&step, &pre_x, &pre_v, &x));
                    let Some((mut y, mut w)) = spread else { return Err(StepFault::Retry(checked.unwrap_err())) };
                    self.collide(&step, &solved, &mut y, &mut w, accept_unresolved)?;
                    self.timed(Stage::FaultChecks, |s| checks::end_of_step(&s.context(&step), &solved, &y, &w))?;
                    (x, v) = (y, w);
                    self.ws.counters.spread_pushes += 1;
                }
                other => other?,
            }
        } else {
            self.timed(Stage::FaultChecks, |s| checks::end_of_step(&s.context(&step), &solved, &x, &v))?;
        }
        // The solve's acceleration (before collisions and constraints), as ARCSim keeps it.
        let a = solved.v.iter().zip(&self.state.mesh.nodes).map(|(v, n)| (v - n.v) / step.h).collect();
        self.commit(x, v, a, t1, step.stuck);
        if self.state.plastic.is_some() {
            self.timed(Stage::Plasticity, Simulation::plastic_update);
        }
        if !self.state.buckle.is_empty() {
            self.timed(Stage::Buckling, |s| s.ws.rest.set_slack(&s.state.mesh, &s.state.buckle, &s.scene.materials));
        }
        Ok(())
    }

    /// The velocity over the step of length `h` that takes every node an exact handle holds
    /// onto its target; the pinch's for the nodes trapped between two obstacles (`separate.rs`).
    fn pinned_velocities(&self, exact: &[(usize, Vec3)], h: Real) -> Vec<Option<Vec3>> {
        let mut pinned = vec![None; self.state.mesh.nodes.len()];
        for &(n, v) in &self.ws.trapped {
            pinned[n] = Some(v);
        }
        for &(n, target) in exact {
            pinned[n] = Some((target - self.state.mesh.nodes[n].x) / h);
        }
        pinned
    }

    /// The physics stage switched off (`disable: ["physics"]`): no forces, no solve; the cloth
    /// stands still unless exact handles, constraints or collisions move it.
    fn still(&self) -> Implicit {
        let x0 = self.state.mesh.positions();
        let v = vec![Vec3::zeros(); x0.len()];
        Implicit { v, u0: self.elastic().energy_at(&x0), friction_work: 0.0, stuck: Vec::new() }
    }

    /// Moves the obstacles to the step and finds the repulsion contacts.
    fn proximity(&mut self, t1: Real) -> Vec<Contact> {
        let Some(world) = &mut self.ws.collisions else { return Vec::new() };
        world.advance(self.state.time, t1);
        let contacts = world.proximity(&self.state.mesh, &self.ws.node_area, &self.ws.face_area, t1 - self.state.time);
        self.ws.counters.contacts += contacts.len();
        contacts
    }

    /// Assembles the linearised backward-Euler system once, then solves it with the friction
    /// of the step's contacts until every contact sticks or slides as Coulomb's law says at the
    /// solved velocities (`collision::friction`; a change of modes refactorises, a change of
    /// sliding forces only re-solves). A matrix that is not positive definite is a fault to
    /// retry.
    fn implicit_solve(
        &mut self,
        h: Real,
        pinned: &[Option<Vec3>],
        springs: &[Spring],
        contacts: &[Contact],
    ) -> Result<Implicit, StepFault> {
        let nodes = &self.state.mesh.nodes;
        let x0 = self.state.mesh.positions();
        let v0: Vec<Vec3> = nodes.iter().map(|n| n.v).collect();
        let inv_mass = inverse_masses(nodes, pinned);
        let world = self.ws.collisions.as_ref();
        let fixed: &[Vec3] = world.map(|w| w.obs_x1.as_slice()).unwrap_or(&[]);
        let fixed_v = world.map(|w| w.obstacle_velocities(h)).unwrap_or_default();
        let frame = FrictionFrame { h, x0: &x0, v0: &v0, inv_mass: &inv_mass, fixed_x: fixed, fixed_v: &fixed_v };
        let clock = Instant::now();
        let mut friction = match world {
            Some(w) if !contacts.is_empty() => {
                Friction::new(friction_contacts(contacts, nodes.len(), w), &frame, &self.state.stuck)
            }
            _ => Friction { contacts: Vec::new(), pending: 0 },
        };
        let mut speculative = Speculative::new(contacts, &frame, self.state.separating);
        let mut friction_s = clock.elapsed().as_secs_f64();
        let input = StepInput {
            mesh: &self.state.mesh,
            rest: &self.ws.rest,
            materials: &self.scene.materials,
            h,
            gravity: self.scene.gravity,
            wind: self.scene.wind.as_ref(),
            pinned,
            springs,
            // The repulsion contacts enter through their active set (`collision::speculative`),
            // not the assembly: a contact the step carries out of the thickness must let go.
            contacts: &[],
            fixed,
        };
        let fatal = |source| match source {
            SolveError::NotPositiveDefinite(_) => StepFault::Retry(Fault::Factorisation(source)),
            _ => StepFault::Fatal(SimError::Solve { step: self.state.steps, time: self.state.time, source }),
        };
        let mut timing = SolveTiming::default();
        let clock = Instant::now();
        let u0 = self.ws.system.assemble(&input);
        timing.assemble_s += clock.elapsed().as_secs_f64();
        let (mut refactor, mut converged) = (true, true);
        let v = loop {
            let mut terms = friction.terms(&frame);
            terms.extend(speculative.terms(&frame));
            let again = !friction.is_empty() || !speculative.is_empty();
            let dv = self.ws.system.solve(&input, &terms, refactor, again, &mut timing).map_err(fatal)?;
            let v: Vec<Vec3> = v0.iter().zip(&dv).map(|(v, dv)| v + dv).collect();
            if friction.is_empty() && speculative.is_empty() {
                break v;
            }
            if timing.solves == friction::MAX_SOLVES {
                converged = false;
                break v;
            }
            let clock = Instant::now();
            let modes = match timing.factorisations {
                f if f <= friction::MAX_REFACTORS => Budget::All,
                f if f <= friction::MAX_REFACTORS + friction::MAX_RELEASES => Budget::Release,
                _ => Budget::None,
            };
            // Contacts that switch on or off change what the step is (a pull or an unseen
            // penetration), like an overloaded stick: worth a refactorisation in either budget.
            let contacts_change = speculative.update(&frame, &v, modes != Budget::None);
            let change = match friction.is_empty() {
                true => Change::None,
                false => friction.update(&frame, &v, timing.solves == 1, modes),
            };
            friction_s += clock.elapsed().as_secs_f64();
            match change.max(contacts_change) {
                Change::None => {
                    converged = friction.pending == 0 && speculative.pending == 0;
                    break v;
                }
                Change::Rhs => refactor = false,
                Change::Modes => refactor = true,
            }
        };
        let clock = Instant::now();
        let friction_work = friction.drag_work(&frame, &v);
        let (stick, slide) = friction.counts();
        friction_s += clock.elapsed().as_secs_f64();
        let c = &mut self.ws.counters;
        c.sticking += stick;
        c.sliding += slide;
        c.friction_resolves += timing.solves - 1;
        c.friction_refactors += timing.factorisations - 1;
        c.tail_refactors += timing.tail_factorisations;
        c.friction_unconverged += usize::from(!converged);
        let timers = &mut self.ws.timers;
        timers.add(Stage::Assembly, timing.assemble_s);
        timers.add(Stage::Factorisation, timing.factor_s);
        timers.add(Stage::Solve, timing.solve_s);
        if !friction.is_empty() {
            timers.add(Stage::Friction, friction_s);
        }
        Ok(Implicit { v, u0, friction_work, stuck: friction.stuck() })
    }

    /// The solved end-of-step velocities (handles: their prescribed ones) and what the later
    /// stages need of the step.
    fn step_data(
        &self,
        h: Real,
        pinned: Vec<Option<Vec3>>,
        held: Held,
        contacts: Vec<Contact>,
        out: &Implicit,
    ) -> (StepData, Vec<Vec3>) {
        let nodes = &self.state.mesh.nodes;
        let v: Vec<Vec3> = out.v.iter().zip(&pinned).map(|(v, p)| p.unwrap_or(*v)).collect();
        let inv_mass = inverse_masses(nodes, &pinned);
        let mut held_inv_mass = inv_mass.clone();
        for s in &held.springs {
            if let Spring::Anchor { node, .. } = s {
                held_inv_mass[*node] = 0.0;
            }
        }
        let yield_inv_mass = (!self.ws.trapped.is_empty()).then(|| {
            let mut m = inv_mass.clone();
            for &(n, _) in self.ws.trapped.iter().filter(|&&(n, _)| nodes[n].mass > 0.0) {
                m[n] = 1.0 / nodes[n].mass;
            }
            // Handles win over the pinch, as in `pinned_velocities`.
            for &(n, _) in &held.exact {
                m[n] = 0.0;
            }
            m
        });
        let obstacle_speed = match &self.ws.collisions {
            Some(w) => w.obstacle_velocities(h).iter().map(|v| v.norm()).fold(0.0, Real::max),
            None => 0.0,
        };
        let x0 = self.state.mesh.positions();
        let (u0, friction_work, stuck) = (out.u0, out.friction_work, out.stuck.clone());
        let Held { exact, springs } = held;
        let step = StepData {
            h,
            x0,
            pinned,
            exact,
            springs,
            contacts,
            inv_mass,
            held_inv_mass,
            yield_inv_mass,
            u0,
            friction_work,
            stuck,
            obstacle_speed,
        };
        (step, v)
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
            springs: &step.springs,
            contacts: &step.contacts,
            fixed: world.map(|w| w.obs_x1.as_slice()).unwrap_or(&[]),
            thickness: world.map_or(0.0, |w| w.params.thickness),
            obstacle_speed: step.obstacle_speed,
            u0: step.u0,
            friction_work: step.friction_work,
        }
    }

    /// x₁ = x₀ + h v, with exact handles' nodes exactly on their targets (no rounding drift).
    fn end_positions(&self, step: &StepData, v: &[Vec3]) -> Vec<Vec3> {
        let mut x: Vec<Vec3> = step.x0.iter().zip(v).map(|(x, v)| x + step.h * v).collect();
        for &(n, target) in &step.exact {
            x[n] = target;
        }
        x
    }

    /// The collision stage on the end-of-step state `x`, `v` (`resolve_collisions`), with the
    /// smallest step's reverts (checks.rs, "Collisions left").
    fn collide(
        &mut self,
        step: &StepData,
        solved: &checks::Solved,
        x: &mut [Vec3],
        v: &mut [Vec3],
        accept_unresolved: bool,
    ) -> Result<(), StepFault> {
        // The smallest step: zones without a projection, or whose projection would fling a
        // node past the speed cap, move rigidly instead (checks.rs, "Collisions left").
        let cap = accept_unresolved.then(|| checks::speed_cap(&self.context(step), solved));
        let rigid_beyond = cap.map(|cap| cap * step.h);
        let capped = self.timed(Stage::Collision, |s| s.resolve_collisions(step, x, v, rigid_beyond));
        if capped && !accept_unresolved {
            return Err(StepFault::Retry(Fault::Collisions));
        }
        if let Some(cap) = cap {
            // A node still flung past the cap keeps the solve's motion.
            let mut reverted = 0;
            for i in 0..x.len() {
                if v[i].norm() > cap {
                    (x[i], v[i]) = (solved.x[i], solved.v[i]);
                    reverted += 1;
                }
            }
            self.ws.counters.flung_reverted += reverted;
        }
        Ok(())
    }

    /// The pushes the collision stage made from `pre_x` to `x`, spread through the step's system
    /// (`solver::spread`): the positions and velocities (those of the nodes that moved taken
    /// from their motion over the step) before colliding again. None when there is nothing to
    /// spread or too much.
    fn spread_pushes(
        &mut self,
        step: &StepData,
        pre_x: &[Vec3],
        pre_v: &[Vec3],
        x: &[Vec3],
    ) -> Option<(Vec<Vec3>, Vec<Vec3>)> {
        let at: Vec<usize> = (0..x.len()).filter(|&i| x[i] != pre_x[i] && step.inv_mass[i] > 0.0).collect();
        let d: Vec<Vec3> = at.iter().map(|&i| x[i] - pre_x[i]).collect();
        let delta = self.ws.system.spread(&at, &d)?;
        let (mut y, mut w) = (pre_x.to_vec(), pre_v.to_vec());
        for i in 0..y.len() {
            if step.inv_mass[i] > 0.0 && delta[i] != Vec3::zeros() {
                y[i] += delta[i];
                w[i] = (y[i] - step.x0[i]) / step.h;
            }
        }
        Some((y, w))
    }

    /// Makes the end positions collision-free (CCD and impact zones); nodes the projection moved
    /// get the velocity of their new motion. Returns whether the iteration cap was hit with
    /// collisions left.
    fn resolve_collisions(
        &mut self,
        step: &StepData,
        x: &mut [Vec3],
        v: &mut [Vec3],
        rigid_beyond: Option<Real>,
    ) -> bool {
        let Some(world) = &mut self.ws.collisions else { return false };
        let cap_hits = self.ws.counters.cap_hits;
        let before = x.to_vec();
        world.resolve(
            &self.state.mesh,
            &step.x0,
            x,
            InvMasses { held: &step.inv_mass, yielding: step.yield_inv_mass.as_deref().unwrap_or(&step.inv_mass) },
            rigid_beyond,
            &mut self.ws.counters,
        );
        for i in 0..x.len() {
            if x[i] != before[i] {
                v[i] = (x[i] - step.x0[i]) / step.h;
            }
        }
        self.ws.counters.cap_hits > cap_hits
    }

    /// Takes the checked end-of-step state.
    fn commit(&mut self, x: Vec<Vec3>, v: Vec<Vec3>, a: Vec<Vec3>, t1: Real, stuck: Vec<[usize; 4]>) {
        self.state.stuck = stuck;
        for (node, ((x, v), a)) in self.state.mesh.nodes.iter_mut().zip(x.into_iter().zip(v).zip(a)) {
            node.x = x;
            node.v = v;
            node.a = a;
        }
        self.state.time = t1;
        self.state.steps += 1;
    }
}
