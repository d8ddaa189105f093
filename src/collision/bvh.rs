//! The one bounding volume hierarchy of the collision stages: axis-aligned boxes, refit when the
//! primitives move and rebuilt when their count changes. The broad phase queries it for
//! overlapping boxes (one box, tree against tree, a tree against itself); the signed distance
//! (`sdf`) for the primitive nearest a point. Queries return results in a deterministic order.

use crate::math::{Real, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub fn empty() -> Self {
        Aabb { min: Vec3::repeat(Real::INFINITY), max: Vec3::repeat(Real::NEG_INFINITY) }
    }

    pub fn from_points<'a>(pts: impl IntoIterator<Item = &'a Vec3>) -> Self {
        let mut b = Aabb::empty();
        for p in pts {
            b.add_point(p);
        }
        b
    }

    pub fn add_point(&mut self, p: &Vec3) {
        self.min = self.min.inf(p);
        self.max = self.max.sup(p);
    }

    pub fn merge(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.inf(&o.min), max: self.max.sup(&o.max) }
    }

    pub fn inflate(&self, r: Real) -> Aabb {
        Aabb { min: self.min.add_scalar(-r), max: self.max.add_scalar(r) }
    }

    #[inline]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.x <= o.max.x
            && o.min.x <= self.max.x
            && self.min.y <= o.max.y
            && o.min.y <= self.max.y
            && self.min.z <= o.max.z
            && o.min.z <= self.max.z
    }

    /// Squared distance from `p` to the box (0 inside).
    pub fn distance_squared(&self, p: &Vec3) -> Real {
        (0..3).map(|k| (self.min[k] - p[k]).max(p[k] - self.max[k]).max(0.0).powi(2)).sum()
    }

    fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
}

const LEAF_SIZE: usize = 4;

#[derive(Clone, Debug)]
struct Node {
    aabb: Aabb,
    /// Leaf (count > 0): primitives `order[start..start + count]`; inner: children `left`, `right`.
    start: u32,
    count: u32,
    left: u32,
    right: u32,
}

/// A BVH over primitives given by their boxes. Nodes are stored parents before children, so a
/// reverse sweep refits bottom-up.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    /// The primitives' boxes in `order`'s sequence: a leaf's boxes side by side in memory (the
    /// tree–tree descent tests them without reaching into the caller's arrays).
    leaf_boxes: Vec<Aabb>,
}

impl Bvh {
    /// Builds by median split along the longest axis of the primitive centres.
    pub fn build(boxes: &[Aabb]) -> Self {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * boxes.len() / LEAF_SIZE + 1),
            order: (0..boxes.len() as u32).collect(),
            leaf_boxes: Vec::new(),
        };
        if !boxes.is_empty() {
            bvh.build_node(boxes, 0, boxes.len());
        }
        bvh.leaf_boxes = bvh.order.iter().map(|&p| boxes[p as usize]).collect();
        bvh
    }

    fn build_node(&mut self, boxes: &[Aabb], start: usize, end: usize) -> u32 {
        let id = self.nodes.len() as u32;
        let aabb = self.order[start..end].iter().fold(Aabb::empty(), |a, &i| a.merge(&boxes[i as usize]));
        self.nodes.push(Node { aabb, start: start as u32, count: (end - start) as u32, left: 0, right: 0 });
        if end - start <= LEAF_SIZE {
            return id;
        }
        let centers = self.order[start..end].iter().fold(Aabb::empty(), |mut a, &i| {
            a.add_point(&boxes[i as usize].center());
            a
        });
        let ext = centers.max - centers.min;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = (start + end) / 2;
        self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            let (ca, cb) = (boxes[a as usize].center()[axis], boxes[b as usize].center()[axis]);
            ca.total_cmp(&cb).then(a.cmp(&b))
        });
        let left = self.build_node(boxes, start, mid);
        let right = self.build_node(boxes, mid, end);
        let n = &mut self.nodes[id as usize];
        (n.count, n.left, n.right) = (0, left, right);
        id
    }

    pub fn len(&self) -> usize {
        self.order.len()
    }

    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// The box of every primitive (`None` for an empty tree).
    pub fn root_box(&self) -> Option<Aabb> {
        self.nodes.first().map(|n| n.aabb)
    }

    /// Refits the boxes for new primitive boxes (same primitives, same tree), primitive p's box
    /// `boxed(p)`, computed straight into the leaves (in parallel for a large tree).
    pub fn refit_by(&mut self, boxed: impl Fn(usize) -> Aabb + Sync) {
        use rayon::prelude::*;
        self.leaf_boxes
            .par_iter_mut()
            .with_min_len(crate::math::PAR_GRAIN)
            .zip(&self.order)
            .for_each(|(slot, &p)| *slot = boxed(p as usize));
        for i in (0..self.nodes.len()).rev() {
            let n = &self.nodes[i];
            let aabb = if n.count > 0 {
                let (s, c) = (n.start as usize, n.count as usize);
                self.leaf_boxes[s..s + c].iter().fold(Aabb::empty(), |a, b| a.merge(b))
            } else {
                self.nodes[n.left as usize].aabb.merge(&self.nodes[n.right as usize].aabb)
            };
            self.nodes[i].aabb = aabb;
        }
    }

    /// Calls `f(primitive)` for every primitive whose box (as last built or refitted) overlaps
    /// `q`.
    pub fn query(&self, q: &Aabb, mut f: impl FnMut(usize)) {
        self.visit(q, |p| {
            f(p);
            false
        });
    }

    /// Whether any primitive's box (as last built or refitted) overlaps `q`: `query` that stops
    /// at the first one.
    pub fn any_overlap(&self, q: &Aabb) -> bool {
        self.visit(q, |_| true)
    }

    /// `query`'s descent, stopped (and true returned) as soon as `f` returns true.
    fn visit(&self, q: &Aabb, mut f: impl FnMut(usize) -> bool) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i as usize];
            if !n.aabb.overlaps(q) {
                continue;
            }
            if n.count > 0 {
                let range = n.start as usize..(n.start + n.count) as usize;
                for (&p, b) in self.order[range.clone()].iter().zip(&self.leaf_boxes[range]) {
                    if b.overlaps(q) && f(p as usize) {
                        return true;
                    }
                }
            } else {
                stack.push(n.right);
                stack.push(n.left);
            }
        }
        false
    }

    /// The primitive nearest to `p`, where `closest(i)` is primitive i's distance to `p` and what
    /// the caller keeps of it: a best-first descent (nearer child box first, the left one when
    /// both are as near), skipping every box no nearer than the best so far.
    ///
    /// Ties: a primitive replaces the best only when its squared distance is strictly smaller,
    /// so among primitives at the same squared distance the first one visited in that order is
    /// returned (and one whose box is no nearer than the best is never visited). The order is a
    /// function of this tree's shape and boxes and of `p`: deterministic, independent of threads.
    pub fn nearest<T>(&self, p: &Vec3, closest: impl Fn(usize) -> (Real, T)) -> Option<(usize, T)> {
        self.nearest_within(p, Real::INFINITY, closest)
    }

    /// `nearest` among the primitives whose squared distance is below `bound2`: boxes no
    /// nearer than `bound2` are skipped from the start. When the nearest primitive lies within
    /// the bound the answer is `nearest`'s, ties included: the boxes visited keep their order,
    /// and every box skipped here holds only primitives farther than the one returned.
    pub fn nearest_within<T>(
        &self,
        p: &Vec3,
        bound2: Real,
        closest: impl Fn(usize) -> (Real, T),
    ) -> Option<(usize, T)> {
        let mut best: Option<(usize, T)> = None;
        let mut best_d2 = bound2;
        let mut stack: Vec<(u32, Real)> = Vec::with_capacity(64);
        if let Some(root) = self.nodes.first() {
            stack.push((0, root.aabb.distance_squared(p)));
        }
        while let Some((i, d2)) = stack.pop() {
            if d2 >= best_d2 {
                continue;
            }
            let n = &self.nodes[i as usize];
            if n.count > 0 {
                for &t in &self.order[n.start as usize..(n.start + n.count) as usize] {
                    let (d, c) = closest(t as usize);
                    if d * d < best_d2 {
                        best_d2 = d * d;
                        best = Some((t as usize, c));
                    }
                }
                continue;
            }
            let (l, r) = (n.left, n.right);
            let (dl, dr) =
                (self.nodes[l as usize].aabb.distance_squared(p), self.nodes[r as usize].aabb.distance_squared(p));
            // The farther child is pushed first, so the nearer is popped next.
            if dl <= dr {
                stack.extend([(r, dr), (l, dl)]);
            } else {
                stack.extend([(l, dl), (r, dr)]);
            }
        }
        best
    }

    /// Every pair (a, b), a from `self`, b from `other`, whose boxes (as last built or
    /// refitted) overlap, sorted.
    pub fn pairs(&self, other: &Bvh) -> Vec<(usize, usize)> {
        let mut out = self.overlapping(
            other,
            false,
            |a, b| a.overlaps(b),
            |(p, pb), (q, qb), out: &mut Vec<(usize, usize)>| {
                if pb.overlaps(qb) {
                    out.push((p, q));
                }
            },
        );
        out.sort_unstable();
        out
    }

    /// Every unordered pair (a < b) of this tree's primitives whose boxes (as last built or
    /// refitted) overlap, sorted.
    pub fn self_pairs(&self) -> Vec<(usize, usize)> {
        let mut out = self.overlapping(
            self,
            true,
            |a, b| a.overlaps(b),
            |(p, pb), (q, qb), out: &mut Vec<(usize, usize)>| {
                if pb.overlaps(qb) {
                    out.push((p.min(q), p.max(q)));
                }
            },
        );
        out.sort_unstable();
        out
    }

    /// Simultaneous descent of two trees (one query for all primitives instead of one per
    /// primitive): calls `leaf((a, box of a), (b, box of b), out)` for every primitive a of
    /// `self` and b of `other` whose nodes pass `near` at every level, and a's own box against
    /// b's leaf. `near(box in self, box in other)` must hold whenever `leaf` could report a pair
    /// of primitives within those boxes (boxes only grow up the tree, and a primitive's box lies
    /// in its leaf's). With `same` (`other` is `self`), each unordered pair of distinct
    /// primitives is visited once, in either order, and `near` must then be symmetric in that
    /// sense. The boxes passed are the ones the tree was last built or refitted with.
    ///
    /// The work is split into a fixed list of subtree pairs, run in parallel and concatenated
    /// in list order: the output does not depend on the thread count.
    pub fn overlapping<T: Send>(
        &self,
        other: &Bvh,
        same: bool,
        near: impl Fn(&Aabb, &Aabb) -> bool + Sync,
        leaf: impl Fn((usize, &Aabb), (usize, &Aabb), &mut Vec<T>) + Sync,
    ) -> Vec<T> {
        use rayon::prelude::*;
        if self.nodes.is_empty() || other.nodes.is_empty() {
            return Vec::new();
        }
        let mut tasks = vec![if same { Visit::Within(0) } else { Visit::Across(0, 0) }];
        while tasks.len() < PARALLEL_TASKS {
            let mut next = Vec::with_capacity(4 * tasks.len());
            let mut split = false;
            for t in tasks {
                if self.expand(other, t, &near, &mut next) {
                    split = true;
                } else {
                    next.push(t);
                }
            }
            tasks = next;
            if !split {
                break;
            }
        }
        let descend = |t: Visit| {
            let (mut out, mut stack) = (Vec::new(), vec![t]);
            while let Some(t) = stack.pop() {
                if !self.expand(other, t, &near, &mut stack) {
                    self.leaf_pairs(other, t, &near, &leaf, &mut out);
                }
            }
            out
        };
        // Small trees on the calling thread (`PAR_GRAIN`); the same list, so the same output.
        match self.order.len() + other.order.len() < 2 * crate::math::PAR_GRAIN {
            true => tasks.into_iter().flat_map(descend).collect(),
            false => tasks.into_par_iter().flat_map_iter(descend).collect(),
        }
    }

    /// Pushes the children of visit `t` (none if its nodes are not near); false when `t` is a
    /// pair of leaves (or one leaf with itself), to be tested primitive by primitive.
    fn expand(&self, other: &Bvh, t: Visit, near: &impl Fn(&Aabb, &Aabb) -> bool, out: &mut Vec<Visit>) -> bool {
        match t {
            Visit::Within(i) => {
                let a = &self.nodes[i as usize];
                if a.count > 0 {
                    return false;
                }
                out.extend([Visit::Across(a.left, a.right), Visit::Within(a.right), Visit::Within(a.left)]);
            }
            Visit::Across(i, j) => {
                let (a, b) = (&self.nodes[i as usize], &other.nodes[j as usize]);
                if !near(&a.aabb, &b.aabb) {
                    return true;
                }
                match (a.count > 0, b.count > 0) {
                    (true, true) => return false,
                    (false, true) => out.extend([Visit::Across(a.right, j), Visit::Across(a.left, j)]),
                    (true, false) => out.extend([Visit::Across(i, b.right), Visit::Across(i, b.left)]),
                    (false, false) => out.extend([
                        Visit::Across(a.right, b.right),
                        Visit::Across(a.right, b.left),
                        Visit::Across(a.left, b.right),
                        Visit::Across(a.left, b.left),
                    ]),
                }
            }
        }
        true
    }

    /// The primitive pairs of a pair of leaves (or of one leaf with itself) for `leaf`; across
    /// two leaves, a primitive whose box is not `near` the other leaf's box meets none of its
    /// primitives.
    fn leaf_pairs<T>(
        &self,
        other: &Bvh,
        t: Visit,
        near: &impl Fn(&Aabb, &Aabb) -> bool,
        leaf: &impl Fn((usize, &Aabb), (usize, &Aabb), &mut Vec<T>),
        out: &mut Vec<T>,
    ) {
        fn prims(tree: &Bvh, i: u32) -> (&[u32], &[Aabb]) {
            let n = &tree.nodes[i as usize];
            let range = n.start as usize..(n.start + n.count) as usize;
            (&tree.order[range.clone()], &tree.leaf_boxes[range])
        }
        match t {
            Visit::Within(i) => {
                let (p, pb) = prims(self, i);
                for k in 0..p.len() {
                    for m in k + 1..p.len() {
                        leaf((p[k] as usize, &pb[k]), (p[m] as usize, &pb[m]), out);
                    }
                }
            }
            Visit::Across(i, j) => {
                let ((p, pb), (q, qb)) = (prims(self, i), prims(other, j));
                let other_box = &other.nodes[j as usize].aabb;
                for (&a, ab) in p.iter().zip(pb) {
                    if !near(ab, other_box) {
                        continue;
                    }
                    for (&b, bb) in q.iter().zip(qb) {
                        leaf((a as usize, ab), (b as usize, bb), out);
                    }
                }
            }
        }
    }
}

/// Subtree pairs a tree–tree query is split into for the thread pool.
const PARALLEL_TASKS: usize = 64;

/// A step of a tree–tree descent: two nodes (one from each tree), or one node against itself.
#[derive(Clone, Copy, Debug)]
enum Visit {
    Across(u32, u32),
    Within(u32),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes(n: usize, seed: u64) -> Vec<Aabb> {
        let mut s = seed;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let c = Vec3::new(rnd(), rnd(), rnd());
                Aabb { min: c, max: c + Vec3::repeat(0.05 * rnd()) }
            })
            .collect()
    }

    fn brute(a: &[Aabb], b: &[Aabb]) -> Vec<(usize, usize)> {
        let mut v = Vec::new();
        for (i, x) in a.iter().enumerate() {
            for (j, y) in b.iter().enumerate() {
                if x.overlaps(y) {
                    v.push((i, j));
                }
            }
        }
        v
    }

    #[test]
    fn pairs_match_brute_force_after_refit() {
        let a = boxes(300, 1);
        let b = boxes(200, 2);
        let (mut ta, tb) = (Bvh::build(&a), Bvh::build(&b));
        assert_eq!(ta.pairs(&tb), brute(&a, &b));
        let moved: Vec<Aabb> = a.iter().map(|x| Aabb { min: x.min * 0.7, max: x.max * 0.7 }).collect();
        ta.refit_by(|p| moved[p]);
        assert_eq!(ta.pairs(&tb), brute(&moved, &b));
        let selfp = ta.self_pairs();
        let want: Vec<_> = brute(&moved, &moved).into_iter().filter(|(i, j)| i < j).collect();
        assert_eq!(selfp, want);
        let mut hits = Vec::new();
        ta.query(&b[0], |p| hits.push(p));
        hits.sort_unstable();
        let want: Vec<_> = (0..moved.len()).filter(|&i| moved[i].overlaps(&b[0])).collect();
        assert_eq!(hits, want);
    }

    #[test]
    fn any_overlap_is_whether_a_query_finds_anything() {
        let a = boxes(300, 3);
        let tree = Bvh::build(&a);
        let queries = boxes(400, 4);
        let mut hits = 0;
        for q in &queries {
            let mut found = false;
            tree.query(q, |_| found = true);
            assert_eq!(tree.any_overlap(q), found);
            hits += usize::from(found);
        }
        // Both answers occur among the queries.
        assert!(hits > 0 && hits < queries.len(), "{hits} of {}", queries.len());
        assert!(!Bvh::build(&[]).any_overlap(&queries[0]));
    }
}
