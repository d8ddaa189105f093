//! Wall-clock time per named stage, accumulated until taken.

use std::collections::BTreeMap;
use std::time::Instant;

#[derive(Clone, Debug, Default)]
pub struct StageTimers {
    current: BTreeMap<String, f64>,
    /// Every stage that has run at least once, in first-run order.
    pub ran: Vec<String>,
}

impl StageTimers {
    pub fn add(&mut self, stage: &str, seconds: f64) {
        if !self.ran.iter().any(|s| s == stage) {
            self.ran.push(stage.to_string());
        }
        *self.current.entry(stage.to_string()).or_insert(0.0) += seconds;
    }

    pub fn time<T>(&mut self, stage: &str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let r = f();
        self.add(stage, t.elapsed().as_secs_f64());
        r
    }

    /// The accumulated times since the last call, resetting them.
    pub fn take(&mut self) -> BTreeMap<String, f64> {
        std::mem::take(&mut self.current)
    }
}
