//! Issue 16, item 3: a cloth whose rest shape is curved (rest angles from a half-cylinder input
//! mesh) keeps that rest shape through remeshing. Before, edges a remesh created rested flat
//! beside old edges keeping the coarse mesh's large angles, so the rest shape became a mix that
//! depended on the mesh: a coarse half-pipe refined at load hung as if it rested flat.
//!
//! The scene: a 1 m × 0.5 m half-pipe (radius 1/π, axis along y), held along one straight edge,
//! hanging for 1 s under gravity; measured: its centroid and free corners.

use std::f64::consts::PI;
use std::path::Path;

mod common;

use common::temp_dir;
use serde_json::json;
use viewcloth::math::Vec3;
use viewcloth::scene;
use viewcloth::sim::Simulation;

const FRAMES: usize = 25;

/// A half-pipe OBJ of nx × ny quads: material coordinates (vt) the flat 1 × 0.5 sheet,
/// positions rolled about the y axis (node j·(nx+1)+i is column i, row j); and the scene
/// holding its u = 0 edge, remeshed in `mode` from it (`None`: the input mesh kept).
fn write_half_pipe(dir: &Path, nx: usize, ny: usize, rest: &str, mode: Option<&str>) -> std::path::PathBuf {
    let r = 1.0 / PI;
    let mut obj = String::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (u, v) = (i as f64 / nx as f64, 0.5 * j as f64 / ny as f64);
            obj += &format!("v {} {} {}\nvt {u} {v}\n", r * (u / r).sin(), v, r * (1.0 - (u / r).cos()));
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i + 1;
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            // Alternating diagonals, so that no direction is favoured.
            let tris = if (i + j) % 2 == 0 { [[a, b, c], [a, c, d]] } else { [[a, b, d], [b, c, d]] };
            for t in tris {
                obj += &format!("f {}/{} {}/{} {}/{}\n", t[0], t[0], t[1], t[1], t[2], t[2]);
            }
        }
    }
    let name = format!("half_pipe_{nx}x{ny}_{rest}_{}", mode.unwrap_or("fixed"));
    std::fs::write(dir.join(format!("{name}.obj")), obj).unwrap();
    let held: Vec<usize> = (0..=ny).map(|j| j * (nx + 1)).collect();
    let mut cloth = json!({
        "mesh": format!("{name}.obj"),
        "material": { "density": 0.1, "warp": 20000, "weft": 20000, "shear": 5000, "bending": 0.02 },
        "rest_angles": rest,
        "handles": [{ "nodes": held }]
    });
    if let Some(mode) = mode {
        cloth["remesh"] = json!({ "mode": mode, "refine_angle": 0.3, "size": [0.03, 0.2], "aspect_min": 0.2 });
    }
    let scene = json!({
        "version": 1, "name": name, "frame_time": 0.04, "steps_per_frame": 5, "frames": FRAMES,
        "gravity": [0, 0, -9.81], "cloths": [cloth]
    });
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, scene.to_string()).unwrap();
    file
}

/// Where the cloth hangs after `FRAMES` frames: its centroid (faces' world centroids weighted by
/// material area) and its two free corners (material (1, 0) and (1, 0.5), kept by any remesh);
/// and its face count.
fn hang(file: &Path) -> ([Vec3; 3], usize) {
    let scene = scene::load_file(file).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(scene).unwrap();
    for _ in 0..FRAMES {
        sim.advance_frame().unwrap();
    }
    let mesh = &sim.state.mesh;
    let (mut sum, mut area) = (Vec3::zeros(), 0.0);
    for f in 0..mesh.faces.len() {
        let a = mesh.material_area(f);
        sum += a * mesh.face_nodes(f).iter().map(|&n| mesh.nodes[n].x).sum::<Vec3>() / 3.0;
        area += a;
    }
    let corner = |y: f64| {
        let v = mesh.verts.iter().find(|v| (v.u.x - 1.0).abs() < 1e-9 && (v.u.y - y).abs() < 1e-9).unwrap();
        mesh.nodes[v.node.idx()].x
    };
    ([sum / area, corner(0.0), corner(0.5)], mesh.faces.len())
}

/// The largest distance between corresponding points of two hangs.
fn apart(a: &[Vec3; 3], b: &[Vec3; 3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

#[test]
fn curved_rest_shape_survives_refinement_and_adaptive_remeshing() {
    let dir = temp_dir("half_pipe");
    let run = |nx, ny, rest, mode| hang(&write_half_pipe(&dir, nx, ny, rest, mode));
    // 8 × 4 quads (edges 0.125 m) refined at load to 0.03 m, against a 32 × 16 input (0.031 m)
    // whose rest angles are exact.
    let (uniform, fu) = run(8, 4, "input", Some("uniform"));
    let (fine, _) = run(32, 16, "input", None);
    let (adaptive, fa) = run(8, 4, "input", Some("adaptive"));
    let (uniform_flat, _) = run(8, 4, "flat", Some("uniform"));
    let (adaptive_flat, _) = run(8, 4, "flat", Some("adaptive"));
    let refined = apart(&uniform, &fine);
    let effect = apart(&uniform_flat, &fine);
    let (gap, gap_flat) = (apart(&adaptive, &uniform), apart(&adaptive_flat, &uniform_flat));
    eprintln!(
        "half-pipe after {FRAMES} frames (centroid, free corners): uniform {uniform:?} ({fu} faces), fine input \
         {fine:?}, adaptive {adaptive:?} ({fa} faces); refined vs fine input {refined:.4} m, flat vs curved \
         rest {effect:.4} m, adaptive vs uniform {gap:.4} m (flat rest: {gap_flat:.4} m)"
    );
    // The rest shape matters here: resting flat moves the cloth by more than 20 cm (46 cm).
    assert!(effect > 0.2, "the flat-rest run hangs like the curved one ({effect} m): the test cannot tell");
    // A coarse curved input refined hangs like a fine one: within 3 cm (3% of the 1 m arc;
    // measured 1.4 cm, and 48 cm when new edges rested flat: as flat as the flat-rest run).
    assert!(refined < 0.03, "refined coarse input and fine input {refined} m apart");
    // The adaptive mesh (far coarser) hangs no further from the uniform one than it does with a
    // flat rest shape, where no rest shape is carried: ≤ 1.5× that discretisation gap (measured
    // 10.8 cm against 8.2 cm, and 53 cm when new edges rested flat).
    assert!(fa * 4 < fu, "adaptive {fa} faces vs uniform {fu}: nothing coarser to compare");
    assert!(gap <= 1.5 * gap_flat, "adaptive vs uniform {gap} m, with a flat rest shape {gap_flat} m");
}
