//! Seams and boundaries through refinement and coarsening (issue 16, item 1): a seamed cylinder
//! refined and coarsened back keeps its seam closed and its outline, and its seam nodes come
//! and go with the sizing instead of accumulating; pattern corners and handles stay.

use std::f64::consts::PI;

use super::*;
use crate::math::{Mat2, Vec2, Vec3};
use crate::mesh::{rectangle, Mesh, Node, NodeId};

const W: f64 = 1.0;
const H: f64 = 0.5;

/// A W × H rectangle (nx × ny quads) rolled into a cylinder of circumference W: the verts of
/// the column u.x = W sit on the nodes of the column u.x = 0 (a seam along the cylinder).
fn cylinder(nx: usize, ny: usize) -> Mesh {
    let rect = rectangle(W, H, nx, ny).unwrap();
    let r = W / (2.0 * PI);
    let mut mesh = Mesh { verts: rect.verts.clone(), faces: rect.faces.clone(), ..Default::default() };
    let mut node_of_vert = vec![0; rect.verts.len()];
    for (v, vert) in rect.verts.iter().enumerate() {
        let (i, j) = (v % (nx + 1), v / (nx + 1));
        if i == nx {
            node_of_vert[v] = node_of_vert[j * (nx + 1)];
            continue;
        }
        let a = vert.u.x / r;
        node_of_vert[v] = mesh.nodes.len();
        mesh.nodes.push(Node {
            x: Vec3::new(r * a.cos(), r * a.sin(), vert.u.y),
            v: Vec3::zeros(),
            a: Vec3::zeros(),
            mass: 0.0,
            cloth: 0,
        });
    }
    for (v, vert) in mesh.verts.iter_mut().enumerate() {
        vert.node = NodeId(node_of_vert[v] as u32);
    }
    mesh.rebuild_topology().unwrap();
    mesh.validate().unwrap();
    mesh
}

fn seam_nodes(m: &Mesh) -> usize {
    let mut verts = vec![0; m.nodes.len()];
    m.verts.iter().for_each(|v| verts[v.node.idx()] += 1);
    verts.iter().filter(|&&k| k > 1).count()
}

/// Every vert on one side of the seam (u.x = 0 or W) has a partner at the same height on the
/// other side on the same node, and nothing else shares a node.
fn assert_seam_closed(m: &Mesh) {
    let side = |x: f64| -> Vec<(f64, usize)> {
        let mut s: Vec<(f64, usize)> =
            m.verts.iter().filter(|v| (v.u.x - x).abs() < 1e-12).map(|v| (v.u.y, v.node.idx())).collect();
        s.sort_by(|a, b| a.0.total_cmp(&b.0));
        s
    };
    let (left, right) = (side(0.0), side(W));
    assert_eq!(left.len(), right.len(), "seam sides hold {} and {} verts", left.len(), right.len());
    for (l, r) in left.iter().zip(&right) {
        assert!((l.0 - r.0).abs() < 1e-12 && l.1 == r.1, "seam open: {l:?} vs {r:?}");
    }
    assert_eq!(seam_nodes(m), left.len(), "a node off the seam holds two verts");
}

/// The material outline is the rectangle: every boundary vert lies on it, its four corners are
/// verts, and the area is W·H.
fn assert_outline_kept(m: &Mesh) {
    let on_outline =
        |u: Vec2| [u.x, W - u.x, u.y, H - u.y].iter().any(|d| d.abs() < 1e-12) && (-1e-12..=W + 1e-12).contains(&u.x);
    let mut pairs = std::collections::HashMap::new();
    for f in &m.faces {
        for k in 0..3 {
            let (a, b) = (f.v[k].idx(), f.v[(k + 1) % 3].idx());
            *pairs.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    for (&(a, b), &n) in &pairs {
        if n == 1 {
            assert!(on_outline(m.verts[a].u) && on_outline(m.verts[b].u), "boundary edge {a}–{b} off the outline");
        }
    }
    for c in [Vec2::new(0.0, 0.0), Vec2::new(W, 0.0), Vec2::new(0.0, H), Vec2::new(W, H)] {
        assert!(m.verts.iter().any(|v| (v.u - c).norm() < 1e-12), "corner {c} lost");
    }
    let area: f64 = (0..m.faces.len()).map(|f| m.material_area(f)).sum();
    assert!((area - W * H).abs() < 1e-9, "area {area}");
}

fn sized(m: &Mesh, h: f64) -> Vec<Mat2> {
    vec![Mat2::identity() / (h * h); m.verts.len()]
}

fn remesh_to(m: &Mesh, h: f64, pinned: Vec<bool>) -> (Finished, RemeshStats) {
    let limits = RemeshLimits { size_min: 0.005, aspect_min: 0.2, coarsen: true, relax_splits: Vec::new() };
    let (done, stats) = remesh(m, sized(m, h), pinned, &[], &[], &[], &[], &limits, &[]).unwrap();
    done.mesh.validate().unwrap();
    (done, stats)
}

#[test]
fn refined_seam_coarsens_back_closed_with_its_outline() {
    // 16 × 4 quads: edges 1/16 around, 1/8 along; a size of 0.14 keeps them (collapses would
    // make edges ≥ 0.125 > 0.9 · 0.14 along the seam).
    let start = cylinder(16, 4);
    let n0 = seam_nodes(&start);
    assert_eq!(n0, 5);
    let (fine, stats) = remesh_to(&start, 0.02, vec![false; start.nodes.len()]);
    assert!(stats.splits > 0);
    let mut mesh = fine.mesh;
    assert_seam_closed(&mesh);
    assert_outline_kept(&mesh);
    let n_fine = seam_nodes(&mesh);
    assert!(n_fine >= 4 * n0, "refining added too few seam nodes: {n0} → {n_fine}");
    for _ in 0..3 {
        mesh = remesh_to(&mesh, 0.14, vec![false; mesh.nodes.len()]).0.mesh;
        assert_seam_closed(&mesh);
        assert_outline_kept(&mesh);
    }
    let n_back = seam_nodes(&mesh);
    eprintln!("seam nodes {n0} → {n_fine} → {n_back}; faces {} → {}", start.faces.len(), mesh.faces.len());
    // Greedy coarsening stops when every two neighbouring seam segments together exceed 0.9·h
    // (else the node between them would go): at most twice the 4 segments the size needs.
    assert!(n_back < 2 * n0, "seam nodes {n0} → {n_fine} (refined) → {n_back} (coarsened)");
    assert!(mesh.faces.len() <= start.faces.len() * 3 / 2, "faces {} → {}", start.faces.len(), mesh.faces.len());
}

#[test]
fn pattern_corners_and_handles_survive_any_coarsening() {
    let start = cylinder(16, 4);
    let (fine, _) = remesh_to(&start, 0.02, vec![false; start.nodes.len()]);
    let mut mesh = fine.mesh;
    // Pin the seam node nearest mid-height.
    let mid = (0..mesh.verts.len())
        .filter(|&v| mesh.verts[v].u.x == 0.0)
        .min_by(|&a, &b| (mesh.verts[a].u.y - H / 2.0).abs().total_cmp(&(mesh.verts[b].u.y - H / 2.0).abs()))
        .unwrap();
    let mut handle = mesh.verts[mid].node.idx();
    let target = mesh.nodes[handle].x;
    for _ in 0..4 {
        // A size far above the cylinder's: everything that may go goes.
        let mut pinned = vec![false; mesh.nodes.len()];
        pinned[handle] = true;
        let done = remesh_to(&mesh, 10.0, pinned).0;
        handle = done.node_map[handle].expect("handle node removed");
        mesh = done.mesh;
        assert_eq!(mesh.nodes[handle].x, target);
        assert_seam_closed(&mesh);
        assert_outline_kept(&mesh);
    }
    // Left: the two seam corners (bottom and top) and the handle.
    assert_eq!(seam_nodes(&mesh), 3, "seam nodes left");
}
