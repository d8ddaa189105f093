//! A cloth's constraint blocks: `lra` (long range attachments, Kim et al. 2012) and
//! `strain_limits` (ARCSim's, on the principal stretches).

use super::super::spec::LraSpec;
use super::{Ctx, Res};
use crate::constraints::{Distance, LraParams};

/// A cloth's `lra` block: `max_attachments` an integer in 1..=64, `stretch` finite and ≥ 0,
/// `distance` `"geodesic"` or `"euclidean"`.
pub(super) fn lra_params(ctx: &Ctx, path: &str, l: &LraSpec) -> Res<LraParams> {
    let mut p = LraParams::default();
    if let Some(n) = l.max_attachments {
        if !(1..=64).contains(&n) {
            return Err(ctx.err(format!("{path}.max_attachments"), format!("expected an integer in 1..=64, got {n}")));
        }
        p.max_attachments = n as usize;
    }
    if let Some(s) = l.stretch {
        if !s.is_finite() || s < 0.0 {
            return Err(ctx.err(format!("{path}.stretch"), format!("expected a number ≥ 0 (0.1 = 10%), got {s}")));
        }
        p.stretch = s;
    }
    if let Some(d) = &l.distance {
        p.distance = Distance::parse(d).ok_or_else(|| {
            ctx.err(format!("{path}.distance"), format!("expected \"geodesic\" or \"euclidean\", got \"{d}\""))
        })?;
    }
    Ok(p)
}

/// `strain_limits: [min, max]` with 0 < min ≤ 1 ≤ max, finite.
pub(super) fn strain_limits(ctx: &Ctx, path: &str, [lo, hi]: [f64; 2]) -> Res<[f64; 2]> {
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= 1.0 && hi >= 1.0) {
        return Err(ctx.err(path, format!("expected [min, max] with 0 < min ≤ 1 ≤ max, got [{lo}, {hi}]")));
    }
    Ok([lo, hi])
}
