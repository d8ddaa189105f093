//! Remesher properties: validity after every operation, metric-length bound, stability on a
//! flat sheet, refinement along a fold, area preservation.

use super::ops;
use super::work::Work;
use super::*;
use crate::math::test_rng::Rng;
use crate::math::{Mat2, Vec2, Vec3};
use crate::mesh::{rectangle, Mesh};
use crate::sizing::{face_metrics, vertex_metrics, Combine, SizingParams};

fn total_area(m: &Mesh) -> f64 {
    (0..m.faces.len()).map(|f| m.material_area(f)).sum()
}

fn uniform(mesh: &Mesh, h: f64) -> Vec<Mat2> {
    vec![Mat2::identity() / (h * h); mesh.verts.len()]
}

fn limits(size_min: f64) -> RemeshLimits {
    RemeshLimits { size_min, aspect_min: 0.2, coarsen: true, relax_splits: Vec::new() }
}

#[test]
fn random_operations_keep_the_mesh_valid() {
    let mut rng = Rng(11);
    for trial in 0..6 {
        let mut mesh = rectangle(1.0, 0.7, 3 + trial, 4).unwrap();
        // Jitter interior points so the mesh is irregular.
        for (i, v) in mesh.verts.iter_mut().enumerate() {
            let (x, y) = (v.u.x, v.u.y);
            if x > 1e-9 && x < 1.0 - 1e-9 && y > 1e-9 && y < 0.7 - 1e-9 {
                v.u += Vec2::new(0.03 * (rng.uniform() - 0.5), 0.03 * (rng.uniform() - 0.5));
            }
            let u = v.u;
            mesh.nodes[i].x = Vec3::new(u.x, u.y, 0.05 * (3.0 * u.x).sin());
        }
        let area0 = total_area(&mesh);
        let mut pinned = vec![false; mesh.nodes.len()];
        pinned[0] = true;
        let mut w = Work::new(&mesh, uniform(&mesh, 0.2), pinned, &[], &[], &[]);
        for _ in 0..300 {
            let edges = w.edges();
            let (a, b) = edges[rng.below(edges.len())];
            let op = match rng.below(3) {
                0 => ops::split(&w, a, b),
                1 => ops::flip(&w, a, b),
                _ => ops::collapse(&w, a, b).filter(|op| ops::collapse_ok(&w, op, 0.05, 10.0, 1e-12)),
            };
            if let Some(op) = op {
                op.apply(&mut w);
                let done = w.finish(mesh.nodes.len()).unwrap();
                done.mesh.validate().unwrap();
                let a = total_area(&done.mesh);
                assert!((a - area0).abs() < 1e-9 * area0, "area {a} vs {area0}");
                assert!(done.node_map[0].is_some(), "pinned node removed");
            }
        }
    }
}

#[test]
fn full_remesh_meets_the_metric() {
    let mesh = rectangle(1.0, 1.0, 4, 4).unwrap();
    // Anisotropic: fine along x near x = 0.5, coarse elsewhere.
    let vsize: Vec<Mat2> = mesh
        .verts
        .iter()
        .map(|v| {
            let d = (v.u.x - 0.5).abs();
            let hx = 0.02 + 0.3 * d;
            Mat2::new(1.0 / (hx * hx), 0.0, 0.0, 1.0 / (0.15 * 0.15))
        })
        .collect();
    let (done, stats) =
        remesh(&mesh, vsize, vec![false; mesh.nodes.len()], &[], &[], &[], &[], &limits(0.02), &[]).unwrap();
    done.mesh.validate().unwrap();
    assert!(stats.splits > 0);
    // Re-evaluate the same field on the new verts and check every edge.
    let field = |u: Vec2| {
        let hx = 0.02 + 0.3 * (u.x - 0.5).abs();
        Mat2::new(1.0 / (hx * hx), 0.0, 0.0, 1.0 / (0.15 * 0.15))
    };
    let mut worst: f64 = 0.0;
    for f in 0..done.mesh.faces.len() {
        let uv = done.mesh.face_uv(f);
        for k in 0..3 {
            let (a, b) = (uv[k], uv[(k + 1) % 3]);
            let e = b - a;
            let m = 0.5 * (field(a) + field(b));
            worst = worst.max(e.dot(&(m * e)).sqrt());
        }
    }
    // Interpolated sizing of split verts differs slightly from the exact field.
    assert!(worst < 1.25, "worst metric edge length {worst}");
    assert!((total_area(&done.mesh) - 1.0).abs() < 1e-9);
}

#[test]
fn flat_sheet_at_rest_with_its_own_size_is_left_alone() {
    let mesh = rectangle(1.0, 1.0, 10, 10).unwrap();
    // Edges are 0.1 (axis) and 0.141 (diagonal): a sizing of 0.16 keeps them all under 1 and
    // collapses would make edges ≥ 0.2 > 0.9 · 0.16.
    let (done, stats) =
        remesh(&mesh, uniform(&mesh, 0.16), vec![false; mesh.nodes.len()], &[], &[], &[], &[], &limits(0.01), &[])
            .unwrap();
    assert_eq!((stats.splits, stats.collapses), (0, 0), "{stats:?}");
    assert_eq!(done.mesh.nodes.len(), mesh.nodes.len());
    for (i, n) in mesh.nodes.iter().enumerate() {
        let j = done.node_map[i].unwrap();
        assert!((done.mesh.nodes[j].x - n.x).norm() <= 1e-9);
    }
}

fn sizing_params() -> SizingParams {
    SizingParams {
        refine_angle: Some(0.3),
        refine_compression: None,
        refine_velocity: None,
        refine_obstacle: false,
        size_min: 0.005,
        size_max: 0.2,
        aspect_min: 0.2,
        combine: Combine::Max,
    }
}

#[test]
fn sharp_fold_refines_along_the_fold_only() {
    // A sheet folded by 90° along x = 0.5 (a crease), remeshed a few times as it would be over
    // frames: faces at the fold end up ≥ 10× smaller than far from it.
    let mut mesh = rectangle(1.0, 1.0, 8, 8).unwrap();
    let fold = |mesh: &mut Mesh| {
        for v in 0..mesh.verts.len() {
            let u = mesh.verts[v].u;
            let n = mesh.verts[v].node.idx();
            mesh.nodes[n].x = if u.x <= 0.5 { Vec3::new(u.x, u.y, 0.0) } else { Vec3::new(0.5, u.y, u.x - 0.5) };
        }
    };
    fold(&mut mesh);
    let p = sizing_params();
    for _ in 0..4 {
        let vs = vertex_metrics(&mesh, &face_metrics(&mesh, &[Some(p.clone())], &[], &[], &[]));
        let (done, _) =
            remesh(&mesh, vs, vec![false; mesh.nodes.len()], &[], &[], &[], &[], &limits(p.size_min), &[]).unwrap();
        mesh = done.mesh;
        fold(&mut mesh);
    }
    mesh.validate().unwrap();
    let (mut near, mut far) = (Vec::new(), Vec::new());
    for f in 0..mesh.faces.len() {
        let c = mesh.face_uv(f).iter().fold(Vec2::zeros(), |a, u| a + u) / 3.0;
        let a = mesh.material_area(f);
        if (c.x - 0.5).abs() < 0.02 {
            near.push(a);
        } else if (c.x - 0.5).abs() > 0.3 {
            far.push(a);
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(!near.is_empty() && !far.is_empty());
    assert!(mean(&far) >= 10.0 * mean(&near), "near {} far {}", mean(&near), mean(&far));
    assert!((total_area(&mesh) - 1.0).abs() < 1e-9);
}

/// A node split between two nodes of one group joins it (ARCSim's `combine_label`, which
/// grows a circle handle's ring), one split between different groups or a grouped and an
/// ungrouped node joins none; groups survive the compaction.
#[test]
fn splits_between_nodes_of_a_group_join_it() {
    let mesh = rectangle(1.0, 1.0, 2, 2).unwrap();
    // The bottom row (nodes 0, 1, 2) is group 7, node 3 (left, middle row) group 5.
    let mut groups = vec![0; mesh.nodes.len()];
    groups[..3].iter_mut().for_each(|g| *g = 7);
    groups[3] = 5;
    let fine = vec![Mat2::identity() / (0.2 * 0.2); mesh.verts.len()];
    let pinned = vec![true; mesh.nodes.len()];
    let (done, stats) = remesh(&mesh, fine, pinned, &groups, &[], &[], &[], &limits(0.05), &[]).unwrap();
    assert!(stats.splits > 0);
    assert_eq!(done.groups.len(), done.mesh.nodes.len());
    for (old, g) in groups.iter().enumerate() {
        assert_eq!(done.groups[done.node_map[old].unwrap()], *g, "old node {old}");
    }
    for (n, node) in done.mesh.nodes.iter().enumerate() {
        let on_bottom = node.x.y.abs() < 1e-12;
        let is_old = done.node_map.contains(&Some(n));
        if !is_old {
            assert_eq!(done.groups[n], if on_bottom { 7 } else { 0 }, "new node {n} at {:?}", node.x);
        }
    }
    assert!(done.mesh.nodes.iter().filter(|n| n.x.y.abs() < 1e-12).count() > 3, "the bottom edge was not split");
}
