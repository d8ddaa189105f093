//! Signed distance from points to an obstacle's triangle mesh: nearest triangle through the
//! collision stages' AABB tree (`bvh::Bvh::nearest`), sign from angle-weighted pseudo-normals
//! (Bærentzen & Aanæs 2005).
//!
//! The closest point lies in a face, on an edge or at a vertex of its triangle; the sign of
//! (p − c) · n, with n that feature's pseudo-normal (face normal; sum of the two face normals for
//! an edge; Σ αᵢ nᵢ over the incident faces, αᵢ the incident angle, for a vertex), is the side of
//! p for a closed, consistently oriented mesh (BA05, Theorem 1). On an open mesh, features on its
//! boundary have no well-defined pseudo-normal: there the closest triangle's normal decides, so a
//! plane patch has "inside" below its normal side.
//!
//! Queries are independent, so `query_all` runs them with rayon and returns the same bits
//! whatever the thread count.
//!
//! Ties: when several triangles are at the same distance (a point nearest an edge or a vertex
//! is as near to every triangle sharing it), the answer is the first one met in the tree's
//! best-first order (`Bvh::nearest`: strictly smaller squared distance replaces, boxes no nearer
//! than the best are skipped); the closest points two triangles compute on their shared edge can
//! differ in the last bit, and so can the answer. That order depends on the tree's shape, which
//! the median split takes from the positions it is built on, so `update` rebuilds the tree
//! rather than refitting it, and a field answers bit for bit as one built from scratch at the
//! same positions, whenever it was first built (a resumed run answers as the uninterrupted one).
//! Refitting would not: on `skirt_mannequin` (rotating capsules), frames 0–12, with trees built
//! at t = 0 and refitted, 4111 of 57408 cloth-node queries got a closest point or normal that
//! differed in the last bits from the fresh tree's (11203 another triangle); on the translating
//! bodies of `sheet_on_sphere`, `crush`, `sphere_bullet` and ARCSim's sphere, none did. Nor
//! would a rule independent of the tree (nearest, then lowest triangle index): it differed from
//! the traversal's answer at 447 of about 4400 sampled skirt queries.
//!
//! parry3d-f64 (0.31.1) signs by the same pseudo-normals and is this module's test oracle
//! (`parry_oracle`), not its implementation. `cargo bench --bench sdf` (one thread, 40k points
//! per mesh, median of 9; 2 cores shared with other builds, ±20 % between runs), ours / parry:
//! a query near the surface 732 / 706 ns on the 1280-face sphere, 1166 / 1046 ns on the
//! 2304-face hips capsule, 3946 / 3919 ns on an 81920-face sphere; over the mesh's box
//! 2506 / 2283, 2872 / 2487, 34312 / 32313 ns; a build 0.48 / 0.73, 0.70 / 0.85, 49 / 92 ms;
//! moving the hips 0.49 (rebuild) / 0.34 ms (refit). Parry's query is 1–15 % faster, so by speed
//! it could be adopted; but its closest point differs from ours in its bits at about 70 % of the
//! points (by at most 9e-15, same side everywhere), from its own point–triangle arithmetic and
//! tree order, so adopting it would change every run's results: not adopted. (`benches/
//! collisions.rs` does not time this field: its penetration count runs outside the timed stages
//! and it does not remesh.)

use std::collections::HashMap;

use rayon::prelude::*;

use super::bvh::{Aabb, Bvh};
use super::geometry::closest_point_triangle;
use crate::math::{Real, Vec3};

/// The answer to a signed-distance query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SdfHit {
    /// Signed distance: negative inside the obstacle.
    pub distance: Real,
    /// Closest surface point.
    pub point: Vec3,
    /// Outward unit normal at `point` as seen from the query: sign · (p − point) / |p − point|,
    /// or the closest feature's pseudo-normal when p is on the surface.
    pub normal: Vec3,
    /// Triangle holding `point`, and `point`'s barycentric weights in it.
    pub triangle: usize,
    pub bary: [Real; 3],
}

/// A triangle mesh prepared for signed-distance queries. Topology is fixed at construction;
/// `update` takes new vertex positions (a moving or deforming obstacle) and refits.
#[derive(Clone, Debug)]
pub struct MeshSdf {
    triangles: Vec<[usize; 3]>,
    x: Vec<Vec3>,
    /// Edge id of edge k = (t[k], t[k+1]) of each triangle.
    tri_edges: Vec<[usize; 3]>,
    /// Edges with exactly two faces; vertices whose every edge has two faces.
    edge_manifold: Vec<bool>,
    vert_interior: Vec<bool>,
    closed: bool,
    face_normal: Vec<Vec3>,
    edge_normal: Vec<Vec3>,
    vert_normal: Vec<Vec3>,
    tree: Bvh,
}

impl MeshSdf {
    /// `triangles` index `positions` and are counter-clockwise seen from outside.
    pub fn new(triangles: &[[usize; 3]], positions: &[Vec3]) -> Self {
        let mut edge_id: HashMap<(usize, usize), usize> = HashMap::new();
        let mut edge_faces: Vec<u32> = Vec::new();
        let mut tri_edges = Vec::with_capacity(triangles.len());
        for t in triangles {
            let mut ids = [0; 3];
            for (k, id) in ids.iter_mut().enumerate() {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let next = edge_faces.len();
                *id = *edge_id.entry((a.min(b), a.max(b))).or_insert(next);
                if *id == next {
                    edge_faces.push(0);
                }
                edge_faces[*id] += 1;
            }
            tri_edges.push(ids);
        }
        let edge_manifold: Vec<bool> = edge_faces.iter().map(|&n| n == 2).collect();
        let mut vert_interior = vec![true; positions.len()];
        for (t, ids) in triangles.iter().zip(&tri_edges) {
            for k in 0..3 {
                if !edge_manifold[ids[k]] {
                    vert_interior[t[k]] = false;
                    vert_interior[t[(k + 1) % 3]] = false;
                }
            }
        }
        let mut sdf = MeshSdf {
            triangles: triangles.to_vec(),
            x: positions.to_vec(),
            closed: edge_manifold.iter().all(|&m| m),
            edge_normal: vec![Vec3::zeros(); edge_manifold.len()],
            tri_edges,
            edge_manifold,
            vert_interior,
            face_normal: Vec::new(),
            vert_normal: Vec::new(),
            tree: Bvh::default(),
        };
        sdf.compute_normals();
        sdf.tree = Bvh::build(&sdf.triangle_boxes());
        sdf
    }

    /// New vertex positions for the same triangles: the topology (edges, manifold flags) is
    /// kept, the pseudo-normals are recomputed and the tree is rebuilt, not refitted, so that every
    /// answer, ties included, is bit for bit that of `new` on these positions (module doc).
    pub fn update(&mut self, positions: &[Vec3]) {
        assert_eq!(positions.len(), self.x.len(), "MeshSdf::update: vertex count changed");
        self.x.copy_from_slice(positions);
        self.compute_normals();
        self.tree = Bvh::build(&self.triangle_boxes());
    }

    /// True when every edge has exactly two faces (the sign is then BA05's everywhere).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    pub fn positions(&self) -> &[Vec3] {
        &self.x
    }

    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// Signed distance, closest point and normal for `p`; `None` for a mesh without faces.
    pub fn query(&self, p: &Vec3) -> Option<SdfHit> {
        self.query_within(p, Real::INFINITY)
    }

    /// `query` when the surface is nearer than `range` (the same answer), else `None` (or,
    /// within a relative 1e-9 beyond the range, the hit: callers compare the distance); the
    /// search skips everything farther (`Bvh::nearest_within`).
    pub fn query_within(&self, p: &Vec3, range: Real) -> Option<SdfHit> {
        // Squared with a margin, so that rounding in d² never drops a point at d < range.
        let bound2 = range * range * (1.0 + 1e-9);
        let (tri, c) = self.tree.nearest_within(p, bound2, |f| {
            let [a, b, d] = self.triangles[f].map(|i| &self.x[i]);
            let c = closest_point_triangle(p, a, b, d);
            (c.dist, c)
        })?;
        let n = self.pseudo_normal(tri, &c.bary);
        let side = (p - c.point).dot(&n);
        let sign = if side < 0.0 { -1.0 } else { 1.0 };
        let normal =
            if c.dist > 0.0 { (p - c.point) * (sign / c.dist) } else { n.try_normalize(0.0).unwrap_or(c.normal) };
        Some(SdfHit { distance: sign * c.dist, point: c.point, normal, triangle: tri, bary: c.bary })
    }

    /// `query` for every point, in parallel; result `i` belongs to `points[i]`.
    pub fn query_all(&self, points: &[Vec3]) -> Vec<Option<SdfHit>> {
        self.query_all_within(points, Real::INFINITY)
    }

    /// `query_within` for every point, in parallel.
    pub fn query_all_within(&self, points: &[Vec3], range: Real) -> Vec<Option<SdfHit>> {
        points.par_iter().map(|p| self.query_within(p, range)).collect()
    }

    /// `query` for every point that lies inside (negative distance), in parallel; `None` for
    /// the others. On a closed mesh, points outside its bounding box are outside and skip the
    /// query.
    pub fn query_inside(&self, points: &[Vec3]) -> Vec<Option<SdfHit>> {
        let root = self.tree.root_box();
        points
            .par_iter()
            .map(|p| {
                if self.closed && root.is_some_and(|b| b.distance_squared(p) > 0.0) {
                    return None;
                }
                self.query(p).filter(|h| h.distance < 0.0)
            })
            .collect()
    }

    /// How many points lie inside deeper than `depth` (signed distance < −depth). On a closed
    /// mesh, points outside its bounding box are outside and skip the query.
    pub fn count_deeper_than(&self, points: &[Vec3], depth: Real) -> usize {
        let root = self.tree.root_box();
        points
            .par_iter()
            .filter(|p| {
                if self.closed && root.is_some_and(|b| b.distance_squared(p) > 0.0) {
                    return false;
                }
                self.query(p).is_some_and(|h| h.distance < -depth)
            })
            .count()
    }

    /// The pseudo-normal (unnormalised) of the feature holding the closest point: a vertex when
    /// two weights are zero, the edge opposite the zero weight, or the face.
    fn pseudo_normal(&self, tri: usize, bary: &[Real; 3]) -> Vec3 {
        let face = self.face_normal[tri];
        let zeros: Vec<usize> = (0..3).filter(|&k| bary[k] == 0.0).collect();
        match zeros[..] {
            [z] => {
                let e = self.tri_edges[tri][(z + 1) % 3];
                if self.edge_manifold[e] {
                    self.edge_normal[e]
                } else {
                    face
                }
            }
            [z0, z1] => {
                let v = self.triangles[tri][3 - z0 - z1];
                if self.vert_interior[v] {
                    self.vert_normal[v]
                } else {
                    face
                }
            }
            _ => face,
        }
    }

    /// Unit face normals; edge normals n₁ + n₂; vertex normals Σ αᵢ nᵢ (BA05, Eq. 3).
    fn compute_normals(&mut self) {
        let x = &self.x;
        self.face_normal = self
            .triangles
            .iter()
            .map(|t| {
                let n = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]]));
                n.try_normalize(0.0).unwrap_or_else(Vec3::zeros)
            })
            .collect();
        self.edge_normal.iter_mut().for_each(|n| *n = Vec3::zeros());
        self.vert_normal = vec![Vec3::zeros(); x.len()];
        for (f, t) in self.triangles.iter().enumerate() {
            let n = self.face_normal[f];
            for k in 0..3 {
                self.edge_normal[self.tri_edges[f][k]] += n;
                let (u, v) = (x[t[(k + 1) % 3]] - x[t[k]], x[t[(k + 2) % 3]] - x[t[k]]);
                let angle = u.cross(&v).norm().atan2(u.dot(&v));
                self.vert_normal[t[k]] += n * angle;
            }
        }
    }

    fn triangle_boxes(&self) -> Vec<Aabb> {
        self.triangles.iter().map(|t| Aabb::from_points(t.iter().map(|&i| &self.x[i]))).collect()
    }
}

#[cfg(test)]
mod parry_oracle;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::obstacle::{box_mesh, capsule_mesh, plane_mesh, sphere_mesh, CHORDAL_TOLERANCE};

    /// Deterministic points in the cube [−a, a]³ (a small LCG, no dependency).
    fn points(n: usize, a: Real) -> Vec<Vec3> {
        let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as Real / (1u64 << 53) as Real * 2.0 - 1.0) * a
        };
        (0..n).map(|_| Vec3::new(next(), next(), next())).collect()
    }

    fn box_sdf(p: &Vec3, h: &Vec3) -> Real {
        let q = p.abs() - h;
        q.sup(&Vec3::zeros()).norm() + q.max().min(0.0)
    }

    fn capsule_sdf(p: &Vec3, r: Real, half: Real) -> Real {
        (p - Vec3::new(0.0, 0.0, p.z.clamp(-half, half))).norm() - r
    }

    /// Mesh distance vs analytic distance at random points, within `tol`; the reported closest
    /// point is at the reported distance, and the normal points from it towards p (outside).
    fn check(mesh: (Vec<Vec3>, Vec<[usize; 3]>), exact: impl Fn(&Vec3) -> Real, a: Real, tol: Real) {
        let (x, tris) = mesh;
        let sdf = MeshSdf::new(&tris, &x);
        assert!(sdf.is_closed());
        let pts = points(2000, a);
        let (mut inside, mut outside) = (0, 0);
        for (p, hit) in pts.iter().zip(sdf.query_all(&pts)) {
            let hit = hit.expect("mesh has faces");
            let e = exact(p);
            assert!((hit.distance - e).abs() <= tol, "at {p}: mesh {} vs exact {e}", hit.distance);
            assert!(((p - hit.point).norm() - hit.distance.abs()).abs() < 1e-12);
            assert!((p - (hit.point + hit.normal * hit.distance)).norm() < 1e-9);
            if e < -tol {
                inside += 1;
            } else if e > tol {
                outside += 1;
            }
        }
        assert!(inside > 100 && outside > 100, "{inside} inside, {outside} outside");
    }

    #[test]
    fn sphere_distance_matches_analytic() {
        let r = 0.5;
        check(sphere_mesh(r, CHORDAL_TOLERANCE), |p| p.norm() - r, 0.8, CHORDAL_TOLERANCE * r);
    }

    #[test]
    fn box_distance_matches_analytic_exactly() {
        let size = [0.4, 1.0, 0.6];
        let h = Vec3::from(size) * 0.5;
        check(box_mesh(size), |p| box_sdf(p, &h), 0.8, 1e-12);
    }

    #[test]
    fn capsule_distance_matches_analytic() {
        let (r, l) = (0.2, 0.6);
        let mesh = capsule_mesh(r, l, CHORDAL_TOLERANCE);
        check(mesh, |p| capsule_sdf(p, r, 0.5 * l), 0.6, CHORDAL_TOLERANCE * r);
    }

    #[test]
    fn open_plane_signs_by_face_normal() {
        let (x, tris) = plane_mesh([2.0, 2.0]);
        let sdf = MeshSdf::new(&tris, &x);
        assert!(!sdf.is_closed());
        for (p, d) in [
            (Vec3::new(0.3, -0.2, 0.1), 0.1),
            (Vec3::new(0.3, -0.2, -0.1), -0.1),
            // Beyond the boundary edge the closest triangle's normal still decides.
            (Vec3::new(1.3, 0.0, -0.4), -0.5),
            (Vec3::new(0.0, 0.0, 0.0), 0.0),
        ] {
            let hit = sdf.query(&p).unwrap();
            assert!((hit.distance - d).abs() < 1e-12, "{p}: {} vs {d}", hit.distance);
        }
        assert_eq!(sdf.query(&Vec3::zeros()).unwrap().normal, Vec3::z());
    }

    #[test]
    fn update_moves_the_surface_and_counts_penetrations() {
        let (x, tris) = sphere_mesh(1.0, CHORDAL_TOLERANCE);
        let mut sdf = MeshSdf::new(&tris, &x);
        let pts = vec![Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.5), Vec3::new(5.0, 5.0, 5.0)];
        assert_eq!(sdf.count_deeper_than(&pts, 0.1), 1);
        let moved: Vec<Vec3> = x.iter().map(|p| p + Vec3::new(2.0, 0.0, 0.0)).collect();
        sdf.update(&moved);
        // At the centre: one radius deep, less the inscribed mesh's chordal error.
        let hit = sdf.query(&pts[0]).unwrap();
        assert!((hit.distance + 1.0).abs() <= CHORDAL_TOLERANCE);
        assert_eq!(sdf.count_deeper_than(&pts, 0.1), 1);
        assert_eq!(sdf.count_deeper_than(&pts, 1.5), 0);
    }

    #[test]
    fn parallel_queries_match_serial_bitwise() {
        let (x, tris) = capsule_mesh(0.3, 0.4, CHORDAL_TOLERANCE);
        let sdf = MeshSdf::new(&tris, &x);
        let pts = points(3000, 0.8);
        let serial: Vec<Option<SdfHit>> = pts.iter().map(|p| sdf.query(p)).collect();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let parallel = pool.install(|| sdf.query_all(&pts));
        for (s, q) in serial.iter().zip(&parallel) {
            let (s, q) = (s.unwrap(), q.unwrap());
            assert_eq!(s.distance.to_bits(), q.distance.to_bits());
            assert_eq!(s.triangle, q.triangle);
        }
    }

    /// A query within a range gives the unbounded query's hit, bit for bit (triangle, point,
    /// sign), wherever the surface is nearer than the range, and nothing elsewhere; on a
    /// tessellated sphere, where many triangles tie in distance for points near the axis.
    #[test]
    fn bounded_queries_match_unbounded_within_the_range() {
        let (x, tris) = sphere_mesh(0.5, CHORDAL_TOLERANCE);
        let sdf = MeshSdf::new(&tris, &x);
        let mut pts = points(3000, 1.0);
        pts.extend((0..50).map(|k| Vec3::new(0.0, 0.0, 0.3 + 0.01 * k as Real)));
        let (mut inside, mut outside) = (0, 0);
        for range in [0.02, 0.1, 0.4] {
            for p in &pts {
                let full = sdf.query(p).unwrap();
                match sdf.query_within(p, range) {
                    Some(h) => {
                        assert!(full.distance.abs() < range * (1.0 + 1e-6), "{p:?}");
                        assert_eq!(h.triangle, full.triangle);
                        assert_eq!(h.distance.to_bits(), full.distance.to_bits());
                        assert_eq!(h.point.map(Real::to_bits), full.point.map(Real::to_bits));
                        assert_eq!(h.normal.map(Real::to_bits), full.normal.map(Real::to_bits));
                        inside += 1;
                    }
                    None => {
                        assert!(full.distance.abs() >= range, "{p:?}: {} < {range}", full.distance);
                        outside += 1;
                    }
                }
            }
        }
        assert!(inside > 500 && outside > 500, "{inside} / {outside}");
    }

    #[test]
    fn tree_agrees_with_brute_force() {
        let (x, tris) = sphere_mesh(0.7, CHORDAL_TOLERANCE);
        let sdf = MeshSdf::new(&tris, &x);
        for p in points(500, 1.5) {
            let brute = tris
                .iter()
                .map(|t| closest_point_triangle(&p, &x[t[0]], &x[t[1]], &x[t[2]]).dist)
                .fold(Real::INFINITY, Real::min);
            assert_eq!(sdf.query(&p).unwrap().distance.abs(), brute);
        }
    }
}
