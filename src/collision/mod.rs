//! Obstacles and collisions: broad phase, proximity repulsion, continuous collision detection
//! and impact-zone resolution.

pub mod bvh;
pub mod impact_zones;
pub mod friction;
pub mod ccd;
pub mod geometry;
pub mod proximity;
pub mod obstacle;
pub mod sdf;
pub mod world;
pub mod broad;
