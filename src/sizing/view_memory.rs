//! Smoothed coarsening (Koh, Narain & O'Brien 2015, "anticipative refinement and smoothed
//! coarsening"): a face's view factor may fall by at most Δt / T_c per remesh, T_c the cloth's
//! `coarsen_time`, whatever makes it fall.
//!
//! The lookahead window (eqs. 6–9, `view::lookahead`) already smooths what the *camera* does:
//! its past samples keep a face refined, with weights falling linearly over the window, after
//! the camera has turned away. It cannot smooth what the *cloth* does, because every sample
//! sees the current geometry: a garment that walks out of a still frame, or turns its back,
//! drops from μ = 1 to μ_out at the next remesh, and the mesh pops coarse in one frame. So each
//! node remembers the largest view factor of its faces at the last remesh, and a face's μ is
//! kept at or above the smallest of its nodes' memories less Δt / T_c: a face seen at μ = 1
//! falls to μ_out over T_c(1 − μ_out), as it does under the window's backward weights (eq. 8)
//! when the camera moves. Refinement is never delayed (the floor only raises μ). The smallest
//! of the nodes, not their mean: a face beside a well-seen region shares nodes with it, and a
//! mean would hold it up for good and spread the view outward ring by ring (the view test's
//! pan kept 1.9× finer faces out of frame that way); the smallest is, to within faces whose
//! every node touches a better-seen face, the face's own last μ.

use crate::math::PAR_GRAIN;
use rayon::prelude::*;

use crate::math::Real;
use crate::mesh::Mesh;

use super::FaceView;

/// Raises every face's view factor to its floor: the least of its nodes' memory less `drop`
/// (per material: Δt / T_c, infinite when smoothing is off). `memory` is empty before the
/// first remesh (no floor).
pub fn apply_floor(mesh: &Mesh, views: &mut [Option<FaceView>], memory: &[Real], drop: &[Real]) {
    if memory.len() != mesh.nodes.len() {
        return;
    }
    views.par_iter_mut().enumerate().with_min_len(PAR_GRAIN).for_each(|(f, view)| {
        let Some(view) = view else { return };
        let d = drop.get(mesh.faces[f].material as usize).copied().unwrap_or(Real::INFINITY);
        let ids = mesh.face_nodes(f);
        let floor = ids.iter().map(|&n| memory[n]).fold(Real::INFINITY, Real::min) - d;
        view.mu = view.mu.max(floor.min(1.0));
    });
}

/// Per node, the largest view factor of its faces (0 for a node of no view-dependent face).
pub fn remember(mesh: &Mesh, views: &[Option<FaceView>]) -> Vec<Real> {
    let mut memory = vec![0.0; mesh.nodes.len()];
    for (f, view) in views.iter().enumerate() {
        let Some(view) = view else { continue };
        for n in mesh.face_nodes(f) {
            memory[n] = Real::max(memory[n], view.mu);
        }
    }
    memory
}

/// Carries node memory through a remesh: a node that survives keeps its value (`node_map`:
/// old id → new id); a node a split created takes the mean of its neighbours that have one
/// (the edge's end nodes, or, between two new nodes, the values those get first).
pub fn carry(memory: &[Real], node_map: &[Option<usize>], mesh: &Mesh) -> Vec<Real> {
    let n = mesh.nodes.len();
    let mut value: Vec<Option<Real>> = vec![None; n];
    for (old, new) in node_map.iter().enumerate() {
        if let (Some(new), Some(&m)) = (new, memory.get(old)) {
            value[*new] = Some(m);
        }
    }
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); n];
    for f in 0..mesh.faces.len() {
        let ids = mesh.face_nodes(f);
        for k in 0..3 {
            let (a, b) = (ids[k], ids[(k + 1) % 3]);
            if !neighbours[a].contains(&b) {
                neighbours[a].push(b);
                neighbours[b].push(a);
            }
        }
    }
    // Passes in node order, each from the values of the previous pass only, so the result does
    // not depend on the order nodes are visited in.
    while value.iter().any(Option::is_none) {
        let filled: Vec<(usize, Real)> = (0..n)
            .filter(|&i| value[i].is_none())
            .filter_map(|i| {
                let known: Vec<Real> = neighbours[i].iter().filter_map(|&j| value[j]).collect();
                (!known.is_empty()).then(|| (i, known.iter().sum::<Real>() / known.len() as Real))
            })
            .collect();
        if filled.is_empty() {
            break;
        }
        for (i, m) in filled {
            value[i] = Some(m);
        }
    }
    value.into_iter().map(|v| v.unwrap_or(0.0)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::rectangle;

    fn seen(mesh: &Mesh, mu: Real) -> Vec<Option<FaceView>> {
        vec![Some(FaceView { mu, size_min: 0.01, visible: 1.0 }); mesh.faces.len()]
    }

    #[test]
    fn a_face_that_leaves_the_view_falls_by_at_most_the_drop_per_remesh() {
        let mesh = rectangle(1.0, 1.0, 4, 4).unwrap();
        let mut memory = remember(&mesh, &seen(&mesh, 1.0));
        let drop = [0.1];
        let mut mus = Vec::new();
        for _ in 0..12 {
            let mut views = seen(&mesh, 0.1);
            apply_floor(&mesh, &mut views, &memory, &drop);
            mus.push(views[0].unwrap().mu);
            memory = remember(&mesh, &views);
        }
        for (k, mu) in mus.iter().enumerate() {
            let expected = (1.0 - 0.1 * (k + 1) as Real).max(0.1);
            assert!((mu - expected).abs() < 1e-12, "remesh {k}: μ {mu}, expected {expected}");
        }
    }

    #[test]
    fn refinement_is_not_delayed_and_no_floor_before_the_first_remesh() {
        let mesh = rectangle(1.0, 1.0, 2, 2).unwrap();
        let memory = remember(&mesh, &seen(&mesh, 0.1));
        let mut views = seen(&mesh, 1.0);
        apply_floor(&mesh, &mut views, &memory, &[0.1]);
        assert!(views.iter().all(|v| v.unwrap().mu == 1.0));
        let mut views = seen(&mesh, 0.1);
        apply_floor(&mesh, &mut views, &[], &[0.1]);
        assert!(views.iter().all(|v| v.unwrap().mu == 0.1), "no memory yet, no floor");
        let mut views = seen(&mesh, 0.1);
        apply_floor(&mesh, &mut views, &remember(&mesh, &seen(&mesh, 1.0)), &[Real::INFINITY]);
        assert!(views.iter().all(|v| v.unwrap().mu == 0.1), "smoothing off");
    }

    #[test]
    fn split_nodes_take_their_neighbours_memory() {
        // Old mesh 2 × 1 quads (6 nodes), new mesh 4 × 1 (10 nodes): old node (i, j) is new
        // node (2i, j); the new nodes in between are created by splits.
        let old = rectangle(2.0, 1.0, 2, 1).unwrap();
        let new = rectangle(2.0, 1.0, 4, 1).unwrap();
        let map: Vec<Option<usize>> = (0..old.nodes.len()).map(|k| Some((k / 3) * 5 + 2 * (k % 3))).collect();
        let carried = carry(&vec![0.7; old.nodes.len()], &map, &new);
        assert!(carried.iter().all(|&m| m == 0.7), "{carried:?}");
        // A field rising along x: survivors keep theirs, split nodes lie between their
        // neighbours' values.
        let memory: Vec<Real> = old.nodes.iter().map(|n| 0.1 + 0.4 * n.x.x).collect();
        let carried = carry(&memory, &map, &new);
        for (k, &m) in memory.iter().enumerate() {
            assert_eq!(carried[map[k].unwrap()], m);
        }
        for (k, m) in carried.iter().enumerate() {
            let x = new.nodes[k].x.x;
            let (lo, hi) = (0.1 + 0.4 * (x - 0.5).max(0.0), 0.1 + 0.4 * (x + 0.5).min(2.0));
            assert!(*m >= lo - 1e-12 && *m <= hi + 1e-12, "node {k} at x = {x}: {m} not in [{lo}, {hi}]");
        }
    }
}
