//! Broad phase: candidate vertex–face and edge–edge pairs from bounding-volume hierarchies over
//! cloth nodes, faces and edges and obstacle vertices, faces and edges (refit when searched,
//! rebuilt when a count changes), searched tree against tree in parallel, the cloth's own pairs
//! kept between searches where that pays (`BroadPhase`); results are put in query order, so the candidate list is the same for
//! any thread count.

use std::time::Instant;

use crate::math::PAR_GRAIN;
use rayon::prelude::*;

use super::bvh::{Aabb, Bvh};
use crate::math::{same_bits, Real, Vec3};
use crate::mesh::Mesh;
use lists::{grown, overlap, tight, ListSlot, PairList, SERVED};

mod lists;

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
/// same ones (`cloth_key`, `obs_key`), rebuilt when they are not: a remesh that keeps the face
/// count renumbers the faces, and a tree refitted over other primitives stays correct but loses
/// its locality (dart.json: frames whose remesh kept the count spent 7–9 s instead of 0.25 s in each of
/// proximity and collision).
///
/// **Cloth–cloth pair lists kept between searches** (issue 17, "proximity and collision
/// coherence"; the Verlet list of molecular dynamics). The cloth's own pairs can be found with
/// every cloth node's box grown (`grown`: three times its travel over the search's interval,
/// plus `reach`, the collision thickness) and kept with those grown boxes (`PairList`, one per
/// pad: the proximity search's and the collision iterations'). A later search whose nodes' boxes
/// all lie within the kept ones takes the kept list instead of searching the trees, and applies
/// to each candidate the box test the tree search applies at its leaves (`overlap`): a pair
/// whose boxes overlap now overlapped within the grown boxes, so it is in the list (containment
/// and the boxes' rounding are monotone), and the list is in the tree search's order. So the
/// candidates, and what the narrow phase makes of them, are exactly a fresh search's: the same
/// bits whether a list was kept or not, and a resumed run finds what the uninterrupted one did.
/// A list is found again as soon as one node leaves its grown box, or the primitives change.
/// Whether one is found at all depends on what it would cost: only where the growth is small
/// beside the edges (`tight`), the grown boxes have held for a few searches (`SERVED`), and
/// the last list cost less per search than the trees (`ListSlot`). Where lists pay is small
/// meshes, whose tree search is mostly fixed cost (ARCSim's square.json: 0.2 ms a search for
/// 400 candidates), and slow cloth. The cloth–obstacle pairs are searched afresh every time: a
/// character's vertices outnumber the garment's and its hands outrun any growth that keeps a
/// list small.
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
    lists: Vec<ListSlot>,
    /// Lists are kept only where they are measured to cost less than the trees (`ListSlot`);
    /// a test keeps them wherever the boxes hold.
    #[cfg(test)]
    always_keep: bool,
    /// Searches of the trees for cloth–cloth pairs (for the tests: how often a list was found
    /// anew).
    #[cfg(test)]
    cloth_searches: usize,
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

/// Which pairs a tree search finds: the cloth's against the obstacles', the cloth's against its
/// own, or both.
#[derive(Clone, Copy)]
struct Sections {
    obstacles: bool,
    cloth: bool,
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
    #[allow(clippy::too_many_arguments)]
    pub fn candidates(
        &mut self,
        mesh: &Mesh,
        obs_tris: &[[usize; 3]],
        obs_edges: &[[usize; 2]],
        iv: &Interval,
        pad: Real,
        reach: Real,
        self_collision: bool,
    ) -> Vec<Candidate> {
        let found = self.search(mesh, obs_tris, obs_edges, iv, pad, reach, self_collision, |_| Some(()));
        found.into_iter().map(|(c, ())| c).collect()
    }

    /// `candidates` with the narrow phase run on each candidate: `narrow(c)`'s results that are
    /// `Some`, in the candidates' order. From the kept pair list while the points stay within
    /// `reach` of where it was found (struct doc), from the trees otherwise.
    #[allow(clippy::too_many_arguments)]
    pub fn search<T: Send>(
        &mut self,
        mesh: &Mesh,
        obs_tris: &[[usize; 3]],
        obs_edges: &[[usize; 2]],
        iv: &Interval,
        pad: Real,
        reach: Real,
        self_collision: bool,
        narrow: impl Fn(Candidate) -> Option<T> + Sync,
    ) -> Vec<(Candidate, T)> {
        let faces: Vec<[usize; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).collect();
        self.forget_changed(&faces, obs_tris);
        let edges: Vec<[usize; 2]> = mesh.edges.iter().map(|e| sorted_edge(e.n[0].idx(), e.n[1].idx())).collect();
        let cloth = spans(iv.cloth0, iv.cloth1);
        let both = Sections { obstacles: true, cloth: self_collision };
        if !self_collision {
            return self.tree_search(&faces, &edges, obs_tris, obs_edges, &cloth, iv, pad, both, &narrow);
        }
        let list_at = |this: &mut Self, boxes: &[Aabb]| -> Vec<Candidate> {
            let all = |_| Some(());
            let own = Sections { obstacles: false, cloth: true };
            let found = this.tree_search(&faces, &edges, &[], &[], boxes, iv, pad, own, all);
            found.into_iter().map(|(c, ())| c).collect()
        };
        let k = match self.lists.iter().position(|l| l.pad == pad.to_bits()) {
            Some(k) => k,
            None => {
                let slot = ListSlot { pad: pad.to_bits(), list: None, tree_s: Real::INFINITY, wait: 0, skip: 0 };
                self.lists.push(slot);
                self.lists.len() - 1
            }
        };
        // Both ways of searching are timed whole (the cloth–obstacle pairs included), so that
        // their costs compare.
        let clock = Instant::now();
        self.lists[k].skip = self.lists[k].skip.saturating_sub(1);
        let mut list = match self.lists[k].list.take() {
            Some(mut list) if list.holds(&cloth) => {
                list.served += 1;
                if list.candidates.is_none() && list.tight && list.served >= SERVED && self.keeps(k) {
                    // The grown boxes have held long enough: the list is found within them.
                    list.candidates = Some(list_at(self, &list.cloth));
                }
                list
            }
            last => {
                // The last list is judged, and a new one grown at these boxes: found at once
                // where the last one was and paid.
                let at_once = self.judge(k, last.as_ref());
                let growth: Vec<Real> = cloth.par_iter().with_min_len(PAR_GRAIN).map(|b| grown(b, reach)).collect();
                let grown: Vec<Aabb> = cloth.iter().zip(&growth).map(|(b, &g)| b.inflate(g)).collect();
                let tight = self.forced() || tight(&growth, &cloth, &edges);
                let candidates = (at_once && tight).then(|| list_at(self, &grown));
                PairList { cloth: grown, tight, candidates, served: 1, listed: 0, spent: 0.0 }
            }
        };
        let out = match &list.candidates {
            Some(candidates) => {
                let others = Sections { obstacles: true, cloth: false };
                let mut out = self.tree_search(&faces, &edges, obs_tris, obs_edges, &cloth, iv, pad, others, &narrow);
                out.par_extend(candidates.par_iter().with_min_len(PAR_GRAIN).filter_map(|&c| {
                    match overlap(&c, pad, |i| &cloth[i]) {
                        true => narrow(c).map(|t| (c, t)),
                        false => None,
                    }
                }));
                list.listed += 1;
                list.spent += clock.elapsed().as_secs_f64();
                out
            }
            None => {
                let out = self.tree_search(&faces, &edges, obs_tris, obs_edges, &cloth, iv, pad, both, &narrow);
                let t = clock.elapsed().as_secs_f64();
                let slot = &mut self.lists[k];
                slot.tree_s = if slot.tree_s.is_finite() { 0.8 * slot.tree_s + 0.2 * t } else { t };
                out
            }
        };
        self.lists[k].list = Some(list);
        out
    }

    /// `search` for the cloth node boxes `cloth` and the obstacles over `iv`, from the trees:
    /// `narrow`'s results that are `Some`, run where each candidate is found, in the
    /// candidates' order.
    #[allow(clippy::too_many_arguments)]
    fn tree_search<T: Send>(
        &mut self,
        faces: &[[usize; 3]],
        edges: &[[usize; 2]],
        obs_tris: &[[usize; 3]],
        obs_edges: &[[usize; 2]],
        cloth: &[Aabb],
        iv: &Interval,
        pad: Real,
        sections: Sections,
        narrow: impl Fn(Candidate) -> Option<T> + Sync,
    ) -> Vec<(Candidate, T)> {
        let keep = |q: usize, c: Candidate, v: &mut Vec<Found<T>>| {
            if let Some(t) = narrow(c) {
                v.push((q as u32, c, t));
            }
        };
        if !sections.cloth && obs_tris.is_empty() {
            return Vec::new();
        }
        #[cfg(test)]
        {
            self.cloth_searches += usize::from(sections.cloth);
        }
        let n = cloth.len();
        let cf = fit(&mut self.cloth_faces, faces.len(), |f| merged(cloth, &faces[f]));
        let ce = fit(&mut self.cloth_edges, edges.len(), |e| merged(cloth, &edges[e]));
        let cn = fit(&mut self.cloth_nodes, n, |i| cloth[i].inflate(pad));
        // A query edge's box is its edge box inflated by `pad`; inflating a node's box instead
        // bounds every inflated leaf box below it (rounding is monotone).
        let near_padded = |a: &Aabb, b: &Aabb| a.inflate(pad).overlaps(b);
        let near = |a: &Aabb, b: &Aabb| a.overlaps(b);
        let mut out: Vec<(Candidate, T)> = Vec::new();

        if sections.obstacles && !obs_tris.is_empty() {
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
        if sections.cloth {
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
    /// Drops the trees and pair lists whose primitives changed since they were built (edges and
    /// nodes follow from the triangles).
    fn forget_changed(&mut self, faces: &[[usize; 3]], obs_tris: &[[usize; 3]]) {
        if self.cloth_key != faces {
            (self.cloth_faces, self.cloth_edges, self.cloth_nodes) = (None, None, None);
            self.cloth_key = faces.to_vec();
            self.lists.iter_mut().for_each(|slot| slot.list = None);
        }
        if self.obs_key != obs_tris {
            self.obs_fit = None;
            self.obs_key = obs_tris.to_vec();
            self.lists.iter_mut().for_each(|slot| slot.list = None);
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

    /// Uniform numbers in [-0.5, 0.5) from `seed` (a linear congruential generator).
    fn uniform(seed: u64) -> impl FnMut() -> Real {
        let mut s = seed;
        move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as Real / (1u64 << 53) as Real - 0.5
        }
    }

    /// A square sheet of side `size` and `n` × `n` cells as an obstacle: the mesh, its triangles
    /// and its sorted edges.
    fn obstacle_sheet(size: Real, n: usize) -> (Mesh, Vec<[usize; 3]>, Vec<[usize; 2]>) {
        let obstacle = rectangle(size, size, n, n).unwrap();
        let tris: Vec<[usize; 3]> = (0..obstacle.faces.len()).map(|f| obstacle.face_nodes(f)).collect();
        let mut edges: Vec<[usize; 2]> =
            obstacle.edges.iter().map(|e| sorted_edge(e.n[0].idx(), e.n[1].idx())).collect();
        edges.sort_unstable();
        (obstacle, tris, edges)
    }

    /// A crumpled sheet moving over an interval against a second, moving sheet as the obstacle:
    /// the tree–tree candidates equal the per-query definition, before and after a refit.
    #[test]
    fn candidates_match_brute_force() {
        let mut rnd = uniform(7);
        let mut mesh = rectangle(1.0, 1.0, 12, 12).unwrap();
        let (obstacle, obs_tris, obs_edges) = obstacle_sheet(1.0, 9);
        let mut broad = BroadPhase { always_keep: true, ..Default::default() };
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
                let got = broad.candidates(&mesh, &obs_tris, &obs_edges, &iv, pad, 0.03, true);
                let want = brute(&mesh, &obs_tris, &obs_edges, &iv, pad);
                assert!(want.len() > 100, "round {round}, pad {pad}: too few candidates to test");
                assert_eq!(got, want, "round {round}, pad {pad}");
            }
            // The cloth moves on within the same obstacle interval, each node by at most 1 cm (a
            // later collision iteration of the step): within the 3 cm reach, so the list found
            // above serves, and gives the definition's candidates.
            let searched = broad.cloth_searches;
            let x2: Vec<Vec3> = x1.iter().map(|x| x + Vec3::new(rnd(), rnd(), rnd()) * 0.02).collect();
            let iv = Interval { cloth0: &x1, cloth1: &x2, obs0: &o0, obs1: &o1 };
            let got = broad.candidates(&mesh, &obs_tris, &obs_edges, &iv, 0.05, 0.03, true);
            assert_eq!(broad.cloth_searches, searched, "round {round}: the kept list serves");
            assert_eq!(got, brute(&mesh, &obs_tris, &obs_edges, &iv, 0.05), "round {round}, cloth moved");
        }
    }

    /// A sheet crumpling over many small steps against a moving obstacle sheet, each search's
    /// candidates and narrow-phase results from the kept lists equal to a fresh broad phase's
    /// (no list kept: reach 0 and a new `BroadPhase` each time) and to the definition; the lists
    /// serve most searches and are searched anew as the points leave them.
    #[test]
    fn kept_pair_lists_give_a_fresh_searchs_pairs() {
        let mut rnd = uniform(11);
        let mut mesh = rectangle(1.0, 1.0, 10, 10).unwrap();
        let (obstacle, obs_tris, obs_edges) = obstacle_sheet(0.8, 7);
        let mut obs: Vec<Vec3> = obstacle.nodes.iter().map(|n| n.x + Vec3::new(0.0, 0.0, 0.02)).collect();
        let drift: Vec<Vec3> = mesh.nodes.iter().map(|_| Vec3::new(rnd(), rnd(), rnd()) * 0.004).collect();
        // Lists kept wherever the boxes hold, and kept where measured to pay (the simulation's).
        let mut kept = BroadPhase { always_keep: true, ..Default::default() };
        let mut measured = BroadPhase::default();
        let (mut searches, mut nonempty) = (0, 0);
        for step in 0..60 {
            let x0 = mesh.positions();
            let x1: Vec<Vec3> =
                x0.iter().zip(&drift).map(|(x, d)| x + d + Vec3::new(rnd(), rnd(), rnd()) * 0.002).collect();
            let o1: Vec<Vec3> = obs.iter().map(|x| x + Vec3::new(0.001, 0.0, -0.0005)).collect();
            // The proximity search (static interval, the thickness as pad) and a collision
            // iteration's (the step's motion, a tiny pad), as a step makes them.
            for (c1, pad) in [(&x0, 0.01), (&x1, 1e-6)] {
                let iv = Interval { cloth0: &x0, cloth1: c1, obs0: &obs, obs1: &o1 };
                // A narrow phase with a result that depends on the positions.
                let narrow = |(_, c): Candidate| {
                    let p = |i: usize| if i < x0.len() { c1[i] } else { o1[i - x0.len()] };
                    let d = (p(c[0]) - p(c[1])).norm();
                    (d < 0.12).then_some(d.to_bits())
                };
                let got = kept.search(&mesh, &obs_tris, &obs_edges, &iv, pad, 0.01, true, narrow);
                let fresh = BroadPhase::default().search(&mesh, &obs_tris, &obs_edges, &iv, pad, 0.0, true, narrow);
                assert_eq!(got, fresh, "step {step}, pad {pad}");
                let by_measure = measured.search(&mesh, &obs_tris, &obs_edges, &iv, pad, 0.01, true, narrow);
                assert_eq!(by_measure, fresh, "step {step}, pad {pad}, measured");
                let all = kept.candidates(&mesh, &obs_tris, &obs_edges, &iv, pad, 0.01, true);
                assert_eq!(all, brute(&mesh, &obs_tris, &obs_edges, &iv, pad), "step {step}, pad {pad}");
                searches += 2;
                nonempty += usize::from(!got.is_empty());
            }
            for (node, x) in mesh.nodes.iter_mut().zip(&x1) {
                node.x = *x;
            }
            obs = o1;
        }
        assert!(nonempty > 100, "the narrow phase finds pairs ({nonempty} searches)");
        assert!(kept.cloth_searches > 4, "the lists are searched anew as the points leave them");
        assert!(2 * kept.cloth_searches < searches, "{} tree searches of {searches}", kept.cloth_searches);
    }

    #[test]
    fn trees_are_rebuilt_when_the_faces_are_renumbered() {
        let mut mesh = rectangle(1.0, 1.0, 6, 6).unwrap();
        let x = mesh.positions();
        let iv = Interval { cloth0: &x, cloth1: &x, obs0: &[], obs1: &[] };
        let mut broad = BroadPhase::default();
        let first = broad.candidates(&mesh, &[], &[], &iv, 0.01, 0.01, true);
        let faces = |m: &Mesh| (0..m.faces.len()).map(|f| m.face_nodes(f)).collect::<Vec<_>>();
        broad.forget_changed(&faces(&mesh), &[]);
        assert!(broad.cloth_faces.is_some(), "the same faces: the trees are kept (refitted)");
        // A remesh that keeps the count but renumbers: same candidates, trees of its own.
        mesh.faces.reverse();
        mesh.rebuild_topology().unwrap();
        broad.forget_changed(&faces(&mesh), &[]);
        assert!(broad.cloth_faces.is_none() && broad.cloth_edges.is_none() && broad.cloth_nodes.is_none());
        let again = broad.candidates(&mesh, &[], &[], &iv, 0.01, 0.01, true);
        assert_eq!(again.len(), first.len());
    }
}
