//! Issue 16, items 5–7: ARCSim 0.2.1's handle, obstacle and `disable` semantics, in viewcloth's
//! own scenes and in confs read as ARCSim reads them (`conf.cpp`, `handle.cpp`,
//! `obstacle.cpp`, `simulation.cpp`).
//!
//! Confs other than the four in `../shared/arcsim` are not used here: each semantic gets a
//! small synthetic scene or conf written to a temporary directory.

mod common;

use std::path::{Path, PathBuf};

use common::{inline_scene, temp_dir, viewcloth};
use serde_json::{json, Value};
use viewcloth::collision::obstacle::sphere_mesh;
use viewcloth::math::{Real, Vec3};
use viewcloth::scene::{self, HandleKind};
use viewcloth::sim::Simulation;

/// A flat `w` × `w` sheet of `n` × `n` quads in the z = 0 plane (rectangle nodes: row-major
/// from the lower-left corner).
fn sheet(w: Real, n: usize) -> Value {
    json!({"rectangle": {"width": w, "height": w, "resolution": [n, n]}, "material": {"preset": "cotton"}})
}

fn scene_of(cloth: Value, extra: Value) -> Value {
    let mut s = json!({"version": 1, "frame_time": 0.02, "steps_per_frame": 4, "frames": 50,
                       "gravity": [0, 0, -9.81], "cloths": [cloth]});
    for (k, v) in extra.as_object().unwrap() {
        s[k] = v.clone();
    }
    s
}

fn sim_of(v: &Value, name: &str) -> Simulation {
    Simulation::new(inline_scene(v, Path::new("."), name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn x(sim: &Simulation, n: usize) -> Vec3 {
    sim.state.mesh.nodes[n].x
}

// ---------------------------------------------------------------------------------------------
// Handles

/// A handle switching on at t = 0.2 holds its node where the node is at that moment (it has
/// fallen ~0.2 m by then), not where it was at load; exactly for an exact handle, within the
/// spring's sag for a soft one.
#[test]
fn a_handle_switching_on_later_holds_its_node_where_it_is_then() {
    for stiffness in [None, Some(5000.0)] {
        let mut handle = json!({"nodes": [24], "start_time": 0.2});
        if let Some(k) = stiffness {
            handle["stiffness"] = json!(k);
        }
        let mut cloth = sheet(0.2, 4);
        cloth["handles"] = json!([handle]);
        let mut sim = sim_of(&scene_of(cloth, json!({})), "late_handle");
        let load = x(&sim, 24);
        let h = sim.scene.time_step();
        let mut on: Option<Vec3> = None;
        while sim.state.time < 0.6 {
            if on.is_none() && sim.state.time >= 0.2 {
                on = Some(x(&sim, 24));
            }
            sim.step(h).unwrap();
            if let Some(at) = on {
                let off = (x(&sim, 24) - at).norm();
                match stiffness {
                    None => assert!(off < 1e-12, "t = {:.3}: exact handle node {off:e} m off", sim.state.time),
                    // Catching the sheet falling at 2 m/s: about v √(m/k) = 2.2 mm.
                    Some(_) => assert!(off < 5e-3, "t = {:.3}: soft handle node {off:e} m off", sim.state.time),
                }
            }
        }
        let at = on.unwrap();
        assert!((at - load).norm() > 0.15, "{stiffness:?}: the node had not fallen before switch-on: {at} vs {load}");
        assert!((x(&sim, 24) - load).norm() > 0.15, "{stiffness:?}: the node went back to its load position");
    }
}

/// The node's acceleration, per step, while the handle lets go at `end_time` (0.3 s) without
/// and with a fade (0.2 s): the largest change of the acceleration from one step to the next.
fn release_jump(fade: Real) -> Real {
    let mut cloth = sheet(0.2, 4);
    // Hanging still (vertical, from its top corners) when the handle lets go.
    cloth["transform"] = json!({"rotate": [90, 1, 0, 0]});
    let mut handle = json!({"nodes": [20, 24], "stiffness": 20.0, "end_time": 0.3});
    if fade > 0.0 {
        handle["fade_time"] = json!(fade);
    }
    cloth["handles"] = json!([handle]);
    let mut sim = sim_of(&scene_of(cloth, json!({"wind": {"velocity": [0, 0, 0], "drag": 1.0}})), "fade");
    let h = sim.scene.time_step();
    let (mut prev_v, mut prev_a, mut jump): (Vec3, Option<Vec3>, Real) = (Vec3::zeros(), None, 0.0);
    while sim.state.time < 0.7 {
        sim.step(h).unwrap();
        let v = sim.state.mesh.nodes[24].v;
        let a = (v - prev_v) / h;
        if sim.state.time > 0.25 {
            if let Some(p) = prev_a {
                jump = jump.max((a - p).norm());
            }
            prev_a = Some(a);
        }
        prev_v = v;
    }
    jump
}

/// ARCSim's fade: the spring's strength falls as (1 − (t − end)/fade)⁴, so the handle node's
/// acceleration changes by at most a few percent of the released force per step, where a
/// release without fade changes it all at once.
#[test]
fn fade_time_ramps_the_handle_force_out() {
    let (sudden, faded) = (release_jump(0.0), release_jump(0.2));
    eprintln!("largest per-step change of the node's acceleration: {sudden:.3} m/s² released, {faded:.3} faded");
    assert!(faded < 0.3 * sudden, "fade 0.2 s: {faded} m/s² per step against {sudden} without fade");
}

/// A soft handle carrying a hanging sheet's whole weight W sags by W / k (within a few %).
#[test]
fn a_soft_handle_sags_by_load_over_stiffness() {
    let k = 0.5;
    let mut cloth = sheet(0.1, 2);
    // Vertical (the xz plane), held at the middle of its top edge (node 7).
    cloth["transform"] = json!({"rotate": [90, 1, 0, 0]});
    cloth["handles"] = json!([{"nodes": [7], "stiffness": k}]);
    let v = scene_of(cloth, json!({"wind": {"velocity": [0, 0, 0], "drag": 1.0}, "frames": 150}));
    let mut sim = sim_of(&v, "sag");
    let anchor = sim.scene.handles[0].anchors[0];
    let weight: Real = sim.state.mesh.nodes.iter().map(|n| n.mass).sum::<Real>() * 9.81;
    let mut sag = Vec::new();
    for frame in 1..=150 {
        sim.advance_frame().unwrap();
        if frame > 125 {
            sag.push(anchor - x(&sim, 7));
        }
    }
    let mean = sag.iter().sum::<Vec3>() / sag.len() as Real;
    let expected = weight / k;
    eprintln!("sag {mean:?} m, W/k = {expected} m");
    assert!((mean.z - expected).abs() < 0.03 * expected, "sag {} m, expected W/k = {expected} m", mean.z);
    assert!(mean.x.abs() < 0.01 * expected && mean.y.abs() < 0.01 * expected, "sideways {mean:?}");
}

/// A glue handle ties two corners of a sheet together and holds them.
#[test]
fn glued_nodes_come_together_and_stay() {
    let mut cloth = sheet(0.2, 4);
    cloth["handles"] = json!([{"glue": [0, 24], "stiffness": 1000.0}]);
    let v = scene_of(cloth, json!({"gravity": [0, 0, 0], "wind": {"velocity": [0, 0, 0], "drag": 1.0}}));
    let mut sim = sim_of(&v, "glue");
    assert!((x(&sim, 0) - x(&sim, 24)).norm() > 0.28);
    for frame in 1..=50 {
        sim.advance_frame().unwrap();
        let d = (x(&sim, 0) - x(&sim, 24)).norm();
        if frame >= 30 {
            assert!(d < 2e-3, "frame {frame}: glued corners {d} m apart");
        }
    }
    // The coupling is in the system's pattern (not majorized on the diagonal).
    assert!(sim.ws.system.pattern.block(24, 0).is_some());
}

// ---------------------------------------------------------------------------------------------
// Confs: handles as ARCSim reads them

/// Writes `conf` as `dir/conf/name.json` with a small measured material and the meshes given;
/// returns its path.
fn write_conf(dir: &Path, name: &str, conf: &Value, meshes: &[(&str, String)]) -> PathBuf {
    for sub in ["conf", "meshes", "materials"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    let (stretching, bending) = (vec![[200.0, 20.0, 200.0, 60.0]; 6], vec![[1e-6; 5]; 3]);
    let material = json!({"density": 0.1, "stretching": stretching, "bending": bending});
    std::fs::write(dir.join("materials/soft.json"), material.to_string()).unwrap();
    for (file, text) in meshes {
        std::fs::write(dir.join("meshes").join(file), text).unwrap();
    }
    let path = dir.join("conf").join(format!("{name}.json"));
    std::fs::write(&path, serde_json::to_string_pretty(conf).unwrap()).unwrap();
    path
}

/// An `n` × `n` quad grid OBJ of side `w` in the z = 0 plane, with texture coordinates.
fn grid_obj(w: Real, n: usize) -> String {
    let mut s = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (w * i as Real / n as Real, w * j as Real / n as Real);
            s += &format!("v {u} {v} 0\nvt {u} {v}\n");
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            s += &format!("f {a}/{a} {b}/{b} {c}/{c}\nf {a}/{a} {c}/{c} {d}/{d}\n");
        }
    }
    s
}

/// An open cylinder of circumference `c` and height `height` around the z axis: `n` nodes per
/// ring, `m` + 1 rings, a seam at angle 0 (its nodes carry u = 0 and u = c); the bottom ring
/// labelled 1, the top ring 2 (ARCSim's `nl` lines).
fn cylinder_obj(c: Real, height: Real, n: usize, m: usize) -> String {
    let r = c / std::f64::consts::TAU;
    let mut s = String::new();
    for j in 0..=m {
        for i in 0..n {
            let a = std::f64::consts::TAU * i as Real / n as Real;
            s += &format!("v {} {} {}\n", r * a.cos(), r * a.sin(), height * j as Real / m as Real);
            match j {
                0 => s += "nl 1\n",
                _ if j == m => s += "nl 2\n",
                _ => {}
            }
        }
    }
    for j in 0..=m {
        for i in 0..=n {
            s += &format!("vt {} {}\n", c * i as Real / n as Real, height * j as Real / m as Real);
        }
    }
    let v = |i: usize, j: usize| j * n + i % n + 1;
    let t = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..m {
        for i in 0..n {
            let (a, b, cc, d) = ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1));
            let f = |p: (usize, usize)| format!("{}/{}", v(p.0, p.1), t(p.0, p.1));
            s += &format!("f {} {} {}\nf {} {} {}\n", f(a), f(b), f(cc), f(a), f(cc), f(d));
        }
    }
    s
}

/// tshirt.json's closing move: a keyframe with scale 0 pulls the handle's nodes onto the key's
/// translation (ARCSim places them at translate + scale·R·x₀). The conf is accepted, and both
/// corners end within a few mm of the point.
#[test]
fn a_scale_zero_keyframe_pulls_the_handle_nodes_onto_a_point() {
    let dir = temp_dir("scale0");
    let target = [0.1, 0.05, 0.15];
    let conf = json!({
        "frame_time": 0.02, "frame_steps": 4, "end_time": 1.0,
        "cloths": [{"mesh": "meshes/grid.obj", "materials": [{"data": "materials/soft.json"}]}],
        "motions": [[{"time": 0.1}, {"time": 0.5, "transform": {"translate": target, "scale": 0}}]],
        "handles": [{"nodes": [0, 2], "motion": 0, "start_time": 0.1}],
        "gravity": [0, 0, -9.8]
    });
    let path = write_conf(&dir, "scale0", &conf, &[("grid.obj", grid_obj(0.2, 2))]);
    let loaded = scene::load_path(&path, None).unwrap_or_else(|e| panic!("{e}"));
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    assert_eq!(loaded.scene.handles[0].stiffness, Some(1e3), "ARCSim's default handle_stiffness");
    let mut sim = Simulation::new(loaded.scene).unwrap();
    for frame in 1..=50 {
        sim.advance_frame().unwrap();
        if frame >= 35 {
            for n in [0, 2] {
                let d = (x(&sim, n) - Vec3::from(target)).norm();
                assert!(d < 5e-3, "frame {frame}: node {n} is {d} m from the key's point");
            }
        }
    }
}

/// A conf after cylinder.json: a tube of circumference 0.12 m and height 0.06 m held by circle
/// handles on its bottom ring (label 1, fixed) and top ring (label 2, turned 90° about z over
/// 0.4 s), soft (`handle_stiffness` 1e5 N/m per metre), remeshed finer than the rings.
fn tube_conf(dir: &Path) -> (Real, Real, PathBuf) {
    let (c, height) = (0.12, 0.06);
    let circle = |label: i64, z: Real, motion: Option<i64>| {
        let mut h = json!({"type": "circle", "label": label, "circumference": c, "u": [1, 0],
                           "center": [0, 0, z], "axis0": [1, 0, 0], "axis1": [0, 1, 0]});
        if let Some(m) = motion {
            h["motion"] = json!(m);
        }
        h
    };
    let conf = json!({
        "frame_time": 0.02, "frame_steps": 4, "end_time": 0.6,
        "cloths": [{"mesh": "meshes/tube.obj", "materials": [{"data": "materials/soft.json"}],
                    "remeshing": {"refine_angle": 0.3, "size": [4e-3, 10e-3], "aspect_min": 0.2}}],
        "motions": [[{"time": 0}, {"time": 0.4, "transform": {"rotate": [90, 0, 0, 1]}}]],
        "handles": [circle(1, 0.0, None), circle(2, height, Some(0))],
        "gravity": [0, 0, -9.8],
        "magic": {"handle_stiffness": 1e5}
    });
    let path = write_conf(dir, "tube", &conf, &[("tube.obj", cylinder_obj(c, height, 8, 3))]);
    (c, height, path)
}

/// cylinder.json's circle handles: the rings (OBJ labels 1 and 2) are held on their circles,
/// the top one turned 90° by its motion, and ring edges the remesher splits bring their new
/// nodes onto the circle too (ARCSim's `combine_label`).
#[test]
fn circle_handles_hold_their_rings_on_the_moving_circle() {
    let dir = temp_dir("circle");
    let (c, height, path) = tube_conf(&dir);
    let loaded = scene::load_path(&path, None).unwrap_or_else(|e| panic!("{e}"));
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    assert_eq!(loaded.scene.handles[0].nodes.len(), 8, "the input ring");
    let mut sim = Simulation::new(loaded.scene).unwrap();
    // ARCSim's initial relaxation remeshes before frame 0 (`initial_relax`): ring edges may be
    // split already, and their new nodes are held like the input's.
    assert!(sim.state.handle_nodes[0].len() >= 8);
    let uv = |sim: &Simulation, n: usize| sim.state.mesh.verts.iter().find(|v| v.node.idx() == n).unwrap().u;
    for frame in 1..=30 {
        sim.advance_frame().unwrap();
        for (h, handle) in sim.scene.handles.iter().enumerate() {
            let HandleKind::Circle(circle) = &handle.kind else { panic!("handle {h} is not a circle") };
            for &n in &sim.state.handle_nodes[h] {
                let target = handle.circle_target(circle, &uv(&sim, n), sim.state.time);
                let off = (x(&sim, n) - target).norm();
                assert!(off < 1e-3, "frame {frame}: ring {h} node {n} {off} m off its circle point");
            }
        }
    }
    let ring = &sim.state.handle_nodes[1];
    assert!(ring.len() > 8, "no ring edge was split ({} nodes)", ring.len());
    // Turned by 90°: the node at u = 0 is on the +y axis.
    let n0 = *ring.iter().find(|&&n| uv(&sim, n).x.abs() < 1e-12 || (uv(&sim, n).x - c).abs() < 1e-12).unwrap();
    let r = c / std::f64::consts::TAU;
    assert!((x(&sim, n0) - Vec3::new(0.0, r, height)).norm() < 1e-3, "{}", x(&sim, n0));
}

/// A handle without "nodes" (sphere-annotated.json's "vertices") holds nothing in ARCSim: it is
/// skipped with one warning naming the field, and the conf loads.
#[test]
fn a_handle_with_vertices_instead_of_nodes_is_skipped_with_a_warning() {
    let dir = temp_dir("vertices");
    let conf = json!({
        "frame_time": 0.02, "frame_steps": 2, "end_frame": 2,
        "cloths": [{"mesh": "meshes/grid.obj", "materials": [{"data": "materials/soft.json"}]}],
        "handles": [{"vertices": [2, 3], "end_time": 7}, {"nodes": [0]}]
    });
    let path = write_conf(&dir, "vertices", &conf, &[("grid.obj", grid_obj(0.2, 2))]);
    let loaded = scene::load_path(&path, None).unwrap();
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].starts_with("handles[0].vertices: "), "{:?}", loaded.warnings);
    assert_eq!(loaded.scene.handles.len(), 1);
    assert_eq!(loaded.scene.handles[0].nodes, vec![0]);
}

// ---------------------------------------------------------------------------------------------
// Obstacles

fn box_obstacle(top: Real, window: Value) -> Value {
    let mut o = json!({"box": {"size": [1.0, 1.0, 0.1]}, "transform": {"translate": [0.1, 0.1, top - 0.05]}});
    for (k, v) in window.as_object().unwrap() {
        o[k] = v.clone();
    }
    o
}

/// An obstacle takes part only during its window: the sheet lands on a box present until
/// t = 0.4 and rests on it, never crossing it, then falls through where it was; a second box
/// appearing at t = 0.6 catches it.
#[test]
fn obstacles_are_present_only_during_their_window() {
    let mut cloth = sheet(0.2, 4);
    cloth["transform"] = json!({"translate": [0, 0, 0.02]});
    let obstacles =
        json!([box_obstacle(0.0, json!({"end_time": 0.4})), box_obstacle(-1.5, json!({"start_time": 0.6}))]);
    let v = scene_of(cloth, json!({"obstacles": obstacles, "frames": 70, "collision": {"thickness": 0.004}}));
    let mut sim = sim_of(&v, "window");
    let (mut lowest_while_held, mut crossings) = (Real::INFINITY, 0);
    for frame in 1..=70 {
        sim.advance_frame().unwrap();
        let t = sim.state.time;
        let zs: Vec<Real> = sim.state.mesh.nodes.iter().map(|n| n.x.z).collect();
        let lo = zs.iter().copied().fold(Real::INFINITY, Real::min);
        let hi = zs.iter().copied().fold(Real::NEG_INFINITY, Real::max);
        crossings += sim.crossings().obstacle.len();
        assert_eq!(sim.penetrations(), 0, "frame {frame}: nodes inside a present obstacle");
        if t <= 0.4 {
            lowest_while_held = lowest_while_held.min(lo);
        }
        if (0.58..0.6).contains(&t) {
            assert!(hi < -0.1, "t = {t:.2}: the sheet did not fall through the absent box (top at z = {hi})");
        }
        if t >= 1.3 {
            assert!(
                lo > -1.5 - 0.004 && hi < -1.3,
                "t = {t:.2}: the second box did not hold the sheet: z in [{lo}, {hi}]"
            );
        }
    }
    assert_eq!(crossings, 0, "cloth crossed a present obstacle");
    assert!(lowest_while_held > -0.004, "the sheet sank to z = {lowest_while_held} into the box while it was present");
}

/// A closed obstacle whose normals face inward on purpose (ARCSim's `sphere-inv.obj`, cloth
/// crumpled inside a sphere) keeps them: its inside is outside the sphere, and a sheet dropped
/// inside it stays inside.
#[test]
fn cloth_inside_an_inward_facing_sphere_stays_inside() {
    let dir = temp_dir("inward");
    let r = 0.2;
    let (x0, tris) = sphere_mesh(r, 0.01);
    let mut obj = String::new();
    x0.iter().for_each(|p| obj += &format!("v {} {} {}\n", p.x, p.y, p.z));
    // Inward: every face turned.
    tris.iter().for_each(|t| obj += &format!("f {} {} {}\n", t[0] + 1, t[2] + 1, t[1] + 1));
    std::fs::write(dir.join("shell.obj"), obj).unwrap();
    let mut cloth = sheet(0.16, 8);
    cloth["transform"] = json!({"translate": [-0.08, -0.08, 0.0]});
    let v =
        scene_of(cloth, json!({"obstacles": [{"mesh": "shell.obj"}], "frames": 40, "collision": {"thickness": 0.003}}));
    let mut sim = Simulation::new(inline_scene(&v, &dir, "inward")).unwrap_or_else(|e| panic!("{e}"));
    for frame in 1..=40 {
        sim.advance_frame().unwrap();
        let far = sim.state.mesh.nodes.iter().map(|n| n.x.norm()).fold(0.0, Real::max);
        assert!(far < r, "frame {frame}: a node {far} m from the centre, outside the shell of radius {r}");
        assert_eq!(sim.penetrations(), 0, "frame {frame}");
    }
    // It did fall onto the shell's bottom.
    let low = sim.state.mesh.nodes.iter().map(|n| n.x.z).fold(Real::INFINITY, Real::min);
    assert!(low < -0.15, "the sheet never reached the bottom of the shell: lowest z = {low}");
}

// ---------------------------------------------------------------------------------------------
// disable

fn falling_onto_box(disable: &[&str]) -> Value {
    let mut cloth = sheet(0.2, 4);
    cloth["transform"] = json!({"translate": [0, 0, 0.02]});
    cloth["strain_limits"] = json!([0.9, 1.1]);
    cloth["lra"] = json!({});
    cloth["handles"] = json!([{"nodes": [0], "end_time": 0.01}]);
    cloth["remesh"] = json!({"refine_angle": 0.3, "size": [0.01, 0.1]});
    scene_of(cloth, json!({"obstacles": [box_obstacle(0.0, json!({}))], "frames": 10, "disable": disable}))
}

/// Every stage `disable` names is off: no remeshing, strain limits or attachments built, no
/// repulsion contacts, no solve (the sheet hangs in the air), no collision stage (with
/// proximity also off the sheet falls through the box).
#[test]
fn disable_switches_each_stage_off() {
    let base = sim_of(&falling_onto_box(&[]), "all_on");
    let c = &base.scene.cloths[0];
    assert!(c.remesh.is_some() && c.strain_limits.is_some() && c.lra.is_some());
    let off = sim_of(&falling_onto_box(&["remeshing", "strain_limiting", "lra", "separation"]), "off");
    let c = &off.scene.cloths[0];
    assert!(c.remesh.is_none() && c.strain_limits.is_none() && c.lra.is_none() && off.scene.disabled.separation);
    assert!(off.ws.constraints.is_none());

    let run = |disable: &[&str]| {
        let mut sim = sim_of(&falling_onto_box(disable), "run");
        let z0: Vec<Real> = sim.state.mesh.nodes.iter().map(|n| n.x.z).collect();
        for _ in 0..10 {
            sim.advance_frame().unwrap();
        }
        let ran: Vec<&str> = sim.ws.timers.ran().collect();
        let lowest = sim.state.mesh.nodes.iter().map(|n| n.x.z).fold(Real::INFINITY, Real::min);
        let still = sim.state.mesh.nodes.iter().zip(&z0).all(|(n, z)| n.x.z == *z);
        (sim.ws.counters.contacts, ran.contains(&"collision"), lowest, still)
    };
    let (contacts, collided, lowest, still) = run(&[]);
    assert!(contacts > 0 && collided && lowest > -0.01 && !still);
    let (contacts, collided, lowest, _) = run(&["proximity"]);
    assert!(contacts == 0 && collided && lowest > -0.01, "proximity off: {contacts} contacts, lowest {lowest}");
    let (contacts, collided, _, _) = run(&["collision"]);
    assert!(contacts > 0 && !collided, "collision off: the collision stage ran");
    let (_, _, lowest, _) = run(&["proximity", "collision"]);
    assert!(lowest < -0.1, "proximity and collision off: the sheet stayed on the box (lowest {lowest})");
    let (_, _, _, still) = run(&["physics", "remeshing"]);
    assert!(still, "physics off: the sheet moved");

    let bad = json!({"disable": ["popfilter"]});
    let mut v = falling_onto_box(&[]);
    v["disable"] = bad["disable"].clone();
    let err = scene::load_str(&v.to_string(), Path::new("s.json"), Path::new("."), "s").unwrap_err().to_string();
    assert!(err.contains("disable[0]") && err.contains("\"physics\"") && !err.contains('\n'), "{err}");
}

/// A conf's `disable`: stages viewcloth has are switched off (plasticity among them); those it
/// lacks are named in one warning, each once; a name that is no ARCSim module is ignored (as ARCSim does) with its own
/// warning.
#[test]
fn a_confs_disable_is_honoured_and_the_absent_stages_warned_once() {
    let dir = temp_dir("disable");
    let conf = json!({
        "frame_time": 0.02, "frame_steps": 2, "end_frame": 2,
        "cloths": [{"mesh": "meshes/grid.obj",
                    "materials": [{"data": "materials/soft.json", "strain_limits": [0.9, 1.1], "yield_curv": 100}],
                    "remeshing": {"size": [0.01, 0.1]}}],
        "disable": ["fracture", "strainlimiting", "plasticity", "fracture", "collision", "popfilter", "remeshing", "warp"]
    });
    let path = write_conf(&dir, "disable", &conf, &[("grid.obj", grid_obj(0.2, 2))]);
    let out = viewcloth(&["check", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    let about: Vec<&&str> = lines.iter().filter(|l| l.contains(": disable: ")).collect();
    assert_eq!(about.len(), 1, "{stderr}");
    assert_eq!(about[0].matches("fracture").count(), 1, "{stderr}");
    assert_eq!(about[0].matches("plasticity").count(), 0, "plasticity is a stage here: {stderr}");
    assert_eq!(about[0].matches("popfilter").count(), 0, "the pop filter is a stage here: {stderr}");
    assert!(lines.iter().any(|l| l.contains(": disable[7]: ") && l.contains("warp")), "{stderr}");
    assert_eq!(lines.len(), 2, "{stderr}");
    let s = scene::load_path(&path, None).unwrap().scene;
    assert!(s.disabled.collision && s.disabled.pop_filter && !s.disabled.proximity && !s.disabled.physics);
    assert!(s.cloths[0].strain_limits.is_none() && s.cloths[0].remesh.is_none());
    assert!(s.materials.iter().all(|m| m.plasticity.is_none()), "disable: plasticity keeps bending elastic");
    assert!(s.collision.self_collision, "ARCSim's proximity still handles cloth–cloth contact");
}

// ---------------------------------------------------------------------------------------------
// The shared confs

/// Every conf in `../shared/arcsim` still passes `check` with the warnings it had before (none,
/// or flag.json's `duration`).
#[test]
fn the_shared_confs_still_check_with_their_old_warnings() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/arcsim/conf");
    if !dir.is_dir() {
        eprintln!("SKIP: ARCSim data not found at {}", dir.display());
        return;
    }
    let mut confs: Vec<PathBuf> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    confs.sort();
    assert!(confs.len() >= 4);
    for conf in confs {
        let out = viewcloth(&["check", conf.to_str().unwrap()]);
        let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        assert!(out.status.success() && stdout.trim_end().ends_with(": ok"), "{}: {stderr}", conf.display());
        let warned: Vec<&str> = stderr.lines().collect();
        match conf.file_name().unwrap().to_str().unwrap() {
            "flag.json" => assert!(warned.len() == 1 && warned[0].contains(": duration: "), "{stderr}"),
            _ => assert!(warned.is_empty(), "{}: {stderr}", conf.display()),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Determinism

/// Soft, circle, glue and fading handles and an obstacle window give the same bits on one
/// thread and on two.
#[test]
fn handles_and_windows_give_the_same_bits_on_any_thread_count() {
    let dir = temp_dir("threads");
    let (_, _, tube) = tube_conf(&dir);
    let mut cloth = sheet(0.2, 4);
    cloth["transform"] = json!({"translate": [0, 0, 0.02]});
    cloth["handles"] = json!([{"glue": [0, 24], "stiffness": 100.0},
                              {"nodes": [4], "stiffness": 500.0, "start_time": 0.05, "end_time": 0.1, "fade_time": 0.05}]);
    let v = scene_of(cloth, json!({"obstacles": [box_obstacle(0.0, json!({"end_time": 0.08}))], "frames": 8}));
    let native = dir.join("native.json");
    std::fs::write(&native, v.to_string()).unwrap();
    for scene in [tube, native] {
        let run = |threads: &str| {
            let out = dir.join(format!("{}_{threads}", scene.file_stem().unwrap().to_str().unwrap()));
            let args = ["simulate", scene.to_str().unwrap(), "--frames", "6", "--threads", threads, "--quiet"];
            let o = viewcloth(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            (0..=6).map(|k| std::fs::read(out.join(format!("frame_{k:04}.obj"))).unwrap()).collect::<Vec<_>>()
        };
        assert!(run("1") == run("2"), "{}: frames differ between 1 and 2 threads", scene.display());
    }
}
