//! Obstacles as a scene describes them: a shape in local coordinates (analytic, an OBJ mesh or a
//! per-frame OBJ sequence), a static transform and an optional keyframed motion.
//! `ObstacleBody::new` meshes them for the collision stages.

use crate::io::obj::ObjData;
use crate::math::motion::{transform_at, Motion, Transform};
use crate::math::{Real, Vec3};

/// An obstacle's shape, as the scene gives it.
#[derive(Clone, Debug)]
pub enum ObstacleShape {
    Mesh(ObjData),
    Sphere {
        radius: Real,
    },
    Plane {
        size: [Real; 2],
    },
    Box {
        size: [Real; 3],
    },
    Capsule {
        radius: Real,
        length: Real,
    },
    /// A deforming mesh given as one OBJ per frame.
    Sequence(MeshSequence),
}

/// A per-frame OBJ sequence of one topology: `frames[k]` holds the local vertex positions at
/// time `start_time + k / fps` (`frames[0]` equals `mesh.positions`).
#[derive(Clone, Debug)]
pub struct MeshSequence {
    /// The first file: faces (shared by every frame) and the positions of frame 0.
    pub mesh: ObjData,
    pub frames: Vec<Vec<Vec3>>,
    pub start_time: Real,
    pub fps: Real,
}

/// An obstacle: its shape in local coordinates, placed by `transform` and then moved by
/// `motion`, present during `window`.
#[derive(Clone, Debug)]
pub struct Obstacle {
    pub name: String,
    pub shape: ObstacleShape,
    pub transform: Transform,
    pub motion: Option<Motion>,
    pub window: Window,
}

/// When an obstacle is present: from `start` to `end`, both included (ARCSim's obstacle
/// `start_time` / `end_time`, `obstacle.cpp`: before it the obstacle has no mesh yet, after it
/// the mesh is deleted).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    pub start: Real,
    pub end: Real,
}

impl Default for Window {
    fn default() -> Self {
        Window { start: Real::NEG_INFINITY, end: Real::INFINITY }
    }
}

impl Window {
    pub fn contains(&self, t: Real) -> bool {
        t >= self.start && t <= self.end
    }

    /// Present at every time.
    pub fn is_always(&self) -> bool {
        *self == Window::default()
    }
}

impl Obstacle {
    /// The local-to-world transform at `t`: `motion(t) ∘ transform`.
    pub fn transform_at(&self, t: Real) -> Transform {
        transform_at(&self.transform, self.motion.as_ref(), t)
    }
}
