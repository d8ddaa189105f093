//! A cloth's `remesh` block: the sizing criteria and limits (Narain et al. 2012) and the view
//! factor parameters of view-dependent mode (Koh et al. 2014).

use super::super::spec::{RemeshSpec, ViewSpec};
use super::super::{Remesh, RemeshMode};
use super::{positive, Ctx, Res};
use crate::sizing::{Combine, SizingParams, ViewParams};

pub(super) fn remesh_params(ctx: &Ctx, path: &str, r: &RemeshSpec) -> Res<Remesh> {
    let mode = match r.mode.as_deref() {
        None => RemeshMode::Adaptive,
        Some(name) => RemeshMode::parse(name).ok_or_else(|| {
            ctx.err(format!("{path}.mode"), format!("expected \"adaptive\", \"uniform\" or \"view\", got \"{name}\""))
        })?,
    };
    let view = view_params(ctx, &format!("{path}.view"), r.view.as_ref())?;
    let opt = |field: &str, v: Option<f64>| v.map(|x| positive(ctx, &format!("{path}.{field}"), x)).transpose();
    let size_min = positive(ctx, &format!("{path}.size[0]"), r.size[0])?;
    let size_max = positive(ctx, &format!("{path}.size[1]"), r.size[1])?;
    if size_min > size_max {
        return Err(ctx
            .err(format!("{path}.size"), format!("expected [min, max] with min ≤ max, got [{size_min}, {size_max}]")));
    }
    let aspect_min = r.aspect_min.unwrap_or(0.2);
    if !(aspect_min > 0.0 && aspect_min <= 1.0) {
        return Err(ctx.err(format!("{path}.aspect_min"), format!("expected a number in (0, 1], got {aspect_min}")));
    }
    let combine = match r.combine.as_deref() {
        None | Some("max") => Combine::Max,
        Some("sum") => Combine::Sum,
        Some(other) => {
            return Err(ctx.err(format!("{path}.combine"), format!("expected \"max\" or \"sum\", got \"{other}\"")))
        }
    };
    let every = match r.every {
        None => 1,
        Some(n) if (1..=100_000).contains(&n) => n as usize,
        Some(n) => return Err(ctx.err(format!("{path}.every"), format!("expected an integer ≥ 1, got {n}"))),
    };
    Ok(Remesh {
        mode,
        sizing: SizingParams {
            refine_angle: opt("refine_angle", r.refine_angle)?,
            refine_compression: opt("refine_compression", r.refine_compression)?,
            refine_velocity: opt("refine_velocity", r.refine_velocity)?,
            refine_obstacle: r.refine_obstacle.unwrap_or(false),
            size_min,
            size_max,
            aspect_min,
            combine,
        },
        every,
        view,
    })
}

/// Koh et al.'s view factor parameters, each checked against the range its equation needs.
fn view_params(ctx: &Ctx, path: &str, v: Option<&ViewSpec>) -> Res<ViewParams> {
    let mut p = ViewParams::default();
    let Some(v) = v else { return Ok(p) };
    let check = |field: &str, x: Option<f64>, lo: f64, hi: f64, open_lo: bool, into: &mut f64| -> Res<()> {
        if let Some(x) = x {
            let ok = x.is_finite() && (if open_lo { x > lo } else { x >= lo }) && x <= hi;
            if !ok {
                let range = if open_lo { format!("({lo}, {hi}]") } else { format!("[{lo}, {hi}]") };
                return Err(ctx.err(format!("{path}.{field}"), format!("expected a number in {range}, got {x}")));
            }
            *into = x;
        }
        Ok(())
    };
    check("k_cos", v.k_cos, 0.0, 1.0, false, &mut p.k_cos)?;
    check("mu_back", v.mu_back, 0.0, 1.0, true, &mut p.mu_back)?;
    check("mu_out", v.mu_out, 0.0, 1.0, true, &mut p.mu_out)?;
    check("margin", v.margin, 0.0, 1e3, false, &mut p.margin)?;
    check("k_dist", v.k_dist, 0.0, 1.0, false, &mut p.k_dist)?;
    check("window", v.window, 0.0, 1e3, false, &mut p.window)?;
    check("hold", v.hold, 0.0, 1e3, false, &mut p.hold)?;
    p.coarsen_time = p.window;
    check("coarsen_time", v.coarsen_time, 0.0, 1e3, false, &mut p.coarsen_time)?;
    if let Some(b) = v.two_sided {
        p.two_sided = b;
    }
    if let Some(b) = v.buckling_compensation {
        p.buckling_compensation = b;
    }
    Ok(p)
}
