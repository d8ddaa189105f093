//! Measured fabric files (Wang, Ramamoorthi & O'Brien 2011, in ARCSim's JSON layout: `density`,
//! 6 × 4 `stretching`, 3 × 5 `bending`, `//` comments allowed) and the `material: {"arcsim": …}`
//! form of a scene.

use std::path::Path;
use std::sync::Arc;

use serde::Deserialize;

use super::spec::MaterialSpec;
use crate::error::InputError;
use crate::forces::data_driven::{FoldSign, Geometric, MeasuredData, MeasuredMaterial};
use crate::forces::material::Material;
use crate::forces::membrane::MembraneStiffness;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeasuredFile {
    density: f64,
    stretching: [[f64; 4]; 6],
    bending: [[f64; 5]; 3],
}

/// Reads a measured material file.
pub fn read_measured(path: &Path) -> Result<MeasuredData, InputError> {
    let err = |location: Option<String>, msg: String| InputError { file: path.to_path_buf(), location, msg };
    let text = std::fs::read_to_string(path).map_err(|e| err(None, format!("cannot read material file: {e}")))?;
    let text = super::arcsim::strip_comments(&text);
    let de = &mut serde_json::Deserializer::from_str(&text);
    let f: MeasuredFile = serde_path_to_error::deserialize(de).map_err(|e| {
        let inner = e.inner();
        let loc =
            if inner.is_syntax() || inner.is_eof() { format!("line {}", inner.line()) } else { e.path().to_string() };
        err(Some(loc), inner.to_string())
    })?;
    let all = std::iter::once(f.density)
        .chain(f.stretching.iter().flatten().copied())
        .chain(f.bending.iter().flatten().copied());
    if let Some(bad) = all.clone().find(|v| !v.is_finite()) {
        return Err(err(None, format!("expected finite numbers, got {bad}")));
    }
    if !(f.density > 0.0) {
        return Err(err(
            Some("density".into()),
            format!("expected a positive areal density (kg/m²), got {}", f.density),
        ));
    }
    Ok(MeasuredData { density: f.density, stretching: f.stretching, bending: f.bending })
}

/// The fabric of a `material` block with `arcsim` set; `data` is the file it names. Errors are
/// `(field, what was expected)` as for `material::resolve`.
pub(super) fn resolve_measured(spec: &MaterialSpec, data: &MeasuredData) -> Result<Material, (&'static str, String)> {
    let conflicting = [
        ("preset", spec.preset.is_some()),
        ("youngs_modulus", spec.youngs_modulus.is_some()),
        ("poisson_ratio", spec.poisson_ratio.is_some()),
        ("thickness", spec.thickness.is_some()),
        ("warp", spec.warp.is_some()),
        ("weft", spec.weft.is_some()),
        ("shear", spec.shear.is_some()),
        ("coupling", spec.coupling.is_some()),
        ("bending", spec.bending.is_some()),
    ];
    if let Some((field, _)) = conflicting.iter().find(|(_, set)| *set) {
        return Err((field, "no stiffness or preset fields together with \"arcsim\" (use the multipliers)".into()));
    }
    let positive = |field: &'static str, v: Option<f64>| match v {
        None => Ok(1.0),
        Some(x) if x > 0.0 && x.is_finite() => Ok(x),
        Some(x) => Err((field, format!("a positive number, got {x}"))),
    };
    let thicken = positive("thicken", spec.thicken)?;
    let density = match spec.density {
        Some(d) if d > 0.0 && d.is_finite() => d,
        Some(d) => return Err(("density", format!("a positive number, got {d}"))),
        None => data.density,
    } * positive("density_mult", spec.density_mult)?
        * thicken;
    let stretching = positive("stretching_mult", spec.stretching_mult)? * thicken;
    let bending = positive("bending_mult", spec.bending_mult)? * thicken;
    let damping = match spec.damping {
        None => 0.0,
        Some(d) if d >= 0.0 && d.is_finite() => d,
        Some(d) => return Err(("damping", format!("a number ≥ 0, got {d}"))),
    };
    let mut measured = MeasuredMaterial::new(data, stretching, bending);
    measured.fold = match spec.bending_curvature.as_deref() {
        None | Some("absolute") => FoldSign::Absolute,
        Some("signed") => FoldSign::Signed,
        Some(other) => return Err(("bending_curvature", format!("\"absolute\" or \"signed\", got \"{other}\""))),
    };
    measured.geometric = match spec.geometric_stiffness.as_deref() {
        None | Some("stress") => Geometric::Stress,
        Some("arcsim") => Geometric::Arcsim,
        Some(other) => return Err(("geometric_stiffness", format!("\"stress\" or \"arcsim\", got \"{other}\""))),
    };
    // The linear fields describe the small-strain slope, for anything that wants a summary.
    let k = measured.stretching.stiffness(0.0, 0.0, 0.0).0;
    Ok(Material {
        density,
        membrane: MembraneStiffness { k11: k[0], k12: k[1], k22: k[2], k33: 0.5 * k[3] },
        bending: measured.bending[0][0] / 12.0,
        damping,
        measured: Some(Arc::new(measured)),
        plasticity: super::material::plasticity(spec)?,
    })
}
