//! Fault handling inside the step: an attempt whose result fails a check is rolled back and the
//! interval is retried as two steps of half the size (recursively, up to `MAX_HALVINGS`), after
//! which the normal step size resumes. A step still failing at the smallest size stops the run.
//!
//! The checks, and why each is a fault rather than physics:
//!
//! - **Factorisation**: the system matrix M + (hα + h²)K − hD is SPD by construction (projected
//!   Hessians); a failed Cholesky means non-finite or absurd entries.
//! - **Energy** (after the implicit solve, before friction and collisions): handles and
//!   obstacles are moved to their end-of-step positions first, which is where all their work is
//!   done (their contact penalties are frozen at those positions); the free nodes' motion is then
//!   one backward-Euler step, which dissipates. So the energy change of the free motion,
//!   ΔE = ΔK_free + ΔP_free + U(x̂) − U(x̃) + C(x̂) − C(x̃)
//!   (x̃: start positions with handles on their targets, x̂: solved positions, U elastic, C
//!   repulsion, P gravity), may exceed the wind's work W only by
//!   `ENERGY_TOLERANCE` × (K₀ + U₀ + C(x̃) + W) + a floor of the cloth's mass dropping
//!   `FLOOR_DROP` and moving at `FLOOR_SPEED`. One linearised Newton step that misses the
//!   stretch of a large rotation (drape_stiff at h = 1/24: 1.5 J → 120 J in one step with fixed
//!   handles) fails this by orders of magnitude.
//! - **Non-finite** positions or velocities at the end of the step.
//! - **Speed** (after friction and collisions): no node faster than 2 (v̂_max + v_obstacle,max)
//!   + `KICK_THICKNESSES`·thickness/h + 1 m/s, v̂ the solved velocities: an impact-zone
//!   projection may carry nodes along with an obstacle and push them out by a few thicknesses,
//!   not fling them.
//! - **Energy of the collision stages**: friction and impact zones may add at most, per node
//!   they touch, the kinetic energy of moving at twice the fastest obstacle's speed plus that
//!   of the push-out above (both scale like the energy they allow, so a smaller step does not
//!   turn a push-out into a fault), with the same tolerance as the solve.
//! - **Strain jump**: the largest principal strain may not rise by more than `STRAIN_JUMP` in
//!   one step (an element torn open by a projection or a solve).
//! - **Collisions left** at the impact-zone iteration cap: retried like the others, but at the
//!   smallest step the result is kept (counted in `ccd_cap_hits`): a residual contact is a
//!   smaller harm to a shot than a stopped run.

use rayon::prelude::*;

use crate::collision::proximity::Contact;
use crate::forces::membrane::{deformation_gradient, max_principal_strain};
use crate::forces::wind::wind_face;
use crate::forces::Projection;
use crate::math::{Real, Vec3};
use crate::solver::SolveError;

use super::{SimError, Simulation};

/// Retries halve the step at most this many times (smallest step h / 256).
pub const MAX_HALVINGS: u32 = 8;
/// Relative energy gain tolerated per step (of the energy present plus the work done).
pub const ENERGY_TOLERANCE: Real = 0.1;
/// Absolute energy floor: the cloth dropping this far (m) …
pub const FLOOR_DROP: Real = 1e-2;
/// … and moving at this speed (m/s).
pub const FLOOR_SPEED: Real = 0.1;
/// A collision push-out may move a node this many thicknesses within one step.
pub const KICK_THICKNESSES: Real = 4.0;
/// Largest rise of the maximum principal strain in one step.
pub const STRAIN_JUMP: Real = 0.5;

/// Why an attempted step was rejected.
#[derive(Clone, Debug, PartialEq)]
pub enum Fault {
    Factorisation(SolveError),
    NonFinite,
    EnergyGain { gain: Real, budget: Real },
    Speed { max: Real, cap: Real },
    StrainJump { from: Real, to: Real },
    Collisions,
}

impl Fault {
    /// Short name, as counted in stats.json.
    pub fn kind(&self) -> &'static str {
        match self {
            Fault::Factorisation(_) => "factorisation",
            Fault::NonFinite => "non_finite",
            Fault::EnergyGain { .. } => "energy",
            Fault::Speed { .. } => "speed",
            Fault::StrainJump { .. } => "strain",
            Fault::Collisions => "collisions",
        }
    }
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Factorisation(e) => write!(f, "{e}"),
            Fault::NonFinite => write!(f, "the state became non-finite (NaN or infinity)"),
            Fault::EnergyGain { gain, budget } => {
                write!(f, "the step created {gain:.3e} J of energy (allowed {budget:.3e} J)")
            }
            Fault::Speed { max, cap } => write!(f, "a node reached {max:.3e} m/s (allowed {cap:.3e} m/s)"),
            Fault::StrainJump { from, to } => write!(f, "max strain jumped from {from:.3} to {to:.3} in one step"),
            Fault::Collisions => write!(f, "collisions left after the impact-zone iteration cap"),
        }
    }
}

/// An attempt's failure: retry smaller, or stop.
#[derive(Debug)]
pub enum StepFault {
    Retry(Fault),
    Fatal(SimError),
}

impl From<SimError> for StepFault {
    fn from(e: SimError) -> Self {
        StepFault::Fatal(e)
    }
}

impl From<Fault> for StepFault {
    fn from(f: Fault) -> Self {
        StepFault::Retry(f)
    }
}

/// Retries since last taken (per frame in stats.json).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FaultStats {
    /// Steps accepted.
    pub steps: usize,
    /// Attempts rolled back.
    pub retries: usize,
    /// Smallest accepted step (s); 0 when no step was taken.
    pub min_step: Real,
    /// Rolled-back attempts by fault kind.
    pub kinds: std::collections::BTreeMap<String, usize>,
}

impl FaultStats {
    fn accepted(&mut self, h: Real) {
        self.min_step = if self.steps == 0 { h } else { self.min_step.min(h) };
        self.steps += 1;
    }
}

/// The solved (pre-collision) state's energy, for the end-of-step check.
pub struct SolvedEnergy {
    pub x: Vec<Vec3>,
    pub kinetic: Real,
    pub elastic: Real,
    /// The absolute energy floor of the scene.
    pub floor: Real,
}

/// What the energy check needs from the step.
pub struct EnergyCheck<'a> {
    pub h: Real,
    pub x0: &'a [Vec3],
    /// Solved end-of-step velocities (handles: their prescribed velocities).
    pub v: &'a [Vec3],
    pub pinned: &'a [Option<Vec3>],
    pub contacts: &'a [Contact],
    /// Elastic energy at the start of the step.
    pub u0: Real,
}

impl Simulation {
    /// One step of size `h`, with fault handling (see the module doc).
    pub fn step(&mut self, h: Real) -> Result<(), SimError> {
        let t1 = self.time + h;
        self.step_to(h, t1, 0)
    }

    fn step_to(&mut self, h: Real, t1: Real, halvings: u32) -> Result<(), SimError> {
        let saved = self.counters.clone();
        let last = halvings == MAX_HALVINGS;
        match self.attempt_step(h, t1, last) {
            Ok(()) => {
                self.faults.accepted(h);
                Ok(())
            }
            Err(StepFault::Fatal(e)) => Err(e),
            Err(StepFault::Retry(fault)) if !last => {
                self.counters = saved;
                self.faults.retries += 1;
                *self.faults.kinds.entry(fault.kind().to_string()).or_insert(0) += 1;
                if std::env::var_os("VIEWCLOTH_DEBUG_FAULTS").is_some() {
                    eprintln!("step {} t = {:.6} h = {h:.3e}: {fault}; retrying at h/2", self.steps, self.time);
                }
                let half = 0.5 * h;
                let t_mid = self.time + half;
                self.step_to(half, t_mid, halvings + 1)?;
                self.step_to(half, t1, halvings + 1)
            }
            Err(StepFault::Retry(fault)) => {
                Err(SimError::StepFailed { step: self.steps, time: self.time, h, halvings, fault: fault.to_string() })
            }
        }
    }

    /// Elastic energy (membrane + bending) at positions `x`; per-element terms in parallel,
    /// summed in element order (deterministic).
    pub(super) fn elastic_energy_at(&self, x: &[Vec3]) -> Real {
        let m = &self.mesh;
        let faces: Vec<Real> = (0..m.faces.len()).into_par_iter().map(|f| self.face_energy(f, x)).collect();
        let hinges: Vec<Real> = (0..self.rest.hinges.len()).into_par_iter().map(|k| self.hinge_energy(k, x)).collect();
        faces.iter().sum::<Real>() + hinges.iter().sum::<Real>()
    }

    fn face_energy(&self, f: usize, x: &[Vec3]) -> Real {
        let xs = self.mesh.face_nodes(f).map(|n| x[n]);
        let mat = &self.scene.materials[self.mesh.faces[f].material as usize];
        mat.stretch(&xs, &self.rest.membrane[f], Projection::Psd).0
    }

    fn hinge_energy(&self, k: usize, x: &[Vec3]) -> Real {
        let hg = &self.rest.hinges[k];
        self.scene.materials[hg.material].bend(&hg.nodes.map(|n| x[n]), hg, Projection::Psd).0
    }

    /// U(x̃) − U(x₀): the elastic work of moving the handle nodes in `moved` to `xt` with every
    /// other node held (only elements touching a moved node change).
    fn handle_work(&self, x0: &[Vec3], xt: &[Vec3], moved: &[bool]) -> Real {
        let mut w = 0.0;
        for f in 0..self.mesh.faces.len() {
            if self.mesh.face_nodes(f).iter().any(|&n| moved[n]) {
                w += self.face_energy(f, xt) - self.face_energy(f, x0);
            }
        }
        for (k, hg) in self.rest.hinges.iter().enumerate() {
            if hg.nodes.iter().any(|&n| moved[n]) {
                w += self.hinge_energy(k, xt) - self.hinge_energy(k, x0);
            }
        }
        w
    }

    /// Repulsion energy Σ ½ k g² (g < 0) of the step's frozen contacts, cloth at `x`.
    fn contact_energy(&self, contacts: &[Contact], x: &[Vec3]) -> Real {
        let n = x.len();
        let fixed: &[Vec3] = self.collisions.as_ref().map(|w| w.obs_x1.as_slice()).unwrap_or(&[]);
        contacts
            .iter()
            .map(|c| {
                let g = c.gap(&c.nodes.map(|i| if i < n { x[i] } else { fixed[i - n] }));
                if g < 0.0 {
                    0.5 * c.stiffness * g * g
                } else {
                    0.0
                }
            })
            .sum()
    }

    /// An upper estimate of the wind's work over the step: per face, the larger of its power
    /// at the start and at the solved end (never negative), times h.
    fn wind_work(&self, h: Real, x0: &[Vec3], v0: &[Vec3], x1: &[Vec3], v1: &[Vec3]) -> Real {
        let Some(wind) = &self.scene.wind else { return 0.0 };
        let power = |f: usize, x: &[Vec3], v: &[Vec3]| {
            let ids = self.mesh.face_nodes(f);
            let (vs, xs) = (ids.map(|n| v[n]), ids.map(|n| x[n]));
            let (force, _) = wind_face(&xs, &vs, wind);
            force.dot(&(vs[0] + vs[1] + vs[2]))
        };
        let p: Vec<Real> = (0..self.mesh.faces.len())
            .into_par_iter()
            .map(|f| power(f, x0, v0).max(power(f, x1, v1)).max(0.0))
            .collect();
        h * p.iter().sum::<Real>()
    }

    /// The energy check on the solved velocities (module doc). Returns the solved state's
    /// energy for the end-of-step check.
    pub(super) fn check_energy(&self, c: &EnergyCheck) -> Result<SolvedEnergy, Fault> {
        let nodes = &self.mesh.nodes;
        let x1: Vec<Vec3> = c.x0.iter().zip(c.v).map(|(x, v)| x + c.h * v).collect();
        if !x1.iter().chain(c.v).all(|p| p.iter().all(|e| e.is_finite())) {
            return Err(Fault::NonFinite);
        }
        let g = self.scene.gravity;
        let (mut dk, mut dp, mut k0) = (0.0, 0.0, 0.0);
        let mut moved = vec![false; nodes.len()];
        for (i, node) in nodes.iter().enumerate() {
            k0 += 0.5 * node.mass * node.v.norm_squared();
            if c.pinned[i].is_some() {
                moved[i] = x1[i] != c.x0[i];
                continue;
            }
            dk += 0.5 * node.mass * (c.v[i].norm_squared() - node.v.norm_squared());
            dp -= node.mass * g.dot(&(x1[i] - c.x0[i]));
        }
        // x̃: start positions with the handles already on their targets.
        let xt: Vec<Vec3> = (0..nodes.len()).map(|i| if moved[i] { x1[i] } else { c.x0[i] }).collect();
        let ut = c.u0 + if moved.iter().any(|&m| m) { self.handle_work(c.x0, &xt, &moved) } else { 0.0 };
        let u1 = self.elastic_energy_at(&x1);
        let k1: Real = nodes.iter().zip(c.v).map(|(n, v)| 0.5 * n.mass * v.norm_squared()).sum();
        let (ct, c1) = (self.contact_energy(c.contacts, &xt), self.contact_energy(c.contacts, &x1));
        let v0: Vec<Vec3> = nodes.iter().map(|n| n.v).collect();
        let wind = self.wind_work(c.h, c.x0, &v0, &x1, c.v);
        let gain = dk + dp + (u1 - ut) + (c1 - ct);
        let mass: Real = nodes.iter().map(|n| n.mass).sum();
        let floor = mass * (g.norm() * FLOOR_DROP + 0.5 * FLOOR_SPEED * FLOOR_SPEED);
        let budget = wind + ENERGY_TOLERANCE * (k0 + c.u0 + ct + wind) + floor;
        if gain > budget || !gain.is_finite() {
            return Err(Fault::EnergyGain { gain, budget });
        }
        Ok(SolvedEnergy { x: x1, kinetic: k1, elastic: u1, floor })
    }

    /// Checks on the end-of-step state (after friction and collisions): finite, speed cap,
    /// energy against the solved state, strain jump.
    pub(super) fn check_end(
        &self,
        h: Real,
        x0: &[Vec3],
        x: &[Vec3],
        v: &[Vec3],
        v_solved: &[Vec3],
        solved: &SolvedEnergy,
    ) -> Result<(), Fault> {
        if !x.iter().chain(v.iter()).all(|p| p.iter().all(|c| c.is_finite())) {
            return Err(Fault::NonFinite);
        }
        let v_obs = match &self.collisions {
            Some(w) => w.obstacle_velocities(h).iter().map(|v| v.norm()).fold(0.0, Real::max),
            None => 0.0,
        };
        let th = self.collisions.as_ref().map_or(0.0, |w| w.params.thickness);
        let v_max_solve = v_solved.iter().map(|v| v.norm()).fold(0.0, Real::max);
        let cap = 2.0 * (v_max_solve + v_obs) + KICK_THICKNESSES * th / h + 1.0;
        let max = v.iter().map(|v| v.norm()).fold(0.0, Real::max);
        if max > cap {
            return Err(Fault::Speed { max, cap });
        }
        if v == v_solved {
            // Friction and collisions changed nothing: the solve's check stands.
            return Ok(());
        }
        // Friction and impact zones are inelastic: they create no energy beyond carrying the
        // nodes they touch along with a moving obstacle (at up to twice its speed) and the kick
        // of pushing a node out by up to `KICK_THICKNESSES` thicknesses within the step. Both
        // allowances scale like the kinetic energy they cover, so halving h does not turn a
        // push-out into a fault.
        let g = self.scene.gravity;
        let kick = KICK_THICKNESSES * th / h;
        let (mut k, mut dp, mut carried) = (0.0, 0.0, 0.0);
        for (i, n) in self.mesh.nodes.iter().enumerate() {
            k += 0.5 * n.mass * v[i].norm_squared();
            dp -= n.mass * g.dot(&(x[i] - solved.x[i]));
            if v[i] != v_solved[i] {
                carried += 0.5 * n.mass * (4.0 * v_obs * v_obs + kick * kick);
            }
        }
        let u = self.elastic_energy_at(x);
        let gain = (k - solved.kinetic) + (u - solved.elastic) + dp;
        let budget = carried + ENERGY_TOLERANCE * (solved.kinetic + solved.elastic + carried) + solved.floor;
        if gain > budget || !gain.is_finite() {
            return Err(Fault::EnergyGain { gain, budget });
        }
        let (from, to) = (self.max_strain_at(x0), self.max_strain_at(x));
        if to > from + STRAIN_JUMP {
            return Err(Fault::StrainJump { from, to });
        }
        Ok(())
    }

    /// Largest principal strain over all faces at positions `x`.
    pub(super) fn max_strain_at(&self, x: &[Vec3]) -> Real {
        (0..self.mesh.faces.len())
            .into_par_iter()
            .map(|f| {
                let xs = self.mesh.face_nodes(f).map(|n| x[n]);
                max_principal_strain(&deformation_gradient(&xs, &self.rest.membrane[f]))
            })
            .reduce(|| Real::NEG_INFINITY, Real::max)
    }
}
