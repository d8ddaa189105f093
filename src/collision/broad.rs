//! Broad phase: candidate vertex–face and edge–edge pairs from bounding-volume hierarchies over
//! cloth nodes, faces and edges and obstacle vertices, faces and edges (refit every call, rebuilt
//! when a count changes), searched tree against tree in parallel; results are put in query order,
//! so the candidate list is the same for any thread count.

use crate::math::PAR_GRAIN;
use rayon::prelude::*;

use super::bvh::{Aabb, Bvh};
use crate::math::{same_bits, Real, Vec3};
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

/// The boxes by their definition, for the tests (the search merges its points' `spans`).
#[cfg(test)]
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

/// The trees of the last search, refitted to the next one's boxes while the primitives are the
/// same ones (`keys`), rebuilt when they are not: a remesh that keeps the face count renumbers
/// the faces, and a tree refitted over other primitives stays correct but loses its locality
/// (dart.json: frames whose remesh kept the count spent 7–9 s instead of 0.25 s in each of
/// proximity and collision).
///
/// The obstacles' boxes and trees are kept with the positions they were fitted to (`ObsFit`): the
/// proximity search and every collision iteration of a step sweep the obstacles over the same
/// interval, so the later searches of a step take them as they are instead of recomputing
/// every obstacle primitive's box (on a crowd of five dancers, 134k obstacle faces, that was a
/// quarter of each search). Compared bit for bit, so they are exactly the boxes a recomputation
/// would give.
#[derive(Default)]
pub struct BroadPhase {
    /// The cloth's triangles and the obstacles' the trees were built over.
    cloth_key: Vec<[usize; 3]>,
    obs_key: Vec<[usize; 3]>,
    cloth_faces: Option<Bvh>,
    cloth_edges: Option<Bvh>,
    cloth_nodes: Option<Bvh>,
    obs_fit: Option<ObsFit>,
}

/// The obstacle trees and what they are fitted to: the interval's obstacle positions (faces'
/// and edges' boxes over it), and the padding the vertex boxes are inflated by (the one part
/// that depends on the search). The trees hold the boxes.
struct ObsFit {
    obs0: Vec<Vec3>,
    obs1: Vec<Vec3>,
    pad: Real,
    /// Each vertex's box over the interval (`spans`).
    spans: Vec<Aabb>,
    face_tree: Bvh,
    edge_tree: Bvh,
    node_tree: Bvh,
}

impl ObsFit {
    /// Whether the fit is for these positions (bitwise: a signed zero counts as a change).
    fn holds(&self, iv: &Interval) -> bool {
        same_bits(&self.obs0, iv.obs0) && same_bits(&self.obs1, iv.obs1)
    }
}

/// The tree of `count` primitives, primitive p's box `boxed(p)`: the one in `slot` refitted when
/// it has as many, built otherwise.
fn fit(slot: &mut Option<Bvh>, count: usize, boxed: impl Fn(usize) -> Aabb + Sync) -> Bvh {
    match slot.take() {
        Some(mut t) if t.len() == count => {
            t.refit_by(boxed);
            t
        }
        _ => Bvh::build(&(0..count).into_par_iter().with_min_len(PAR_GRAIN).map(&boxed).collect::<Vec<_>>()),
    }
}

/// Each point's box over the interval (its start and end positions). A primitive's box over
/// the interval is the merge of its points' (a minimum of the same coordinates), so the
/// primitives' boxes are merged from these.
fn spans(x0: &[Vec3], x1: &[Vec3]) -> Vec<Aabb> {
    x0.par_iter().with_min_len(PAR_GRAIN).zip(x1).map(|(a, b)| Aabb::from_points([a, b])).collect()
}

fn merged<const K: usize>(spans: &[Aabb], ids: &[usize; K]) -> Aabb {
    ids.iter().fold(Aabb::empty(), |a, &i| a.merge(&spans[i]))
}

fn sorted_edge(a: usize, b: usize) -> [usize; 2] {
    [a.min(b), a.max(b)]
}

/// A candidate found for query primitive `.0` (the index the candidate list is ordered by).
type Found<T> = (u32, Candidate, T);

impl BroadPhase {
    /// All candidates whose boxes, the query's inflated by `pad`, overlap over the interval.
    ///
    /// The list is ordered by query primitive (cloth node, obstacle vertex, cloth edge), each
    /// query's candidates sorted: the order a tree finds them in depends on the tree's shape,
    /// hence on the positions it was built at, and a resumed run rebuilds its trees elsewhere.
    /// The trees are searched against each other (`Bvh::overlapping`), and every reported pair
    /// passes the same box test a per-query search would apply, so the list is the same.
    /// (The simulation calls `search`; this is its reference form for the tests.)
    #[cfg(test)]
    pub fn candidates(
        &mut self,
        mesh: &Mesh,
        obs_tris: &[[usize; 3]],
        obs_edges: &[[usize; 2]],
        iv: &Interval,
        pad: Real,
        self_collision: bool,
    ) -> Vec<Candidate> {
        let found = self.search(mesh, obs_tris, obs_edges, iv, pad, self_collision, |_| Some(()));
        found.into_iter().map(|(c, ())| c).collect()
    }

    /// `candidates` with the narrow phase run where each candidate is found: `narrow(c)`'s
    /// results that are `Some`, in the candidates' order, without building the candidate
    /// list.
    #[allow(clippy::too_many_arguments)]
    pub fn search<T: Send>(
        &mut self,
        mesh: &Mesh,
        obs_tris: &[[usize; 3]],
        obs_edges: &[[usize; 2]],
        iv: &Interval,
        pad: Real,
        self_collision: bool,
        narrow: impl Fn(Candidate) -> Option<T> + Sync,
    ) -> Vec<(Candidate, T)> {
        let keep = |q: usize, c: Candidate, v: &mut Vec<Found<T>>| {
            if let Some(t) = narrow(c) {
                v.push((q as u32, c, t));
            }
        };
        let n = mesh.nodes.len();
        let faces: Vec<[usize; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).collect();
        let edges: Vec<[usize; 2]> = mesh.edges.iter().map(|e| sorted_edge(e.n[0].idx(), e.n[1].idx())).collect();
        self.forget_changed(&faces, obs_tris);
        let cloth = spans(iv.cloth0, iv.cloth1);
        let cf = fit(&mut self.cloth_faces, faces.len(), |f| merged(&cloth, &faces[f]));
        let ce = fit(&mut self.cloth_edges, edges.len(), |e| merged(&cloth, &edges[e]));
        let cn = fit(&mut self.cloth_nodes, n, |i| cloth[i].inflate(pad));
        // A query edge's box is its edge box inflated by `pad`; inflating a node's box instead
        // bounds every inflated leaf box below it (rounding is monotone).
        let near_padded = |a: &Aabb, b: &Aabb| a.inflate(pad).overlaps(b);
        let near = |a: &Aabb, b: &Aabb| a.overlaps(b);
        let mut out: Vec<(Candidate, T)> = Vec::new();

        if !obs_tris.is_empty() {
            let fit = self.fit_obstacles(obs_tris, obs_edges, iv, pad);
            let (of, oe, on) = (&fit.face_tree, &fit.edge_tree, &fit.node_tree);
            // Cloth node vs obstacle face.
            let found = cn.overlapping(of, false, near, |(p, pb), (t, tb), v: &mut Vec<Found<T>>| {
                if tb.overlaps(pb) {
                    let o = obs_tris[t];
                    keep(p, (VF, [p, o[0] + n, o[1] + n, o[2] + n]), v);
                }
            });
            out.extend(by_query(found, n));
            // Obstacle vertex vs cloth face.
            let found = on.overlapping(&cf, false, near, |(k, kb), (f, fb), v: &mut Vec<Found<T>>| {
                if fb.overlaps(kb) {
                    let c = faces[f];
                    keep(k, (VF, [k + n, c[0], c[1], c[2]]), v);
                }
            });
            out.extend(by_query(found, iv.obs1.len()));
            // Cloth edge vs obstacle edge.
            let found = ce.overlapping(oe, false, near_padded, |(e, eb), (k, kb), v: &mut Vec<Found<T>>| {
                if kb.overlaps(&eb.inflate(pad)) {
                    let [a, b] = edges[e];
                    let [c, d] = obs_edges[k];
                    keep(e, (EE, [a, b, c + n, d + n]), v);
                }
            });
            out.extend(by_query(found, edges.len()));
            self.obs_fit = Some(fit);
        }
        if self_collision {
            // Cloth node vs cloth face not containing it.
            let found = cn.overlapping(&cf, false, near, |(p, pb), (f, fb), v: &mut Vec<Found<T>>| {
                let c = faces[f];
                if fb.overlaps(pb) && !c.contains(&p) {
                    keep(p, (VF, [p, c[0], c[1], c[2]]), v);
                }
            });
            out.extend(by_query(found, n));
            // Cloth edge vs cloth edge, each unordered pair once (queried from the lower
            // index), no shared node. The tree meets a pair from either side, so its nodes are
            // near when either one's inflated box overlaps the other.
            let near_either = |a: &Aabb, b: &Aabb| near_padded(a, b) || near_padded(b, a);
            let found = ce.overlapping(&ce, true, near_either, |p, q, v: &mut Vec<Found<T>>| {
                let ((e, eb), (g, gb)) = if p.0 < q.0 { (p, q) } else { (q, p) };
                let ([a, b], [c, d]) = (edges[e], edges[g]);
                if a != c && a != d && b != c && b != d && gb.overlaps(&eb.inflate(pad)) {
                    keep(e, (EE, [a, b, c, d]), v);
                }
            });
            out.extend(by_query(found, edges.len()));
        }
        self.cloth_faces = Some(cf);
        self.cloth_edges = Some(ce);
        self.cloth_nodes = Some(cn);
        out
    }
}

impl BroadPhase {
    /// Drops the trees whose primitives changed since they were built (edges and nodes follow
    /// from the triangles).
    fn forget_changed(&mut self, faces: &[[usize; 3]], obs_tris: &[[usize; 3]]) {
        if self.cloth_key != faces {
            (self.cloth_faces, self.cloth_edges, self.cloth_nodes) = (None, None, None);
            self.cloth_key = faces.to_vec();
        }
        if self.obs_key != obs_tris {
            self.obs_fit = None;
            self.obs_key = obs_tris.to_vec();
        }
    }

    /// The obstacle boxes over `iv` (vertex boxes inflated by `pad`) with the obstacle trees
    /// fitted to them: the last search's where it was over the same positions (and, for the
    /// vertices, the same pad), recomputed and its trees refitted otherwise (built for the first
    /// search over these triangles). Call after `forget_changed`.
    fn fit_obstacles(&mut self, obs_tris: &[[usize; 3]], obs_edges: &[[usize; 2]], iv: &Interval, pad: Real) -> ObsFit {
        match self.obs_fit.take() {
            Some(fit) if fit.holds(iv) && fit.pad.to_bits() == pad.to_bits() => fit,
            Some(mut fit) if fit.holds(iv) => {
                fit.pad = pad;
                let spans = &fit.spans;
                fit.node_tree.refit_by(|k| spans[k].inflate(pad));
                fit
            }
            old => {
                let spans = spans(iv.obs0, iv.obs1);
                let (mut ft, mut et, mut nt) = match old {
                    Some(f) => (Some(f.face_tree), Some(f.edge_tree), Some(f.node_tree)),
                    None => (None, None, None),
                };
                let face_tree = fit(&mut ft, obs_tris.len(), |t| merged(&spans, &obs_tris[t]));
                let edge_tree = fit(&mut et, obs_edges.len(), |e| merged(&spans, &obs_edges[e]));
                let node_tree = fit(&mut nt, spans.len(), |k| spans[k].inflate(pad));
                ObsFit { obs0: iv.obs0.to_vec(), obs1: iv.obs1.to_vec(), pad, spans, face_tree, edge_tree, node_tree }
            }
        }
    }
}

/// Orders candidates by query primitive (a counting sort over `0..queries`), each query's
/// candidates sorted.
fn by_query<T>(found: Vec<Found<T>>, queries: usize) -> Vec<(Candidate, T)> {
    let mut start = vec![0usize; queries + 1];
    for &(q, ..) in &found {
        start[q as usize + 1] += 1;
    }
    for q in 0..queries {
        start[q + 1] += start[q];
    }
    let mut slot = vec![0usize; found.len()];
    let mut next = start.clone();
    for (k, &(q, ..)) in found.iter().enumerate() {
        slot[k] = next[q as usize];
        next[q as usize] += 1;
    }
    let mut placed: Vec<Option<(Candidate, T)>> = (0..found.len()).map(|_| None).collect();
    for (k, (_, c, t)) in found.into_iter().enumerate() {
        placed[slot[k]] = Some((c, t));
    }
    let mut out: Vec<(Candidate, T)> = placed.into_iter().map(|x| x.expect("every slot is filled once")).collect();
    for q in 0..queries {
        if start[q + 1] - start[q] > 1 {
            // Equal candidates (a duplicated primitive) carry equal results.
            out[start[q]..start[q + 1]].sort_unstable_by_key(|x| x.0);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::rectangle;

    /// The definition the tree–tree search must reproduce: every query primitive against every
    /// target by the same box test, in query order, each query's candidates sorted.
    fn brute(
        mesh: &Mesh,
        obs_tris: &[[usize; 3]],
        obs_edges: &[[usize; 2]],
        iv: &Interval,
        pad: Real,
    ) -> Vec<Candidate> {
        let n = mesh.nodes.len();
        let faces: Vec<[usize; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).collect();
        let edges: Vec<[usize; 2]> = mesh.edges.iter().map(|e| sorted_edge(e.n[0].idx(), e.n[1].idx())).collect();
        let fb: Vec<Aabb> = faces.iter().map(|f| iv.cloth_box(f)).collect();
        let eb: Vec<Aabb> = edges.iter().map(|e| iv.cloth_box(e)).collect();
        let ofb: Vec<Aabb> = obs_tris.iter().map(|t| iv.obs_box(t)).collect();
        let oeb: Vec<Aabb> = obs_edges.iter().map(|e| iv.obs_box(e)).collect();
        let mut out = Vec::new();
        let mut section = |queries: usize, each: &dyn Fn(usize, &mut Vec<Candidate>)| {
            for q in 0..queries {
                let mut v = Vec::new();
                each(q, &mut v);
                v.sort_unstable();
                out.extend(v);
            }
        };
        section(n, &|p, v| {
            let q = iv.cloth_box(&[p]).inflate(pad);
            for (t, o) in obs_tris.iter().enumerate() {
                if ofb[t].overlaps(&q) {
                    v.push((VF, [p, o[0] + n, o[1] + n, o[2] + n]));
                }
            }
        });
        section(iv.obs1.len(), &|k, v| {
            let q = iv.obs_box(&[k]).inflate(pad);
            for (f, c) in faces.iter().enumerate() {
                if fb[f].overlaps(&q) {
                    v.push((VF, [k + n, c[0], c[1], c[2]]));
                }
            }
        });
        section(edges.len(), &|e, v| {
            for (k, &[c, d]) in obs_edges.iter().enumerate() {
                if oeb[k].overlaps(&eb[e].inflate(pad)) {
                    v.push((EE, [edges[e][0], edges[e][1], c + n, d + n]));
                }
            }
        });
        section(n, &|p, v| {
            let q = iv.cloth_box(&[p]).inflate(pad);
            for (f, c) in faces.iter().enumerate() {
                if fb[f].overlaps(&q) && !c.contains(&p) {
                    v.push((VF, [p, c[0], c[1], c[2]]));
                }
            }
        });
        section(edges.len(), &|e, v| {
            let [a, b] = edges[e];
            for (g, &[c, d]) in edges.iter().enumerate() {
                if e < g && a != c && a != d && b != c && b != d && eb[g].overlaps(&eb[e].inflate(pad)) {
                    v.push((EE, [a, b, c, d]));
                }
            }
        });
        out
    }

    /// A crumpled sheet moving over an interval against a second, moving sheet as the obstacle:
    /// the tree–tree candidates equal the per-query definition, before and after a refit.
    #[test]
    fn candidates_match_brute_force() {
        let mut s = 7u64;
        let mut rnd = move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as Real / (1u64 << 53) as Real - 0.5
        };
        let mut mesh = rectangle(1.0, 1.0, 12, 12).unwrap();
        let obstacle = rectangle(1.0, 1.0, 9, 9).unwrap();
        let obs_tris: Vec<[usize; 3]> = (0..obstacle.faces.len()).map(|f| obstacle.face_nodes(f)).collect();
        let mut obs_edges: Vec<[usize; 2]> =
            obstacle.edges.iter().map(|e| sorted_edge(e.n[0].idx(), e.n[1].idx())).collect();
        obs_edges.sort_unstable();
        let mut broad = BroadPhase::default();
        for round in 0..3 {
            for node in &mut mesh.nodes {
                node.x += Vec3::new(rnd(), rnd(), rnd()) * 0.05;
            }
            let x0 = mesh.positions();
            let x1: Vec<Vec3> = x0.iter().map(|x| x + Vec3::new(rnd(), rnd(), rnd()) * 0.02).collect();
            let o0: Vec<Vec3> = obstacle.nodes.iter().map(|n| n.x + Vec3::new(rnd(), rnd(), 0.3 * rnd())).collect();
            let o1: Vec<Vec3> = o0.iter().map(|x| x + Vec3::new(rnd(), rnd(), rnd()) * 0.02).collect();
            let iv = Interval { cloth0: &x0, cloth1: &x1, obs0: &o0, obs1: &o1 };
            for pad in [1e-6, 0.01, 0.05] {
                let got = broad.candidates(&mesh, &obs_tris, &obs_edges, &iv, pad, true);
                let want = brute(&mesh, &obs_tris, &obs_edges, &iv, pad);
                assert!(want.len() > 100, "round {round}, pad {pad}: too few candidates to test");
                assert_eq!(got, want, "round {round}, pad {pad}");
            }
            // The cloth moves on within the same obstacle interval (a later collision iteration
            // of the step): the obstacles' boxes and trees are the kept ones.
            let x2: Vec<Vec3> = x1.iter().map(|x| x + Vec3::new(rnd(), rnd(), rnd()) * 0.02).collect();
            let iv = Interval { cloth0: &x1, cloth1: &x2, obs0: &o0, obs1: &o1 };
            let got = broad.candidates(&mesh, &obs_tris, &obs_edges, &iv, 0.05, true);
            assert!(broad.obs_fit.as_ref().is_some_and(|f| f.holds(&iv) && f.pad == 0.05));
            assert_eq!(got, brute(&mesh, &obs_tris, &obs_edges, &iv, 0.05), "round {round}, cloth moved");
        }
    }

    #[test]
    fn trees_are_rebuilt_when_the_faces_are_renumbered() {
        let mut mesh = rectangle(1.0, 1.0, 6, 6).unwrap();
        let x = mesh.positions();
        let iv = Interval { cloth0: &x, cloth1: &x, obs0: &[], obs1: &[] };
        let mut broad = BroadPhase::default();
        let first = broad.candidates(&mesh, &[], &[], &iv, 0.01, true);
        let faces = |m: &Mesh| (0..m.faces.len()).map(|f| m.face_nodes(f)).collect::<Vec<_>>();
        broad.forget_changed(&faces(&mesh), &[]);
        assert!(broad.cloth_faces.is_some(), "the same faces: the trees are kept (refitted)");
        // A remesh that keeps the count but renumbers: same candidates, trees of its own.
        mesh.faces.reverse();
        mesh.rebuild_topology().unwrap();
        broad.forget_changed(&faces(&mesh), &[]);
        assert!(broad.cloth_faces.is_none() && broad.cloth_edges.is_none() && broad.cloth_nodes.is_none());
        let again = broad.candidates(&mesh, &[], &[], &iv, 0.01, true);
        assert_eq!(again.len(), first.len());
    }
}
