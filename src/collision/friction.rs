//! Coulomb friction inside the implicit step: each repulsion contact either sticks or slides,
//! and the backward-Euler system is re-solved until every contact's mode agrees with Coulomb's
//! law at the solved velocities (an active-set iteration on the stick/slip complementarity).
//!
//! A contact acts on the generalised relative velocity v_rel = Σ wᵢ vᵢ of its four participants
//! (node–face and edge–edge, cloth–obstacle and cloth–cloth alike; obstacle points move with the
//! obstacle's velocity over the step), tangentially: T = I − n nᵀ, v_t = T v_rel. Its normal
//! force is the repulsion penalty's at the solved positions, f_n = k · max(0, −g(x₀ + h v₁))
//! (`proximity.rs`, Harmon et al. 2008; Narain et al. 2012 §6), and the Coulomb bound is
//! |f_t| ≤ μ f_n.
//!
//! - **Stick**: a stiff tangential damper f = −c T v_rel, node i taking wᵢ f, with
//!   c = `STICK_STIFFNESS` · m_eff / h (m_eff = 1 / Σ wᵢ²/mᵢ over the free nodes). It enters the
//!   system matrix like any damping force (A += h c (w wᵀ) ⊗ T, positive semi-definite), so a
//!   stuck node drags its neighbours implicitly instead of being stopped behind their backs. The
//!   residual slip is 1/`STICK_STIFFNESS` of what one step of the tangential load would give.
//! - **Slide**: the kinetic force −μ f_n t̂ along the direction t̂ of the relative motion, with
//!   its Jacobian across the motion (`Slide`) capped at m_eff / h: the across-motion damping can
//!   at most stop the contact's sideways velocity within the step, as inertia would. (Capped at
//!   the stick damper instead, a contact released from sticking, whose residual slip is tiny,
//!   stayed stuck across its sliding direction: on ARCSim's sphere scene that was half of the
//!   friction force on the sheet, twice Coulomb's bound in all.)
//!
//! After each solve: a sticking contact whose damper force exceeds μ f_n slides; a sliding one
//! sticks when its relative motion reversed against its force (the force would stop it within
//! the step) or is so slow that the stick damper would hold it within μ f_n; a sliding one whose
//! direction or normal force moved updates its force. A change of modes changes the matrix (a
//! refactorisation); a change of sliding forces only the right-hand side (a back-substitution
//! with the same factor). Refactorisations are budgeted (`Budget`): the first may apply any
//! change; up to `MAX_RELEASES` more only release sticks beyond the bound, because a stick held
//! in the matrix applies whatever force its damper takes, while a slide that should stick still
//! applies a force within the bound and can wait for the next step. First guess: the contacts that stuck at the previous step stick (kept
//! in the state, so a resumed run takes the same path), the others slide along their start
//! relative velocity; with no previous step (after a load or a remesh), a contact sticks when
//! μ f_n at the start could stop its start velocity within the step.
//!
//! Why not ARCSim's friction (`IneqCon::friction`, a lagged viscous force with coefficient
//! min(μ f_n / |v_t|, m_eff / h)): its cap lets a sheet on a slope below the friction angle creep
//! at h·g·sin θ, and its coefficient, lagged from the start velocity, can brake far beyond μ f_n
//! when sliding starts. Why not the velocity filter after the solve (Bridson et al. 2002 §7.2,
//! viewcloth before this): it stops contact nodes while their neighbours move on, creating
//! elastic energy that the step's energy check rejected (45% of the steps of the uniform
//! `sheet_on_sphere` reference), and it takes its normal impulse from the explicit penalty force.

use super::proximity::Law;
use crate::math::{Mat3, Real, Vec3};

/// κ in the stick damper c = κ m_eff / h.
pub const STICK_STIFFNESS: Real = 1e3;
/// Solves per step at most (the first included); the last one is taken even if some contact
/// still disagrees with its mode (counted).
pub const MAX_SOLVES: usize = 6;
/// Refactorisations per step for mode changes at most. Beyond them modes stay as they are
/// within the step (the sliding forces still follow) and the changes wait for the next step's
/// first guess: with thousands of contacts some contact changes at every solve, and each
/// refactorisation costs as much as the step's first.
pub const MAX_REFACTORS: usize = 1;
/// Mode changes refactorise only when at least this fraction of the contacts wants one, or
/// some sticking contact must be released; fewer wait for the next step. With thousands of
/// contacts a handful change at every solve.
pub const MIN_CHANGES: Real = 0.01;
/// Further refactorisations per step that only release sticking contacts beyond the bound (and
/// switch speculative contacts, `collision::speculative`). Measured on ARCSim's sphere scene at
/// frame 60: with none, the deferred sticks applied 44–53 N beyond their 53 N bound.
pub const MAX_RELEASES: usize = 2;
/// A sliding force that moved (in direction or size) by more than this fraction of its size is
/// updated: Coulomb's law holds to 2% of the friction force (about 1° in direction).
const SLIDE_TOLERANCE: Real = 0.02;
/// From the second update of a step on, a contact changes mode only when it is clearly on the
/// other side: a sticking one when its force exceeds μ f_n by this fraction, a sliding one when
/// its relative motion reversed by this fraction of what its force changes in a step. Coupled
/// contacts near the Coulomb bound (two cloth layers touching at several contacts) otherwise
/// trade modes from solve to solve without settling.
const HYSTERESIS: Real = 0.1;

/// Whether a contact sticks or slides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    Stick,
    Slide(Slide),
}

/// Kinetic friction −`force` t̂, t̂ the direction of the tangential relative velocity, linearised
/// about the last iterate's v_t,k: f(v) ≈ −force t̂ₖ − P (v_t − v_t,k) with P = (force / |v_t|)
/// (T − t̂ t̂ᵀ), the Jacobian of −force v_t/|v_t| across the motion, taken when the contact
/// started sliding and kept while it slides (so only the right-hand side changes as t̂ₖ
/// follows the iterates: a chord Newton iteration on the direction). Without P the direction
/// of a slowly sliding contact (friction almost balancing the load) converges only linearly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slide {
    pub t: Vec3,
    pub force: Real,
    vt: Vec3,
    p: Mat3,
}

/// One contact as friction sees it.
#[derive(Clone, Copy, Debug)]
pub struct FrictionContact {
    /// Participants: cloth nodes below the cloth node count, fixed (obstacle) points above.
    pub nodes: [usize; 4],
    pub w: [Real; 4],
    pub n: Vec3,
    pub thickness: Real,
    /// Repulsion stiffness k and law (`proximity::Law`).
    pub stiffness: Real,
    pub law: Law,
    pub mu: Real,
    /// 1 / Σ wᵢ²/mᵢ over the free nodes.
    m_eff: Real,
    pub mode: Mode,
    /// Whether Coulomb's law, at the last update, says it sticks.
    next_stick: bool,
}

/// The state friction is evaluated against: start positions and velocities of the cloth,
/// inverse masses (0 for pinned nodes), fixed points at the end of the step and their velocities.
pub struct FrictionFrame<'a> {
    pub h: Real,
    pub x0: &'a [Vec3],
    pub v0: &'a [Vec3],
    pub inv_mass: &'a [Real],
    pub fixed_x: &'a [Vec3],
    pub fixed_v: &'a [Vec3],
}

#[cfg(test)]
impl<'a> FrictionFrame<'a> {
    /// A unit-mass cloth node against one fixed point at the origin moving at `fixed_v[0]`,
    /// h = 0.01 s: the unit tests' frame.
    pub(crate) fn one_node(x0: &'a [Vec3], v0: &'a [Vec3], fixed_v: &'a [Vec3]) -> Self {
        const ORIGIN: &[Vec3] = &[Vec3::new(0.0, 0.0, 0.0)];
        FrictionFrame { h: 0.01, x0, v0, inv_mass: &[1.0], fixed_x: ORIGIN, fixed_v }
    }
}

impl FrictionFrame<'_> {
    /// Position and velocity of participant `i` with cloth velocities `v`.
    pub(crate) fn point(&self, i: usize, v: &[Vec3]) -> (Vec3, Vec3) {
        let n = self.x0.len();
        if i < n {
            (self.x0[i] + self.h * v[i], v[i])
        } else {
            (self.fixed_x[i - n], self.fixed_v[i - n])
        }
    }

    /// Normal force −E′(g) (k·max(0, −g) for the quadratic law) and tangential relative velocity
    /// of `c` at cloth velocities `v` (positions x₀ + h v).
    fn kinematics(&self, c: &FrictionContact, v: &[Vec3]) -> (Real, Vec3) {
        let (mut sep, mut vrel) = (Vec3::zeros(), Vec3::zeros());
        for j in 0..4 {
            let (x, u) = self.point(c.nodes[j], v);
            sep += c.w[j] * x;
            vrel += c.w[j] * u;
        }
        let gap = c.n.dot(&sep) - c.thickness;
        (c.law.eval(c.stiffness, c.thickness, gap).1, vrel - c.n * c.n.dot(&vrel))
    }

    /// Stick damper coefficient c of a contact.
    fn stick_coefficient(&self, c: &FrictionContact) -> Real {
        STICK_STIFFNESS * c.m_eff / self.h
    }

    /// A sliding mode of `c` with tangential relative velocity `vt` and force `force`, its
    /// Jacobian P taken now (its coefficient at most m_eff / h).
    fn slide(&self, c: &FrictionContact, vt: Vec3, force: Real) -> Slide {
        let speed = vt.norm();
        let t = if speed > 0.0 { vt / speed } else { Vec3::zeros() };
        let p = match speed > 0.0 {
            true => {
                let across = Mat3::identity() - c.n * c.n.transpose() - t * t.transpose();
                (force / speed).min(c.m_eff / self.h) * across
            }
            false => Mat3::zeros(),
        };
        Slide { t, force, vt, p }
    }

    /// The friction force of `c` in its mode, as the solve applies it, at cloth velocities `v`.
    fn force(&self, c: &FrictionContact, v: &[Vec3]) -> Vec3 {
        let (_, vt) = self.kinematics(c, v);
        match c.mode {
            Mode::Stick => -self.stick_coefficient(c) * vt,
            Mode::Slide(s) => -s.force * s.t - s.p * (vt - s.vt),
        }
    }
}

/// A friction term as the implicit system takes it: node i gets the right-hand side `rhs[i]`
/// (h times the force at the start velocities) and, for a sticking contact, the matrix blocks
/// wₐ w_b · `damper` between its cloth nodes.
#[derive(Clone, Copy, Debug)]
pub struct FrictionTerm {
    pub nodes: [usize; 4],
    pub w: [Real; 4],
    pub rhs: [Vec3; 4],
    /// h c T for a sticking contact.
    pub damper: Option<Mat3>,
}

/// Which mode changes an update may apply (each applied change costs a refactorisation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Budget {
    /// Any: stick → slide and slide → stick.
    All,
    /// Only stick → slide: a sticking contact whose damper exceeds μ f_n applies a force beyond
    /// Coulomb's bound for as long as it stays in the matrix, so releasing it is worth a
    /// refactorisation; a slide that should stick still applies a force within the bound and
    /// can wait for the next step.
    Release,
    /// None: changes wait for the next step.
    None,
}

/// What a friction update changed (ordered: a matrix change includes a right-hand side change).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Change {
    /// Every contact agrees with its mode: done.
    None,
    /// Only sliding forces moved: the same factor serves.
    Rhs,
    /// Some contact changed between stick and slide: the matrix changed.
    Modes,
}

/// The contacts of one step with their modes.
pub struct Friction {
    pub contacts: Vec<FrictionContact>,
    /// Contacts whose mode change the last update did not apply.
    pub pending: usize,
}

impl Friction {
    /// Friction contacts from the step's repulsion contacts; contacts with μ = 0 or without a
    /// free cloth node are left out. Modes start at the first guess (module doc) from `stuck`,
    /// the sorted participants of the contacts that stuck at the previous step.
    ///
    /// The system's pattern couples every contact's cloth nodes (the step analyses them before it
    /// solves, `Workspace::pattern_for_step`), so a sticking contact's damper enters whole.
    pub fn new(
        contacts: impl Iterator<Item = FrictionContact>,
        frame: &FrictionFrame,
        stuck: &[[usize; 4]],
    ) -> Friction {
        let n = frame.x0.len();
        let contacts = contacts
            .filter(|c| c.mu > 0.0)
            .filter_map(|mut c| {
                let w2m: Real =
                    (0..4).filter(|&j| c.nodes[j] < n).map(|j| c.w[j] * c.w[j] * frame.inv_mass[c.nodes[j]]).sum();
                if w2m <= 0.0 {
                    return None;
                }
                c.m_eff = 1.0 / w2m;
                let (fn0, vt) = frame.kinematics(&c, frame.v0);
                let speed = vt.norm();
                // Stuck at the previous step, or slow enough for μ f_n to stop within the step
                // (a contact new at this step: sliding at a force that stops it several times
                // over would reverse it).
                let guess = stuck.binary_search(&c.nodes).is_ok() || speed <= c.mu * fn0 * frame.h / c.m_eff;
                c.mode = match guess {
                    true => Mode::Stick,
                    false => Mode::Slide(frame.slide(&c, vt, c.mu * fn0)),
                };
                c.next_stick = c.mode == Mode::Stick;
                Some(c)
            })
            .collect::<Vec<FrictionContact>>();
        Friction { contacts, pending: 0 }
    }

    pub fn is_empty(&self) -> bool {
        self.contacts.is_empty()
    }

    /// The system terms of the current modes.
    pub fn terms(&self, frame: &FrictionFrame) -> Vec<FrictionTerm> {
        self.contacts
            .iter()
            .map(|c| {
                let h = frame.h;
                let damper = match c.mode {
                    Mode::Stick => Some(h * frame.stick_coefficient(c) * (Mat3::identity() - c.n * c.n.transpose())),
                    Mode::Slide(s) if s.p != Mat3::zeros() => Some(h * s.p),
                    Mode::Slide(_) => None,
                };
                // The right-hand side takes the force at the start velocities (its linear part
                // in Δv is the damper).
                let force = frame.force(c, frame.v0);
                FrictionTerm { nodes: c.nodes, w: c.w, rhs: c.w.map(|w| h * w * force), damper }
            })
            .collect()
    }

    /// Re-evaluates every contact's mode at the solved velocities `v` (module doc); `first` for
    /// the first update of a step (no hysteresis). Mode changes are applied only with `modes`
    /// and when at least `MIN_CHANGES` of the contacts want one; otherwise the matrix stays,
    /// they are counted in `pending` and become the next step's first guess (`stuck`).
    pub fn update(&mut self, frame: &FrictionFrame, v: &[Vec3], first: bool, modes: Budget) -> Change {
        let slack = if first { 0.0 } else { HYSTERESIS };
        // Coulomb's verdict per contact: its state at `v` and whether it should stick.
        let verdicts: Vec<(Real, Vec3, bool)> = self
            .contacts
            .iter()
            .map(|c| {
                let (fn1, vt) = frame.kinematics(c, v);
                let (bound, speed) = (c.mu * fn1, vt.norm());
                let stick = match c.mode {
                    Mode::Stick => frame.stick_coefficient(c) * speed <= bound * (1.0 + slack.max(SLIDE_TOLERANCE)),
                    Mode::Slide(s) => {
                        // Sticks when reversed by more than the slack, by no more than the
                        // friction force alone changes it in a step (friction would have stopped
                        // it), or when sliding so slowly that the stick damper would hold it
                        // within the bound.
                        let (along, reach) = (vt.dot(&s.t), s.force * frame.h / c.m_eff);
                        let reversed = along <= -slack * reach && -along <= reach;
                        let creeping = frame.stick_coefficient(c) * speed < bound * (1.0 - slack);
                        bound > 0.0 && (reversed || creeping)
                    }
                };
                (bound, vt, stick)
            })
            .collect();
        let wanted = self.contacts.iter().zip(&verdicts).filter(|(c, v)| (c.mode == Mode::Stick) != v.2).count();
        let releases = self.contacts.iter().zip(&verdicts).filter(|(c, v)| c.mode == Mode::Stick && !v.2).count();
        let enough = |k: usize| k > 0 && k as Real >= MIN_CHANGES * self.contacts.len() as Real;
        let (apply, release) = match modes {
            Budget::All => (enough(wanted) || releases > 0, false),
            Budget::Release => (false, releases > 0),
            Budget::None => (false, false),
        };
        self.pending = if apply {
            0
        } else if release {
            wanted - releases
        } else {
            wanted
        };
        let mut change = if apply || release { Change::Modes } else { Change::None };
        for (c, &(bound, vt, stick)) in self.contacts.iter_mut().zip(&verdicts) {
            c.next_stick = stick;
            let speed = vt.norm();
            match c.mode {
                Mode::Stick if !stick && (apply || release) => c.mode = Mode::Slide(frame.slide(c, vt, bound)),
                Mode::Stick => {}
                Mode::Slide(_) if stick && apply => c.mode = Mode::Stick,
                Mode::Slide(s) => {
                    // The force follows when it moved by more than the tolerance of its size.
                    // It is at most what stops the relative motion within the step (ARCSim's
                    // cap, m_eff |v_t| / h): more would reverse it, and between re-solves with
                    // one factor a force that grows with the depth it drives diverges.
                    // "The relative motion" is the one friction meets: the solved velocity with
                    // this force's own effect in the step, −f t̂ h / m_eff, taken back. Capping at
                    // the solved speed alone would cap a loaded contact at its load (a sheet on
                    // an incline then slides at one step's load, g_t h, for ever, its friction
                    // exactly balancing gravity instead of decelerating it to a stop).
                    let t1 = if speed > 0.0 { vt / speed } else { s.t };
                    let met = (vt + s.t * (s.force * frame.h / c.m_eff)).norm();
                    let force = bound.min(c.m_eff * met / frame.h);
                    let delta = (force * t1 - s.force * s.t).norm();
                    if delta > SLIDE_TOLERANCE * force.max(s.force) {
                        c.mode = Mode::Slide(Slide { t: t1, force, vt, p: s.p });
                        if change == Change::None {
                            change = Change::Rhs;
                        }
                    }
                }
            }
        }
        change
    }

    /// The work friction may do on the cloth over the step: h Σ max(0, −f · o) over the
    /// contacts, o = Σ wⱼ vⱼ over a contact's obstacle points. Friction dissipates relative
    /// motion (f · v_rel ≤ 0), so the power it puts into the cloth, f · (v_rel − o), is at most
    /// the drag −f · o of a moving obstacle; on a static obstacle or between cloth layers it is
    /// none. A step whose friction did more work than this (a sliding force that overshot and
    /// now pushes along the relative motion) fails the energy check instead of being excused.
    pub fn drag_work(&self, frame: &FrictionFrame, v: &[Vec3]) -> Real {
        let n = frame.x0.len();
        self.contacts
            .iter()
            .map(|c| {
                let o: Vec3 = (0..4).filter(|&j| c.nodes[j] >= n).map(|j| c.w[j] * frame.fixed_v[c.nodes[j] - n]).sum();
                frame.h * (-frame.force(c, v).dot(&o)).max(0.0)
            })
            .sum()
    }

    /// The sticking contacts' participants, sorted (the next step's first guess).
    pub fn stuck(&self) -> Vec<[usize; 4]> {
        let mut stuck: Vec<[usize; 4]> = self.contacts.iter().filter(|c| c.next_stick).map(|c| c.nodes).collect();
        stuck.sort_unstable();
        stuck.dedup();
        stuck
    }

    /// Contacts sticking and sliding.
    pub fn counts(&self) -> (usize, usize) {
        let stick = self.contacts.iter().filter(|c| c.mode == Mode::Stick).count();
        (stick, self.contacts.len() - stick)
    }
}

impl FrictionContact {
    /// A contact with its participants, weights, normal, gap offset, stiffness and μ; its mode
    /// is set by `Friction::new`.
    pub fn new(nodes: [usize; 4], w: [Real; 4], n: Vec3, thickness: Real, stiffness: Real, mu: Real) -> Self {
        FrictionContact {
            nodes,
            w,
            n,
            thickness,
            stiffness,
            law: Law::Quadratic,
            mu,
            m_eff: 0.0,
            mode: Mode::Stick,
            next_stick: false,
        }
    }

    /// The same contact with penalty law `law`.
    pub fn with_law(self, law: Law) -> Self {
        FrictionContact { law, ..self }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Node 0 (mass 1) on a fixed point (index 1) with normal +z, `depth` inside a 2 mm
    /// thickness, stiffness 1000.
    fn one(mu: Real, v: Vec3, fixed_v: Vec3, depth: Real) -> (Friction, [Vec3; 1], [Vec3; 1]) {
        let x0 = [Vec3::new(0.0, 0.0, 2e-3 - depth)];
        let v0 = [v];
        let fixed_v = [fixed_v];
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        let c = FrictionContact::new([0, 1, 0, 0], [1.0, -1.0, 0.0, 0.0], Vec3::z(), 2e-3, 1000.0, mu);
        (Friction::new(std::iter::once(c), &frame, &[]), x0, v0)
    }

    #[test]
    fn lagged_guess_sticks_what_friction_can_stop_within_the_step() {
        // μ f_n h / m = 0.5 · 1000 · 1e-3 · 0.01 = 5e-3 m/s.
        let (f, _, _) = one(0.5, Vec3::new(4e-3, 0.0, 0.0), Vec3::zeros(), 1e-3);
        assert_eq!(f.contacts[0].mode, Mode::Stick);
        let (f, _, _) = one(0.5, Vec3::new(6e-3, 0.0, 0.0), Vec3::zeros(), 1e-3);
        assert!(matches!(f.contacts[0].mode, Mode::Slide(s) if s.t == Vec3::x() && s.force == 0.5));
        // Relative to a moving obstacle: same speed as the obstacle is at rest.
        let (f, _, _) = one(0.5, Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), 1e-3);
        assert_eq!(f.contacts[0].mode, Mode::Stick);
    }

    #[test]
    fn zero_friction_and_fixed_only_contacts_are_left_out() {
        let (f, _, _) = one(0.0, Vec3::zeros(), Vec3::zeros(), 1e-3);
        assert!(f.is_empty());
        let x0 = [Vec3::zeros()];
        let frame =
            FrictionFrame { h: 0.01, x0: &x0, v0: &x0, inv_mass: &[0.0], fixed_x: &[Vec3::zeros()], fixed_v: &x0 };
        let c = FrictionContact::new([0, 1, 0, 0], [1.0, -1.0, 0.0, 0.0], Vec3::z(), 2e-3, 1000.0, 0.5);
        assert!(Friction::new(std::iter::once(c), &frame, &[]).is_empty());
    }

    #[test]
    fn stick_term_is_a_tangential_damper_toward_the_obstacle_velocity() {
        let (f, x0, v0) = one(0.5, Vec3::new(1e-3, 0.0, 2e-3), Vec3::new(0.0, 1e-3, 0.0), 1e-3);
        let fixed_v = [Vec3::new(0.0, 1e-3, 0.0)];
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        let t = f.terms(&frame)[0];
        let c = STICK_STIFFNESS / 0.01;
        // h c T, and h · (−c T v_rel) with v_rel = (1e-3, −1e-3, 2e-3): no normal part.
        let d = t.damper.unwrap();
        assert!((d - 0.01 * c * Mat3::from_diagonal(&Vec3::new(1.0, 1.0, 0.0))).norm() < 1e-9);
        assert!((t.rhs[0] - 0.01 * -c * Vec3::new(1e-3, -1e-3, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn update_slides_a_stick_beyond_the_bound_and_sticks_a_reversed_slide() {
        let (mut f, x0, v0) = one(0.5, Vec3::new(1e-3, 0.0, 0.0), Vec3::zeros(), 1e-3);
        let fixed_v = [Vec3::zeros()];
        let frame = FrictionFrame::one_node(&x0, &v0, &fixed_v);
        assert_eq!(f.contacts[0].mode, Mode::Stick);
        // c = 1e5: a residual slip of 1e-6 m/s needs 0.1 N ≤ μ f_n = 0.5 (f_n at x₀ + h v).
        assert_eq!(f.update(&frame, &[Vec3::new(1e-6, 0.0, 0.0)], true, Budget::All), Change::None);
        // 1e-5 m/s needs 1 N > 0.5: slides along +x with 0.5 N.
        assert_eq!(f.update(&frame, &[Vec3::new(1e-5, 0.0, 0.0)], true, Budget::All), Change::Modes);
        assert!(matches!(f.contacts[0].mode, Mode::Slide(s) if s.t == Vec3::x() && s.force == 0.5));
        // Same direction and force: converged.
        assert_eq!(f.update(&frame, &[Vec3::new(2e-5, 0.0, 0.0)], true, Budget::All), Change::None);
        // Turned: the force follows (right-hand side only).
        assert_eq!(f.update(&frame, &[Vec3::new(2e-5, 2e-5, 0.0)], true, Budget::All), Change::Rhs);
        // Reversed against the force: sticks.
        assert_eq!(f.update(&frame, &[Vec3::new(-1e-5, -1e-5, 0.0)], true, Budget::All), Change::Modes);
        assert_eq!(f.contacts[0].mode, Mode::Stick);
    }

    #[test]
    fn friction_may_do_work_only_where_a_moving_obstacle_drags() {
        let x0 = [Vec3::new(0.0, 0.0, 1e-3)];
        let v = [Vec3::new(0.5, 0.0, 0.0)];
        for (fixed_v, positive) in [(Vec3::zeros(), false), (Vec3::new(1.0, 0.0, 0.0), true)] {
            let fixed_v = [fixed_v];
            let frame = FrictionFrame::one_node(&x0, &v, &fixed_v);
            let c = FrictionContact::new([0, 1, 0, 0], [1.0, -1.0, 0.0, 0.0], Vec3::z(), 2e-3, 1000.0, 0.5);
            let f = Friction::new(std::iter::once(c), &frame, &[]);
            assert_eq!(f.drag_work(&frame, &v) > 0.0, positive);
        }
    }
}
