//! View factors (Koh, Narain & O'Brien 2014, "View-dependent adaptive cloth simulation",
//! eqs. 1–13): a per-face μ ∈ (0, 1] from a scripted camera, whose square scales the
//! curvature and compression criteria of the sizing field (eq. 5), and a minimum edge length
//! that grows with the distance to the camera (eq. 10).
//!
//! - orientation: μ₁ blends μ_back and 1 by a non-uniformly scaled cosine of the angle between
//!   the face normal and the direction to the eye (eqs. 1–2);
//! - frustum: μ₂ blends μ₁ towards μ_out over a margin outside the frustum (eqs. 3–4);
//! - lookahead: μ′₃ is the weighted maximum of μ₂ over camera times around the current one,
//!   weight 1 now and for the next `hold` seconds, then falling linearly to 0 over `window`
//!   seconds (and backwards over `window`), so that cloth is refined before it comes into view
//!   and stays refined briefly after it leaves (eqs. 6–9).
//!
//! The cloth's motion over the window is not predicted (the paper's choice): the current
//! geometry is seen from each camera time. Beyond the paper, cloth hidden behind obstacles or
//! other cloth is coarsened like cloth out of frame (`occlusion`).

use crate::math::PAR_GRAIN;
use rayon::prelude::*;

use crate::camera::{Camera, View};
use crate::io::stats::ViewFrameStats;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;
use crate::metrics::rasterize;

use super::occlusion::{occluded_factor, DepthMap};

/// Koh et al.'s parameters (their values as defaults).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewParams {
    /// Share of the scaled cosine's range given to back-facing orientations (eq. 1).
    pub k_cos: Real,
    /// View factor of a face seen edge-on from behind (eq. 2).
    pub mu_back: Real,
    /// View factor outside the frustum beyond the margin (eq. 3).
    pub mu_out: Real,
    /// Margin (m) over which μ falls to μ_out outside the frustum (eq. 4).
    pub margin: Real,
    /// Minimum edge length per metre of distance to the eye (eq. 10).
    pub k_dist: Real,
    /// When set, the distance term of eq. 10 is the world size of this many pixels of an image
    /// `image_height` pixels high at the face (`pixel_size_min`), so that a zoom or a dolly
    /// changes the resolution; `k_dist` is then unused.
    pub min_edge_pixels: Option<Real>,
    /// Height (pixels) of the rendered image, for `min_edge_pixels`.
    pub image_height: Real,
    /// Lookahead window (s) over which the weights fall to 0 (eqs. 6–8).
    pub window: Real,
    /// Time (s) ahead held at full weight (eq. 9).
    pub hold: Real,
    /// Both sides of the cloth can be seen: orientation uses |cos θ|. Koh et al. coarsen the
    /// back side (a garment's inside); a single-layer sheet is visible from both sides. The
    /// scene loader decides the default per cloth (`scene::load::view_sides`).
    pub two_sided: bool,
    /// Seconds over which a face's view factor may fall from 1 to 0 (smoothed coarsening,
    /// `view_memory`); 0 lets it fall at once. Defaults to `window`.
    pub coarsen_time: Real,
    /// Coarsened faces keep only part of their compressive stress (`forces::buckling`).
    pub buckling_compensation: bool,
    /// +1 when the faces' normals (counter-clockwise winding) point to the side seen, −1 when
    /// they point to the back (a garment modelled with inward normals); used when one-sided.
    pub front: Real,
    /// Height (pixels) of the depth images that decide occlusion at each camera time of the
    /// window (`occlusion`); 0 turns occlusion off.
    pub occlusion_pixels: usize,
    /// How far (pixels of an `image_height`-high image) a remesh may move the cloth the camera
    /// sees (`sizing::remesh_jump`, `remesh::jump`); 0 leaves it unbounded.
    pub max_jump_pixels: Real,
}

impl Default for ViewParams {
    fn default() -> Self {
        ViewParams {
            k_cos: 0.2,
            mu_back: 0.1,
            mu_out: 0.1,
            margin: 0.2,
            k_dist: 0.005,
            min_edge_pixels: None,
            image_height: 1080.0,
            window: 0.4,
            hold: 0.2,
            two_sided: true,
            coarsen_time: 0.4,
            buckling_compensation: false,
            front: 1.0,
            occlusion_pixels: 128,
            max_jump_pixels: 1.0,
        }
    }
}

/// What the sizing of one face needs from the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceView {
    /// μ′₃ (eq. 9).
    pub mu: Real,
    /// l_min,vd = max(l_min, k_dist · d) (eq. 10), d the distance to the eye now.
    pub size_min: Real,
    /// Share of the face seen from the camera now, not hidden behind obstacles or cloth
    /// (`occlusion`); 1 when occlusion is off.
    pub visible: Real,
}

/// Non-uniformly scaled cosine, eq. 1.
pub fn scaled_cos(cos: Real, k_cos: Real) -> Real {
    if cos <= 0.0 {
        k_cos * (cos + 1.0)
    } else {
        (1.0 - k_cos) * cos + k_cos
    }
}

/// Orientation view factor μ₁, eq. 2; `cos` is that of the winding normal with the direction
/// to the eye, turned to the seen side by `front` when one-sided.
pub fn mu_orientation(cos: Real, p: &ViewParams) -> Real {
    let c = scaled_cos(if p.two_sided { cos.abs() } else { p.front * cos }, p.k_cos);
    (1.0 - c) * p.mu_back + c
}

/// μ₂ from μ₁ and the signed distance `d` to the frustum (negative inside), eqs. 3–4.
pub fn mu_frustum(mu1: Real, d: Real, p: &ViewParams) -> Real {
    let delta = if p.margin > 0.0 {
        (d / p.margin).clamp(0.0, 1.0)
    } else if d > 0.0 {
        1.0
    } else {
        0.0
    };
    (1.0 - delta) * mu1 + delta * p.mu_out
}

/// μ₂ of a triangle `x` seen by `view` (eqs. 1–4): orientation from its normal and the
/// direction to the eye, blended towards μ_out outside the frustum by its centroid's distance.
pub fn triangle_view_factor(x: &[Vec3; 3], view: &View, p: &ViewParams) -> Real {
    let centroid = (x[0] + x[1] + x[2]) / 3.0;
    let normal = (x[1] - x[0]).cross(&(x[2] - x[0])).try_normalize(0.0).unwrap_or_else(Vec3::zeros);
    let cos = normal.dot(&(view.eye - centroid).try_normalize(0.0).unwrap_or_else(Vec3::zeros));
    mu_frustum(mu_orientation(cos, p), view.frustum_distance(&centroid), p)
}

/// Camera time offsets (s) and weights of the lookahead window, eqs. 6–9: the current time and
/// `hold` ahead at weight 1, then `window` more each way with weights 1 − i/m, sampled every
/// `dt` seconds (the remeshing interval).
pub fn lookahead(dt: Real, p: &ViewParams) -> Vec<(Real, Real)> {
    let m = (p.window / dt).round() as usize;
    let n = (p.hold / dt).round() as usize;
    let mut out = vec![(0.0, 1.0)];
    for j in 1..=n {
        out.push((j as Real * dt, 1.0));
    }
    for i in 1..m {
        let w = 1.0 - i as Real / m as Real;
        out.push(((n + i) as Real * dt, w));
        out.push((-(i as Real) * dt, w));
    }
    out
}

/// The minimum edge at `x` from its size on screen: an edge `px` pixels long in an image `height`
/// pixels high seen by `view` is 2 d tan(fov/2) px / height long at distance d (eq. 10 with
/// k_dist = 2 tan(fov/2) px / height, so a zoom or dolly changes it). Over the lookahead window
/// the finest demand wins, weighted as the view factors are (eq. 6, on 1/l): min over samples of
/// l_s / w_s, so a zoom is anticipated by the window's `hold` and ramp.
pub fn pixel_size_min(x: &Vec3, samples: &[(View, Real)], px: Real, height: Real) -> Real {
    samples
        .iter()
        .filter(|(_, w)| *w > 0.0)
        .map(|(view, w)| 2.0 * view.eye_distance(x) * view.tan_half_fov * px / height / w)
        .fold(Real::INFINITY, Real::min)
}

/// Obstacle triangles at a time, for occlusion: (positions, triangles) of the bodies present.
pub type Soup = (Vec<Vec3>, Vec<[usize; 3]>);

/// View factor and minimum edge length of every face at time `t`, remeshing every `dt`
/// seconds. `params[material]` holds the view parameters and minimum edge length of each
/// view-dependent cloth; faces of other cloths get `None`. `obstacles_at(t)` gives the
/// obstacles that can hide cloth at a camera time (with the whole cloth mesh, as it is now,
/// they make the depth images of `occlusion`); `kept` holds the obstacle images between calls.
pub fn face_views(
    mesh: &Mesh,
    camera: &Camera,
    t: Real,
    dt: Real,
    params: &[Option<(ViewParams, Real)>],
    obstacles_at: &dyn Fn(Real) -> Soup,
    kept: &mut ObstacleDepths,
) -> Vec<Option<FaceView>> {
    let depth_maps = DepthMaps::new(mesh, camera, (t, dt), params, obstacles_at, kept);
    let offsets: Vec<Vec<(Real, Real)>> =
        params.iter().map(|p| p.as_ref().map_or(Vec::new(), |(p, _)| lookahead(dt, p))).collect();
    let samples: Vec<Vec<(View, Real)>> =
        offsets.iter().map(|o| o.iter().map(|&(off, w)| (camera.view_at(t + off), w)).collect()).collect();
    let maps: Vec<Vec<Option<&DepthMap>>> = offsets
        .iter()
        .zip(params)
        .map(|(o, p)| o.iter().map(|&(off, _)| depth_maps.get(off, p.map_or(0, |(p, _)| p.occlusion_pixels))).collect())
        .collect();
    let now = camera.view_at(t);
    (0..mesh.faces.len())
        .into_par_iter()
        .with_min_len(PAR_GRAIN)
        .map(|f| {
            let material = mesh.faces[f].material as usize;
            let (p, size_min) = params.get(material).copied().flatten()?;
            let x = mesh.face_nodes(f).map(|n| mesh.nodes[n].x);
            let centroid: Vec3 = (x[0] + x[1] + x[2]) / 3.0;
            let mut mu: Real = 0.0;
            let mut visible = 1.0;
            for (k, ((view, w), map)) in samples[material].iter().zip(&maps[material]).enumerate() {
                let mu2 = triangle_view_factor(&x, view, &p);
                // The lookahead's first sample is now (`lookahead`); its visibility is
                // reported even when it cannot raise μ.
                let wanted = k == 0 || w * mu2 > mu;
                let v = match map {
                    Some(map) if wanted && mu2 > p.mu_out => map.visible_fraction(&x),
                    _ => 1.0,
                };
                if k == 0 {
                    visible = v;
                }
                mu = mu.max(w * occluded_factor(mu2, v, p.mu_out));
            }
            let distance_term = match p.min_edge_pixels {
                Some(px) => pixel_size_min(&centroid, &samples[material], px, p.image_height),
                None => p.k_dist * now.eye_distance(&centroid),
            };
            Some(FaceView { mu, size_min: size_min.max(distance_term), visible })
        })
        .collect()
}

/// The depth images of every camera time a view-dependent cloth samples, one per distinct
/// (time on the occlusion grid, resolution), built once per call.
struct DepthMaps {
    t: Real,
    step: Real,
    maps: Vec<((i64, usize), DepthMap)>,
}

/// The obstacles' depth images kept from one remesh to the next (`face_views`): an obstacle
/// image depends only on its grid time and resolution (the cloth's part, as it is now, is drawn
/// at every remesh), and successive remeshes ask for mostly the same grid times. A resumed run
/// starts with none and draws the same images.
#[derive(Clone, Debug, Default)]
pub struct ObstacleDepths {
    /// (grid index, resolution, grid step's bits) and the raw depth image.
    images: Vec<((i64, usize, u64), Vec<Real>)>,
}

impl DepthMaps {
    fn new(
        mesh: &Mesh,
        camera: &Camera,
        (t, dt): (Real, Real),
        params: &[Option<(ViewParams, Real)>],
        obstacles_at: &dyn Fn(Real) -> Soup,
        kept: &mut ObstacleDepths,
    ) -> Self {
        let step = OCCLUSION_STEP.max(dt);
        let mut keys: Vec<(i64, usize)> = Vec::new();
        for (p, _) in params.iter().flatten().filter(|(p, _)| p.occlusion_pixels > 0) {
            for (off, _) in lookahead(dt, p) {
                let key = (occlusion_index(t + off, step), p.occlusion_pixels);
                if !keys.contains(&key) {
                    keys.push(key);
                }
            }
        }
        let cloth_tris: Vec<[usize; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).collect();
        let cloth_x = mesh.positions();
        let mut images = Vec::with_capacity(keys.len());
        let maps = keys
            .into_iter()
            .map(|(k, px)| {
                let time = k as Real * step;
                let view = camera.view_at(time);
                let (width, height) = DepthMap::size(&view, px);
                let id = (k, px, step.to_bits());
                let obstacles = match kept.images.iter().position(|(key, _)| *key == id) {
                    Some(i) => std::mem::take(&mut kept.images[i].1),
                    None => {
                        let (ox, otris) = obstacles_at(time);
                        rasterize(&ox, &otris, &view, width, height).depth
                    }
                };
                let cloth = rasterize(&cloth_x, &cloth_tris, &view, width, height).depth;
                let depth: Vec<Real> = cloth.iter().zip(&obstacles).map(|(c, o)| c.min(*o)).collect();
                images.push((id, obstacles));
                ((k, px), DepthMap::from_depth(&view, width, height, &depth))
            })
            .collect();
        kept.images = images;
        DepthMaps { t, step, maps }
    }

    /// The depth image serving camera time `t + off` (the nearest on the occlusion grid).
    fn get(&self, off: Real, px: usize) -> Option<&DepthMap> {
        if px == 0 {
            return None;
        }
        let key = (occlusion_index(self.t + off, self.step), px);
        self.maps.iter().find(|(k, _)| *k == key).map(|(_, m)| m)
    }
}

/// Occlusion changes more slowly than the window is sampled: depth images are made at the
/// multiples of `OCCLUSION_STEP` seconds (or of `dt` when that is longer) that the window
/// reaches, and each camera time uses the nearest one. The grid is absolute, not relative to the
/// remesh time, so the next remesh finds most of its obstacle images made (`ObstacleDepths`).
const OCCLUSION_STEP: Real = 0.1;

/// The index on the occlusion grid of the image that serves camera time `time`.
fn occlusion_index(time: Real, step: Real) -> i64 {
    (time / step).round() as i64
}

/// Area-weighted mean μ′₃ over the faces with a view (`views` from `face_views`), how many of
/// them have their centroid inside / outside the frustum of the camera at time `t`, and how many
/// of those inside are mostly hidden (less than half of the face seen).
pub fn view_summary(mesh: &Mesh, camera: &Camera, t: Real, views: &[Option<FaceView>]) -> ViewFrameStats {
    let now = camera.view_at(t);
    let (mut weighted, mut area) = (0.0, 0.0);
    let mut out = ViewFrameStats::default();
    for (f, v) in views.iter().enumerate() {
        let Some(v) = v else { continue };
        let x = mesh.face_nodes(f).map(|n| mesh.nodes[n].x);
        let a = 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm();
        weighted += a * v.mu;
        area += a;
        if now.frustum_distance(&((x[0] + x[1] + x[2]) / 3.0)) <= 0.0 {
            out.view_faces_in_frame += 1;
            if v.visible < 0.5 {
                out.view_faces_occluded += 1;
            }
        } else {
            out.view_faces_out_of_frame += 1;
        }
    }
    out.view_mean_mu = if area > 0.0 { weighted / area } else { 0.0 };
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 m sheet 3 m in front of a camera panning across it, half hidden behind a 2 m-wide
    /// wall 1 m in front of it that slides sideways: the obstacle images kept from one remesh to
    /// the next give the views a fresh start gives, while most of them are not drawn again.
    #[test]
    fn kept_obstacle_images_give_the_views_of_a_fresh_start() {
        let camera = Camera::from_json(
            r#"{ "version": 1, "aspect": 1.0, "keys": [
                { "time": 0.0, "position": [0.5, -3, 0.5], "target": [0.5, 0, 0.5], "up": [0, 0, 1], "fov": 50 },
                { "time": 1.0, "position": [1.5, -3, 0.5], "target": [1.0, 0, 0.5], "up": [0, 0, 1], "fov": 50 } ] }"#,
            std::path::Path::new("camera.json"),
        )
        .unwrap();
        let mut mesh = crate::mesh::rectangle(1.0, 1.0, 8, 8).unwrap();
        for n in &mut mesh.nodes {
            n.x = Vec3::new(n.x.x, 0.0, n.x.y);
        }
        let drawn = std::cell::Cell::new(0);
        let wall = |t: Real| -> Soup {
            drawn.set(drawn.get() + 1);
            let (x0, x1) = (-1.5 + t, 0.5 + t);
            let p = vec![
                Vec3::new(x0, -1.0, -1.0),
                Vec3::new(x1, -1.0, -1.0),
                Vec3::new(x1, -1.0, 2.0),
                Vec3::new(x0, -1.0, 2.0),
            ];
            (p, vec![[0, 1, 2], [0, 2, 3]])
        };
        let p = ViewParams { occlusion_pixels: 32, ..Default::default() };
        let params = [Some((p, 0.01))];
        let (dt, frames) = (0.04, 10);
        let mut kept = ObstacleDepths::default();
        let mut hidden = 0;
        for frame in 0..frames {
            let t = frame as Real * dt;
            let before = drawn.get();
            let fresh = face_views(&mesh, &camera, t, dt, &params, &wall, &mut ObstacleDepths::default());
            let per_call = drawn.get() - before;
            let views = face_views(&mesh, &camera, t, dt, &params, &wall, &mut kept);
            assert_eq!(views, fresh, "frame {frame}");
            if frame > 0 {
                assert!(drawn.get() - before - per_call < per_call, "frame {frame}: kept images drawn again");
            }
            hidden += views.iter().flatten().filter(|v| v.visible < 1.0).count();
        }
        assert!(hidden > 0, "the wall hides part of the sheet");
    }

    #[test]
    fn scaled_cosine_gives_a_fifth_of_its_range_to_back_faces() {
        let k = 0.2;
        assert_eq!(scaled_cos(-1.0, k), 0.0);
        assert_eq!(scaled_cos(0.0, k), k);
        assert!((scaled_cos(1.0, k) - 1.0).abs() < 1e-15);
        assert!((scaled_cos(0.5, k) - 0.6).abs() < 1e-15);
        assert!((scaled_cos(-0.5, k) - 0.1).abs() < 1e-15);
    }

    #[test]
    fn orientation_factor_runs_from_mu_back_to_one() {
        let one_sided = ViewParams { two_sided: false, ..Default::default() };
        assert!((mu_orientation(1.0, &one_sided) - 1.0).abs() < 1e-15);
        assert!((mu_orientation(-1.0, &one_sided) - 0.1).abs() < 1e-15);
        // Edge-on: μ_back + k_cos (1 − μ_back).
        assert!((mu_orientation(0.0, &one_sided) - 0.28).abs() < 1e-15);
        let two_sided = ViewParams::default();
        assert!((mu_orientation(-1.0, &two_sided) - 1.0).abs() < 1e-15);
        // Inward normals: the winding's back is the seen side.
        let inward = ViewParams { two_sided: false, front: -1.0, ..Default::default() };
        assert!((mu_orientation(-1.0, &inward) - 1.0).abs() < 1e-15);
        assert!((mu_orientation(1.0, &inward) - 0.1).abs() < 1e-15);
    }

    #[test]
    fn frustum_factor_falls_to_mu_out_over_the_margin() {
        let p = ViewParams::default();
        assert_eq!(mu_frustum(0.8, -1.0, &p), 0.8);
        assert_eq!(mu_frustum(0.8, 0.0, &p), 0.8);
        assert!((mu_frustum(0.8, 0.1, &p) - 0.45).abs() < 1e-15);
        assert!((mu_frustum(0.8, 5.0, &p) - 0.1).abs() < 1e-15);
    }

    #[test]
    fn lookahead_holds_then_falls_linearly_both_ways() {
        let p = ViewParams { window: 0.4, hold: 0.2, ..Default::default() };
        let w = lookahead(0.1, &p);
        let at = |t: Real| w.iter().find(|(o, _)| (o - t).abs() < 1e-9).map(|(_, w)| *w);
        assert_eq!(at(0.0), Some(1.0));
        assert_eq!(at(0.1), Some(1.0));
        assert_eq!(at(0.2), Some(1.0));
        assert_eq!(at(0.3), Some(0.75));
        assert_eq!(at(0.5), Some(0.25));
        assert_eq!(at(0.6), None, "weight 0 at the window's end is not sampled");
        assert_eq!(at(-0.1), Some(0.75));
        assert_eq!(at(-0.3), Some(0.25));
        assert_eq!(at(-0.4), None);
    }

    #[test]
    fn pixel_size_is_the_finest_weighted_demand_over_the_window() {
        let cam = |fov: Real| {
            let text = format!(
                r#"{{"version": 1, "keys": [{{"time": 0, "position": [0, 0, 2], "target": [0, 0, 0], "up": [0, 1, 0], "fov": {fov}}}]}}"#
            );
            Camera::from_json(&text, std::path::Path::new("c.json")).unwrap().view_at(0.0)
        };
        let x = Vec3::zeros();
        let wide = cam(40.0);
        let l = pixel_size_min(&x, &[(wide, 1.0)], 2.0, 1080.0);
        let expected = 2.0 * 2.0 * (20.0 as Real).to_radians().tan() * 2.0 / 1080.0;
        assert!((l - expected).abs() < 1e-15, "{l} vs {expected}");
        // A zoom 10× narrower at half weight: 1/10 the size, over 1/2 the weight.
        let narrow = cam(2.0 * (0.1 * (20.0 as Real).to_radians().tan()).atan().to_degrees());
        let l2 = pixel_size_min(&x, &[(wide, 1.0), (narrow, 0.5)], 2.0, 1080.0);
        assert!((l2 - expected * 0.2).abs() < 1e-12, "{l2} vs {}", expected * 0.2);
        assert_eq!(pixel_size_min(&x, &[(narrow, 0.0)], 2.0, 1080.0), Real::INFINITY, "weight 0 is not sampled");
    }
}
