//! Mesh validity: the invariant every operation (load, remesh) must keep.

use std::collections::HashSet;

use super::Mesh;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    #[error("edge between nodes {a} and {b} is shared by more than two faces (non-manifold)")]
    NonManifoldEdge { a: u32, b: u32 },
    #[error("face {face} repeats a node (degenerate)")]
    RepeatedNode { face: usize },
    #[error("face {face} has material-space area {area:e} m² (expected > 0: counter-clockwise, non-degenerate)")]
    BadMaterialArea { face: usize, area: f64 },
    #[error("face {face} duplicates face {other}")]
    DuplicateFace { face: usize, other: usize },
    #[error("vert {vert} points to node {node}, but there are only {count} nodes")]
    BadNodeRef { vert: usize, node: usize, count: usize },
    #[error("face {face} references vert {vert}, but there are only {count} verts")]
    BadVertRef { face: usize, vert: usize, count: usize },
    #[error("adjacency is inconsistent at {what}")]
    Adjacency { what: String },
    #[error("node {node} has a non-finite position or velocity")]
    NonFinite { node: usize },
    #[error("the crease between nodes {a} and {b} is not an edge of the mesh (or is listed twice)")]
    Crease { a: u32, b: u32 },
}

/// Smallest material area accepted, relative to the mean face area.
const MIN_RELATIVE_AREA: f64 = 1e-12;

impl Mesh {
    /// Checks the mesh invariants: references in range, non-degenerate counter-clockwise faces in
    /// material space, no duplicate faces, manifold (≤ 2 faces per edge) and derived adjacency
    /// consistent with the faces.
    pub fn validate(&self) -> Result<(), MeshError> {
        for (i, v) in self.verts.iter().enumerate() {
            if v.node.idx() >= self.nodes.len() {
                return Err(MeshError::BadNodeRef { vert: i, node: v.node.idx(), count: self.nodes.len() });
            }
        }
        for (i, n) in self.nodes.iter().enumerate() {
            if !(n.x.iter().chain(n.v.iter()).all(|c| c.is_finite())) {
                return Err(MeshError::NonFinite { node: i });
            }
        }
        let mut total = 0.0;
        for (f, face) in self.faces.iter().enumerate() {
            for v in face.v {
                if v.idx() >= self.verts.len() {
                    return Err(MeshError::BadVertRef { face: f, vert: v.idx(), count: self.verts.len() });
                }
            }
            total += self.material_area(f).abs();
        }
        let floor = MIN_RELATIVE_AREA * total / self.faces.len().max(1) as f64;
        let mut seen = std::collections::HashMap::new();
        for f in 0..self.faces.len() {
            let n = self.face_nodes(f);
            if n[0] == n[1] || n[1] == n[2] || n[0] == n[2] {
                return Err(MeshError::RepeatedNode { face: f });
            }
            let area = self.material_area(f);
            if !(area > floor) {
                return Err(MeshError::BadMaterialArea { face: f, area });
            }
            let mut key = n;
            key.sort_unstable();
            if let Some(other) = seen.insert(key, f) {
                return Err(MeshError::DuplicateFace { face: f, other });
            }
        }
        self.validate_adjacency()
    }

    fn validate_adjacency(&self) -> Result<(), MeshError> {
        let bad = |what: String| Err(MeshError::Adjacency { what });
        if self.face_edges.len() != self.faces.len() {
            return bad(format!("face_edges has {} entries for {} faces", self.face_edges.len(), self.faces.len()));
        }
        let mut keys = HashSet::new();
        for (e, edge) in self.edges.iter().enumerate() {
            let key = (edge.n[0].min(edge.n[1]), edge.n[0].max(edge.n[1]));
            if !keys.insert(key) {
                return bad(format!("edge {e} duplicates another edge"));
            }
            if edge.adj.0[0].is_none() {
                return bad(format!("edge {e} has no face"));
            }
            for (f, k) in edge.adj.0.iter().flatten() {
                if self.face_edges[f.idx()][*k as usize].idx() != e {
                    return bad(format!("edge {e} and face {}", f.idx()));
                }
            }
        }
        for (f, fe) in self.face_edges.iter().enumerate() {
            let n = self.face_nodes(f);
            for k in 0..3 {
                let edge = self.edges.get(fe[k].idx());
                let Some(edge) = edge else {
                    return bad(format!("face {f} points to missing edge {}", fe[k].idx()));
                };
                let (a, b) = (n[(k + 1) % 3], n[(k + 2) % 3]);
                let (p, q) = (edge.n[0].idx(), edge.n[1].idx());
                if !((p == a && q == b) || (p == b && q == a)) {
                    return bad(format!("face {f} corner {k}"));
                }
                if !edge.adj.0.iter().flatten().any(|(g, kk)| g.idx() == f && *kk as usize == k) {
                    return bad(format!("edge {} does not list face {f}", fe[k].idx()));
                }
            }
        }
        for (i, &[a, b]) in self.creases.iter().enumerate() {
            let sorted = a < b && (i == 0 || self.creases[i - 1] < [a, b]);
            if !sorted || !keys.contains(&(a, b)) {
                return Err(MeshError::Crease { a: a.0, b: b.0 });
            }
        }
        Ok(())
    }
}
