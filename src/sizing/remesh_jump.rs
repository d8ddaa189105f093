//! How far a remesh moves the visible cloth on screen (issue 19, item 5: "screen-space jump of
//! visible nodes at a remesh below a pixel").
//!
//! A remesh keeps the cloth's material (texture) coordinates and changes its surface: a split
//! puts a node on the old surface (no jump), a collapse or a flip drops a node or an edge, so the
//! material points around it now lie on a flatter surface, and the pop filter (Narain et al.
//! 2013) moves the new nodes to rest. What the viewer sees jump is the *material* point: where a
//! point of the cloth was on screen just before the remesh and where it is just after. Both
//! surfaces are sampled at their nodes' material coordinates (the new mesh's nodes located on the
//! old surface, and the old mesh's on the new one, so that what a collapse removes is seen as
//! well as what a split or the pop filter adds), each point placed by barycentric interpolation of
//! the other surface's positions, projected through the camera at the remesh time, and the
//! distance taken in pixels of an image `image_height` pixels high.
//!
//! A point counts when it is seen before the remesh: inside the camera's frame, in front of the
//! near plane, on an old face of a view-dependent cloth that is not mostly hidden (`FaceView::
//! visible` ≥ ½; 1 when occlusion is off). Points of one cloth are located only among that cloth's
//! faces (two garments' material spaces overlap).

use crate::camera::View;
use crate::math::{Real, Vec2, Vec3};
use crate::mesh::Mesh;
use crate::resample::locate::{by_group, Locator};

use super::view::FaceView;

/// The on-screen jumps of one remesh: over the material points that count (module doc), the
/// largest and the 99th percentile, in pixels, and how many points there were.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Jump {
    pub max_px: Real,
    pub p99_px: Real,
    pub points: usize,
}

/// A mesh's faces in material space, cloth by cloth, for locating material points.
struct Side<'a> {
    mesh: &'a Mesh,
    /// Per cloth: the faces of that cloth, and a locator over their material triangles
    /// (indexed like the list).
    cloths: Vec<Option<(Vec<usize>, Locator)>>,
}

impl<'a> Side<'a> {
    fn new(mesh: &'a Mesh, counts: impl Fn(usize) -> bool) -> Side<'a> {
        let faces = (0..mesh.faces.len()).filter(|&f| counts(f));
        Side { mesh, cloths: by_group(faces.map(|f| (f, corners_u(mesh, f), cloth_of(mesh, f)))) }
    }

    /// The face of cloth `c` holding material point `u` and the position there, if that cloth
    /// has faces here.
    fn place(&self, c: usize, u: &Vec2) -> Option<(usize, Vec3)> {
        let (faces, loc) = self.cloths.get(c)?.as_ref()?;
        let hit = loc.locate(u);
        let f = faces[hit.triangle];
        let x = self.mesh.face_nodes(f).map(|n| self.mesh.nodes[n].x);
        Some((f, x[0] * hit.bary[0] + x[1] * hit.bary[1] + x[2] * hit.bary[2]))
    }
}

fn cloth_of(mesh: &Mesh, f: usize) -> usize {
    mesh.nodes[mesh.face_nodes(f)[0]].cloth as usize
}

fn corners_u(mesh: &Mesh, f: usize) -> [Vec2; 3] {
    mesh.faces[f].v.map(|v| mesh.verts[v.idx()].u)
}

/// The world size of one pixel at `p` (m), seen by `view` in an image `height` pixels high,
/// when `p` is in frame.
pub fn pixel_world_size(view: &View, height: Real, p: &Vec3) -> Option<Real> {
    on_screen(view, height, p)?;
    Some(2.0 * (p - view.eye).dot(&view.forward) * view.tan_half_fov / height)
}

/// Pixel coordinates of `p` (origin at the image centre, y up) in an image `height` pixels high,
/// when it is in front of the near plane and inside the frame.
fn on_screen(view: &View, height: Real, p: &Vec3) -> Option<[Real; 2]> {
    let c = p - view.eye;
    let z = c.dot(&view.forward);
    if z <= view.near {
        return None;
    }
    let s = 0.5 * height / (z * view.tan_half_fov);
    let q = [c.dot(&view.right) * s, c.dot(&view.up) * s];
    (q[0].abs() <= 0.5 * height * view.aspect && q[1].abs() <= 0.5 * height).then_some(q)
}

/// Pixel distance between `a` and `b` as `view` sees them; `None` unless `a` is on screen.
fn distance_px(view: &View, height: Real, a: &Vec3, b: &Vec3) -> Option<Real> {
    let pa = on_screen(view, height, a)?;
    let c = b - view.eye;
    let z = c.dot(&view.forward).max(view.near);
    let s = 0.5 * height / (z * view.tan_half_fov);
    let pb = [c.dot(&view.right) * s, c.dot(&view.up) * s];
    Some(((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt())
}

/// The on-screen jump from the mesh `old` (just before the remesh, seen as `old_views` say)
/// to `new` (after it and the pop filter), seen by `view` in an image `height` pixels high.
/// Faces without a view (cloths that are not view-dependent) are left out.
pub fn remesh_jump(old: &Mesh, old_views: &[Option<FaceView>], new: &Mesh, view: &View, height: Real) -> Jump {
    let view_cloths: Vec<bool> = {
        let n = old.nodes.iter().map(|n| n.cloth as usize + 1).max().unwrap_or(0);
        let mut c = vec![false; n];
        (0..old.faces.len())
            .filter(|&f| old_views.get(f).is_some_and(Option::is_some))
            .for_each(|f| c[cloth_of(old, f)] = true);
        c
    };
    let of_view_cloth = |m: &Mesh, f: usize| view_cloths.get(cloth_of(m, f)).copied().unwrap_or(false);
    let before = Side::new(old, |f| of_view_cloth(old, f));
    let after = Side::new(new, |f| of_view_cloth(new, f));
    let seen = |f: usize| old_views.get(f).and_then(Option::as_ref).is_some_and(|v| v.visible >= 0.5);
    let mut jumps = Vec::new();
    // The new mesh's material points: where they were (old surface) and where they are.
    for vert in &new.verts {
        let node = &new.nodes[vert.node.idx()];
        let Some((f, was)) = before.place(node.cloth as usize, &vert.u) else { continue };
        if seen(f) {
            jumps.extend(distance_px(view, height, &was, &node.x));
        }
    }
    // The old mesh's: where they were (their nodes) and where they are (new surface).
    for vert in &old.verts {
        let node = &old.nodes[vert.node.idx()];
        let Some((f, _)) = before.place(node.cloth as usize, &vert.u) else { continue };
        let Some((_, now)) = after.place(node.cloth as usize, &vert.u) else { continue };
        if seen(f) {
            jumps.extend(distance_px(view, height, &node.x, &now));
        }
    }
    if jumps.is_empty() {
        return Jump::default();
    }
    jumps.sort_by(Real::total_cmp);
    let p99 = jumps[((jumps.len() - 1) as Real * 0.99).round() as usize];
    Jump { max_px: jumps[jumps.len() - 1], p99_px: p99, points: jumps.len() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::mesh::rectangle;

    /// A still camera 2 m in front of a 1 m sheet, 40° high, 500 px: 1 px ≈ 2.9 mm at the sheet.
    fn setup() -> (Mesh, View) {
        let camera = Camera::from_json(
            r#"{ "version": 1, "aspect": 1.0, "keys": [
                { "time": 0.0, "position": [0.5, -2, 0.5], "target": [0.5, 0, 0.5], "up": [0, 0, 1], "fov": 40 } ] }"#,
            std::path::Path::new("camera.json"),
        )
        .unwrap();
        let mut mesh = rectangle(1.0, 1.0, 8, 8).unwrap();
        for n in &mut mesh.nodes {
            n.x = Vec3::new(n.x.x, 0.0, n.x.y);
        }
        (mesh, camera.view_at(0.0))
    }

    fn views(mesh: &Mesh, visible: Real) -> Vec<Option<FaceView>> {
        vec![Some(FaceView { mu: 1.0, size_min: 0.01, visible }); mesh.faces.len()]
    }

    #[test]
    fn the_same_surface_does_not_jump_and_a_moved_node_jumps_by_its_projection() {
        let (old, view) = setup();
        let j = remesh_jump(&old, &views(&old, 1.0), &old, &view, 500.0);
        assert_eq!(j.max_px, 0.0);
        assert_eq!(j.points, 2 * old.verts.len());
        // One interior node moved 1 cm across the line of sight (x): 500 px over
        // 2·2 m·tan 20° = 1.456 m, so 3.43 px, seen from both sides.
        let mut new = old.clone();
        let i = (0..new.nodes.len()).find(|&i| (new.nodes[i].x - Vec3::new(0.5, 0.0, 0.5)).norm() < 1e-9).unwrap();
        new.nodes[i].x.x += 0.01;
        let j = remesh_jump(&old, &views(&old, 1.0), &new, &view, 500.0);
        let expected = 0.01 * 500.0 / (2.0 * 2.0 * (20.0f64).to_radians().tan());
        assert!((j.max_px - expected).abs() < 1e-9 * expected, "{} vs {expected}", j.max_px);
        // Moving along the line of sight shows (almost) nothing.
        let mut new = old.clone();
        new.nodes[i].x.y += 0.01;
        let j = remesh_jump(&old, &views(&old, 1.0), &new, &view, 500.0);
        assert!(j.max_px < 0.01 * expected, "{}", j.max_px);
        // Hidden faces do not count.
        let mut new = old.clone();
        new.nodes[i].x.x += 0.01;
        assert_eq!(remesh_jump(&old, &views(&old, 0.0), &new, &view, 500.0).points, 0);
    }

    #[test]
    fn a_finer_mesh_of_the_same_surface_does_not_jump_but_a_coarser_one_of_a_pleated_sheet_does() {
        let (old, view) = setup();
        // A 16×16 mesh of the same flat sheet: every material point stays where it was.
        let mut fine = rectangle(1.0, 1.0, 16, 16).unwrap();
        for n in &mut fine.nodes {
            n.x = Vec3::new(n.x.x, 0.0, n.x.y);
        }
        let j = remesh_jump(&old, &views(&old, 1.0), &fine, &view, 500.0);
        assert!(j.max_px < 1e-9, "{}", j.max_px);
        // The 16×16 sheet with every other column of nodes shifted 1 cm along x (a pleat), then
        // coarsened to the 8×8 mesh whose nodes are the unshifted columns: the shifted columns'
        // material points fall back onto the flat surface, 1 cm ≈ 3.4 px.
        for (k, n) in fine.nodes.iter_mut().enumerate() {
            if k % 17 % 2 == 1 {
                n.x.x += 0.01;
            }
        }
        let coarse = old.clone();
        let j = remesh_jump(&fine, &views(&fine, 1.0), &coarse, &view, 500.0);
        let expected = 0.01 * 500.0 / (2.0 * 2.0 * (20.0f64).to_radians().tan());
        assert!((j.max_px - expected).abs() < 1e-6 * expected, "{} vs {expected}", j.max_px);
    }
}
