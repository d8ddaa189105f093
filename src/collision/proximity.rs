//! Repulsion contacts for the implicit solve (Harmon et al. 2008; Narain et al. 2012, ARCSim's
//! `proximity`): node–face and edge–edge pairs closer than the collision thickness get a one-sided
//! penalty on their gap.
//!
//! The weights `w` and normal `n` are frozen at the start of the step, so the gap
//! g(x) = n · Σ wᵢ xᵢ − thickness is linear in the 12 coordinates, ∂g/∂xᵢ = wᵢ n, and a penalty
//! E(g) of the depth d = max(0, −g) has the gradient E′(g) ∂g and the exact, PSD Hessian
//! E″(g) (∂g)(∂g)ᵀ. Two laws (`Law`): viewcloth's quadratic ½ k d², and ARCSim 0.2.1's cubic
//! k d³/(6 τ) with τ the thickness (`constraint.cpp`, `IneqCon::energy`), which is soft in
//! shallow contact and stiffens with depth. Obstacle nodes (infinite mass) are treated like any
//! other here; callers drop their rows when scattering.

use super::geometry::{any_perpendicular, closest_point_triangle, closest_segments};
use crate::math::{Mat12, Real, Vec12, Vec3};

/// Closest-point parameters nearer an end than this belong to the node–face test instead of
/// edge–edge (ARCSim's `in_wedge` plays the same role), so a pair is not pushed twice.
const END_TOLERANCE: Real = 1e-6;

/// How a contact's penalty grows with its depth d = max(0, −g) (scene `collision.penalty`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Law {
    /// E = ½ k d²: viewcloth's, k = stiffness × the largest cloth node area of the pair.
    #[default]
    Quadratic,
    /// E = k d³/(6 τ), τ the thickness: ARCSim 0.2.1's, k = stiffness × the smaller of the two
    /// elements' areas (`proximity.cpp`, `make_constraint`). Deeper than one thickness (cloth
    /// through the other surface, which only a start inside an obstacle brings here) the force
    /// goes on along its tangent at τ: k τ/2 + k (d − τ).
    Cubic,
}

impl Law {
    /// Energy E, normal force −E′(g) ≥ 0 and stiffness E″(g) ≥ 0 of stiffness `k`, thickness
    /// `thickness`, at gap `g`; zeros at g ≥ 0. Both laws are C¹ at g = 0.
    pub fn eval(self, k: Real, thickness: Real, g: Real) -> (Real, Real, Real) {
        let d = (-g).max(0.0);
        if d == 0.0 {
            return (0.0, 0.0, 0.0);
        }
        match self {
            Law::Quadratic => (0.5 * k * d * d, k * d, k),
            Law::Cubic if d <= thickness => {
                let s = k / thickness;
                (s * d * d * d / 6.0, 0.5 * s * d * d, s * d)
            }
            Law::Cubic => {
                // Past the thickness the cloth is through the other surface, which ARCSim's
                // collision stage never leaves at a step's start; here cloth that starts inside
                // an obstacle does. The cubic's growth would fling it (force ∝ d²); its tangent
                // at one thickness continues instead: C¹ in the force, stiffness k.
                let e = d - thickness;
                (
                    k * thickness * thickness / 6.0 + 0.5 * k * thickness * e + 0.5 * k * e * e,
                    0.5 * k * thickness + k * e,
                    k,
                )
            }
        }
    }
}

/// A frozen repulsion contact between four nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Node–face: `[p, a, b, c]`; edge–edge: `[a0, a1, b0, b1]`.
    pub nodes: [usize; 4],
    /// Node–face `[1, −b₀, −b₁, −b₂]`; edge–edge `[1 − s, s, −(1 − u), −u]`.
    pub w: [Real; 4],
    /// Unit normal from the second primitive toward the first.
    pub n: Vec3,
    pub thickness: Real,
    /// Penalty stiffness k (N/m; for the cubic law, the force at a depth of one thickness is
    /// k·thickness/2).
    pub stiffness: Real,
    pub law: Law,
}

impl Contact {
    /// `Law::eval` of this contact at gap `g`: energy, normal force and stiffness.
    pub fn penalty(&self, g: Real) -> (Real, Real, Real) {
        self.law.eval(self.stiffness, self.thickness, g)
    }

    /// g(x) = n · Σ wᵢ xᵢ − thickness; negative when closer than the thickness.
    pub fn gap(&self, x: &[Vec3; 4]) -> Real {
        let sep: Vec3 = x.iter().zip(&self.w).map(|(x, w)| x * *w).sum();
        self.n.dot(&sep) - self.thickness
    }

    /// ∂g/∂x over the 12 coordinates: block i is wᵢ n (constant, since w and n are frozen).
    pub fn gap_gradient(&self) -> Vec12 {
        Vec12::from_fn(|r, _| self.w[r / 3] * self.n[r % 3])
    }
}

/// Energy E(g), gradient E′(g) ∂g and Hessian E″(g) ∂g ∂gᵀ when g < 0; zeros otherwise. The
/// energy is C¹ at g = 0 and the Hessian is exact (not a projection) away from it.
pub fn repulsion(contact: &Contact, x: &[Vec3; 4]) -> (Real, Vec12, Mat12) {
    let g = contact.gap(x);
    if g >= 0.0 {
        return (0.0, Vec12::zeros(), Mat12::zeros());
    }
    let (e, force, k) = contact.penalty(g);
    let dg = contact.gap_gradient();
    // (∂g ∂gᵀ) k rather than (k ∂g) ∂gᵀ: bitwise symmetric.
    match contact.law {
        // k g ∂g, bit for bit as before the cubic law.
        Law::Quadratic => (e, k * g * dg, dg * dg.transpose() * k),
        Law::Cubic => (e, -force * dg, dg * dg.transpose() * k),
    }
}

/// Repulsion energy Σ E(g) of frozen `contacts`, cloth at `x` and the fixed points
/// (obstacle vertices) they index past the cloth nodes at `fixed`.
pub fn contacts_energy(contacts: &[Contact], x: &[Vec3], fixed: &[Vec3]) -> Real {
    let n = x.len();
    contacts.iter().map(|c| repulsion(c, &c.nodes.map(|i| if i < n { x[i] } else { fixed[i - n] })).0).sum()
}

/// A node–face contact when node `p` is closer than `thickness` to face `(a, b, c)` and projects
/// inside it (ARCSim's rule): the normal is the face normal on p's side and the initial gap is
/// distance − thickness. A node beside the face is left to the edge–edge and neighbouring
/// node–face tests; accepting it here would push neighbouring nodes of a flat, finely meshed
/// sheet apart in its own plane.
pub fn node_face_contact(nodes: [usize; 4], x: &[Vec3; 4], thickness: Real, stiffness: Real) -> Option<Contact> {
    let cl = closest_point_triangle(&x[0], &x[1], &x[2], &x[3]);
    if cl.dist >= thickness {
        return None;
    }
    if !cl.interior {
        return None;
    }
    let n = cl.normal;
    let w = [1.0, -cl.bary[0], -cl.bary[1], -cl.bary[2]];
    Some(Contact { nodes, w, n, thickness, stiffness, law: Law::Quadratic })
}

/// An edge–edge contact when edges `x[0]`–`x[1]` and `x[2]`–`x[3]` are closer than `thickness`
/// at points interior to both (an end-point contact is a node–face contact of an adjacent face).
/// The normal is the separation direction; for touching edges, eₐ × e_b.
pub fn edge_edge_contact(nodes: [usize; 4], x: &[Vec3; 4], thickness: Real, stiffness: Real) -> Option<Contact> {
    let sc = closest_segments(&x[0], &x[1], &x[2], &x[3]);
    let inner = |s: Real| s > END_TOLERANCE && s < 1.0 - END_TOLERANCE;
    if sc.dist >= thickness || !inner(sc.s) || !inner(sc.t) {
        return None;
    }
    let w = [1.0 - sc.s, sc.s, -(1.0 - sc.t), -sc.t];
    let sep: Vec3 = x.iter().zip(&w).map(|(x, w)| x * *w).sum();
    let (ea, eb) = (x[1] - x[0], x[3] - x[2]);
    let n = if sc.dist > 0.0 {
        sep / sc.dist
    } else {
        ea.cross(&eb).try_normalize(0.0).unwrap_or_else(|| any_perpendicular(&ea))
    };
    Some(Contact { nodes, w, n, thickness, stiffness, law: Law::Quadratic })
}

/// An obstacle vertex `x[0]` against a cloth face `x[1..4]`. The cloth belongs outside the
/// obstacle, so the normal is the face normal on the side of the obstacle's outward normal
/// `outward` at the vertex (pointing from the cloth into the obstacle), whichever side the vertex
/// is on at the end of the step: a vertex that passed through the face within the step pushes
/// the face back out, not further in. Counts within the thickness in front and within `reach`
/// (thickness plus the obstacle's travel) behind.
pub fn obstacle_vertex_contact(
    nodes: [usize; 4],
    x: &[Vec3; 4],
    thickness: Real,
    stiffness: Real,
    reach: Real,
    outward: &Vec3,
) -> Option<Contact> {
    let cl = closest_point_triangle(&x[0], &x[1], &x[2], &x[3]);
    if !cl.interior || cl.dist >= reach {
        return None;
    }
    let face = (x[2] - x[1]).cross(&(x[3] - x[1])).try_normalize(0.0)?;
    let n = if face.dot(outward) > 0.0 { -face } else { face };
    let w = [1.0, -cl.bary[0], -cl.bary[1], -cl.bary[2]];
    oriented_within(Contact { nodes, w, n, thickness, stiffness, law: Law::Quadratic }, x, reach)
}

/// A cloth edge `x[0]`–`x[1]` against an obstacle edge `x[2]`–`x[3]` whose outward normal is
/// `outward`: as `edge_edge_contact`, with the normal oriented out of the obstacle (see
/// `obstacle_vertex_contact`).
pub fn obstacle_edge_contact(
    nodes: [usize; 4],
    x: &[Vec3; 4],
    thickness: Real,
    stiffness: Real,
    reach: Real,
    outward: &Vec3,
    opposite: impl IntoIterator<Item = Vec3>,
) -> Option<Contact> {
    let sc = closest_segments(&x[0], &x[1], &x[2], &x[3]);
    let inner = |s: Real| s > END_TOLERANCE && s < 1.0 - END_TOLERANCE;
    if sc.dist >= reach || !inner(sc.s) || !inner(sc.t) {
        return None;
    }
    // Only where the cloth point lies in the obstacle edge's own Voronoi wedge, over none of its
    // adjacent triangles (ARCSim's `in_wedge`): over a triangle, that triangle's node–face
    // contact already pushes. Without this, a cloth point over a smooth obstacle's triangle is
    // also held by the edges around it, at frozen normals that differ by the facets' angles,
    // and those planes make a corner it cannot slide out of (ARCSim's sphere.json: the sheet
    // stayed on the moving sphere 6 frames longer and stretched 40%, obstacle friction off).
    let p = x[0] * (1.0 - sc.s) + x[1] * sc.s;
    let e = x[3] - x[2];
    let over_a_triangle = opposite.into_iter().any(|o| {
        let toward = e.cross(&(o - x[2])).cross(&e);
        toward.dot(&(p - x[2])) > 0.0
    });
    if over_a_triangle {
        return None;
    }
    let w = [1.0 - sc.s, sc.s, -(1.0 - sc.t), -sc.t];
    let sep: Vec3 = x.iter().zip(&w).map(|(x, w)| x * *w).sum();
    let (ea, eb) = (x[1] - x[0], x[3] - x[2]);
    let n =
        ea.cross(&eb).try_normalize(1e-12).or_else(|| sep.try_normalize(0.0)).unwrap_or_else(|| any_perpendicular(&ea));
    let n = if n.dot(outward) < 0.0 { -n } else { n };
    oriented_within(Contact { nodes, w, n, thickness, stiffness, law: Law::Quadratic }, x, reach)
}

/// `c` if its signed separation n · Σ wᵢ xᵢ lies in (−reach, thickness): closer than the
/// thickness in front, or behind by less than `reach`.
fn oriented_within(c: Contact, x: &[Vec3; 4], reach: Real) -> Option<Contact> {
    let s = c.gap(x) + c.thickness;
    (s < c.thickness && s > -reach).then_some(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: Real, y: Real, z: Real) -> Vec3 {
        Vec3::new(x, y, z)
    }

    fn perturb(x: &[Vec3; 4], i: usize, h: Real) -> [Vec3; 4] {
        let mut y = *x;
        y[i / 3][i % 3] += h;
        y
    }

    /// Central differences of the energy against the gradient and of the gradient against the
    /// Hessian at ε = 1e-3 … 1e-6 (below |g|, so no kink is crossed): the error must fall like
    /// ε², bounded by the third derivative (zero for the quadratic law, whose errors sit at
    /// round-off from the start: with frozen w, n its active energy is exactly quadratic).
    fn check_fd(c: &Contact, x: &[Vec3; 4]) {
        let (_, grad, hess) = repulsion(c, x);
        assert!(c.gap(x) < -1e-3, "the test must stay inside the active region");
        let third = match c.law {
            Law::Quadratic => 0.0,
            Law::Cubic => c.stiffness / c.thickness * c.gap_gradient().norm().powi(3),
        };
        let scale = grad.norm() + hess.norm() + third;
        for eps in [1e-3, 1e-4, 1e-5, 1e-6] {
            let mut eg: Real = 0.0;
            let mut eh: Real = 0.0;
            for i in 0..12 {
                let (ep, gp, _) = repulsion(c, &perturb(x, i, eps));
                let (em, gm, _) = repulsion(c, &perturb(x, i, -eps));
                eg = eg.max(((ep - em) / (2.0 * eps) - grad[i]).abs());
                eh = eh.max(((gp - gm) / (2.0 * eps) - hess.column(i)).norm());
            }
            let bound = scale * (eps * eps + 1e-9);
            assert!(eg <= bound && eh <= bound, "ε = {eps}: gradient error {eg}, Hessian error {eh}");
        }
    }

    #[test]
    fn node_face_gradient_hessian_fd() {
        let x = [v(0.2, 0.3, 0.004), v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        let c = node_face_contact([0, 1, 2, 3], &x, 0.01, 1e3).unwrap();
        // The step then moves the nodes: w and n stay frozen.
        let moved = [x[0] + v(0.01, -0.02, -0.001), x[1] + v(0.0, 0.01, 0.002), x[2], x[3] + v(-0.03, 0.0, 0.001)];
        check_fd(&c, &x);
        check_fd(&c, &moved);
    }

    /// ARCSim's cubic law: energy k d³/(6τ) against its gradient and Hessian by central
    /// differences, at a node–face and an edge–edge contact; the force at a depth of one
    /// thickness is k τ / 2, and the law is C¹ at the thickness (no force, no stiffness).
    #[test]
    fn cubic_law_gradient_hessian_fd() {
        let x = [v(0.2, 0.3, 0.004), v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        let c = Contact { law: Law::Cubic, ..node_face_contact([0, 1, 2, 3], &x, 0.01, 1e3).unwrap() };
        check_fd(&c, &x);
        let moved = [x[0] + v(0.01, -0.02, -0.001), x[1] + v(0.0, 0.01, 0.002), x[2], x[3] + v(-0.03, 0.0, 0.001)];
        check_fd(&c, &moved);
        let (e, _, _) = repulsion(&c, &x);
        assert!((e - 1e3 * 0.006f64.powi(3) / (6.0 * 0.01)).abs() < 1e-15, "{e}");
        let (_, force, k) = c.penalty(-0.01);
        assert!((force - 1e3 * 0.01 / 2.0).abs() < 1e-12 && (k - 1e3).abs() < 1e-9);
        assert_eq!(c.penalty(0.0), (0.0, 0.0, 0.0));
        let xe = [v(-1.0, 0.2, 0.003), v(1.0, 0.3, 0.004), v(0.1, -1.0, -0.002), v(-0.2, 1.0, 0.0)];
        let ce = Contact { law: Law::Cubic, ..edge_edge_contact([4, 5, 6, 7], &xe, 0.01, 5e2).unwrap() };
        check_fd(&ce, &xe);
        // Through the face (depth 1.5 τ): the tangent at one thickness goes on, so a node that
        // starts inside an obstacle is not flung by a force growing with d².
        let through = [v(0.2, 0.3, -0.005), x[1], x[2], x[3]];
        check_fd(&c, &through);
        let (_, force, k) = c.penalty(-0.015);
        assert!((force - 1e3 * (0.01 / 2.0 + 0.005)).abs() < 1e-12 && (k - 1e3).abs() < 1e-9, "{force} {k}");
        // Continuous across the thickness in energy, force and stiffness (2e-12 apart: within
        // what the force and the stiffness change over that span).
        let (below, above) = (c.penalty(-0.01 + 1e-12), c.penalty(-0.01 - 1e-12));
        assert!(
            (below.0 - above.0).abs() < 2e-11 && (below.1 - above.1).abs() < 2e-8 && (below.2 - above.2).abs() < 1e-6,
            "{below:?} {above:?}"
        );
    }

    #[test]
    fn edge_edge_gradient_hessian_fd() {
        let x = [v(-1.0, 0.2, 0.003), v(1.0, 0.3, 0.004), v(0.1, -1.0, -0.002), v(-0.2, 1.0, 0.0)];
        let c = edge_edge_contact([4, 5, 6, 7], &x, 0.01, 5e2).unwrap();
        check_fd(&c, &x);
    }

    #[test]
    fn hessian_is_psd_and_inactive_beyond_thickness() {
        let x = [v(0.2, 0.3, 0.004), v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        let c = node_face_contact([0, 1, 2, 3], &x, 0.01, 1e3).unwrap();
        let (e, _, hess) = repulsion(&c, &x);
        assert!((e - 0.5 * 1e3 * 0.006 * 0.006).abs() < 1e-15);
        assert!((hess - hess.transpose()).norm() == 0.0);
        let eig = hess.symmetric_eigenvalues();
        assert!(eig.iter().all(|&l| l >= -1e-9 * hess.norm()), "{eig}");
        // Pushed beyond the thickness along n: no force.
        let far = [x[0] + v(0.0, 0.0, 0.01), x[1], x[2], x[3]];
        let (e, g, h) = repulsion(&c, &far);
        assert!(e == 0.0 && g == Vec12::zeros() && h == Mat12::zeros());
    }

    #[test]
    fn node_face_geometry() {
        let (a, b, c) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        // Above the interior: the face normal, barycentric weights, gap = distance − thickness.
        let x = [v(0.2, 0.3, -0.004), a, b, c];
        let k = node_face_contact([0, 1, 2, 3], &x, 0.01, 1.0).unwrap();
        assert!((k.n - v(0.0, 0.0, -1.0)).norm() < 1e-15);
        let want = [1.0, -0.5, -0.2, -0.3];
        assert!(k.w.iter().zip(want).all(|(w, e)| (w - e).abs() < 1e-15), "{:?}", k.w);
        assert!((k.gap(&x) - (0.004 - 0.01)).abs() < 1e-15);
        // Beside an edge (projecting outside the face): no node–face contact. In a flat sheet
        // that is every node next to a face it is not on.
        assert!(node_face_contact([0, 1, 2, 3], &[v(0.5, -0.003, 0.004), a, b, c], 0.01, 1.0).is_none());
        assert!(node_face_contact(
            [0, 1, 2, 3],
            &[v(1.001, 0.5, 0.0), v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0)],
            0.01,
            1.0
        )
        .is_none());
        // Farther than the thickness: no contact.
        assert!(node_face_contact([0, 1, 2, 3], &[v(0.2, 0.3, 0.02), a, b, c], 0.01, 1.0).is_none());
    }

    #[test]
    fn edge_edge_geometry() {
        let x = [v(-1.0, 0.5, 0.004), v(1.0, 0.5, 0.004), v(0.0, -1.0, 0.0), v(0.0, 1.0, 0.0)];
        let k = edge_edge_contact([0, 1, 2, 3], &x, 0.01, 1.0).unwrap();
        let want = [0.5, 0.5, -0.25, -0.75];
        assert!(k.w.iter().zip(want).all(|(w, e)| (w - e).abs() < 1e-15), "{:?}", k.w);
        assert!((k.n - v(0.0, 0.0, 1.0)).norm() < 1e-15 && (k.gap(&x) + 0.006).abs() < 1e-15);
        // Crossing exactly: the normal is eₐ × e_b.
        let touching = [x[0] - v(0.0, 0.0, 0.004), x[1] - v(0.0, 0.0, 0.004), x[2], x[3]];
        let k = edge_edge_contact([0, 1, 2, 3], &touching, 0.01, 1.0).unwrap();
        assert!((k.n.cross(&v(0.0, 0.0, 1.0))).norm() < 1e-15);
        // Closest at an end of edge a: left to the node–face test.
        let end = [v(0.0, 0.5, 0.004), v(1.0, 0.5, 0.004), x[2], x[3]];
        assert!(edge_edge_contact([0, 1, 2, 3], &end, 0.01, 1.0).is_none());
        // Parallel and overlapping: the middle of the overlap.
        let par = [v(0.0, 0.0, 0.005), v(1.0, 0.0, 0.005), v(0.5, 0.0, 0.0), v(1.5, 0.0, 0.0)];
        let k = edge_edge_contact([0, 1, 2, 3], &par, 0.01, 1.0).unwrap();
        assert!((k.w[1] - 0.75).abs() < 1e-15 && (k.w[3] + 0.25).abs() < 1e-15);
        assert!((k.n - v(0.0, 0.0, 1.0)).norm() < 1e-15);
    }

    /// A cloth edge 3 mm above an obstacle crease, crossing it. In a valley (the two triangles
    /// rising 30° away from the crease) the cloth point is over the triangles, whose node–face
    /// contacts push, so no edge contact. Over a ridge (the triangles falling away) the point is
    /// in the edge's own wedge between their normals and gets one, pushing outward.
    #[test]
    fn obstacle_edge_contacts_only_in_the_edges_wedge() {
        let (c, d) = (v(0.0, -1.0, 0.0), v(0.0, 1.0, 0.0));
        let up = Vec3::z();
        let x = [v(-0.5, 0.0, 0.003), v(0.5, 0.0, 0.003), c, d];
        let valley = [v(-1.0, 0.0, 0.577), v(1.0, 0.0, 0.577)];
        assert!(obstacle_edge_contact([0, 1, 2, 3], &x, 0.005, 1.0, 0.005, &up, valley).is_none());
        let ridge = [v(-1.0, 0.0, -0.577), v(1.0, 0.0, -0.577)];
        let k = obstacle_edge_contact([0, 1, 2, 3], &x, 0.005, 1.0, 0.005, &up, ridge).expect("in the wedge");
        assert!(k.n.dot(&up) > 0.99, "pushes out of the obstacle: {:?}", k.n);
    }
}
