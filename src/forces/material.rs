//! A fabric: its parameters in SI units and the dispatch to the membrane and bending kernels
//! (linear orthotropic, or measured after Wang et al. 2011).

use std::sync::Arc;

use super::bending::{bending, bending_energy};
use super::data_driven::{
    measured_bending, measured_bending_energy, measured_membrane_energy, measured_membrane_with, MeasuredMaterial,
};
use super::membrane::{membrane, membrane_energy, MembraneRest, MembraneStiffness};
use super::plasticity::Plasticity;
use super::{Hinge, Projection};
use crate::math::{Mat12, Mat2, Mat9, Real, Vec12, Vec3, Vec9};

/// A fabric, in SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Areal density (kg/m²).
    pub density: Real,
    pub membrane: MembraneStiffness,
    /// Bending stiffness (N·m).
    pub bending: Real,
    /// Stiffness-proportional damping coefficient α (s): f_d = −α K v.
    pub damping: Real,
    /// Measured stretching and bending (Wang et al. 2011); when present it replaces `membrane`
    /// and `bending`.
    pub measured: Option<Arc<MeasuredMaterial>>,
    /// Bending plasticity and damage (Narain et al. 2013); `None`: elastic.
    pub plasticity: Option<Plasticity>,
}

impl Material {
    /// The membrane kernel of this fabric for one face, weakened by its damage.
    #[inline]
    pub fn stretch(&self, x: &[Vec3; 3], rest: &MembraneRest, proj: Projection) -> (Real, Vec9, Mat9) {
        slack_applied(rest, |rest| {
            let out = match &self.measured {
                Some(m) => measured_membrane_with(x, rest, &m.stretching, proj, m.geometric),
                None => membrane(x, rest, &self.membrane, proj),
            };
            weaken(out, rest.weakened)
        })
    }

    /// `stretch`'s energy alone, bit for bit (issue 17 item 3: the fault checks and the pop
    /// filter's line search evaluate energies only, and the derivatives were half their cost).
    pub fn stretch_energy(&self, x: &[Vec3; 3], rest: &MembraneRest) -> Real {
        slack_applied(rest, |rest| {
            let e = match &self.measured {
                Some(m) => measured_membrane_energy(x, rest, &m.stretching),
                None => membrane_energy(x, rest, &self.membrane),
            };
            weaken_energy(e, rest.weakened)
        })
    }

    /// The bending kernel of this fabric for one hinge, weakened by its damage.
    #[inline]
    pub fn bend(&self, x: &[Vec3; 4], hinge: &Hinge, proj: Projection) -> (Real, Vec12, Mat12) {
        let out = match &self.measured {
            Some(m) => measured_bending(x, &hinge.rest, &hinge.measured, &m.bending, m.fold, proj),
            None => bending(x, &hinge.rest, self.bending, proj),
        };
        weaken(out, hinge.weakened)
    }

    /// `bend`'s energy alone, bit for bit.
    pub fn bend_energy(&self, x: &[Vec3; 4], hinge: &Hinge) -> Real {
        let e = match &self.measured {
            Some(m) => measured_bending_energy(x, &hinge.rest, &hinge.measured, &m.bending, m.fold),
            None => bending_energy(x, &hinge.rest, self.bending),
        };
        weaken_energy(e, hinge.weakened)
    }

    /// The weakening w of plastic damage (0 for an elastic fabric).
    pub fn weakening(&self) -> Real {
        self.plasticity.map_or(0.0, |p| p.weakening)
    }
}

/// `kernel` on the rest data with its slack applied (`MembraneRest::slackened`; the rest data
/// itself where there is none).
#[inline]
fn slack_applied<R>(rest: &MembraneRest, kernel: impl FnOnce(&MembraneRest) -> R) -> R {
    match rest.slack == Mat2::identity() {
        true => kernel(rest),
        false => kernel(&rest.slackened()),
    }
}

/// A kernel's output with its stiffness divided by 1 + w·d (`plasticity`): energy, gradient and
/// Hessian are all linear in the stiffness.
#[inline]
fn weaken<G: std::ops::MulAssign<Real>, H: std::ops::MulAssign<Real>>(
    (e, mut g, mut h): (Real, G, H),
    factor: Real,
) -> (Real, G, H) {
    if factor != 1.0 {
        g *= factor;
        h *= factor;
    }
    (weaken_energy(e, factor), g, h)
}

/// `weaken`'s energy.
fn weaken_energy(e: Real, factor: Real) -> Real {
    match factor != 1.0 {
        true => e * factor,
        false => e,
    }
}
