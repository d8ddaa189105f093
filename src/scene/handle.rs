//! Handles: cloth nodes held on scripted targets, exactly (pinned) or by a penalty spring (soft,
//! as every ARCSim handle is), while they are switched on.
//!
//! Behavioural reference: ARCSim 0.2.1 `handle.hpp` / `handle.cpp` and `conf.cpp`.
//!
//! - **Switch-on.** A handle switches on at the first step that starts at or after its
//!   `start`. Each node is then anchored where it is at that moment, x_on, at time t_on: its
//!   target at t is D(t) x_on with D(t) = M(t) ∘ M(t_on)⁻¹, M the handle's rigid motion (its
//!   keyframes or `.mot` body, or the full transform of the obstacle it rides on). A handle on
//!   from the run's start anchors the nodes' initial positions at the run's start time.
//!   ARCSim's `NodeHandle::get_constraints` stores M(t_on)⁻¹ x_on the same way.
//! - **Strength.** s(t) = 1 from `start` to `end`; a soft handle then fades over `fade`:
//!   s = (1 − (t − end)/fade)⁴, then 0 (ARCSim's `Handle::strength`). An exact handle holds
//!   during [start, end).
//! - **Circle** handles hold a ring of nodes on a circle of circumference c: a node at material
//!   coordinate u goes to centre + (axis0 cos θ + axis1 sin θ) c / 2π with θ = 2π (u · û) / c,
//!   moved by the handle's motion M(t) (not anchored). A soft circle's spring on a node is
//!   `stiffness` × s × the material length of the node's edges to other nodes of the ring
//!   (ARCSim's `CircleHandle`).
//! - **Glue** handles tie two nodes together by a spring of `stiffness` × s in each direction
//!   (ARCSim's `GlueHandle`).

use crate::collision::shape::Obstacle;
use crate::math::motion::{transform_at, Motion, Transform};
use crate::math::{Real, Vec2, Vec3};

/// What a handle holds its nodes to.
#[derive(Clone, Debug, PartialEq)]
pub enum HandleKind {
    /// Each node to its anchor, moved by the handle's motion.
    Nodes,
    /// A ring of nodes to a circle, placed by their material coordinates.
    Circle(Circle),
    /// Two nodes to each other.
    Glue,
}

/// The circle of a circle handle (world coordinates before the handle's motion).
#[derive(Clone, Debug, PartialEq)]
pub struct Circle {
    pub circumference: Real,
    /// Material direction along the ring: θ = 2π (u · û) / circumference.
    pub u: Vec2,
    pub center: Vec3,
    pub axis0: Vec3,
    pub axis1: Vec3,
}

impl Circle {
    /// Where the ring's node at material coordinate `u` goes (before the motion).
    pub fn point(&self, u: &Vec2) -> Vec3 {
        let tau = std::f64::consts::TAU;
        let theta = tau * u.dot(&self.u) / self.circumference;
        self.center + (self.axis0 * theta.cos() + self.axis1 * theta.sin()) * (self.circumference / tau)
    }
}

/// A handle of the scene.
#[derive(Clone, Debug)]
pub struct Handle {
    /// Node indices in the scene's input mesh: the held nodes, a circle's ring at load, or the
    /// two glued nodes.
    pub nodes: Vec<usize>,
    /// Initial world positions of `nodes`.
    pub anchors: Vec<Vec3>,
    pub kind: HandleKind,
    pub motion: Option<Motion>,
    /// Set instead of `motion` when the handle rides on an obstacle.
    pub follow: Option<FollowObstacle>,
    pub start: Real,
    pub end: Real,
    /// Seconds over which a soft handle's strength fades after `end` (0: it releases at `end`).
    pub fade: Real,
    /// `None`: exact (the nodes land on their targets); `Some(k)`: a spring of k N/m per node
    /// (for a circle, N/m per metre of ring; for glue, between the two nodes).
    pub stiffness: Option<Real>,
    /// The time `anchors` hold at: the run's start.
    pub anchor_time: Real,
}

/// A handle carried rigidly by an obstacle: its motion is the obstacle's full local-to-world
/// transform T(t) (`Obstacle::transform_at`), so anchors move by T(t) ∘ T(t_on)⁻¹.
#[derive(Clone, Debug)]
pub struct FollowObstacle {
    /// Index into `Scene::obstacles`.
    pub obstacle: usize,
    transform: Transform,
    motion: Option<Motion>,
}

impl FollowObstacle {
    /// Follows `obstacles[index]` (a rigid obstacle: not a per-frame sequence).
    pub fn new(index: usize, obstacle: &Obstacle) -> Self {
        FollowObstacle { obstacle: index, transform: obstacle.transform, motion: obstacle.motion.clone() }
    }
}

impl Handle {
    /// Exact handles hold during [start, end) (at the start time of a step).
    pub fn active(&self, t: Real) -> bool {
        t >= self.start && t < self.end
    }

    /// The spring strength of a soft handle at `t` (ARCSim's `Handle::strength`).
    pub fn strength(&self, t: Real) -> Real {
        if t < self.start || t > self.end + self.fade {
            return 0.0;
        }
        if t <= self.end {
            return 1.0;
        }
        let s = 1.0 - (t - self.end) / self.fade;
        (s * s) * (s * s)
    }

    /// The handle's rigid motion at `t`: its keyframes, the obstacle's full transform, or the
    /// identity.
    pub fn rigid(&self, t: Real) -> Transform {
        match (&self.follow, &self.motion) {
            (Some(f), _) => transform_at(&f.transform, f.motion.as_ref(), t),
            (None, Some(m)) => m.eval(t),
            (None, None) => Transform::default(),
        }
    }

    /// D = M(t) ∘ M(t_on)⁻¹: where a point anchored at `t_on` is carried by `t`. `None` when the
    /// motion's scale is 0 at `t_on` (no anchor can be recovered).
    pub fn displacement(&self, t_on: Real, t: Real) -> Option<Transform> {
        let on = self.rigid(t_on);
        let now = self.rigid(t);
        if on == Transform::default() {
            return Some(now);
        }
        (on.scale != 0.0 && on.scale.is_finite()).then(|| now.compose(&on.inverse()))
    }

    /// The time a handle on from the run's start anchors at.
    pub fn switch_on_time(&self) -> Real {
        self.start.max(self.anchor_time)
    }

    /// The target at `t` of node `k` of a node handle anchored at its initial position when the
    /// handle switched on (at the run's start, or at `start` if later).
    pub fn target(&self, k: usize, t: Real) -> Vec3 {
        match self.displacement(self.switch_on_time(), t) {
            Some(d) => d.apply(&self.anchors[k]),
            None => self.anchors[k],
        }
    }

    /// A circle handle's target at `t` for its node at material coordinate `u`.
    pub fn circle_target(&self, circle: &Circle, u: &Vec2, t: Real) -> Vec3 {
        self.rigid(t).apply(&circle.point(u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::motion::Keyframe;

    fn handle(start: Real, end: Real, fade: Real) -> Handle {
        Handle {
            nodes: vec![0],
            anchors: vec![Vec3::zeros()],
            kind: HandleKind::Nodes,
            motion: None,
            follow: None,
            start,
            end,
            fade,
            stiffness: Some(1.0),
            anchor_time: 0.0,
        }
    }

    #[test]
    fn strength_fades_as_arcsim_does() {
        let h = handle(1.0, 2.0, 0.5);
        assert_eq!(h.strength(0.99), 0.0);
        assert_eq!(h.strength(1.0), 1.0);
        assert_eq!(h.strength(2.0), 1.0);
        assert!((h.strength(2.25) - 0.0625).abs() < 1e-15, "(1 − ½)⁴");
        assert_eq!(h.strength(2.5), 0.0);
        assert_eq!(h.strength(2.51), 0.0);
        let no_fade = handle(0.0, 2.0, 0.0);
        assert_eq!(no_fade.strength(2.0), 1.0);
        assert_eq!(no_fade.strength(2.0 + 1e-9), 0.0);
    }

    #[test]
    fn displacement_is_relative_to_the_switch_on() {
        let key = |time: Real, x: Real, s: Real| Keyframe { time, transform: Transform::new([x, 0.0, 0.0], None, s) };
        let mut h = handle(1.0, 9.0, 0.0);
        h.motion = Some(Motion::new(vec![key(0.0, 0.0, 1.0), key(2.0, 1.0, 2.0), key(4.0, 3.0, 0.0)]));
        // Anchored at t = 2 where x = (1 + 2·p): at t = 2 the target is where the node was.
        let p = Vec3::new(0.5, 0.2, -0.1);
        let x_on = h.rigid(2.0).apply(&p);
        let d = h.displacement(2.0, 2.0).unwrap();
        assert!((d.apply(&x_on) - x_on).norm() < 1e-15);
        // At t = 4 the motion's scale is 0: every node is pulled onto its translation.
        let d = h.displacement(2.0, 4.0).unwrap();
        assert!((d.apply(&x_on) - Vec3::new(3.0, 0.0, 0.0)).norm() < 1e-15);
        assert!(h.displacement(4.0, 5.0).is_none(), "no anchor from a zero scale");
    }

    #[test]
    fn circle_points_follow_the_material_coordinate() {
        let c = Circle {
            circumference: 0.28,
            u: Vec2::new(1.0, 0.0),
            center: Vec3::new(0.0, 0.0, 0.2),
            axis0: Vec3::x(),
            axis1: Vec3::y(),
        };
        let r = 0.28 / std::f64::consts::TAU;
        assert!((c.point(&Vec2::new(0.0, 0.3)) - Vec3::new(r, 0.0, 0.2)).norm() < 1e-15);
        assert!((c.point(&Vec2::new(0.07, 0.0)) - Vec3::new(0.0, r, 0.2)).norm() < 1e-15);
        assert!((c.point(&Vec2::new(0.28, 0.0)) - c.point(&Vec2::zeros())).norm() < 1e-15);
    }
}
