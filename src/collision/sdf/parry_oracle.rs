//! parry3d-f64 as the oracle of the signed distance and of the point–triangle query. parry's
//! `TriMesh` with `ORIENTED` signs a projection by the same angle-weighted pseudo-normals
//! (Bærentzen & Aanæs 2005: face normal, sum of the two face normals at an edge, Σ αᵢ nᵢ at a
//! vertex), from its own tree and its own point–triangle code: the two must agree on the side
//! exactly and on the distance and closest point to rounding, on points spread around closed
//! meshes and on points just off their edges and vertices, where a face normal alone gives the
//! wrong side.

use parry3d_f64::math::Vector;
use parry3d_f64::query::{PointQuery, PointQueryWithLocation};
use parry3d_f64::shape::{TriMesh, TriMeshFlags, Triangle};

use super::MeshSdf;
use crate::collision::geometry::closest_point_triangle;
use crate::collision::obstacle::{box_mesh, capsule_mesh, sphere_mesh, CHORDAL_TOLERANCE};
use crate::math::test_rng::Rng;
use crate::math::{Real, Vec3};

/// Agreement required of distances and closest points, relative to the mesh's size (≈ 1 here).
const TOL: Real = 1e-12;

fn to_parry(v: &Vec3) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

fn from_parry(v: Vector) -> Vec3 {
    Vec3::new(v.x, v.y, v.z)
}

fn unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = rng.vec();
        if let Some(u) = v.try_normalize(0.1) {
            return u;
        }
    }
}

/// A closed, outward, non-convex mesh: a coarse icosphere with every vertex moved radially by
/// up to ±35 % (each face keeps its orientation about the centre, so the surface stays
/// embedded), giving sharp and concave edges and saddle vertices.
fn blob(rng: &mut Rng) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let (x, tris) = sphere_mesh(0.5, 0.03);
    (x.iter().map(|p| p * (1.0 + 0.35 * (2.0 * rng.uniform() - 1.0))).collect(), tris)
}

/// Query points for a mesh: spread over its box grown by half, and just off its vertices and
/// edges (offsets from 10⁻² to 10⁻⁵ of the mesh size in random directions).
fn query_points(x: &[Vec3], tris: &[[usize; 3]], rng: &mut Rng) -> Vec<Vec3> {
    let (lo, hi) = x
        .iter()
        .fold((Vec3::repeat(Real::INFINITY), Vec3::repeat(Real::NEG_INFINITY)), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    let (centre, half) = (0.5 * (lo + hi), 0.75 * (hi - lo));
    let mut pts: Vec<Vec3> = (0..3000).map(|_| centre + rng.vec().component_mul(&half)).collect();
    let offset = |rng: &mut Rng| 10.0_f64.powf(-2.0 - 3.0 * rng.uniform()) * unit(rng);
    for _ in 0..1500 {
        let v = x[(rng.uniform() * x.len() as Real) as usize];
        pts.push(v + offset(rng));
        let t = tris[(rng.uniform() * tris.len() as Real) as usize];
        let k = (rng.uniform() * 3.0) as usize;
        let s = rng.uniform();
        pts.push(x[t[k]] * (1.0 - s) + x[t[(k + 1) % 3]] * s + offset(rng));
    }
    pts
}

/// Our signed distance against parry's projection on one closed mesh. Returns how many points
/// the closest triangle's face normal alone would have put on the wrong side.
fn compare_with_parry(name: &str, (x, tris): (Vec<Vec3>, Vec<[usize; 3]>), rng: &mut Rng) -> usize {
    let sdf = MeshSdf::new(&tris, &x);
    assert!(sdf.is_closed(), "{name}: not closed");
    let indices = tris.iter().map(|t| t.map(|i| i as u32)).collect();
    let mesh = TriMesh::with_flags(x.iter().map(to_parry).collect(), indices, TriMeshFlags::ORIENTED)
        .unwrap_or_else(|e| panic!("{name}: parry rejects the mesh: {e:?}"));
    let (mut naive_wrong, mut inside) = (0, 0);
    for p in query_points(&x, &tris, rng) {
        let ours = sdf.query(&p).expect("mesh has faces");
        let (proj, _) = mesh.project_local_point_and_get_location(to_parry(&p), false);
        let theirs = from_parry(proj.point);
        let d = (p - theirs).norm();
        assert!(
            (ours.distance.abs() - d).abs() <= TOL,
            "{name} at {p:?}: distance {} vs parry {d}",
            ours.distance.abs()
        );
        assert!((ours.point - theirs).norm() <= TOL, "{name} at {p:?}: closest {:?} vs parry {theirs:?}", ours.point);
        // On the surface (within rounding) either side is right; parry counts it inside.
        if d > TOL {
            assert_eq!(ours.distance < 0.0, proj.is_inside, "{name} at {p:?}: sign (distance {})", ours.distance);
            inside += usize::from(proj.is_inside);
            let t = tris[ours.triangle];
            let face = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]]));
            naive_wrong += usize::from(((p - ours.point).dot(&face) < 0.0) != proj.is_inside);
        }
    }
    assert!(inside > 500, "{name}: only {inside} points inside");
    naive_wrong
}

#[test]
fn signed_distance_matches_parry_on_closed_meshes() {
    let mut rng = Rng(0x5d_f0_0d);
    compare_with_parry("sphere", sphere_mesh(0.5, CHORDAL_TOLERANCE), &mut rng);
    compare_with_parry("box", box_mesh([0.4, 1.0, 0.6]), &mut rng);
    compare_with_parry("capsule", capsule_mesh(0.2, 0.6, CHORDAL_TOLERANCE), &mut rng);
    let mesh = blob(&mut rng);
    // The points just off edges and vertices do exercise the pseudo-normals: there the
    // closest face's own normal gives the wrong side, and ours (and parry's) the right one.
    let naive_wrong = compare_with_parry("blob", mesh, &mut rng);
    assert!(naive_wrong > 20, "blob: the face normal alone was wrong at only {naive_wrong} points");
}

#[test]
fn point_triangle_matches_parry() {
    let mut rng = Rng(0x7e_a1);
    for _ in 0..20_000 {
        let [a, b, c] = [rng.vec(), rng.vec(), rng.vec()];
        // Points around the triangle, and a few far away (every Voronoi region is reached).
        let p = if rng.uniform() < 0.9 { rng.vec() * 1.5 } else { rng.vec() * 20.0 };
        let ours = closest_point_triangle(&p, &a, &b, &c);
        let tri = Triangle::new(to_parry(&a), to_parry(&b), to_parry(&c));
        let theirs = from_parry(tri.project_local_point(to_parry(&p), false).point);
        let scale = p.norm().max(1.0);
        assert!(
            (ours.point - theirs).norm() <= TOL * scale,
            "triangle {a:?} {b:?} {c:?}, point {p:?}: {:?} vs parry {theirs:?}",
            ours.point
        );
        assert!((ours.dist - (p - theirs).norm()).abs() <= TOL * scale);
    }
}
