//! The exact intersection check of a frame: triangle pairs that truly cross, cloth against cloth
//! (one cloth with itself and cloths with each other) and cloth against obstacles. Pairs sharing
//! a node are skipped (adjacent triangles always touch). It is a measurement, not a response:
//! run after a frame is written (`crossings_self`, `crossings_obstacle` in stats.json) and by
//! `viewcloth crossings` on the written files.
//!
//! **What counts.** Two triangles cross when their open interiors share a point and their planes
//! differ: one passes through the other. In general position that is "an edge of one passes
//! through the interior of the other". Touching is not crossing: a vertex or an edge lying on
//! the other triangle, two edges meeting, and coplanar triangles (touching or overlapping inside
//! one plane: neither passes from one side of the other to the other side) are not counted. A
//! degenerate triangle (collinear corners) has no interior and crosses nothing.
//!
//! **Exactness.** Every decision is the sign of an orientation determinant computed exactly
//! (Shewchuk's adaptive predicates, the `robust` crate), so a vertex exactly on a plane and an
//! edge exactly through another are decided as what they are, not by rounding. The test is
//! Guigue & Devillers' (2003, "Fast and robust triangle-triangle overlap test using orientation
//! predicates"), with strict inequalities for the open interiors.
//!
//! Broad phase: the collision stages' BVH (`bvh::Bvh`) over the triangles' boxes; its tree-tree
//! descent is parallel with an output order independent of the thread count, and the result here
//! is a sorted list of pairs: the same for any number of threads.

use rayon::prelude::*;

use super::bvh::{Aabb, Bvh};
use crate::math::Vec3;

/// Positions and triangles (indices into the positions).
#[derive(Clone, Copy, Debug)]
pub struct Soup<'a> {
    pub x: &'a [Vec3],
    pub tris: &'a [[usize; 3]],
}

impl Soup<'_> {
    fn corners(&self, t: usize) -> [Vec3; 3] {
        self.tris[t].map(|i| self.x[i])
    }

    fn boxes(&self) -> Vec<Aabb> {
        self.tris.iter().map(|t| Aabb::from_points(t.iter().map(|&i| &self.x[i]))).collect()
    }
}

/// The crossing pairs of one frame.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Crossings {
    /// Cloth triangle pairs (a < b) that cross.
    pub cloth: Vec<(usize, usize)>,
    /// (cloth triangle, obstacle triangle) pairs that cross.
    pub obstacle: Vec<(usize, usize)>,
}

/// Every crossing pair of `cloth` with itself and with `obstacles` (obstacles against each
/// other are not looked at), each list sorted.
pub fn find_crossings(cloth: Soup, obstacles: Soup) -> Crossings {
    let tree = Bvh::build(&cloth.boxes());
    Crossings { cloth: self_crossings(cloth, &tree), obstacle: crossings_with(cloth, &tree, obstacles) }
}

/// Every crossing pair of `cloth` with itself (a < b), sorted: `find_crossings`' cloth list alone.
pub fn find_self_crossings(cloth: Soup) -> Vec<(usize, usize)> {
    let tree = Bvh::build(&cloth.boxes());
    self_crossings(cloth, &tree)
}

/// Pairs of `soup`'s triangles, sharing no node, that cross; sorted.
fn self_crossings(soup: Soup, tree: &Bvh) -> Vec<(usize, usize)> {
    let mut out = tree.overlapping(tree, true, open_overlap, |(p, pb), (q, qb), out: &mut Vec<(usize, usize)>| {
        let (tp, tq) = (&soup.tris[p], &soup.tris[q]);
        if open_overlap(pb, qb)
            && !tp.iter().any(|i| tq.contains(i))
            && triangles_cross(&soup.corners(p), &soup.corners(q))
        {
            out.push((p.min(q), p.max(q)));
        }
    });
    out.sort_unstable();
    out
}

/// Pairs (triangle of `soup`, triangle of `other`) that cross; sorted. Only `other`'s triangles
/// whose boxes meet a box of `soup`'s (`tree`) are put in a tree: a crowd's bodies have far
/// more triangles than lie near their garments.
fn crossings_with(soup: Soup, tree: &Bvh, other: Soup) -> Vec<(usize, usize)> {
    let (near, boxes): (Vec<usize>, Vec<Aabb>) =
        other.boxes().into_par_iter().enumerate().filter(|(_, b)| tree.any_overlap(b)).unzip();
    let other_tree = Bvh::build(&boxes);
    let mut out =
        tree.overlapping(&other_tree, false, open_overlap, |(p, pb), (k, qb), out: &mut Vec<(usize, usize)>| {
            let q = near[k];
            if open_overlap(pb, qb) && triangles_cross(&soup.corners(p), &other.corners(q)) {
                out.push((p, q));
            }
        });
    out.sort_unstable();
    out
}

/// Whether the boxes overlap in an open set (positive volume). Triangles whose boxes only touch
/// never cross: a point of both open interiors on the shared face of the boxes would be an
/// extreme point of a linear function (that coordinate) over each triangle, so the coordinate
/// would be constant on both, and the triangles coplanar. This keeps flat rest states (sheets
/// in an axis plane, neighbours' boxes touching) from reaching the exact predicates, where exact
/// zeros are the slow case; the test also holds for a tree's inner boxes, which contain their
/// leaves'.
fn open_overlap(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|k| a.min[k] < b.max[k] && b.min[k] < a.max[k])
}

/// Whether triangles `a` and `b` cross: their open interiors share a point and their planes
/// differ (module doc). Exact.
pub fn triangles_cross(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    // Each triangle must have vertices strictly on both sides of the other's plane: otherwise
    // its interior lies on one side (touching at most) or both lie in one plane.
    let sa = a.map(|p| orient(&b[0], &b[1], &b[2], &p));
    let Some(ia) = lone(&sa) else { return false };
    let sb = b.map(|q| orient(&a[0], &a[1], &a[2], &q));
    let Some(ib) = lone(&sb) else { return false };
    // Rotate each triangle so that its lone vertex comes first (orientation kept), then swap the
    // other two of the *other* triangle to put that vertex on the positive side of its plane.
    let mut p = [a[ia], a[(ia + 1) % 3], a[(ia + 2) % 3]];
    let mut q = [b[ib], b[(ib + 1) % 3], b[(ib + 2) % 3]];
    if sa[ia] < 0 {
        q.swap(1, 2);
    }
    if sb[ib] < 0 {
        p.swap(1, 2);
    }
    // Each triangle meets the planes' common line in a segment, [i, j] for p (i on p0p1, j on
    // p0p2) and [k, l] for q (k on q0q1, l on q0q2). The open segments (the interiors' part of
    // the line) overlap iff k is before i and l after j along the line, each the sign of one
    // orientation (Guigue & Devillers 2003, Sec. 3.1; zero: the two ends coincide, a touch).
    orient(&p[0], &p[1], &q[0], &q[1]) < 0 && orient(&p[0], &p[2], &q[2], &q[0]) < 0
}

/// The index of the vertex alone on its side of a plane, from the vertices' sides (+1, −1, 0),
/// when there are vertices strictly on both sides (else None). With signs (+, −, 0) either
/// strict one is alone; the positive one is taken.
fn lone(s: &[i8; 3]) -> Option<usize> {
    let pos = s.iter().filter(|&&v| v > 0).count();
    let neg = s.iter().filter(|&&v| v < 0).count();
    if pos == 0 || neg == 0 {
        return None;
    }
    let side = if pos == 1 { 1 } else { -1 };
    s.iter().position(|&v| v == side)
}

/// The exact sign of (b − a) × (c − a) · (d − a): +1 when `d` is on the side of plane abc its
/// normal (b − a) × (c − a) points to, −1 on the other, 0 on the plane.
pub fn orient(a: &Vec3, b: &Vec3, c: &Vec3, d: &Vec3) -> i8 {
    let coord = |p: &Vec3| robust::Coord3D { x: p.x, y: p.y, z: p.z };
    // robust's orient3d is positive when d lies *below* the plane: the opposite convention.
    let r = robust::orient3d(coord(a), coord(b), coord(c), coord(d));
    if r < 0.0 {
        1
    } else if r > 0.0 {
        -1
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::test_rng::Rng;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// The unit right triangle in the plane z = 0.
    fn floor() -> [Vec3; 3] {
        [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]
    }

    /// Whether the open segment pq passes through the open triangle x, from strict signs only:
    /// the "edge through the other triangle" of the definition, for inputs in general position.
    fn edge_through(p: &Vec3, q: &Vec3, x: &[Vec3; 3]) -> bool {
        let (sp, sq) = (orient(&x[0], &x[1], &x[2], p), orient(&x[0], &x[1], &x[2], q));
        let s = [0, 1, 2].map(|k| orient(p, q, &x[k], &x[(k + 1) % 3]));
        sp * sq < 0 && (s.iter().all(|&v| v > 0) || s.iter().all(|&v| v < 0))
    }

    fn any_edge_through(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
        (0..3).any(|k| edge_through(&a[k], &a[(k + 1) % 3], b))
            || (0..3).any(|k| edge_through(&b[k], &b[(k + 1) % 3], a))
    }

    /// Every vertex order of both triangles, and the two triangles swapped.
    fn all_orders(a: &[Vec3; 3], b: &[Vec3; 3]) -> Vec<([Vec3; 3], [Vec3; 3])> {
        let perms = [[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]];
        let mut out = Vec::new();
        for pa in perms {
            for pb in perms {
                let (x, y) = (pa.map(|i| a[i]), pb.map(|i| b[i]));
                out.push((x, y));
                out.push((y, x));
            }
        }
        out
    }

    fn crosses_in_every_order(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
        let all: Vec<bool> = all_orders(a, b).iter().map(|(x, y)| triangles_cross(x, y)).collect();
        assert!(all.iter().all(|&c| c == all[0]), "order-dependent answer for {a:?} {b:?}");
        all[0]
    }

    #[test]
    fn orient_is_positive_on_the_normal_side() {
        let [a, b, c] = floor();
        assert_eq!(orient(&a, &b, &c, &v(0.2, 0.2, 1.0)), 1);
        assert_eq!(orient(&a, &b, &c, &v(0.2, 0.2, -1e-300)), -1);
        assert_eq!(orient(&a, &b, &c, &v(5.0, -3.0, 0.0)), 0);
    }

    #[test]
    fn a_triangle_pierced_by_an_edge_counts() {
        // A vertical triangle whose bottom edge passes through the floor triangle's interior.
        let pierce = [v(0.2, 0.2, -0.5), v(0.3, 0.25, 0.5), v(2.0, 2.0, 3.0)];
        assert!(crosses_in_every_order(&floor(), &pierce));
        assert!(any_edge_through(&floor(), &pierce));
        // The same across one of the floor triangle's edges: the floor's edge passes through it.
        let across = [v(0.5, -1.0, -0.5), v(0.5, -1.0, 0.5), v(0.5, 1.0, 0.0)];
        assert!(crosses_in_every_order(&floor(), &across));
    }

    #[test]
    fn touching_and_near_pairs_do_not_count() {
        let f = floor();
        let cases = [
            // A vertex exactly on the interior, the triangle above.
            [v(0.2, 0.2, 0.0), v(0.5, 0.2, 1.0), v(0.2, 0.5, 1.0)],
            // An edge lying in the floor's interior, the triangle above.
            [v(0.1, 0.1, 0.0), v(0.3, 0.2, 0.0), v(0.2, 0.2, 1.0)],
            // An edge exactly through one of the floor's edges, reaching below: the triangle
            // stands on the floor's boundary line (x + y = 1 side), its interior outside.
            [v(0.5, 0.5, -1.0), v(0.5, 0.5, 1.0), v(2.0, 2.0, 0.0)],
            // A vertex exactly on the floor's vertex.
            [v(1.0, 0.0, 0.0), v(2.0, 0.0, 1.0), v(2.0, 1.0, -1.0)],
            // Near: one nanometre above.
            [v(0.2, 0.2, 1e-9), v(0.5, 0.2, 1.0), v(0.2, 0.5, 1.0)],
            // Coplanar and overlapping (not a crossing: neither passes through the other).
            [v(0.1, 0.1, 0.0), v(0.9, 0.05, 0.0), v(0.1, 0.8, 0.0)],
            // Coplanar and touching at a vertex.
            [v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(2.0, 1.0, 0.0)],
            // Parallel planes.
            [v(0.0, 0.0, 1e-12), v(1.0, 0.0, 1e-12), v(0.0, 1.0, 1e-12)],
        ];
        for (k, t) in cases.iter().enumerate() {
            assert!(!crosses_in_every_order(&f, t), "case {k}");
        }
    }

    #[test]
    fn tips_through_each_other_count_though_no_edge_passes_through() {
        // A stands in y = 0 with its tip exactly on B's interior; B lies in z = 0 with its tip
        // exactly on A's interior. The interiors share the segment 0 < x < 0.5 of the x axis,
        // but every edge either touches the other's plane at its end or misses the other.
        let a = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 1.0), v(1.0, 0.0, -1.0)];
        let b = [v(0.5, 0.0, 0.0), v(-1.0, 1.0, 0.0), v(-1.0, -1.0, 0.0)];
        assert!(!any_edge_through(&a, &b));
        assert!(crosses_in_every_order(&a, &b));
        // Tips that only meet (B's tip moved to A's tip): a touch.
        let b = [v(0.0, 0.0, 0.0), v(-1.0, 1.0, 0.0), v(-1.0, -1.0, 0.0)];
        assert!(!crosses_in_every_order(&a, &b));
    }

    #[test]
    fn agrees_with_edge_through_triangle_in_general_position() {
        let mut rng = Rng(0x5eed);
        let (mut crossing, mut n) = (0, 20000);
        while n > 0 {
            let a = [rng.vec(), rng.vec(), rng.vec()];
            let b = [rng.vec(), rng.vec(), rng.vec()].map(|x| x * 0.7 + v(0.1, 0.0, 0.0));
            let want = any_edge_through(&a, &b);
            assert_eq!(triangles_cross(&a, &b), want, "{a:?} {b:?}");
            assert_eq!(triangles_cross(&b, &a), want);
            crossing += want as usize;
            n -= 1;
        }
        assert!(crossing > 2000, "too few crossing cases drawn ({crossing})");
    }

    /// A flat grid of `n`×`n` squares in the plane at height `z`, two triangles each.
    fn grid(n: usize, z: f64) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        crate::metrics::test_grid(n, n, |i, j| v(i, j, z))
    }

    #[test]
    fn triangles_sharing_a_node_cross_only_beyond_it() {
        // The remesher's guard tests such pairs with the same predicate (`remesh::guard`).
        let o = v(0.0, 0.0, 0.0);
        let floor = [o, v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        // Through the floor's interior along the diagonal from the shared node.
        assert!(triangles_cross(&floor, &[o, v(1.0, 1.0, 1.0), v(1.0, 1.0, -1.0)]));
        // The same wall turned away: it meets the floor at the shared node only.
        assert!(!triangles_cross(&floor, &[o, v(-1.0, -1.0, 1.0), v(-1.0, -1.0, -1.0)]));
        // Standing on the floor's edge from the node (a fold): touching, not crossing.
        assert!(!triangles_cross(&floor, &[o, v(1.0, 0.0, 0.0), v(0.5, 0.0, 1.0)]));
        assert!(!triangles_cross(&floor, &[o, v(2.0, 0.0, 0.0), v(0.5, 0.0, 1.0)]));
    }

    #[test]
    fn shared_node_pairs_are_skipped_and_a_fold_through_is_found() {
        let (mut x, tris) = grid(6, 0.0);
        let none = Soup { x: &[], tris: &[] };
        // Flat: every pair touches or is apart.
        assert_eq!(find_crossings(Soup { x: &x, tris: &tris }, none), Crossings::default());
        // One node pushed far down: its six triangles cross no neighbour (they share it) but
        // pass through nothing else either, so still none.
        let centre = 3 * 7 + 3;
        x[centre].z = -0.5;
        assert!(find_crossings(Soup { x: &x, tris: &tris }, none).cloth.is_empty());
        // A second sheet's triangle pushed through the first: exactly the pairs found by brute force.
        let (y, t2) = grid(2, 0.05);
        let mut all_x = x.clone();
        all_x.extend(y.iter().map(|p| p + v(0.2, 0.2, 0.0)));
        let base = x.len();
        let mut all_t = tris.clone();
        all_t.extend(t2.iter().map(|t| t.map(|i| i + base)));
        all_x[base + 4].z = -0.3; // the centre of the small sheet, through the big one
        let soup = Soup { x: &all_x, tris: &all_t };
        let found = find_crossings(soup, none).cloth;
        let mut brute = Vec::new();
        for a in 0..all_t.len() {
            for b in a + 1..all_t.len() {
                if !all_t[a].iter().any(|i| all_t[b].contains(i)) && triangles_cross(&soup.corners(a), &soup.corners(b))
                {
                    brute.push((a, b));
                }
            }
        }
        assert!(!found.is_empty());
        assert_eq!(found, brute);
    }

    #[test]
    fn obstacle_pairs_match_brute_force_and_any_thread_count() {
        let (x, tris) = grid(8, 0.0);
        let mut rng = Rng(7);
        // Every third triangle far from the cloth: the search keeps the others' own numbers.
        let obs_x: Vec<Vec3> = (0..90)
            .map(|i| {
                rng.vec() * 0.5 + v(0.5, 0.5, 0.0) + if (i / 3) % 3 == 1 { v(5.0, 0.0, 0.0) } else { v(0.0, 0.0, 0.0) }
            })
            .collect();
        let obs_t: Vec<[usize; 3]> = (0..30).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let (cloth, obs) = (Soup { x: &x, tris: &tris }, Soup { x: &obs_x, tris: &obs_t });
        let mut brute = Vec::new();
        for a in 0..tris.len() {
            for b in 0..obs_t.len() {
                if triangles_cross(&cloth.corners(a), &obs.corners(b)) {
                    brute.push((a, b));
                }
            }
        }
        let found = find_crossings(cloth, obs);
        assert!(!brute.is_empty() && brute.iter().any(|&(_, b)| b > 1));
        assert_eq!(found.obstacle, brute);
        assert!(found.cloth.is_empty());
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            assert_eq!(pool.install(|| find_crossings(cloth, obs)), found, "{threads} threads");
        }
    }
}
