//! The handles stage of a step (`scene::handle` for the semantics): switching handles on,
//! the exact handles' targets (their nodes' prescribed positions at the step's end) and the
//! soft handles' springs (forces of the implicit solve, `forces::handle`), and the rings of
//! circle handles after a remesh.

use crate::error::InputError;
use crate::forces::handle::Spring;
use crate::math::{Real, Vec2, Vec3};
use crate::mesh::Mesh;
use crate::scene::{Handle, HandleKind};

use super::state::HandleOn;
use super::{SimError, Simulation};

/// What the handles do in one step: nodes held exactly on a target at the step's end, and
/// springs.
#[derive(Clone, Debug, Default)]
pub struct Held {
    /// (node, target at the step's end) of every node an exact handle holds.
    pub exact: Vec<(usize, Vec3)>,
    pub springs: Vec<Spring>,
}

impl Simulation {
    /// Switches on, at a step starting at the current time t0, every handle whose start has
    /// come and that still acts: its nodes are anchored where they are now.
    pub(super) fn switch_on_handles(&mut self) {
        let t0 = self.state.time;
        for (h, handle) in self.scene.handles.iter().enumerate() {
            if self.state.handle_on[h].is_some() || t0 < handle.start || !acts(handle, t0) {
                continue;
            }
            let x = match handle.kind {
                HandleKind::Nodes => self.state.handle_nodes[h].iter().map(|&n| self.state.mesh.nodes[n].x).collect(),
                HandleKind::Circle(_) | HandleKind::Glue => Vec::new(),
            };
            self.state.handle_on[h] = Some(HandleOn { time: t0, x });
        }
    }

    /// The exact targets and the springs of the step from the current time to `t1`.
    pub(super) fn held(&self, t1: Real) -> Result<Held, SimError> {
        let t0 = self.state.time;
        let mesh = &self.state.mesh;
        let mut held = Held::default();
        let mut uv: Option<Vec<Vec2>> = None;
        for (h, handle) in self.scene.handles.iter().enumerate() {
            let Some(on) = &self.state.handle_on[h] else { continue };
            let nodes = &self.state.handle_nodes[h];
            let strength = match handle.stiffness {
                None if handle.active(t0) => 1.0,
                Some(_) => handle.strength(t1),
                None => 0.0,
            };
            if strength == 0.0 {
                continue;
            }
            let mut hold = |node: usize, target: Vec3, k: Option<Real>| match k {
                None => held.exact.push((node, target)),
                Some(k) => held.springs.push(Spring::Anchor { node, target, k: k * strength }),
            };
            match &handle.kind {
                HandleKind::Nodes => {
                    let d = handle.displacement(on.time, t1).ok_or_else(|| zero_scale(self, h, on.time))?;
                    for (k, &n) in nodes.iter().enumerate() {
                        hold(n, d.apply(&on.x[k]), handle.stiffness);
                    }
                }
                HandleKind::Circle(circle) => {
                    let uv = uv.get_or_insert_with(|| node_uv(mesh));
                    let ring_length = ring_lengths(mesh, nodes);
                    for (k, &n) in nodes.iter().enumerate() {
                        let target = handle.circle_target(circle, &uv[n], t1);
                        hold(n, target, handle.stiffness.map(|s| s * ring_length[k]));
                    }
                }
                HandleKind::Glue => {
                    let k = handle.stiffness.unwrap_or(0.0) * strength;
                    held.springs.push(Spring::Glue { nodes: [nodes[0], nodes[1]], k });
                }
            }
        }
        Ok(held)
    }

    /// After a remesh that mapped old nodes to new ones and gave each new node a group (the
    /// groups `circle_groups` set up): every circle's ring is the nodes of its group.
    pub(super) fn rings_remeshed(&mut self, groups: &[u32]) {
        for (h, handle) in self.scene.handles.iter().enumerate() {
            if let HandleKind::Circle(_) = handle.kind {
                let group = ring_group(&self.scene.handles, h);
                self.state.handle_nodes[h] = (0..groups.len()).filter(|&n| groups[n] == group).collect();
            }
        }
    }

    /// Per node of the current mesh, the group the remesher carries for circle rings (0: none),
    /// or an empty list when the scene has no circle handle.
    pub(super) fn circle_groups(&self) -> Vec<u32> {
        let handles = &self.scene.handles;
        if !handles.iter().any(|h| matches!(h.kind, HandleKind::Circle(_))) {
            return Vec::new();
        }
        let mut groups = vec![0; self.state.mesh.nodes.len()];
        for (h, handle) in handles.iter().enumerate() {
            if let HandleKind::Circle(_) = handle.kind {
                for &n in &self.state.handle_nodes[h] {
                    groups[n] = ring_group(handles, h);
                }
            }
        }
        groups
    }
}

/// Whether a handle still acts in a step starting at `t`: exact ones until `end`, soft ones
/// until their fade is over.
fn acts(handle: &Handle, t: Real) -> bool {
    match handle.stiffness {
        None => t < handle.end,
        Some(_) => t <= handle.end + handle.fade,
    }
}

/// The group of circle handle `h`'s ring: 1 + the first circle handle with the same ring (two
/// handles on one label share it).
fn ring_group(handles: &[Handle], h: usize) -> u32 {
    let same = handles.iter().position(|o| matches!(o.kind, HandleKind::Circle(_)) && o.nodes == handles[h].nodes);
    1 + same.unwrap_or(h) as u32
}

/// The material coordinate of every node: its first vert's (ARCSim takes `node->verts[0]`).
fn node_uv(mesh: &Mesh) -> Vec<Vec2> {
    let mut uv = vec![None; mesh.nodes.len()];
    for v in &mesh.verts {
        uv[v.node.idx()].get_or_insert(v.u);
    }
    uv.into_iter().map(|u| u.unwrap_or_else(Vec2::zeros)).collect()
}

/// Per ring node, the material length of its edges to other ring nodes (an edge's length is
/// the mean over its sides, which differ across a seam; ARCSim's `edge->l`).
fn ring_lengths(mesh: &Mesh, ring: &[usize]) -> Vec<Real> {
    let mut index = vec![usize::MAX; mesh.nodes.len()];
    for (k, &n) in ring.iter().enumerate() {
        index[n] = k;
    }
    let mut length = vec![0.0; ring.len()];
    for e in &mesh.edges {
        let (a, b) = (index[e.n[0].idx()], index[e.n[1].idx()]);
        if a == usize::MAX || b == usize::MAX {
            continue;
        }
        let sides: Vec<Real> = e
            .adj
            .0
            .iter()
            .flatten()
            .map(|&(f, k)| {
                let uv = mesh.face_uv(f.idx());
                (uv[(k as usize + 1) % 3] - uv[(k as usize + 2) % 3]).norm()
            })
            .collect();
        let l = sides.iter().sum::<Real>() / sides.len().max(1) as Real;
        length[a] += l;
        length[b] += l;
    }
    length
}

fn zero_scale(sim: &Simulation, h: usize, t: Real) -> SimError {
    SimError::Input(InputError {
        file: sim.scene.file.clone(),
        location: None,
        msg: format!(
            "handle {h}: its motion's scale is 0 at t = {t} s, when it switched on: its nodes cannot be anchored"
        ),
    })
}
