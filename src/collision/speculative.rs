//! Speculative repulsion contacts: an active set inside the implicit step.
//!
//! The repulsion penalty E = ½ k g², g < 0 (`proximity.rs`; Harmon et al. 2008, Narain et al.
//! 2012 §6) enters the backward-Euler system linearised at the start of the step, so a pair that
//! is outside the thickness at the start (g(x₀) ≥ 0) gets no force, however fast it closes. Cloth
//! moving faster than the thickness per step then ends deep inside it, and the next step's
//! penalty releases ½ k g² that no work paid for (a light fabric falling at 2 m/s onto a ball
//! gains a quarter of its energy this way).
//!
//! Backward Euler proper takes the force at the end of the step, −k min(0, g(x₁)) ∂g: piecewise
//! linear in the unknown velocities. Proximity therefore also returns the pairs the start
//! velocities carry within the thickness during the step (`CollisionWorld::proximity`), and this
//! module solves the complementarity by an active set over them:
//!
//! - an **active** contact adds its spring −k g(x) ∂g, linear in x (g is linear with the normal
//!   and weights frozen), to the system: matrix h² k (w wᵀ) ⊗ (n nᵀ), right-hand side
//!   h wᵢ (−k g(x₀ + h v₀) n), as the assembly adds a contact that starts inside;
//! - after each solve a contact is active exactly when its gap at the solved end positions is
//!   negative; a change switches it (the matrix changes: a refactorisation, within the friction
//!   iteration's budget, `sim::step`).
//!
//! First guess: active when the start velocities end inside, g(x₀ + h v₀) < 0. At a converged
//! set every active contact ends inside (its spring pushes, as the one-sided penalty would) and
//! every inactive one outside (no force, as the penalty gives none), so the step is backward Euler
//! with the one-sided penalty at the end positions. An active contact whose solved motion stops
//! short of the thickness would otherwise be a spring that pulls the cloth in.

use super::friction::{Change, FrictionFrame, FrictionTerm};
use super::proximity::Contact;
use crate::math::{Real, Vec3};

/// One contact that starts outside the thickness.
#[derive(Clone, Copy, Debug)]
struct Item {
    contact: Contact,
    active: bool,
}

/// The step's speculative contacts and which of them are active.
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

impl Speculative {
    /// The contacts of `contacts` outside the thickness at the start of the step, active when
    /// the start velocities carry them inside.
    pub fn new(contacts: &[Contact], frame: &FrictionFrame) -> Speculative {
        let rest = vec![Vec3::zeros(); frame.x0.len()];
        let items = contacts
            .iter()
            .filter(|c| gap(frame, c, &rest) >= 0.0)
            .map(|&contact| Item { contact, active: gap(frame, &contact, frame.v0) < 0.0 })
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
                let force = -c.stiffness * gap(frame, c, frame.v0) * c.n;
                let damper = (h * h * c.stiffness) * (c.n * c.n.transpose());
                FrictionTerm { nodes: c.nodes, w: c.w, rhs: c.w.map(|w| h * w * force), damper: Some(damper) }
            })
            .collect()
    }

    /// Re-evaluates which contacts end inside at the solved velocities `v`; switches them when
    /// `apply` (a change of the matrix), otherwise counts them in `pending`.
    pub fn update(&mut self, frame: &FrictionFrame, v: &[Vec3], apply: bool) -> Change {
        let verdicts: Vec<bool> = self.items.iter().map(|it| gap(frame, &it.contact, v) < 0.0).collect();
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
        let c =
            Contact { nodes: [0, 1, 0, 0], w: [1.0, -1.0, 0.0, 0.0], n: Vec3::z(), thickness: 2e-3, stiffness: 1000.0 };
        ([Vec3::new(0.0, 0.0, height)], [Vec3::new(0.0, 0.0, v)], c)
    }

    #[test]
    fn a_pair_closing_within_the_step_starts_active_and_one_stopping_short_is_switched_off() {
        // 3 mm up, falling at 0.2 m/s, h = 0.01: predicted 1 mm, inside the 2 mm thickness.
        let (x0, v0, c) = setup(3e-3, -0.2);
        let fixed_v = [Vec3::zeros()];
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        let mut s = Speculative::new(&[c], &frame);
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
    fn contacts_inside_at_the_start_are_left_to_the_assembly() {
        let (x0, v0, c) = setup(1e-3, 0.0);
        let fixed_v = [Vec3::zeros()];
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        assert!(Speculative::new(&[c], &frame).is_empty());
    }
}
