//! A deterministic CPU rasteriser: depth, normal and triangle-id buffers of a mesh seen by a
//! `View`, for the visible-error measures.
//!
//! Camera coordinates are (x, y, z) = (d · right, d · up, d · forward) with d = p − eye; a point
//! projects to pixel coordinates
//! u = (1 + x / (z tan_h)) W / 2, v = (1 − y / (z tan_v)) H / 2 (tan_v = tan(fov / 2),
//! tan_h = aspect · tan_v; v grows downwards, row 0 at the top), and pixel (i, j) is sampled at
//! its centre (i + ½, j + ½). 1/z is affine in (u, v), so depth is interpolated as 1/z
//! (perspective-correct).
//!
//! Triangles are clipped against the near plane (z ≥ near) in camera space before projection;
//! samples beyond the far plane are discarded. A pixel centre exactly on an edge belongs to one
//! of the triangles sharing it (a fixed fill rule, see `for_each_sample`), so a mesh's
//! triangles cover each centre once. Work is split into bands of rows processed in
//! parallel; each pixel belongs to one band, which draws its triangles in index order, and depth
//! ties go to the lower triangle index, so the image is the same whatever the thread count.

use rayon::prelude::*;

use crate::camera::View;
use crate::math::{Real, Vec3};

/// Rows per parallel work item.
const BAND: usize = 8;

/// Depth, normal and triangle buffers of one rasterised view.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    /// Per pixel (row-major, row 0 at the top): depth along `view.forward` (m) of the nearest
    /// surface, `Real::INFINITY` where no triangle covers the pixel centre.
    pub depth: Vec<Real>,
    /// Unit world-space normal of the nearest triangle there, flipped to face the eye (cloth is
    /// two-sided); zero where empty.
    pub normal: Vec<Vec3>,
    /// Index of the nearest triangle, `u32::MAX` where empty.
    pub face: Vec<u32>,
}

impl Image {
    /// True when a triangle covers the centre of `pixel` (row-major index).
    pub fn covered(&self, pixel: usize) -> bool {
        self.face[pixel] != u32::MAX
    }
}

/// A triangle after clipping and projection: pixel coordinates, 1/z per vertex, its mesh
/// triangle, and the inclusive pixel range its bounding box touches.
#[derive(Clone, Copy, Debug)]
struct ScreenTri {
    uv: [[Real; 2]; 3],
    inv_z: [Real; 3],
    face: u32,
    cols: (usize, usize),
    rows: (usize, usize),
}

/// Rasterises `triangles` over `positions` seen by `view` into a `width` × `height` image.
///
/// Perspective projection with the view's vertical fov and aspect (`width / height` is not
/// consulted: a different image aspect stretches the picture); pixel centres sampled; depth
/// interpolated perspective-correctly. Triangles are clipped against the near plane, so one
/// partly behind the eye is drawn in its visible part; samples farther than `view.far` are
/// dropped. Triangles with a non-finite vertex or zero area are skipped. Deterministic: identical
/// output for any thread count; ties in depth go to the lower triangle index.
///
/// # Panics
/// If a triangle indexes outside `positions`, or there are `u32::MAX` triangles or more.
pub fn rasterize(positions: &[Vec3], triangles: &[[usize; 3]], view: &View, width: usize, height: usize) -> Image {
    assert!(triangles.len() < u32::MAX as usize, "rasterize: too many triangles for u32 ids");
    let n_pixels = width * height;
    let mut depth = vec![Real::INFINITY; n_pixels];
    let mut face = vec![u32::MAX; n_pixels];
    let facing: Vec<Option<Vec3>> = triangles.par_iter().map(|t| facing_normal(positions, t, &view.eye)).collect();
    if n_pixels > 0 {
        let screen: Vec<ScreenTri> = triangles
            .par_iter()
            .enumerate()
            .filter(|(f, _)| facing[*f].is_some())
            .flat_map_iter(|(f, t)| project(positions, t, f as u32, view, width, height).into_iter().flatten())
            .collect();
        let bins = bin_by_band(&screen, height);
        depth.par_chunks_mut(BAND * width).zip(face.par_chunks_mut(BAND * width)).zip(&bins).enumerate().for_each(
            |(band, ((depth, face), bin))| {
                for &s in bin {
                    draw(&screen[s as usize], band * BAND, width, view.far, depth, face);
                }
            },
        );
    }
    let normal = face
        .par_iter()
        .map(|&f| if f == u32::MAX { Vec3::zeros() } else { facing[f as usize].unwrap_or_else(Vec3::zeros) })
        .collect();
    Image { width, height, depth, normal, face }
}

/// Unit normal of triangle `t`, flipped so that it points to the eye's side of its plane; None
/// for a degenerate or non-finite triangle.
fn facing_normal(positions: &[Vec3], t: &[usize; 3], eye: &Vec3) -> Option<Vec3> {
    let [a, b, c] = t.map(|i| positions[i]);
    let n = (b - a).cross(&(c - a)).try_normalize(0.0)?;
    if !n.iter().all(|x| x.is_finite()) {
        return None;
    }
    Some(if n.dot(&(eye - a)) < 0.0 { -n } else { n })
}

/// Clips triangle `t` against the near plane (Sutherland–Hodgman, one plane: at most a quad) and
/// projects the result to pixel coordinates: zero, one or two screen triangles (the quad is split
/// along its 0–2 diagonal).
fn project(
    positions: &[Vec3],
    t: &[usize; 3],
    face: u32,
    view: &View,
    width: usize,
    height: usize,
) -> [Option<ScreenTri>; 2] {
    let cam = t.map(|i| {
        let d = positions[i] - view.eye;
        Vec3::new(d.dot(&view.right), d.dot(&view.up), d.dot(&view.forward))
    });
    let mut poly = [Vec3::zeros(); 4];
    let mut n = 0;
    for k in 0..3 {
        let (p, q) = (cam[k], cam[(k + 1) % 3]);
        let (p_in, q_in) = (p.z >= view.near, q.z >= view.near);
        if p_in {
            poly[n] = p;
            n += 1;
        }
        if p_in != q_in {
            // The edge crosses the plane: its point at z = near, interpolated from the inside
            // end so that both triangles sharing the edge get the same bits, and z set exactly.
            let (i, o) = if p_in { (p, q) } else { (q, p) };
            let s = (view.near - i.z) / (o.z - i.z);
            let mut x = i + (o - i) * s;
            x.z = view.near;
            poly[n] = x;
            n += 1;
        }
    }
    let tan_v = view.tan_half_fov;
    let tan_h = view.aspect * tan_v;
    let (w, h) = (width as Real, height as Real);
    let to_screen = |p: &Vec3| [(1.0 + p.x / (p.z * tan_h)) * 0.5 * w, (1.0 - p.y / (p.z * tan_v)) * 0.5 * h];
    let screen_tri = |i: [usize; 3]| {
        let uv = i.map(|k| to_screen(&poly[k]));
        let inv_z = i.map(|k| 1.0 / poly[k].z);
        screen_tri(uv, inv_z, face, width, height)
    };
    match n {
        3 => [screen_tri([0, 1, 2]), None],
        4 => [screen_tri([0, 1, 2]), screen_tri([0, 2, 3])],
        _ => [None, None],
    }
}

/// A projected triangle with its pixel range, or None when it is degenerate, non-finite or
/// covers no pixel centre's bounding box.
fn screen_tri(uv: [[Real; 2]; 3], inv_z: [Real; 3], face: u32, width: usize, height: usize) -> Option<ScreenTri> {
    if !uv.iter().flatten().chain(&inv_z).all(|x| x.is_finite()) || orient(uv[0], uv[1], uv[2]) == 0.0 {
        return None;
    }
    let cols = pixel_range(uv.map(|p| p[0]), width)?;
    let rows = pixel_range(uv.map(|p| p[1]), height)?;
    Some(ScreenTri { uv, inv_z, face, cols, rows })
}

/// The inclusive range of pixels along one axis whose centres k + ½ lie within the coordinates'
/// span, clamped to [0, n − 1]; None when empty.
fn pixel_range(c: [Real; 3], n: usize) -> Option<(usize, usize)> {
    let lo = (c[0].min(c[1]).min(c[2]) - 0.5).ceil().max(0.0);
    let hi = (c[0].max(c[1]).max(c[2]) - 0.5).floor().min(n as Real - 1.0);
    (lo <= hi).then_some((lo as usize, hi as usize))
}

/// Screen triangles per band of `BAND` rows, in increasing index.
fn bin_by_band(screen: &[ScreenTri], height: usize) -> Vec<Vec<u32>> {
    let mut bins = vec![Vec::new(); height.div_ceil(BAND)];
    for (s, tri) in screen.iter().enumerate() {
        for bin in &mut bins[tri.rows.0 / BAND..=tri.rows.1 / BAND] {
            bin.push(s as u32);
        }
    }
    bins
}

/// Draws `tri` into one band (rows from `row0`) of the depth and face buffers.
fn draw(tri: &ScreenTri, row0: usize, width: usize, far: Real, depth: &mut [Real], face: &mut [u32]) {
    let rows = tri.rows.0.max(row0)..=tri.rows.1.min(row0 + depth.len() / width - 1);
    for_each_sample(tri, rows, far, |i, j, z| {
        let k = (j - row0) * width + i;
        if z < depth[k] || (z == depth[k] && tri.face < face[k]) {
            depth[k] = z;
            face[k] = tri.face;
        }
    });
}

/// Calls `f(column, row, depth)` for every pixel centre of `rows` inside `tri` and not beyond
/// `far`.
fn for_each_sample(
    tri: &ScreenTri,
    rows: std::ops::RangeInclusive<usize>,
    far: Real,
    mut f: impl FnMut(usize, usize, Real),
) {
    let [a, b, c] = tri.uv;
    // A centre exactly on edge k counts when the triangle lies on the positive side of the edge
    // taken in its fixed endpoint order (`edge`): the two triangles sharing an edge lie on
    // opposite sides, so exactly one of them takes the centre. This is "the triangle holding
    // p + δ" for the fixed infinitesimal δ = (−ε², ε), so a centre on a shared vertex goes to
    // one triangle of its fan too (a top-left-style fill rule).
    let ties = [(b, c, a), (c, a, b), (a, b, c)].map(|(p, q, r)| {
        let (lo, hi) = if (p[0], p[1]) <= (q[0], q[1]) { (p, q) } else { (q, p) };
        orient(lo, hi, r) > 0.0
    });
    for j in rows {
        for i in tri.cols.0..=tri.cols.1 {
            let p = [i as Real + 0.5, j as Real + 0.5];
            // Edge functions: e_k is twice the signed area opposite vertex k.
            let e = [edge(b, c, p), edge(c, a, p), edge(a, b, p)];
            let sum = e[0] + e[1] + e[2];
            let inside = (0..3).all(|k| e[k] * sum > 0.0 || (e[k] == 0.0 && ties[k]));
            if !inside || sum == 0.0 {
                continue;
            }
            // Screen barycentrics e_k / Σe; 1/z is affine in screen space.
            let inv_z = (e[0] * tri.inv_z[0] + e[1] * tri.inv_z[1] + e[2] * tri.inv_z[2]) / sum;
            let z = 1.0 / inv_z;
            if z <= far {
                f(i, j, z);
            }
        }
    }
}

/// Pixel centres each triangle covers whether or not something is in front of it (no depth
/// test; same clipping and sampling as `rasterize`): the denominator of a triangle's visible
/// pixel fraction.
///
/// # Panics
/// As `rasterize`.
pub fn coverage(positions: &[Vec3], triangles: &[[usize; 3]], view: &View, width: usize, height: usize) -> Vec<u32> {
    assert!(triangles.len() < u32::MAX as usize, "coverage: too many triangles for u32 ids");
    triangles
        .par_iter()
        .enumerate()
        .map(|(f, t)| {
            if width * height == 0 || facing_normal(positions, t, &view.eye).is_none() {
                return 0;
            }
            let mut n = 0;
            for s in project(positions, t, f as u32, view, width, height).iter().flatten() {
                for_each_sample(s, s.rows.0..=s.rows.1, view.far, |_, _, _| n += 1);
            }
            n
        })
        .collect()
}

/// Area-weighted vertex normals: per vertex, Σ (b − a) × (c − a) over its triangles,
/// normalised (zero for a vertex without area) — the `vn` a frame OBJ carries
/// (`Mesh::node_normals`), which a renderer interpolates.
pub fn vertex_normals(positions: &[Vec3], triangles: &[[usize; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i]);
        let area_normal = (b - a).cross(&(c - a));
        for &i in t {
            n[i] += area_normal;
        }
    }
    n.iter().map(|v| v.try_normalize(0.0).unwrap_or_else(Vec3::zeros)).collect()
}

/// Per pixel, the shading normal a renderer uses: the vertex normals of the front triangle
/// interpolated (Phong) at the point the pixel centre sees, normalised, and flipped with the
/// image's flat normal so it faces the eye's side; zero where empty, the flat normal where the
/// interpolation vanishes.
///
/// The seen point is the pixel ray at the pixel's depth z, in camera coordinates
/// (z (2(i + ½)/W − 1) tan_h, z (1 − 2(j + ½)/H) tan_v, z) (the module's projection inverted);
/// its barycentrics in the 3D triangle make the interpolation perspective-correct.
pub fn shading_normals(
    image: &Image,
    positions: &[Vec3],
    triangles: &[[usize; 3]],
    normals: &[Vec3],
    view: &View,
) -> Vec<Vec3> {
    let (w, h) = (image.width as Real, image.height as Real);
    let tan_v = view.tan_half_fov;
    let tan_h = view.aspect * tan_v;
    (0..image.face.len())
        .into_par_iter()
        .map(|p| {
            let f = image.face[p];
            if f == u32::MAX {
                return Vec3::zeros();
            }
            let t = triangles[f as usize];
            let (i, j, z) = ((p % image.width) as Real, (p / image.width) as Real, image.depth[p]);
            let x = z * (2.0 * (i + 0.5) / w - 1.0) * tan_h;
            let y = z * (1.0 - 2.0 * (j + 0.5) / h) * tan_v;
            let seen = view.eye + view.right * x + view.up * y + view.forward * z;
            let [a, b, c] = t.map(|k| positions[k]);
            let bary = barycentric(&seen, &a, &b, &c);
            let n = t.iter().zip(bary).map(|(&k, w)| normals[k] * w).sum::<Vec3>();
            let flat = image.normal[p];
            match n.try_normalize(0.0) {
                // The geometric normal (b − a) × (c − a) against the flipped flat normal: the same
                // flip for the shading normal.
                Some(n) if (b - a).cross(&(c - a)).dot(&flat) < 0.0 => -n,
                Some(n) => n,
                None => flat,
            }
        })
        .collect()
}

/// Barycentric weights of `p` (projected onto the plane) in triangle (a, b, c) (Ericson 2005,
/// §3.4, by the normal equations); the centroid's for a degenerate triangle.
fn barycentric(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> [Real; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11, d20, d21) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1), v2.dot(&v0), v2.dot(&v1));
    let denom = d00 * d11 - d01 * d01;
    if denom <= 0.0 {
        return [1.0 / 3.0; 3];
    }
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    [1.0 - v - w, v, w]
}

/// Twice the signed area of (a, b, p).
fn orient(a: [Real; 2], b: [Real; 2], p: [Real; 2]) -> Real {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// `orient(a, b, p)` evaluated with the edge's endpoints in a fixed order, so the two triangles
/// sharing an edge get exactly opposite values and a pixel centre on it is never missed by both.
fn edge(a: [Real; 2], b: [Real; 2], p: [Real; 2]) -> Real {
    if (a[0], a[1]) <= (b[0], b[1]) {
        orient(a, b, p)
    } else {
        -orient(b, a, p)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Eye at the origin looking along +y with z up (right = +x), 90° vertical fov.
    pub(crate) fn view(aspect: Real) -> View {
        View {
            eye: Vec3::zeros(),
            forward: Vec3::y(),
            up: Vec3::z(),
            right: Vec3::x(),
            tan_half_fov: 1.0,
            aspect,
            near: 0.1,
            far: 100.0,
        }
    }

    /// The analytic camera-space ray through the centre of pixel (i, j): the point at depth z is
    /// z · (a, 1, b) in world space for `view(aspect)`.
    fn ray(i: usize, j: usize, width: usize, height: usize, aspect: Real) -> (Real, Real) {
        let a = (2.0 * (i as Real + 0.5) / width as Real - 1.0) * aspect;
        let b = 1.0 - 2.0 * (j as Real + 0.5) / height as Real;
        (a, b)
    }

    fn v(x: Real, y: Real, z: Real) -> Vec3 {
        Vec3::new(x, y, z)
    }

    fn count(image: &Image) -> usize {
        (0..image.face.len()).filter(|&p| image.covered(p)).count()
    }

    /// An `n` × `n` grid over [−1, 1]² in x–z at depth ≈ 2, rippled in y: 2n² triangles.
    pub(crate) fn wavy_grid(n: usize) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        super::super::test_grid(n, n, |s, t| {
            let y = 2.0 + 0.1 * (9.0 * s).sin() * (7.0 * t).cos() + 0.3 * s * t;
            v(2.0 * s - 1.0, y, 2.0 * t - 1.0)
        })
    }

    #[test]
    fn facing_triangle_covers_its_area_in_pixels() {
        let (w, h) = (200, 100);
        // At depth 2 the image spans x ∈ [−4, 4]: 0.04 m per pixel.
        let x = [v(-1.0, 2.0, -1.0), v(1.0, 2.0, -1.0), v(0.0, 2.0, 1.0)];
        let image = rasterize(&x, &[[0, 1, 2]], &view(2.0), w, h);
        let px = 0.04;
        let area = 2.0 / (px * px);
        let perimeter = (2.0 + 2.0 * 5.0_f64.sqrt()) / px;
        let n = count(&image) as Real;
        // Edge pixels may go either way: allow a quarter of them.
        assert!((n - area).abs() < 0.25 * perimeter, "{n} pixels, area {area}");
        assert!(image.face.iter().all(|&f| f == 0 || f == u32::MAX));
    }

    #[test]
    fn depth_is_perspective_correct() {
        let (w, h, aspect) = (200, 100, 2.0);
        // The plane y = 2 + 0.5 x, tilted: the ray z·(a, 1, b) meets it at z = 2 / (1 − 0.5 a).
        let plane = |x: Real, z: Real| v(x, 2.0 + 0.5 * x, z);
        let x = [plane(-3.0, -1.5), plane(3.0, -1.5), plane(0.0, 1.5)];
        let image = rasterize(&x, &[[0, 1, 2]], &view(aspect), w, h);
        for (i, j) in [(100, 50), (60, 60), (140, 70), (99, 49)] {
            let (a, _) = ray(i, j, w, h, aspect);
            let k = j * w + i;
            assert!(image.covered(k), "pixel ({i}, {j})");
            let exact = 2.0 / (1.0 - 0.5 * a);
            assert!((image.depth[k] - exact).abs() < 1e-12, "({i}, {j}): {} vs {exact}", image.depth[k]);
        }
    }

    #[test]
    fn nearer_triangle_wins_and_ties_go_to_the_lower_index() {
        let (w, h) = (64, 32);
        let far = [v(-2.0, 3.0, -2.0), v(2.0, 3.0, -2.0), v(0.0, 3.0, 2.0)];
        let near = [v(-1.0, 2.0, -1.0), v(1.0, 2.0, -1.0), v(0.0, 2.0, 1.0)];
        let x: Vec<Vec3> = far.iter().chain(&near).copied().collect();
        let centre = (h / 2) * w + w / 2;
        // The nearer is drawn second, with the higher index.
        let image = rasterize(&x, &[[0, 1, 2], [3, 4, 5]], &view(2.0), w, h);
        assert_eq!(image.face[centre], 1);
        assert!((image.depth[centre] - 2.0).abs() < 1e-12);
        // The same triangle twice: the lower index wins, whichever order.
        let image = rasterize(&x, &[[3, 4, 5], [5, 3, 4]], &view(2.0), w, h);
        assert!((0..w * h).filter(|&p| image.covered(p)).all(|p| image.face[p] == 0));
    }

    #[test]
    fn same_bits_for_one_and_two_threads() {
        let (x, tris) = wavy_grid(100);
        let mut view = view(16.0 / 9.0);
        view.eye = v(0.1, 1.0, 0.05);
        let render = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| rasterize(&x, &tris, &view, 960, 540))
        };
        let (one, two) = (render(1), render(2));
        assert!(count(&one) > 100_000, "the grid should fill much of the frame");
        assert_eq!(one.face, two.face);
        assert!(one.depth.iter().zip(&two.depth).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(one
            .normal
            .iter()
            .zip(&two.normal)
            .all(|(a, b)| a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits())));
    }

    #[test]
    fn shared_edges_leave_no_gaps() {
        // A closed grid seen head on: every pixel inside its outline is covered.
        let (x, tris) = wavy_grid(37);
        let image = rasterize(&x, &tris, &view(1.0), 300, 300);
        // At depth ≥ 2 the grid spans at most [−0.5, 0.5] of the half-width: pixels 75..225.
        let inner = (110..190).flat_map(|j| (110..190).map(move |i| j * 300 + i));
        assert!(inner.into_iter().all(|p| image.covered(p)));
    }

    #[test]
    fn triangle_behind_the_camera_covers_nothing() {
        let x = [v(-1.0, -2.0, -1.0), v(1.0, -2.0, -1.0), v(0.0, -2.0, 1.0)];
        let image = rasterize(&x, &[[0, 1, 2]], &view(2.0), 64, 32);
        assert_eq!(count(&image), 0);
        assert!(image.depth.iter().all(|d| *d == Real::INFINITY));
        assert!(image.normal.iter().all(|n| *n == Vec3::zeros()));
    }

    #[test]
    fn triangle_through_the_near_plane_is_clipped() {
        let (w, h, aspect) = (200, 100, 2.0);
        // From y = −2 (behind the eye) to y = 2 (in front), in the plane z = −0.5.
        let x = [v(-1.0, 2.0, -0.5), v(1.0, 2.0, -0.5), v(0.0, -2.0, -0.5)];
        let image = rasterize(&x, &[[0, 1, 2]], &view(aspect), w, h);
        assert!(count(&image) > 0);
        let near = view(aspect).near;
        for k in (0..w * h).filter(|&k| image.covered(k)) {
            let (i, j) = (k % w, k / w);
            let (_, b) = ray(i, j, w, h, aspect);
            // The ray z·(a, 1, b) meets z_world = −0.5 at depth −0.5 / b.
            let exact = -0.5 / b;
            assert!(image.depth[k] >= near * (1.0 - 1e-12));
            assert!((image.depth[k] - exact).abs() < 1e-9 * exact, "({i}, {j}): {} vs {exact}", image.depth[k]);
        }
    }

    #[test]
    fn back_facing_normal_is_flipped_toward_the_eye() {
        // Counter-clockwise seen from +y: the geometric normal points away from the eye.
        let x = [v(-1.0, 2.0, -1.0), v(0.0, 2.0, 1.0), v(1.0, 2.0, -1.0)];
        let n = (x[1] - x[0]).cross(&(x[2] - x[0]));
        assert!(n.y > 0.0);
        let image = rasterize(&x, &[[0, 1, 2]], &view(2.0), 64, 32);
        let centre = 16 * 64 + 32;
        assert!(image.covered(centre));
        assert_eq!(image.normal[centre], v(0.0, -1.0, 0.0));
        // The other winding already faces the eye.
        let image = rasterize(&x, &[[0, 2, 1]], &view(2.0), 64, 32);
        assert_eq!(image.normal[centre], v(0.0, -1.0, 0.0));
    }
}
