//! Obstacles and collisions: obstacle descriptions (`shape`) and the bodies meshed from them
//! (`obstacle`), broad phase, proximity repulsion, continuous collision detection and impact-zone
//! resolution (with rigid zones as its last resort), with their parameters (`params`); the exact count of crossing triangle pairs that
//! checks each written frame (`crossings`), and the analysis of where cloth has crossed itself
//! that takes it back (`untangle`).

pub mod areas;
pub mod broad;
pub mod bvh;
pub mod ccd;
pub mod crossings;
pub mod friction;
pub mod geometry;
pub mod impact_zones;
pub mod obstacle;
pub mod params;
pub mod proximity;
pub mod rigid_zone;
pub mod sdf;
pub mod shape;
pub mod speculative;
pub mod untangle;
pub mod world;
