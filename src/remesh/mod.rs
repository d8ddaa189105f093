//! Anisotropic adaptive remeshing (Narain, Samii & O'Brien 2012, §4): flip all edges, split
//! every edge longer than 1 in the sizing metric (worst first, local flips after each), then
//! collapse edges whose removal keeps every new edge under 0.9 (local flips after each), until
//! nothing changes. Operations are checked values (`ops`); boundaries keep their shape, seams
//! stay closed (their nodes collapse only along them, both sides together), creases stay edges
//! (never flipped, split into creases, collapsed only along themselves), handle nodes stay,
//! and no flip or collapse makes the cloth cross itself (`guard`).

pub mod guard;
pub mod jump;
pub mod ops;
pub mod rest_shape;
pub mod split_place;
pub mod work;

use crate::math::{Mat2, Real, Vec3};
use crate::mesh::{Mesh, MeshError};
use guard::Guard;
use work::Work;
pub use work::{FaceData, Finished};

/// Anti flip-flop threshold of the flip test (ARCSim's `edge_flip_threshold`).
pub const FLIP_THRESHOLD: Real = 1e-2;
/// No flip across a world-space fold sharper than this (radians).
pub const MAX_FLIP_FOLD: Real = 40.0 * std::f64::consts::PI / 180.0;
/// A collapse may not create an edge longer than this in the metric.
pub const COLLAPSE_MAX_LENGTH: Real = 0.9;
/// Caps on passes, against pathological sizing fields.
const MAX_PASSES: usize = 64;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RemeshStats {
    pub splits: usize,
    pub flips: usize,
    pub collapses: usize,
}

/// Limits the remesher needs from the sizing parameters.
#[derive(Clone, Debug)]
pub struct RemeshLimits {
    pub size_min: Real,
    pub aspect_min: Real,
    /// Run the collapse phase (false for a one-off uniform refinement).
    pub coarsen: bool,
    /// Per cloth (`Node::cloth`): a split moves its new node off the midpoint as ARCSim does
    /// (`split_place`); absent cloths keep the midpoint.
    pub relax_splits: Vec<bool>,
}

/// Remeshes `mesh` to the per-vert sizing metrics `vsize`; nodes flagged in `pinned` (handles)
/// survive; `groups` (empty: none) gives nodes a group that a node split between two of them
/// joins; `shapes` are the faces' rest shape operators (`rest_shape`; empty for a flat rest
/// shape) and `damage` their plastic damage (empty: none); `rest_x` the nodes' rest embedding
/// (empty: none; a split's node takes the midpoint); no flip or collapse may move a point of the
/// surface near node n farther than `jump[n]` (m; empty for no bound: the view mode's bound of a
/// pixel on screen for the cloth the camera sees, `jump.rs`; a split's node takes the smaller
/// bound of its edge's ends). Returns the new mesh with the map from old to new node ids, the new
/// faces' rest shape operators and damage, the nodes' groups and rest embedding.
#[allow(clippy::too_many_arguments)]
pub fn remesh(
    mesh: &Mesh,
    vsize: Vec<Mat2>,
    pinned: Vec<bool>,
    groups: &[u32],
    shapes: &[Mat2],
    damage: &[Real],
    rest_x: &[Vec3],
    limits: &RemeshLimits,
    jump: &[Real],
) -> Result<(Finished, RemeshStats), MeshError> {
    let mut w = Work::new(mesh, vsize, pinned, shapes, damage, rest_x);
    if !jump.is_empty() {
        w.jump = jump.to_vec();
        w.start = Some(jump::Start::new(&w));
    }
    if !groups.is_empty() {
        w.group = groups.to_vec();
    }
    let mut stats = RemeshStats::default();
    let mut guard = Guard::new(&w);
    flip_all(&mut w, &mut guard, &mut stats);
    split_all(&mut w, &mut guard, limits, &mut stats);
    if limits.coarsen {
        collapse_all(&mut w, &mut guard, limits, &mut stats);
    }
    Ok((w.finish(mesh.nodes.len())?, stats))
}

/// Applies a flip or collapse unless it would push cloth through cloth (`guard`).
fn apply_guarded(w: &mut Work, guard: &mut Guard, op: &ops::Op) -> bool {
    if w.start.as_ref().is_some_and(|s| jump::too_far(w, s, op)) || guard.crosses(w, op) {
        return false;
    }
    for f in op.apply(w) {
        guard.insert(w, f);
    }
    true
}

fn flip_all(w: &mut Work, guard: &mut Guard, stats: &mut RemeshStats) {
    for _ in 0..MAX_PASSES {
        let mut flipped = 0;
        for (a, b) in w.edges() {
            if w.valive[a] && w.valive[b] && ops::should_flip(w, a, b, FLIP_THRESHOLD, MAX_FLIP_FOLD) {
                if let Some(op) = ops::flip(w, a, b) {
                    flipped += usize::from(apply_guarded(w, guard, &op));
                }
            }
        }
        stats.flips += flipped;
        if flipped == 0 {
            break;
        }
    }
}

/// Flips around the faces of `verts` until they are locally Delaunay in the metric.
fn flip_around(w: &mut Work, guard: &mut Guard, verts: &[usize], stats: &mut RemeshStats) {
    for _ in 0..MAX_PASSES {
        let mut edges: Vec<(usize, usize)> = verts
            .iter()
            .flat_map(|&v| {
                w.vfaces[v].iter().flat_map(|&f| {
                    let t = w.faces[f];
                    (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])))
                })
            })
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let mut flipped = 0;
        for (a, b) in edges {
            if ops::should_flip(w, a, b, FLIP_THRESHOLD, MAX_FLIP_FOLD) {
                if let Some(op) = ops::flip(w, a, b) {
                    flipped += usize::from(apply_guarded(w, guard, &op));
                }
            }
        }
        stats.flips += flipped;
        if flipped == 0 {
            break;
        }
    }
}

fn split_all(w: &mut Work, guard: &mut Guard, limits: &RemeshLimits, stats: &mut RemeshStats) {
    for _ in 0..MAX_PASSES {
        let mut bad: Vec<(Real, usize, usize)> =
            w.edges().into_iter().map(|(a, b)| (w.split_length(a, b), a, b)).filter(|e| e.0 > 1.0).collect();
        if bad.is_empty() {
            return;
        }
        // Worst first; ties by ids for determinism.
        bad.sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        for (_, a, b) in bad {
            if !(w.valive[a] && w.valive[b]) || w.split_length(a, b) <= 1.0 {
                continue;
            }
            let Some(mut op) = ops::split(w, a, b) else { continue };
            let first_new = w.u.len();
            let midpoint = op.new_nodes[0].x;
            // The view mode's on-screen bound (`jump`) keeps midpoints: it assumes splits keep
            // the surface.
            let relax = w.start.is_none() && limits.relax_splits.get(w.cloth[w.vnode[a]] as usize) == Some(&true);
            if relax {
                op.new_nodes[0].x = split_place::relaxed(w, &op, midpoint);
            }
            let added = op.apply(w);
            // A split at the midpoint keeps the surface: no crossing test. A relaxed one moved
            // off it, and goes back to the midpoint if that made a face cross.
            if relax && guard.crosses(w, &op) {
                let node = w.x.len() - 1;
                w.x[node] = midpoint;
            }
            for f in added {
                guard.insert(w, f);
            }
            stats.splits += 1;
            let new_verts: Vec<usize> = (first_new..w.u.len()).collect();
            flip_around(w, guard, &new_verts, stats);
        }
    }
}

fn collapse_all(w: &mut Work, guard: &mut Guard, limits: &RemeshLimits, stats: &mut RemeshStats) {
    let floor = 1e-4 * limits.size_min * limits.size_min;
    for _ in 0..MAX_PASSES {
        let mut collapsed = 0;
        for (a, b) in w.edges() {
            if !(w.valive[a] && w.valive[b])
                || w.metric_length(a, b) >= COLLAPSE_MAX_LENGTH
                || w.edge_faces(a, b).is_empty()
            {
                continue;
            }
            for (i, j) in [(a, b), (b, a)] {
                if !ops::collapse_fits(w, i, j, COLLAPSE_MAX_LENGTH) {
                    continue;
                }
                let Some(op) = ops::collapse(w, i, j) else { continue };
                if ops::collapse_ok(w, &op, limits.aspect_min, COLLAPSE_MAX_LENGTH, floor)
                    && apply_guarded(w, guard, &op)
                {
                    collapsed += 1;
                    let kept: Vec<usize> = op.merged.iter().map(|&(_, t)| t).collect();
                    flip_around(w, guard, &kept, stats);
                    break;
                }
            }
        }
        stats.collapses += collapsed;
        if collapsed == 0 {
            break;
        }
    }
}

#[cfg(test)]
mod crease_tests;
#[cfg(test)]
mod seam_tests;
#[cfg(test)]
mod tests;
