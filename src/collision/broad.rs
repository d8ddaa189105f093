//! Broad phase: candidate vertex–face and edge–edge pairs from bounding-volume hierarchies over
//! cloth faces and edges and obstacle faces and edges (refit every call, rebuilt when a count
//! changes). Each primitive queries the trees once, in parallel; results are concatenated in
//! query order, so the candidate list is the same for any thread count.

use rayon::prelude::*;

use super::bvh::{Aabb, Bvh};
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;

/// A candidate pair: `VF` = `[p, a, b, c]` (vertex p, face abc), `EE` = `[a0, a1, b0, b1]`.
/// Indices below the cloth node count are cloth nodes, the others obstacle vertices.
pub const VF: u8 = 0;
pub const EE: u8 = 1;
pub type Candidate = (u8, [usize; 4]);

/// Positions over an interval (start and end; equal for a proximity query).
pub struct Interval<'a> {
    pub cloth0: &'a [Vec3],
    pub cloth1: &'a [Vec3],
    pub obs0: &'a [Vec3],
    pub obs1: &'a [Vec3],
}

impl Interval<'_> {
    fn cloth_box(&self, ids: &[usize]) -> Aabb {
        Aabb::from_points(ids.iter().map(|&i| &self.cloth0[i]))
            .merge(&Aabb::from_points(ids.iter().map(|&i| &self.cloth1[i])))
    }
    fn obs_box(&self, ids: &[usize]) -> Aabb {
        Aabb::from_points(ids.iter().map(|&i| &self.obs0[i]))
            .merge(&Aabb::from_points(ids.iter().map(|&i| &self.obs1[i])))
    }
}

#[derive(Default)]
pub struct BroadPhase {
    cloth_faces: Option<Bvh>,
    cloth_edges: Option<Bvh>,
    obs_faces: Option<Bvh>,
    obs_edges: Option<Bvh>,
}

fn refit(slot: &mut Option<Bvh>, boxes: &[Aabb]) -> Bvh {
    match slot.take() {
        Some(mut t) if t.len() == boxes.len() => {
            t.refit(boxes);
            t
        }
        _ => Bvh::build(boxes),
    }
}

fn sorted_edge(a: usize, b: usize) -> [usize; 2] {
    [a.min(b), a.max(b)]
}

impl BroadPhase {
    /// All candidates whose boxes, the query's inflated by `pad`, overlap over the interval.
    pub fn candidates(
        &mut self,
        mesh: &Mesh,
        obs_tris: &[[usize; 3]],
        obs_edges: &[[usize; 2]],
        iv: &Interval,
        pad: Real,
        self_collision: bool,
    ) -> Vec<Candidate> {
        let n = mesh.nodes.len();
        let faces: Vec<[usize; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).collect();
        let edges: Vec<[usize; 2]> = mesh.edges.iter().map(|e| sorted_edge(e.n[0].idx(), e.n[1].idx())).collect();
        let face_boxes: Vec<Aabb> = faces.par_iter().map(|f| iv.cloth_box(f)).collect();
        let edge_boxes: Vec<Aabb> = edges.par_iter().map(|e| iv.cloth_box(e)).collect();
        let node_boxes: Vec<Aabb> = (0..n).into_par_iter().map(|i| iv.cloth_box(&[i]).inflate(pad)).collect();
        let cf = refit(&mut self.cloth_faces, &face_boxes);
        let ce = refit(&mut self.cloth_edges, &edge_boxes);
        let mut out: Vec<Candidate> = Vec::new();

        if !obs_tris.is_empty() {
            let of_boxes: Vec<Aabb> = obs_tris.par_iter().map(|t| iv.obs_box(t)).collect();
            let oe_boxes: Vec<Aabb> = obs_edges.par_iter().map(|e| iv.obs_box(e)).collect();
            let of = refit(&mut self.obs_faces, &of_boxes);
            let oe = refit(&mut self.obs_edges, &oe_boxes);
            // Cloth node vs obstacle face.
            out.extend(collect(0..n, |p, v| {
                of.query(&node_boxes[p], &of_boxes, |t| {
                    let o = obs_tris[t];
                    v.push((VF, [p, o[0] + n, o[1] + n, o[2] + n]));
                })
            }));
            // Obstacle vertex vs cloth face.
            out.extend(collect(0..iv.obs1.len(), |k, v| {
                let q = iv.obs_box(&[k]).inflate(pad);
                cf.query(&q, &face_boxes, |f| {
                    let c = faces[f];
                    v.push((VF, [k + n, c[0], c[1], c[2]]));
                })
            }));
            // Cloth edge vs obstacle edge.
            out.extend(collect(0..edges.len(), |e, v| {
                oe.query(&edge_boxes[e].inflate(pad), &oe_boxes, |k| {
                    let [a, b] = edges[e];
                    let [c, d] = obs_edges[k];
                    v.push((EE, [a, b, c + n, d + n]));
                })
            }));
            self.obs_faces = Some(of);
            self.obs_edges = Some(oe);
        }
        if self_collision {
            // Cloth node vs cloth face not containing it.
            out.extend(collect(0..n, |p, v| {
                cf.query(&node_boxes[p], &face_boxes, |f| {
                    let c = faces[f];
                    if !c.contains(&p) {
                        v.push((VF, [p, c[0], c[1], c[2]]));
                    }
                })
            }));
            // Cloth edge vs cloth edge, each unordered pair once, no shared node.
            out.extend(collect(0..edges.len(), |e, v| {
                ce.query(&edge_boxes[e].inflate(pad), &edge_boxes, |g| {
                    let ([a, b], [c, d]) = (edges[e], edges[g]);
                    if e < g && a != c && a != d && b != c && b != d {
                        v.push((EE, [a, b, c, d]));
                    }
                })
            }));
        }
        self.cloth_faces = Some(cf);
        self.cloth_edges = Some(ce);
        out
    }
}

/// Runs `query(i, &mut found)` for each `i` in parallel and concatenates in index order. Each
/// query's results are sorted: the order a tree finds them in depends on the tree's shape,
/// hence on the positions it was built at, and a resumed run rebuilds its trees elsewhere.
fn collect(range: std::ops::Range<usize>, query: impl Fn(usize, &mut Vec<Candidate>) + Sync) -> Vec<Candidate> {
    range
        .into_par_iter()
        .fold(Vec::new, |mut v, i| {
            let start = v.len();
            query(i, &mut v);
            v[start..].sort_unstable();
            v
        })
        .reduce(Vec::new, |mut a, mut b| {
            a.append(&mut b);
            a
        })
}
