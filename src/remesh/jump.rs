//! Keeps remeshing from making the cloth the camera sees jump (issue 19, item 5): a flip or a
//! collapse replaces some faces by others over the same piece of material, and where the new
//! surface differs from the one the remesh started from, a point of the cloth moves
//! (`sizing::remesh_jump` measures it on screen). Both surfaces are linear on each of their
//! triangles, so their difference is linear on each cell of the two triangulations laid over
//! each other in material space, and it is largest at a corner of such a cell: a corner of a new
//! face, a corner of a face of the start mesh inside it, or a point where the edges of the two
//! cross. The operation is refused when a new face moves the surface farther there than the
//! smallest bound (`Work::jump`) of the nodes of the faces it removes. Judged against the start
//! mesh, not against the surface the operations before it left, moves on one spot do not add up.

use crate::math::{cross2, Real, Vec2, Vec3};

use super::ops::Op;
use super::work::Work;
use crate::resample::locate::{by_group, Locator};

/// A face over material corners `u` with world corners `x`.
type Tri = ([Vec2; 3], [Vec3; 3]);

/// Barycentric coordinates of `p` in `u`, when inside (to a relative slack).
fn inside(u: &[Vec2; 3], p: &Vec2) -> Option<[Real; 3]> {
    let d = cross2(&(u[1] - u[0]), &(u[2] - u[0]));
    if d == 0.0 {
        return None;
    }
    let l0 = cross2(&(u[1] - p), &(u[2] - p)) / d;
    let l1 = cross2(&(u[2] - p), &(u[0] - p)) / d;
    let l2 = 1.0 - l0 - l1;
    const SLACK: Real = 1e-9;
    (l0 >= -SLACK && l1 >= -SLACK && l2 >= -SLACK).then_some([l0, l1, l2])
}

/// The surface `tris` at material point `p`, if a face holds it.
fn at(tris: &[Tri], p: &Vec2) -> Option<Vec3> {
    tris.iter().find_map(|(u, x)| inside(u, p).map(|b| x[0] * b[0] + x[1] * b[1] + x[2] * b[2]))
}

/// Where segments a0–a1 and b0–b1 cross (interiors), if they do.
fn crossing(a0: &Vec2, a1: &Vec2, b0: &Vec2, b1: &Vec2) -> Option<Vec2> {
    let (da, db) = (a1 - a0, b1 - b0);
    let den = cross2(&da, &db);
    if den == 0.0 {
        return None;
    }
    let s = cross2(&(b0 - a0), &db) / den;
    let t = cross2(&(b0 - a0), &da) / den;
    (s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0).then(|| a0 + da * s)
}

/// The farthest `new` moves a point of the surface `old` covers, both over the same material
/// (the module doc's sample points).
pub fn largest_move(old: &[Tri], new: &[Tri]) -> Real {
    new.iter().map(|t| face_move(old, t)).fold(0.0, Real::max)
}

/// The farthest the face `t` lies from the surface `old` over its material (where `old` covers
/// it).
fn face_move(old: &[Tri], t: &Tri) -> Real {
    let (un, xn) = t;
    let mut points: Vec<Vec2> = un.to_vec();
    for (uo, _) in old {
        points.extend(uo.iter().filter(|p| inside(un, p).is_some()));
        for k in 0..3 {
            for l in 0..3 {
                points.extend(crossing(&uo[k], &uo[(k + 1) % 3], &un[l], &un[(l + 1) % 3]));
            }
        }
    }
    points
        .iter()
        .filter_map(|p| {
            let b = inside(un, p)?;
            Some((at(old, p)? - (xn[0] * b[0] + xn[1] * b[1] + xn[2] * b[2])).norm())
        })
        .fold(0.0, Real::max)
}

/// The surface a remesh starts from, per cloth, for `too_far`.
#[derive(Clone, Debug)]
pub struct Start {
    tris: Vec<Tri>,
    /// Per cloth: its faces (indices into `tris`) and a locator over their material triangles.
    cloths: Vec<Option<(Vec<usize>, Locator)>>,
}

impl Start {
    /// The faces of `w` as they are (before any operation).
    pub fn new(w: &Work) -> Start {
        let alive: Vec<usize> = (0..w.faces.len()).filter(|&f| w.falive[f]).collect();
        let tris: Vec<Tri> =
            alive.iter().map(|&f| w.faces[f]).map(|t| (t.map(|v| w.u[v]), t.map(|v| w.x[w.vnode[v]]))).collect();
        let cloths =
            by_group(tris.iter().enumerate().map(|(k, t)| (k, t.0, w.cloth[w.vnode[w.faces[alive[k]][0]]] as usize)));
        Start { tris, cloths }
    }

    /// The start faces of cloth `c` whose material boxes may overlap `u`'s.
    fn near(&self, c: usize, u: &[Vec2; 3]) -> Vec<Tri> {
        let Some(Some((faces, loc))) = self.cloths.get(c) else { return Vec::new() };
        let (lo, hi) = (u[0].inf(&u[1]).inf(&u[2]), u[0].sup(&u[1]).sup(&u[2]));
        loc.near_box(&lo, &hi).into_iter().map(|k| self.tris[faces[k]]).collect()
    }
}

/// Whether `op` (a flip or collapse, before it is applied) moves the surface farther from where
/// the remesh started than the bound of the nodes of the faces it removes.
pub fn too_far(w: &Work, start: &Start, op: &Op) -> bool {
    if w.jump.is_empty() {
        return false;
    }
    let bound =
        op.remove_faces.iter().flat_map(|&f| w.faces[f]).map(|v| w.jump[w.vnode[v]]).fold(Real::INFINITY, Real::min);
    if bound == Real::INFINITY {
        return false;
    }
    // The op's verts are existing ones (flips and collapses add none), a merged vert's node
    // being the one it merges into.
    let node = |v: usize| op.merged.iter().find(|(s, _)| *s == v).map_or(w.vnode[v], |&(_, t)| w.vnode[t]);
    op.add_faces.iter().any(|(t, _)| {
        let new: Tri = (t.map(|v| op.u(w, v)), t.map(|v| w.x[node(v)]));
        face_move(&start.near(w.cloth[node(t[0])] as usize, &new.0), &new) > bound
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat2;
    use crate::mesh::{rectangle, Mesh};
    use crate::remesh::{remesh, RemeshLimits};

    /// The farthest a material point at a node of either mesh lies from the other mesh's
    /// surface at the same material point (world space).
    fn node_moves(a: &Mesh, b: &Mesh) -> Real {
        let one_way = |a: &Mesh, b: &Mesh| {
            let tri = |m: &Mesh, f: usize| m.faces[f].v.map(|v| m.verts[v.idx()].u);
            let loc = Locator::from_triangles((0..b.faces.len()).map(|f| tri(b, f)).collect());
            a.verts
                .iter()
                .map(|v| {
                    let hit = loc.locate(&v.u);
                    let x = b.face_nodes(hit.triangle).map(|n| b.nodes[n].x);
                    let there = x[0] * hit.bary[0] + x[1] * hit.bary[1] + x[2] * hit.bary[2];
                    (a.nodes[v.node.idx()].x - there).norm()
                })
                .fold(0.0, Real::max)
        };
        one_way(a, b).max(one_way(b, a))
    }

    #[test]
    fn a_bounded_remesh_keeps_a_curved_sheet_within_the_bound() {
        // A 1 m sheet on 16 × 16 quads rolled onto a cylinder of radius 0.5 m, coarsened to
        // 25 cm edges: a chord that long stands 1.6 cm off the arc.
        let mut mesh = rectangle(1.0, 1.0, 16, 16).unwrap();
        let r = 0.5;
        for n in &mut mesh.nodes {
            let (u, v) = (n.x.x, n.x.y);
            n.x = Vec3::new(r * (u / r).sin(), v, r * (1.0 - (u / r).cos()));
        }
        let vsize = vec![Mat2::identity() / (0.25 * 0.25); mesh.verts.len()];
        let limits = RemeshLimits { size_min: 0.01, aspect_min: 0.2, coarsen: true, relax_splits: Vec::new() };
        let run = |jump: &[Real]| {
            let pinned = vec![false; mesh.nodes.len()];
            let (done, stats) = remesh(&mesh, vsize.clone(), pinned, &[], &[], &[], &[], &limits, jump).unwrap();
            done.mesh.validate().unwrap();
            (done.mesh, stats)
        };
        let (free, free_stats) = run(&[]);
        let bound = 0.001;
        let (held, held_stats) = run(&vec![bound; mesh.nodes.len()]);
        assert!(node_moves(&mesh, &free) > 5.0 * bound, "unbounded: {}", node_moves(&mesh, &free));
        assert!(node_moves(&mesh, &held) <= bound * (1.0 + 1e-9), "bounded: {}", node_moves(&mesh, &held));
        // It still coarsens, only less.
        assert!(held_stats.collapses > 0 && held.faces.len() < mesh.faces.len(), "{held_stats:?}");
        assert!(held.faces.len() > free.faces.len(), "{} vs {}", held.faces.len(), free.faces.len());
        assert!(free_stats.collapses > held_stats.collapses);
    }

    fn v2(x: Real, y: Real) -> Vec2 {
        Vec2::new(x, y)
    }

    #[test]
    fn a_flip_of_a_bent_quad_moves_the_diagonals_crossing_by_the_bend() {
        // Unit square a(0,0) b(1,1) c(1,0) d(0,1); the a–b diagonal's ends raised 1 cm.
        let (ua, ub, uc, ud) = (v2(0.0, 0.0), v2(1.0, 1.0), v2(1.0, 0.0), v2(0.0, 1.0));
        let x = |u: Vec2, h: Real| Vec3::new(u.x, u.y, h);
        let (xa, xb, xc, xd) = (x(ua, 0.01), x(ub, 0.01), x(uc, 0.0), x(ud, 0.0));
        let old = [([ua, uc, ub], [xa, xc, xb]), ([ua, ub, ud], [xa, xb, xd])];
        let new = [([ua, uc, ud], [xa, xc, xd]), ([uc, ub, ud], [xc, xb, xd])];
        // At the centre the old surface is at 1 cm (on a–b), the new at 0 (on c–d).
        assert!((largest_move(&old, &new) - 0.01).abs() < 1e-12);
        // A planar quad flips without a move.
        let (xa, xb) = (x(ua, 0.0), x(ub, 0.0));
        let old = [([ua, uc, ub], [xa, xc, xb]), ([ua, ub, ud], [xa, xb, xd])];
        let new = [([ua, uc, ud], [xa, xc, xd]), ([uc, ub, ud], [xc, xb, xd])];
        assert_eq!(largest_move(&old, &new), 0.0);
    }

    #[test]
    fn a_collapse_moves_the_removed_node_onto_the_new_faces() {
        // A fan of four faces around a centre node raised 2 cm; collapsed onto corner (1, 0),
        // the centre's material point lies on the new faces at height 0.
        let c = v2(0.5, 0.5);
        let corners = [v2(0.0, 0.0), v2(1.0, 0.0), v2(1.0, 1.0), v2(0.0, 1.0)];
        let x = |u: Vec2, h: Real| Vec3::new(u.x, u.y, h);
        let old: Vec<Tri> = (0..4)
            .map(|k| {
                ([corners[k], corners[(k + 1) % 4], c], [x(corners[k], 0.0), x(corners[(k + 1) % 4], 0.0), x(c, 0.02)])
            })
            .collect();
        let new: Vec<Tri> = vec![
            ([corners[1], corners[2], corners[3]], [x(corners[1], 0.0), x(corners[2], 0.0), x(corners[3], 0.0)]),
            ([corners[1], corners[3], corners[0]], [x(corners[1], 0.0), x(corners[3], 0.0), x(corners[0], 0.0)]),
        ];
        assert!((largest_move(&old, &new) - 0.02).abs() < 1e-12);
    }
}
