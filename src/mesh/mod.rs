//! The cloth mesh: material space (verts, 2D rest coordinates) and world space (nodes).
//!
//! Faces reference verts; each vert points to the node it sits on. A seam is two verts on one
//! node. Edges are over nodes and derived from the faces (`rebuild_topology`), so bending acts
//! across seams. Every array is a flat `Vec` indexed by typed ids: an operation that changes
//! topology rebuilds ids and leaves no holes. Units are metres throughout (material coordinates
//! included) and kilograms for mass.

mod generate;
mod topology;
mod validate;

pub use generate::rectangle;
pub use topology::EdgeFaces;
pub use validate::MeshError;

use crate::math::{cross2, Real, Vec2, Vec3};

macro_rules! typed_id {
    ($name:ident) => {
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub struct $name(pub u32);
        impl $name {
            #[inline]
            pub fn idx(self) -> usize {
                self.0 as usize
            }
        }
    };
}
typed_id!(VertId);
typed_id!(NodeId);
typed_id!(FaceId);
typed_id!(EdgeId);

/// A material-space vertex: the rest (pattern) coordinate of a corner.
#[derive(Clone, Debug)]
pub struct Vert {
    pub u: Vec2,
    pub node: NodeId,
}

/// A world-space node: the simulated degree of freedom.
#[derive(Clone, Debug)]
pub struct Node {
    pub x: Vec3,
    pub v: Vec3,
    /// Acceleration of the last accepted step's implicit solve (Δv / h; zero before the first
    /// step, interpolated like the velocity by remeshing): the pop filter's target (`sim::pop`).
    pub a: Vec3,
    /// Lumped mass (kg), recomputed by `Mesh::compute_masses`.
    pub mass: Real,
    /// Which cloth of the scene this node belongs to.
    pub cloth: u16,
}

/// A triangle over three verts, counter-clockwise in material space.
#[derive(Clone, Debug)]
pub struct Face {
    pub v: [VertId; 3],
    /// Index into the scene's materials (one per cloth).
    pub material: u16,
}

/// An edge between two nodes, with up to two adjacent faces (derived).
#[derive(Clone, Debug)]
pub struct Edge {
    pub n: [NodeId; 2],
    pub adj: EdgeFaces,
}

#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub verts: Vec<Vert>,
    pub nodes: Vec<Node>,
    pub faces: Vec<Face>,
    /// Derived from faces by `rebuild_topology`.
    pub edges: Vec<Edge>,
    /// Derived: for each face, the edge opposite each corner (edge k joins corners k+1, k+2).
    pub face_edges: Vec<[EdgeId; 3]>,
    /// Creases: edges the input labels (ARCSim's `e`/`el`), each as its two nodes, smaller id
    /// first, sorted. Remeshing keeps them edges: never flipped, split into creases, their
    /// nodes collapsed only along them (`remesh`).
    pub creases: Vec<[NodeId; 2]>,
}

impl Mesh {
    #[inline]
    pub fn node_of(&self, v: VertId) -> NodeId {
        self.verts[v.idx()].node
    }

    /// The three node ids of a face.
    #[inline]
    pub fn face_nodes(&self, f: usize) -> [usize; 3] {
        let fv = &self.faces[f].v;
        [self.verts[fv[0].idx()].node.idx(), self.verts[fv[1].idx()].node.idx(), self.verts[fv[2].idx()].node.idx()]
    }

    /// Material-space corners of a face.
    #[inline]
    pub fn face_uv(&self, f: usize) -> [Vec2; 3] {
        let fv = &self.faces[f].v;
        [self.verts[fv[0].idx()].u, self.verts[fv[1].idx()].u, self.verts[fv[2].idx()].u]
    }

    /// Signed material-space area (positive for counter-clockwise faces).
    pub fn material_area(&self, f: usize) -> Real {
        let [a, b, c] = self.face_uv(f);
        0.5 * cross2(&(b - a), &(c - a))
    }

    /// World-space area of a face.
    pub fn world_area(&self, f: usize) -> Real {
        let [a, b, c] = self.face_nodes(f).map(|n| self.nodes[n].x);
        0.5 * (b - a).cross(&(c - a)).norm()
    }

    /// Unit world-space face normal (zero for a degenerate face).
    pub fn face_normal(&self, f: usize) -> Vec3 {
        let [a, b, c] = self.face_nodes(f).map(|n| self.nodes[n].x);
        let n = (b - a).cross(&(c - a));
        let l = n.norm();
        if l > 0.0 {
            n / l
        } else {
            Vec3::zeros()
        }
    }

    /// Area-weighted vertex normals per node.
    pub fn node_normals(&self) -> Vec<Vec3> {
        let mut nn = vec![Vec3::zeros(); self.nodes.len()];
        for f in 0..self.faces.len() {
            let ids = self.face_nodes(f);
            let [a, b, c] = ids.map(|n| self.nodes[n].x);
            let n = (b - a).cross(&(c - a));
            for i in ids {
                nn[i] += n;
            }
        }
        for n in &mut nn {
            let l = n.norm();
            if l > 0.0 {
                *n /= l;
            }
        }
        nn
    }

    /// Lumped masses: each face gives a third of `density × material area` to each corner node.
    pub fn compute_masses(&mut self, density: &[Real]) {
        for n in &mut self.nodes {
            n.mass = 0.0;
        }
        for f in 0..self.faces.len() {
            let m = density[self.faces[f].material as usize] * self.material_area(f) / 3.0;
            for n in self.face_nodes(f) {
                self.nodes[n].mass += m;
            }
        }
    }

    pub fn positions(&self) -> Vec<Vec3> {
        self.nodes.iter().map(|n| n.x).collect()
    }
}
