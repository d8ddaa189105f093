//! Fault handling inside the step: an attempt whose result fails a check (`checks.rs`) is
//! rolled back and the interval is retried as two steps of half the size (recursively, up to
//! `MAX_HALVINGS`), after which the normal step size resumes. A step still failing at the
//! smallest size stops the run.

use crate::math::Real;
use crate::solver::SolveError;

use super::timers::Stage;
use super::{SimError, Simulation};

/// Retries halve the step at most this many times (smallest step h / 256).
pub const MAX_HALVINGS: u32 = 8;

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

impl Simulation {
    /// One step of size `h`, with fault handling (see the module doc), after the separation
    /// stage while cloth that started inside an obstacle is not out yet, or while two obstacles
    /// are close enough to pinch cloth between them (`separate.rs`).
    pub fn step(&mut self, h: Real) -> Result<(), SimError> {
        self.release_trapped();
        self.timed(Stage::Separation, |s| s.separate(h));
        self.timed(Stage::Separation, Simulation::untangle);
        let t1 = self.state.time + h;
        let result = self.step_to(h, t1, 0);
        // The separation's hold is the step's: a remesh after it numbers the nodes anew.
        self.release_trapped();
        result
    }

    /// Forgets the nodes the separation stage holds or exempts from obstacle collisions, and the
    /// untangling stage's exemptions.
    fn release_trapped(&mut self) {
        self.ws.trapped.clear();
        if let Some(world) = &mut self.ws.collisions {
            world.exempt.clear();
            world.untangling.clear();
        }
    }

    fn step_to(&mut self, h: Real, t1: Real, halvings: u32) -> Result<(), SimError> {
        let saved = self.ws.counters.clone();
        let last = halvings == MAX_HALVINGS;
        match self.attempt(h, t1, last) {
            Ok(()) => {
                self.ws.faults.accepted(h);
                Ok(())
            }
            Err(StepFault::Fatal(e)) => Err(e),
            Err(StepFault::Retry(fault)) if !last => {
                self.ws.counters = saved;
                self.ws.faults.retries += 1;
                *self.ws.faults.kinds.entry(fault.kind().to_string()).or_insert(0) += 1;
                if std::env::var_os("VIEWCLOTH_DEBUG_FAULTS").is_some() {
                    eprintln!(
                        "step {} t = {:.6} h = {h:.3e}: {fault}; retrying at h/2",
                        self.state.steps, self.state.time
                    );
                }
                let half = 0.5 * h;
                let t_mid = self.state.time + half;
                self.step_to(half, t_mid, halvings + 1)?;
                self.step_to(half, t1, halvings + 1)
            }
            Err(StepFault::Retry(fault)) => Err(SimError::StepFailed {
                step: self.state.steps,
                time: self.state.time,
                h,
                halvings,
                fault: fault.to_string(),
            }),
        }
    }
}
