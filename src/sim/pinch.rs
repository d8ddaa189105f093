//! Where two obstacles pinch cloth (the separation stage's "Pinches during the run",
//! `separate.rs`): the *bands* where two present obstacles' surfaces face each other within
//! twice the thickness near the cloth, the cloth nodes within the thickness of both sides of a
//! band, and the *pinch points* where the two surfaces close on each other.
//!
//! Everything here is local geometry on the few faces of each band, taken at the step's start
//! from the positions the collision stages already hold: no signed distance field is built or
//! brought to the step for it. ARCSim's dancer is 16 rigid parts that overlap at every joint;
//! querying their fields (each rebuilt for every step the body moves) for the dress's nodes cost
//! a fifth of `dress_dance`'s frame time while finding no pinch at all.

use std::borrow::Cow;

use rayon::prelude::*;

use crate::collision::bvh::{Aabb, Bvh};
use crate::collision::geometry::closest_point_triangle;
use crate::collision::sdf::SdfHit;
use crate::collision::world::CollisionWorld;
use crate::math::{Real, Vec3};

/// Two obstacle surfaces pinch a node when it lies within the thickness of both and their
/// outward normals there are more than 120° apart (cos < −½): they face each other across it. A
/// floor meeting a wall (90°) leaves a corner the cloth can rest in; it is not a pinch.
pub const PINCH_COS: Real = -0.5;

/// A pinch point's two surfaces close on each other by at least this fraction of the thickness
/// per step (a guard against round-off between bodies that move together).
pub const CLOSING: Real = 1e-3;

/// A band keeps the faces of one obstacle near a face of the other whose normal points against
/// theirs at all (dot product below 0): looser than `PINCH_COS`, as the closest point's normal
/// may be an edge's or a vertex's. Where the parts of a body overlap at a joint their surfaces
/// cross at a shallow angle, normals alike, and no band forms there.
const BAND_FACING: Real = -0.5;

/// Barycentric weights of the samples a face gives `pinch_points`: centroid, vertices, edge
/// midpoints.
const FACE_SAMPLES: [[Real; 3]; 7] = [
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
];

/// A point where two obstacles pinch, with the velocity of the pinch there (the mean of both
/// surfaces').
pub(super) struct Pinch {
    pub x: Vec3,
    pub v: Vec3,
}

/// Some faces of one obstacle at the step's start, queried for the closest point.
struct Patch<'a> {
    body: usize,
    x: &'a [Vec3],
    tris: &'a [[usize; 3]],
    faces: Vec<usize>,
    /// Per patch face: its unit normal.
    normals: Vec<Vec3>,
    /// Over the patch faces' boxes grown by twice the thickness.
    tree: Bvh,
}

impl<'a> Patch<'a> {
    fn new(body: usize, x: &'a [Vec3], tris: &'a [[usize; 3]], faces: Vec<usize>, grow: Real) -> Self {
        let corners = |f: usize| tris[f].map(|i| x[i]);
        let normals = faces
            .iter()
            .map(|&f| {
                let [a, b, c] = corners(f);
                (b - a).cross(&(c - a)).try_normalize(0.0).unwrap_or_else(Vec3::zeros)
            })
            .collect();
        let boxes: Vec<Aabb> = faces.iter().map(|&f| Aabb::from_points(&corners(f)).inflate(grow)).collect();
        Patch { body, x, tris, normals, tree: Bvh::build(&boxes), faces }
    }

    /// The closest point to `p` on the patch's faces whose grown boxes hold `p` (ties: the first
    /// in the tree's order), signed by the face's normal where `p` lies over the face's interior.
    /// A patch is part of a surface: a point nearest an edge or a corner of it may lie outside
    /// the body across a face the patch leaves out (beside a plate standing on a floor, level
    /// with its bottom face), so there the distance counts as outside.
    fn closest(&self, p: &Vec3) -> Option<SdfHit> {
        let mut best: Option<SdfHit> = None;
        self.tree.query(&Aabb { min: *p, max: *p }, |k| {
            let f = self.faces[k];
            let [a, b, c] = self.tris[f].map(|i| &self.x[i]);
            let cp = closest_point_triangle(p, a, b, c);
            if best.as_ref().is_some_and(|h| h.distance.abs() <= cp.dist) {
                return;
            }
            let sign = if cp.interior && (p - cp.point).dot(&self.normals[k]) < 0.0 { -1.0 } else { 1.0 };
            let normal = if cp.dist > 0.0 { (p - cp.point) * (sign / cp.dist) } else { self.normals[k] };
            best = Some(SdfHit { distance: sign * cp.dist, point: cp.point, normal, triangle: f, bary: cp.bary });
        });
        best
    }
}

/// Two obstacles' faces that face each other within twice the thickness, near the cloth.
pub(super) struct Band<'a> {
    sides: [Patch<'a>; 2],
}

/// Each present obstacle's vertex positions at `t` (the collision stages' own when it takes
/// part in the current step).
pub(super) fn body_positions(world: &CollisionWorld, t: Real) -> Vec<Option<Cow<'_, [Vec3]>>> {
    (0..world.bodies.len())
        .map(|b| match world.present(b, t) {
            false => None,
            true => Some(match world.body_positions(b) {
                Some(x) => Cow::Borrowed(x),
                None => Cow::Owned(world.bodies[b].positions_at(t)),
            }),
        })
        .collect()
}

/// The faces that can form bands over one frame: for each pair of present obstacles, the faces
/// of each within twice the thickness of a face of the other that faces it (normals' dot
/// product below `FRAME_FACING`), with margins for how far both move over the frame. Found
/// once per frame (the parts of ARCSim's dancer have 25,000 faces, 16,000 of them in the boxes of
/// other parts); each step keeps those near the cloth (`bands`).
pub(super) struct BandCache {
    frame: usize,
    present: Vec<bool>,
    pairs: Vec<(usize, usize, Vec<usize>, Vec<usize>)>,
    /// The cloth nodes where the cache was built, and how far they may move from there before
    /// it must be built again: only obstacle faces that can come near the cloth are kept.
    cloth_at: Vec<Vec3>,
    cloth_margin: Real,
}

/// Face pairs that face each other at the frame's start by this much (dot product) are kept for
/// the frame: looser than `BAND_FACING`, as the parts turn during it.
const FRAME_FACING: Real = -0.3;

impl BandCache {
    /// Whether the cache was built for `frame` with these bodies present, and the cloth nodes
    /// `x` are still within its margin of where they were.
    pub(super) fn holds(&self, frame: usize, present: &[bool], x: &[Vec3]) -> bool {
        let r2 = self.cloth_margin * self.cloth_margin;
        self.frame == frame
            && self.present == present
            && x.len() == self.cloth_at.len()
            && x.iter().zip(&self.cloth_at).all(|(p, q)| (p - q).norm_squared() <= r2)
    }

    /// The cache for the frame `frame` from `t` on (its start, a resume, or a step at which the
    /// cloth left the last cache's margin), `frame_time` long: the cloth's nodes at `t` are `x`,
    /// its faces `cloth`, its fastest node moving at `speed`.
    ///
    /// A band at a later step of the frame holds only obstacle faces within three thicknesses
    /// of a cloth face then (`bands`), paired only with such faces. So only faces whose box,
    /// grown by how far their own vertices travel over the frame, comes within three
    /// thicknesses and the cloth's margin of a cloth face now are paired here, each with the
    /// faces of the other body whose grown boxes come within twice the thickness of its own;
    /// and the cache holds while no cloth node has moved farther than that margin (`holds`).
    /// The bands are those of the whole bodies' pairs (most of a dancer's joints are far from
    /// the dress, and a slow shoulder's faces need not be paired as far as its fast hand's).
    pub(super) fn new(
        world: &CollisionWorld,
        positions: &[Option<Cow<'_, [Vec3]>>],
        x: &[Vec3],
        cloth: &[([usize; 3], [Vec3; 3])],
        speed: Real,
        t: Real,
        frame_time: Real,
        frame: usize,
    ) -> Self {
        let th = world.params.thickness;
        let cloth_margin = (2.0 * speed * frame_time).max(4.0 * th);
        let cloth_tree = cloth_tree(cloth);
        let near_cloth = |bx: &Aabb| cloth_tree.any_overlap(bx);
        let present: Vec<bool> = positions.iter().map(Option::is_some).collect();
        // How far each body's vertices move over the frame (at its middle and end; ×1.25 for the
        // arcs in between), and the farthest of each body.
        let vertex_travel: Vec<Vec<Real>> = (0..world.bodies.len())
            .map(|k| {
                let (Some(x), false) = (positions[k].as_deref(), world.bodies[k].is_static()) else {
                    return Vec::new();
                };
                let (mid, end) =
                    (world.bodies[k].positions_at(t + 0.5 * frame_time), world.bodies[k].positions_at(t + frame_time));
                x.iter()
                    .zip(mid.iter().zip(&end))
                    .map(|(p, (m, e))| 1.25 * (m - p).norm().max((e - p).norm()))
                    .collect()
            })
            .collect();
        let travel: Vec<Real> = vertex_travel.iter().map(|v| v.iter().copied().fold(0.0, Real::max)).collect();
        let boxes: Vec<_> =
            (0..world.bodies.len()).map(|b| world.body_box(b, t).map(|bx| bx.inflate(th + travel[b]))).collect();
        // Pairs of present bodies whose boxes meet, then each pair's facing faces (the heavy
        // part) in parallel, kept in pair order.
        let meeting: Vec<(usize, usize, Aabb, Aabb)> = (0..boxes.len())
            .flat_map(|a| (a + 1..boxes.len()).map(move |b| (a, b)))
            .filter_map(|(a, b)| match (boxes[a], boxes[b]) {
                (Some(box_a), Some(box_b)) if box_a.overlaps(&box_b) => Some((a, b, box_a, box_b)),
                _ => None,
            })
            .collect();
        // A body's faces that `keep` accepts at `t`, their boxes grown by how far their own
        // vertices travel over the frame, kept when within three thicknesses and the cloth's
        // margin of a cloth face.
        let swept = |k: usize, x: &[Vec3], keep: &dyn Fn(&Aabb) -> bool| -> Faces {
            let (tris, tau) = (world.bodies[k].triangles(), vertex_travel[k].as_slice());
            let (faces, boxes, normals) = faces_where(tris, x, 0..tris.len(), keep);
            let mut out: Faces = (Vec::new(), Vec::new(), Vec::new());
            for ((f, bx), n) in faces.into_iter().zip(boxes).zip(normals) {
                let grow = tris[f].iter().map(|&i| tau.get(i).copied().unwrap_or(0.0)).fold(0.0, Real::max);
                let bx = bx.inflate(grow);
                if near_cloth(&bx.inflate(3.0 * th + cloth_margin)) {
                    out.0.push(f);
                    out.1.push(bx);
                    out.2.push(n);
                }
            }
            out
        };
        let pairs = meeting
            .par_iter()
            .filter_map(|&(a, b, box_a, box_b)| {
                let (xa, xb) = (positions[a].as_deref()?, positions[b].as_deref()?);
                let reach = 2.0 * th + travel[a] + travel[b];
                let (ra, rb) = (box_b.inflate(reach), box_a.inflate(reach));
                let side_a = swept(a, xa, &|bx| bx.overlaps(&ra));
                let side_b = swept(b, xb, &|bx| bx.overlaps(&rb));
                let (side_a, side_b) = facing_pairs(&side_a, &side_b, 2.0 * th, FRAME_FACING)?;
                Some((a, b, side_a, side_b))
            })
            .collect();
        BandCache { frame, present, pairs, cloth_at: x.to_vec(), cloth_margin }
    }
}

/// The bands at `t` (`Band`): of the frame's face pairs (`BandCache`), each side's faces that
/// face a face of the other within twice the thickness (`BAND_FACING`), within three
/// thicknesses of a cloth face (`cloth`: the cloth faces' nodes and corners).
pub(super) fn bands<'a>(
    world: &'a CollisionWorld,
    positions: &'a [Option<Cow<'a, [Vec3]>>],
    cache: &BandCache,
    cloth: &[([usize; 3], [Vec3; 3])],
) -> Vec<Band<'a>> {
    let th = world.params.thickness;
    let reach = 2.0 * th;
    if cache.pairs.is_empty() || cloth.is_empty() {
        return Vec::new();
    }
    let cloth_tree = cloth_tree(cloth);
    let near_cloth = |bx: &Aabb| cloth_tree.any_overlap(&bx.inflate(reach + th));
    // The box of some faces of a body at positions x.
    let faces_box = |tris: &[[usize; 3]], x: &[Vec3], faces: &[usize]| {
        Aabb::from_points(faces.iter().flat_map(|&f| tris[f].map(|i| &x[i])))
    };
    // Each pair in parallel, the bands kept in pair order.
    cache
        .pairs
        .par_iter()
        .filter_map(|(a, b, fa, fb)| {
            let (xa, xb) = (positions[*a].as_deref()?, positions[*b].as_deref()?);
            // A side none of whose faces is near the cloth makes no band: one query for the box
            // of all its faces instead of one per face (most of a dancer's part pairs are far
            // from the dress).
            let (ta, tb) = (world.bodies[*a].triangles(), world.bodies[*b].triangles());
            if !near_cloth(&faces_box(ta, xa, fa)) || !near_cloth(&faces_box(tb, xb, fb)) {
                return None;
            }
            // Each side's faces near the cloth, with boxes and normals at t.
            let side_a = faces_where(ta, xa, fa.iter().copied(), near_cloth);
            let side_b = faces_where(tb, xb, fb.iter().copied(), near_cloth);
            let (side_a, side_b) = facing_pairs(&side_a, &side_b, reach, BAND_FACING)?;
            Some(Band { sides: [Patch::new(*a, xa, ta, side_a, reach), Patch::new(*b, xb, tb, side_b, reach)] })
        })
        .collect()
}

/// A tree over the cloth faces' boxes (`cloth`: the faces' nodes and corners).
fn cloth_tree(cloth: &[([usize; 3], [Vec3; 3])]) -> Bvh {
    Bvh::build(&cloth.iter().map(|(_, c)| Aabb::from_points(c)).collect::<Vec<_>>())
}

/// Some faces of a body at positions `x`: those `keep` accepts by their box, with their boxes
/// and unit normals.
type Faces = (Vec<usize>, Vec<Aabb>, Vec<Vec3>);

fn faces_where(
    tris: &[[usize; 3]],
    x: &[Vec3],
    faces: impl Iterator<Item = usize>,
    keep: impl Fn(&Aabb) -> bool,
) -> Faces {
    let mut out = (Vec::new(), Vec::new(), Vec::new());
    for f in faces {
        let c = tris[f].map(|i| x[i]);
        let bx = Aabb::from_points(&c);
        if keep(&bx) {
            out.0.push(f);
            out.1.push(bx);
            out.2.push((c[1] - c[0]).cross(&(c[2] - c[0])).try_normalize(0.0).unwrap_or_else(Vec3::zeros));
        }
    }
    out
}

/// Of two bodies' faces, those of each within `reach` (box-wise) of a face of the other whose
/// normal faces theirs (dot product below `facing`); `None` when there are none.
fn facing_pairs(
    (fa, ba, na): &Faces,
    (fb, bb, nb): &Faces,
    reach: Real,
    facing: Real,
) -> Option<(Vec<usize>, Vec<usize>)> {
    if fa.is_empty() || fb.is_empty() {
        return None;
    }
    let tree_b = Bvh::build(bb);
    let mut partner = vec![false; fb.len()];
    let mut side_a = Vec::new();
    for k in 0..fa.len() {
        let mut found = false;
        tree_b.query(&ba[k].inflate(reach), |j| {
            if na[k].dot(&nb[j]) < facing {
                found = true;
                partner[j] = true;
            }
        });
        if found {
            side_a.push(fa[k]);
        }
    }
    let mut side_b: Vec<usize> = (0..fb.len()).filter(|&j| partner[j]).map(|j| fb[j]).collect();
    side_b.sort_unstable();
    side_b.dedup();
    (!side_a.is_empty()).then_some((side_a, side_b))
}

/// Per cloth node, (body, hit) for each side of a band it lies within the thickness of (or
/// inside of, near the surface), one per body: what the node rule of `separate.rs` judges.
pub(super) fn node_hits(bands: &[Band], x: &[Vec3], th: Real) -> Vec<Vec<(usize, SdfHit)>> {
    let mut out: Vec<Vec<(usize, SdfHit)>> = vec![Vec::new(); x.len()];
    for band in bands {
        // A node outside a side's tree box meets none of its faces (`Patch::closest` tests that
        // box first): only the nodes inside either side's are searched.
        let roots = band.sides.each_ref().map(|s| s.tree.root_box());
        let inside = |p: &Vec3| roots.iter().flatten().any(|r| r.overlaps(&Aabb { min: *p, max: *p }));
        let near: Vec<usize> = (0..x.len()).filter(|&i| inside(&x[i])).collect();
        let found: Vec<[Option<SdfHit>; 2]> = near
            .par_iter()
            .map(|&i| band.sides.each_ref().map(|s| s.closest(&x[i]).filter(|q| q.distance < th)))
            .collect();
        for (&i, pair) in near.iter().zip(found) {
            for (side, q) in band.sides.iter().zip(pair) {
                if let Some(q) = q {
                    keep_nearest(&mut out[i], side.body, q);
                }
            }
        }
    }
    out
}

/// A node's hit `q` on `body` kept when the node has none on that body yet or it is nearer than
/// the one it has.
fn keep_nearest(hits: &mut Vec<(usize, SdfHit)>, body: usize, q: SdfHit) {
    match hits.iter_mut().find(|(b, _)| *b == body) {
        Some((_, old)) if old.distance.abs() <= q.distance.abs() => {}
        Some((_, old)) => *old = q,
        None => hits.push((body, q)),
    }
}

/// The present obstacles' vertex positions at the step's end, each moving body's computed once,
/// when first asked.
pub(super) struct StepEnd {
    t1: Real,
    x: Vec<Option<Vec<Vec3>>>,
}

impl StepEnd {
    pub(super) fn new(world: &CollisionWorld, t1: Real) -> Self {
        StepEnd { t1, x: vec![None; world.bodies.len()] }
    }

    /// Body `k`'s positions at the step's end; `None` for a body that never moves.
    fn positions(&mut self, world: &CollisionWorld, k: usize) -> Option<&[Vec3]> {
        let body = &world.bodies[k];
        if body.is_static() {
            return None;
        }
        Some(self.x[k].get_or_insert_with(|| body.positions_at(self.t1)))
    }

    /// The velocity over a step of length `h` of the point of body `k`'s triangle `tri` with
    /// barycentric weights `w`, at `p` now (zero on a body that never moves).
    pub(super) fn velocity(
        &mut self,
        world: &CollisionWorld,
        k: usize,
        tri: [usize; 3],
        w: &[Real; 3],
        p: &Vec3,
        h: Real,
    ) -> Vec3 {
        match self.positions(world, k) {
            Some(x1) => ((0..3).map(|j| x1[tri[j]] * w[j]).sum::<Vec3>() - p) / h,
            None => Vec3::zeros(),
        }
    }
}

/// The points where the two sides of a band pinch (`Pinch`): samples of either side's faces
/// within twice the thickness of the other side, facing it (`PINCH_COS`) and closing on it
/// (`CLOSING`) over a step of length `h`, with their velocities.
pub(super) fn pinch_points(world: &CollisionWorld, bands: &[Band], end: &mut StepEnd, h: Real) -> Vec<Pinch> {
    let reach = 2.0 * world.params.thickness;
    let mut out = Vec::new();
    for band in bands {
        // The two sides cannot close by CLOSING·τ in the step if the fastest of their vertices
        // move less than that between them (a body paused in its pose, parts at rest).
        let mut travel = |side: &Patch| match end.positions(world, side.body) {
            None => 0.0,
            Some(x1) => {
                side.faces.iter().flat_map(|&f| side.tris[f]).map(|i| (x1[i] - side.x[i]).norm()).fold(0.0, Real::max)
            }
        };
        if travel(&band.sides[0]) + travel(&band.sides[1]) < CLOSING * world.params.thickness {
            continue;
        }
        for (from, to) in [(&band.sides[0], &band.sides[1]), (&band.sides[1], &band.sides[0])] {
            let samples: Vec<(usize, [Real; 3], Vec3, Vec3)> = from
                .faces
                .iter()
                .zip(&from.normals)
                .flat_map(|(&f, &n)| {
                    let tri = from.tris[f];
                    FACE_SAMPLES.iter().map(move |w| (f, *w, (0..3).map(|k| from.x[tri[k]] * w[k]).sum(), n))
                })
                .collect();
            let found: Vec<Option<SdfHit>> = samples
                .par_iter()
                .map(|(_, _, p, n)| to.closest(p).filter(|q| q.distance.abs() < reach && q.normal.dot(n) < PINCH_COS))
                .collect();
            if found.iter().all(Option::is_none) {
                continue;
            }
            for ((f, w, p, _), q) in samples.iter().zip(found) {
                let Some(q) = q else { continue };
                let v_a = end.velocity(world, from.body, from.tris[*f], w, p, h);
                let v_b = end.velocity(world, to.body, to.tris[q.triangle], &q.bary, &q.point, h);
                // The gap's rate of change is (v_a − v_b)·n_b: only a closing pinch squeezes.
                if (v_a - v_b).dot(&q.normal) * h < -CLOSING * world.params.thickness {
                    out.push(Pinch { x: *p, v: 0.5 * (v_a + v_b) });
                }
            }
        }
    }
    out
}

/// The nodes of every cloth face (`cloth`: the faces' nodes and corners) within `th` of a pinch
/// point, each with that pinch's velocity (the first pinch, in `pinches`' order, found for it).
/// The pinch points are searched in a tree over them: a moving dancer's joints give hundreds.
pub(super) fn faces_at_pinches(pinches: &[Pinch], cloth: &[([usize; 3], [Vec3; 3])], th: Real) -> Vec<(usize, Vec3)> {
    if pinches.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = pinches.iter().map(|p| Aabb { min: p.x, max: p.x }).collect();
    let tree = Bvh::build(&boxes);
    let first: Vec<Option<usize>> = cloth
        .par_iter()
        .map(|(_, [a, b, c])| {
            // A point lies in the grown box exactly when its own (degenerate) box overlaps it.
            let bx = Aabb::from_points([a, b, c]).inflate(th);
            let mut first: Option<usize> = None;
            tree.query(&bx, |k| {
                if first.is_none_or(|f| k < f) && closest_point_triangle(&pinches[k].x, a, b, c).dist < th {
                    first = Some(k);
                }
            });
            first
        })
        .collect();
    let mut out = Vec::new();
    for ((nodes, _), k) in cloth.iter().zip(first) {
        if let Some(k) = k {
            out.extend(nodes.map(|i| (i, pinches[k].v)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::test_rng::Rng;

    /// The first pinch in order within `th` of each face, by scanning them all.
    fn brute(pinches: &[Pinch], cloth: &[([usize; 3], [Vec3; 3])], th: Real) -> Vec<(usize, Vec3)> {
        let mut out = Vec::new();
        for (nodes, [a, b, c]) in cloth {
            let bx = Aabb::from_points([a, b, c]).inflate(th);
            let hit = pinches
                .iter()
                .find(|p| bx.distance_squared(&p.x) == 0.0 && closest_point_triangle(&p.x, a, b, c).dist < th);
            if let Some(p) = hit {
                out.extend(nodes.map(|i| (i, p.v)));
            }
        }
        out
    }

    #[test]
    fn faces_at_pinches_finds_the_first_pinch_of_each_face() {
        let mut rng = Rng(7);
        let mut point = |s: Real| Vec3::new(rng.uniform() * s, rng.uniform() * s, rng.uniform() * 0.02);
        let cloth: Vec<([usize; 3], [Vec3; 3])> = (0..400)
            .map(|f| {
                let o = point(1.0);
                ([3 * f, 3 * f + 1, 3 * f + 2], [o, o + Vec3::new(0.03, 0.0, 0.0), o + Vec3::new(0.0, 0.03, 0.0)])
            })
            .collect();
        // Several pinches near one another, so that a face is near more than one.
        let pinches: Vec<Pinch> =
            (0..300).map(|k| Pinch { x: point(1.0), v: Vec3::new(k as Real, 0.0, 0.0) }).collect();
        let th = 0.01;
        let want = brute(&pinches, &cloth, th);
        assert!(want.len() > 30, "{} nodes held", want.len());
        assert_eq!(faces_at_pinches(&pinches, &cloth, th), want);
        assert!(faces_at_pinches(&[], &cloth, th).is_empty());
    }

    /// Random 5 cm triangles in a 40 cm cube, as faces of a body: their nodes and positions.
    fn random_faces(rng: &mut Rng, count: usize) -> (Vec<[usize; 3]>, Vec<Vec3>) {
        let mut x = Vec::new();
        let tris = (0..count)
            .map(|f| {
                let o = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 0.4;
                let mut corner = || o + Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 0.05;
                x.extend([corner(), corner(), corner()]);
                [3 * f, 3 * f + 1, 3 * f + 2]
            })
            .collect();
        (tris, x)
    }

    /// Each side's faces with a facing partner on the other within reach, by testing every pair
    /// with the same box test and normals.
    #[test]
    fn facing_pairs_are_the_faces_with_a_partner() {
        let mut rng = Rng(11);
        let (ta, xa) = random_faces(&mut rng, 300);
        let (tb, xb) = random_faces(&mut rng, 250);
        let (fa, fb) = (faces_where(&ta, &xa, 0..ta.len(), |_| true), faces_where(&tb, &xb, 0..tb.len(), |_| true));
        for (reach, facing) in [(0.01, -0.5), (0.03, 0.0), (0.0, -0.2)] {
            let pairs =
                |k: usize, j: usize| fb.1[j].overlaps(&fa.1[k].inflate(reach)) && fa.2[k].dot(&fb.2[j]) < facing;
            let side_a: Vec<usize> = (0..fa.0.len()).filter(|&k| (0..fb.0.len()).any(|j| pairs(k, j))).collect();
            let side_b: Vec<usize> = (0..fb.0.len()).filter(|&j| (0..fa.0.len()).any(|k| pairs(k, j))).collect();
            let want = (!side_a.is_empty()).then_some((side_a, side_b));
            if let Some((a, b)) = &want {
                assert!(
                    a.len() > 10 && a.len() < fa.0.len() && b.len() > 10,
                    "reach {reach}: {} / {}",
                    a.len(),
                    b.len()
                );
            }
            assert_eq!(facing_pairs(&fa, &fb, reach, facing), want, "reach {reach}, facing {facing}");
        }
        let none = (Vec::new(), Vec::new(), Vec::new());
        assert_eq!(facing_pairs(&none, &fb, 0.01, 0.0), None);
    }

    /// The nodes' hits when every node is searched in every band, as `Patch::closest` gives them.
    #[test]
    fn node_hits_are_every_nodes_nearest_faces() {
        let mut rng = Rng(5);
        let (ta, xa) = random_faces(&mut rng, 200);
        let (tb, xb) = random_faces(&mut rng, 200);
        let th = 0.02;
        // Sixty faces of a body from `from` on.
        fn patch<'a>(body: usize, x: &'a [Vec3], tris: &'a [[usize; 3]], from: usize, grow: Real) -> Patch<'a> {
            Patch::new(body, x, tris, (from..from + 60).collect(), grow)
        }
        let bands = vec![
            Band { sides: [patch(0, &xa, &ta, 0, 2.0 * th), patch(1, &xb, &tb, 0, 2.0 * th)] },
            Band { sides: [patch(0, &xa, &ta, 100, 2.0 * th), patch(2, &xb, &tb, 120, 2.0 * th)] },
        ];
        let nodes: Vec<Vec3> =
            (0..3000).map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 0.45).collect();
        let mut want: Vec<Vec<(usize, SdfHit)>> = vec![Vec::new(); nodes.len()];
        for band in &bands {
            for (i, p) in nodes.iter().enumerate() {
                for side in &band.sides {
                    if let Some(q) = side.closest(p).filter(|q| q.distance < th) {
                        keep_nearest(&mut want[i], side.body, q);
                    }
                }
            }
        }
        let hit = want.iter().filter(|h| !h.is_empty()).count();
        assert!(hit > 20 && hit < nodes.len() / 2, "{hit} nodes hit");
        assert_eq!(node_hits(&bands, &nodes, th), want);
    }
}
