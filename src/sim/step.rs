//! One time step as a list of named, timed stages (DESIGN.md "Pipeline of one time step"):
//! handles → proximity → assembly/factorisation/solve → integration → friction → collision.
//! A stage the scene does not need does not run. An attempt whose result fails a fault check
//! (`recover`) is not committed; `Simulation::step` (in `recover`) retries it in halves.

use crate::collision::friction::{apply_friction, FrictionContact, FrictionState};
use crate::collision::proximity::Contact;
use crate::math::{Real, Vec3};
use crate::scene::RemeshMode;
use crate::solver::pattern::BlockPattern;
use crate::solver::{ImplicitSystem, SolveError, StepInput};

use super::recover::{EnergyCheck, Fault, StepFault};
use super::{SimError, Simulation};

impl Simulation {
    /// Target velocity of every node held by an active handle at the end of a step to `t1`.
    fn pinned_velocities(&self, t1: Real, h: Real) -> Vec<Option<Vec3>> {
        let mut pinned = vec![None; self.mesh.nodes.len()];
        for handle in self.scene.handles.iter().filter(|hd| hd.active(self.time)) {
            for (k, &n) in handle.nodes.iter().enumerate() {
                pinned[n] = Some((handle.target(k, t1) - self.mesh.nodes[n].x) / h);
            }
        }
        pinned
    }

    /// Analyses a remeshed cloth's pending pattern, extended by this step's missing cloth–cloth
    /// contact couplings. Otherwise the pattern stays fixed within the frame: a missing
    /// coupling is only recorded in `extra_pairs` (assembly majorizes that contact on the
    /// diagonal) and enters at the next frame start (`add_recorded_pairs`), because in a scene
    /// with self contact new pairs appear at most steps and each analysis is a fill-reducing
    /// ordering and a symbolic factorisation.
    fn ensure_pattern(&mut self, contacts: &[Contact]) -> Result<(), SimError> {
        let n = self.mesh.nodes.len();
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
            self.extra_pairs.extend(missing);
            self.extra_pairs.sort_unstable();
            self.extra_pairs.dedup();
            if self.pending_pattern.is_some() {
                self.pending_pattern = Some(BlockPattern::new(&self.mesh, &self.rest.hinges, &self.extra_pairs));
            }
        }
        match self.pending_pattern.take() {
            Some(pattern) => self.analyse(pattern),
            None => Ok(()),
        }
    }

    /// A new implicit system over `pattern`: fill-reducing ordering and symbolic factorisation.
    fn analyse(&mut self, pattern: BlockPattern) -> Result<(), SimError> {
        self.system = ImplicitSystem::new(pattern).map_err(|source| SimError::Solve {
            step: self.steps,
            time: self.time,
            source,
        })?;
        Ok(())
    }

    /// At a frame start without a remesh: analyses the pattern with the contact couplings
    /// recorded during the previous frame. Done here rather than at the next step so that the
    /// system at a frame boundary is the one a checkpoint rebuilds from `extra_pairs`.
    fn add_recorded_pairs(&mut self) -> Result<(), SimError> {
        let pattern = &self.system.pattern;
        if self.pending_pattern.is_some() || self.extra_pairs.iter().all(|&(i, j)| pattern.block(i, j).is_some()) {
            return Ok(());
        }
        let clock = std::time::Instant::now();
        self.analyse(BlockPattern::new(&self.mesh, &self.rest.hinges, &self.extra_pairs))?;
        self.timers.add("factorisation", clock.elapsed().as_secs_f64());
        Ok(())
    }

    /// One attempt at an implicit step of size `h` from `self.time` to `t1`. The state is
    /// committed only when every fault check passes; otherwise it is left as it was (caches
    /// such as the contact pattern may have grown). With `accept_unresolved`, collisions left
    /// at the impact-zone iteration cap do not fail the attempt (the last, smallest retry).
    pub(super) fn attempt_step(&mut self, h: Real, t1: Real, accept_unresolved: bool) -> Result<(), StepFault> {
        let t0 = self.time;
        let clock = std::time::Instant::now();
        let pinned = self.pinned_velocities(t1, h);
        self.timers.add("handles", clock.elapsed().as_secs_f64());

        let clock = std::time::Instant::now();
        let contacts = match &mut self.collisions {
            Some(world) => {
                world.advance(t0, t1);
                world.proximity(&self.mesh, &self.node_area)
            }
            None => Vec::new(),
        };
        if self.collisions.is_some() {
            self.counters.contacts += contacts.len();
            self.timers.add("proximity", clock.elapsed().as_secs_f64());
        }
        let clock = std::time::Instant::now();
        self.ensure_pattern(&contacts)?;
        self.timers.add("factorisation", clock.elapsed().as_secs_f64());

        let fixed: &[Vec3] = self.collisions.as_ref().map(|w| w.obs_x1.as_slice()).unwrap_or(&[]);
        let input = StepInput {
            mesh: &self.mesh,
            rest: &self.rest,
            materials: &self.scene.materials,
            h,
            gravity: self.scene.gravity,
            wind: self.scene.wind.as_ref(),
            pinned: &pinned,
            contacts: &contacts,
            fixed,
        };
        let out = self.system.solve_step(&input).map_err(|source| match source {
            SolveError::NotPositiveDefinite(_) => StepFault::Retry(Fault::Factorisation(source)),
            _ => StepFault::Fatal(SimError::Solve { step: self.steps, time: self.time, source }),
        })?;
        self.timers.add("assembly", out.assemble_s);
        self.timers.add("factorisation", out.factor_s);
        self.timers.add("solve", out.solve_s);

        let clock = std::time::Instant::now();
        let x_start = self.mesh.positions();
        let mut v: Vec<Vec3> = self.mesh.nodes.iter().zip(&out.dv).map(|(n, dv)| n.v + dv).collect();
        for (vi, p) in v.iter_mut().zip(&pinned) {
            if let Some(p) = p {
                *vi = *p;
            }
        }
        let inv_mass: Vec<Real> = self
            .mesh
            .nodes
            .iter()
            .zip(&pinned)
            .map(|(n, p)| if p.is_some() || n.mass <= 0.0 { 0.0 } else { 1.0 / n.mass })
            .collect();
        self.timers.add("integration", clock.elapsed().as_secs_f64());

        let clock = std::time::Instant::now();
        let v_solved = v.clone();
        let check =
            EnergyCheck { h, x0: &x_start, v: &v, pinned: &pinned, contacts: &contacts, u0: out.elastic_energy };
        let solved = self.check_energy(&check)?;
        self.timers.add("fault_checks", clock.elapsed().as_secs_f64());

        if !contacts.is_empty() {
            let clock = std::time::Instant::now();
            self.friction(&contacts, &x_start, &mut v, &inv_mass, h);
            self.timers.add("friction", clock.elapsed().as_secs_f64());
        }

        let clock = std::time::Instant::now();
        let mut x: Vec<Vec3> = x_start.iter().zip(&v).map(|(x, v)| x + h * v).collect();
        // Handles land exactly on their targets (no rounding drift).
        for handle in self.scene.handles.iter().filter(|hd| hd.active(t0)) {
            for (k, &n) in handle.nodes.iter().enumerate() {
                x[n] = handle.target(k, t1);
            }
        }
        self.timers.add("integration", clock.elapsed().as_secs_f64());

        let cap_hits = self.counters.cap_hits;
        if let Some(world) = &mut self.collisions {
            let clock = std::time::Instant::now();
            let before = x.clone();
            world.resolve(&self.mesh, &x_start, &mut x, &inv_mass, &mut self.counters);
            for i in 0..x.len() {
                if x[i] != before[i] {
                    v[i] = (x[i] - x_start[i]) / h;
                }
            }
            self.timers.add("collision", clock.elapsed().as_secs_f64());
        }

        let clock = std::time::Instant::now();
        if self.counters.cap_hits > cap_hits && !accept_unresolved {
            return Err(StepFault::Retry(Fault::Collisions));
        }
        self.check_end(h, &x_start, &x, &v, &v_solved, &solved)?;
        self.timers.add("fault_checks", clock.elapsed().as_secs_f64());
        for (node, (x, v)) in self.mesh.nodes.iter_mut().zip(x.into_iter().zip(v)) {
            node.x = x;
            node.v = v;
        }
        self.time = t1;
        self.steps += 1;
        Ok(())
    }

    /// Coulomb friction on the contacts of this step, evaluated at the tentative end positions.
    fn friction(&self, contacts: &[Contact], x_start: &[Vec3], v: &mut [Vec3], inv_mass: &[Real], h: Real) {
        let Some(world) = &self.collisions else { return };
        let n = self.mesh.nodes.len();
        let x_end: Vec<Vec3> = x_start.iter().zip(v.iter()).map(|(x, v)| x + h * v).collect();
        let fixed_v = world.obstacle_velocities(h);
        let fc: Vec<FrictionContact> = contacts
            .iter()
            .map(|c| {
                let against_obstacle = c.nodes.iter().any(|&i| i >= n);
                let mu = if against_obstacle { world.params.friction } else { world.params.self_friction };
                FrictionContact { nodes: c.nodes, w: c.w, n: c.n, thickness: c.thickness, stiffness: c.stiffness, mu }
            })
            .collect();
        let mut state = FrictionState { x: &x_end, v, inv_mass, fixed_x: &world.obs_x1, fixed_v: &fixed_v };
        apply_friction(&mut state, &fc, h);
    }

    /// Advances one frame (the scene's steps per frame), remeshing adaptive cloths first when due.
    pub fn advance_frame(&mut self) -> Result<(), SimError> {
        let every = self
            .scene
            .cloths
            .iter()
            .filter_map(|c| c.remesh.as_ref().filter(|r| r.mode.is_adaptive()).map(|r| r.every))
            .min();
        if every.is_some_and(|e| self.frame % e == 0) {
            let s = self.remesh(RemeshMode::Adaptive)?;
            self.remesh_stats.splits += s.splits;
            self.remesh_stats.flips += s.flips;
            self.remesh_stats.collapses += s.collapses;
        }
        self.add_recorded_pairs()?;
        self.frame += 1;
        let h = self.scene.time_step();
        for _ in 0..self.scene.steps_per_frame {
            self.step(h)?;
        }
        Ok(())
    }
}
