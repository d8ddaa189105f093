//! The named stages of a step and a frame, and the wall-clock time spent in each, accumulated
//! until taken (per frame in stats.json).

use std::collections::BTreeMap;
use std::time::Instant;

/// A stage of the step (`step.rs`) or of the frame (`adapt.rs`, `run.rs`). `name` is the key in
/// stats.json (`stages`, `stage_s`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Target velocities of the handle nodes.
    Handles,
    /// Repulsion contacts within the collision thickness (broad and narrow phase).
    Proximity,
    /// Element kernels summed into the implicit system.
    Assembly,
    /// Sparsity analysis and numeric Cholesky factorisation.
    Factorisation,
    /// Triangular solves.
    Solve,
    /// Positions and velocities from the solved velocity change.
    Integration,
    /// The Coulomb friction filter.
    Friction,
    /// Continuous collision detection and impact zones.
    Collision,
    /// The fault checks of `checks.rs`.
    FaultChecks,
    /// View factors of the faces (Koh et al. 2014), before a view-dependent remesh.
    View,
    /// The sizing field.
    Sizing,
    /// Splits, flips and collapses, and the state rebuilt on the new mesh.
    Remesh,
    /// Counting cloth nodes inside obstacles at the frame end.
    PenetrationCheck,
    /// Counting crossing triangle pairs at the frame end (`collision::crossings`).
    CrossingCheck,
    /// Writing the frame's meshes.
    Output,
    /// Writing a checkpoint.
    Checkpoint,
    /// Long range attachments projected after the solve (`constraints::lra`).
    Lra,
    /// Strain limiting after the solve (`constraints::strain_limit`).
    StrainLimit,
    /// The plastic update at the end of a step (`plastic.rs`).
    Plasticity,
    /// The pop filter after a remesh (`pop.rs`), without its collision sweep (`Collision`).
    PopFilter,
    /// Moving cloth that started inside obstacles out (`separate.rs`).
    Separation,
    /// Buckling compensation: the coarsened faces' κ at a view-dependent remesh and their rest
    /// shapes' slack after each step (`forces::buckling`).
    Buckling,
}

impl Stage {
    pub fn name(self) -> &'static str {
        match self {
            Stage::Handles => "handles",
            Stage::Proximity => "proximity",
            Stage::Assembly => "assembly",
            Stage::Factorisation => "factorisation",
            Stage::Solve => "solve",
            Stage::Integration => "integration",
            Stage::Friction => "friction",
            Stage::Collision => "collision",
            Stage::FaultChecks => "fault_checks",
            Stage::View => "view",
            Stage::Sizing => "sizing",
            Stage::Remesh => "remesh",
            Stage::PenetrationCheck => "penetration_check",
            Stage::CrossingCheck => "crossing_check",
            Stage::Output => "output",
            Stage::Checkpoint => "checkpoint",
            Stage::Lra => "lra",
            Stage::StrainLimit => "strain_limit",
            Stage::Plasticity => "plasticity",
            Stage::PopFilter => "pop_filter",
            Stage::Separation => "separation",
            Stage::Buckling => "buckling",
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct StageTimers {
    current: BTreeMap<Stage, f64>,
    /// Every stage that has run at least once, in first-run order.
    ran: Vec<Stage>,
}

impl StageTimers {
    pub fn add(&mut self, stage: Stage, seconds: f64) {
        if !self.ran.contains(&stage) {
            self.ran.push(stage);
        }
        *self.current.entry(stage).or_insert(0.0) += seconds;
    }

    /// Adds the time since `clock` to `stage`.
    pub fn since(&mut self, stage: Stage, clock: Instant) {
        self.add(stage, clock.elapsed().as_secs_f64());
    }

    /// The names of the stages that have run, in first-run order.
    pub fn ran(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.ran.iter().map(|s| s.name())
    }

    /// The accumulated times since the last call, by stage name, resetting them.
    pub fn take(&mut self) -> BTreeMap<String, f64> {
        std::mem::take(&mut self.current).into_iter().map(|(s, t)| (s.name().to_string(), t)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_listed_in_first_run_order_and_taken_by_name() {
        let mut t = StageTimers::default();
        t.add(Stage::Solve, 1.0);
        t.add(Stage::Handles, 0.5);
        t.add(Stage::Solve, 2.0);
        assert_eq!(t.ran().collect::<Vec<_>>(), ["solve", "handles"]);
        let taken = t.take();
        assert_eq!(taken["solve"], 3.0);
        assert_eq!(taken["handles"], 0.5);
        assert!(t.take().is_empty());
        assert_eq!(t.ran().count(), 2);
    }
}
