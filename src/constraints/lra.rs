//! Long range attachments (Kim, Chentanez & Müller 2012): every free node of a cloth may not get
//! farther from an attachment (a pinned node: a handle's, or one riding on an obstacle) than the
//! length of the cloth between them at rest, inflated by `stretch` (§3.1, §3.5). The constraint
//! is unilateral: a node inside its sphere moves freely, so the cloth still buckles and wrinkles.
//!
//! - Rest lengths are material-space distances (`geodesic`: along the surface; `euclidean`: the
//!   straight segment within one chart of the pattern), §3.2.
//! - Attachments form islands (nodes joined by mesh edges, Algorithm 2, found once on the input
//!   mesh by the caller); each free node is tied to the closest attachment of each of its
//!   `max_attachments` closest islands (Algorithm 2, §3.4).
//! - `project` moves each node violating a constraint onto the sphere's surface, averaging the
//!   displacements of its violated constraints (Algorithm 1, Jacobi style).
//!
//! The constraint set is a function of the mesh and of which attachments are active, so it is
//! rebuilt after a remesh (nodes created by splits get distances from their material position,
//! collapsed ones drop theirs) and when a handle switches on or off.

use crate::math::{Real, Vec3};
use crate::mesh::Mesh;

use super::geodesic::{distance_field, vert_charts, Field, NodeFaces, Outline};

/// How rest lengths are measured in material space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distance {
    /// Along the surface: shortest paths refined toward geodesics (`geodesic`).
    Geodesic,
    /// The straight material-space segment, between verts of one chart (a node with no vert in
    /// the attachment's chart falls back to the geodesic).
    Euclidean,
}

impl Distance {
    pub fn parse(name: &str) -> Option<Distance> {
        match name {
            "geodesic" => Some(Distance::Geodesic),
            "euclidean" => Some(Distance::Euclidean),
            _ => None,
        }
    }
}

/// One cloth's attachment parameters (scene field `lra`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LraParams {
    /// Islands a node is tied to (N of Algorithm 2; default 4).
    pub max_attachments: usize,
    /// Radius inflation: 0 inextensible, 0.1 allows 10% (§3.5).
    pub stretch: Real,
    pub distance: Distance,
}

impl Default for LraParams {
    fn default() -> Self {
        LraParams { max_attachments: 4, stretch: 0.0, distance: Distance::Geodesic }
    }
}

/// An attached node and its island.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Attachment {
    pub node: usize,
    pub island: usize,
}

/// A free node's tie to one attachment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    pub node: u32,
    pub attachment: u32,
    /// Material-space distance (m).
    pub rest: Real,
    /// rest × (1 + stretch): the sphere's radius.
    pub radius: Real,
}

/// The constraints of a mesh, grouped by node (ascending).
#[derive(Clone, Debug, Default)]
pub struct Lra {
    pub constraints: Vec<Constraint>,
}

/// What one projection did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Projected {
    /// Constraints found violated (over all passes).
    pub violated: usize,
    /// Nodes moved.
    pub nodes: usize,
}

/// Jacobi passes per step; each pass averages a node's violated constraints (Algorithm 1), so
/// a node held by two attachments pulling different ways needs a few.
const PASSES: usize = 4;

impl Lra {
    /// The constraints of `mesh`'s nodes whose cloth has parameters (`params[node.cloth]`) to the
    /// `attachments` (active ones only), by Algorithm 2.
    pub fn build(mesh: &Mesh, attachments: &[Attachment], params: &[Option<LraParams>]) -> Lra {
        let n = mesh.nodes.len();
        let node_faces = NodeFaces::new(mesh);
        let mut islands: Vec<usize> = attachments.iter().map(|a| a.island).collect();
        islands.sort_unstable();
        islands.dedup();
        let attached: Vec<bool> = {
            let mut v = vec![false; n];
            for a in attachments {
                v[a.node] = true;
            }
            v
        };
        let charts = vert_charts(mesh);
        let node_verts = node_verts(mesh);
        let outline = Outline::new(mesh, &charts);
        // Per island: the closest attachment (geodesic) of every node, and its distance.
        let fields: Vec<(Vec<usize>, Field)> = islands
            .iter()
            .map(|&i| {
                let sources: Vec<usize> = attachments.iter().filter(|a| a.island == i).map(|a| a.node).collect();
                let field = distance_field(mesh, &node_faces, &sources, true);
                (sources, field)
            })
            .collect();
        let mut constraints = Vec::new();
        let mut candidates: Vec<(Real, u32)> = Vec::new();
        for (k, node) in mesh.nodes.iter().enumerate() {
            let Some(p) = params.get(node.cloth as usize).copied().flatten() else { continue };
            if attached[k] || node.mass <= 0.0 {
                continue;
            }
            candidates.clear();
            for (sources, field) in &fields {
                if !field.dist[k].is_finite() {
                    continue;
                }
                let geo = (field.dist[k], field.source[k]);
                let pick = match p.distance {
                    // Where the straight segment to that attachment stays on the chart, it is
                    // the geodesic: exact on convex panels whatever the mesh.
                    Distance::Geodesic => {
                        let s = geo.1 as usize;
                        match visible_distance(mesh, &charts, &node_verts, &outline, k, s) {
                            Some(d) if d < geo.0 => (d, geo.1),
                            _ => geo,
                        }
                    }
                    Distance::Euclidean => sources
                        .iter()
                        .filter(|&&s| mesh.nodes[s].cloth == node.cloth)
                        .filter_map(|&s| chart_distance(mesh, &charts, &node_verts, k, s).map(|d| (d, s as u32)))
                        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                        .unwrap_or(geo),
                };
                candidates.push(pick);
            }
            candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            for &(rest, a) in candidates.iter().take(p.max_attachments) {
                constraints.push(Constraint { node: k as u32, attachment: a, rest, radius: rest * (1.0 + p.stretch) });
            }
        }
        Lra { constraints }
    }

    /// Projects the free nodes of `x` into their attachment spheres (Algorithm 1): per pass,
    /// each node violating constraints moves by the mean of the displacements that put it on
    /// each violated sphere. Nodes with `inv_mass` 0 (pinned) do not move. Returns what was done;
    /// `moved[i]` is set for every node moved.
    pub fn project(&self, x: &mut [Vec3], inv_mass: &[Real], moved: &mut [bool]) -> Projected {
        let mut out = Projected::default();
        for _ in 0..PASSES {
            let mut any = false;
            let mut i = 0;
            while i < self.constraints.len() {
                let node = self.constraints[i].node as usize;
                let mut j = i;
                let (mut sum, mut count) = (Vec3::zeros(), 0usize);
                while j < self.constraints.len() && self.constraints[j].node as usize == node {
                    let c = &self.constraints[j];
                    let d = x[node] - x[c.attachment as usize];
                    let len = d.norm();
                    if len > c.radius && len > 0.0 {
                        sum += d * (c.radius / len - 1.0);
                        count += 1;
                    }
                    j += 1;
                }
                if count > 0 && inv_mass[node] > 0.0 {
                    x[node] += sum / count as Real;
                    moved[node] = true;
                    out.violated += count;
                    any = true;
                }
                i = j;
            }
            if !any {
                break;
            }
        }
        out.nodes = moved.iter().filter(|&&m| m).count();
        out
    }

    /// The largest stretch along an attachment path, |x_i − x_a| / rest − 1, over the
    /// constraints (−1 when there are none), and how many constraints are taut (at or beyond
    /// their radius, to 1e-9 relative).
    pub fn measure(&self, x: &[Vec3]) -> (Real, usize) {
        let (mut worst, mut taut) = (-1.0 as Real, 0);
        for c in &self.constraints {
            let d = (x[c.node as usize] - x[c.attachment as usize]).norm();
            if c.rest > 0.0 {
                worst = worst.max(d / c.rest - 1.0);
            }
            if d >= c.radius * (1.0 - 1e-9) {
                taut += 1;
            }
        }
        (worst, taut)
    }
}

/// The verts of each node.
fn node_verts(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); mesh.nodes.len()];
    for (v, vert) in mesh.verts.iter().enumerate() {
        out[vert.node.idx()].push(v as u32);
    }
    out
}

/// The shortest straight material-space distance between a vert of node `a` and a vert of node
/// `b` in the same chart.
fn chart_distance(mesh: &Mesh, charts: &[u32], node_verts: &[Vec<u32>], a: usize, b: usize) -> Option<Real> {
    let mut best: Option<Real> = None;
    for &va in &node_verts[a] {
        for &vb in &node_verts[b] {
            if charts[va as usize] == charts[vb as usize] {
                let d = (mesh.verts[va as usize].u - mesh.verts[vb as usize].u).norm();
                best = Some(best.map_or(d, |x: Real| x.min(d)));
            }
        }
    }
    best
}

/// The straight material distance between nodes `a` and `b` through a pair of their verts in
/// one chart whose segment stays inside it.
fn visible_distance(
    mesh: &Mesh,
    charts: &[u32],
    node_verts: &[Vec<u32>],
    outline: &Outline,
    a: usize,
    b: usize,
) -> Option<Real> {
    let mut best: Option<Real> = None;
    for &va in &node_verts[a] {
        for &vb in &node_verts[b] {
            let c = charts[va as usize];
            let (p, q) = (mesh.verts[va as usize].u, mesh.verts[vb as usize].u);
            if c == charts[vb as usize] && outline.sees(c, p, q) {
                let d = (p - q).norm();
                best = Some(best.map_or(d, |x: Real| x.min(d)));
            }
        }
    }
    best
}

/// Islands of attached nodes (Algorithm 2): nodes joined by an edge of `mesh` are in one island.
/// Returns the island of each of `nodes` (numbered from 0 in order of first appearance).
pub fn islands(mesh: &Mesh, nodes: &[usize]) -> Vec<usize> {
    let mut index = std::collections::HashMap::new();
    for (k, &n) in nodes.iter().enumerate() {
        index.entry(n).or_insert(k);
    }
    let mut parent: Vec<usize> = (0..nodes.len()).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut join = |a: usize, b: usize| {
        if let (Some(&i), Some(&j)) = (index.get(&a), index.get(&b)) {
            let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
            parent[ri.max(rj)] = ri.min(rj);
        }
    };
    for f in 0..mesh.faces.len() {
        let [a, b, c] = mesh.face_nodes(f);
        join(a, b);
        join(b, c);
        join(c, a);
    }
    for (k, &n) in nodes.iter().enumerate() {
        let first = index[&n];
        let (rk, rf) = (root(&mut parent, k), root(&mut parent, first));
        parent[rk.max(rf)] = rk.min(rf);
    }
    let mut label = std::collections::HashMap::new();
    (0..nodes.len())
        .map(|k| {
            let r = root(&mut parent, k);
            let next = label.len();
            *label.entry(r).or_insert(next)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::rectangle;

    fn sheet() -> Mesh {
        let mut m = rectangle(1.0, 1.0, 10, 10).unwrap();
        m.compute_masses(&[0.1]);
        m
    }

    #[test]
    fn islands_join_adjacent_attachments_only() {
        let m = sheet();
        // Top row nodes 110..=120, plus the bottom-left corner 0 and its neighbour 1; and 5.
        let mut nodes: Vec<usize> = (110..=120).collect();
        nodes.extend([0, 1, 5]);
        let isl = islands(&m, &nodes);
        assert!(isl[..11].iter().all(|&i| i == 0));
        assert_eq!(isl[11], 1);
        assert_eq!(isl[12], 1);
        assert_eq!(isl[13], 2);
    }

    #[test]
    fn each_node_tied_to_the_closest_attachment_of_its_closest_islands() {
        let m = sheet();
        let att = [
            Attachment { node: 110, island: 0 },
            Attachment { node: 120, island: 1 },
            Attachment { node: 0, island: 2 },
        ];
        let p = LraParams { max_attachments: 2, ..Default::default() };
        let lra = Lra::build(&m, &att, &[Some(p)]);
        // Node 111 (top row, next to 110): its two closest islands are 0 (0.1 m) and 1 (0.9 m),
        // not 2 (1.005 m).
        let c: Vec<_> = lra.constraints.iter().filter(|c| c.node == 111).collect();
        assert_eq!(c.len(), 2);
        assert_eq!(c[0].attachment, 110);
        assert!((c[0].rest - 0.1).abs() < 1e-12);
        assert_eq!(c[1].attachment, 120);
        assert!((c[1].rest - 0.9).abs() < 1e-9, "{}", c[1].rest);
        assert!(lra.constraints.iter().all(|c| ![110, 120, 0].contains(&c.node)));
    }

    #[test]
    fn projection_is_unilateral_and_lands_on_the_sphere() {
        let lra = Lra {
            constraints: vec![
                Constraint { node: 1, attachment: 0, rest: 1.0, radius: 1.1 },
                Constraint { node: 2, attachment: 0, rest: 1.0, radius: 1.1 },
            ],
        };
        let mut x = vec![Vec3::zeros(), Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.5, 0.0, -0.5)];
        let before = x.clone();
        let mut moved = vec![false; 3];
        let p = lra.project(&mut x, &[0.0, 1.0, 1.0], &mut moved);
        assert_eq!(p.nodes, 1);
        assert!((x[1] - Vec3::new(0.0, 0.0, -1.1)).norm() < 1e-12);
        assert_eq!(x[2], before[2], "a node inside its sphere is not moved");
        assert!(!moved[2]);
    }

    #[test]
    fn two_attachments_pulling_apart_are_averaged_and_iterated() {
        let lra = Lra {
            constraints: vec![
                Constraint { node: 2, attachment: 0, rest: 1.0, radius: 1.0 },
                Constraint { node: 2, attachment: 1, rest: 1.0, radius: 1.0 },
            ],
        };
        let mut x = vec![Vec3::new(-0.6, 0.0, 0.0), Vec3::new(0.6, 0.0, 0.0), Vec3::new(0.0, 0.0, -2.0)];
        let mut moved = vec![false; 3];
        lra.project(&mut x, &[0.0, 0.0, 1.0], &mut moved);
        // The spheres meet at z = −0.8 on the axis; the Jacobi passes approach it.
        assert!(x[2].x.abs() < 1e-12);
        assert!((x[2].z + 0.8).abs() < 0.05, "{}", x[2].z);
    }
}
