//! Remeshing operations as values (ARCSim's `RemeshOp`): what is added and what is removed.
//! An operation is built, checked, and only then applied to the working mesh.

use crate::math::{cross2, Mat2, Real, Vec2, Vec3};

use super::work::{FaceData, NewNode, Work};

/// A local change: new nodes, new verts (ids continue the work's arrays, in order), faces
/// removed and added (over old and new vert ids), verts removed.
#[derive(Clone, Debug, Default)]
pub struct Op {
    /// (position, velocity, cloth, group).
    pub new_nodes: Vec<NewNode>,
    /// (material coordinate, node id — old or new —, sizing metric).
    pub new_verts: Vec<(Vec2, usize, Mat2)>,
    pub remove_faces: Vec<usize>,
    pub add_faces: Vec<([usize; 3], FaceData)>,
    pub remove_verts: Vec<usize>,
    /// A collapse's removed verts, each with the vert it merges into.
    pub merged: Vec<(usize, usize)>,
    /// The nodes of a split edge (its creases pass to the halves, `Work::split_crease`).
    pub split_nodes: Option<(usize, usize)>,
    /// A collapse's removed node and the node it merges into (`Work::collapse_crease`).
    pub collapse_nodes: Option<(usize, usize)>,
}

impl Op {
    /// Applies the change; returns the ids of the added faces.
    pub fn apply(&self, w: &mut Work) -> Vec<usize> {
        let first_node = w.x.len();
        for &n in &self.new_nodes {
            w.add_node(n);
        }
        if !w.jump.is_empty() {
            // A node on a split edge takes the smaller bound of its ends.
            let bound = self.split_nodes.map_or(Real::INFINITY, |(a, b)| w.jump[a].min(w.jump[b]));
            w.jump.resize(w.x.len(), bound);
        }
        if let Some((a, b)) = self.split_nodes {
            w.split_crease(a, b, first_node);
        }
        if let Some((i, j)) = self.collapse_nodes {
            w.collapse_crease(i, j);
        }
        for &(u, node, m) in &self.new_verts {
            w.add_vert(u, node, m);
        }
        for &f in &self.remove_faces {
            w.remove_face(f);
        }
        let added = self.add_faces.iter().map(|&(t, m)| w.add_face(t, m)).collect();
        for &v in &self.remove_verts {
            w.remove_vert(v);
        }
        added
    }

    /// Material coordinate of a vert of this op (existing or new).
    pub fn u(&self, w: &Work, v: usize) -> Vec2 {
        if v < w.u.len() {
            w.u[v]
        } else {
            self.new_verts[v - w.u.len()].0
        }
    }
}

/// Material-space aspect below which an operation may not leave a face thinner than the faces
/// it replaces. Splitting a short edge of a thin face makes it thinner, and repeated along a
/// boundary or seam whose own edge is not split (its ends' metric is coarser than the interior
/// vert's) this drove faces to collinear corners: a view-dependent run of the dancer stopped
/// with "remeshing left face N degenerate" (aspect 1e-2 → 1e-6 → 0 over one remesh).
pub const SLIVER: Real = 1e-2;

/// Whether replacing faces of least aspect `before` by `after` makes a sliver (`SLIVER`).
fn makes_sliver(before: Real, after: impl IntoIterator<Item = [Vec2; 3]>) -> bool {
    after.into_iter().any(|u| {
        let q = aspect(u);
        q < SLIVER && q < before
    })
}

/// Splits the faces on edge (s → t) of `face` at new vert `p` (material coordinate `up`):
/// (s, p, k) and (p, t, k); false, adding nothing, when that would make a sliver.
fn split_face(w: &Work, f: usize, a: usize, b: usize, (p, up): (usize, Vec2), op: &mut Op) -> bool {
    let (s, t) = if w.directed(f, a, b).is_some() { (a, b) } else { (b, a) };
    let k = w.opposite(f, a, b);
    let before = aspect(w.faces[f].map(|v| w.u[v]));
    if makes_sliver(before, [[w.u[s], up, w.u[k]], [up, w.u[t], w.u[k]]]) {
        return false;
    }
    op.remove_faces.push(f);
    op.add_faces.push(([s, p, k], w.fdata[f]));
    op.add_faces.push(([p, t, k], w.fdata[f]));
    true
}

/// Split of material edge a–b at its midpoint (both sides of a seam with one new node). The
/// new node's position, velocity and acceleration interpolate the ends (linear, so the surface is unchanged).
pub fn split(w: &Work, a: usize, b: usize) -> Option<Op> {
    let faces = w.edge_faces(a, b);
    if faces.is_empty() {
        return None;
    }
    let (na, nb) = (w.vnode[a], w.vnode[b]);
    let mut op = Op { split_nodes: Some((na, nb)), ..Default::default() };
    let node = w.x.len();
    // A node between two nodes of one group joins it (ARCSim's `combine_label`).
    let group = if w.group[na] == w.group[nb] { w.group[na] } else { 0 };
    op.new_nodes.push(NewNode {
        x: 0.5 * (w.x[na] + w.x[nb]),
        v: 0.5 * (w.v[na] + w.v[nb]),
        a: 0.5 * (w.a[na] + w.a[nb]),
        y: match w.y.is_empty() {
            true => Vec3::zeros(),
            false => 0.5 * (w.y[na] + w.y[nb]),
        },
        cloth: w.cloth[na],
        group,
    });
    let (p, up) = (w.u.len(), 0.5 * (w.u[a] + w.u[b]));
    op.new_verts.push((up, node, 0.5 * (w.vsize[a] + w.vsize[b])));
    for &f in &faces {
        if !split_face(w, f, a, b, (p, up), &mut op) {
            return None;
        }
    }
    if faces.len() == 1 {
        if let Some((c, d)) = w.seam_partner(a, b) {
            let (q, uq) = (p + 1, 0.5 * (w.u[c] + w.u[d]));
            op.new_verts.push((uq, node, 0.5 * (w.vsize[c] + w.vsize[d])));
            for f in w.edge_faces(c, d) {
                if !split_face(w, f, c, d, (q, uq), &mut op) {
                    return None;
                }
            }
        }
    }
    Some(op)
}

/// Flip of the interior edge a–b: faces (a, b, c) and (b, a, d) become (c, a, d) and (d, b, c).
/// A crease is never flipped (ARCSim's labelled edges).
pub fn flip(w: &Work, a: usize, b: usize) -> Option<Op> {
    let faces = w.edge_faces(a, b);
    if faces.len() != 2 || w.is_crease(w.vnode[a], w.vnode[b]) {
        return None;
    }
    let (f0, f1) = if w.directed(faces[0], a, b).is_some() { (faces[0], faces[1]) } else { (faces[1], faces[0]) };
    let c = w.directed(f0, a, b)?;
    let d = w.directed(f1, b, a)?;
    if c == d || w.neighbours(c).contains(&d) || w.vnode[c] == w.vnode[d] {
        return None;
    }
    let (t0, t1) = ([c, a, d], [d, b, c]);
    let floor = 1e-12 * (w.area(&w.faces[f0]) + w.area(&w.faces[f1]));
    if w.area(&t0) <= floor || w.area(&t1) <= floor {
        return None;
    }
    let before = aspect(w.faces[f0].map(|v| w.u[v])).min(aspect(w.faces[f1].map(|v| w.u[v])));
    if makes_sliver(before, [t0.map(|v| w.u[v]), t1.map(|v| w.u[v])]) {
        return None;
    }
    // The pair's rest shape and damage, area-weighted, go to both new faces (`rest_shape`).
    let (a0, a1) = (w.area(&w.faces[f0]), w.area(&w.faces[f1]));
    let shape = (a0 * w.fdata[f0].shape + a1 * w.fdata[f1].shape) / (a0 + a1);
    let damage = (a0 * w.fdata[f0].damage + a1 * w.fdata[f1].damage) / (a0 + a1);
    let (d0, d1) = (FaceData { shape, damage, ..w.fdata[f0] }, FaceData { shape, damage, ..w.fdata[f1] });
    Some(Op { remove_faces: vec![f0, f1], add_faces: vec![(t0, d0), (t1, d1)], ..Default::default() })
}

/// Anisotropic Delaunay test (Bossen & Heckbert 1996, in ARCSim's form): flip a–b when the
/// angles opposite it, measured in the mean metric of the four verts, sum to more than π
/// (sin(α + β) < 0), beyond a small threshold against flip-flopping; never across a world-space
/// fold sharper than `max_fold` radians.
pub fn should_flip(w: &Work, a: usize, b: usize, threshold: Real, max_fold: Real) -> bool {
    let faces = w.edge_faces(a, b);
    if faces.len() != 2 {
        return false;
    }
    let (f0, f1) = if w.directed(faces[0], a, b).is_some() { (faces[0], faces[1]) } else { (faces[1], faces[0]) };
    let (Some(c), Some(d)) = (w.directed(f0, a, b), w.directed(f1, b, a)) else { return false };
    let (n0, n1) = (w.world_normal(&w.faces[f0]), w.world_normal(&w.faces[f1]));
    let cos = n0.dot(&n1) / (n0.norm() * n1.norm()).max(1e-300);
    if cos < max_fold.cos() {
        return false;
    }
    let m = 0.25 * (w.vsize[a] + w.vsize[b] + w.vsize[c] + w.vsize[d]);
    let (ua, ub, uc, ud) = (w.u[a], w.u[b], w.u[c], w.u[d]);
    let (ca, cb, da, db) = (ua - uc, ub - uc, ua - ud, ub - ud);
    let (cross_c, cross_d) = (cross2(&ca, &cb), cross2(&db, &da));
    let s = ca.dot(&(m * cb)) * cross_d + cross_c * db.dot(&(m * da));
    s < -threshold * (cross_c + cross_d)
}

/// Collapse of node(i) onto node(j) along the material edge i–j (Narain 2012 §4.3; ARCSim's
/// `try_edge_collapse`): every vert of node(i) merges into the vert of node(j) beside it, its
/// faces on the edge go and its other faces take that vert, and node(i) is removed. An interior
/// node moves along any edge; a boundary or seam node only along its own boundary or seam, onto
/// its neighbour on that same line, both sides of a seam together, so a boundary stays a
/// boundary and a seam stays closed. `None` when node(i) must stay: a handle, a corner of the
/// pattern (a boundary that turns, a node where seams meet), or when the link condition fails
/// (the result would be non-manifold in material or world space). A node on a crease moves only
/// along it, where it runs straight through the node (ARCSim's labelled edges; ARCSim also keeps
/// every node the input puts on one, viewcloth only its ends, junctions and bends).
pub fn collapse(w: &Work, i: usize, j: usize) -> Option<Op> {
    let (ni, nj) = (w.vnode[i], w.vnode[j]);
    if ni == nj || w.pinned[ni] || w.edge_faces(i, j).is_empty() {
        return None;
    }
    if !w.ncrease[ni].is_empty() && !crease_runs_through(w, i, j) {
        return None;
    }
    let merged = if w.nverts[ni].len() == 1 && w.boundary_neighbours(i).is_empty() {
        vec![(i, j)]
    } else {
        line_partners(w, i, j)?
    };
    let mut opposite_nodes = Vec::new();
    for &(s, t) in &merged {
        let edge_faces = w.edge_faces(s, t);
        // Link condition: the common neighbours of s and t are exactly the edge's opposite corners.
        let mut opp: Vec<usize> = edge_faces.iter().map(|&f| w.opposite(f, s, t)).collect();
        opp.sort_unstable();
        let s_set = w.neighbours(s);
        let common: Vec<usize> = w.neighbours(t).into_iter().filter(|v| s_set.contains(v)).collect();
        if common != opp {
            return None;
        }
        opposite_nodes.extend(opp.iter().map(|&v| w.vnode[v]));
    }
    // The same in world space, where a seam joins panels: no node other than the opposite
    // corners may neighbour both nodes, or an edge would gain a third face.
    opposite_nodes.sort_unstable();
    opposite_nodes.dedup();
    let ni_set = w.node_neighbours(ni);
    if w.node_neighbours(nj).into_iter().filter(|n| ni_set.contains(n)).ne(opposite_nodes) {
        return None;
    }
    let mut op = Op { merged: merged.clone(), collapse_nodes: Some((ni, nj)), ..Default::default() };
    for &(s, t) in &merged {
        op.remove_verts.push(s);
        for &f in &w.vfaces[s] {
            op.remove_faces.push(f);
            if !w.faces[f].contains(&t) {
                op.add_faces.push((w.faces[f].map(|v| if v == s { t } else { v }), w.fdata[f]));
            }
        }
    }
    Some(op)
}

/// Whether vert i's node lies on exactly two creases, one to j's node, running straight
/// through it in material space (so collapsing i into j keeps the crease's line).
fn crease_runs_through(w: &Work, i: usize, j: usize) -> bool {
    let (ni, nj) = (w.vnode[i], w.vnode[j]);
    let c = &w.ncrease[ni];
    if c.len() != 2 || !c.contains(&nj) {
        return false;
    }
    let nk = if c[0] == nj { c[1] } else { c[0] };
    let Some(k) = w.neighbours(i).into_iter().find(|&v| w.vnode[v] == nk) else { return false };
    let (e0, e1) = (w.u[j] - w.u[i], w.u[k] - w.u[i]);
    cross2(&e0, &e1).abs() <= 1e-9 * e0.norm() * e1.norm() && e0.dot(&e1) < 0.0
}

/// For a boundary or seam vert i collapsing along the boundary edge i–j: each vert of node(i)
/// with the vert of node(j) it merges into. Every vert of node(i) must lie on a straight
/// stretch of its panel's boundary between the same two nodes (node(j) and one other), so a
/// corner, a node where seams meet, or an edge off the line gives `None`.
fn line_partners(w: &Work, i: usize, j: usize) -> Option<Vec<(usize, usize)>> {
    let bn = w.boundary_neighbours(i);
    if bn.len() != 2 || !bn.contains(&j) {
        return None;
    }
    let k = if bn[0] == j { bn[1] } else { bn[0] };
    let (nj, nk) = (w.vnode[j], w.vnode[k]);
    if nj == nk {
        return None;
    }
    let mut merged = Vec::with_capacity(w.nverts[w.vnode[i]].len());
    for &s in &w.nverts[w.vnode[i]] {
        let sn = w.boundary_neighbours(s);
        let on = |n: usize| sn.iter().copied().find(|&v| w.vnode[v] == n);
        let (Some(t), Some(r)) = (on(nj), on(nk)) else { return None };
        let (e0, e1) = (w.u[t] - w.u[s], w.u[r] - w.u[s]);
        if sn.len() != 2 || cross2(&e0, &e1).abs() > 1e-9 * e0.norm() * e1.norm() || e0.dot(&e1) >= 0.0 {
            return None;
        }
        merged.push((s, t));
    }
    Some(merged)
}

/// Whether collapsing vert `i` into `j` keeps every edge it creates, j to the other corners of
/// i's faces without j, within `max_len` in the metric: a necessary condition of `collapse_ok`
/// (which checks those edges among others), cheap enough to reject most candidates before
/// `collapse` builds the operation and checks its topology.
pub fn collapse_fits(w: &Work, i: usize, j: usize, max_len: Real) -> bool {
    w.vfaces[i]
        .iter()
        .map(|&f| w.faces[f])
        .filter(|t| !t.contains(&j))
        .all(|t| t.iter().all(|&k| k == i || w.metric_length(j, k) <= max_len))
}

/// Triangle aspect ratio 12√3·A/P² (1 for equilateral) in material space.
pub fn aspect(u: [Vec2; 3]) -> Real {
    let area = 0.5 * cross2(&(u[1] - u[0]), &(u[2] - u[0]));
    let p = (u[1] - u[0]).norm() + (u[2] - u[1]).norm() + (u[0] - u[2]).norm();
    if p == 0.0 {
        return 0.0;
    }
    12.0 * 3f64.sqrt() * area / (p * p)
}

/// Quality checks of a collapse (Narain 2012, §4.3): no new face inverted in material or world
/// space or below the area floor, none falling below `aspect_min` (unless the face it replaces
/// was already worse), and no new edge longer than `max_len` in the metric.
pub fn collapse_ok(w: &Work, op: &Op, aspect_min: Real, max_len: Real, area_floor: Real) -> bool {
    // `collapse` adds, in order, one face for each removed face that does not hold the vert its
    // removed corner merges into.
    let mut added = op.add_faces.iter();
    for &f in &op.remove_faces {
        let old = w.faces[f];
        let Some(&(_, j)) = op.merged.iter().find(|(s, _)| old.contains(s)) else { continue };
        if old.contains(&j) {
            continue;
        }
        let Some(&(t, _)) = added.next() else { return false };
        let u = t.map(|v| op.u(w, v));
        if 0.5 * cross2(&(u[1] - u[0]), &(u[2] - u[0])) <= area_floor {
            return false;
        }
        if w.world_normal(&t).dot(&w.world_normal(&old)) <= 0.0 {
            return false;
        }
        if aspect(u) < aspect_min.min(aspect(old.map(|v| w.u[v]))) {
            return false;
        }
        if t.iter().any(|&k| k != j && w.metric_length(j, k) > max_len) {
            return false;
        }
    }
    true
}
