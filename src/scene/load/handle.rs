//! A cloth's `handles`: which nodes (`nodes`, `region`, or the `glue` pair), what holds them
//! (exactly, or a spring of `stiffness`), how they move (`motion`, `mot`, `obstacle`, or a
//! `circle`) and when (`start_time`, `end_time`, `fade_time`).

use super::super::spec::{CircleSpec, HandleSpec};
use super::instance::Placement;
use super::{finite3, motion_or_mot, Ctx, Res};
use crate::collision::shape::{Obstacle, ObstacleShape};
use crate::math::Vec2;
use crate::mesh::Mesh;
use crate::scene::{Circle, FollowObstacle, Handle, HandleKind, Scene};

/// Handle `hs` of a cloth whose input mesh is `local`, its nodes numbered from `node0` in the
/// scene's mesh (the cloth's nodes already in `scene`, placed, with its obstacles), placed by
/// `placement` (its motion and times; see `instance`).
pub(super) fn load_handle(
    ctx: &Ctx,
    hp: &str,
    hs: &HandleSpec,
    local: &Mesh,
    node0: usize,
    scene: &Scene,
    placement: &Placement,
) -> Res<Handle> {
    let (obstacles, run_start) = (&scene.obstacles, scene.start_time());
    let stiffness = match hs.stiffness {
        Some(k) if k > 0.0 && k.is_finite() => Some(k),
        Some(k) => return Err(ctx.err(format!("{hp}.stiffness"), format!("expected a positive number (N/m), got {k}"))),
        None => None,
    };
    let kind = match (&hs.circle, &hs.glue) {
        (Some(_), Some(_)) => return Err(ctx.err(format!("{hp}.glue"), "give circle or glue, not both")),
        (Some(c), None) => HandleKind::Circle(circle(ctx, &format!("{hp}.circle"), c)?),
        (None, Some(_)) => HandleKind::Glue,
        (None, None) => HandleKind::Nodes,
    };
    let nodes = match &hs.glue {
        Some(pair) => glue_nodes(ctx, hp, hs, pair, local, stiffness)?,
        None => handle_nodes(ctx, hp, hs, local)?,
    };
    // A key may shrink the nodes onto a point (ARCSim places them at translate + scale R x₀).
    let motion = motion_or_mot(ctx, hp, hs.motion.as_deref(), hs.mot.as_ref(), true)?;
    let follow = match &hs.obstacle {
        Some(_) if motion.is_some() => {
            return Err(ctx.err(format!("{hp}.obstacle"), "give motion (or mot) or obstacle, not both"))
        }
        Some(_) if !matches!(kind, HandleKind::Nodes) => {
            return Err(ctx.err(format!("{hp}.obstacle"), "only a node handle can ride on an obstacle"))
        }
        Some(name) => Some(follow_obstacle(ctx, &format!("{hp}.obstacle"), name, obstacles)?),
        None => None,
    };
    let start = hs.start_time.unwrap_or(f64::NEG_INFINITY);
    let end = hs.end_time.unwrap_or(f64::INFINITY);
    if start.is_nan() || end.is_nan() || end <= start || start == f64::INFINITY {
        return Err(ctx.err(format!("{hp}.end_time"), format!("expected end_time > start_time, got {start} .. {end}")));
    }
    let fade = match hs.fade_time {
        Some(f) if !(f >= 0.0 && f.is_finite()) => {
            return Err(ctx.err(format!("{hp}.fade_time"), format!("expected a number ≥ 0 (seconds), got {f}")))
        }
        Some(f) if f > 0.0 && stiffness.is_none() => {
            let msg = "a handle that fades must be soft: give \"stiffness\" (N/m)";
            return Err(ctx.err(format!("{hp}.fade_time"), msg));
        }
        Some(f) if f > 0.0 && end == f64::INFINITY => {
            return Err(ctx.err(format!("{hp}.fade_time"), "fades after end_time: give end_time"));
        }
        Some(f) => f,
        None => 0.0,
    };
    let handle = placement.handle(Handle {
        nodes: nodes.iter().map(|n| n + node0).collect(),
        anchors: nodes.iter().map(|&n| scene.mesh.nodes[n + node0].x).collect(),
        kind,
        motion,
        follow,
        start,
        end,
        fade,
        stiffness,
        anchor_time: run_start,
    });
    // The nodes are anchored through M(t_on)⁻¹: a motion shrunk to a point there has none.
    if handle.kind == HandleKind::Nodes
        && handle.displacement(handle.switch_on_time(), handle.switch_on_time()).is_none()
    {
        let at = handle.switch_on_time();
        let msg =
            format!("the motion's scale is 0 at t = {at} s, when the handle switches on: its nodes cannot be anchored");
        return Err(ctx.err(format!("{hp}.start_time"), msg));
    }
    Ok(handle)
}

/// A circle: `circumference` > 0, `u` a non-zero material direction, finite points and axes.
fn circle(ctx: &Ctx, path: &str, c: &CircleSpec) -> Res<Circle> {
    if !(c.circumference > 0.0 && c.circumference.is_finite()) {
        let msg = format!("expected a positive number (m), got {}", c.circumference);
        return Err(ctx.err(format!("{path}.circumference"), msg));
    }
    let u = Vec2::from(c.u);
    if !u.iter().all(|x| x.is_finite()) || u == Vec2::zeros() {
        return Err(ctx.err(format!("{path}.u"), "expected a non-zero material direction [u, v]"));
    }
    Ok(Circle {
        circumference: c.circumference,
        u,
        center: finite3(ctx, &format!("{path}.center"), c.center)?,
        axis0: finite3(ctx, &format!("{path}.axis0"), c.axis0)?,
        axis1: finite3(ctx, &format!("{path}.axis1"), c.axis1)?,
    })
}

/// The two nodes of a glue handle: distinct, in range; the handle is a spring, so it needs a
/// stiffness, and holds nothing else.
fn glue_nodes(ctx: &Ctx, hp: &str, hs: &HandleSpec, pair: &[i64], mesh: &Mesh, k: Option<f64>) -> Res<Vec<usize>> {
    if hs.nodes.is_some() || hs.region.is_some() {
        return Err(ctx.err(format!("{hp}.glue"), "give glue instead of nodes or region, not both"));
    }
    let moved = [("motion", hs.motion.is_some()), ("mot", hs.mot.is_some()), ("obstacle", hs.obstacle.is_some())];
    if let Some((field, _)) = moved.iter().find(|(_, given)| *given) {
        return Err(ctx.err(format!("{hp}.{field}"), "a glue handle ties two nodes together and does not move"));
    }
    if k.is_none() {
        return Err(ctx.err(format!("{hp}.stiffness"), "a glue handle is a spring: give \"stiffness\" (N/m)"));
    }
    let n = mesh.nodes.len();
    let [a, b] = pair else {
        return Err(ctx.err(format!("{hp}.glue"), format!("expected two node indices, got {}", pair.len())));
    };
    for (i, &m) in [a, b].into_iter().enumerate() {
        if m < 0 || m as usize >= n {
            return Err(ctx.err(format!("{hp}.glue[{i}]"), format!("expected a node index in 0..{n}, got {m}")));
        }
    }
    if a == b {
        return Err(ctx.err(format!("{hp}.glue"), format!("expected two different nodes, got {a} twice")));
    }
    Ok(vec![*a as usize, *b as usize])
}

/// The obstacle a handle follows, by name; it must be rigid (a per-frame sequence deforms, so
/// it carries no single transform).
fn follow_obstacle(ctx: &Ctx, path: &str, name: &str, obstacles: &[Obstacle]) -> Res<FollowObstacle> {
    let Some(o) = obstacles.iter().position(|ob| ob.name == name) else {
        let names: Vec<String> = obstacles.iter().map(|ob| format!("\"{}\"", ob.name)).collect();
        let known = if names.is_empty() { "the scene has none".to_string() } else { names.join(", ") };
        return Err(ctx.err(path, format!("no obstacle named \"{name}\" (obstacles: {known})")));
    };
    if obstacles.iter().filter(|ob| ob.name == name).count() > 1 {
        return Err(ctx.err(path, format!("several obstacles are named \"{name}\"; name them apart")));
    }
    if matches!(obstacles[o].shape, ObstacleShape::Sequence(_)) {
        return Err(ctx.err(
            path,
            format!("obstacle \"{name}\" is a per-frame sequence; a handle can only follow a rigid obstacle"),
        ));
    }
    Ok(FollowObstacle::new(o, &obstacles[o]))
}

fn handle_nodes(ctx: &Ctx, path: &str, hs: &HandleSpec, mesh: &Mesh) -> Res<Vec<usize>> {
    let mut nodes = Vec::new();
    match (&hs.nodes, &hs.region) {
        (Some(list), None) => {
            for (i, &n) in list.iter().enumerate() {
                if n < 0 || n as usize >= mesh.nodes.len() {
                    return Err(ctx.err(
                        format!("{path}.nodes[{i}]"),
                        format!("expected a node index in 0..{}, got {n}", mesh.nodes.len()),
                    ));
                }
                nodes.push(n as usize);
            }
        }
        (None, Some(r)) => {
            let (lo, hi) = (Vec2::from(r.min), Vec2::from(r.max));
            for v in &mesh.verts {
                let u = v.u;
                if u.x >= lo.x && u.x <= hi.x && u.y >= lo.y && u.y <= hi.y {
                    nodes.push(v.node.idx());
                }
            }
        }
        _ => return Err(ctx.err(path, "expected exactly one of \"nodes\", \"region\" or \"glue\"")),
    }
    nodes.sort_unstable();
    nodes.dedup();
    if nodes.is_empty() {
        return Err(ctx.err(path, "selects no node"));
    }
    Ok(nodes)
}
