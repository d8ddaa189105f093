//! A cloth's `remesh` block: the sizing criteria and limits (Narain et al. 2012) and the view
//! factor parameters of view-dependent mode (Koh et al. 2014).

use super::super::spec::{ClothSpec, RemeshSpec, ViewSpec};
use super::super::{Remesh, RemeshMode};
use super::{positive, Ctx, Res};
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;
use crate::sizing::{Combine, SizingParams, ViewParams};

/// Which sides of a cloth the camera can see when its `view.two_sided` is not given: a
/// garment — an input mesh with a seam (a node carrying two or more material coordinates:
/// panels sewn together) or a handle riding on an obstacle or a `.mot` body — is one-sided,
/// its inside coarsened to μ_back (Koh et al. 2014, eq. 2); anything else (a flat sheet, a
/// single panel) is two-sided. Returns (two_sided, front), `front` the sign that turns the
/// winding normal outward (see `outward_sign`).
pub(super) fn view_sides(local: &Mesh, cs: &ClothSpec) -> (bool, Real) {
    let seams = local.verts.len() > local.nodes.len();
    let on_body = cs.handles.iter().any(|h| h.obstacle.is_some() || h.mot.is_some());
    (!(seams || on_body), outward_sign(local))
}

/// +1 when the winding normals point away from the cloth's own area centroid c̄ at its input
/// pose, −1 when they point towards it: the sign of Σ_f 2A_f n̂_f · (c_f − c̄). A garment
/// wraps its body, so the side facing away from its centroid is the outside, whichever way
/// the modeller wound the faces. Invariant under the cloth's transform (a rotation, a
/// translation and a positive scale). A flat cloth (|flux| below 10⁻⁶ (2A)^{3/2}) keeps its
/// winding.
fn outward_sign(mesh: &Mesh) -> Real {
    let tris: Vec<[Vec3; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f).map(|n| mesh.nodes[n].x)).collect();
    let area_normal = |x: &[Vec3; 3]| (x[1] - x[0]).cross(&(x[2] - x[0]));
    let centroid = |x: &[Vec3; 3]| (x[0] + x[1] + x[2]) / 3.0;
    let (mut weighted, mut area) = (Vec3::zeros(), 0.0);
    for x in &tris {
        let a = area_normal(x).norm();
        weighted += a * centroid(x);
        area += a;
    }
    if area <= 0.0 {
        return 1.0;
    }
    let c = weighted / area;
    let flux: Real = tris.iter().map(|x| area_normal(x).dot(&(centroid(x) - c))).sum();
    // A flat sheet's flux is rounding: keep its winding.
    if flux < -1e-6 * area * area.sqrt() {
        -1.0
    } else {
        1.0
    }
}

/// `sides`: the cloth's default (two_sided, front) from `view_sides`.
pub(super) fn remesh_params(ctx: &Ctx, path: &str, r: &RemeshSpec, sides: (bool, Real)) -> Res<Remesh> {
    let mode = match r.mode.as_deref() {
        None => RemeshMode::Adaptive,
        Some(name) => RemeshMode::parse(name).ok_or_else(|| {
            ctx.err(format!("{path}.mode"), format!("expected \"adaptive\", \"uniform\" or \"view\", got \"{name}\""))
        })?,
    };
    let view = view_params(ctx, &format!("{path}.view"), r.view.as_ref(), sides)?;
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
    let relax_splits = match r.split_position.as_deref() {
        None | Some("midpoint") => false,
        Some("relaxed") => true,
        Some(other) => {
            return Err(ctx.err(
                format!("{path}.split_position"),
                format!("expected \"midpoint\" or \"relaxed\", got \"{other}\""),
            ))
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
        relax_splits,
    })
}

/// Koh et al.'s view factor parameters, each checked against the range its equation needs.
fn view_params(ctx: &Ctx, path: &str, v: Option<&ViewSpec>, sides: (bool, Real)) -> Res<ViewParams> {
    let mut p = ViewParams { two_sided: sides.0, front: sides.1, ..ViewParams::default() };
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
    if let Some(px) = v.min_edge_pixels {
        let mut x = 0.0;
        check("min_edge_pixels", Some(px), 0.0, 1e4, true, &mut x)?;
        p.min_edge_pixels = Some(x);
    }
    if let Some(h) = v.image_height {
        if !(1..=100_000).contains(&h) {
            return Err(
                ctx.err(format!("{path}.image_height"), format!("expected an integer 1..=100000 (pixels), got {h}"))
            );
        }
        p.image_height = h as Real;
    }
    if let Some(h) = v.occlusion_pixels {
        if !(0..=4096).contains(&h) {
            return Err(ctx.err(
                format!("{path}.occlusion_pixels"),
                format!("expected an integer 0..=4096 (pixels; 0 turns occlusion off), got {h}"),
            ));
        }
        p.occlusion_pixels = h as usize;
    }
    check("max_jump_pixels", v.max_jump_pixels, 0.0, 1e4, false, &mut p.max_jump_pixels)?;
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
