//! Assembly of the implicit system: element kernels run in parallel in fixed-size chunks, and
//! their local matrices are scattered serially in element order, so the sums (and the result)
//! are bit-identical whatever the thread count. This is the one place where local Hessians are
//! added into the global matrix.

use crate::math::PAR_GRAIN;
use rayon::prelude::*;

use crate::collision::friction::FrictionTerm;
use crate::collision::proximity::{repulsion, Contact};
use crate::forces::handle::{anchor_spring, glue_spring, Spring};
use crate::forces::material::Material;
use crate::forces::wind::{wind_face, Wind};
use crate::forces::{Projection, RestState};
use crate::math::{Mat12, Mat3, Mat9, Real, Vec12, Vec3, Vec9};
use crate::mesh::Mesh;

use super::pattern::NONE;
use super::{ImplicitSystem, SolveError, SolveTiming};

/// A contact coupling absent from the pattern (see `add_contacts`).
const MISSING: usize = usize::MAX - 1;

/// Elements processed per parallel chunk (bounds the memory of local matrices).
const CHUNK: usize = 4096;

/// Everything one step's system depends on.
pub struct StepInput<'a> {
    pub mesh: &'a Mesh,
    pub rest: &'a RestState,
    pub materials: &'a [Material],
    pub h: Real,
    pub gravity: Vec3,
    pub wind: Option<&'a Wind>,
    /// For each node: `Some(v)` if its velocity at the end of the step is prescribed.
    pub pinned: &'a [Option<Vec3>],
    /// Soft handles' springs, their targets at the step's end.
    pub springs: &'a [Spring],
    /// Repulsion contacts (collision proximity), frozen for the step.
    pub contacts: &'a [Contact],
    /// Positions of the fixed points (obstacle vertices) that contacts index past the nodes.
    pub fixed: &'a [Vec3],
}

/// How the element forces enter the system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// A backward-Euler step of size `StepInput::h` (the `solver` module doc).
    Step,
    /// A Newton step on the potential at fixed positions (the pop filter, `sim::pop`):
    /// A = ∇²E, b = −∇E over the elastic, repulsion and handle-spring energies; no mass, gravity,
    /// damping, velocities or wind. It is the step's system at h = 1 with those switched off.
    Static,
}

impl Scheme {
    /// The step size the terms are scaled by, and an element's damping coefficient.
    fn h_and_damping(self, inp: &StepInput, damping: Real) -> (Real, Real) {
        match self {
            Scheme::Step => (inp.h, damping),
            Scheme::Static => (1.0, 0.0),
        }
    }

    /// Node `i`'s velocity as the terms see it.
    fn velocity(self, inp: &StepInput, i: usize) -> Vec3 {
        match self {
            Scheme::Step => inp.mesh.nodes[i].v,
            Scheme::Static => Vec3::zeros(),
        }
    }
}

struct Local<const N: usize, const M: usize> {
    energy: Real,
    rhs: nalgebra::SVector<Real, M>,
    mat: nalgebra::SMatrix<Real, M, M>,
}

fn face_local(inp: &StepInput, scheme: Scheme, proj: Projection, f: usize) -> Local<3, 9> {
    let mesh = inp.mesh;
    let ids = mesh.face_nodes(f);
    let x = ids.map(|n| mesh.nodes[n].x);
    let v = ids.map(|n| scheme.velocity(inp, n));
    let m = &inp.materials[mesh.faces[f].material as usize];
    let (h, damping) = scheme.h_and_damping(inp, m.damping);
    let (energy, grad, hess) = m.stretch(&x, &inp.rest.membrane[f], proj);
    let vl = Vec9::from_fn(|r, _| v[r / 3][r % 3]);
    // b = h(f − (α + h) K v), A = (hα + h²) K; the gradient alone when no matrix is wanted
    // (`Scheme::Static` has v = 0, so b is the same).
    let (mut rhs, mut mat) = match proj {
        Projection::Gradient => (-h * grad, Mat9::zeros()),
        _ => (-h * grad - h * (damping + h) * (hess * vl), (h * damping + h * h) * hess),
    };
    if let Some(w) = inp.wind.filter(|_| scheme == Scheme::Step) {
        let (fw, dfdv) = wind_face(&x, &v, w);
        for i in 0..3 {
            for d in 0..3 {
                rhs[3 * i + d] += h * fw[d];
            }
            if !w.implicit {
                continue;
            }
            for j in 0..3 {
                let mut blk = mat.fixed_view_mut::<3, 3>(3 * i, 3 * j);
                blk -= h * dfdv;
            }
        }
    }
    Local { energy, rhs, mat }
}

fn hinge_local(inp: &StepInput, scheme: Scheme, proj: Projection, k: usize) -> Local<4, 12> {
    let hinge = &inp.rest.hinges[k];
    let x = hinge.nodes.map(|n| inp.mesh.nodes[n].x);
    let m = &inp.materials[hinge.material];
    let (h, damping) = scheme.h_and_damping(inp, m.damping);
    let (energy, grad, hess) = m.bend(&x, hinge, proj);
    if proj == Projection::Gradient {
        return Local { energy, rhs: -h * grad, mat: Mat12::zeros() };
    }
    let vl = Vec12::from_fn(|r, _| scheme.velocity(inp, hinge.nodes[r / 3])[r % 3]);
    let rhs = -h * grad - h * (damping + h) * (hess * vl);
    let mat: Mat12 = (h * damping + h * h) * hess;
    Local { energy, rhs, mat }
}

/// Adds a local right-hand side, and with `blocks` its matrix, into the system.
fn scatter<const N: usize, const M: usize>(
    blocks: Option<&mut [Mat3]>,
    rhs: &mut [Vec3],
    nodes: &[usize; N],
    slots: &[usize],
    local: &Local<N, M>,
) {
    for i in 0..N {
        rhs[nodes[i]] += local.rhs.fixed_rows::<3>(3 * i);
    }
    let Some(blocks) = blocks else { return };
    for i in 0..N {
        for j in 0..N {
            let s = slots[i * N + j];
            if s != NONE {
                blocks[s] += local.mat.fixed_view::<3, 3>(3 * i, 3 * j);
            }
        }
    }
}

impl ImplicitSystem {
    /// Assembles the step's system without friction (elastic forces, damping, wind, gravity,
    /// repulsion); returns the elastic energy at the start of the step. `solve` adds the friction
    /// terms and the pinned nodes.
    pub fn assemble(&mut self, inp: &StepInput) -> Real {
        let energy = self.assemble_base(inp, Scheme::Step, true);
        self.base_saved = false;
        energy
    }

    /// Assembles the static Newton system of the potential E (elastic, repulsion, springs) at
    /// the mesh's positions, plus `mu` I, with `rhs` added to −∇E (`Scheme::Static`); returns
    /// the elastic energy. `solve` (no terms) then gives the position change, pinned nodes
    /// held where `inp.pinned` is their current velocity. Without `matrix` only the right-hand
    /// side is assembled (the same bits), for a solve with the factor of an earlier matrix.
    pub fn assemble_static(&mut self, inp: &StepInput, mu: Real, rhs: &[Vec3], matrix: bool) -> Real {
        let energy = self.assemble_base(inp, Scheme::Static, matrix);
        for (b, r) in rhs.iter().enumerate().take(self.pattern.nodes) {
            if matrix {
                self.blocks[self.pattern.col_start[b]] += Mat3::identity() * mu;
            }
            self.rhs[b] += r;
        }
        self.base_saved = false;
        energy
    }

    /// Solves the assembled system with the friction and contact `terms` added; returns Δv.
    /// With `refactor` false the matrix must be the one last factorised (only the right-hand
    /// side changed). `again`: the step may solve again with other terms (the assembled system
    /// is then kept).
    pub fn solve(
        &mut self,
        inp: &StepInput,
        terms: &[FrictionTerm],
        refactor: bool,
        again: bool,
        timing: &mut SolveTiming,
    ) -> Result<Vec<Vec3>, SolveError> {
        let t0 = std::time::Instant::now();
        if self.base_saved {
            self.blocks.copy_from_slice(&self.base_blocks);
            self.rhs.copy_from_slice(&self.base_rhs);
        } else if again {
            // Kept for the re-solves of this step.
            self.base_blocks.clone_from(&self.blocks);
            self.base_rhs.clone_from(&self.rhs);
            self.base_saved = true;
        }
        self.add_friction(inp, terms);
        self.eliminate_pinned(inp);
        let t1 = std::time::Instant::now();
        timing.assemble_s += (t1 - t0).as_secs_f64();
        if refactor {
            let blocks = &self.blocks;
            self.values.par_iter_mut().zip(self.chol.value_sources().par_iter()).with_min_len(64 * PAR_GRAIN).for_each(
                |(v, &s)| {
                    let b = &blocks[s / 9];
                    *v = b[((s % 9) / 3, s % 3)];
                },
            );
            // A step's first factorisation is a full one, so that no step's factor depends on
            // an earlier step's (a resumed run then takes the same bits).
            let tail = match timing.factorisations {
                0 => self.chol.factor(&self.values).map(|_| false)?,
                _ => self.chol.refactor(&self.values)?,
            };
            timing.factorisations += 1;
            timing.tail_factorisations += usize::from(tail);
        }
        let t2 = std::time::Instant::now();
        let mut x: Vec<f64> = self.rhs.iter().flat_map(|r| [r.x, r.y, r.z]).collect();
        self.chol.solve(&mut x);
        let dv = x.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
        let t3 = std::time::Instant::now();
        timing.factor_s += (t2 - t1).as_secs_f64();
        timing.solve_s += (t3 - t2).as_secs_f64();
        timing.solves += 1;
        Ok(dv)
    }

    /// Fills `rhs` and, with `matrix`, `blocks` (left as they were otherwise); returns the
    /// elastic energy.
    fn assemble_base(&mut self, inp: &StepInput, scheme: Scheme, matrix: bool) -> Real {
        let mesh = inp.mesh;
        // The right-hand side alone equals the full one's only without velocities.
        debug_assert!(matrix || scheme == Scheme::Static, "a right-hand side alone is for the static system");
        let proj = if matrix { Projection::Psd } else { Projection::Gradient };
        if matrix {
            self.blocks.iter_mut().for_each(|b| *b = Mat3::zeros());
        }
        self.rhs.iter_mut().for_each(|r| *r = Vec3::zeros());
        if scheme == Scheme::Step {
            for (r, n) in self.rhs.iter_mut().zip(&mesh.nodes) {
                *r = inp.h * n.mass * inp.gravity;
            }
            for b in (0..self.pattern.nodes).filter(|_| matrix) {
                // The diagonal block is first in its column.
                self.blocks[self.pattern.col_start[b]] += Mat3::identity() * mesh.nodes[b].mass;
            }
        }
        let mut energy = 0.0;
        let nf = mesh.faces.len();
        for start in (0..nf).step_by(CHUNK) {
            let locals: Vec<Local<3, 9>> = (start..(start + CHUNK).min(nf))
                .into_par_iter()
                .with_min_len(PAR_GRAIN)
                .map(|f| face_local(inp, scheme, proj, f))
                .collect();
            for (k, local) in locals.iter().enumerate() {
                let f = start + k;
                energy += local.energy;
                let blocks = matrix.then_some(self.blocks.as_mut_slice());
                scatter(blocks, &mut self.rhs, &mesh.face_nodes(f), &self.pattern.face_slots[f], local);
            }
        }
        let nh = inp.rest.hinges.len();
        for start in (0..nh).step_by(CHUNK) {
            let locals: Vec<Local<4, 12>> = (start..(start + CHUNK).min(nh))
                .into_par_iter()
                .with_min_len(PAR_GRAIN)
                .map(|k| hinge_local(inp, scheme, proj, k))
                .collect();
            for (j, local) in locals.iter().enumerate() {
                let k = start + j;
                energy += local.energy;
                scatter(
                    matrix.then_some(self.blocks.as_mut_slice()),
                    &mut self.rhs,
                    &inp.rest.hinges[k].nodes,
                    &self.pattern.hinge_slots[k],
                    local,
                );
            }
        }
        self.add_contacts(inp, scheme, matrix);
        self.add_springs(inp, scheme, matrix);
        energy
    }

    /// Soft handles enter like elastic elements without damping (ARCSim's
    /// `add_constraint_forces`): A += h² ∇²E (with `matrix`), b += −h (∇E + h ∇²E v).
    fn add_springs(&mut self, inp: &StepInput, scheme: Scheme, matrix: bool) {
        let (h, _) = scheme.h_and_damping(inp, 0.0);
        let nodes = &inp.mesh.nodes;
        for spring in inp.springs {
            match *spring {
                Spring::Anchor { node, target, k } => {
                    let (_, grad, hess) = anchor_spring(&nodes[node].x, &target, k);
                    self.rhs[node] -= h * (grad + h * (hess * scheme.velocity(inp, node)));
                    if matrix {
                        self.blocks[self.pattern.col_start[node]] += h * h * hess;
                    }
                }
                Spring::Glue { nodes: [a, b], k } => {
                    let (_, grad, hess) = glue_spring(&nodes[a].x, &nodes[b].x, k);
                    let mut vl = nalgebra::SVector::<Real, 6>::zeros();
                    vl.fixed_rows_mut::<3>(0).copy_from(&scheme.velocity(inp, a));
                    vl.fixed_rows_mut::<3>(3).copy_from(&scheme.velocity(inp, b));
                    let rhs = -h * (grad + h * (hess * vl));
                    self.rhs[a] += rhs.fixed_rows::<3>(0);
                    self.rhs[b] += rhs.fixed_rows::<3>(3);
                    if !matrix {
                        continue;
                    }
                    let kk = h * h * k * Mat3::identity();
                    // The pair's coupling is in the pattern (`SimState::extra_pairs` holds glue
                    // pairs); were it missing, 2 k I on each diagonal majorizes the spring, as
                    // for contacts (`add_contacts`).
                    let (hi, lo) = (a.max(b), a.min(b));
                    let (diag, off) = match self.pattern.block(hi, lo) {
                        Some(s) => (kk, Some(s)),
                        None => (2.0 * kk, None),
                    };
                    self.blocks[self.pattern.col_start[a]] += diag;
                    self.blocks[self.pattern.col_start[b]] += diag;
                    if let Some(s) = off {
                        self.blocks[s] -= kk;
                    }
                }
            }
        }
    }

    /// Repulsion contacts enter like elastic elements (without damping):
    /// A += h² K_c (with `matrix`), b += h (−∇E_c − h K_c v) over the cloth nodes; fixed points
    /// are constant.
    /// Only the pop filter's static solve passes contacts here; the implicit step passes none
    /// and adds its contacts through their active set (`collision::speculative`), so that a
    /// contact the step carries out of the thickness lets go.
    ///
    /// A contact coupling cloth nodes whose blocks are not all in the pattern (a guard: the
    /// pop filter analyses the pattern for its contacts first, `Workspace::pattern_for_step`)
    /// keeps its exact right-hand side, but its matrix enters on the diagonal only, as
    /// a majorizer: K_c = k (w wᵀ) ⊗ (n nᵀ) and, for the m cloth nodes of the contact,
    /// (Σᵢ wᵢ xᵢ·n)² ≤ m Σᵢ wᵢ² (xᵢ·n)² (Cauchy–Schwarz), so m · blockdiag(K_c) ⪰ K_c: the
    /// system stays SPD and the step is at least as stiff as with the full block.
    fn add_contacts(&mut self, inp: &StepInput, scheme: Scheme, matrix: bool) {
        let n = inp.mesh.nodes.len();
        let (h, _) = scheme.h_and_damping(inp, 0.0);
        for c in inp.contacts {
            let pos = c.nodes.map(|i| if i < n { inp.mesh.nodes[i].x } else { inp.fixed[i - n] });
            let (_, grad, hess) = repulsion(c, &pos);
            if grad == Vec12::zeros() {
                continue;
            }
            let vl = Vec12::from_fn(|r, _| {
                let i = c.nodes[r / 3];
                if i < n {
                    scheme.velocity(inp, i)[r % 3]
                } else {
                    0.0
                }
            });
            let rhs = -h * grad - h * h * (hess * vl);
            let slots = self.contact_slots(&c.nodes, n);
            let cloth = c.nodes.iter().filter(|&&i| i < n).count() as Real;
            let complete = slots.iter().all(|&s| s != MISSING);
            for a in 0..4 {
                let i = c.nodes[a];
                if i >= n {
                    continue;
                }
                self.rhs[i] += rhs.fixed_rows::<3>(3 * a);
                if !matrix {
                    continue;
                }
                if !complete {
                    let diag = self.pattern.col_start[i]; // first in its column
                    self.blocks[diag] += (cloth * h * h) * hess.fixed_view::<3, 3>(3 * a, 3 * a);
                    continue;
                }
                for b in 0..4 {
                    let s = slots[4 * a + b];
                    if s != NONE {
                        self.blocks[s] += h * h * hess.fixed_view::<3, 3>(3 * a, 3 * b);
                    }
                }
            }
        }
    }

    /// Friction terms (`collision::friction`): their right-hand sides, and a sticking contact's
    /// damper h c T between each pair of its cloth nodes, weighted wₐ w_b (PSD: (w wᵀ) ⊗ T).
    /// A coupling missing from the pattern enters as the diagonal majorizer, as in
    /// `add_contacts`.
    fn add_friction(&mut self, inp: &StepInput, terms: &[FrictionTerm]) {
        let n = inp.mesh.nodes.len();
        for t in terms {
            let slots = self.contact_slots(&t.nodes, n);
            let cloth = t.nodes.iter().filter(|&&i| i < n).count() as Real;
            let complete = slots.iter().all(|&s| s != MISSING);
            for a in 0..4 {
                let i = t.nodes[a];
                if i >= n {
                    continue;
                }
                self.rhs[i] += t.rhs[a];
                let Some(d) = t.damper else { continue };
                if !complete {
                    let diag = self.pattern.col_start[i]; // first in its column
                    self.blocks[diag] += (cloth * t.w[a] * t.w[a]) * d;
                    continue;
                }
                for b in 0..4 {
                    let s = slots[4 * a + b];
                    if s != NONE {
                        self.blocks[s] += (t.w[a] * t.w[b]) * d;
                    }
                }
            }
        }
    }

    /// Block index of each lower-triangle cloth–cloth coupling (a, b) of a contact; `NONE` for
    /// a fixed point or the upper triangle, `MISSING` for a coupling not in the pattern.
    fn contact_slots(&self, nodes: &[usize; 4], n: usize) -> [usize; 16] {
        let mut slots = [NONE; 16];
        for a in 0..4 {
            for b in 0..4 {
                let (i, j) = (nodes[a], nodes[b]);
                if i < n && j < n && i >= j {
                    slots[4 * a + b] = self.pattern.block(i, j).unwrap_or(MISSING);
                }
            }
        }
        slots
    }

    /// Dirichlet elimination: a pinned node's Δv is prescribed; its coupling moves to the right
    /// side of its neighbours' rows and its own row becomes the identity.
    fn eliminate_pinned(&mut self, inp: &StepInput) {
        let dv: Vec<Option<Vec3>> = inp.pinned.iter().zip(&inp.mesh.nodes).map(|(p, n)| p.map(|v| v - n.v)).collect();
        if dv.iter().all(Option::is_none) {
            return;
        }
        let p = &self.pattern;
        for b in 0..p.nodes {
            for k in p.col_start[b]..p.col_start[b + 1] {
                let a = p.rows[k];
                let blk = self.blocks[k];
                if a == b {
                    if dv[b].is_some() {
                        self.blocks[k] = Mat3::identity();
                    }
                    continue;
                }
                match (dv[a], dv[b]) {
                    (None, None) => continue,
                    (None, Some(d)) => self.rhs[a] -= blk * d,
                    (Some(d), None) => self.rhs[b] -= blk.transpose() * d,
                    (Some(_), Some(_)) => {}
                }
                self.blocks[k] = Mat3::zeros();
            }
        }
        for (r, d) in self.rhs.iter_mut().zip(&dv) {
            if let Some(d) = d {
                *r = *d;
            }
        }
    }
}
