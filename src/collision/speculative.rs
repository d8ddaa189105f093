//! The repulsion contacts' active set inside the implicit step.
//!
//! The repulsion penalty E(g), g < 0 (`proximity.rs`; Harmon et al. 2008, Narain et al. 2012 §6),
//! linearised at the start of the step, has two faults as a term of the backward-Euler system:
//!
//! - a pair outside the thickness at the start (g(x₀) ≥ 0) gets no force, however fast it
//!   closes. Cloth moving faster than the thickness per step then ends deep inside it, and the
//!   next step's penalty releases ½ k g² that no work paid for (a light fabric falling at 2 m/s
//!   onto a ball gains a quarter of its energy this way);
//! - a pair inside at the start keeps its linear spring whatever the solved motion does, so one
//!   the step carries out of the thickness is pulled back: the contact holds the cloth like glue
//!   for the step. Cloth sliding around a curved obstacle leaves each contact's frozen plane a
//!   little every step, and was held to it: a frictionless strip over a ball at 5 ms steps slid
//!   half as far as it should in 0.4 s, and ARCSim's sphere.json sheet stretched over the moving
//!   sphere (mean strain 0.060 at frame 59 on a fixed 8,192-face mesh, against ARCSim's 0.026 and
//!   0.027 here at 1.25 ms steps).
//!
//! Backward Euler proper takes the force at the end of the step, −E′(g(x₁)) ∂g for g(x₁) < 0 and
//! none otherwise: piecewise linear in the unknown velocities for the quadratic law. Proximity
//! returns the pairs within the thickness and those the start velocities carry within it
//! during the step (`CollisionWorld::proximity`), and this module solves the complementarity by
//! an active set over all of them:
//!
//! - an **active** contact adds its spring −k g(x) ∂g, linear in x (g is linear with the normal
//!   and weights frozen), to the system: matrix h² k (w wᵀ) ⊗ (n nᵀ), right-hand side
//!   h wᵢ (−k g(x₀ + h v₀) n);
//! - after each solve a contact is active exactly when its gap at the solved end positions is
//!   negative; a change switches it (the matrix changes: a refactorisation, within the friction
//!   iteration's budget, `sim::step`).
//!
//! ARCSim's cubic penalty (`proximity::Law::Cubic`) is not linear in the gap: an active contact
//! gets its tangent at a gap g*: for a contact inside at the start, the start gap with *both*
//! sides where they are at the start of the step (ARCSim's own linearisation, `physics.cpp`,
//! `add_constraint_forces`, which evaluates the constraint before `update_obstacles` moves the
//! obstacle and carries the obstacle's motion in the velocity term), else the gap it is
//! expected to end at (the start velocities' at first, the solved one once an update switches
//! it on): force −E′(g*) − E″(g*)(g − g*), matrix h² E″(g*). A contact expected to end at the
//! thickness exactly has neither. (Linearised with the obstacle already at the end of the step,
//! a sphere closing at 2 m/s put g* two thicknesses deep, where the cubic is 8 times stiffer
//! than at one: the solve overshot, and ARCSim's sphere.json met 12,000 impacts a frame.)
//!
//! First guess: active when inside at the start or when the start velocities end inside,
//! g(x₀ + h v₀) < 0. At a converged set every active contact ends inside (its spring pushes, as
//! the one-sided penalty would) and every inactive one outside (no force, as the penalty gives
//! none), so the step is backward Euler with the one-sided penalty at the end positions. When the
//! budget runs out first, the changes left (`pending`) wait for the next step.

use super::friction::{Change, FrictionFrame, FrictionTerm};
use super::proximity::{Contact, Law};
use crate::math::{Real, Vec3};

/// A contact inside at the start of the step whose two sides already part faster than this many
/// thicknesses per step stays active for the whole step. Sliding parts them slowly (a strip
/// sliding over a ball left its contacts' frozen planes at under 0.01 m/s) and an obstacle
/// pushing cloth not at all; two sides parting fast were launched by the contact's own spring,
/// which pushes cloth deep in the thickness out to it within one step, and let go the cloth flies
/// (a sheet walked out of a box by the separation stage flew off its top with 2.7 times the work
/// of lifting it out). Held, the spring stops it at the thickness, as every contact did before
/// they were in the active set.
pub const LEAVING: Real = 0.5;

/// One repulsion contact and whether its spring is in the system.
#[derive(Clone, Copy, Debug)]
struct Item {
    contact: Contact,
    active: bool,
    /// The gap a cubic-law contact is linearised at (see the module documentation).
    g_lin: Real,
    /// Active for the whole step whatever the solve does (`Speculative::new`, `hold_inside`).
    held: bool,
}

/// The step's repulsion contacts and which of them are active.
pub struct Speculative {
    items: Vec<Item>,
    /// Contacts whose verdict differs from their state after the last update (changes it did
    /// not apply).
    pub pending: usize,
}

/// Gap of `c` with the cloth at velocities `v` over the step (x₀ + h v; obstacle points at
/// the end of the step).
fn gap(frame: &FrictionFrame, c: &Contact, v: &[Vec3]) -> Real {
    c.gap(&c.nodes.map(|i| frame.point(i, v).0))
}

/// The rate n · Σ wᵢ uᵢ at which `c`'s gap opens at the start velocities (uᵢ the cloth's v₀ and
/// the obstacle points' velocities over the step): the relative normal speed; with
/// `obstacle_only`, the obstacle points' part alone (the gap's rate with the cloth held still).
fn normal_speed(frame: &FrictionFrame, c: &Contact, obstacle_only: bool) -> Real {
    let cloth = frame.x0.len();
    let rate: Vec3 = (0..4)
        .filter(|&j| !obstacle_only || c.nodes[j] >= cloth)
        .map(|j| c.w[j] * frame.point(c.nodes[j], frame.v0).1)
        .sum();
    c.n.dot(&rate)
}

impl Speculative {
    /// All of `contacts`, active when inside the thickness at the start of the step or carried
    /// inside by the start velocities. A contact inside at the start whose sides already part
    /// faster than `LEAVING` thicknesses per step, and with `hold_inside` (while the separation
    /// stage, `sim::separate`, walks cloth out of an obstacle) every contact inside at the start,
    /// stays active for the whole step, as all did before they were in the active set.
    pub fn new(contacts: &[Contact], frame: &FrictionFrame, hold_inside: bool) -> Speculative {
        let rest = vec![Vec3::zeros(); frame.x0.len()];
        let items = contacts
            .iter()
            .map(|&contact| {
                let (g0, g1) = (gap(frame, &contact, &rest), gap(frame, &contact, frame.v0));
                // g0 holds the cloth still against the obstacle at the end of the step; ARCSim
                // linearises with the obstacle still at the start too.
                let g_start = g0 - frame.h * normal_speed(frame, &contact, true);
                let g_lin = if g_start < 0.0 { g_start } else { g1 };
                let leaving = frame.h * normal_speed(frame, &contact, false) > LEAVING * contact.thickness;
                let held = g0 < 0.0 && (hold_inside || leaving);
                Item { contact, active: g0 < 0.0 || g1 < 0.0, g_lin, held }
            })
            .collect();
        Speculative { items, pending: 0 }
    }

    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The active contacts' springs as system terms.
    pub fn terms(&self, frame: &FrictionFrame) -> Vec<FrictionTerm> {
        let h = frame.h;
        self.items
            .iter()
            .filter(|it| it.active)
            .map(|it| {
                let c = &it.contact;
                // The spring's force at the start velocities; its linear part in Δv is the matrix.
                let g1 = gap(frame, c, frame.v0);
                let (force, k) = match c.law {
                    Law::Quadratic => (-c.stiffness * g1, c.stiffness),
                    Law::Cubic => {
                        let (_, f, k) = c.penalty(it.g_lin);
                        (f - k * (g1 - it.g_lin), k)
                    }
                };
                let force = force * c.n;
                let damper = (h * h * k) * (c.n * c.n.transpose());
                FrictionTerm { nodes: c.nodes, w: c.w, rhs: c.w.map(|w| h * w * force), damper: Some(damper) }
            })
            .collect()
    }

    /// Re-evaluates which contacts end inside at the solved velocities `v`; switches them when
    /// `apply` (a change of the matrix), otherwise counts them in `pending`.
    pub fn update(&mut self, frame: &FrictionFrame, v: &[Vec3], apply: bool) -> Change {
        let verdicts: Vec<bool> = self.items.iter().map(|it| it.held || gap(frame, &it.contact, v) < 0.0).collect();
        let wanted = self.items.iter().zip(&verdicts).filter(|(it, &inside)| it.active != inside).count();
        if wanted == 0 {
            self.pending = 0;
            return Change::None;
        }
        if !apply {
            self.pending = wanted;
            return Change::None;
        }
        for (it, inside) in self.items.iter_mut().zip(verdicts) {
            if inside && !it.active {
                it.g_lin = gap(frame, &it.contact, v);
            }
            it.active = inside;
        }
        self.pending = 0;
        Change::Modes
    }

    /// Contacts active and speculative in all.
    pub fn counts(&self) -> (usize, usize) {
        (self.items.iter().filter(|it| it.active).count(), self.items.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Node 0 (mass 1) above a fixed point (index 1), normal +z, thickness 2 mm, k = 1000.
    fn setup(height: Real, v: Real) -> ([Vec3; 1], [Vec3; 1], Contact) {
        let c = Contact {
            nodes: [0, 1, 0, 0],
            w: [1.0, -1.0, 0.0, 0.0],
            n: Vec3::z(),
            thickness: 2e-3,
            stiffness: 1000.0,
            law: Law::Quadratic,
        };
        ([Vec3::new(0.0, 0.0, height)], [Vec3::new(0.0, 0.0, v)], c)
    }

    #[test]
    fn a_pair_closing_within_the_step_starts_active_and_one_stopping_short_is_switched_off() {
        // 3 mm up, falling at 0.2 m/s, h = 0.01: predicted 1 mm, inside the 2 mm thickness.
        let (x0, v0, c) = setup(3e-3, -0.2);
        let fixed_v = [Vec3::zeros()];
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        let mut s = Speculative::new(&[c], &frame, false);
        assert_eq!(s.counts(), (1, 1));
        let t = s.terms(&frame)[0];
        // Spring at the predicted gap −1 mm: pushes up with k · 1 mm = 1 N, times h.
        assert!((t.rhs[0] - Vec3::new(0.0, 0.0, 0.01)).norm() < 1e-12);
        assert!((t.damper.unwrap()[(2, 2)] - 0.1).abs() < 1e-12);
        // Solved: stops 0.5 mm outside the thickness: switched off.
        assert_eq!(s.update(&frame, &[Vec3::new(0.0, 0.0, -0.05)], true), Change::Modes);
        assert_eq!(s.counts(), (0, 1));
        // Solved inside again but changes may not be applied: pending.
        assert_eq!(s.update(&frame, &[Vec3::new(0.0, 0.0, -0.2)], false), Change::None);
        assert_eq!((s.counts(), s.pending), ((0, 1), 1));
    }

    #[test]
    fn a_contact_inside_at_the_start_that_the_step_carries_out_is_released_not_held() {
        // 1 mm up, inside the 2 mm thickness, leaving slowly (0.05 m/s, h = 0.01: predicted
        // 0.5 mm up, still inside). Active at first, its spring pushing with k · 0.5 mm; solved
        // leaving at 0.2 m/s it ends 1 mm outside: released, where the assembly's linearised
        // penalty held it (pulling −k · 1 mm: the glue that held sliding cloth).
        let (x0, v0, c) = setup(1e-3, 0.05);
        let fixed_v = [Vec3::zeros()];
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        let mut s = Speculative::new(&[c], &frame, false);
        assert_eq!(s.counts(), (1, 1));
        let t = s.terms(&frame)[0];
        assert!((t.rhs[0] - Vec3::new(0.0, 0.0, 0.005)).norm() < 1e-12, "{:?}", t.rhs[0]);
        assert_eq!(s.update(&frame, &[Vec3::new(0.0, 0.0, 0.2)], true), Change::Modes);
        assert_eq!(s.counts(), (0, 1));
        assert!(s.terms(&frame).is_empty());
        // Sides already parting fast (0.3 m/s: 3 mm a step, beyond half the thickness): the
        // spring launched them, and the contact is held for the step; so is every contact
        // inside at the start while the separation stage runs.
        for (v, hold) in [(0.3, false), (0.0, true)] {
            let (x0, v0, c) = setup(1e-3, v);
            let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
            let mut s = Speculative::new(&[c], &frame, hold);
            assert_eq!(s.update(&frame, &[Vec3::new(0.0, 0.0, 0.2)], true), Change::None, "v = {v}, hold {hold}");
            assert_eq!(s.counts(), (1, 1));
        }
        // Resting inside (no motion): stays active and pushes with k · 1 mm.
        let (x0, v0, c) = setup(1e-3, 0.0);
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        let mut s = Speculative::new(&[c], &frame, false);
        assert_eq!(s.update(&frame, &[Vec3::zeros()], true), Change::None);
        assert!((s.terms(&frame)[0].rhs[0] - Vec3::new(0.0, 0.0, 0.01)).norm() < 1e-12);
    }

    /// ARCSim's cubic law is linearised where both sides are at the start of the step. The
    /// fixed point ends at the origin, having risen 2 mm at 0.2 m/s; the node, still, is 1 mm
    /// above the point's start (inside the 2 mm thickness by 1 mm) and 3 mm inside at the end.
    #[test]
    fn a_cubic_contact_is_linearised_with_the_obstacle_at_the_start() {
        let (x0, v0, mut c) = setup(-1e-3, 0.0);
        c.law = Law::Cubic;
        let fixed_v = [Vec3::new(0.0, 0.0, 0.2)];
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        let s = Speculative::new(&[c], &frame, false);
        let t = s.terms(&frame)[0];
        // At depth 1 mm: E″ = (k/τ)·1 mm = 500 N/m, −E′ = ½(k/τ)(1 mm)² = 0.25 N; at the
        // predicted gap (−3 mm) the tangent gives 0.25 + 500 · 2 mm = 1.25 N, times h.
        // (Linearised at −3 mm it would be 2.25 N with E″ = 1,500: three times as stiff.)
        assert!((t.damper.unwrap()[(2, 2)] - 0.01 * 0.01 * 500.0).abs() < 1e-12, "{:?}", t.damper);
        assert!((t.rhs[0] - Vec3::new(0.0, 0.0, 0.0125)).norm() < 1e-12, "{:?}", t.rhs[0]);
        // The tangent agrees with the law: force and stiffness at the start gap.
        let (_, f, k) = c.penalty(-1e-3);
        assert!((f - 0.25).abs() < 1e-12 && (k - 500.0).abs() < 1e-9);
    }
}
