//! Creases through refinement and coarsening (issue 16: ARCSim's labelled edges, which dart.json's
//! folded paper uses): a crease stays a line of edges, is never flipped or cut across, coarsens
//! along itself, and keeps its ends and junctions.

use super::*;
use crate::math::{Mat2, Vec3};
use crate::mesh::{rectangle, Mesh, NodeId};

const N: usize = 8;

/// A unit square of N × N quads folded by `angle` (radians) along the crease u.x = 1/2, which
/// is labelled, with a second, flat crease along u.y = 1/2 for u.x ≤ 1/2 (a T junction).
fn folded(angle: f64) -> Mesh {
    let mut m = rectangle(1.0, 1.0, N, N).unwrap();
    for n in &mut m.nodes {
        if n.x.x > 0.5 {
            let d = n.x.x - 0.5;
            n.x = Vec3::new(0.5 + d * angle.cos(), n.x.y, d * angle.sin());
        }
    }
    let id = |i: usize, j: usize| NodeId((j * (N + 1) + i) as u32);
    m.creases = (0..N)
        .map(|j| [id(N / 2, j), id(N / 2, j + 1)])
        .chain((0..N / 2).map(|i| [id(i, N / 2), id(i + 1, N / 2)]))
        .collect();
    m.creases.sort_unstable();
    m.validate().unwrap();
    m
}

fn remesh_to(m: &Mesh, h: f64) -> Finished {
    let limits = RemeshLimits { size_min: 0.005, aspect_min: 0.2, coarsen: true, relax_splits: Vec::new() };
    let vsize = vec![Mat2::identity() / (h * h); m.verts.len()];
    let (done, _) = remesh(m, vsize, vec![false; m.nodes.len()], &[], &[], &[], &[], &limits, &[]).unwrap();
    done.mesh.validate().unwrap();
    done
}

/// No face has corners on both sides of the fold line u.x = 1/2 (the fold stays on edges).
fn assert_fold_on_edges(m: &Mesh) {
    for f in 0..m.faces.len() {
        let u = m.face_uv(f);
        let (lo, hi) = (u.iter().any(|u| u.x < 0.5 - 1e-12), u.iter().any(|u| u.x > 0.5 + 1e-12));
        assert!(!(lo && hi), "face {f} crosses the fold: {u:?}");
    }
}

/// The creases cover exactly the two labelled lines, end to end.
fn assert_creases_cover_the_lines(m: &Mesh) {
    let u = |n: NodeId| m.verts.iter().find(|v| v.node == n).unwrap().u;
    let (mut vertical, mut horizontal) = (0.0, 0.0);
    for &[a, b] in &m.creases {
        let (ua, ub) = (u(a), u(b));
        if (ua.x - 0.5).abs() < 1e-12 && (ub.x - 0.5).abs() < 1e-12 {
            vertical += (ub.y - ua.y).abs();
        } else {
            assert!((ua.y - 0.5).abs() < 1e-12 && (ub.y - 0.5).abs() < 1e-12, "crease {ua} – {ub} off both lines");
            assert!(ua.x <= 0.5 + 1e-12 && ub.x <= 0.5 + 1e-12, "crease {ua} – {ub} beyond the junction");
            horizontal += (ub.x - ua.x).abs();
        }
    }
    assert!(
        (vertical - 1.0).abs() < 1e-9 && (horizontal - 0.5).abs() < 1e-9,
        "creases cover {vertical} and {horizontal}"
    );
}

#[test]
fn a_fold_on_a_crease_stays_on_edges_through_refinement_and_coarsening() {
    // 20°: flat enough that flips across the fold are allowed (`MAX_FLIP_FOLD`), so only the
    // crease keeps them off it.
    let start = folded(20f64.to_radians());
    let fine = remesh_to(&start, 0.03);
    assert!(fine.mesh.faces.len() > 4 * start.faces.len(), "refined to {} faces only", fine.mesh.faces.len());
    assert_fold_on_edges(&fine.mesh);
    assert_creases_cover_the_lines(&fine.mesh);
    let on_creases = |m: &Mesh| {
        let mut nodes: Vec<NodeId> = m.creases.iter().flatten().copied().collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes.len()
    };
    let refined = on_creases(&fine.mesh);
    let mut mesh = fine.mesh;
    for _ in 0..3 {
        mesh = remesh_to(&mesh, 0.6).mesh;
        assert_fold_on_edges(&mesh);
        assert_creases_cover_the_lines(&mesh);
    }
    let coarse = on_creases(&mesh);
    eprintln!(
        "crease nodes {} → {refined} → {coarse}; faces {} → {}",
        on_creases(&start),
        start.faces.len(),
        mesh.faces.len()
    );
    assert!(refined > 2 * on_creases(&start), "refining added too few crease nodes: {refined}");
    // Kept: the three ends and the junction; a straight crease's inner nodes may go.
    assert!(
        coarse < on_creases(&start),
        "crease nodes {} → {refined} (refined) → {coarse} (coarsened)",
        on_creases(&start)
    );
    let u = |n: usize| mesh.verts.iter().find(|v| v.node.idx() == n).unwrap().u;
    let crease_points: Vec<_> = mesh.creases.iter().flatten().map(|n| u(n.idx())).collect();
    for p in [[0.5, 0.0], [0.5, 1.0], [0.0, 0.5], [0.5, 0.5]] {
        assert!(
            crease_points.iter().any(|q| (q.x - p[0]).abs() < 1e-12 && (q.y - p[1]).abs() < 1e-12),
            "crease point {p:?} lost"
        );
    }
}

#[test]
fn without_its_crease_the_same_fold_is_cut_across() {
    // The property the crease test asserts is not a property of the remesher alone.
    let mut start = folded(20f64.to_radians());
    start.creases.clear();
    let mut mesh = remesh_to(&start, 0.03).mesh;
    for _ in 0..3 {
        mesh = remesh_to(&mesh, 0.6).mesh;
    }
    let crossing = (0..mesh.faces.len())
        .filter(|&f| {
            let u = mesh.face_uv(f);
            u.iter().any(|u| u.x < 0.5 - 1e-12) && u.iter().any(|u| u.x > 0.5 + 1e-12)
        })
        .count();
    assert!(crossing > 0, "no face crosses the unlabelled fold");
}
