//! The rest shape through a remesh (issue 16, item 3). Rest dihedral angles live on edges, which
//! a remesh creates and destroys; the rest *shape* is carried instead as a per-face material-space
//! shape operator (Grinspun et al. 2003's discrete shape operator, the one the curvature sizing
//! uses, Narain 2012 §3):
//!
//!   S_f = −(1/A_f) Σₑ ½ θₑ |eₑ| t̂ₑ t̂ₑᵀ,   t̂ₑ the unit material-space normal of edge e,
//!
//! which every remesh operation hands on to the faces it adds (a split's halves inherit it, a
//! flip's pair takes the pair's area-weighted mean, a collapse's faces that of the face each
//! replaces). Afterwards each face's three edge angles are solved back from its S_f (the map
//! above is 3 × 3 and invertible for a non-degenerate triangle) and an interior edge takes the
//! mean of its two faces' values. This is ARCSim's choice when it carries a rest shape through
//! remeshing (plasticity.cpp: `edges_to_face`, `face_to_edges`, `recompute_edge_plasticity`):
//! a curved rest mesh stays curved at any resolution, where carrying angles by node pair left
//! new edges flat and the rest shape a mix. An unchanged neighbourhood gets its angles back
//! exactly (to rounding); a flat rest shape stays exactly flat.
//!
//! An input that labels creases (a folded model) carries its rest shape as a rest embedding
//! instead (`Scene::rest_embedded`, `SimState::rest_x`, ARCSim's plastic-space positions), and
//! the new mesh's rest angles are the embedding's dihedral angles (`sim::adapt`): exact, where
//! solving from the faces' operators spreads a sharp fold over the faces beside it (a face with
//! one folded edge has an operator whose solution on its split halves bends their other edges
//! too). For a smooth curved input that spreading is what is wanted, where an embedding with
//! linear midpoints would kink it along its input edges. With an embedding the operators carry
//! only the plastic residuals.
//!
//! Under plasticity (`forces::plasticity`, issue 16 item 9) S_f is the plastic shape itself, the
//! state, not derived from the angles, and each face's damage rides along the same way (a flip
//! takes the pair's area-weighted mean). ARCSim resamples both by overlap area against the old
//! mesh (`restore_residuals`); handing them on with each operation keeps ∫S_f dA over a split or
//! flip exactly.

use nalgebra::{Matrix3, Vector3};

use crate::math::{Mat2, Real, Vec2};
use crate::mesh::Mesh;

/// The terms −½|e| t̂t̂ᵀ of face `f`'s edges (edge k opposite corner k) as columns of
/// (xx, yy, xy) components: S_f·A_f = columns · θ.
fn edge_terms(mesh: &Mesh, f: usize) -> Matrix3<Real> {
    let u = mesh.face_uv(f);
    let mut a = Matrix3::zeros();
    for k in 0..3 {
        let e: Vec2 = u[(k + 2) % 3] - u[(k + 1) % 3];
        let len = e.norm();
        if len == 0.0 {
            continue;
        }
        let t = Vec2::new(e.y, -e.x) / len;
        a.set_column(k, &(-0.5 * len * Vector3::new(t.x * t.x, t.y * t.y, t.x * t.y)));
    }
    a
}

/// The shape operator of face `f` from the angles of its edges (zero for a degenerate face).
pub fn face_shape(mesh: &Mesh, f: usize, angles: &[Real]) -> Mat2 {
    let area = mesh.material_area(f);
    if area <= 0.0 {
        return Mat2::zeros();
    }
    let theta = Vector3::from(mesh.face_edges[f].map(|e| angles[e.idx()]));
    let s = edge_terms(mesh, f) * theta / area;
    Mat2::new(s[0], s[2], s[2], s[1])
}

/// The rest shape operator of every face from the rest angles of its edges (zero for a
/// degenerate face).
pub fn face_shapes(mesh: &Mesh, rest_angles: &[Real]) -> Vec<Mat2> {
    (0..mesh.faces.len()).map(|f| face_shape(mesh, f, rest_angles)).collect()
}

/// The angles of face `f`'s edges (edge k opposite corner k) whose shape operator is `s`; `None`
/// for a face that cannot be solved (degenerate).
fn solve_face(mesh: &Mesh, f: usize, s: &Mat2) -> Option<Vector3<Real>> {
    let area = mesh.material_area(f);
    let inv = edge_terms(mesh, f).try_inverse().filter(|_| area > 0.0)?;
    Some(inv * (area * Vector3::new(s[(0, 0)], s[(1, 1)], 0.5 * (s[(0, 1)] + s[(1, 0)]))))
}

/// Rest angle of every edge from the faces' rest shape operators: each face's edge angles solved
/// from its S_f, averaged over an interior edge's two faces; zero on boundary edges (which do not
/// bend) and where no adjacent face can be solved.
pub fn edge_angles_from_shapes(mesh: &Mesh, shapes: &[Mat2]) -> Vec<Real> {
    let mut angles = vec![0.0; mesh.edges.len()];
    solve_edges(mesh, shapes, &vec![true; mesh.edges.len()], &mut angles);
    angles
}

/// `edge_angles_from_shapes` for the edges of the faces flagged in `changed` only: the other
/// rest angles are left exactly as they are.
pub fn refresh_edge_angles(mesh: &Mesh, shapes: &[Mat2], changed: &[bool], angles: &mut [Real]) {
    let mut stale = vec![false; mesh.edges.len()];
    for f in (0..mesh.faces.len()).filter(|&f| changed[f]) {
        mesh.face_edges[f].iter().for_each(|e| stale[e.idx()] = true);
    }
    solve_edges(mesh, shapes, &stale, angles);
}

/// Sets `angles[e]` of every edge flagged in `stale` from the shapes of its faces.
fn solve_edges(mesh: &Mesh, shapes: &[Mat2], stale: &[bool], angles: &mut [Real]) {
    let mut sum = vec![0.0; mesh.edges.len()];
    let mut count = vec![0u8; mesh.edges.len()];
    for (f, s) in shapes.iter().enumerate() {
        let edges = mesh.face_edges[f];
        if !edges.iter().any(|e| stale[e.idx()]) {
            continue;
        }
        let Some(theta) = solve_face(mesh, f, s) else { continue };
        for (k, e) in edges.iter().enumerate() {
            sum[e.idx()] += theta[k];
            count[e.idx()] += 1;
        }
    }
    for e in (0..mesh.edges.len()).filter(|&e| stale[e]) {
        angles[e] = match mesh.hinge_nodes(e).is_some() && count[e] > 0 {
            true => sum[e] / Real::from(count[e]),
            false => 0.0,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::edge_angles;
    use crate::math::Vec3;
    use crate::mesh::rectangle;

    /// A 1 × 0.5 sheet rolled about the y axis into a half-cylinder (radius 1/π).
    fn half_cylinder(nx: usize, ny: usize) -> Mesh {
        let mut m = rectangle(1.0, 0.5, nx, ny).unwrap();
        let r = 1.0 / std::f64::consts::PI;
        for v in 0..m.verts.len() {
            let u = m.verts[v].u;
            let a = u.x / r;
            m.nodes[m.verts[v].node.idx()].x = Vec3::new(r * a.sin(), u.y, r * (1.0 - a.cos()));
        }
        m
    }

    #[test]
    fn angles_survive_the_round_trip_through_face_shapes() {
        let m = half_cylinder(7, 3);
        let theta = edge_angles(&m);
        let back = edge_angles_from_shapes(&m, &face_shapes(&m, &theta));
        for (e, (a, b)) in theta.iter().zip(&back).enumerate() {
            assert!((a - b).abs() < 1e-12, "edge {e}: {a} vs {b}");
        }
    }

    #[test]
    fn face_shape_of_a_cylinder_is_its_curvature() {
        // Away from the boundary the discrete operator of a cylinder of radius r is ≈ diag(1/r, 0)
        // up to sign: the x–x entry holds the curvature, the others vanish.
        let m = half_cylinder(24, 8);
        let shapes = face_shapes(&m, &edge_angles(&m));
        let k = std::f64::consts::PI;
        for f in 0..m.faces.len() {
            let c = m.face_uv(f).iter().fold(Vec2::zeros(), |a, u| a + u) / 3.0;
            if c.x < 0.1 || c.x > 0.9 || c.y < 0.1 || c.y > 0.4 {
                continue;
            }
            let s = shapes[f];
            assert!((s[(0, 0)].abs() - k).abs() < 0.15 * k, "face {f}: {s}");
            assert!(s[(1, 1)].abs() < 0.15 * k && s[(0, 1)].abs() < 0.15 * k, "face {f}: {s}");
        }
    }
}
