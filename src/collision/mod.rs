//! Obstacles and collisions: broad phase, proximity repulsion, continuous collision detection
//! and impact-zone resolution.

pub mod broad;
pub mod bvh;
pub mod ccd;
pub mod friction;
pub mod geometry;
pub mod impact_zones;
pub mod obstacle;
pub mod params;
pub mod proximity;
pub mod sdf;
pub mod shape;
pub mod world;
