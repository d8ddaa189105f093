//! `stats.json`: what ran, how long each stage took, and the state of each frame.

use std::collections::BTreeMap;

use serde::Serialize;

#[derive(Serialize, Debug, Clone, Default)]
pub struct FrameStats {
    pub frame: usize,
    pub time: f64,
    pub wall_s: f64,
    pub stage_s: BTreeMap<String, f64>,
    pub nodes: usize,
    pub faces: usize,
    pub kinetic_energy: f64,
    /// Total energy: kinetic + elastic + gravitational potential (J).
    pub total_energy: f64,
    pub max_strain: f64,
    pub mean_strain: f64,
    pub steps: usize,
}

#[derive(Serialize, Debug, Clone, Default)]
pub struct RunStats {
    pub scene: String,
    pub mode: String,
    pub stages: Vec<String>,
    pub total_wall_s: f64,
    pub frames: Vec<FrameStats>,
}
