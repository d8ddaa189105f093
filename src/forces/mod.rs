//! Element force kernels: pure functions from element state to (energy, gradient, Hessian).
//! Scattering into the global system happens in `solver::assembly`. A fabric
//! (`material::Material`) picks the membrane and bending kernels of its faces and hinges.

pub mod bending;
pub mod buckling;
pub mod data_driven;
pub mod handle;
pub mod material;
pub mod membrane;
pub mod plasticity;
pub mod wind;

/// Which Hessian a kernel returns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// The exact second derivative (may be indefinite); used by tests.
    Exact,
    /// A positive semidefinite form, used to assemble the implicit system.
    Psd,
    /// The energy and its gradient, bit-identical to `Psd`'s (Hessian returned as zeros): the
    /// pop filter's Newton steps after its first reuse the first step's factor and need only
    /// the right-hand side.
    Gradient,
}

use crate::math::Real;
use crate::math::PAR_GRAIN;
use crate::mesh::Mesh;
use bending::{dihedral_angle, BendingRest};
use material::Material;
use membrane::MembraneRest;

/// A bending hinge: nodes `[x0, x1, x2, x3]` (edge x0–x1), its edge, material and rest data.
#[derive(Clone, Copy, Debug)]
pub struct Hinge {
    pub nodes: [usize; 4],
    pub edge: usize,
    pub material: usize,
    pub rest: BendingRest,
    /// Edge direction and curvature scale, for measured (direction-dependent) bending.
    pub measured: data_driven::HingeRest,
    /// Stiffness factor 1/(1 + w·d) of plastic damage (`plasticity`); 1 when undamaged.
    pub weakened: Real,
}

/// Rest-state data of every element, rebuilt whenever the topology changes.
#[derive(Clone, Debug, Default)]
pub struct RestState {
    pub membrane: Vec<MembraneRest>,
    pub hinges: Vec<Hinge>,
}

impl RestState {
    /// Rest data from material coordinates; rest dihedral angles from `rest_angle(edge)`.
    /// Fails (with the face index) on a degenerate material-space face.
    pub fn new(mesh: &Mesh, rest_angle: impl Fn(usize) -> Real) -> Result<Self, usize> {
        let membrane = (0..mesh.faces.len())
            .map(|f| MembraneRest::new(mesh.face_uv(f)).ok_or(f))
            .collect::<Result<Vec<_>, _>>()?;
        let mut hinges = Vec::new();
        for e in 0..mesh.edges.len() {
            let Some(nodes) = mesh.hinge_nodes(e) else {
                continue;
            };
            let edge = &mesh.edges[e];
            let (Some((f0, k0)), Some((f1, k1))) = (edge.adj.0[0], edge.adj.0[1]) else {
                continue;
            };
            // Material-space edge length, from the first face's verts.
            let uv = mesh.face_uv(f0.idx());
            let k = k0 as usize;
            let du0 = uv[(k + 2) % 3] - uv[(k + 1) % 3];
            let len2 = du0.norm_squared();
            let area = membrane[f0.idx()].area + membrane[f1.idx()].area;
            // The same edge in the second face's material coordinates (they differ across a seam).
            let uv1 = mesh.face_uv(f1.idx());
            let k1 = k1 as usize;
            let du1 = uv1[(k1 + 2) % 3] - uv1[(k1 + 1) % 3];
            hinges.push(Hinge {
                nodes,
                edge: e,
                material: mesh.faces[f0.idx()].material as usize,
                rest: BendingRest { shape: 3.0 * len2 / area, theta0: rest_angle(e) },
                measured: data_driven::HingeRest::new([du0, du1], len2.sqrt(), area),
                weakened: 1.0,
            });
        }
        Ok(RestState { membrane, hinges })
    }

    /// Takes new rest angles (each hinge's θ̄ from `rest_angles`, indexed by edge) after a
    /// plastic update.
    pub fn set_rest_angles(&mut self, rest_angles: &[Real]) {
        for h in &mut self.hinges {
            h.rest.theta0 = rest_angles[h.edge];
        }
    }

    /// The rest shapes' slack of buckling compensation (`buckling`) from the current positions:
    /// face f keeps `kappa[f]` of its compressive stress (1: no slack). `kappa` empty: none.
    pub fn set_slack(&mut self, mesh: &Mesh, kappa: &[Real], materials: &[Material]) {
        use rayon::prelude::*;
        if kappa.len() != self.membrane.len() {
            self.membrane.iter_mut().for_each(|m| m.slack = crate::math::Mat2::identity());
            return;
        }
        self.membrane.par_iter_mut().enumerate().with_min_len(PAR_GRAIN).for_each(|(f, m)| {
            m.slack = crate::math::Mat2::identity();
            if kappa[f] < 1.0 {
                let x = mesh.face_nodes(f).map(|n| mesh.nodes[n].x);
                let mat = &materials[mesh.faces[f].material as usize];
                m.slack = buckling::slack(m, kappa[f], |r| mat.stretch(&x, r, Projection::Exact).0);
            }
        });
    }

    /// The stiffness factors of plastic damage (`plasticity`): a face's from its own damage
    /// `damage[f]` and its material's weakening, a hinge's from the mean of its two faces'
    /// damage and the larger of their materials' weakening (ARCSim's `recompute_edge_plasticity`
    /// and `bending_energy`). `weakening` is indexed by material.
    pub fn weaken(&mut self, mesh: &Mesh, damage: &[Real], weakening: &[Real]) {
        let w_face = |f: usize| weakening[mesh.faces[f].material as usize];
        for (f, m) in self.membrane.iter_mut().enumerate() {
            m.weakened = plasticity::weakened(w_face(f), damage[f]);
        }
        for h in &mut self.hinges {
            let (Some((f0, _)), Some((f1, _))) = (mesh.edges[h.edge].adj.0[0], mesh.edges[h.edge].adj.0[1]) else {
                continue;
            };
            let (f0, f1) = (f0.idx(), f1.idx());
            h.weakened = plasticity::weakened(w_face(f0).max(w_face(f1)), 0.5 * (damage[f0] + damage[f1]));
        }
    }
}

/// Current dihedral angle of every edge (zero on boundary edges): the rest angles of a scene
/// are those of its input shape.
pub fn edge_angles(mesh: &Mesh) -> Vec<Real> {
    edge_angles_by(mesh, |n| mesh.nodes[n].x)
}

/// `edge_angles` of the mesh with its nodes at `x` (a rest embedding, `SimState::rest_x`).
pub fn edge_angles_at(mesh: &Mesh, x: &[crate::math::Vec3]) -> Vec<Real> {
    edge_angles_by(mesh, |n| x[n])
}

fn edge_angles_by(mesh: &Mesh, at: impl Fn(usize) -> crate::math::Vec3) -> Vec<Real> {
    (0..mesh.edges.len())
        .map(|e| match mesh.hinge_nodes(e) {
            Some(h) => {
                let x = h.map(|n| {
                    let p = at(n);
                    crate::math::dual::V3([p.x, p.y, p.z])
                });
                dihedral_angle(&x)
            }
            None => 0.0,
        })
        .collect()
}
