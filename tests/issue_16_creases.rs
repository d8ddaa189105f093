//! Issue 16: a folded paper model as ARCSim's dart.json gives one, on an adaptive mesh. Its OBJ
//! labels the fold's edges (ARCSim's `e`/`el`); its world shape is the fold, 3% larger than its
//! flat pattern, and is its rest shape (`rest_angles: "input"`, ARCSim's `preserve_creases`),
//! so it relaxes first (`initial_relax`) and then rests in the relaxed shape. Through refinement
//! the fold must stay a sharp line of edges between flat wings (the rest shape carried as an
//! embedding, not through the faces' shape operators, which spread it over the faces beside
//! it), the model at rest, and no triangle through another. (That the labels keep a fold on
//! edges where the remesher would otherwise cut across it: `remesh::crease_tests`.)
//!
//! The model: a 100 mm × 40 mm sheet of paper (ARCSim's `materials/paper.json`, as in
//! `issue_16_plasticity.rs`) of 10 mm quads, folded by 30° along the line u = 50 mm, no gravity,
//! refined to at most 5 mm, with dart.json's repulsion thickness (0.2 mm). (With 1 mm, the
//! refined wings' nodes within a millimetre of the fold repel the other wing's faces across it
//! and the fold settles 1.5° flatter: a property of repulsion at a sharp fold, not of the rest
//! shape.)

use std::path::{Path, PathBuf};

mod common;

use common::{at_material, temp_dir};
use serde_json::json;
use viewcloth::math::{Real, Vec2, Vec3};
use viewcloth::mesh::Mesh;
use viewcloth::scene;
use viewcloth::sim::Simulation;

const FOLD_DEG: Real = 30.0;
const FRAMES: usize = 10;
/// The world shape is the pattern this much larger (dart.obj starts at 13% strain).
const SCALE: Real = 1.03;

/// The OBJ of the folded sheet: 10 × 4 quads in material space (metres), the right half turned
/// by the fold about u = 50 mm, the world 3% larger; the fold's edges labelled when `labelled`.
fn folded_obj(labelled: bool) -> String {
    let (nx, ny, h) = (10, 4, 0.01);
    let phi = FOLD_DEG.to_radians();
    let mut s = String::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (u, v) = (i as Real * h, j as Real * h);
            let d = u - 0.05;
            let x = match d > 0.0 {
                true => Vec3::new(0.05 + d * phi.cos(), v, d * phi.sin()),
                false => Vec3::new(u, v, 0.0),
            } * SCALE;
            s += &format!("v {} {} {}\nvt {u} {v}\n", x.x, x.y, x.z);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i + 1;
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            s += &format!("f {a}/{a} {b}/{b} {c}/{c}\nf {a}/{a} {c}/{c} {d}/{d}\n");
        }
    }
    if labelled {
        for j in 0..ny {
            s += &format!("e {} {}\nel 1\n", id(5, j), id(5, j + 1));
        }
    }
    s
}

fn scene_file(dir: &Path, labelled: bool) -> PathBuf {
    let name = if labelled { "labelled" } else { "unlabelled" };
    std::fs::write(dir.join(format!("{name}.obj")), folded_obj(labelled)).unwrap();
    let cloth = json!({
        "mesh": format!("{name}.obj"),
        "material": {
            "density": 0.1, "youngs_modulus": 5e9, "thickness": 1e-4, "poisson_ratio": 0.0,
            "bending": 0.4e-3 / 12.0, "damping": 1e-3
        },
        "rest_angles": "input",
        "remesh": { "mode": "adaptive", "refine_angle": 0.3, "size": [0.002, 0.005], "aspect_min": 0.2 }
    });
    let scene = json!({
        "version": 1, "name": name, "frame_time": 0.02, "steps_per_frame": 5, "frames": FRAMES,
        "gravity": [0, 0, 0], "initial_relax": true, "collision": { "self_collision": true, "thickness": 2e-4 },
        "cloths": [cloth]
    });
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, scene.to_string()).unwrap();
    file
}

/// The fold angle (degrees) between the wings' directions across the fold, from the material
/// points `near` and `far` from the fold line on each side, at height v.
fn fold_deg(mesh: &Mesh, near: Real, far: Real, v: Real) -> Real {
    let p = |u: Real| at_material(mesh, Vec2::new(u, v));
    let (left, right) = (p(0.05 - near) - p(0.05 - far), p(0.05 + far) - p(0.05 + near));
    left.angle(&right).to_degrees()
}

/// Faces with corners on both sides of the fold line in material space.
fn faces_across(mesh: &Mesh) -> usize {
    (0..mesh.faces.len())
        .filter(|&f| {
            let u = mesh.face_uv(f);
            u.iter().any(|u| u.x < 0.05 - 1e-9) && u.iter().any(|u| u.x > 0.05 + 1e-9)
        })
        .count()
}

struct Run {
    sim: Simulation,
    /// Faces across the fold, most at any frame end.
    across: usize,
    crossings: usize,
    faces: Vec<usize>,
}

fn run(file: &Path) -> Run {
    let scene = scene::load_file(file).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{e}"));
    let (mut across, mut crossings, mut faces) = (faces_across(&sim.state.mesh), 0, Vec::new());
    for k in 1..=FRAMES {
        sim.advance_frame().unwrap_or_else(|e| panic!("{}: frame {k}: {e}", file.display()));
        across = across.max(faces_across(&sim.state.mesh));
        crossings += sim.crossings().cloth.len();
        faces.push(sim.state.mesh.faces.len());
    }
    Run { sim, across, crossings, faces }
}

#[test]
fn a_labelled_fold_stays_sharp_between_flat_wings_at_rest() {
    let dir = temp_dir("creases");
    let r = run(&scene_file(&dir, true));
    let mesh = &r.sim.state.mesh;
    let speed = mesh.nodes.iter().map(|n| n.v.norm()).fold(0.0, Real::max);
    let angles: Vec<Real> = [0.005, 0.02, 0.035].iter().map(|&v| fold_deg(mesh, 0.002, 0.045, v)).collect();
    let sharp = fold_deg(mesh, 0.0005, 0.004, 0.02);
    eprintln!(
        "faces per frame {:?}; fold {angles:.3?}° (wings), {sharp:.3}° (beside the fold); fastest node {speed:.2e} m/s",
        r.faces
    );
    assert!(mesh.faces.len() >= 320, "not refined: {} faces", mesh.faces.len());
    assert_eq!(r.across, 0, "a face lies across the fold");
    assert_eq!(r.crossings, 0, "crossing triangle pairs");
    // Sharp between flat wings: the same angle measured at the fold as across the whole wings,
    // the input's fold (a uniform 3% scale keeps angles).
    for a in angles.iter().chain([&sharp]) {
        assert!((a - FOLD_DEG).abs() < 0.5, "fold {a:.3}° (input {FOLD_DEG}°): wings {angles:?}, at the fold {sharp}");
    }
    // At rest in the relaxed shape: no snap, no drift.
    assert!(speed < 1e-3, "fastest node {speed:e} m/s");
}
