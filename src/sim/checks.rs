//! The fault checks of a step: pure functions of the state before the step, the solved state
//! and the state after collisions. A check that fails returns the `Fault`; the
//! step (`recover.rs`) rolls the attempt back and retries it in halves.
//!
//! The checks, and why each is a fault rather than physics:
//!
//! - **Factorisation** (in the solve): the system matrix M + (hα + h²)K − hD is SPD by
//!   construction (projected Hessians); a failed Cholesky means non-finite or absurd entries.
//! - **Energy** (after the implicit solve, before collisions): handles and obstacles are moved
//!   to their end-of-step positions first, which is where all their work is done (their contact
//!   penalties are frozen at those positions); the free nodes' motion is then one backward-Euler
//!   step, which dissipates. So the energy change of the free motion,
//!   ΔE = ΔK_free + ΔP_free + U(x̂) − U(x̃) + C(x̂) − C(x̃) + S(x̂) − S(x̃)
//!   (x̃: start positions with handles on their targets, x̂: solved positions, U elastic, C
//!   repulsion, S the soft handles' springs at their end-of-step targets, P gravity), may exceed the work W of the wind and of friction (positive where a
//!   moving obstacle drags the cloth; `Friction::work`) only by
//!   `ENERGY_TOLERANCE` × (K₀ + U₀ + C(x̃) + S(x̃) + W) + a floor of the cloth's mass dropping
//!   `FLOOR_DROP` and moving at `FLOOR_SPEED`. One linearised Newton step that misses the
//!   stretch of a large rotation (drape_stiff at h = 1/24: 1.5 J → 120 J in one step with fixed
//!   handles) fails this by orders of magnitude.
//! - **Non-finite** positions or velocities at the end of the step.
//! - **Speed** (after collisions): no node faster than 2 (v̂_max + v_obstacle,max)
//!   + `KICK_THICKNESSES`·thickness/h + 1 m/s, v̂ the solved velocities: an impact-zone
//!   projection may carry nodes along with an obstacle and push them out by a few thicknesses,
//!   not fling them.
//! - **Energy of the collision stage**: impact zones may add at most, per node
//!   they touch, the kinetic energy of moving at twice the fastest obstacle's speed plus that
//!   of the push-out above (both scale like the energy they allow, so a smaller step does not
//!   turn a push-out into a fault), with the same tolerance as the solve.
//! - **Strain jump**: the largest principal strain may not rise by more than `STRAIN_JUMP` in
//!   one step (an element torn open by a projection or a solve).
//! - **Collisions left** at the impact-zone iteration cap (in the step): retried like the
//!   others, but at the smallest step the result is kept (counted in `ccd_cap_hits`): a residual
//!   contact is a smaller harm to a shot than a stopped run. For the same reason, at that
//!   smallest step a node the projection flung faster than the speed cap keeps its solved
//!   position and velocity (counted in `flung_reverted`; its collision may be left), instead of
//!   the run stopping on the speed check.

use crate::math::PAR_GRAIN;
use rayon::prelude::*;

use crate::collision::proximity::{contacts_energy, Contact};
use crate::forces::handle::Spring;
use crate::forces::material::Material;
use crate::forces::membrane::{deformation_gradient, max_principal_strain};
use crate::forces::wind::{wind_face, Wind};
use crate::forces::RestState;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;

use super::recover::Fault;

/// Relative energy gain tolerated per step (of the energy present plus the work done).
pub const ENERGY_TOLERANCE: Real = 0.1;
/// Absolute energy floor: the cloth dropping this far (m) …
pub const FLOOR_DROP: Real = 1e-2;
/// … and moving at this speed (m/s).
pub const FLOOR_SPEED: Real = 0.1;
/// A collision push-out may move a node this many thicknesses within one step.
pub const KICK_THICKNESSES: Real = 4.0;
/// Largest rise of the maximum principal strain in one step.
pub const STRAIN_JUMP: Real = 0.5;

/// The cloth's elastic model: what its energy is a function of.
pub struct Elastic<'a> {
    pub mesh: &'a Mesh,
    pub rest: &'a RestState,
    pub materials: &'a [Material],
}

impl Elastic<'_> {
    /// Elastic energy (membrane + bending) at positions `x`; per-element terms in parallel,
    /// summed in element order (deterministic).
    pub fn energy_at(&self, x: &[Vec3]) -> Real {
        let faces: Vec<Real> = (0..self.mesh.faces.len())
            .into_par_iter()
            .with_min_len(PAR_GRAIN)
            .map(|f| self.face_energy(f, x))
            .collect();
        let hinges: Vec<Real> = (0..self.rest.hinges.len())
            .into_par_iter()
            .with_min_len(PAR_GRAIN)
            .map(|k| self.hinge_energy(k, x))
            .collect();
        faces.iter().sum::<Real>() + hinges.iter().sum::<Real>()
    }

    /// Elastic energy at positions `x`, summed serially over faces, then hinges (the energy
    /// reported in stats.json).
    pub fn energy_serial(&self, x: &[Vec3]) -> Real {
        let mut e = 0.0;
        for f in 0..self.mesh.faces.len() {
            e += self.face_energy(f, x);
        }
        for k in 0..self.rest.hinges.len() {
            e += self.hinge_energy(k, x);
        }
        e
    }

    fn face_energy(&self, f: usize, x: &[Vec3]) -> Real {
        let xs = self.mesh.face_nodes(f).map(|n| x[n]);
        let mat = &self.materials[self.mesh.faces[f].material as usize];
        mat.stretch_energy(&xs, &self.rest.membrane[f])
    }

    fn hinge_energy(&self, k: usize, x: &[Vec3]) -> Real {
        let hg = &self.rest.hinges[k];
        self.materials[hg.material].bend_energy(&hg.nodes.map(|n| x[n]), hg)
    }

    /// U(x̃) − U(x₀): the elastic work of moving the handle nodes in `moved` to `xt` with every
    /// other node held (only elements touching a moved node change).
    fn handle_work(&self, x0: &[Vec3], xt: &[Vec3], moved: &[bool]) -> Real {
        let mut w = 0.0;
        for f in 0..self.mesh.faces.len() {
            if self.mesh.face_nodes(f).iter().any(|&n| moved[n]) {
                w += self.face_energy(f, xt) - self.face_energy(f, x0);
            }
        }
        for (k, hg) in self.rest.hinges.iter().enumerate() {
            if hg.nodes.iter().any(|&n| moved[n]) {
                w += self.hinge_energy(k, xt) - self.hinge_energy(k, x0);
            }
        }
        w
    }

    /// Largest principal strain over all faces at positions `x`.
    pub fn max_strain_at(&self, x: &[Vec3]) -> Real {
        (0..self.mesh.faces.len())
            .into_par_iter()
            .with_min_len(PAR_GRAIN)
            .map(|f| {
                let xs = self.mesh.face_nodes(f).map(|n| x[n]);
                max_principal_strain(&deformation_gradient(&xs, &self.rest.membrane[f]))
            })
            .reduce(|| Real::NEG_INFINITY, Real::max)
    }
}

/// The step the checks judge: the model, the state before it (`elastic.mesh`'s positions and
/// velocities) and what acted on it.
pub struct StepContext<'a> {
    pub elastic: Elastic<'a>,
    pub gravity: Vec3,
    pub wind: Option<&'a Wind>,
    pub h: Real,
    /// Start positions (the mesh's).
    pub x0: &'a [Vec3],
    /// Handle nodes' prescribed velocities.
    pub pinned: &'a [Option<Vec3>],
    /// Soft handles' springs (targets at the step's end).
    pub springs: &'a [Spring],
    /// The step's frozen repulsion contacts, and the obstacle nodes at the step's end.
    pub contacts: &'a [Contact],
    pub fixed: &'a [Vec3],
    /// Collision thickness (0 without collisions) and the fastest obstacle node's speed.
    pub thickness: Real,
    pub obstacle_speed: Real,
    /// Elastic energy at the start of the step (from the assembly).
    pub u0: Real,
    /// The work friction may do on the cloth over the step: a moving obstacle's drag
    /// (`Friction::drag_work`).
    pub friction_work: Real,
}

/// The solved (pre-collision) state and its energy, for the end-of-step check.
pub struct Solved {
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub kinetic: Real,
    pub elastic: Real,
    /// The absolute energy floor of the scene.
    pub floor: Real,
}

fn all_finite(a: &[Vec3], b: &[Vec3]) -> bool {
    a.iter().chain(b).all(|p| p.iter().all(|c| c.is_finite()))
}

/// Repulsion energy of the step's frozen contacts, cloth at `x`.
fn contact_energy(c: &StepContext, x: &[Vec3]) -> Real {
    contacts_energy(c.contacts, x, c.fixed)
}

/// An upper estimate of the wind's work over the step: per face, the larger of its power at the
/// start and at the solved end (never negative), times h. Still air (ARCSim's default wind, in
/// every one of its confs) does none: its force on a face, A (ρ|v_n| v_n n̂ + c_d v_t)/3 with
/// v_rel = −v̄, has power f · 3v̄ = −A (ρ|v_n| v_n² + c_d |v_t|²) ≤ 0.
fn wind_work(c: &StepContext, x1: &[Vec3], v1: &[Vec3]) -> Real {
    let Some(wind) = c.wind.filter(|w| w.velocity != Vec3::zeros()) else { return 0.0 };
    let mesh = c.elastic.mesh;
    let v0: Vec<Vec3> = mesh.nodes.iter().map(|n| n.v).collect();
    let power = |f: usize, x: &[Vec3], v: &[Vec3]| {
        let ids = mesh.face_nodes(f);
        let (vs, xs) = (ids.map(|n| v[n]), ids.map(|n| x[n]));
        let (force, _) = wind_face(&xs, &vs, wind);
        force.dot(&(vs[0] + vs[1] + vs[2]))
    };
    let p: Vec<Real> = (0..mesh.faces.len())
        .into_par_iter()
        .with_min_len(PAR_GRAIN)
        .map(|f| power(f, c.x0, &v0).max(power(f, x1, v1)).max(0.0))
        .collect();
    c.h * p.iter().sum::<Real>()
}

/// The energy check on the solved velocities `v` (module doc). Returns the solved state.
pub fn after_solve(c: &StepContext, v: Vec<Vec3>) -> Result<Solved, Fault> {
    let nodes = &c.elastic.mesh.nodes;
    let x1: Vec<Vec3> = c.x0.iter().zip(&v).map(|(x, v)| x + c.h * v).collect();
    if !all_finite(&x1, &v) {
        return Err(Fault::NonFinite);
    }
    let g = c.gravity;
    let (mut dk, mut dp, mut k0) = (0.0, 0.0, 0.0);
    let mut moved = vec![false; nodes.len()];
    for (i, node) in nodes.iter().enumerate() {
        k0 += 0.5 * node.mass * node.v.norm_squared();
        if c.pinned[i].is_some() {
            moved[i] = x1[i] != c.x0[i];
            continue;
        }
        dk += 0.5 * node.mass * (v[i].norm_squared() - node.v.norm_squared());
        dp -= node.mass * g.dot(&(x1[i] - c.x0[i]));
    }
    // x̃: start positions with the handles already on their targets.
    let xt: Vec<Vec3> = (0..nodes.len()).map(|i| if moved[i] { x1[i] } else { c.x0[i] }).collect();
    let ut = c.u0 + if moved.iter().any(|&m| m) { c.elastic.handle_work(c.x0, &xt, &moved) } else { 0.0 };
    let u1 = c.elastic.energy_at(&x1);
    let k1: Real = nodes.iter().zip(&v).map(|(n, v)| 0.5 * n.mass * v.norm_squared()).sum();
    let (ct, c1) = (contact_energy(c, &xt), contact_energy(c, &x1));
    let spring_energy = |x: &[Vec3]| c.springs.iter().map(|s| s.energy(x)).sum::<Real>();
    let (st, s1) = (spring_energy(&xt), spring_energy(&x1));
    let work = wind_work(c, &x1, &v) + c.friction_work;
    let gain = dk + dp + (u1 - ut) + (c1 - ct) + (s1 - st);
    let mass: Real = nodes.iter().map(|n| n.mass).sum();
    let floor = mass * (g.norm() * FLOOR_DROP + 0.5 * FLOOR_SPEED * FLOOR_SPEED);
    let budget = work + ENERGY_TOLERANCE * (k0 + c.u0 + ct + st + work) + floor;
    if gain > budget || !gain.is_finite() {
        return Err(Fault::EnergyGain { gain, budget });
    }
    Ok(Solved { x: x1, v, kinetic: k1, elastic: u1, floor })
}

/// The speed no node may exceed after collisions (module doc, "Speed").
pub fn speed_cap(c: &StepContext, solved: &Solved) -> Real {
    let v_max_solve = solved.v.iter().map(|v| v.norm()).fold(0.0, Real::max);
    2.0 * (v_max_solve + c.obstacle_speed) + KICK_THICKNESSES * c.thickness / c.h + 1.0
}

/// Checks on the end-of-step state `x`, `v` (after collisions): finite, speed cap,
/// energy against the solved state, strain jump.
pub fn end_of_step(c: &StepContext, solved: &Solved, x: &[Vec3], v: &[Vec3]) -> Result<(), Fault> {
    if !all_finite(x, v) {
        return Err(Fault::NonFinite);
    }
    let (th, v_obs) = (c.thickness, c.obstacle_speed);
    let cap = speed_cap(c, solved);
    let max = v.iter().map(|v| v.norm()).fold(0.0, Real::max);
    if max > cap {
        return Err(Fault::Speed { max, cap });
    }
    if v == solved.v.as_slice() {
        // Collisions changed nothing: the solve's check stands.
        return Ok(());
    }
    // Impact zones are inelastic: they create no energy beyond carrying the nodes
    // they touch along with a moving obstacle (at up to twice its speed) and the kick of
    // pushing a node out by up to `KICK_THICKNESSES` thicknesses within the step. Both
    // allowances scale like the kinetic energy they cover, so halving h does not turn a
    // push-out into a fault.
    let g = c.gravity;
    let kick = KICK_THICKNESSES * th / c.h;
    let (mut k, mut dp, mut carried) = (0.0, 0.0, 0.0);
    for (i, n) in c.elastic.mesh.nodes.iter().enumerate() {
        k += 0.5 * n.mass * v[i].norm_squared();
        dp -= n.mass * g.dot(&(x[i] - solved.x[i]));
        if v[i] != solved.v[i] {
            carried += 0.5 * n.mass * (4.0 * v_obs * v_obs + kick * kick);
        }
    }
    let u = c.elastic.energy_at(x);
    let gain = (k - solved.kinetic) + (u - solved.elastic) + dp;
    let budget = carried + ENERGY_TOLERANCE * (solved.kinetic + solved.elastic + carried) + solved.floor;
    if gain > budget || !gain.is_finite() {
        return Err(Fault::EnergyGain { gain, budget });
    }
    let (from, to) = (c.elastic.max_strain_at(c.x0), c.elastic.max_strain_at(x));
    if to > from + STRAIN_JUMP {
        return Err(Fault::StrainJump { from, to });
    }
    Ok(())
}
