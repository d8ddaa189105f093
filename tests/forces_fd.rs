//! Finite-difference checks of every force kernel (DESIGN.md "How the code should read" 4):
//! gradients against central differences of the energy, exact Hessians against central
//! differences of the gradient, at shrinking ε, showing the O(ε²) rate of central differences.
//! Also: rigid motions give zero elastic force, and the PSD projections are PSD and agree with
//! the exact Hessian where nothing needs projecting. Soft handles' springs (`forces::handle`)
//! are checked the same way.

mod common;

use common::fd::{fd_errors, max_abs, FdErrors};
use common::Rng;
use nalgebra::{SMatrix, SVector, UnitQuaternion};
use viewcloth::forces::bending::{bending, dihedral_angle, BendingRest};
use viewcloth::forces::handle::{anchor_spring, glue_spring, Spring};
use viewcloth::forces::membrane::{membrane, MembraneRest, MembraneStiffness};
use viewcloth::forces::wind::{wind_face, Wind};
use viewcloth::forces::{edge_angles, Projection, RestState};
use viewcloth::math::dual::V3;
use viewcloth::math::{Mat3, Real, Vec2, Vec3};

/// A uniformly random axis (away from the origin) and an angle in [−3, 3) rad.
fn rotation(rng: &mut Rng) -> UnitQuaternion<Real> {
    let axis = loop {
        let a = rng.vec();
        if a.norm() > 0.1 {
            break a;
        }
    };
    UnitQuaternion::from_scaled_axis(axis.normalize() * rng.range(-3.0, 3.0))
}

/// The step sizes, relative to the element's length scale.
const EPS: [Real; 3] = [1e-2, 1e-3, 1e-4];
/// Below this relative error, roundoff (not truncation) dominates: no rate can be seen.
const ROUNDOFF_FLOOR: Real = 1e-8;

/// Asserts that central-difference errors (at the `EPS` steps) shrink at the O(ε²) rate:
/// each tenfold smaller ε divides the error by more than 30, unless the error is already
/// below the roundoff floor relative to `scale`. The finest error must be small in any case.
fn assert_second_order(what: &str, errors: &[Real], scale: Real) {
    let rel: Vec<String> = errors.iter().map(|e| format!("{:.3e}", e / scale)).collect();
    let rel_of = |i: usize| errors[i] / scale;
    for i in 1..errors.len() {
        assert!(
            rel_of(i) < ROUNDOFF_FLOOR || rel_of(i - 1) / rel_of(i) > 30.0,
            "{what}: relative FD errors {rel:?} (ε = {EPS:?}) do not shrink like ε²"
        );
    }
    assert!(rel_of(errors.len() - 1) < 1e-6, "{what}: relative FD errors {rel:?} do not converge");
}

/// FD check of `grad` against `energy` and of `hess` against `grad`, around `x`, with steps
/// `EPS · len`. Returns the relative errors at the finest step (for the log).
fn check_fd<const N: usize>(
    what: &str,
    x: &SVector<Real, N>,
    len: Real,
    f: impl Fn(&SVector<Real, N>) -> (Real, SVector<Real, N>, SMatrix<Real, N, N>),
) {
    let FdErrors { gradient: grad_err, hessian: hess_err, g, h } = fd_errors(x, EPS.map(|e| e * len), f);
    // Scales: the derivative's own size, or what a unit change over the element would give.
    let g_scale = max_abs(&g).max(max_abs(&h) * len);
    let h_scale = max_abs(&h);
    assert!(g_scale > 0.0 && h_scale > 0.0, "{what}: zero derivatives");
    assert_second_order(&format!("{what}: gradient"), &grad_err, g_scale);
    assert_second_order(&format!("{what}: Hessian"), &hess_err, h_scale);
}

fn assert_symmetric<const N: usize>(what: &str, h: &SMatrix<Real, N, N>) {
    let asym = max_abs(&(h - h.transpose()));
    assert!(asym <= 1e-12 * max_abs(h), "{what}: Hessian not symmetric ({asym:e})");
}

/// Smallest eigenvalue ≥ −1e-9 · ‖H‖.
fn assert_psd<const N: usize>(what: &str, h: &SMatrix<Real, N, N>) {
    let sym = nalgebra::DMatrix::from_iterator(N, N, (0.5 * (h + h.transpose())).iter().copied());
    let min = sym.symmetric_eigen().eigenvalues.min();
    let norm = h.norm();
    assert!(min >= -1e-9 * norm, "{what}: PSD Hessian has eigenvalue {min:e} (norm {norm:e})");
}

/// Smallest eigenvalue of the symmetric part.
fn min_eigenvalue<const N: usize>(h: &SMatrix<Real, N, N>) -> Real {
    let sym = nalgebra::DMatrix::from_iterator(N, N, (0.5 * (h + h.transpose())).iter().copied());
    sym.symmetric_eigen().eigenvalues.min()
}

// ---------------------------------------------------------------------------------------------
// Membrane

const ANISO: MembraneStiffness = MembraneStiffness { k11: 2000.0, k12: 150.0, k22: 700.0, k33: 40.0 };

/// A random well-shaped material-space triangle, counter-clockwise, edges of order `s`.
fn random_rest_triangle(rng: &mut Rng, s: Real) -> [Vec2; 3] {
    loop {
        let u = [0, 1, 2].map(|_| Vec2::new(rng.range(-s, s), rng.range(-s, s)));
        let (a, b) = (u[1] - u[0], u[2] - u[0]);
        let area = 0.5 * (a.x * b.y - a.y * b.x);
        let longest = a.norm().max(b.norm()).max((u[2] - u[1]).norm());
        // Aspect bounded away from slivers, and counter-clockwise.
        if area > 0.15 * longest * longest {
            return u;
        }
    }
}

/// World positions x = R (F u) + t with F = diag(s₁, s₂) in a rotated material frame, plus
/// noise: `stretch` picks the principal stretches.
fn deformed(rng: &mut Rng, u: &[Vec2; 3], s: (Real, Real), noise: Real) -> [Vec3; 3] {
    let phi = rng.range(0.0, std::f64::consts::TAU);
    let (c, si) = (phi.cos(), phi.sin());
    let r = rotation(rng);
    let t = rng.vec();
    u.map(|p| {
        // Rotate the material frame by φ, stretch, rotate back: F symmetric with stretches s.
        let q = Vec2::new(c * p.x + si * p.y, -si * p.x + c * p.y);
        let q = Vec2::new(s.0 * q.x, s.1 * q.y);
        let q = Vec2::new(c * q.x - si * q.y, si * q.x + c * q.y);
        r * Vec3::new(q.x, q.y, 0.0) + t + rng.vec() * noise
    })
}

fn stack3(x: &[Vec3; 3]) -> SVector<Real, 9> {
    SVector::<Real, 9>::from_fn(|r, _| x[r / 3][r % 3])
}

fn unstack3(x: &SVector<Real, 9>) -> [Vec3; 3] {
    std::array::from_fn(|i| Vec3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2]))
}

#[test]
fn membrane_gradient_and_hessian_match_finite_differences() {
    let mut rng = Rng(1);
    // Principal stretches: tension, compression in both directions, mixed, near rest, and
    // strongly compressed (the indefinite regime).
    let states = [(1.2, 1.1), (0.8, 0.9), (1.3, 0.7), (1.0, 1.0), (0.4, 0.5), (1.05, 0.3)];
    for trial in 0..6 {
        for &s in &states {
            let u = random_rest_triangle(&mut rng, 0.05);
            let rest = MembraneRest::new(u).expect("well-shaped rest triangle");
            let k = MembraneStiffness {
                k11: ANISO.k11 * rng.range(0.5, 2.0),
                k12: ANISO.k12 * rng.range(0.0, 1.0),
                k22: ANISO.k22 * rng.range(0.5, 2.0),
                k33: ANISO.k33 * rng.range(0.5, 2.0),
            };
            let x = deformed(&mut rng, &u, s, 0.01);
            let len = (u[1] - u[0]).norm();
            let what = format!("membrane trial {trial}, stretches {s:?}");
            let (_, _, h) = membrane(&x, &rest, &k, Projection::Exact);
            assert_symmetric(&what, &h);
            check_fd(&what, &stack3(&x), len, |y| membrane(&unstack3(y), &rest, &k, Projection::Exact));
        }
    }
}

#[test]
fn membrane_psd_projection() {
    let mut rng = Rng(2);
    let mut saw_indefinite = false;
    for _ in 0..200 {
        let u = random_rest_triangle(&mut rng, 0.05);
        let rest = MembraneRest::new(u).unwrap();
        let s = (rng.range(0.3, 1.4), rng.range(0.3, 1.4));
        let x = deformed(&mut rng, &u, s, 0.005);
        let (e0, g0, h_exact) = membrane(&x, &rest, &ANISO, Projection::Exact);
        let (e1, g1, h_psd) = membrane(&x, &rest, &ANISO, Projection::Psd);
        // The projection changes only the Hessian.
        assert_eq!(e0, e1);
        assert_eq!(g0, g1);
        assert_psd(&format!("membrane stretches {s:?}"), &h_psd);
        assert_symmetric("membrane PSD", &h_psd);
        saw_indefinite |= min_eigenvalue(&h_exact) < -1e-6 * h_exact.norm();
    }
    assert!(saw_indefinite, "the test never reached an indefinite exact Hessian");
}

#[test]
fn membrane_psd_equals_exact_under_pure_tension() {
    let mut rng = Rng(3);
    for _ in 0..50 {
        let u = random_rest_triangle(&mut rng, 0.05);
        let rest = MembraneRest::new(u).unwrap();
        // Stretched along the material axes (φ = 0): E₁₂ = 0 and E₁₁, E₂₂ > 0, so the stress
        // S = C ε is positive definite for a non-negative coupling.
        let s = (rng.range(1.01, 1.3), rng.range(1.01, 1.3));
        let r = rotation(&mut rng);
        let t = rng.vec();
        let x = u.map(|p| r * Vec3::new(s.0 * p.x, s.1 * p.y, 0.0) + t);
        let (_, _, exact) = membrane(&x, &rest, &ANISO, Projection::Exact);
        let (_, _, psd) = membrane(&x, &rest, &ANISO, Projection::Psd);
        let diff = max_abs(&(exact - psd));
        assert!(diff <= 1e-12 * max_abs(&exact), "tension {s:?}: PSD differs from exact by {diff:e}");
    }
}

#[test]
fn membrane_rigid_motion_gives_zero_force() {
    let mut rng = Rng(4);
    for _ in 0..100 {
        let size = rng.range(0.01, 0.5);
        let u = random_rest_triangle(&mut rng, size);
        let rest = MembraneRest::new(u).unwrap();
        let r = rotation(&mut rng);
        let t = rng.vec() * 10.0;
        let x = u.map(|p| r * Vec3::new(p.x, p.y, 0.0) + t);
        let (e, g, _) = membrane(&x, &rest, &ANISO, Projection::Psd);
        let len = (u[1] - u[0]).norm();
        // A force scale: stiffness × edge length; 1e-10 of it is roundoff on |t| ≤ 10.
        let scale = ANISO.k11 * len;
        assert!(
            max_abs(&g) <= 1e-10 * scale * (1.0 + t.norm() / len),
            "rigid motion: membrane force {:e} (scale {scale:e})",
            max_abs(&g)
        );
        assert!(e.abs() <= 1e-18 * ANISO.k11 * rest.area * (1.0 + t.norm() / len).powi(2));
    }
}

// ---------------------------------------------------------------------------------------------
// Bending

/// A random hinge with dihedral angle ≈ `theta` (edge along a random direction, wings of
/// random length and position along the edge), rigidly placed.
fn random_hinge(rng: &mut Rng, theta: Real, len: Real) -> [Vec3; 4] {
    let e = Vec3::new(len, 0.0, 0.0);
    let w = |rng: &mut Rng, ang: Real| {
        let h = len * rng.range(0.4, 1.2);
        let along = len * rng.range(-0.2, 1.2);
        Vec3::new(along, h * ang.cos(), h * ang.sin())
    };
    // Wing 2 at angle 0 in the (y, z) plane, wing 3 opposite, rotated by θ.
    let x2 = w(rng, 0.0);
    let x3 = w(rng, std::f64::consts::PI + theta);
    let r = rotation(rng);
    let t = rng.vec();
    [Vec3::zeros(), e, x2, x3].map(|p| r * p + t)
}

fn stack4(x: &[Vec3; 4]) -> SVector<Real, 12> {
    SVector::<Real, 12>::from_fn(|r, _| x[r / 3][r % 3])
}

fn unstack4(x: &SVector<Real, 12>) -> [Vec3; 4] {
    std::array::from_fn(|i| Vec3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2]))
}

fn angle(x: &[Vec3; 4]) -> Real {
    dihedral_angle(&x.map(|p| V3([p.x, p.y, p.z])))
}

#[test]
fn bending_gradient_and_hessian_match_finite_differences() {
    let mut rng = Rng(5);
    // Current angles: strongly bent both ways, moderate, near flat.
    let thetas = [-2.0, -0.7, 0.3, 1.1, 2.4, 1e-3, -2e-4];
    for trial in 0..5 {
        for &theta in &thetas {
            let len = rng.range(0.01, 0.2);
            let x = random_hinge(&mut rng, theta, len);
            let measured = angle(&x);
            // The hinge builder's sign convention need not match; the magnitude must.
            assert!((measured.abs() - theta.abs()).abs() < 1e-9, "hinge built for θ = {theta} measures {measured}");
            for theta0 in [rng.range(-1.5, 1.5), 0.0] {
                let rest = BendingRest { shape: rng.range(1.0, 6.0), theta0 };
                let kb = rng.range(1e-6, 1e-4);
                let what = format!("bending trial {trial}, θ = {measured:.4}, θ̄ = {theta0:.4}");
                let (_, _, h) = bending(&x, &rest, kb, Projection::Exact);
                assert_symmetric(&what, &h);
                check_fd(&what, &stack4(&x), len, |y| bending(&unstack4(y), &rest, kb, Projection::Exact));
            }
        }
    }
}

#[test]
fn bending_psd_projection() {
    let mut rng = Rng(6);
    for _ in 0..200 {
        let theta = rng.range(-2.5, 2.5);
        let len = rng.range(0.01, 0.2);
        let x = random_hinge(&mut rng, theta, len);
        let rest = BendingRest { shape: rng.range(1.0, 6.0), theta0: rng.range(-1.5, 1.5) };
        let (e0, g0, _) = bending(&x, &rest, 1e-5, Projection::Exact);
        let (e1, g1, h) = bending(&x, &rest, 1e-5, Projection::Psd);
        assert_eq!(e0, e1);
        assert_eq!(g0, g1);
        assert_psd(&format!("bending θ = {theta}"), &h);
    }
}

#[test]
fn bending_psd_equals_exact_at_rest_angle() {
    let mut rng = Rng(7);
    for _ in 0..50 {
        let (theta, len) = (rng.range(-2.5, 2.5), rng.range(0.01, 0.2));
        let x = random_hinge(&mut rng, theta, len);
        let rest = BendingRest { shape: rng.range(1.0, 6.0), theta0: angle(&x) };
        let (e, g, exact) = bending(&x, &rest, 1e-5, Projection::Exact);
        let (_, _, psd) = bending(&x, &rest, 1e-5, Projection::Psd);
        assert_eq!(e, 0.0);
        assert_eq!(max_abs(&g), 0.0);
        let diff = max_abs(&(exact - psd));
        assert!(diff <= 1e-14 * max_abs(&exact), "θ = θ̄: PSD differs from exact by {diff:e}");
    }
}

#[test]
fn bending_rigid_motion_gives_zero_force() {
    let mut rng = Rng(8);
    for _ in 0..100 {
        let len = rng.range(0.01, 0.5);
        let theta = rng.range(-2.5, 2.5);
        let x = random_hinge(&mut rng, theta, len);
        let rest = BendingRest { shape: 3.0, theta0: angle(&x) };
        let kb = 1e-5;
        let r = rotation(&mut rng);
        let t = rng.vec() * 10.0;
        let y = x.map(|p| r * p + t);
        let (e, g, h) = bending(&y, &rest, kb, Projection::Psd);
        // Gauss–Newton Hessian 2c ∇θ∇θᵀ gives the force scale of a unit angle change.
        let unit = h.norm().sqrt() * (kb * rest.shape).sqrt();
        let drift = 1e-11 * (1.0 + t.norm() / len);
        assert!(
            max_abs(&g) <= drift * unit,
            "rigid motion: bending force {:e} (unit-angle force {unit:e})",
            max_abs(&g)
        );
        assert!(e <= drift * drift * kb * rest.shape);
    }
}

// ---------------------------------------------------------------------------------------------
// Wind

#[test]
fn wind_velocity_jacobian_matches_finite_differences() {
    let mut rng = Rng(9);
    let mut checked = 0;
    while checked < 60 {
        let x = [0, 1, 2].map(|_| rng.vec() * 0.1);
        let v = [0, 1, 2].map(|_| rng.vec() * 2.0);
        let wind = Wind {
            velocity: rng.vec() * 10.0,
            density: rng.range(0.5, 2.0),
            drag: rng.range(0.0, 0.5),
            implicit: true,
        };
        let n = (x[1] - x[0]).cross(&(x[2] - x[0]));
        let vrel = wind.velocity - (v[0] + v[1] + v[2]) / 3.0;
        let vn = n.normalize().dot(&vrel);
        // |v_n| v_n is not twice differentiable at v_n = 0; stay clear of the kink, and of
        // slivers.
        if vn.abs() < 0.1 || n.norm() < 1e-3 {
            continue;
        }
        checked += 1;
        let (_, dfdv) = wind_face(&x, &v, &wind);
        // Negative semidefinite (it damps): the symmetric part has no positive eigenvalue.
        let lmax = -min_eigenvalue(&(-dfdv));
        assert!(lmax <= 1e-12 * dfdv.norm(), "wind dfdv eigenvalue {lmax:e}");
        let scale = max_abs(&dfdv);
        for j in 0..3 {
            let mut errs = Vec::new();
            for eps in EPS {
                let mut fd = Mat3::zeros();
                for d in 0..3 {
                    let (mut vp, mut vm) = (v, v);
                    vp[j][d] += eps;
                    vm[j][d] -= eps;
                    let (fp, _) = wind_face(&x, &vp, &wind);
                    let (fm, _) = wind_face(&x, &vm, &wind);
                    fd.set_column(d, &((fp - fm) / (2.0 * eps)));
                }
                errs.push(max_abs(&(fd - dfdv)));
            }
            assert_second_order(&format!("wind dfdv, node {j}"), &errs, scale);
        }
    }
}

/// Still air does no positive work on a face (the fault checks count no wind work for it,
/// `sim::checks`): the power f · (v₀ + v₁ + v₂) of the force at any positions and velocities is
/// at most zero, as computed (rounding included), over faces of every size and speeds from
/// mm/s to 100 m/s.
#[test]
fn still_air_does_no_positive_work() {
    let mut rng = Rng(23);
    for _ in 0..100_000 {
        let size = 10f64.powf(rng.range(-3.0, 0.0));
        let speed = 10f64.powf(rng.range(-3.0, 2.0));
        let x = [0, 1, 2].map(|_| rng.vec() * size);
        let v = [0, 1, 2].map(|_| rng.vec() * speed);
        let wind =
            Wind { velocity: Vec3::zeros(), density: rng.range(0.5, 2.0), drag: rng.range(0.0, 0.5), implicit: true };
        let (f, _) = wind_face(&x, &v, &wind);
        let power = f.dot(&(v[0] + v[1] + v[2]));
        assert!(power <= 0.0, "still air did work {power:e} at x {x:?}, v {v:?}");
    }
}

#[test]
fn wind_on_degenerate_face_is_zero_not_nan() {
    let x = [Vec3::zeros(), Vec3::x(), 2.0 * Vec3::x()];
    let wind = Wind { velocity: Vec3::new(5.0, 1.0, 0.0), density: 1.2, drag: 0.1, implicit: true };
    let (f, dfdv) = wind_face(&x, &[Vec3::zeros(); 3], &wind);
    assert!(f.iter().chain(dfdv.iter()).all(|c| c.is_finite()));
}

// ---------------------------------------------------------------------------------------------
// Whole meshes: a rigidly moved rest mesh has zero elastic force.

/// A folded (piecewise-flat) strip: columns on a zig-zag polyline in the xy plane, rows along z,
/// texture coordinates = arc length, so each face is exactly isometric to its material shape
/// and the folds give non-zero rest angles.
fn folded_strip_obj() -> String {
    let cols = [(0.0, 0.0), (0.1, 0.02), (0.2, -0.03), (0.28, 0.05), (0.4, 0.0)];
    let rows = [0.0, 0.07, 0.15, 0.2];
    let mut s = String::new();
    let mut arc = vec![0.0];
    for w in cols.windows(2) {
        let d = ((w[1].0 - w[0].0) as Real).hypot(w[1].1 - w[0].1);
        arc.push(arc.last().unwrap() + d);
    }
    for z in rows {
        for (i, (x, y)) in cols.iter().enumerate() {
            s += &format!("v {x} {y} {z}\nvt {} {z}\n", arc[i]);
        }
    }
    let nc = cols.len();
    for j in 0..rows.len() - 1 {
        for i in 0..nc - 1 {
            let id = |i: usize, j: usize| j * nc + i + 1;
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            s += &format!("f {a}/{a} {b}/{b} {c}/{c}\nf {a}/{a} {c}/{c} {d}/{d}\n");
        }
    }
    s
}

#[test]
fn rigid_motion_of_rest_mesh_gives_zero_elastic_force() {
    let dir = common::temp_dir("strip");
    std::fs::write(dir.join("strip.obj"), folded_strip_obj()).unwrap();
    let json = r#"{"version": 1, "frame_time": 0.04, "frames": 1,
        "cloths": [{"mesh": "strip.obj", "material": {"preset": "denim"}}]}"#;
    let scene =
        viewcloth::scene::load_str(json, &dir.join("strip.json"), &dir, "strip").expect("folded strip scene loads");
    std::fs::remove_dir_all(&dir).ok();
    let mut mesh = scene.mesh;
    let mat = &scene.materials[0];
    let angles = edge_angles(&mesh);
    assert!(angles.iter().any(|a| a.abs() > 0.1), "the strip should have folds");
    let rest = RestState::new(&mesh, |e| angles[e]).unwrap();
    assert!(!rest.hinges.is_empty());

    // Global elastic gradient (membrane + bending), and its scale: stiffness × edge length.
    let gradient = |mesh: &viewcloth::mesh::Mesh| {
        let mut g = vec![Vec3::zeros(); mesh.nodes.len()];
        let mut energy = 0.0;
        for f in 0..mesh.faces.len() {
            let ids = mesh.face_nodes(f);
            let x = ids.map(|n| mesh.nodes[n].x);
            let (e, gl, _) = membrane(&x, &rest.membrane[f], &mat.membrane, Projection::Psd);
            energy += e;
            for (k, &n) in ids.iter().enumerate() {
                g[n] += gl.fixed_rows::<3>(3 * k);
            }
        }
        for hg in &rest.hinges {
            let x = hg.nodes.map(|n| mesh.nodes[n].x);
            let (e, gl, _) = bending(&x, &hg.rest, mat.bending, Projection::Psd);
            energy += e;
            for (k, &n) in hg.nodes.iter().enumerate() {
                g[n] += gl.fixed_rows::<3>(3 * k);
            }
        }
        (energy, g.iter().map(|v| v.norm()).fold(0.0, Real::max))
    };
    let scale = mat.membrane.k11 * 0.1;
    let (e, g) = gradient(&mesh);
    assert!(g <= 1e-11 * scale && e <= 1e-20, "rest mesh: energy {e:e}, force {g:e}");
    let mut rng = Rng(10);
    for _ in 0..10 {
        let r = rotation(&mut rng);
        let t = rng.vec() * 5.0;
        let x0: Vec<Vec3> = mesh.nodes.iter().map(|n| n.x).collect();
        for (n, p) in mesh.nodes.iter_mut().zip(&x0) {
            n.x = r * p + t;
        }
        let (e, g) = gradient(&mesh);
        assert!(g <= 1e-10 * scale && e <= 1e-18, "rigid motion: energy {e:e}, force {g:e} (scale {scale:e})");
        for (n, p) in mesh.nodes.iter_mut().zip(&x0) {
            n.x = *p;
        }
    }
}

#[test]
fn fd_check_detects_a_wrong_hessian() {
    // The harness must not be vacuous: in compression the PSD membrane Hessian is not the
    // derivative of the gradient, and the bending Gauss–Newton one is not either away from θ̄.
    let mut rng = Rng(11);
    let u = random_rest_triangle(&mut rng, 0.05);
    let rest = MembraneRest::new(u).unwrap();
    let x = deformed(&mut rng, &u, (0.5, 0.6), 0.0);
    let len = (u[1] - u[0]).norm();
    let membrane_psd = std::panic::catch_unwind(|| {
        check_fd("membrane PSD", &stack3(&x), len, |y| membrane(&unstack3(y), &rest, &ANISO, Projection::Psd))
    });
    assert!(membrane_psd.is_err(), "FD check accepted the projected membrane Hessian");
    let hinge = random_hinge(&mut rng, 1.0, 0.1);
    let brest = BendingRest { shape: 3.0, theta0: 0.2 };
    let bending_gn = std::panic::catch_unwind(|| {
        check_fd("bending Gauss–Newton", &stack4(&hinge), 0.1, |y| {
            bending(&unstack4(y), &brest, 1e-5, Projection::Psd)
        })
    });
    assert!(bending_gn.is_err(), "FD check accepted the Gauss–Newton bending Hessian");
}

// ---------------------------------------------------------------------------------------------
// Soft handles

#[test]
fn handle_springs_match_finite_differences() {
    let mut rng = Rng(12);
    for _ in 0..30 {
        let k = rng.range(1.0, 1e6);
        let (x, target) = (rng.vec() * 0.3, rng.vec() * 0.3);
        check_fd("anchor spring", &x, 0.1, |y| anchor_spring(y, &target, k));
        let (a, b) = (rng.vec() * 0.3, rng.vec() * 0.3);
        let ab = SVector::<Real, 6>::from_fn(|r, _| if r < 3 { a[r] } else { b[r - 3] });
        let glue = |y: &SVector<Real, 6>| glue_spring(&y.fixed_rows::<3>(0).into(), &y.fixed_rows::<3>(3).into(), k);
        check_fd("glue spring", &ab, 0.1, glue);
        assert_psd("glue spring", &glue(&ab).2);
        // The energy a step's check sums is the kernel's.
        let xs = [a, b];
        let e = Spring::Glue { nodes: [0, 1], k }.energy(&xs);
        assert!((e - 0.5 * k * (b - a).norm_squared()).abs() <= 1e-12 * e.max(1e-30));
        let e = Spring::Anchor { node: 1, target, k }.energy(&xs);
        assert!((e - 0.5 * k * (b - target).norm_squared()).abs() <= 1e-12 * e.max(1e-30));
        // Moving both glued nodes together changes nothing.
        let t = rng.vec();
        let (eg, g, _) = glue_spring(&(a + t), &(b + t), k);
        assert!((eg - glue(&ab).0).abs() <= 1e-9 * eg.max(1e-30) && (g - glue(&ab).1).norm() <= 1e-9 * k);
    }
}
