//! Long range attachments (Kim, Chentanez & Müller 2012) and strain limiting (issue 12): the
//! bound a hanging sheet keeps with them and breaks without, unilaterality, the bound on an
//! adaptive mesh (nodes created by splits included), geodesic against Euclidean rest lengths on a
//! folded pattern, and ARCSim's flag.json with its strain limits.

use std::path::{Path, PathBuf};

use serde_json::json;
use viewcloth::constraints::lra::Constraint;
use viewcloth::constraints::strain_limit::{face_stretches, TOLERANCE};
use viewcloth::math::{Real, Vec2};
use viewcloth::scene;
use viewcloth::sim::Simulation;

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load(scene: serde_json::Value) -> Simulation {
    let s = scene::load_value(scene, Path::new("test.json"), &crate_dir(), "test").unwrap_or_else(|e| panic!("{e}"));
    Simulation::new(s).unwrap_or_else(|e| panic!("{e}"))
}

/// A 1 m sheet hanging in the x–z plane from its whole top edge, with a membrane 200× softer
/// than cotton; optional `lra`, `remesh`, initial velocity and gravity.
fn hanging(
    lra: Option<serde_json::Value>,
    remesh: Option<serde_json::Value>,
    velocity: [f64; 3],
    g: f64,
) -> Simulation {
    // Coarse when remeshed, so that the remesher has to split.
    let res = if remesh.is_some() { 4 } else { 16 };
    let mut cloth = json!({
        "name": "sheet",
        "rectangle": {"width": 1.0, "height": 1.0, "resolution": [res, res]},
        "transform": {"rotate": [90, 1, 0, 0], "translate": [0, 0, 1]},
        "velocity": velocity,
        "material": {"preset": "cotton", "stretching_mult": 0.005},
        "handles": [{"region": {"min": [-0.01, 0.99], "max": [1.01, 1.01]}}]
    });
    if let Some(l) = lra {
        cloth["lra"] = l;
    }
    if let Some(r) = remesh {
        cloth["remesh"] = r;
    }
    load(json!({
        "version": 1, "name": "hanging_lra", "frame_time": 0.04, "steps_per_frame": 5, "frames": 10,
        "gravity": [0, 0, g], "cloths": [cloth]
    }))
}

fn constraints(sim: &Simulation) -> Vec<Constraint> {
    sim.ws.constraints.as_ref().unwrap().lra.as_ref().unwrap().lra.constraints.clone()
}

/// The largest |x_i − x_a| / rest over `cs` at the current state.
fn worst_ratio(sim: &Simulation, cs: &[Constraint]) -> Real {
    let x = sim.mesh().positions();
    cs.iter().map(|c| (x[c.node as usize] - x[c.attachment as usize]).norm() / c.rest).fold(0.0, Real::max)
}

/// The straight material-space distance from node `i` to the closest pinned (top-row) node:
/// the exact geodesic on this convex panel.
fn exact_rest(sim: &Simulation, i: usize) -> Real {
    let m = sim.mesh();
    let u = |n: usize| m.verts.iter().find(|v| v.node.idx() == n).unwrap().u;
    sim.state.handle_nodes[0].iter().map(|&a| (u(i) - u(a)).norm()).fold(Real::INFINITY, Real::min)
}

#[test]
fn hanging_sheet_stays_within_its_attachment_spheres_only_with_lra() {
    let stretch = 0.02;
    let mut with = hanging(Some(json!({"stretch": stretch})), None, [0.0; 3], -9.81);
    let mut without = hanging(None, None, [0.0; 3], -9.81);
    let cs = constraints(&with);
    assert_eq!(cs.len(), 17 * 16, "every free node tied to one attachment (one island: the top edge)");
    let (mut worst_with, mut worst_without) = (0.0 as Real, 0.0 as Real);
    for _ in 0..6 {
        with.advance_frame().unwrap();
        without.advance_frame().unwrap();
        worst_with = worst_with.max(worst_ratio(&with, &cs));
        worst_without = worst_without.max(worst_ratio(&without, &cs));
    }
    eprintln!("largest |x − x_a| / rest: with LRA {worst_with:.4}, without {worst_without:.4}");
    assert!(worst_with <= 1.0 + stretch + 0.01, "with LRA: {worst_with}");
    assert!(worst_without > 1.0 + stretch + 0.01, "without LRA the soft sheet should stretch: {worst_without}");
}

#[test]
fn pushing_towards_the_attachments_applies_no_correction() {
    // No gravity, every node moving up (toward the top edge): the constraints stay slack and
    // the run is bit for bit the one without LRA.
    let mut with = hanging(Some(json!({"stretch": 0.0})), None, [0.0, 0.0, 0.5], 0.0);
    let mut without = hanging(None, None, [0.0, 0.0, 0.5], 0.0);
    for _ in 0..3 {
        with.advance_frame().unwrap();
        without.advance_frame().unwrap();
    }
    let (a, b) = (with.mesh().positions(), without.mesh().positions());
    assert_eq!(a, b, "a slack attachment moved a node");
    let (_, taut) = with.ws.constraints.as_ref().unwrap().lra.as_ref().unwrap().lra.measure(&a);
    assert_eq!(taut, 0);
}

#[test]
fn with_remeshing_the_bound_holds_for_every_node_including_split_ones() {
    let stretch = 0.02;
    let remesh = json!({"refine_angle": 0.3, "refine_compression": 0.01, "refine_velocity": 0.5, "size": [0.02, 0.2]});
    let mut sim = hanging(Some(json!({"stretch": stretch})), Some(remesh), [0.0; 3], -9.81);
    let n0 = sim.mesh().nodes.len();
    let mut grew = false;
    for _ in 0..5 {
        sim.advance_frame().unwrap();
        let cs = constraints(&sim);
        let m = sim.mesh();
        grew |= m.nodes.len() > n0;
        // Every free node has a constraint, with the exact material-space rest length.
        let pinned: std::collections::HashSet<usize> = sim.state.handle_nodes[0].iter().copied().collect();
        let mut tied = vec![false; m.nodes.len()];
        for c in &cs {
            tied[c.node as usize] = true;
            let exact = exact_rest(&sim, c.node as usize);
            // Within 0.5% on the adaptive mesh (refined shortest paths, straight where visible).
            assert!((c.rest - exact).abs() <= 0.005 * exact + 1e-9, "node {}: rest {} exact {exact}", c.node, c.rest);
        }
        assert!((0..m.nodes.len()).all(|i| tied[i] || pinned.contains(&i)), "a free node has no attachment");
        let w = worst_ratio(&sim, &cs);
        assert!(w <= 1.0 + stretch + 0.01, "bound broken after remeshing: {w}");
    }
    assert!(grew, "the mesh should have been refined (split nodes present)");
}

/// A U-shaped pattern (two 0.3 m wide arms joined at the bottom, a 0.4 m gap between them),
/// lying flat at z = 1 and held by the top of its left arm: a pattern folded back on itself
/// (the paper's Fig. 4 has the fold in the rest shape; here material space is the rest shape).
/// Under gravity the cloth falls and hangs. Geodesic rest lengths (down, across, up) let the
/// right arm fall open below; straight material distances across the gap hold its top within
/// 0.7 m of the attachment.
fn u_pattern(dir: &Path) -> PathBuf {
    let (nx, ny, h) = (10usize, 10usize, 0.1);
    let inside = |i: usize, j: usize| !(i >= 3 && i < 7 && j >= 3); // cell (i, j) kept?
    let id = |i: usize, j: usize| j * (nx + 1) + i + 1;
    let mut used = vec![false; (nx + 1) * (ny + 1) + 1];
    let mut faces = String::new();
    for j in 0..ny {
        for i in 0..nx {
            if inside(i, j) {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                faces += &format!("f {a}/{a} {b}/{b} {c}/{c}\nf {a}/{a} {c}/{c} {d}/{d}\n");
                for k in [a, b, c, d] {
                    used[k] = true;
                }
            }
        }
    }
    // Unused vertices are rejected: keep them out by renumbering.
    let mut map = vec![0usize; used.len()];
    let (mut vs, mut vts, mut next) = (String::new(), String::new(), 0);
    for j in 0..=ny {
        for i in 0..=nx {
            let k = id(i, j);
            if used[k] {
                next += 1;
                map[k] = next;
                vs += &format!("v {} {} 1\n", i as f64 * h, j as f64 * h);
                vts += &format!("vt {} {}\n", i as f64 * h, j as f64 * h);
            }
        }
    }
    let faces: String = faces
        .lines()
        .map(|l| {
            let idx: Vec<String> = l[2..]
                .split(' ')
                .map(|t| {
                    let k: usize = t.split('/').next().unwrap().parse().unwrap();
                    format!("{0}/{0}", map[k])
                })
                .collect();
            format!("f {}\n", idx.join(" "))
        })
        .collect();
    let path = dir.join("u_pattern.obj");
    std::fs::write(&path, vs + &vts + &faces).unwrap();
    path
}

fn u_sim(dir: &Path, distance: &str) -> Simulation {
    let mesh = u_pattern(dir);
    let scene = json!({
        "version": 1, "name": "u_fold", "frame_time": 0.04, "steps_per_frame": 4, "frames": 14,
        "gravity": [0, 0, -9.81],
        "cloths": [{
            "name": "u", "mesh": mesh.to_str().unwrap(),
            "material": {"preset": "cotton", "bending_mult": 0.01},
            "rest_angles": "flat",
            "lra": {"stretch": 0.0, "distance": distance},
            "handles": [{"region": {"min": [-0.01, 0.99], "max": [0.31, 1.01]}}]
        }]
    });
    let s = scene::load_value(scene, &dir.join("u.json"), dir, "u").unwrap_or_else(|e| panic!("{e}"));
    Simulation::new(s).unwrap()
}

#[test]
fn geodesic_rest_lengths_let_a_folded_pattern_open_and_euclidean_ones_do_not() {
    let dir = std::env::temp_dir().join(format!("viewcloth-lra-u-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut geo = u_sim(&dir, "geodesic");
    let mut euc = u_sim(&dir, "euclidean");
    // The right arm's top-right corner: material (1, 1).
    let corner = |sim: &Simulation| {
        let m = sim.mesh();
        m.verts.iter().find(|v| (v.u - Vec2::new(1.0, 1.0)).norm() < 1e-9).unwrap().node.idx()
    };
    let (cg, ce) = (corner(&geo), corner(&euc));
    let rest = |sim: &Simulation, n: usize| constraints(sim).iter().find(|c| c.node as usize == n).unwrap().rest;
    let (rg, re) = (rest(&geo, cg), rest(&euc, ce));
    eprintln!("rest length of the right arm's corner: geodesic {rg:.3} m, euclidean {re:.3} m");
    assert!(rg > 1.4 * re, "geodesic {rg} vs euclidean {re}");
    for _ in 0..20 {
        geo.advance_frame().unwrap();
        euc.advance_frame().unwrap();
    }
    let (zg, ze) = (geo.mesh().nodes[cg].x.z, euc.mesh().nodes[ce].x.z);
    eprintln!("right arm's corner height after 20 frames: geodesic {zg:.3} m, euclidean {ze:.3} m (started at 1.0)");
    assert!(ze > 1.0 - re - 1e-6, "euclidean holds the corner within its sphere");
    assert!(zg < ze - 0.3, "the fold should open with geodesic rest lengths: {zg} vs {ze}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The principal stretch range over the faces at the current state.
fn stretch_range(sim: &Simulation) -> (Real, Real) {
    let m = sim.mesh();
    let x = m.positions();
    let (mut lo, mut hi) = (Real::INFINITY, 0.0 as Real);
    for f in 0..m.faces.len() {
        let s = face_stretches(m, &sim.ws.rest.membrane[f], f, &x);
        lo = lo.min(s[0]);
        hi = hi.max(s[1]);
    }
    (lo, hi)
}

/// Principal stretches of every face from the mesh's positions and material coordinates,
/// computed here (first fundamental form in material coordinates, its eigenvalues in closed
/// form) rather than by the limiter's code.
fn stretches_from_mesh(sim: &Simulation) -> Vec<(Real, Real)> {
    let m = sim.mesh();
    (0..m.faces.len())
        .map(|f| {
            let [a, b, c] = m.face_nodes(f).map(|n| m.nodes[n].x);
            let [ua, ub, uc] = m.face_uv(f);
            let (e1, e2) = (b - a, c - a);
            let (d1, d2) = (ub - ua, uc - ua);
            let det = d1.x * d2.y - d2.x * d1.y;
            // Columns of D_m⁻¹ combine the edges into F's columns.
            let f0 = (e1 * d2.y - e2 * d1.y) / det;
            let f1 = (e2 * d1.x - e1 * d2.x) / det;
            let (g00, g01, g11) = (f0.dot(&f0), f0.dot(&f1), f1.dot(&f1));
            let (mean, r) = (0.5 * (g00 + g11), (0.25 * (g00 - g11).powi(2) + g01 * g01).sqrt());
            ((mean - r).max(0.0).sqrt(), (mean + r).sqrt())
        })
        .collect()
}

/// ARCSim's flag.json sets `strain_limits: [0.95, 1.05]` (the bound): after every
/// step's projection no face's principal stretch is outside them by more than the solver
/// tolerance, and at every frame end (after collision handling and remeshing) the faces, measured
/// independently, are still within them; without limits the flag leaves them by far.
#[test]
fn arcsim_flag_stays_within_its_strain_limits() {
    let conf = crate_dir().join("../shared/arcsim/conf/flag.json");
    if !conf.is_file() {
        eprintln!("SKIP: ARCSim data not found at {}", conf.display());
        return;
    }
    let loaded = scene::load_path(&conf, None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.scene.cloths[0].strain_limits, Some([0.95, 1.05]));
    let mut free_scene = loaded.scene.clone();
    free_scene.cloths[0].strain_limits = None;
    let mut sim = Simulation::new(loaded.scene).unwrap();
    let mut free = Simulation::new(free_scene).unwrap();
    let mut out_without: Real = 0.0;
    for frame in 1..=8 {
        sim.advance_frame().unwrap();
        free.advance_frame().unwrap();
        let mut fs = sim.measure(frame);
        sim.constraint_stats(&mut fs);
        let st = fs.strain_limit.expect("strain limit stats");
        let s = stretches_from_mesh(&sim);
        let lo = s.iter().map(|s| s.0).fold(Real::INFINITY, Real::min);
        let hi = s.iter().map(|s| s.1).fold(0.0, Real::max);
        let (flo, fhi) = stretch_range(&free);
        eprintln!(
            "flag frame {frame}: {} faces; stretches with limits [{lo:.4}, {hi:.4}], without [{flo:.4}, {fhi:.4}]; {st:?}",
            sim.mesh().faces.len()
        );
        assert_eq!(st.strain_limit_unconverged, 0, "frame {frame}: a projection stopped short: {st:?}");
        assert!(st.strain_limit_excess <= TOLERANCE, "frame {frame}: {st:?}");
        assert!(lo >= 0.95 - TOLERANCE && hi <= 1.05 + TOLERANCE, "frame {frame}: stretches [{lo}, {hi}]");
        out_without = out_without.max(0.95 - flo).max(fhi - 1.05);
    }
    assert!(out_without > 0.1, "without limits the flag should leave [0.95, 1.05] by far: {out_without}");
}

#[test]
fn bad_lra_and_strain_limit_values_are_one_line_errors_naming_the_field() {
    let scene = |extra: serde_json::Value| {
        let mut cloth = json!({"rectangle": {"width": 1.0, "height": 1.0, "resolution": [2, 2]}, "material": {}});
        for (k, v) in extra.as_object().unwrap() {
            cloth[k] = v.clone();
        }
        json!({"version": 1, "frame_time": 0.04, "steps_per_frame": 1, "frames": 1, "cloths": [cloth]})
    };
    let cases = [
        (json!({"lra": {"stretch": -1}}), "cloths[0].lra.stretch"),
        (json!({"lra": {"max_attachments": 0}}), "cloths[0].lra.max_attachments"),
        (json!({"lra": {"distance": "manhattan"}}), "cloths[0].lra.distance"),
        (json!({"lra": {"radius": 1}}), "cloths[0].lra"),
        (json!({"strain_limits": [1.1, 1.2]}), "cloths[0].strain_limits"),
    ];
    for (extra, field) in cases {
        let e = scene::load_value(scene(extra.clone()), Path::new("s.json"), &crate_dir(), "s").unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(field) && !msg.contains('\n'), "{extra}: {msg}");
    }
    let ok = scene::load_value(scene(json!({"lra": {}})), Path::new("s.json"), &crate_dir(), "s").unwrap();
    assert_eq!(ok.cloths[0].lra, Some(viewcloth::constraints::LraParams::default()));
}

/// Through the command line: stats.json lists the `lra` and `strain_limit` stages and their
/// per-frame fields, and a run resumed from a checkpoint (constraints rebuilt from the state,
/// on an adaptive mesh) writes the same bytes as an uninterrupted one.
#[test]
fn stats_and_resume_with_lra_and_strain_limits() {
    let dir = std::env::temp_dir().join(format!("viewcloth-lra-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = json!({
        "version": 1, "name": "lra_cli", "frame_time": 0.04, "steps_per_frame": 4, "frames": 4,
        "gravity": [0, 0, -9.81],
        "cloths": [{
            "rectangle": {"width": 0.5, "height": 0.5, "resolution": [4, 4]},
            "transform": {"rotate": [90, 1, 0, 0], "translate": [0, 0, 1]},
            "material": {"preset": "cotton", "stretching_mult": 0.01},
            "lra": {"stretch": 0.01},
            "strain_limits": [0.9, 1.1],
            "remesh": {"refine_angle": 0.3, "refine_velocity": 0.5, "size": [0.03, 0.2]},
            "handles": [{"region": {"min": [-0.01, 0.49], "max": [0.51, 0.51]}}]
        }]
    });
    let file = dir.join("lra_cli.json");
    std::fs::write(&file, scene.to_string()).unwrap();
    let bin = env!("CARGO_BIN_EXE_viewcloth");
    let run = |args: &[&str]| {
        let out = std::process::Command::new(bin).args(args).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    };
    let (full, part) = (dir.join("full"), dir.join("part"));
    let f = file.to_str().unwrap();
    run(&["simulate", f, "--out", full.to_str().unwrap(), "--quiet", "--threads", "1"]);
    run(&[
        "simulate",
        f,
        "--frames",
        "2",
        "--checkpoint-every",
        "2",
        "--out",
        part.to_str().unwrap(),
        "--quiet",
        "--threads",
        "1",
    ]);
    run(&["resume", part.to_str().unwrap(), "--frames", "4", "--quiet", "--threads", "1"]);
    for k in 0..=4 {
        let name = format!("frame_{k:04}.obj");
        assert_eq!(std::fs::read(full.join(&name)).unwrap(), std::fs::read(part.join(&name)).unwrap(), "{name}");
    }
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(full.join("stats.json")).unwrap()).unwrap();
    let stages: Vec<&str> = stats["stages"].as_array().unwrap().iter().map(|s| s.as_str().unwrap()).collect();
    assert!(stages.contains(&"lra") && stages.contains(&"strain_limit"), "{stages:?}");
    let last = stats["frames"].as_array().unwrap().last().unwrap();
    for key in ["lra_constraints", "lra_taut", "lra_projected", "lra_max_stretch", "strain_limit_faces"] {
        assert!(last.get(key).is_some(), "frame stats lack {key}: {last}");
    }
    assert!(last["stage_s"].get("lra").is_some());
    assert!(last["lra_max_stretch"].as_f64().unwrap() <= 0.01 + 0.01);
    std::fs::remove_dir_all(&dir).ok();
}
