//! Named fabric presets, and the resolution of a scene's material block into a `Material`.

use crate::forces::material::Material;
use crate::forces::membrane::MembraneStiffness;
use crate::forces::plasticity::Plasticity;
use crate::math::Real;

use super::spec::MaterialSpec;

/// Named presets. Areal densities are typical fabric weights (cotton shirting ≈ 150 g/m²,
/// 11 oz denim ≈ 390 g/m², silk crêpe ≈ 60 g/m², cotton jersey ≈ 180 g/m²). Membrane stiffnesses
/// are small-strain tensile slopes in N/m of the order measured by Wang, Ramamoorthi & O'Brien
/// (2011) for wovens and knits; bending stiffnesses are Kawabata (KES-FB2) bending rigidities
/// (0.02–0.5 gf·cm²/cm, 1 gf·cm²/cm = 9.81e-5 N·m) of the same fabric classes.
pub const PRESETS: &[(&str, Material)] = &[
    ("cotton", preset(0.15, 2000.0, 1500.0, 40.0, 1.0e-5)),
    ("denim", preset(0.39, 5000.0, 3500.0, 80.0, 5.0e-5)),
    ("silk", preset(0.06, 800.0, 700.0, 15.0, 2.0e-6)),
    ("jersey", preset(0.18, 150.0, 60.0, 20.0, 3.0e-6)),
];

/// The fabric used when a scene names none.
pub const DEFAULT_PRESET: &str = "cotton";

const fn preset(density: Real, warp: Real, weft: Real, shear: Real, bending: Real) -> Material {
    Material {
        density,
        membrane: MembraneStiffness { k11: warp, k12: 0.0, k22: weft, k33: shear },
        bending,
        damping: 1e-3,
        measured: None,
        plasticity: None,
    }
}

pub fn find_preset(name: &str) -> Option<&'static Material> {
    PRESETS.iter().find(|(n, _)| *n == name).map(|(_, m)| m)
}

/// Resolves a material block into a `Material`. Errors are `(field, what was expected)`.
pub fn resolve(spec: &MaterialSpec) -> Result<Material, (&'static str, String)> {
    let names = || PRESETS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ");
    let base_name = spec.preset.as_deref().unwrap_or(DEFAULT_PRESET);
    let mut m =
        find_preset(base_name).ok_or_else(|| ("preset", format!("one of {}, got \"{base_name}\"", names())))?.clone();
    let positive = |field: &'static str, v: Option<f64>| -> Result<Option<f64>, (&'static str, String)> {
        match v {
            Some(x) if !(x > 0.0 && x.is_finite()) => Err((field, format!("a positive number, got {x}"))),
            other => Ok(other),
        }
    };
    let non_negative = |field: &'static str, v: Option<f64>| -> Result<Option<f64>, (&'static str, String)> {
        match v {
            Some(x) if !(x >= 0.0 && x.is_finite()) => Err((field, format!("a number ≥ 0, got {x}"))),
            other => Ok(other),
        }
    };
    if let Some(d) = positive("density", spec.density)? {
        m.density = d;
    }
    if spec.bending_curvature.is_some() {
        return Err((
            "bending_curvature",
            "no bending_curvature without \"arcsim\" (it chooses how a measured bending table is read)".into(),
        ));
    }
    if spec.geometric_stiffness.is_some() {
        return Err((
            "geometric_stiffness",
            "no geometric_stiffness without \"arcsim\" (it chooses a measured material's Jacobian)".into(),
        ));
    }
    let iso = [spec.youngs_modulus, spec.poisson_ratio, spec.thickness];
    let ortho = [spec.warp, spec.weft, spec.shear, spec.coupling];
    if iso.iter().any(Option::is_some) {
        if ortho.iter().any(Option::is_some) {
            return Err((
                "youngs_modulus",
                "either youngs_modulus/poisson_ratio/thickness or warp/weft/shear, not both".into(),
            ));
        }
        let e = positive("youngs_modulus", spec.youngs_modulus)?
            .ok_or(("youngs_modulus", "a Young's modulus (Pa) with poisson_ratio and thickness".to_string()))?;
        let t = positive("thickness", spec.thickness)?
            .ok_or(("thickness", "a thickness (m) with youngs_modulus".to_string()))?;
        let nu = spec.poisson_ratio.unwrap_or(0.3);
        if !(0.0..0.5).contains(&nu) {
            return Err(("poisson_ratio", format!("a number in [0, 0.5), got {nu}")));
        }
        let k = e * t / (1.0 - nu * nu);
        m.membrane = MembraneStiffness { k11: k, k12: nu * k, k22: k, k33: e * t / (2.0 * (1.0 + nu)) };
    } else {
        if let Some(v) = positive("warp", spec.warp)? {
            m.membrane.k11 = v;
        }
        if let Some(v) = positive("weft", spec.weft)? {
            m.membrane.k22 = v;
        }
        if let Some(v) = positive("shear", spec.shear)? {
            m.membrane.k33 = v;
        }
        if let Some(v) = non_negative("coupling", spec.coupling)? {
            m.membrane.k12 = v;
        }
        let k = &m.membrane;
        if k.k12 * k.k12 >= k.k11 * k.k22 {
            return Err(("coupling", format!("coupling² < warp·weft (got coupling {})", k.k12)));
        }
    }
    if let Some(v) = non_negative("bending", spec.bending)? {
        m.bending = v;
    }
    if let Some(v) = non_negative("damping", spec.damping)? {
        m.damping = v;
    }
    if let Some(s) = positive("stretching_mult", spec.stretching_mult)? {
        let k = &mut m.membrane;
        (k.k11, k.k12, k.k22, k.k33) = (k.k11 * s, k.k12 * s, k.k22 * s, k.k33 * s);
    }
    if let Some(s) = positive("bending_mult", spec.bending_mult)? {
        m.bending *= s;
    }
    m.plasticity = plasticity(spec)?;
    Ok(m)
}

/// The plasticity of a material block (`forces::plasticity`): `yield_curv` (1/m) > 0, and
/// `weakening` ≥ 0 only with it (damage accumulates only where a face yields).
pub fn plasticity(spec: &MaterialSpec) -> Result<Option<Plasticity>, (&'static str, String)> {
    let weakening = match spec.weakening {
        None => 0.0,
        Some(w) if w >= 0.0 && w.is_finite() => w,
        Some(w) => return Err(("weakening", format!("a number ≥ 0, got {w}"))),
    };
    match spec.yield_curv {
        None if spec.weakening.is_some() => {
            Err(("weakening", "a yield_curv with it (damage comes from yielding)".into()))
        }
        None => Ok(None),
        Some(k) if k > 0.0 && k.is_finite() => Ok(Some(Plasticity { yield_curv: k, weakening })),
        Some(k) => Err(("yield_curv", format!("a positive curvature (1/m), got {k}"))),
    }
}
