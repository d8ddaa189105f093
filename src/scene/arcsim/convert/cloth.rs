//! Conversion of a conf's cloths: mesh, transform, velocity, material (measured data or
//! isotropic parameters, with ARCSim's multipliers) and remeshing parameters.

use std::path::PathBuf;

use serde_json::Value;

use super::{join, nums, obj, Conv, Magic, Origin, J};
use crate::scene::arcsim::Res;

impl Conv<'_> {
    /// One cloth's scene fields and its mesh file.
    pub(super) fn cloth(&mut self, v: &Value, c: usize, magic: &Magic) -> Res<(Vec<(String, J)>, PathBuf)> {
        let loc = format!("cloths[{c}]");
        let m = self.object(v, &loc)?;
        let known = ["mesh", "transform", "velocity", "materials", "remeshing"];
        self.check_keys(m, &loc, &known, &[("reference", "reference shapes are not supported")]);
        let rel = self.string(m.get("mesh").unwrap_or(&Value::Null), &join(&loc, "mesh"))?;
        let (full, mesh) = self.path(rel);
        let mut fields: Vec<(String, J)> = vec![("mesh".into(), J::Str(mesh))];
        if let Some(t) = m.get("transform") {
            fields.push(("transform".into(), self.transform(t, &join(&loc, "transform"))?));
        }
        if let Some(vel) = m.get("velocity") {
            fields.push(("velocity".into(), nums(&self.cloth_velocity(vel, &join(&loc, "velocity"))?)));
        }
        let materials = self.array(m.get("materials").unwrap_or(&Value::Null), &join(&loc, "materials"))?;
        let Some(first) = materials.first() else {
            return Err(self.err(&join(&loc, "materials"), "expected at least one material"));
        };
        if materials.len() > 1 {
            let msg = "only the first material is used (faces carry no material labels here)";
            self.warn(&format!("{loc}.materials[1]"), msg);
        }
        let (material, strain_limits) = self.material(first, &format!("{loc}.materials[0]"))?;
        self.origin(&join(&loc, "material"), Origin::Same(format!("{loc}.materials[0]")));
        self.origin(&join(&loc, "strain_limits"), Origin::Same(format!("{loc}.materials[0].strain_limits")));
        self.origin(&join(&loc, "remesh"), Origin::Same(join(&loc, "remeshing")));
        fields.push(("material".into(), material));
        if let Some(sl) = strain_limits {
            fields.push(("strain_limits".into(), nums(&sl)));
        }
        if let Some(r) = m.get("remeshing") {
            fields.push(("remesh".into(), self.remeshing(r, &join(&loc, "remeshing"), magic)?));
        }
        // ARCSim's bending rest angles are zero, unless `magic.preserve_creases` makes the input
        // mesh's folds the rest shape (`reset_plasticity` before and after the initial
        // relaxation sets every edge's ideal angle to its current one).
        let rest = if magic.preserve_creases { "input" } else { "flat" };
        fields.push(("rest_angles".into(), J::Str(rest.into())));
        Ok((fields, full))
    }

    /// A cloth's initial velocity: `[x, y, z]` or `{linear, angular, origin}`.
    fn cloth_velocity(&mut self, v: &Value, loc: &str) -> Res<[f64; 3]> {
        if v.is_array() {
            return self.numbers::<3>(v, loc);
        }
        let m = self.object(v, loc)?;
        self.check_keys(m, loc, &["linear", "angular", "origin"], &[]);
        if let Some(w) = m.get("angular") {
            if self.numbers::<3>(w, &join(loc, "angular"))? != [0.0; 3] {
                self.warn(&join(loc, "angular"), "initial angular velocity is not supported; ignored");
            }
        }
        match m.get("linear") {
            Some(l) => self.numbers::<3>(l, &join(loc, "linear")),
            None => Ok([0.0; 3]),
        }
    }

    /// A material's scene fields, and its `strain_limits`.
    fn material(&mut self, v: &Value, loc: &str) -> Res<(J, Option<[f64; 2]>)> {
        let m = self.object(v, loc)?;
        let known = [
            "data",
            "density_mult",
            "stretching_mult",
            "bending_mult",
            "thicken",
            "damping",
            "strain_limits",
            "thickness",
            "density",
            "elastic_modulus",
            "poisson_ratio",
            "yield_curv",
            "weakening",
        ];
        let not_supported = "stretching plasticity and fracture are not supported";
        let ignored = [
            ("yield_stretch", not_supported),
            ("plastic_flow", not_supported),
            ("plastic_limit", not_supported),
            ("toughness", not_supported),
            ("fracture_bending_mult", not_supported),
        ];
        self.check_keys(m, loc, &known, &ignored);
        let strain_limits = match m.get("strain_limits") {
            Some(sl) => {
                let [lo, hi] = self.numbers::<2>(sl, &join(loc, "strain_limits"))?;
                if !(lo > 0.0 && lo <= 1.0 && hi >= 1.0) {
                    let msg = format!("expected [min, max] with 0 < min ≤ 1 ≤ max, got [{lo}, {hi}]");
                    return Err(self.err(&join(loc, "strain_limits"), msg));
                }
                Some([lo, hi])
            }
            None => None,
        };
        let mut fields = Vec::new();
        let mult = |c: &Self, key: &str| -> Res<Option<f64>> {
            match c.opt_num(m, key, loc)? {
                Some(x) if x <= 0.0 => Err(c.err(&join(loc, key), format!("expected a positive number, got {x}"))),
                other => Ok(other),
            }
        };
        match m.get("data") {
            Some(d) => {
                let (_, file) = self.path(self.string(d, &join(loc, "data"))?);
                fields.push(("arcsim", J::Str(file)));
                for key in ["density_mult", "stretching_mult", "bending_mult", "thicken"] {
                    if let Some(x) = mult(self, key)? {
                        fields.push((key, J::Num(x)));
                    }
                }
                // ARCSim reads the bending table by signed curvature (`FoldSign::Signed`).
                fields.push(("bending_curvature", J::Str("signed".into())));
                // ARCSim's membrane Jacobian (`Geometric::Arcsim`).
                fields.push(("geometric_stiffness", J::Str("arcsim".into())));
            }
            None => {
                // ARCSim's isotropic material: density in kg/m³, E in Pa, bending E t³/(12(1 − ν²)).
                let need = |c: &Self, key: &str| -> Res<f64> {
                    match c.opt_num(m, key, loc)? {
                        Some(x) if x > 0.0 => Ok(x),
                        Some(x) => Err(c.err(&join(loc, key), format!("expected a positive number, got {x}"))),
                        None => Err(c.err(&join(loc, key), "expected a number (or a \"data\" file)")),
                    }
                };
                let (t, rho, e) = (need(self, "thickness")?, need(self, "density")?, need(self, "elastic_modulus")?);
                let nu = self.opt_num(m, "poisson_ratio", loc)?.unwrap_or(0.0);
                if !(0.0..0.5).contains(&nu) {
                    return Err(
                        self.err(&join(loc, "poisson_ratio"), format!("expected a number in [0, 0.5), got {nu}"))
                    );
                }
                let bending = e * t.powi(3) / (12.0 * (1.0 - nu * nu)) * mult(self, "bending_mult")?.unwrap_or(1.0);
                fields.push(("density", J::Num(rho * t)));
                fields.push(("youngs_modulus", J::Num(e)));
                fields.push(("poisson_ratio", J::Num(nu)));
                fields.push(("thickness", J::Num(t)));
                fields.push(("bending", J::Num(bending)));
                if let Some(s) = mult(self, "stretching_mult")? {
                    fields.push(("stretching_mult", J::Num(s)));
                }
                for key in ["density_mult", "thicken"] {
                    if m.contains_key(key) {
                        self.warn(&join(loc, key), "only used with a \"data\" file (as in ARCSim); ignored");
                    }
                }
            }
        }
        let damping = match self.opt_num(m, "damping", loc)? {
            Some(d) if d < 0.0 => {
                return Err(self.err(&join(loc, "damping"), format!("expected a number ≥ 0, got {d}")))
            }
            Some(d) => d,
            None => 0.0,
        };
        fields.push(("damping", J::Num(damping)));
        fields.extend(self.plasticity(m, loc)?);
        Ok((obj(fields), strain_limits))
    }

    /// Bending plasticity (Narain et al. 2013): ARCSim's `yield_curv` (1/m, default ∞: elastic)
    /// and `weakening` (default 0), read unscaled (`disable` with plasticity drops them at load).
    fn plasticity(&mut self, m: &serde_json::Map<String, Value>, loc: &str) -> Res<Vec<(&'static str, J)>> {
        let (yield_curv, weakening) = (self.opt_num(m, "yield_curv", loc)?, self.opt_num(m, "weakening", loc)?);
        if let Some(k) = yield_curv.filter(|&k| !(k > 0.0)) {
            return Err(self.err(&join(loc, "yield_curv"), format!("expected a positive curvature (1/m), got {k}")));
        }
        if let Some(w) = weakening.filter(|&w| !(w >= 0.0)) {
            return Err(self.err(&join(loc, "weakening"), format!("expected a number ≥ 0, got {w}")));
        }
        match yield_curv {
            Some(k) => {
                Ok([("yield_curv", J::Num(k))].into_iter().chain(weakening.map(|w| ("weakening", J::Num(w)))).collect())
            }
            None => {
                if weakening.is_some() {
                    self.warn(&join(loc, "weakening"), "no effect without yield_curv (as in ARCSim); ignored");
                }
                Ok(Vec::new())
            }
        }
    }

    fn remeshing(&mut self, v: &Value, loc: &str, magic: &Magic) -> Res<J> {
        let m = self.object(v, loc)?;
        let known = ["refine_angle", "refine_compression", "refine_velocity", "size", "aspect_min"];
        let ignored = [("size_uniform", "not supported"), ("refine_fracture", "fracture is not supported")];
        self.check_keys(m, loc, &known, &ignored);
        let mut fields = Vec::new();
        if magic.fixed_high_res_mesh {
            fields.push(("mode", J::Str("uniform".into())));
        }
        for key in ["refine_angle", "refine_compression", "refine_velocity"] {
            if let Some(x) = self.opt_num(m, key, loc)? {
                fields.push((key, J::Num(x)));
            }
        }
        let size = m.get("size").ok_or_else(|| self.err(&join(loc, "size"), "expected [min, max] edge lengths (m)"))?;
        fields.push(("size", nums(&self.numbers::<2>(size, &join(loc, "size"))?)));
        if let Some(a) = self.opt_num(m, "aspect_min", loc)? {
            fields.push(("aspect_min", J::Num(a)));
        }
        // ARCSim always refines near obstacles: remeshing_step passes every node's nearest
        // obstacle plane within 10 × repulsion thickness (nearobs.cpp) to the sizing's
        // obstacle_metric; viewcloth's range is the same 10 × thickness.
        fields.push(("refine_obstacle", J::Bool(true)));
        if let Some(combine) = magic.combine_tensors {
            fields.push(("combine", J::Str(if combine { "max" } else { "sum" }.into())));
        }
        // ARCSim's split_edge relaxes the new node (`set_midpoint_position`) unless
        // `magic.preserve_creases` is set.
        if !magic.preserve_creases {
            fields.push(("split_position", J::Str("relaxed".into())));
        }
        Ok(obj(fields))
    }
}
