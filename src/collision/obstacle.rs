//! Obstacles as the collision stage sees them: a triangle mesh with fixed topology whose
//! world-space vertex positions are a function of time.
//!
//! World positions are `motion(t) ∘ transform` applied to the local positions: the static scene
//! `transform` first, then the keyframed `motion` (as in the scene format: "rigid motion applied
//! after `transform`"). Local positions are fixed, except for a per-frame OBJ sequence, whose
//! frames are interpolated linearly in time and held outside their range.
//!
//! Analytic shapes are meshed at load, inscribed in the true surface (vertices on it), fine
//! enough that the chordal error (the largest gap between a face and the surface) is at most
//! `CHORDAL_TOLERANCE` × radius, with outward faces. An OBJ keeps the orientation its file
//! gives: its normals say which side is outside, so a closed mesh whose normals face inward
//! (a shell that holds the cloth inside, ARCSim's `sphere-inv.obj`) keeps them. Only faces that
//! disagree with their neighbours are turned, to the orientation that most of the component's
//! area has in the file (`orient_consistently`).
//!
//! An obstacle is present during its `Window` only (`present_at`).

use std::collections::HashMap;

use super::shape::{MeshSequence, Obstacle, ObstacleShape, Window};
use crate::math::motion::{Motion, Transform};
use crate::math::{Real, Vec3};

/// Largest chordal error of a meshed sphere or capsule, relative to its radius.
pub const CHORDAL_TOLERANCE: Real = 0.005;

/// An obstacle ready for collision handling. Infinite mass: it moves as scripted.
#[derive(Clone, Debug)]
pub struct ObstacleBody {
    pub name: String,
    /// Vertex indices per face, counter-clockwise seen from outside.
    triangles: Vec<[usize; 3]>,
    shape: LocalShape,
    transform: Transform,
    motion: Option<Motion>,
    window: Window,
}

#[derive(Clone, Debug)]
enum LocalShape {
    Rigid(Vec<Vec3>),
    /// `frames[k]` at time `start_time + k / fps`.
    Sequence {
        frames: Vec<Vec<Vec3>>,
        start_time: Real,
        fps: Real,
    },
}

impl ObstacleBody {
    pub fn new(o: &Obstacle) -> Self {
        let (shape, triangles) = match &o.shape {
            ObstacleShape::Mesh(d) => {
                let mut tris: Vec<[usize; 3]> = d.triangles.iter().map(|t| t.map(|c| c.v)).collect();
                orient_consistently(&mut tris, &d.positions);
                (LocalShape::Rigid(d.positions.clone()), tris)
            }
            ObstacleShape::Sequence(s) => sequence_shape(s),
            ObstacleShape::Sphere { radius } => rigid(sphere_mesh(*radius, CHORDAL_TOLERANCE)),
            ObstacleShape::Plane { size } => rigid(plane_mesh(*size)),
            ObstacleShape::Box { size } => rigid(box_mesh(*size)),
            ObstacleShape::Capsule { radius, length } => rigid(capsule_mesh(*radius, *length, CHORDAL_TOLERANCE)),
        };
        ObstacleBody {
            name: o.name.clone(),
            triangles,
            shape,
            transform: o.transform,
            motion: o.motion.clone(),
            window: o.window,
        }
    }

    /// Whether the obstacle is present at `t` (its window; ARCSim's obstacle `start_time` and
    /// `end_time`).
    pub fn present_at(&self, t: Real) -> bool {
        self.window.contains(t)
    }

    /// Whether the obstacle is ever absent.
    pub fn has_window(&self) -> bool {
        !self.window.is_always()
    }

    /// Faces as vertex indices into `positions_at(t)`; counter-clockwise seen from outside.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    pub fn vertex_count(&self) -> usize {
        match &self.shape {
            LocalShape::Rigid(p) => p.len(),
            LocalShape::Sequence { frames, .. } => frames[0].len(),
        }
    }

    /// True when the obstacle never moves or deforms (its signed distance field, once built,
    /// holds at every time: `CollisionWorld::with_sdf`).
    pub fn is_static(&self) -> bool {
        self.motion.is_none() && matches!(self.shape, LocalShape::Rigid(_))
    }

    /// The local-to-world transform at `t`: `motion(t) ∘ transform`.
    pub fn transform_at(&self, t: Real) -> Transform {
        match &self.motion {
            Some(m) => m.eval(t).compose(&self.transform),
            None => self.transform,
        }
    }

    /// Local (untransformed) vertex positions at `t`.
    pub fn local_positions_at(&self, t: Real) -> Vec<Vec3> {
        match &self.shape {
            LocalShape::Rigid(p) => p.clone(),
            LocalShape::Sequence { frames, start_time, fps } => interpolate_frames(frames, (t - start_time) * fps),
        }
    }

    /// World-space vertex positions at `t`.
    pub fn positions_at(&self, t: Real) -> Vec<Vec3> {
        let tf = self.transform_at(t);
        let mut p = self.local_positions_at(t);
        p.iter_mut().for_each(|x| *x = tf.apply(x));
        p
    }

    /// Vertex velocities over the step `[t0, t1]`: (x(t1) − x(t0)) / (t1 − t0), so that
    /// `x(t0) + h v = x(t1)` exactly as CCD sees the step.
    pub fn velocities(&self, t0: Real, t1: Real) -> Vec<Vec3> {
        let (x0, x1) = (self.positions_at(t0), self.positions_at(t1));
        let inv_h = 1.0 / (t1 - t0);
        x0.iter().zip(&x1).map(|(a, b)| (b - a) * inv_h).collect()
    }
}

fn rigid((positions, triangles): (Vec<Vec3>, Vec<[usize; 3]>)) -> (LocalShape, Vec<[usize; 3]>) {
    (LocalShape::Rigid(positions), triangles)
}

fn sequence_shape(s: &MeshSequence) -> (LocalShape, Vec<[usize; 3]>) {
    let mut tris: Vec<[usize; 3]> = s.mesh.triangles.iter().map(|t| t.map(|c| c.v)).collect();
    orient_consistently(&mut tris, &s.frames[0]);
    let shape = LocalShape::Sequence { frames: s.frames.clone(), start_time: s.start_time, fps: s.fps };
    (shape, tris)
}

/// Positions at fractional frame `s`: linear between `frames[⌊s⌋]` and the next, held outside.
fn interpolate_frames(frames: &[Vec<Vec3>], s: Real) -> Vec<Vec3> {
    let last = frames.len() - 1;
    if last == 0 || s.is_nan() || s <= 0.0 {
        return frames[0].clone();
    }
    if s >= last as Real {
        return frames[last].clone();
    }
    let k = (s.floor() as usize).min(last - 1);
    let w = s - k as Real;
    frames[k].iter().zip(&frames[k + 1]).map(|(a, b)| a * (1.0 - w) + b * w).collect()
}

/// Makes face orientations agree across every manifold edge, component by component: a
/// breadth-first pass from the component's first face turns each neighbour that traverses a
/// shared edge the same way; then, if the faces this turned hold more of the component's area
/// than those it kept, the whole component is turned back. So a consistent file is left as it
/// is (inward normals included), and an inconsistent one takes the orientation most of its area
/// has in the file.
pub fn orient_consistently(tris: &mut [[usize; 3]], positions: &[Vec3]) {
    let mut edge_faces: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edge_faces.entry((a.min(b), a.max(b))).or_default().push(f);
        }
    }
    let area = |t: &[usize; 3]| (positions[t[1]] - positions[t[0]]).cross(&(positions[t[2]] - positions[t[0]])).norm();
    let mut seen = vec![false; tris.len()];
    let mut turned = vec![false; tris.len()];
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..tris.len() {
        if seen[seed] {
            continue;
        }
        seen[seed] = true;
        queue.push_back(seed);
        let mut members = vec![seed];
        while let Some(f) = queue.pop_front() {
            for k in 0..3 {
                let (a, b) = (tris[f][k], tris[f][(k + 1) % 3]);
                let faces = &edge_faces[&(a.min(b), a.max(b))];
                if faces.len() != 2 {
                    continue;
                }
                let g = if faces[0] == f { faces[1] } else { faces[0] };
                if seen[g] {
                    continue;
                }
                // A consistent neighbour traverses the shared edge as b → a.
                if (0..3).any(|j| tris[g][j] == a && tris[g][(j + 1) % 3] == b) {
                    tris[g].swap(1, 2);
                    turned[g] = true;
                }
                seen[g] = true;
                members.push(g);
                queue.push_back(g);
            }
        }
        let (mut kept_area, mut turned_area) = (0.0, 0.0);
        for &f in &members {
            match turned[f] {
                true => turned_area += area(&tris[f]),
                false => kept_area += area(&tris[f]),
            }
        }
        if turned_area > kept_area {
            members.iter().for_each(|&f| tris[f].swap(1, 2));
        }
    }
}

/// Signed volume enclosed by the faces (divergence theorem): Σ a · (b × c) / 6.
pub fn signed_volume<'a>(tris: impl IntoIterator<Item = &'a [usize; 3]>, x: &[Vec3]) -> Real {
    tris.into_iter().map(|t| x[t[0]].dot(&x[t[1]].cross(&x[t[2]]))).sum::<Real>() / 6.0
}

/// An icosphere: the icosahedron subdivided (midpoints pushed onto the sphere) until its
/// chordal error is at most `tol · radius`.
pub fn sphere_mesh(radius: Real, tol: Real) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let phi = (1.0 + 5.0_f64.sqrt()) / 2.0;
    let mut x: Vec<Vec3> = [
        (-1.0, phi, 0.0),
        (1.0, phi, 0.0),
        (-1.0, -phi, 0.0),
        (1.0, -phi, 0.0),
        (0.0, -1.0, phi),
        (0.0, 1.0, phi),
        (0.0, -1.0, -phi),
        (0.0, 1.0, -phi),
        (phi, 0.0, -1.0),
        (phi, 0.0, 1.0),
        (-phi, 0.0, -1.0),
        (-phi, 0.0, 1.0),
    ]
    .iter()
    .map(|&(a, b, c)| Vec3::new(a, b, c).normalize())
    .collect();
    #[rustfmt::skip]
    let mut tris: Vec<[usize; 3]> = vec![
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
        [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
        [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ];
    // Icosphere faces are acute, so a face's farthest point from the sphere is its circumcentre,
    // at distance 1 − (plane offset) on the unit sphere.
    let error = |x: &[Vec3], tris: &[[usize; 3]]| {
        tris.iter()
            .map(|t| {
                let n = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]])).normalize();
                1.0 - n.dot(&x[t[0]])
            })
            .fold(0.0, Real::max)
    };
    while error(&x, &tris) > tol {
        let mut midpoint: HashMap<(usize, usize), usize> = HashMap::new();
        let mut mid = |a: usize, b: usize, x: &mut Vec<Vec3>| {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                x.push((x[a] + x[b]).normalize());
                x.len() - 1
            })
        };
        let mut next = Vec::with_capacity(4 * tris.len());
        for &[a, b, c] in &tris {
            let (ab, bc, ca) = (mid(a, b, &mut x), mid(b, c, &mut x), mid(c, a, &mut x));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    (x.iter().map(|p| p * radius).collect(), tris)
}

/// A `size[0]` × `size[1]` rectangle in the local xy plane, centred, normal +z.
pub fn plane_mesh(size: [Real; 2]) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let (w, h) = (0.5 * size[0], 0.5 * size[1]);
    let x = vec![Vec3::new(-w, -h, 0.0), Vec3::new(w, -h, 0.0), Vec3::new(w, h, 0.0), Vec3::new(-w, h, 0.0)];
    (x, vec![[0, 1, 2], [0, 2, 3]])
}

/// An axis-aligned box of full extents `size`, centred: 8 vertices, 12 outward faces.
pub fn box_mesh(size: [Real; 3]) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let h = Vec3::from(size) * 0.5;
    // Vertex i has coordinate signs from its bits: x from bit 0, y from bit 1, z from bit 2.
    let x = (0..8)
        .map(|i| {
            let s = |bit: usize| if i >> bit & 1 == 1 { 1.0 } else { -1.0 };
            Vec3::new(s(0) * h.x, s(1) * h.y, s(2) * h.z)
        })
        .collect();
    #[rustfmt::skip]
    let tris = vec![
        [0, 2, 3], [0, 3, 1], // −z
        [4, 5, 7], [4, 7, 6], // +z
        [0, 1, 5], [0, 5, 4], // −y
        [2, 6, 7], [2, 7, 3], // +y
        [0, 4, 6], [0, 6, 2], // −x
        [1, 3, 7], [1, 7, 5], // +x
    ];
    (x, tris)
}

/// A capsule along local z: hemisphere centres at z = ±length/2, joined by a cylinder. A
/// latitude–longitude mesh whose cells span at most Δ = √2 · acos(1 − tol) in azimuth and
/// polar angle, so each triangle's circumradius (≤ half its diagonal, Δ/√2) keeps the chordal
/// error r (1 − cos(Δ/√2)) ≤ tol · r.
pub fn capsule_mesh(radius: Real, length: Real, tol: Real) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    use std::f64::consts::{FRAC_PI_2, TAU};
    let step = std::f64::consts::SQRT_2 * (1.0 - tol).acos();
    let n = ((TAU / step).ceil() as usize).div_ceil(4) * 4;
    let m = (FRAC_PI_2 / step).ceil() as usize;
    let half = 0.5 * length;
    // Rings from north to south as (z, ring radius); the equator is shared when length is 0.
    let mut rings: Vec<(Real, Real)> = Vec::new();
    for i in 1..=m {
        let theta = FRAC_PI_2 * i as Real / m as Real;
        rings.push((half + radius * theta.cos(), radius * theta.sin()));
    }
    let south_start = if length > 0.0 { m } else { m - 1 };
    for i in (1..=south_start).rev() {
        let theta = FRAC_PI_2 * i as Real / m as Real;
        rings.push((-half - radius * theta.cos(), radius * theta.sin()));
    }
    let mut x = vec![Vec3::new(0.0, 0.0, half + radius)];
    for &(z, rho) in &rings {
        for j in 0..n {
            let a = TAU * j as Real / n as Real;
            x.push(Vec3::new(rho * a.cos(), rho * a.sin(), z));
        }
    }
    let south = x.len();
    x.push(Vec3::new(0.0, 0.0, -half - radius));
    let ring = |r: usize, j: usize| 1 + r * n + j % n;
    let mut tris = Vec::with_capacity(2 * n * rings.len());
    for j in 0..n {
        tris.push([0, ring(0, j), ring(0, j + 1)]);
    }
    for r in 0..rings.len() - 1 {
        for j in 0..n {
            let (u0, u1, l0, l1) = (ring(r, j), ring(r, j + 1), ring(r + 1, j), ring(r + 1, j + 1));
            tris.push([u0, l0, l1]);
            tris.push([u0, l1, u1]);
        }
    }
    let last = rings.len() - 1;
    for j in 0..n {
        tris.push([south, ring(last, j + 1), ring(last, j)]);
    }
    (x, tris)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::motion::Keyframe;
    use std::f64::consts::PI;

    /// Every edge is shared by exactly two faces that traverse it in opposite directions.
    fn assert_closed_consistent(tris: &[[usize; 3]]) {
        let mut directed: HashMap<(usize, usize), usize> = HashMap::new();
        for t in tris {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(count, 1, "edge {a}→{b} used {count} times");
            assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}–{b} is on a boundary");
        }
    }

    /// Analytic signed distance of a capsule along z (a sphere when `half` is 0).
    fn capsule_sdf(p: &Vec3, radius: Real, half: Real) -> Real {
        let axis = Vec3::new(0.0, 0.0, p.z.clamp(-half, half));
        (p - axis).norm() - radius
    }

    /// Largest depth of the mesh below the true surface, sampled on a barycentric grid.
    fn chordal_error(x: &[Vec3], tris: &[[usize; 3]], sdf: impl Fn(&Vec3) -> Real) -> Real {
        let k = 8;
        let mut worst: Real = 0.0;
        for t in tris {
            for i in 0..=k {
                for j in 0..=k - i {
                    let (u, v) = (i as Real / k as Real, j as Real / k as Real);
                    let p = x[t[0]] * (1.0 - u - v) + x[t[1]] * u + x[t[2]] * v;
                    worst = worst.max(-sdf(&p));
                }
            }
        }
        worst
    }

    #[test]
    fn sphere_is_closed_outward_and_within_tolerance() {
        let r = 0.3;
        let (x, tris) = sphere_mesh(r, CHORDAL_TOLERANCE);
        assert_closed_consistent(&tris);
        assert!(x.iter().all(|p| (p.norm() - r).abs() < 1e-12));
        let err = chordal_error(&x, &tris, |p| capsule_sdf(p, r, 0.0));
        assert!(err <= CHORDAL_TOLERANCE * r, "chordal error {err}");
        let (v, exact) = (signed_volume(&tris, &x), 4.0 / 3.0 * PI * r.powi(3));
        // An inscribed mesh loses at most a shell of depth tol·r: 3·tol relative volume.
        assert!(v > 0.0 && (exact - v) / exact <= 3.0 * CHORDAL_TOLERANCE, "{v} vs {exact}");
        assert!(tris.len() <= 2000, "{} faces", tris.len());
    }

    #[test]
    fn capsule_is_closed_outward_and_within_tolerance() {
        for (r, l) in [(0.1, 0.5), (0.2, 0.0)] {
            let (x, tris) = capsule_mesh(r, l, CHORDAL_TOLERANCE);
            assert_closed_consistent(&tris);
            let err = chordal_error(&x, &tris, |p| capsule_sdf(p, r, 0.5 * l));
            assert!(err <= CHORDAL_TOLERANCE * r, "chordal error {err}");
            let v = signed_volume(&tris, &x);
            let exact = PI * r * r * l + 4.0 / 3.0 * PI * r.powi(3);
            assert!(v > 0.0 && (exact - v) / exact <= 3.0 * CHORDAL_TOLERANCE, "{v} vs {exact}");
        }
    }

    #[test]
    fn box_and_plane_are_outward() {
        let (x, tris) = box_mesh([1.0, 2.0, 3.0]);
        assert_eq!(tris.len(), 12);
        assert_closed_consistent(&tris);
        assert!((signed_volume(&tris, &x) - 6.0).abs() < 1e-12);
        // Each face normal points away from the centre.
        for t in &tris {
            let n = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]]));
            assert!(n.dot(&(x[t[0]] + x[t[1]] + x[t[2]])) > 0.0);
        }
        let (x, tris) = plane_mesh([2.0, 1.0]);
        for t in &tris {
            let n = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]]));
            assert!(n.z > 0.0 && n.x == 0.0 && n.y == 0.0);
        }
    }

    #[test]
    fn orientation_is_the_files_repaired_by_majority() {
        let (x, good) = sphere_mesh(1.0, 0.05);
        // Consistently inward (a shell holding cloth inside): kept as it is.
        let inward: Vec<[usize; 3]> = good.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let mut tris = inward.clone();
        orient_consistently(&mut tris, &x);
        assert_eq!(tris, inward);
        assert!(signed_volume(&tris, &x) < 0.0);
        // Inward with a few faces flipped back (the first one among them): the majority wins.
        for flip_first in [false, true] {
            let mut tris = inward.clone();
            for t in tris.iter_mut().skip(usize::from(!flip_first)).step_by(7) {
                t.swap(1, 2);
            }
            orient_consistently(&mut tris, &x);
            assert_closed_consistent(&tris);
            assert!(signed_volume(&tris, &x) < 0.0, "flip_first {flip_first}");
        }
        // Outward with a few faces flipped: outward.
        let mut tris = good.clone();
        for t in tris.iter_mut().step_by(5) {
            t.swap(1, 2);
        }
        orient_consistently(&mut tris, &x);
        assert_closed_consistent(&tris);
        assert!(signed_volume(&tris, &x) > 0.0);
        // An open patch with one face of two flipped: the larger area decides (both equal here,
        // so the first face's orientation stays).
        let (px, mut ptris) = plane_mesh([1.0, 1.0]);
        ptris[1].swap(1, 2);
        orient_consistently(&mut ptris, &px);
        assert_eq!(ptris, plane_mesh([1.0, 1.0]).1);
    }

    fn obstacle(shape: ObstacleShape, motion: Option<Motion>) -> Obstacle {
        Obstacle {
            name: "o".into(),
            shape,
            transform: Transform::new([0.0, 0.0, 1.0], Some([90.0, 0.0, 0.0, 1.0]), 2.0),
            motion,
            window: Default::default(),
        }
    }

    #[test]
    fn positions_follow_transform_then_motion() {
        let key = |time: Real, x: Real| Keyframe { time, transform: Transform::new([x, 0.0, 0.0], None, 1.0) };
        let motion = Motion::new(vec![key(0.0, 0.0), key(1.0, 2.0)]);
        let body = ObstacleBody::new(&obstacle(ObstacleShape::Sphere { radius: 0.5 }, Some(motion)));
        let local = body.local_positions_at(0.0);
        for (t, dx) in [(-1.0, 0.0), (0.0, 0.0), (0.5, 1.0), (1.0, 2.0), (3.0, 2.0)] {
            let x = body.positions_at(t);
            for (p, l) in x.iter().zip(&local) {
                // transform: scale 2, rotate 90° about z, lift by 1; then the motion shifts x.
                let expect = Vec3::new(-2.0 * l.y + dx, 2.0 * l.x, 2.0 * l.z + 1.0);
                assert!((p - expect).norm() < 1e-12, "t = {t}: {p} vs {expect}");
            }
        }
        // Velocity over a step reproduces the step's end positions.
        let (t0, t1) = (0.2, 0.25);
        let (x0, x1, v) = (body.positions_at(t0), body.positions_at(t1), body.velocities(t0, t1));
        for i in 0..x0.len() {
            assert!((x0[i] + v[i] * (t1 - t0) - x1[i]).norm() < 1e-12);
        }
        assert!(!body.is_static());
    }

    #[test]
    fn sequence_interpolates_linearly_and_holds() {
        let (x, tris) = box_mesh([1.0, 1.0, 1.0]);
        let mut obj = crate::io::obj::ObjData { positions: x.clone(), ..Default::default() };
        obj.triangles = tris.iter().map(|t| t.map(|v| crate::io::obj::Corner { v, vt: None })).collect();
        let frames: Vec<Vec<Vec3>> = (0..3).map(|k| x.iter().map(|p| p * (1.0 + k as Real)).collect()).collect();
        let seq = MeshSequence { mesh: obj, frames: frames.clone(), start_time: 0.5, fps: 10.0 };
        let mut o = obstacle(ObstacleShape::Sequence(seq), None);
        o.transform = Transform::default();
        let body = ObstacleBody::new(&o);
        assert!(!body.is_static());
        assert_eq!(body.triangles(), &tris[..]);
        let half = body.positions_at(0.55);
        for i in 0..x.len() {
            assert!((half[i] - 0.5 * (frames[0][i] + frames[1][i])).norm() < 1e-12);
        }
        assert_eq!(body.positions_at(0.0), frames[0]);
        assert_eq!(body.positions_at(0.8), frames[2]);
        assert_eq!(body.positions_at(9.0), frames[2]);
    }
}
