//! ARCSim compatibility (issue 6): ARCSim's scene files load (directly and converted), `.mot`
//! motions and keyframe velocities follow ARCSim's splines, the measured-material kernels pass
//! their finite-difference checks and reproduce the sample data, and two ARCSim scenes behave as
//! in ARCSim (square: refine while squeezed, coarsen back; sphere: never inside the sphere).
//!
//! The ARCSim data is read from `../shared/arcsim` beside the repository (never copied into it);
//! tests that need it print a SKIP line and pass when it is absent.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::fd::{fd_errors, max_abs, FdErrors};
use common::{temp_dir, Rng};
use nalgebra::{SMatrix, SVector};
use viewcloth::collision::proximity::Law;
use viewcloth::collision::sdf::MeshSdf;
use viewcloth::forces::bending::{bending, bending_energy, dihedral_angle, BendingRest};
use viewcloth::forces::data_driven::{
    bending_stiffness, measured_bending, measured_bending_energy, measured_membrane, measured_membrane_energy,
    stretching_sample, FoldSign, HingeRest, MeasuredData, MeasuredMaterial,
};
use viewcloth::forces::membrane::{membrane, membrane_energy, MembraneRest, MembraneStiffness};
use viewcloth::forces::Projection;
use viewcloth::math::dual::V3;
use viewcloth::math::{Mat2, Real, Vec2, Vec3};
use viewcloth::scene::{self, arcsim};
use viewcloth::sim::Simulation;

fn arcsim_dir(test: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/arcsim");
    if dir.join("conf").is_dir() {
        Some(dir)
    } else {
        eprintln!("SKIP {test}: ARCSim data not found at {}", dir.display());
        None
    }
}

fn confs(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir.join("conf"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    v.sort();
    v
}

// ---------------------------------------------------------------------------------------------
// Scene files

#[test]
fn every_conf_parses_and_check_reports_it_valid() {
    let Some(dir) = arcsim_dir("every_conf_parses_and_check_reports_it_valid") else { return };
    let confs = confs(&dir);
    assert!(confs.len() >= 4, "expected ARCSim's confs, found {confs:?}");
    for conf in &confs {
        let loaded = scene::load_path(conf, None).unwrap_or_else(|e| panic!("{}: {e}", conf.display()));
        assert!(loaded.scene.frames > 0 && !loaded.scene.cloths.is_empty());
        let out = Command::new(env!("CARGO_BIN_EXE_viewcloth")).arg("check").arg(conf).output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "check {}: {}", conf.display(), String::from_utf8_lossy(&out.stderr));
        assert!(stdout.trim_end().ends_with(": ok"), "check {}: {stdout}", conf.display());
    }
}

#[test]
fn confs_read_as_arcsim_reads_them() {
    let Some(dir) = arcsim_dir("confs_read_as_arcsim_reads_them") else { return };
    let conf = |name: &str| scene::load_path(&dir.join("conf").join(name), None).unwrap();

    let sphere = conf("sphere.json");
    let s = &sphere.scene;
    assert_eq!((s.frame_time, s.steps_per_frame, s.frames), (0.04, 8, 250));
    assert_eq!(s.gravity, Vec3::new(0.0, 0.0, -9.8));
    assert_eq!(s.collision.thickness, 5e-3);
    assert_eq!((s.collision.friction, s.collision.self_friction), (0.3, 0.6));
    // ARCSim's still air: density 1, no velocity.
    let wind = s.wind.unwrap();
    assert_eq!((wind.velocity, wind.density), (Vec3::zeros(), 1.0));
    // gray-interlock, thicken 2: density 0.187 × 2.
    assert!((s.materials[0].density - 0.374).abs() < 1e-12);
    assert!(s.materials[0].measured.is_some() && s.cloths[0].flat_rest);
    // Handle on nodes 2 and 3 (the far edge after the translation), released at t = 7.
    assert_eq!(s.handles.len(), 1);
    assert_eq!(s.handles[0].end, 7.0);
    assert_eq!(s.handles[0].anchors[0], Vec3::new(0.5, 0.0, 0.5));
    // The sphere: unit mesh scaled by the motion's 0.1, moving to y = −1.5 at t = 3.
    let ball = &s.obstacles[0];
    assert_eq!(ball.transform_at(0.5).scale, 0.1);
    assert!((ball.transform_at(3.0).translate - Vec3::new(0.0, -1.5, 0.0)).norm() < 1e-12);
    assert!(sphere.warnings.is_empty(), "{:?}", sphere.warnings);
    // ARCSim's remeshing always refines near obstacles (nearobs.cpp, 10 × thickness).
    let remesh = s.cloths[0].remesh.as_ref().unwrap();
    assert!(remesh.sizing.refine_obstacle && remesh.sizing.refine_compression == Some(0.005));

    let square = conf("square.json");
    assert_eq!(square.scene.frames, 325);
    assert_eq!(square.scene.collision.thickness, 1e-3, "ARCSim's default repulsion thickness");
    // ARCSim's own cubic penalty K·a·v³/(6τ): ARCSim's default K = 1e9 here, the conf's own 1e6
    // on sphere.
    assert_eq!(square.scene.collision.stiffness, 1e9);
    assert_eq!(s.collision.stiffness, 1e6);
    assert_eq!((square.scene.collision.penalty, s.collision.penalty), (Law::Cubic, Law::Cubic));
    assert!(square.scene.collision.self_collision, "ARCSim's cloth–cloth contact is on without obstacles too");
    assert!(square.warnings.is_empty(), "{:?}", square.warnings);

    let flag = conf("flag.json");
    assert_eq!(flag.scene.wind.unwrap().velocity, Vec3::new(10.0, 0.0, 0.0));
    assert_eq!(flag.scene.frames, 500, "duration 20 s used as the end time");
    let w = flag.warnings.join("\n");
    assert!(w.contains("duration") && !w.contains("strain_limits"), "{w}");
    assert_eq!(flag.scene.cloths[0].strain_limits, Some([0.95, 1.05]), "strain limiting now runs");

    let dress = conf("dress-blue.json");
    assert_eq!(dress.scene.obstacles.len(), 16, "body0000 … body0015");
    assert!(dress.scene.obstacles.iter().all(|o| o.motion.is_some()));
    assert!(dress.warnings.is_empty(), "{:?}", dress.warnings);
}

#[test]
fn converted_scenes_load_like_their_confs() {
    let Some(dir) = arcsim_dir("converted_scenes_load_like_their_confs") else { return };
    let out = temp_dir("arcsim-convert");
    for conf in confs(&dir) {
        // Into a directory that does not exist yet: convert creates it, paths stay relative.
        let target = out.join("scenes").join(conf.file_name().unwrap());
        let status = Command::new(env!("CARGO_BIN_EXE_viewcloth"))
            .args(["convert".as_ref(), conf.as_os_str(), "--out".as_ref(), target.as_os_str()])
            .output()
            .unwrap();
        assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
        let text = std::fs::read_to_string(&target).unwrap();
        assert!(text.starts_with("{\n  \"version\": 1,"), "{text}");
        assert!(!text.contains("\"mesh\": \"/"), "absolute mesh path in {}:\n{text}", target.display());
        let a = scene::load_path(&conf, None).unwrap().scene;
        let b = scene::load_file(&target).unwrap();
        assert!(scene::load_path(&target, None).unwrap().warnings.is_empty());
        assert_eq!((a.frames, a.steps_per_frame, a.frame_time), (b.frames, b.steps_per_frame, b.frame_time));
        assert_eq!((a.gravity, a.wind, &a.collision), (b.gravity, b.wind, &b.collision));
        assert_eq!(a.materials, b.materials);
        assert_eq!(
            a.mesh.nodes.iter().map(|n| n.x).collect::<Vec<_>>(),
            b.mesh.nodes.iter().map(|n| n.x).collect::<Vec<_>>()
        );
        assert_eq!(a.mesh.faces.len(), b.mesh.faces.len());
        assert_eq!(a.handles.len(), b.handles.len());
        for (ha, hb) in a.handles.iter().zip(&b.handles) {
            assert_eq!((&ha.nodes, ha.start, ha.end), (&hb.nodes, hb.start, hb.end));
            assert_eq!(ha.target(0, 6.3), hb.target(0, 6.3));
        }
        assert_eq!(a.obstacles.len(), b.obstacles.len());
        for (oa, ob) in a.obstacles.iter().zip(&b.obstacles) {
            assert_eq!(oa.transform_at(1.234), ob.transform_at(1.234));
        }
    }
}

#[test]
fn bad_confs_name_the_json_path() {
    let dir = temp_dir("arcsim-bad");
    for sub in ["conf", "meshes", "materials"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    let square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    std::fs::write(dir.join("meshes/m.obj"), square).unwrap();
    let material = r#"{"density": 0.1, "stretching": [[9, 1, 9, 3], [9, 1, 9, 3], [9, 1, 9, 3], [9, 1, 9, 3], [9, 1, 9, 3], [9, 1, 9, 3]],
                       "bending": [[1e-6, 1e-6, 1e-6, 1e-6, 1e-6], [1e-6, 1e-6, 1e-6, 1e-6, 1e-6], [1e-6, 1e-6, 1e-6, 1e-6, 1e-6]]}"#;
    std::fs::write(dir.join("materials/m.json"), material).unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.join("conf").join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let cases = [
        (
            "type.json",
            r#"{"frame_time": 0.04, "frame_steps": 8, "end_time": 1,
                "cloths": [{"mesh": "m.obj", "materials": [{"data": 3}]}]}"#,
            "cloths[0].materials[0].data: expected a string",
        ),
        ("noend.json", r#"{"frame_time": 0.04, "frame_steps": 8, "cloths": []}"#, "end_time"),
        (
            "motion.json",
            r#"// a comment
               {"frame_time": 0.04, "end_frame": 3, "motions": [],
                "cloths": [{"mesh": "m.obj", "materials": [{"data": "x.json"}]}],
                "obstacles": [{"mesh": "s.obj", "motion": 2}]}"#,
            "obstacles[0].motion: expected a motion index",
        ),
        (
            // Found by the scene loader in the converted scene, reported where it is in the conf.
            "scale.json",
            r#"{"frame_time": 0.04, "end_frame": 3,
                "motions": [[{"time": 0}, {"time": 1, "transform": {"scale": -1}}]],
                "cloths": [{"mesh": "meshes/m.obj", "materials": [{"data": "materials/m.json"}]}],
                "handles": [{"nodes": [0], "motion": 0}]}"#,
            "motions[0][1].transform.scale: expected a number ≥ 0",
        ),
    ];
    for (name, text, expected) in cases {
        let path = write(name, text);
        let out = Command::new(env!("CARGO_BIN_EXE_viewcloth")).arg("check").arg(&path).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{name}: one line: {stderr}");
        assert!(stderr.starts_with("error: ") && stderr.contains(expected), "{name}: {stderr}");
    }
}

#[test]
fn plasticity_fields_are_read_unscaled_and_disable_drops_them() {
    let Some(dir) = arcsim_dir("plasticity_fields_are_read_unscaled_and_disable_drops_them") else { return };
    let conf = temp_dir("arcsim-plastic").join("p.json");
    let text = |disable: &str| {
        format!(
            r#"{{"frame_time": 0.04, "frame_steps": 2, "end_frame": 2, "disable": [{disable}],
                "cloths": [{{"mesh": "meshes/square4.obj",
                            "materials": [{{"data": "materials/paper.json", "yield_curv": 200, "weakening": 2}}]}}]}}"#
        )
    };
    std::fs::write(&conf, text("")).unwrap();
    let plastic = scene::load_path(&conf, Some(&dir)).unwrap();
    let p = plastic.scene.materials[0].plasticity.expect("plastic");
    assert_eq!((p.yield_curv, p.weakening), (200.0, 2.0));
    assert!(plastic.warnings.is_empty(), "{:?}", plastic.warnings);
    std::fs::write(&conf, text(r#""plasticity""#)).unwrap();
    assert_eq!(scene::load_path(&conf, Some(&dir)).unwrap().scene.materials[0].plasticity, None);
}

#[test]
fn unsupported_keys_are_one_warning_line_each() {
    let Some(dir) = arcsim_dir("unsupported_keys_are_one_warning_line_each") else { return };
    let conf = temp_dir("arcsim-warn").join("w.json");
    std::fs::write(
        &conf,
        r#"{"frame_time": 0.04, "frame_steps": 2, "end_frame": 2,
            "cloths": [{"mesh": "meshes/square4.obj",
                        "materials": [{"data": "materials/paper.json", "toughness": 3}]}],
            "handles": [{"nodes": [0], "labels": [1]}],
            "magic": {"projection_thickness": 1e-4, "rib_stiffening": 2, "repulsion_thickness": 2e-3},
            "passive_time": 1, "frobnicate": true}"#,
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_viewcloth"))
        .args(["check".as_ref(), conf.as_os_str(), "--base".as_ref(), dir.as_os_str()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    for key in [
        "cloths[0].materials[0].toughness",
        "handles[0].labels",
        "magic.projection_thickness",
        "magic.rib_stiffening",
        "passive_time",
        "frobnicate",
    ] {
        assert_eq!(lines.iter().filter(|l| l.contains(&format!(": {key}: "))).count(), 1, "{key}: {stderr}");
    }
    assert_eq!(lines.len(), 6, "{stderr}");
    assert!(lines.iter().all(|l| l.starts_with("warning: ")), "{stderr}");
}

// ---------------------------------------------------------------------------------------------
// Motions

#[test]
fn mot_bodies_follow_their_frames_and_the_conf_transform() {
    let Some(dir) = arcsim_dir("mot_bodies_follow_their_frames_and_the_conf_transform") else { return };
    let mot = scene::mot::read_mot(&dir.join("meshes/dance-paused.mot")).unwrap();
    assert_eq!(mot.bodies.len(), 16);
    assert!(mot.bodies.iter().all(|b| b.len() == 716));
    let dress = scene::load_path(&dir.join("conf/dress-blue.json"), None).unwrap().scene;
    // motions.transform: translate (0, 0, −1), rotate −90° about z, applied after the body's own.
    let after = viewcloth::math::motion::Transform::new([0.0, 0.0, -1.0], Some([-90.0, 0.0, 0.0, 1.0]), 1.0);
    for (b, frame) in [(0, 0), (3, 100), (15, 715), (7, 333)] {
        let expected = after.compose(&mot.bodies[b][frame]);
        let got = dress.obstacles[b].transform_at(frame as Real / 30.0);
        let p = Vec3::new(0.1, -0.2, 0.3);
        assert!((got.apply(&p) - expected.apply(&p)).norm() < 1e-9, "body {b} frame {frame}");
    }
}

#[test]
fn keyframe_velocities_hold_the_square_still_between_6_and_7_s() {
    let Some(dir) = arcsim_dir("keyframe_velocities_hold_the_square_still_between_6_and_7_s") else { return };
    let square = scene::load_path(&dir.join("conf/square.json"), None).unwrap().scene;
    let h = &square.handles[0];
    let at = |t: Real| h.target(0, t);
    assert_eq!(at(0.5), at(1.0), "held before the first key");
    for t in [6.0, 6.25, 6.5, 6.9, 7.0] {
        assert!((at(t) - at(6.0)).norm() < 1e-12, "t = {t}: {}", at(t) - at(6.0));
    }
    assert!((at(6.0).x - h.anchors[0].x - 0.45).abs() < 1e-12);
    // Zero tangent at t = 6 (given), so the approach is smooth: no overshoot past 0.45.
    assert!((1..60).all(|k| at(1.0 + 5.0 * k as Real / 60.0).x - h.anchors[0].x <= 0.45 + 1e-12));
}

// ---------------------------------------------------------------------------------------------
// Measured materials: finite differences

/// Central differences at shrinking ε: the error must fall like ε² until rounding (ratio ≥ 50 over
/// a factor 10 in ε) or already be at rounding level.
fn assert_second_order(what: &str, errs: &[Real], scale: Real) {
    let rounding = 1e-7 * scale;
    let ok = errs.windows(2).any(|w| w[1] <= w[0] / 50.0 || w[1] <= rounding) || errs[0] <= rounding;
    assert!(ok, "{what}: errors {errs:?} (scale {scale:e}) do not fall like ε²");
}

/// Checks `grad` against central differences of `energy` (when `energy` is a potential) and
/// `hess` against central differences of `grad`, at x.
fn check_fd<const N: usize>(
    what: &str,
    x: &SVector<Real, N>,
    len: Real,
    check_gradient: bool,
    f: impl Fn(&SVector<Real, N>) -> (Real, SVector<Real, N>, SMatrix<Real, N, N>),
) {
    let FdErrors { gradient: ge, hessian: he, g, h } = fd_errors(x, [1e-3, 1e-4, 1e-5].map(|e| e * len), f);
    if check_gradient {
        assert_second_order(&format!("{what}: gradient"), &ge, max_abs(&g).max(max_abs(&h) * len));
    }
    assert_second_order(&format!("{what}: Jacobian"), &he, max_abs(&h));
}

fn assert_psd<const N: usize>(what: &str, h: &SMatrix<Real, N, N>) {
    assert!(max_abs(&(h - h.transpose())) <= 1e-12 * max_abs(h), "{what}: not symmetric");
    let sym = nalgebra::DMatrix::from_iterator(N, N, h.iter().copied());
    let min = sym.symmetric_eigen().eigenvalues.min();
    assert!(min >= -1e-9 * max_abs(h), "{what}: eigenvalue {min:e}");
}

/// gray-interlock's samples (Wang et al. 2011), so that these tests run without ../shared.
const KNIT: MeasuredData = MeasuredData {
    density: 0.187,
    stretching: [
        [16.593832, -14.695990, 34.477123, 36.860302],
        [46.364765, 53.694656, 261.013855, -29.691301],
        [49.285110, 87.596100, 206.373993, 22.768457],
        [123.989220, 105.181770, 365.966217, 44.217571],
        [139.686325, 73.592560, 413.553162, -174.43853],
        [127.443810, 85.848587, 405.872833, 32.238411],
    ],
    bending: [
        [23.191698e-6, 32.932217e-6, 34.406498e-6, 39.014420e-6, 23.382786e-6],
        [24.749964e-6, 18.651314e-6, 16.370552e-6, 25.095791e-6, 8.860165e-6],
        [14.267624e-6, 7.052906e-6, 14.515154e-6, 24.665127e-6, 19.383726e-6],
    ],
};

/// A material whose samples are all equal (like ARCSim's paper): constant stiffness, so the
/// stress derives from a potential.
fn uniform_data() -> MeasuredData {
    MeasuredData { density: 0.1, stretching: [[500.0, 100.0, 400.0, 300.0]; 6], bending: [[4e-4; 5]; 3] }
}

fn stack3(x: &[Vec3; 3]) -> SVector<Real, 9> {
    SVector::from_fn(|r, _| x[r / 3][r % 3])
}
fn unstack3(y: &SVector<Real, 9>) -> [Vec3; 3] {
    std::array::from_fn(|i| Vec3::new(y[3 * i], y[3 * i + 1], y[3 * i + 2]))
}
fn stack4(x: &[Vec3; 4]) -> SVector<Real, 12> {
    SVector::from_fn(|r, _| x[r / 3][r % 3])
}
fn unstack4(y: &SVector<Real, 12>) -> [Vec3; 4] {
    std::array::from_fn(|i| Vec3::new(y[3 * i], y[3 * i + 1], y[3 * i + 2]))
}

/// A triangle with material edges of ~5 cm, deformed by `f` (2 × 2, embedded in 3D and rotated).
fn strained_triangle(f: Mat2, shear_z: Real) -> ([Vec3; 3], MembraneRest) {
    let u = [Vec2::new(0.0, 0.0), Vec2::new(0.05, 0.01), Vec2::new(0.015, 0.045)];
    let rest = MembraneRest::new(u).unwrap();
    let rot = nalgebra::UnitQuaternion::from_scaled_axis(Vec3::new(0.3, -0.2, 0.5));
    let x = u.map(|p| {
        let q = f * p;
        rot * Vec3::new(q.x, q.y, shear_z * p.x)
    });
    (x, rest)
}

/// The grid cell fractions of the strain of `x`, to keep FD probes away from the table's kinks.
fn away_from_grid_lines(x: &[Vec3; 3], rest: &MembraneRest) -> bool {
    let f = viewcloth::forces::membrane::deformation_gradient(x, rest);
    let c = f.transpose() * f;
    let g = [0.5 * (c[(0, 0)] - 1.0) + 0.25, 0.5 * (c[(1, 1)] - 1.0) + 0.25, (0.5 * c[(0, 1)]).abs()];
    g.iter().all(|v| {
        let s = v * 30.0;
        let frac = s - s.floor();
        (0.05..0.95).contains(&frac)
    })
}

#[test]
fn measured_stretching_with_constant_samples_is_a_potential() {
    let mat = MeasuredMaterial::new(&uniform_data(), 1.0, 1.0);
    for (k, f) in [Mat2::new(1.05, 0.02, -0.03, 0.98), Mat2::new(1.1, 0.1, 0.0, 1.2), Mat2::new(0.97, 0.0, 0.05, 1.0)]
        .into_iter()
        .enumerate()
    {
        let (x, rest) = strained_triangle(f, 0.02);
        let what = format!("constant samples, state {k}");
        check_fd(&what, &stack3(&x), 0.05, true, |y| {
            measured_membrane(&unstack3(y), &rest, &mat.stretching, Projection::Exact)
        });
        // Constant stiffness = the orthotropic StVK kernel with k₃₃ = k₃/2 (ARCSim's shear term).
        let k = [1000.0, 200.0, 800.0, 600.0];
        let lin = MembraneStiffness { k11: k[0], k12: k[1], k22: k[2], k33: 0.5 * k[3] };
        let (e0, g0, h0) = membrane(&x, &rest, &lin, Projection::Exact);
        let (e1, g1, h1) = measured_membrane(&x, &rest, &mat.stretching, Projection::Exact);
        assert!((e0 - e1).abs() <= 1e-12 * e0.abs() && max_abs(&(g0 - g1)) <= 1e-12 * max_abs(&g0), "{what}");
        assert!(max_abs(&(h0 - h1)) <= 1e-10 * max_abs(&h0), "{what}");
    }
}

#[test]
fn measured_stretching_jacobian_matches_finite_differences() {
    let mat = MeasuredMaterial::new(&KNIT, 2.0, 1.0);
    let mut tested = 0;
    let mut rng = Rng(11);
    let mut rnd = move || rng.uniform() - 0.5;
    for _ in 0..40 {
        let f = Mat2::new(1.0 + 0.3 * rnd(), 0.2 * rnd(), 0.2 * rnd(), 1.0 + 0.3 * rnd());
        let (x, rest) = strained_triangle(f, 0.05 * rnd());
        if !away_from_grid_lines(&x, &rest) {
            continue;
        }
        tested += 1;
        // Not a potential: only the Jacobian is checked against differences of the gradient.
        check_fd("measured stretching", &stack3(&x), 0.05, false, |y| {
            measured_membrane(&unstack3(y), &rest, &mat.stretching, Projection::Exact)
        });
        // The gradient is ARCSim's stress at the current stiffness: the StVK force with k(G).
        let fdg = viewcloth::forces::membrane::deformation_gradient(&x, &rest);
        let c = fdg.transpose() * fdg;
        let (k, _) = mat.stretching.stiffness(0.5 * (c[(0, 0)] - 1.0), 0.5 * (c[(1, 1)] - 1.0), 0.5 * c[(0, 1)]);
        let lin = MembraneStiffness { k11: k[0], k12: k[1], k22: k[2], k33: 0.5 * k[3] };
        let (_, g_lin, _) = membrane(&x, &rest, &lin, Projection::Psd);
        let (_, g, h_psd) = measured_membrane(&x, &rest, &mat.stretching, Projection::Psd);
        assert!(max_abs(&(g - g_lin)) <= 1e-12 * max_abs(&g));
        assert_psd("measured stretching PSD", &h_psd);
    }
    assert!(tested >= 10, "only {tested} probes away from the table's grid lines");
}

fn hinge(theta: Real) -> [Vec3; 4] {
    // Edge along a direction at 30° from the warp, wings of ~2 cm.
    let e = Vec3::new(0.03, 0.0, 0.0);
    let w1 = Vec3::new(0.01, 0.05, 0.0);
    let w2 = Vec3::new(0.012, -0.045 * theta.cos(), 0.045 * theta.sin());
    [Vec3::zeros(), e, w1, w2]
}

fn hinge_rest(x: &[Vec3; 4]) -> (BendingRest, HingeRest) {
    let l = (x[1] - x[0]).norm();
    let a = 0.5 * l * 0.05 + 0.5 * l * 0.045;
    let du = Vec2::new(l * 0.866, l * 0.5);
    (BendingRest { shape: 3.0 * l * l / a, theta0: 0.1 }, HingeRest::new([du, du], l, a))
}

#[test]
fn measured_bending_with_constant_samples_is_a_potential() {
    let table = [[4e-4; 5]; 3];
    for theta in [0.3, 1.2, 2.5] {
        let x = hinge(theta);
        let (rest, hr) = hinge_rest(&x);
        let what = format!("constant bending, θ-ish {theta}");
        check_fd(&what, &stack4(&x), 0.02, true, |y| {
            measured_bending(&unstack4(y), &rest, &hr, &table, FoldSign::Absolute, Projection::Exact)
        });
        // ke ℓ²/(8A)(θ − θ̄)² is the dihedral kernel's ½ k_b 3ℓ²/A (θ − θ̄)² with k_b = ke/12.
        let (e0, g0, _) = bending(&x, &rest, 4e-4 / 12.0, Projection::Psd);
        let (e1, g1, h1) = measured_bending(&x, &rest, &hr, &table, FoldSign::Absolute, Projection::Psd);
        assert!((e0 - e1).abs() <= 1e-12 * e0 && max_abs(&(g0 - g1)) <= 1e-12 * max_abs(&g0));
        assert_psd(&what, &h1);
    }
}

#[test]
fn measured_bending_jacobian_matches_finite_differences() {
    for theta in [0.4, 0.9, 1.3, 1.7] {
        let x = hinge(theta);
        let (rest, hr) = hinge_rest(&x);
        let angle = dihedral_angle(&x.map(|p| V3([p.x, p.y, p.z]))).abs();
        let value = angle * hr.curvature_per_angle * 0.1;
        assert!(value < 4.0 && (value - value.floor()) > 0.02, "probe on a sample curvature: {value}");
        check_fd("measured bending", &stack4(&x), 0.02, false, |y| {
            measured_bending(&unstack4(y), &rest, &hr, &KNIT.bending, FoldSign::Absolute, Projection::Exact)
        });
        let (_, _, h) = measured_bending(&x, &rest, &hr, &KNIT.bending, FoldSign::Absolute, Projection::Psd);
        assert_psd("measured bending PSD", &h);
    }
}

/// ARCSim 0.2.1 looks its bending table up by the signed curvature κ_A = θ_A ℓ/(A₁+A₂), θ_A = −θ
/// (`FoldSign::Signed`): a fold with κ_A > 0 reads the table as the default |θ| rule does, one
/// with κ_A < 0 extrapolates the first two samples linearly (clamped at zero). The signed rule's
/// Jacobian matches finite differences on the extrapolated side.
#[test]
fn measured_bending_signed_reads_the_table_as_arcsim() {
    let mut sides = [0, 0];
    for theta in [0.5, -0.5, 1.1, -1.1] {
        let x = hinge(theta);
        let (rest, hr) = hinge_rest(&x);
        let rest = BendingRest { theta0: 0.0, ..rest };
        let t = dihedral_angle(&x.map(|p| V3([p.x, p.y, p.z])));
        let kappa_a = -t * hr.curvature_per_angle;
        // By hand: the table row at this edge's bias, its first two samples at κ = 0 and 10 m⁻¹.
        let b = hr.bias[0];
        assert!(b > 0.0 && b < 1.0, "bias {b} between the warp and the bias rows");
        let row = |i: usize| KNIT.bending[0][i] * (1.0 - b) + KNIT.bending[1][i] * b;
        let energy = |ke: Real| 0.25 * ke * rest.shape / 6.0 * t * t;
        let (signed, _, _) = measured_bending(&x, &rest, &hr, &KNIT.bending, FoldSign::Signed, Projection::Psd);
        let (absolute, _, _) = measured_bending(&x, &rest, &hr, &KNIT.bending, FoldSign::Absolute, Projection::Psd);
        sides[usize::from(kappa_a < 0.0)] += 1;
        if kappa_a > 0.0 {
            assert!((signed - absolute).abs() <= 1e-12 * absolute, "θ_A > 0: {signed} vs {absolute}");
        } else {
            let want = (row(0) + (row(1) - row(0)) * kappa_a / 10.0).max(0.0);
            assert!(
                (signed - energy(want)).abs() <= 1e-12 * energy(want).max(1e-30),
                "θ_A = {}: {signed} vs {}",
                -t,
                energy(want)
            );
            assert!((signed - absolute).abs() > 1e-3 * absolute, "the back fold reads the table as the front");
            check_fd("signed measured bending", &stack4(&x), 0.02, false, |y| {
                measured_bending(&unstack4(y), &rest, &hr, &KNIT.bending, FoldSign::Signed, Projection::Exact)
            });
        }
    }
    assert_eq!(sides, [2, 2], "folds to the front and to the back");
}

// ---------------------------------------------------------------------------------------------
// Measured materials: the sample data

/// The normal stress along unit material direction d under a uniaxial stretch λ along d, from
/// the kernel's gradient: gᵀ ∂x/∂λ = A λ dᵀSd for G = ½(λ² − 1) d dᵀ.
fn kernel_stress(mat: &MeasuredMaterial, d: Vec2, lambda: Real) -> Real {
    let f = |l: Real| Mat2::identity() + (l - 1.0) * d * d.transpose();
    let (x, rest) = strained_triangle(f(lambda), 0.0);
    let (_, g, _) = measured_membrane(&x, &rest, &mat.stretching, Projection::Psd);
    let eps = 1e-7;
    let (xp, _) = strained_triangle(f(lambda + eps), 0.0);
    let (xm, _) = strained_triangle(f(lambda - eps), 0.0);
    let dx = (stack3(&xp) - stack3(&xm)) / (2.0 * eps);
    g.dot(&dx) / (rest.area * lambda)
}

/// The normal stress dᵀSd the sample row `k` gives for G = g d dᵀ (S₀₀ = k₀G₀₀ + k₁G₁₁,
/// S₁₁ = k₁G₀₀ + k₂G₁₁, S₀₁ = k₃G₀₁).
fn sample_stress(k: [Real; 4], d: Vec2, g: Real) -> Real {
    let gm = g * d * d.transpose();
    let s = Mat2::new(
        k[0] * gm[(0, 0)] + k[1] * gm[(1, 1)],
        k[3] * gm[(0, 1)],
        k[3] * gm[(0, 1)],
        k[1] * gm[(0, 0)] + k[2] * gm[(1, 1)],
    );
    d.dot(&(s * d))
}

/// Unit material direction at `deg` from the warp, exact along the axes (a rounding-level shear
/// would tilt the principal direction of an equal-stretch state arbitrarily).
fn direction(deg: Real) -> Vec2 {
    let a = deg.to_radians();
    Vec2::new(a.cos(), a.sin()).map(|c| if c.abs() < 1e-12 { 0.0 } else { c })
}

fn check_samples(name: &str, data: &MeasuredData) {
    let dirs = [(0.0, 1), (22.5, 2), (45.0, 3), (67.5, 4), (90.0, 5)];
    for (deg, row) in dirs {
        let d = direction(deg);
        // ARCSim's per-sample evaluation: at rest, row 0; at λ = 7/6 along the direction, its row
        // (clamped at zero, doubled).
        let at = |l: Real| stretching_sample(&(0.5 * (l * l - 1.0) * d * d.transpose()), &data.stretching);
        let expect = |r: usize| data.stretching[r].map(|v| 2.0 * v.max(0.0));
        for (got, want) in [(at(1.0), expect(0)), (at(7.0 / 6.0), expect(row))] {
            for c in 0..4 {
                assert!(
                    (got[c] - want[c]).abs() <= 1e-5 * want[c].abs().max(1.0),
                    "{name} {deg}°: {got:?} vs {want:?}"
                );
            }
        }
    }
    // Stress–strain along warp, weft and bias through the kernel, which reads ARCSim's 30³ table
    // of the samples (trilinear between table points 1/30 apart in strain). Along warp and weft
    // the neighbouring table points share the direction and the table stays within 2 % of the
    // sample row at λ = 7/6 (measured: ≤ 1.3 %). Along the bias the off-diagonal neighbours have
    // principal directions 7–10° away, so the table blends in the 22.5° / 67.5° rows: up to 12 %
    // off for navy-sparkle-sweat, whose 67.5° row has no shear stiffness (ARCSim's behaviour,
    // kept); bounded here at 15 %.
    let mat = MeasuredMaterial::new(data, 1.0, 1.0);
    for (what, deg, row, tol) in [("warp", 0.0, 1, 0.02), ("bias", 45.0, 3, 0.15), ("weft", 90.0, 5, 0.02)] {
        let d = direction(deg);
        let lambda = 7.0 / 6.0;
        let g = 0.5 * (lambda * lambda - 1.0);
        let want = sample_stress(data.stretching[row].map(|v| 2.0 * v.max(0.0)), d, g);
        let got = kernel_stress(&mat, d, lambda);
        assert!((got - want).abs() <= tol * want.abs(), "{name} {what} at λ = 7/6: σ = {got} vs samples {want}");
    }
    // Bending: at the sample curvatures (0, 10, … 40 m⁻¹) and directions (0°, 45°, 90°), exactly
    // the sample.
    for (dir, bias) in [(0, 0.0), (1, 1.0), (2, 2.0)] {
        for (i, curv) in [0.0, 10.0, 20.0, 30.0, 40.0].into_iter().enumerate() {
            let (ke, _) = bending_stiffness(&data.bending, curv, bias);
            let want = data.bending[dir][i].max(0.0);
            assert!((ke - want).abs() <= 1e-12 * want.abs(), "{name} bending {dir} at {curv}: {ke} vs {want}");
        }
    }
}

#[test]
fn stress_strain_along_warp_weft_and_bias_matches_the_samples() {
    check_samples("gray-interlock (built in)", &KNIT);
    let Some(dir) = arcsim_dir("stress_strain_along_warp_weft_and_bias_matches_the_samples") else { return };
    let mut n = 0;
    for entry in std::fs::read_dir(dir.join("materials")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let data = scene::read_measured(&path).unwrap_or_else(|e| panic!("{e}"));
            check_samples(&path.display().to_string(), &data);
            n += 1;
        }
    }
    assert!(n >= 12, "expected the ten fabrics, paper and aluminium; found {n}");
}

#[test]
fn hinge_directions_follow_arcsims_bias_coordinate() {
    let b = |deg: Real| {
        let a = deg.to_radians();
        HingeRest::new([Vec2::new(a.cos(), a.sin()); 2], 1.0, 1.0).bias[0]
    };
    for (deg, want) in [(0.0, 0.0), (45.0, 1.0), (90.0, 2.0), (135.0, 1.0), (180.0, 0.0), (-90.0, 2.0), (22.5, 0.5)] {
        assert!((b(deg) - want).abs() < 1e-12, "{deg}°: {}", b(deg));
    }
}

// ---------------------------------------------------------------------------------------------
// ARCSim's scenes

/// Per-frame face counts of an ARCSim conf simulated for `frames` frames; every frame must be
/// free of crossing triangle pairs (issue 18: the exact count that goes to stats.json).
fn simulate_faces(conf: &Path, frames: usize, each: impl FnMut(usize, &Simulation)) -> Vec<usize> {
    simulate_scene_faces(conf, scene::load_path(conf, None).unwrap().scene, frames, each)
}

fn simulate_scene_faces(
    conf: &Path,
    scene: scene::Scene,
    frames: usize,
    mut each: impl FnMut(usize, &Simulation),
) -> Vec<usize> {
    let mut sim = Simulation::new(scene).unwrap();
    let mut faces = vec![sim.state.mesh.faces.len()];
    for f in 1..=frames {
        sim.advance_frame().unwrap_or_else(|e| panic!("{}: frame {f}: {e}", conf.display()));
        let c = sim.crossings();
        assert!(
            c.cloth.is_empty() && c.obstacle.is_empty(),
            "{}: frame {f}: crossing triangle pairs: {} cloth–cloth, {} cloth–obstacle",
            conf.display(),
            c.cloth.len(),
            c.obstacle.len()
        );
        faces.push(sim.state.mesh.faces.len());
        each(f, &sim);
    }
    faces
}

/// square.json: squeezed from t = 1 s to 6 s, held to 7 s, released by 12 s (frame 300). ARCSim
/// 0.2.1 itself, run on this machine kind (2026-12-02, `simulateoffline conf/square.json`):
/// 128 faces → 471.3 on average over frames 150–175 (squeezed, max 474) → 130 over frames
/// 300–310. Issue 16: the compression criterion must refine the squeeze as ARCSim's does (its
/// signed square root, `sizing`), within 8% of those counts on both plateaus. The clamped root
/// it replaced gave 426.2 and 147.0 (−9.6%, +13%).
///
/// The handles are made exact here so that this measures the sizing criterion alone. With
/// ARCSim's own soft handles (1e3 N/m, as the converter reads them) the squeeze refines to 416.0
/// faces on every jittered start (558.5–582.0 before converted confs took ARCSim's split-node
/// relaxation, explicit drag and geometric stiffness), against 436–512 over ARCSim's own
/// jittered starts: README, "Where square.json's squeeze gap comes from".
const ARCSIM_SQUARE_SQUEEZED: f64 = 471.3;
const ARCSIM_SQUARE_RELEASED: f64 = 130.0;

#[test]
fn square_refines_while_squeezed_and_returns_after_release() {
    let Some(dir) = arcsim_dir("square_refines_while_squeezed_and_returns_after_release") else { return };
    let started = std::time::Instant::now();
    let conf = dir.join("conf/square.json");
    let mut square = scene::load_path(&conf, None).unwrap().scene;
    assert!(square.handles.iter().all(|h| h.stiffness == Some(1e3)), "square.json's handles: ARCSim's soft springs");
    square.handles.iter_mut().for_each(|h| h.stiffness = None);
    let faces = simulate_scene_faces(&conf, square, 310, |_, _| {});
    let start = faces[1];
    let mean = |r: std::ops::RangeInclusive<usize>| {
        let n = r.clone().count() as f64;
        faces[r].iter().map(|&f| f as f64).sum::<f64>() / n
    };
    let squeezed = mean(150..=175);
    let released = mean(300..=310);
    eprintln!(
        "square.json: faces {start} (frame 1) → {squeezed:.1} (frames 150–175) → {released:.1} (frames \
         300–310); ARCSim {ARCSIM_SQUARE_SQUEEZED} → {ARCSIM_SQUARE_RELEASED}; {:.0} s",
        started.elapsed().as_secs_f64()
    );
    let within = |ours: f64, theirs: f64| (ours - theirs).abs() <= 0.08 * theirs;
    assert!(
        within(squeezed, ARCSIM_SQUARE_SQUEEZED),
        "squeezed: {squeezed:.1} faces against ARCSim's {ARCSIM_SQUARE_SQUEEZED} (bound ±8%)"
    );
    assert!(
        within(released, ARCSIM_SQUARE_RELEASED),
        "released: {released:.1} faces against ARCSim's {ARCSIM_SQUARE_RELEASED} (bound ±8%)"
    );
}

/// sphere.json: the cloth never ends a frame inside the sphere (clearance ≥ 0) over the first
/// 100 frames (4 s: the sheet falls and drapes over the sphere, which from t = 2 s sweeps away
/// at up to 2 m/s dragging the sheet; about a minute here).
const SPHERE_TEST_FRAMES: usize = 100;

#[test]
fn sphere_clearance_is_never_negative() {
    let Some(dir) = arcsim_dir("sphere_clearance_is_never_negative") else { return };
    let mut worst = Real::INFINITY;
    simulate_faces(&dir.join("conf/sphere.json"), SPHERE_TEST_FRAMES, |f, sim| {
        let world = sim.ws.collisions.as_ref().unwrap();
        let body = &world.bodies[0];
        let sdf = MeshSdf::new(body.triangles(), &body.positions_at(sim.state.time));
        let x = sim.state.mesh.positions();
        let d = sdf.query_all(&x).into_iter().flatten().map(|h| h.distance).fold(Real::INFINITY, Real::min);
        assert!(d >= 0.0, "frame {f}: a cloth node is {:.2e} m inside the sphere", -d);
        worst = worst.min(d);
    });
    eprintln!("sphere.json: smallest clearance over {SPHERE_TEST_FRAMES} frames {worst:.2e} m");
}

#[test]
fn arcsim_default_base_is_the_conf_grand_parent() {
    assert_eq!(arcsim::default_base(Path::new("x/conf/a.json")), Path::new("x/conf/.."));
}

/// The kernels' energy-only forms (the fault checks' and the pop filter's energies, issue 17
/// item 3) give the energy of the full kernels bit for bit, for every kernel; and the measured
/// grid's stiffness without derivatives is its stiffness with them.
#[test]
fn energy_only_is_the_kernels_energy_bit_for_bit() {
    let knit = MeasuredMaterial::new(&KNIT, 2.0, 1.0);
    let lin = MembraneStiffness { k11: 1000.0, k12: 200.0, k22: 800.0, k33: 300.0 };
    let mut rng = Rng(5);
    let mut rnd = move || rng.uniform() - 0.5;
    for _ in 0..20 {
        let f = Mat2::new(1.0 + 0.3 * rnd(), 0.2 * rnd(), 0.2 * rnd(), 1.0 + 0.3 * rnd());
        let (x, rest) = strained_triangle(f, 0.05 * rnd());
        let cases = [
            (membrane(&x, &rest, &lin, Projection::Psd), membrane_energy(&x, &rest, &lin)),
            (
                measured_membrane(&x, &rest, &knit.stretching, Projection::Psd),
                measured_membrane_energy(&x, &rest, &knit.stretching),
            ),
        ];
        for ((e, g, _), e_only) in cases {
            assert!(e != 0.0 && g != SVector::<Real, 9>::zeros());
            assert_eq!(e.to_bits(), e_only.to_bits());
        }
        let g = [rnd(), rnd(), rnd()];
        let (k, _) = knit.stretching.stiffness(g[0], g[1], g[2]);
        assert_eq!(k.map(Real::to_bits), knit.stretching.stiffness_alone(g[0], g[1], g[2]).map(Real::to_bits));
        let h = hinge(1.5 * rnd());
        let (brest, hr) = hinge_rest(&h);
        let cases = [
            (bending(&h, &brest, 2e-5, Projection::Psd).0, bending_energy(&h, &brest, 2e-5)),
            (
                measured_bending(&h, &brest, &hr, &knit.bending, FoldSign::Absolute, Projection::Psd).0,
                measured_bending_energy(&h, &brest, &hr, &knit.bending, FoldSign::Absolute),
            ),
        ];
        for (e, e_only) in cases {
            assert!(e != 0.0);
            assert_eq!(e.to_bits(), e_only.to_bits());
        }
    }
}
