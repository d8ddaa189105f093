//! Derived connectivity: edges over nodes and face–edge incidence.

use std::collections::HashMap;

use super::{Edge, EdgeId, FaceId, Mesh, MeshError, NodeId};

/// The faces on each side of an edge: `(face, corner of that face opposite the edge)`.
/// Side 0 is the face in which the edge runs `n[0] → n[1]` counter-clockwise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EdgeFaces(pub [Option<(FaceId, u8)>; 2]);

impl EdgeFaces {
    pub fn is_boundary(&self) -> bool {
        self.0[1].is_none()
    }
}

impl Mesh {
    /// Rebuilds `edges` and `face_edges` from the faces. Edge ids follow first appearance in
    /// face order, so the result is deterministic. Fails on an edge shared by more than two faces.
    pub fn rebuild_topology(&mut self) -> Result<(), MeshError> {
        let mut map: HashMap<(u32, u32), EdgeId> = HashMap::with_capacity(self.faces.len() * 2);
        let mut edges: Vec<Edge> = Vec::with_capacity(self.faces.len() * 3 / 2 + 8);
        let mut face_edges = Vec::with_capacity(self.faces.len());
        for f in 0..self.faces.len() {
            let nodes = self.face_nodes(f);
            let mut fe = [EdgeId(0); 3];
            for k in 0..3 {
                let (a, b) = (nodes[(k + 1) % 3] as u32, nodes[(k + 2) % 3] as u32);
                let key = (a.min(b), a.max(b));
                let e = *map.entry(key).or_insert_with(|| {
                    edges.push(Edge { n: [NodeId(a), NodeId(b)], adj: EdgeFaces::default() });
                    EdgeId(edges.len() as u32 - 1)
                });
                let edge = &mut edges[e.idx()];
                let entry = Some((FaceId(f as u32), k as u8));
                if edge.adj.0[0].is_none() {
                    edge.adj.0[0] = entry;
                } else if edge.adj.0[1].is_none() {
                    edge.adj.0[1] = entry;
                } else {
                    return Err(MeshError::NonManifoldEdge { a: key.0, b: key.1 });
                }
                fe[k] = e;
            }
            face_edges.push(fe);
        }
        self.edges = edges;
        self.face_edges = face_edges;
        Ok(())
    }

    /// For an interior edge: `[x0, x1, x2, x3]` node ids with the edge `x0–x1`, `x2` opposite in
    /// the first face and `x3` opposite in the second. `None` on a boundary edge.
    pub fn hinge_nodes(&self, e: usize) -> Option<[usize; 4]> {
        let edge = &self.edges[e];
        let (f0, k0) = edge.adj.0[0]?;
        let (f1, k1) = edge.adj.0[1]?;
        let a = self.face_nodes(f0.idx());
        let b = self.face_nodes(f1.idx());
        Some([edge.n[0].idx(), edge.n[1].idx(), a[k0 as usize], b[k1 as usize]])
    }

    /// True when the edge is interior in world space but its two faces use different verts
    /// (a seam between pattern pieces).
    pub fn is_seam(&self, e: usize) -> bool {
        let edge = &self.edges[e];
        let (Some((f0, k0)), Some((f1, k1))) = (edge.adj.0[0], edge.adj.0[1]) else {
            return false;
        };
        let vs = |f: FaceId, k: u8| {
            let fv = self.faces[f.idx()].v;
            let (a, b) = (fv[(k as usize + 1) % 3], fv[(k as usize + 2) % 3]);
            (a.min(b), a.max(b))
        };
        vs(f0, k0) != vs(f1, k1)
    }
}
