//! The pop filter (Narain, Pfaff & O'Brien 2013, "Folding and crumpling adaptive sheets",
//! post-remeshing projection; ARCSim 0.2.1's `apply_pop_filter`). A remesh puts new nodes at
//! edge midpoints, where the forces of the new, finer elements are not the ones the old
//! elements balanced: the next step turns the difference into a pop of kinetic energy, and the
//! jitter it leaves is curvature and compression the sizing field refines again. After each
//! adaptive remesh the positions move to
//!
//!   x = argmin  E(x) + Σᵢ (mᵢ a₀ᵢ − f_ext,ᵢ) · (xᵢ − x₀ᵢ) + μ/2 Σᵢ |xᵢ − x₀ᵢ|²,
//!
//! E the potential of the elastic, repulsion and soft-handle forces F = −∇E (contacts found at
//! the current time, frozen), a₀ each node's acceleration over the last step (a split node's
//! interpolated, `Node::a`), f_ext gravity and wind at x₀, and μ = `RUBBER_BAND` a spring to x₀
//! per node. At the minimum F(x) + f_ext = m a₀ + μ (x − x₀): each node gets the acceleration it
//! had, within what the rubber band allows; where the old mesh's forces were what moved it, the
//! gradient vanishes at x₀ and nothing moves. Velocities are kept.
//!
//! Newton's method with a backtracking line search on the objective, at most `ITERATIONS`
//! Newton steps (ARCSim's `line_search_newtons_method` with `max_iter(10)`), each an assembly
//! (`Scheme::Static`), a Cholesky factorisation and a solve on the step's sparsity pattern.
//!
//! Where viewcloth differs from ARCSim, and why:
//! - f_ext is in the objective. ARCSim's leaves gravity out, so every remesh lifts a hanging
//!   sheet by m g / μ (a few µm); with it, a sheet in equilibrium does not move at all.
//! - Exact handles hold their nodes (ARCSim's handles are springs; viewcloth's soft handles are,
//!   and are in E).
//! - The filter's motion is swept by the collision stage (CCD and impact zones, obstacles
//!   still), so it creates no crossing; ARCSim moves the nodes without a check.
//! - It does not run before the first step (no acceleration is known; ARCSim skips its
//!   initialising remeshes), nor with the physics stage switched off, nor while the separation
//!   stage (`separate.rs`) is moving cloth out of obstacles: those nodes take no obstacle
//!   repulsion, and the filter's would push them out at once.

use std::time::Instant;

use crate::collision::proximity::{contacts_energy, Contact};
use crate::collision::world::InvMasses;
use crate::forces::wind::wind_face;
use crate::math::{Real, Vec3};
use crate::solver::{SolveTiming, StepInput};

use super::checks::Elastic;
use super::step::inverse_masses;
use super::timers::Stage;
use super::{SimError, Simulation};

/// μ, the rubber band to the pre-filter positions (N/m per node; ARCSim's default
/// regularisation, `popfilter.hpp`).
pub const RUBBER_BAND: Real = 1e3;
/// μ of the initial equilibration (`Simulation::equilibrate`; ARCSim's `equilibration_step`
/// passes a regularisation of 1).
pub const EQUILIBRATION_BAND: Real = 1.0;
/// Newton steps at most (ARCSim's).
pub const ITERATIONS: usize = 10;
/// Newton stops once no node moves farther than this in a step (m; ARCSim's `eps_x`, there on
/// the 2-norm of the whole step) …
const TOLERANCE: Real = 1e-6;
/// … or the objective falls by less than this (J; ARCSim's `eps_f`).
const DECREASE: Real = 1e-12;
/// Halvings of a Newton step before the line search gives up.
const HALVINGS: usize = 10;

/// What the pop filter did at one remesh.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PopStats {
    /// Newton steps taken.
    pub iterations: usize,
    /// Cholesky factorisations among them.
    pub factorisations: usize,
    /// The largest distance a node moved (m), before the collision sweep.
    pub max_move: Real,
}

/// The linear term of the objective.
#[derive(Clone, Copy)]
enum Load {
    /// f_ext − m a₀ (the pop filter).
    External,
    /// None (the initial equilibration: ARCSim zeroes the accelerations and leaves gravity out).
    None,
}

/// The objective's fixed parts.
struct Objective<'a> {
    elastic: Elastic<'a>,
    contacts: &'a [Contact],
    fixed: &'a [Vec3],
    springs: &'a [crate::forces::handle::Spring],
    x0: &'a [Vec3],
    /// f_ext − m a₀ per node (zero for held nodes).
    load: &'a [Vec3],
    /// μ, the rubber band to x₀ (N/m per node).
    mu: Real,
}

impl Objective<'_> {
    fn value(&self, x: &[Vec3]) -> Real {
        let potential = self.elastic.energy_at(x)
            + contacts_energy(self.contacts, x, self.fixed)
            + self.springs.iter().map(|s| s.energy(x)).sum::<Real>();
        let mut linear = 0.0;
        for ((x, x0), load) in x.iter().zip(self.x0).zip(self.load) {
            let d = x - x0;
            linear += 0.5 * self.mu * d.norm_squared() - load.dot(&d);
        }
        potential + linear
    }
}

impl Simulation {
    /// The pop filter after an adaptive remesh (module doc). Returns what it did; `None` when it
    /// does not run.
    pub(super) fn pop_filter(&mut self) -> Result<Option<PopStats>, SimError> {
        let disabled = &self.scene.disabled;
        if disabled.pop_filter || disabled.physics || self.state.steps == 0 || self.state.separating {
            return Ok(None);
        }
        self.relax(RUBBER_BAND, Load::External).map(Some)
    }

    /// ARCSim's equilibration of the initial state (`relax_initial_state`, its
    /// `equilibration_step`): the pop filter's minimisation with every acceleration zero, no
    /// external load and a weak band, μ = `EQUILIBRATION_BAND`, so that a mesh given strained
    /// (garment panels stretched around a body towards their seams, a folded paper model whose
    /// folds are not isometric to its flat pattern) starts near its elastic equilibrium instead
    /// of snapping there, and buckling, in the first steps. Where viewcloth differs from ARCSim:
    /// handles hold their nodes and repulsion contacts are in the objective (ARCSim leaves both
    /// out and resolves collisions after); the motion is swept by the collision stage as the pop
    /// filter's is. Not while the separation stage is to walk cloth out of obstacles, nor with
    /// the physics stage off.
    pub(super) fn equilibrate(&mut self) -> Result<Option<PopStats>, SimError> {
        if self.scene.disabled.physics || self.state.separating {
            return Ok(None);
        }
        self.relax(EQUILIBRATION_BAND, Load::None).map(Some)
    }

    /// Minimises E(x) + Σᵢ −loadᵢ · (xᵢ − x₀ᵢ) + μ/2 Σᵢ |xᵢ − x₀ᵢ|² by Newton's method with a
    /// line search (module doc), then sweeps the motion through the collision stage.
    fn relax(&mut self, mu: Real, load: Load) -> Result<PopStats, SimError> {
        let clock = Instant::now();
        let t = self.state.time;
        let held = self.held(t)?;
        let contacts = match &mut self.ws.collisions {
            Some(world) if !self.scene.disabled.proximity => {
                // Obstacles still at their current pose for the filter and its sweep.
                world.advance(t, t);
                world.proximity(&self.state.mesh, &self.ws.node_area, &self.ws.face_area, self.scene.time_step())
            }
            Some(world) => {
                world.advance(t, t);
                Vec::new()
            }
            None => Vec::new(),
        };
        self.ws.pattern_for_step(&mut self.state, &contacts)?;
        let nodes = &self.state.mesh.nodes;
        let x0 = self.state.mesh.positions();
        let mut pinned: Vec<Option<Vec3>> = vec![None; nodes.len()];
        for &(n, _) in &held.exact {
            // A prescribed velocity equal to the current one: the node's change is zero.
            pinned[n] = Some(nodes[n].v);
        }
        let load = match load {
            Load::External => self.pop_load(&pinned),
            Load::None => vec![Vec3::zeros(); x0.len()],
        };
        let fixed: Vec<Vec3> = self.ws.collisions.as_ref().map(|w| w.obs_x1.clone()).unwrap_or_default();
        let mut stats = PopStats::default();
        let mut x = x0.clone();
        // The mesh the system is assembled at (positions x); the state's keeps x₀ until the end.
        let mut at_x = self.state.mesh.clone();
        let rest = &self.ws.rest;
        let objective = Objective {
            elastic: Elastic { mesh: &self.state.mesh, rest, materials: &self.scene.materials },
            contacts: &contacts,
            fixed: &fixed,
            springs: &held.springs,
            x0: &x0,
            load: &load,
            mu,
        };
        let mut value = objective.value(&x);
        let mut timing = SolveTiming::default();
        // The first Newton step's factor serves the later ones (their matrices differ little: the
        // steps are small); a step it does not make descend is taken again with a new factor.
        let mut refactor = true;
        for _ in 0..ITERATIONS {
            let rhs: Vec<Vec3> = (0..x.len()).map(|i| load[i] - mu * (x[i] - x0[i])).collect();
            let input = StepInput {
                mesh: &at_x,
                rest,
                materials: &self.scene.materials,
                h: 1.0,
                gravity: self.scene.gravity,
                wind: None,
                pinned: &pinned,
                springs: &held.springs,
                contacts: &contacts,
                fixed: &fixed,
            };
            // Steps on the first step's factor need the right-hand side alone.
            self.ws.system.assemble_static(&input, mu, &rhs, refactor);
            let dx = self
                .ws
                .system
                .solve(&input, &[], refactor, false, &mut timing)
                .map_err(|source| SimError::Solve { step: self.state.steps, time: t, source })?;
            stats.iterations += 1;
            let Some((next, next_value)) = line_search(&objective, &x, &dx, value) else {
                match refactor {
                    true => break,
                    false => {
                        refactor = true;
                        continue;
                    }
                }
            };
            refactor = false;
            let moved = x.iter().zip(&next).map(|(a, b)| (a - b).norm()).fold(0.0, Real::max);
            let converged = moved < TOLERANCE || value - next_value < DECREASE;
            x = next;
            value = next_value;
            for (node, p) in at_x.nodes.iter_mut().zip(&x) {
                node.x = *p;
            }
            if converged {
                break;
            }
        }
        for (node, p) in self.state.mesh.nodes.iter_mut().zip(&x) {
            node.x = *p;
        }
        stats.factorisations = timing.factorisations;
        stats.max_move = x.iter().zip(&x0).map(|(a, b)| (a - b).norm()).fold(0.0, Real::max);
        self.ws.timers.add(Stage::PopFilter, clock.elapsed().as_secs_f64());
        if stats.max_move > 0.0 && self.ws.collisions.is_some() && !self.scene.disabled.collision {
            self.sweep_pop(&x0, &pinned);
        }
        Ok(stats)
    }

    /// f_ext − m a₀ per free node: gravity and wind at the current state, less the force the
    /// last step's acceleration took.
    fn pop_load(&self, pinned: &[Option<Vec3>]) -> Vec<Vec3> {
        let mesh = &self.state.mesh;
        let mut load: Vec<Vec3> = mesh.nodes.iter().map(|n| n.mass * (self.scene.gravity - n.a)).collect();
        if let Some(wind) = &self.scene.wind {
            for f in 0..mesh.faces.len() {
                let ids = mesh.face_nodes(f);
                let (force, _) = wind_face(&ids.map(|n| mesh.nodes[n].x), &ids.map(|n| mesh.nodes[n].v), wind);
                for n in ids {
                    load[n] += force;
                }
            }
        }
        for (l, p) in load.iter_mut().zip(pinned) {
            if p.is_some() {
                *l = Vec3::zeros();
            }
        }
        load
    }

    /// Sweeps the filter's motion from `x0` to the current positions through the collision
    /// stage, so that it creates no crossing.
    fn sweep_pop(&mut self, x0: &[Vec3], pinned: &[Option<Vec3>]) {
        let clock = Instant::now();
        let Some(world) = &mut self.ws.collisions else { return };
        let mesh = &self.state.mesh;
        let inv_mass = inverse_masses(&mesh.nodes, pinned);
        let mut x = mesh.positions();
        world.resolve(
            mesh,
            x0,
            &mut x,
            InvMasses { held: &inv_mass, yielding: &inv_mass },
            None,
            &mut self.ws.counters,
        );
        for (node, p) in self.state.mesh.nodes.iter_mut().zip(x) {
            node.x = p;
        }
        self.ws.timers.since(Stage::Collision, clock);
    }
}

/// Backtracking along the Newton step `dx` from `x`: the first of 1, ½, ¼, … that lowers the
/// objective, with its value; `None` when none does (x is a minimum to rounding).
fn line_search(objective: &Objective, x: &[Vec3], dx: &[Vec3], value: Real) -> Option<(Vec<Vec3>, Real)> {
    let mut alpha = 1.0;
    for _ in 0..HALVINGS {
        let trial: Vec<Vec3> = x.iter().zip(dx).map(|(x, d)| x + alpha * d).collect();
        let v = objective.value(&trial);
        if v < value {
            return Some((trial, v));
        }
        alpha *= 0.5;
    }
    None
}

#[cfg(test)]
#[path = "pop_tests.rs"]
mod tests;
