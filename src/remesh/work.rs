//! The remesher's working mesh: the `Mesh` arrays with vert→face adjacency kept up to date by
//! every operation, and tombstones instead of removals until `finish` compacts it back.

use crate::math::{cross2, Mat2, Real, Vec2, Vec3};
use crate::mesh::{Face, Mesh, MeshError, Node, NodeId, Vert, VertId};

#[derive(Clone, Debug)]
pub struct Work {
    pub u: Vec<Vec2>,
    pub vnode: Vec<usize>,
    pub vsize: Vec<Mat2>,
    pub valive: Vec<bool>,
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub a: Vec<Vec3>,
    /// Rest embedding per node (`SimState::rest_x`); empty without one.
    pub y: Vec<Vec3>,
    pub cloth: Vec<u16>,
    pub nalive: Vec<bool>,
    /// Nodes that must survive (handles).
    pub pinned: Vec<bool>,
    /// A group per node (0: none): a node split between two nodes of one group joins it (the
    /// rings of circle handles; ARCSim's node labels).
    pub group: Vec<u32>,
    pub faces: Vec<[usize; 3]>,
    pub fdata: Vec<FaceData>,
    pub falive: Vec<bool>,
    /// Alive faces around each vert.
    pub vfaces: Vec<Vec<usize>>,
    /// Alive verts on each node (two or more on a seam).
    pub nverts: Vec<Vec<usize>>,
    /// Per node, how far a flip or collapse may move the surface near it (m; `jump.rs`);
    /// empty for no bound.
    pub jump: Vec<Real>,
    /// The surface the remesh started from, when `jump` bounds the moves.
    pub start: Option<super::jump::Start>,
    /// Each node's neighbours along creases (`Mesh::creases`; empty off them).
    pub ncrease: Vec<Vec<usize>>,
}

/// A node a split creates: position, velocity and acceleration interpolated, its cloth and
/// group.
#[derive(Clone, Copy, Debug)]
pub struct NewNode {
    pub x: Vec3,
    pub v: Vec3,
    pub a: Vec3,
    /// Rest embedding (unused without one).
    pub y: Vec3,
    pub cloth: u16,
    pub group: u32,
}

/// What a face carries through remeshing besides its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceData {
    pub material: u16,
    /// Rest shape operator in material space (`rest_shape`).
    pub shape: Mat2,
    /// Plastic damage (`forces::plasticity`), carried as the rest shape is.
    pub damage: Real,
}

/// The compacted mesh, for every old node its new id (None if it was removed), and every new
/// face's rest shape operator and damage.
pub struct Finished {
    pub mesh: Mesh,
    pub node_map: Vec<Option<usize>>,
    pub face_shapes: Vec<Mat2>,
    /// The group of every node of `mesh`.
    pub groups: Vec<u32>,
    pub face_damage: Vec<Real>,
    /// The rest embedding of every node of `mesh` (empty without one).
    pub rest_x: Vec<Vec3>,
}

impl Work {
    /// `shapes`: each face's rest shape operator (empty: all zero, a flat rest shape); `damage`
    /// each face's plastic damage (empty: all zero); `rest_x` each node's rest embedding
    /// (empty: none).
    pub fn new(
        mesh: &Mesh,
        vsize: Vec<Mat2>,
        pinned: Vec<bool>,
        shapes: &[Mat2],
        damage: &[Real],
        rest_x: &[Vec3],
    ) -> Self {
        let nv = mesh.verts.len();
        let mut vfaces = vec![Vec::new(); nv];
        let faces: Vec<[usize; 3]> = mesh.faces.iter().map(|f| f.v.map(|v| v.idx())).collect();
        for (f, t) in faces.iter().enumerate() {
            for &v in t {
                vfaces[v].push(f);
            }
        }
        let mut nverts = vec![Vec::new(); mesh.nodes.len()];
        for (i, v) in mesh.verts.iter().enumerate() {
            nverts[v.node.idx()].push(i);
        }
        let mut ncrease = vec![Vec::new(); mesh.nodes.len()];
        for &[a, b] in &mesh.creases {
            ncrease[a.idx()].push(b.idx());
            ncrease[b.idx()].push(a.idx());
        }
        Work {
            u: mesh.verts.iter().map(|v| v.u).collect(),
            vnode: mesh.verts.iter().map(|v| v.node.idx()).collect(),
            vsize,
            valive: vec![true; nv],
            x: mesh.nodes.iter().map(|n| n.x).collect(),
            v: mesh.nodes.iter().map(|n| n.v).collect(),
            a: mesh.nodes.iter().map(|n| n.a).collect(),
            y: rest_x.to_vec(),
            cloth: mesh.nodes.iter().map(|n| n.cloth).collect(),
            nalive: vec![true; mesh.nodes.len()],
            pinned,
            group: vec![0; mesh.nodes.len()],
            fdata: (0..mesh.faces.len())
                .map(|f| FaceData {
                    material: mesh.faces[f].material,
                    shape: shapes.get(f).copied().unwrap_or_else(Mat2::zeros),
                    damage: damage.get(f).copied().unwrap_or(0.0),
                })
                .collect(),
            falive: vec![true; faces.len()],
            faces,
            vfaces,
            nverts,
            jump: Vec::new(),
            start: None,
            ncrease,
        }
    }

    /// Whether nodes `a` and `b` are joined by a crease.
    pub fn is_crease(&self, a: usize, b: usize) -> bool {
        self.ncrease[a].contains(&b)
    }

    /// The crease a–b becomes a–p and p–b (a split at new node `p`); nothing off creases.
    pub fn split_crease(&mut self, a: usize, b: usize, p: usize) {
        if !self.is_crease(a, b) {
            return;
        }
        for (s, t) in [(a, b), (b, a)] {
            for n in &mut self.ncrease[s] {
                if *n == t {
                    *n = p;
                }
            }
        }
        self.ncrease[p] = vec![a, b];
    }

    /// Node `i` collapsed into `j`: its creases other than i–j now end at `j`.
    pub fn collapse_crease(&mut self, i: usize, j: usize) {
        for k in std::mem::take(&mut self.ncrease[i]) {
            self.ncrease[k].retain(|&n| n != i);
            if k != j && !self.ncrease[k].contains(&j) {
                self.ncrease[k].push(j);
                self.ncrease[j].push(k);
            }
        }
    }

    /// Alive faces containing both verts.
    pub fn edge_faces(&self, a: usize, b: usize) -> Vec<usize> {
        self.vfaces[a].iter().copied().filter(|&f| self.faces[f].contains(&b)).collect()
    }

    /// The face's corners rotated so that `a → b` is its directed edge, with the third corner;
    /// `None` if the face does not run `a → b`.
    pub fn directed(&self, f: usize, a: usize, b: usize) -> Option<usize> {
        let t = self.faces[f];
        (0..3).find(|&k| t[k] == a && t[(k + 1) % 3] == b).map(|k| t[(k + 2) % 3])
    }

    /// The corner of face `f` that is neither `a` nor `b`.
    pub fn opposite(&self, f: usize, a: usize, b: usize) -> usize {
        let t = self.faces[f];
        t.into_iter().find(|&v| v != a && v != b).unwrap_or(t[0])
    }

    pub fn area(&self, t: &[usize; 3]) -> Real {
        0.5 * cross2(&(self.u[t[1]] - self.u[t[0]]), &(self.u[t[2]] - self.u[t[0]]))
    }

    /// World-space (unnormalised) normal of a face given by verts.
    pub fn world_normal(&self, t: &[usize; 3]) -> Vec3 {
        let [a, b, c] = t.map(|v| self.x[self.vnode[v]]);
        (b - a).cross(&(c - a))
    }

    /// Verts sharing an alive face with `a` (sorted, unique).
    pub fn neighbours(&self, a: usize) -> Vec<usize> {
        let mut n: Vec<usize> = self.vfaces[a].iter().flat_map(|&f| self.faces[f]).filter(|&v| v != a).collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    /// Nodes sharing an alive face with node `n`, over all its verts (sorted, unique).
    pub fn node_neighbours(&self, n: usize) -> Vec<usize> {
        let mut out: Vec<usize> = self.nverts[n]
            .iter()
            .flat_map(|&a| self.neighbours(a))
            .map(|v| self.vnode[v])
            .filter(|&m| m != n)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    pub fn is_boundary_edge(&self, a: usize, b: usize) -> bool {
        self.edge_faces(a, b).len() == 1
    }

    /// Boundary neighbours of `a` (verts joined to it by a material-space boundary edge).
    pub fn boundary_neighbours(&self, a: usize) -> Vec<usize> {
        self.neighbours(a).into_iter().filter(|&b| self.is_boundary_edge(a, b)).collect()
    }

    /// Another material-space edge on the same two nodes (the other side of a seam), as
    /// `(c, d)` with `c` on `a`'s node and `d` on `b`'s.
    pub fn seam_partner(&self, a: usize, b: usize) -> Option<(usize, usize)> {
        let (na, nb) = (self.vnode[a], self.vnode[b]);
        for &c in &self.nverts[na] {
            for &d in &self.nverts[nb] {
                if (c, d) != (a, b) && !self.edge_faces(c, d).is_empty() {
                    return Some((c, d));
                }
            }
        }
        None
    }

    /// Metric length of the material edge a–b: √(½ uᵀ(M_a + M_b)u).
    pub fn metric_length(&self, a: usize, b: usize) -> Real {
        let e = self.u[b] - self.u[a];
        let m = 0.5 * (self.vsize[a] + self.vsize[b]);
        e.dot(&(m * e)).max(0.0).sqrt()
    }

    /// The metric length that decides a split: on a seam, where one split cuts both sides, the
    /// mean of the two sides' lengths (ARCSim's `edge_metric` of a seam edge).
    pub fn split_length(&self, a: usize, b: usize) -> Real {
        let l = self.metric_length(a, b);
        match self.edge_faces(a, b).len() == 1 {
            true => self.seam_partner(a, b).map_or(l, |(c, d)| 0.5 * (l + self.metric_length(c, d))),
            false => l,
        }
    }

    /// Every alive material edge once, as (a, b) with a < b, in a deterministic order.
    pub fn edges(&self) -> Vec<(usize, usize)> {
        let mut e: Vec<(usize, usize)> = Vec::with_capacity(self.faces.len() * 3 / 2);
        for (f, t) in self.faces.iter().enumerate() {
            if !self.falive[f] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                e.push((a.min(b), a.max(b)));
            }
        }
        e.sort_unstable();
        e.dedup();
        e
    }

    pub fn add_face(&mut self, t: [usize; 3], data: FaceData) -> usize {
        let f = self.faces.len();
        self.faces.push(t);
        self.fdata.push(data);
        self.falive.push(true);
        for v in t {
            self.vfaces[v].push(f);
        }
        f
    }

    pub fn remove_face(&mut self, f: usize) {
        self.falive[f] = false;
        for v in self.faces[f] {
            self.vfaces[v].retain(|&g| g != f);
        }
    }

    pub fn add_node(&mut self, n: NewNode) -> usize {
        self.group.push(n.group);
        self.x.push(n.x);
        self.v.push(n.v);
        self.a.push(n.a);
        if !self.y.is_empty() {
            self.y.push(n.y);
        }
        self.cloth.push(n.cloth);
        self.nalive.push(true);
        self.pinned.push(false);
        self.nverts.push(Vec::new());
        self.ncrease.push(Vec::new());
        self.x.len() - 1
    }

    pub fn add_vert(&mut self, u: Vec2, node: usize, size: Mat2) -> usize {
        self.u.push(u);
        self.vnode.push(node);
        self.vsize.push(size);
        self.valive.push(true);
        self.vfaces.push(Vec::new());
        self.nverts[node].push(self.u.len() - 1);
        self.u.len() - 1
    }

    pub fn remove_vert(&mut self, v: usize) {
        self.valive[v] = false;
        let n = self.vnode[v];
        self.nverts[n].retain(|&w| w != v);
        if self.nverts[n].is_empty() {
            self.nalive[n] = false;
        }
    }

    /// Compacts into a `Mesh` (ids in ascending old order, new elements after), with derived
    /// topology rebuilt.
    pub fn finish(&self, old_nodes: usize) -> Result<Finished, MeshError> {
        let mut node_id = vec![usize::MAX; self.x.len()];
        let mut mesh = Mesh::default();
        let (mut groups, mut rest_x) = (Vec::new(), Vec::new());
        for i in 0..self.x.len() {
            if self.nalive[i] {
                node_id[i] = mesh.nodes.len();
                groups.push(self.group[i]);
                if !self.y.is_empty() {
                    rest_x.push(self.y[i]);
                }
                mesh.nodes.push(Node { x: self.x[i], v: self.v[i], a: self.a[i], mass: 0.0, cloth: self.cloth[i] });
            }
        }
        let mut vert_id = vec![usize::MAX; self.u.len()];
        for i in 0..self.u.len() {
            if self.valive[i] {
                vert_id[i] = mesh.verts.len();
                mesh.verts.push(Vert { u: self.u[i], node: NodeId(node_id[self.vnode[i]] as u32) });
            }
        }
        let (mut face_shapes, mut face_damage) = (Vec::new(), Vec::new());
        for (f, t) in self.faces.iter().enumerate() {
            if self.falive[f] {
                mesh.faces.push(Face { v: t.map(|v| VertId(vert_id[v] as u32)), material: self.fdata[f].material });
                face_shapes.push(self.fdata[f].shape);
                face_damage.push(self.fdata[f].damage);
            }
        }
        mesh.creases = (0..self.x.len())
            .filter(|&a| self.nalive[a])
            .flat_map(|a| self.ncrease[a].iter().filter(move |&&b| a < b).map(move |&b| (a, b)))
            .filter(|&(_, b)| self.nalive[b])
            .map(|(a, b)| [a, b].map(|n| NodeId(node_id[n] as u32)))
            .collect();
        mesh.creases.sort_unstable();
        mesh.rebuild_topology()?;
        let node_map = (0..old_nodes).map(|i| (node_id[i] != usize::MAX).then_some(node_id[i])).collect();
        Ok(Finished { mesh, node_map, face_shapes, face_damage, groups, rest_x })
    }
}
