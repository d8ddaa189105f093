//! The plasticity stage (`forces::plasticity`, Narain et al. 2013 after ARCSim 0.2.1's
//! `plasticity_step`): at the end of every accepted step, each face of a material with a yield
//! curvature compares its current shape operator with its plastic one and flows back to the
//! yield surface; the rest angles of the edges of faces that flowed are solved again from the
//! plastic shapes, and the hinges' rest angles and damage factors follow. Nothing changes,
//! bit for bit, while every face stays below its yield.

use crate::forces::bending::unwrap_angle;
use crate::forces::edge_angles;
use crate::forces::material::Material;
use crate::forces::plasticity::yield_face;
use crate::math::Real;
use crate::remesh::rest_shape::{face_shape, refresh_edge_angles};

use super::Simulation;

impl Simulation {
    /// One plastic update of the state and the rest data (no-op without plasticity).
    pub(super) fn plastic_update(&mut self) {
        let Some(plastic) = &mut self.state.plastic else { return };
        let mesh = &self.state.mesh;
        let materials = &self.scene.materials;
        // Current angles on the side of the rest angles (ARCSim's unwrap about the reference
        // angle), so that a crease folded flat reads as π, not −π.
        let current: Vec<Real> =
            edge_angles(mesh).iter().zip(&self.state.rest_angles).map(|(&a, &r)| unwrap_angle(a, r)).collect();
        let mut changed = vec![false; mesh.faces.len()];
        for f in 0..mesh.faces.len() {
            let Some(p) = materials[mesh.faces[f].material as usize].plasticity else { continue };
            if let Some(y) = yield_face(&face_shape(mesh, f, &current), &plastic.shapes[f], p.yield_curv) {
                plastic.shapes[f] = y.shape;
                plastic.damage[f] += y.damage;
                changed[f] = true;
            }
        }
        if !changed.contains(&true) {
            return;
        }
        refresh_edge_angles(mesh, &plastic.shapes, &changed, &mut self.state.rest_angles);
        self.ws.rest.set_rest_angles(&self.state.rest_angles);
        let weakening: Vec<Real> = materials.iter().map(Material::weakening).collect();
        if weakening.iter().any(|&w| w > 0.0) {
            self.ws.rest.weaken(mesh, &plastic.damage, &weakening);
        }
    }
}
