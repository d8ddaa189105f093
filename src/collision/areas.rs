//! Element areas for ARCSim's contact stiffness (`proximity::Law::Cubic`): a contact's stiffness
//! is the scene's stiffness times the smaller of its two elements' areas (ARCSim 0.2.1,
//! `proximity.cpp`: `make_constraint`, `area`). A node's area is a third of its faces', an
//! edge's a third of its (one or two) faces', a face's its own; cloth areas in material space,
//! obstacle areas in world space at the end of the step.

use std::collections::HashMap;

use super::broad::VF;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;

/// Areas of the cloth's and the obstacles' nodes, edges and faces, looked up by their nodes
/// (obstacle vertices numbered from the cloth node count, as in contacts).
pub struct ElementAreas<'a> {
    n: usize,
    node: &'a [Real],
    /// Cloth faces by sorted nodes.
    face: HashMap<[usize; 3], Real>,
    /// Cloth and obstacle edges by sorted nodes.
    edge: HashMap<[usize; 2], Real>,
    obs_node: Vec<Real>,
    obs_x: &'a [Vec3],
}

fn sorted<const N: usize>(mut a: [usize; N]) -> [usize; N] {
    a.sort_unstable();
    a
}

impl<'a> ElementAreas<'a> {
    /// From the cloth's node and face material areas and the obstacle triangles at `obs_x`.
    pub fn new(
        mesh: &Mesh,
        node_area: &'a [Real],
        face_area: &[Real],
        obs_tris: &[[usize; 3]],
        obs_x: &'a [Vec3],
    ) -> Self {
        let n = mesh.nodes.len();
        let mut face = HashMap::with_capacity(mesh.faces.len());
        let mut edge: HashMap<[usize; 2], Real> = HashMap::with_capacity(2 * mesh.faces.len());
        let mut add_edges = |t: [usize; 3], a: Real| {
            for k in 0..3 {
                *edge.entry(sorted([t[k], t[(k + 1) % 3]])).or_insert(0.0) += a / 3.0;
            }
        };
        for (f, &a) in face_area.iter().enumerate() {
            let t = mesh.face_nodes(f);
            face.insert(sorted(t), a);
            add_edges(t, a);
        }
        let mut obs_node = vec![0.0; obs_x.len()];
        for t in obs_tris {
            let a = triangle_area(obs_x[t[0]], obs_x[t[1]], obs_x[t[2]]);
            for &i in t {
                obs_node[i] += a / 3.0;
            }
            add_edges(t.map(|i| i + n), a);
        }
        ElementAreas { n, node: node_area, face, edge, obs_node, obs_x }
    }

    fn node_area(&self, i: usize) -> Real {
        if i < self.n {
            self.node[i]
        } else {
            self.obs_node[i - self.n]
        }
    }

    fn face_area(&self, t: [usize; 3]) -> Real {
        if t[0] < self.n {
            self.face.get(&sorted(t)).copied().unwrap_or(0.0)
        } else {
            let x = |i: usize| self.obs_x[i - self.n];
            triangle_area(x(t[0]), x(t[1]), x(t[2]))
        }
    }

    fn edge_area(&self, e: [usize; 2]) -> Real {
        self.edge.get(&sorted(e)).copied().unwrap_or(0.0)
    }

    /// The smaller of the two elements' areas of a candidate: node `nodes[0]` and face
    /// `nodes[1..4]` (VF), or edges `nodes[0..2]` and `nodes[2..4]`.
    pub fn pair(&self, kind: u8, nodes: &[usize; 4]) -> Real {
        if kind == VF {
            self.node_area(nodes[0]).min(self.face_area([nodes[1], nodes[2], nodes[3]]))
        } else {
            self.edge_area([nodes[0], nodes[1]]).min(self.edge_area([nodes[2], nodes[3]]))
        }
    }
}

fn triangle_area(a: Vec3, b: Vec3, c: Vec3) -> Real {
    0.5 * (b - a).cross(&(c - a)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::rectangle;

    /// A 2×2-cell unit grid (8 faces of 1/8 m²) against one obstacle triangle of 1/2 m²: a
    /// node's area is a third of its faces', an interior edge's two thirds of a face, a
    /// boundary edge's one third; the obstacle's from its world positions.
    #[test]
    fn areas_as_arcsim_takes_them() {
        let mesh = rectangle(1.0, 1.0, 2, 2).unwrap();
        let n = mesh.nodes.len();
        let face_area = vec![0.125; mesh.faces.len()];
        let mut node_area = vec![0.0; n];
        for f in 0..mesh.faces.len() {
            for i in mesh.face_nodes(f) {
                node_area[i] += 0.125 / 3.0;
            }
        }
        let obs_x = [Vec3::new(0.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 1.0, -1.0)];
        let areas = ElementAreas::new(&mesh, &node_area, &face_area, &[[0, 1, 2]], &obs_x);
        let t = mesh.face_nodes(0);
        // Cloth node against the obstacle face: the node's area is smaller.
        let centre = (0..n).max_by(|&a, &b| node_area[a].total_cmp(&node_area[b])).unwrap();
        assert_eq!(areas.pair(VF, &[centre, n, n + 1, n + 2]), node_area[centre]);
        // Obstacle vertex (1/6 m²) against a cloth face (1/8 m²).
        assert_eq!(areas.pair(VF, &[n, t[0], t[1], t[2]]), 0.125);
        // A cloth edge against an obstacle edge (1/6 m²): the cloth edge's area, interior or not.
        let per_edge: Vec<Real> = (0..3).map(|k| areas.edge_area([t[k], t[(k + 1) % 3]])).collect();
        assert!(per_edge.iter().all(|&a| a == 0.125 / 3.0 || a == 0.25 / 3.0), "{per_edge:?}");
        assert!(per_edge.contains(&(0.25 / 3.0)), "a 2×2 grid's first face has an interior edge");
        assert_eq!(areas.pair(1, &[t[0], t[1], n, n + 1]), per_edge[0].min(0.5 / 3.0));
    }
}
