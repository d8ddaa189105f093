//! `--auto`: the fixed mesh made from the run. Each face of each frame defines the metric in
//! which its own edges have length one (its sizing, as the remesher left it); the tensor max of
//! those metrics over every frame, at a point, is the finest the run ever was there. The first
//! frame's mesh is refined (`remesh`, splits and flips only) until its edges are under one in
//! that metric, looking the metric up again at the new vertices until nothing splits.

use super::locate::Locator;
use super::{FixedMesh, ResampleError, RunFrame};
use crate::math::{Mat2, Real, Vec2, Vec3};
use crate::mesh::{Face, Mesh, Node, NodeId, Vert, VertId};
use crate::remesh::{remesh, RemeshLimits};
use crate::sizing::tensor_max::tensor_max;

/// Metrics are shrunk by this (edges up to 1/0.95 of a run's face), so the first frame's own
/// faces, exactly one in their own metric, do not split on rounding.
const SLACK: Real = 0.95 * 0.95;
/// Rounds of look-up and refinement.
const ROUNDS: usize = 12;

/// The metric M in which the triangle's three edges have unit length: eᵀ M e = 1 for each.
fn face_metric(u: [Vec2; 3]) -> Option<Mat2> {
    let e = [u[1] - u[0], u[2] - u[1], u[0] - u[2]];
    let a = nalgebra::Matrix3::from_fn(|r, c| match c {
        0 => e[r].x * e[r].x,
        1 => 2.0 * e[r].x * e[r].y,
        _ => e[r].y * e[r].y,
    });
    let m = a.lu().solve(&nalgebra::Vector3::new(1.0, 1.0, 1.0))?;
    let m = Mat2::new(m[0], m[1], m[1], m[2]) * SLACK;
    (m.determinant() > 0.0 && m[(0, 0)] > 0.0).then_some(m)
}

/// The first frame's mesh in material space (texture units), world positions kept.
fn first_mesh(frame: &RunFrame) -> Result<Mesh, ResampleError> {
    let obj = &frame.obj;
    let mut mesh = Mesh::default();
    for p in &obj.positions {
        mesh.nodes.push(Node { x: *p, v: Vec3::zeros(), a: Vec3::zeros(), mass: 0.0, cloth: 0 });
    }
    let mut node_of_vt: Vec<Option<usize>> = vec![None; obj.texcoords.len()];
    for t in &obj.triangles {
        for c in t {
            node_of_vt[c.vt.unwrap_or(0)].get_or_insert(c.v);
        }
    }
    let mut vert_of_vt = vec![u32::MAX; obj.texcoords.len()];
    for (vt, node) in node_of_vt.iter().enumerate() {
        if let Some(n) = node {
            vert_of_vt[vt] = mesh.verts.len() as u32;
            mesh.verts.push(Vert { u: obj.texcoords[vt], node: NodeId(*n as u32) });
        }
    }
    for t in &obj.triangles {
        mesh.faces.push(Face { v: t.map(|c| VertId(vert_of_vt[c.vt.unwrap_or(0)])), material: 0 });
    }
    mesh.rebuild_topology().map_err(|e| ResampleError::Auto(format!("frame {}: {e}", frame.number)))?;
    Ok(mesh)
}

/// The fixed mesh of every cloth of a run of `count` frames, `read(k)` giving frame k's cloths
/// (the same cloths in every frame). Frames are read again at each round rather than held, so a
/// long run is never all in memory.
pub fn auto_targets(
    count: usize,
    read: &dyn Fn(usize) -> Result<Vec<RunFrame>, ResampleError>,
) -> Result<Vec<FixedMesh>, ResampleError> {
    let first = read(0)?;
    let mut meshes = first.iter().map(first_mesh).collect::<Result<Vec<_>, _>>()?;
    let mut done = vec![false; meshes.len()];
    let limits = RemeshLimits { size_min: 0.0, aspect_min: 0.2, coarsen: false, relax_splits: Vec::new() };
    for _ in 0..ROUNDS {
        let mut vsize: Vec<Vec<Mat2>> = meshes.iter().map(|m| vec![Mat2::zeros(); m.verts.len()]).collect();
        for k in 0..count {
            let frame = read(k)?;
            for (c, cloth) in frame.iter().enumerate().filter(|(c, _)| !done[*c]) {
                refine_sizing(&mut vsize[c], &meshes[c], cloth);
            }
        }
        for (c, mesh) in meshes.iter_mut().enumerate() {
            if done[c] {
                continue;
            }
            let pinned = vec![false; mesh.nodes.len()];
            let vs = std::mem::take(&mut vsize[c]);
            let (finished, stats) = remesh(mesh, vs, pinned, &[], &[], &[], &[], &limits, &[])
                .map_err(|e| ResampleError::Auto(format!("remeshing: {e}")))?;
            *mesh = finished.mesh;
            done[c] = stats.splits == 0;
        }
        if done.iter().all(|&d| d) {
            break;
        }
    }
    Ok(meshes.into_iter().map(fixed_mesh).collect())
}

/// Raises each vertex's sizing `vsize` to the tensor max with the metric of `frame`'s face
/// holding it.
fn refine_sizing(vsize: &mut [Mat2], mesh: &Mesh, frame: &RunFrame) {
    let uv = |t: &[crate::io::obj::Corner; 3]| t.map(|c| frame.obj.texcoords[c.vt.unwrap_or(0)]);
    let locator = Locator::new(&frame.obj);
    let metrics: Vec<Option<Mat2>> = frame.obj.triangles.iter().map(|t| face_metric(uv(t))).collect();
    for (m, v) in vsize.iter_mut().zip(&mesh.verts) {
        if let Some(mf) = metrics[locator.locate(&v.u).triangle] {
            *m = tensor_max(&[*m, mf]);
        }
    }
}

/// The refined mesh as a fixed mesh: each node tracked at its first vert's location.
fn fixed_mesh(mesh: Mesh) -> FixedMesh {
    let mut node_uv: Vec<Option<Vec2>> = vec![None; mesh.nodes.len()];
    for v in &mesh.verts {
        node_uv[v.node.idx()].get_or_insert(v.u);
    }
    FixedMesh {
        texcoords: mesh.verts.iter().map(|v| v.u).collect(),
        node_uv: node_uv.into_iter().map(|u| u.unwrap_or_default()).collect(),
        triangles: (0..mesh.faces.len())
            .map(|f| {
                let n = mesh.face_nodes(f);
                let v = mesh.faces[f].v;
                [(n[0], v[0].idx()), (n[1], v[1].idx()), (n[2], v[2].idx())]
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_faces_metric_gives_its_edges_unit_length() {
        let u = [Vec2::new(0.0, 0.0), Vec2::new(0.3, 0.0), Vec2::new(0.1, 0.2)];
        let m = face_metric(u).unwrap() / SLACK;
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            let e = u[b] - u[a];
            assert!(((e.transpose() * m * e)[(0, 0)] - 1.0).abs() < 1e-12);
        }
    }
}
