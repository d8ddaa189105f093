//! Issue 14: `viewcloth resample` (Brown, Samii, O'Brien & Narain 2015). Resampling a uniform
//! run onto its own mesh reproduces it; an adaptive run resampled onto `--auto` has one face
//! list in every frame, its vertices on the adaptive surface, an error per frame, a PC2 cache
//! and a USD layer; bad input is refused in one line.

use std::path::Path;

mod common;
use common::{temp_dir, viewcloth};
use serde_json::{json, Value};
use viewcloth::io::obj::parse_obj;
use viewcloth::math::Vec3;

fn ok(args: &[&str]) -> String {
    let o = viewcloth(args);
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn scene(dir: &Path, remesh: bool) -> String {
    let mut cloth = json!({
        "rectangle": { "width": 1.0, "height": 1.0, "resolution": [6, 6] },
        "transform": { "translate": [-0.5, -1.0, 0.5] },
        "material": { "preset": "cotton" },
        "handles": [{ "nodes": [42, 48] }]
    });
    if remesh {
        cloth["remesh"] =
            json!({ "refine_angle": 0.3, "refine_compression": 0.01, "refine_velocity": 1.0, "size": [0.06, 0.3] });
    }
    let v = json!({ "version": 1, "frame_time": 0.04, "steps_per_frame": 4, "frames": 4, "start_frame": 101,
                    "cloths": [cloth], "collision": { "self_collision": false } });
    let file = dir.join(if remesh { "adaptive.json" } else { "uniform.json" });
    std::fs::write(&file, v.to_string()).unwrap();
    file.to_string_lossy().into_owned()
}

fn frame(dir: &Path, n: usize) -> (String, viewcloth::io::obj::ObjData) {
    let text = std::fs::read_to_string(dir.join(format!("frame_{n:04}.obj"))).unwrap();
    let obj = parse_obj(&text).unwrap();
    (text, obj)
}

/// Distance from `p` to the nearest triangle of `mesh`.
fn distance_to_surface(p: Vec3, mesh: &viewcloth::io::obj::ObjData) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|c| mesh.positions[c.v]);
            point_triangle(p, a, b, c)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to triangle `abc` (Ericson, "Real-Time Collision Detection", 5.1.5).
fn point_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let n = (b - a).cross(&(c - a));
    let inside = [(a, b), (b, c), (c, a)].iter().all(|(s, t)| (t - s).cross(&(p - s)).dot(&n) >= 0.0);
    if inside {
        return (p - a).dot(&n).abs() / n.norm();
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|(s, t)| {
            let e = t - s;
            let u = ((p - s).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
            (s + e * u - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn resampling_a_uniform_run_onto_its_mesh_reproduces_it() {
    let dir = temp_dir("uniform");
    let (s, run, out) = (scene(&dir, false), dir.join("run"), dir.join("resampled"));
    ok(&["simulate", &s, "--out", run.to_str().unwrap(), "--quiet", "--obj-velocities"]);
    let mesh = run.join("frame_0101.obj");
    ok(&["resample", run.to_str().unwrap(), "--mesh", mesh.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    for n in 101..=105 {
        let ((_, a), (_, b)) = (frame(&run, n), frame(&out, n));
        assert_eq!(a.positions.len(), b.positions.len());
        for (p, q) in a.positions.iter().zip(&b.positions) {
            assert!((p - q).norm() < 2e-9, "frame {n}: {p:?} resampled at {q:?}");
        }
        let faces = |o: &viewcloth::io::obj::ObjData| o.triangles.iter().map(|t| t.map(|c| c.v)).collect::<Vec<_>>();
        assert_eq!(faces(&a), faces(&b), "frame {n}");
    }
    let report: Value = serde_json::from_str(&std::fs::read_to_string(out.join("resample.json")).unwrap()).unwrap();
    for f in report["frames"].as_array().unwrap() {
        assert!(f["max"].as_f64().unwrap() < 1e-9, "{f}");
    }
    assert_eq!(report["faces"], report["run_max_faces"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn adaptive_run_resampled_onto_auto_has_one_topology_on_its_surface() {
    let dir = temp_dir("adaptive");
    let (s, run, out) = (scene(&dir, true), dir.join("run"), dir.join("resampled"));
    ok(&["simulate", &s, "--out", run.to_str().unwrap(), "--quiet", "--obj-velocities"]);
    let line = ok(&["resample", run.to_str().unwrap(), "--auto", "--out", out.to_str().unwrap()]);
    assert!(line.contains("5 frames resampled onto"), "{line}");
    let report: Value = serde_json::from_str(&std::fs::read_to_string(out.join("resample.json")).unwrap()).unwrap();
    let faces_of = |text: &str| text.lines().filter(|l| l.starts_with("f ")).map(str::to_string).collect::<Vec<_>>();
    let (first_text, first) = frame(&out, 101);
    let faces = faces_of(&first_text);
    assert_eq!(faces.len() as u64, report["faces"].as_u64().unwrap());
    let (_, run0) = frame(&run, 101);
    assert!(faces.len() >= run0.triangles.len(), "auto mesh coarser than the first frame");
    for n in 101..=105 {
        let ((text, resampled), (_, adaptive)) = (frame(&out, n), frame(&run, n));
        assert_eq!(faces_of(&text), faces, "frame {n}: another face list");
        assert_eq!(resampled.positions.len(), first.positions.len());
        let error = report["frames"][n - 101]["max"].as_f64().unwrap();
        assert!(error.is_finite() && error < 0.05, "frame {n}: error {error}");
        // Each resampled vertex is on the adaptive surface (to the OBJ's printed precision).
        for p in &resampled.positions {
            let d = distance_to_surface(*p, &adaptive);
            assert!(d < 1e-8 && d <= error + 1e-8, "frame {n}: a vertex {d} m off the adaptive surface");
        }
    }
    let pc2 = std::fs::read(out.join("cloth.pc2")).unwrap();
    assert_eq!(&pc2[..12], b"POINTCACHE2\0");
    assert_eq!(pc2.len(), 32 + 5 * first.positions.len() * 12);
    let layer = std::fs::read_to_string(out.join("cloth.usda")).unwrap();
    assert!(layer.contains("startTimeCode = 101\n") && layer.contains("int[] faceVertexIndices = ["));
    assert!(layer.contains("vector3f[] velocities.timeSamples"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn resample_refuses_bad_input_in_one_line() {
    let dir = temp_dir("bad");
    let (s, run) = (scene(&dir, false), dir.join("run"));
    ok(&["simulate", &s, "--out", run.to_str().unwrap(), "--quiet", "--format", "usd"]);
    let out = dir.join("out");
    let (r, o) = (run.to_str().unwrap(), out.to_str().unwrap());
    let e = viewcloth(&["resample", r, "--auto", "--out", o]);
    let err = String::from_utf8_lossy(&e.stderr);
    assert_eq!(e.status.code(), Some(2), "{err}");
    assert!(err.contains("frame_0101.obj") && err.trim_end().lines().count() == 1, "{err}");
    std::fs::write(dir.join("novt.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    ok(&["simulate", &s, "--out", r, "--quiet", "--force"]);
    let e = viewcloth(&["resample", r, "--mesh", dir.join("novt.obj").to_str().unwrap(), "--out", o]);
    let err = String::from_utf8_lossy(&e.stderr);
    assert_eq!(e.status.code(), Some(2), "{err}");
    assert!(err.contains("novt.obj") && err.contains("texture coordinates"), "{err}");
    assert_eq!(viewcloth(&["resample", r, "--out", o]).status.code(), Some(2), "neither --mesh nor --auto");
    std::fs::remove_dir_all(&dir).ok();
}

/// Two sheets side by side, named, each pinned at two corners; adaptive when `remesh`.
fn two_cloth_scene(dir: &Path, remesh: bool) -> String {
    let cloth = |name: &str, x: f64| {
        let mut c = json!({
            "name": name,
            "rectangle": { "width": 0.6, "height": 0.6, "resolution": [4, 4] },
            "transform": { "translate": [x, -1.0, 0.5] },
            "material": { "preset": "cotton" },
            "handles": [{ "nodes": [20, 24] }]
        });
        if remesh {
            c["remesh"] = json!({ "refine_angle": 0.3, "refine_compression": 0.01, "refine_velocity": 1.0,
                                  "size": [0.05, 0.3] });
        }
        c
    };
    let v = json!({ "version": 1, "frame_time": 0.04, "steps_per_frame": 4, "frames": 4, "start_frame": 101,
                    "cloths": [cloth("left", -1.0), cloth("right", 0.5)], "collision": { "self_collision": false } });
    let file = dir.join(if remesh { "two_adaptive.json" } else { "two_uniform.json" });
    std::fs::write(&file, v.to_string()).unwrap();
    file.to_string_lossy().into_owned()
}

/// The lines of `text` under `o name` up to the next `o`.
fn group_faces(text: &str, name: &str) -> Vec<String> {
    let mut current = None;
    let mut out = Vec::new();
    for l in text.lines() {
        if let Some(n) = l.strip_prefix("o ") {
            current = Some(n.to_string());
        } else if l.starts_with("f ") && current.as_deref() == Some(name) {
            out.push(l.to_string());
        }
    }
    out
}

/// Cloth `name` of an OBJ frame as an OBJ of its own (its faces' `v` and `vt`, renumbered in
/// file order).
fn cloth_obj(text: &str, name: &str) -> String {
    let obj = parse_obj(text).unwrap();
    let faces: Vec<Vec<(usize, usize)>> = group_faces(text, name)
        .iter()
        .map(|f| {
            f[2..]
                .split_whitespace()
                .map(|c| {
                    let mut it = c.split('/').map(|n| n.parse::<usize>().unwrap() - 1);
                    (it.next().unwrap(), it.next().unwrap())
                })
                .collect()
        })
        .collect();
    let used = |k: fn(&(usize, usize)) -> usize| {
        let mut u: Vec<usize> = faces.iter().flatten().map(k).collect();
        u.sort_unstable();
        u.dedup();
        u
    };
    let (vs, vts) = (used(|c| c.0), used(|c| c.1));
    let mut s = String::new();
    for &v in &vs {
        let p = obj.positions[v];
        s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    for &vt in &vts {
        let u = obj.texcoords[vt];
        s.push_str(&format!("vt {} {}\n", u.x, u.y));
    }
    for f in &faces {
        let index = |list: &[usize], x: usize| list.binary_search(&x).unwrap() + 1;
        let c: Vec<String> = f.iter().map(|&(v, vt)| format!("{}/{}", index(&vs, v), index(&vts, vt))).collect();
        s.push_str(&format!("f {}\n", c.join(" ")));
    }
    s
}

#[test]
fn every_cloth_of_a_run_is_resampled() {
    let dir = temp_dir("two_cloths");
    // Uniform: each cloth onto its own first-frame mesh reproduces the run, in its `o` group.
    let (s, run, out) = (two_cloth_scene(&dir, false), dir.join("run"), dir.join("resampled"));
    ok(&["simulate", &s, "--out", run.to_str().unwrap(), "--quiet", "--obj-velocities"]);
    let (first_text, _) = frame(&run, 101);
    let meshes: Vec<String> = ["left", "right"]
        .iter()
        .map(|name| {
            let path = dir.join(format!("{name}.obj"));
            std::fs::write(&path, cloth_obj(&first_text, name)).unwrap();
            path.to_string_lossy().into_owned()
        })
        .collect();
    let (r, o) = (run.to_str().unwrap(), out.to_str().unwrap());
    ok(&["resample", r, "--mesh", &meshes[0], "--mesh", &meshes[1], "--out", o]);
    for n in 101..=105 {
        let ((_, a), (text, b)) = (frame(&run, n), frame(&out, n));
        assert_eq!(a.positions.len(), b.positions.len());
        for (p, q) in a.positions.iter().zip(&b.positions) {
            assert!((p - q).norm() < 2e-9, "frame {n}: {p:?} resampled at {q:?}");
        }
        assert_eq!(text.lines().filter(|l| l.starts_with("o ")).collect::<Vec<_>>(), ["o left", "o right"]);
    }
    let report: Value = serde_json::from_str(&std::fs::read_to_string(out.join("resample.json")).unwrap()).unwrap();
    assert_eq!(report["cloths"].as_array().unwrap().len(), 2);
    assert!(report["frames"].as_array().unwrap().iter().all(|f| f["max"].as_f64().unwrap() < 1e-9));
    let layer = std::fs::read_to_string(out.join("cloth.usda")).unwrap();
    assert!(layer.contains("def Mesh \"left\"") && layer.contains("def Mesh \"right\""));
    // One --mesh for two cloths: refused in one line naming --mesh and the cloths.
    let e = viewcloth(&["resample", r, "--mesh", &meshes[0], "--out", o]);
    let err = String::from_utf8_lossy(&e.stderr);
    assert_eq!(e.status.code(), Some(2), "{err}");
    assert!(err.contains("--mesh") && err.contains("left, right") && err.trim_end().lines().count() == 1, "{err}");

    // Adaptive, --auto: each cloth keeps one face list, its vertices on its own surface.
    let (s, run, out) = (two_cloth_scene(&dir, true), dir.join("arun"), dir.join("aresampled"));
    ok(&["simulate", &s, "--out", run.to_str().unwrap(), "--quiet", "--obj-velocities"]);
    ok(&["resample", run.to_str().unwrap(), "--auto", "--out", out.to_str().unwrap()]);
    let (first_text, first) = frame(&out, 101);
    for n in 101..=105 {
        let ((text, resampled), (_, adaptive)) = (frame(&out, n), frame(&run, n));
        for name in ["left", "right"] {
            assert_eq!(group_faces(&text, name), group_faces(&first_text, name), "frame {n}: {name}'s faces");
        }
        for p in &resampled.positions {
            let d = distance_to_surface(*p, &adaptive);
            assert!(d < 1e-8, "frame {n}: a vertex {d} m off the run's surface");
        }
    }
    let pc2 = std::fs::read(out.join("cloth.pc2")).unwrap();
    assert_eq!(pc2.len(), 32 + 5 * first.positions.len() * 12);
    std::fs::remove_dir_all(&dir).ok();
}
