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
    /// Present when the collision stages ran.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub collision: Option<CollisionFrameStats>,
    /// Present when a cloth remeshes adaptively.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub remesh: Option<RemeshFrameStats>,
}

/// Remeshing work done at the start of a frame.
#[derive(Serialize, Debug, Clone, Default, PartialEq)]
pub struct RemeshFrameStats {
    pub splits: usize,
    pub flips: usize,
    pub collapses: usize,
}

/// Collision counters of one frame (summed over its steps).
#[derive(Serialize, Debug, Clone, Default, PartialEq)]
pub struct CollisionFrameStats {
    /// Repulsion contacts in the implicit solves.
    pub contacts: usize,
    /// Impacts found by continuous collision detection.
    pub impacts: usize,
    pub impact_zones: usize,
    pub ccd_iterations: usize,
    /// Steps whose impact-zone loop hit `collision.max_iterations` with collisions left.
    pub ccd_cap_hits: usize,
    /// Zones whose projection had no solution.
    pub failed_zones: usize,
    /// Cloth nodes deeper than thickness/2 inside an obstacle at the frame end (must be 0).
    pub penetrations: usize,
}

#[derive(Serialize, Debug, Clone, Default)]
pub struct RunStats {
    pub scene: String,
    pub mode: String,
    pub stages: Vec<String>,
    pub total_wall_s: f64,
    pub frames: Vec<FrameStats>,
}
