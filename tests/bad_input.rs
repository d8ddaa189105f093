//! Bad input through the CLI (issue 2, "Tests"; DESIGN.md "How the code should read" 7): each
//! case exits with code 2 and prints exactly one line, `error: <file>: <field or line N>: …`,
//! without a panic and without creating the output directory.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::{temp_dir, viewcloth};

/// A valid scene around a cloth block (`mesh` or `rectangle` plus anything else).
fn scene_with_cloth(cloth: &str) -> String {
    format!(
        r#"{{
  "version": 1,
  "frame_time": 0.04,
  "steps_per_frame": 2,
  "frames": 2,
  "cloths": [
    {{
      {cloth},
      "material": {{ "preset": "cotton" }}
    }}
  ]
}}
"#
    )
}

fn rect_scene() -> String {
    scene_with_cloth(r#""rectangle": { "width": 1, "height": 1, "resolution": [2, 2] }"#)
}

/// A flat 2 × 2-quad OBJ (9 vertices on lines 2–10, 8 faces on lines 11–18), with `extra`
/// lines appended (line 19 onwards).
fn grid_obj(extra: &str) -> String {
    let mut s = String::from("# 2x2 grid\n");
    for j in 0..3 {
        for i in 0..3 {
            s += &format!("v {} {} 0\n", i as f64 * 0.5, j as f64 * 0.5);
        }
    }
    for j in 0..2 {
        for i in 0..2 {
            let id = |i: usize, j: usize| j * 3 + i + 1;
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            s += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
        }
    }
    s + extra
}

/// A valid remesh block (for the out-of-range cases that edit it).
const REMESH: &str = r#""remesh": { "mode": "adaptive", "refine_angle": 0.3, "size": [0.01, 0.2], "aspect_min": 0.2 }"#;

/// Where the message must point: a JSON path, `line N`, or nowhere more precise than the file.
enum Loc {
    Field(&'static str),
    Line(usize),
    FileOnly,
}

struct Case {
    name: &'static str,
    /// Files written into the case directory: (name, contents).
    files: Vec<(&'static str, String)>,
    /// The scene file passed to the CLI (in the case directory; it may not exist).
    scene: &'static str,
    /// Extra CLI arguments after the scene.
    args: &'static [&'static str],
    /// The file the message must name (in the case directory).
    file: &'static str,
    loc: Loc,
    /// A word the message must contain (what was wrong).
    mentions: &'static str,
}

fn cases() -> Vec<Case> {
    let obj_scene = scene_with_cloth(r#""mesh": "sheet.obj""#);
    let with = |name: &'static str, obj: String, loc: Loc, mentions: &'static str| Case {
        name,
        files: vec![("scene.json", obj_scene.clone()), ("sheet.obj", obj)],
        scene: "scene.json",
        args: &[],
        file: "sheet.obj",
        loc,
        mentions,
    };
    let json = |name: &'static str, scene: String, loc: Loc, mentions: &'static str| Case {
        name,
        files: vec![("scene.json", scene)],
        scene: "scene.json",
        args: &[],
        file: "scene.json",
        loc,
        mentions,
    };
    let rect = rect_scene();
    vec![
        json(
            "instance_scene_missing",
            rect.replace("\"frames\": 2,", "\"frames\": 2, \"instances\": [{ \"scene\": \"nope.json\" }],"),
            Loc::Field("instances[0].scene"),
            "nope.json",
        ),
        json(
            "instance_name_not_a_file_name",
            rect.replace("\"frames\": 2,", "\"frames\": 2, \"instances\": [{ \"name\": \"a b\", \"scene\": \"scene.json\" }],"),
            Loc::Field("instances[0].name"),
            "letters, digits",
        ),
        json(
            "instance_scale_negative",
            rect.replace(
                "\"frames\": 2,",
                "\"frames\": 2, \"instances\": [{ \"scene\": \"scene.json\", \"transform\": { \"scale\": -1 } }],",
            ),
            Loc::Field("instances[0].transform.scale"),
            "positive",
        ),
        json(
            "instances_nest",
            rect.replace("\"frames\": 2,", "\"frames\": 2, \"instances\": [{ \"scene\": \"scene.json\" }],"),
            Loc::Field("instances[0].scene"),
            "do not nest",
        ),
        Case {
            name: "instances_named_alike",
            files: vec![
                (
                    "scene.json",
                    rect.replace(
                        "\"frames\": 2,",
                        "\"frames\": 2, \"instances\": [{ \"name\": \"a\", \"scene\": \"inner.json\" }, { \"name\": \"a\", \"scene\": \"inner.json\", \"time_offset\": -0.5 }],",
                    ),
                ),
                ("inner.json", rect.clone()),
            ],
            scene: "scene.json",
            args: &[],
            file: "scene.json",
            loc: Loc::Field("instances[1].name"),
            mentions: "apart",
        },
        Case {
            name: "instanced_scene_bad_field",
            files: vec![
                (
                    "scene.json",
                    rect.replace("\"frames\": 2,", "\"frames\": 2, \"instances\": [{ \"scene\": \"inner.json\" }],"),
                ),
                ("inner.json", rect.replace("[2, 2]", "[0, 2]")),
            ],
            scene: "scene.json",
            args: &[],
            file: "inner.json",
            loc: Loc::Field("cloths[0].rectangle.resolution"),
            mentions: "1..=4096",
        },
        Case {
            name: "missing_scene_file",
            files: vec![],
            scene: "nope.json",
            args: &[],
            file: "nope.json",
            loc: Loc::FileOnly,
            mentions: "cannot read",
        },
        Case {
            name: "missing_mesh_file",
            files: vec![("scene.json", obj_scene.clone())],
            scene: "scene.json",
            args: &[],
            file: "scene.json",
            loc: Loc::Field("cloths[0].mesh"),
            mentions: "sheet.obj",
        },
        json(
            "malformed_json",
            rect.replace("\"frames\": 2,", "\"frames\": 2,,"),
            Loc::Line(5),
            "must be",
        ),
        json(
            "initial_intersections_unknown",
            rect.replace("\"frames\": 2,", "\"frames\": 2, \"collision\": { \"initial_intersections\": \"ignore\" },"),
            Loc::Field("collision.initial_intersections"),
            "\"refuse\"",
        ),
        json(
            "truncated_json",
            rect[..rect.len() / 2].to_string(),
            Loc::Line(rect[..rect.len() / 2].lines().count()),
            "EOF",
        ),
        json(
            "unknown_field",
            rect.replace("\"preset\": \"cotton\"", "\"preset\": \"cotton\", \"colour\": \"red\""),
            Loc::Field("cloths[0].material.colour"),
            "colour",
        ),
        json(
            "unknown_top_level_field",
            rect.replace("\"frames\": 2,", "\"frames\": 2, \"frame\": 3,"),
            Loc::Field("frame"),
            "unknown field",
        ),
        json(
            "wrong_type",
            rect.replace("\"preset\": \"cotton\"", "\"density\": \"heavy\""),
            Loc::Field("cloths[0].material.density"),
            "invalid type",
        ),
        json(
            "wrong_type_resolution",
            rect.replace("[2, 2]", "[2.5, 2]"),
            Loc::Field("cloths[0].rectangle.resolution[0]"),
            "invalid type",
        ),
        json(
            "bending_curvature_without_a_measured_fabric",
            rect.replace("\"preset\": \"cotton\"", "\"preset\": \"cotton\", \"bending_curvature\": \"signed\""),
            Loc::Field("cloths[0].material.bending_curvature"),
            "arcsim",
        ),
        json(
            "geometric_stiffness_without_a_measured_fabric",
            rect.replace("\"preset\": \"cotton\"", "\"preset\": \"cotton\", \"geometric_stiffness\": \"arcsim\""),
            Loc::Field("cloths[0].material.geometric_stiffness"),
            "arcsim",
        ),
        json(
            "split_position_unknown",
            rect.replace("\"material\"", &format!("{REMESH},\n      \"material\""))
                .replace("\"aspect_min\": 0.2", "\"aspect_min\": 0.2, \"split_position\": \"centre\""),
            Loc::Field("cloths[0].remesh.split_position"),
            "\"midpoint\" or \"relaxed\"",
        ),
        json(
            "negative_density",
            rect.replace("\"preset\": \"cotton\"", "\"density\": -0.1"),
            Loc::Field("cloths[0].material.density"),
            "positive",
        ),
        json(
            "handle_missing_vertex",
            rect.replace(
                "\"material\"",
                "\"handles\": [{ \"nodes\": [0, 9] }],\n      \"material\"",
            ),
            Loc::Field("cloths[0].handles[0].nodes[1]"),
            "0..9",
        ),
        json(
            "frames_zero",
            rect.replace("\"frames\": 2", "\"frames\": 0"),
            Loc::Field("frames"),
            "≥ 1",
        ),
        json(
            "frames_negative",
            rect.replace("\"frames\": 2", "\"frames\": -4"),
            Loc::Field("frames"),
            "≥ 1",
        ),
        json(
            "keyframes_not_increasing",
            rect.replace(
                "\"material\"",
                "\"handles\": [{ \"nodes\": [6], \"motion\": [{ \"time\": 0 }, { \"time\": 0.5 }, { \"time\": 0.5, \"translate\": [0, 0, 1] }] }],\n      \"material\"",
            ),
            Loc::Field("cloths[0].handles[0].motion[2].time"),
            "increase",
        ),
        with(
            "zero_area_triangle",
            grid_obj("v 2 0 0\nv 3 0 0\nf 3 10 11\n"),
            Loc::Line(21),
            "zero",
        ),
        with(
            "repeated_vertex_triangle",
            grid_obj("f 3 3 6\n"),
            Loc::Line(19),
            "face",
        ),
        with(
            // Edge 5–6 already has faces on lines 14 and 17; line 20 adds a third.
            "non_manifold",
            grid_obj("v 1.2 0.7 0\nf 5 6 10\n"),
            Loc::Line(20),
            "non-manifold",
        ),
        with(
            // A copy of an interior face (line 12), not only of a boundary one.
            "duplicate_face",
            grid_obj("f 1 5 4\n"),
            Loc::Line(19),
            "duplicate",
        ),
        with(
            "nan_coordinate",
            grid_obj("").replace("v 0.5 0.5 0\n", "v 0.5 nan 0\n"),
            Loc::Line(6),
            "finite",
        ),
        with(
            "face_index_out_of_range",
            grid_obj("f 1 2 42\n"),
            Loc::Line(19),
            "out of range",
        ),
        with(
            // ARCSim's edge labels (creases): nodes 1 and 9 are opposite corners of the grid.
            "labelled_edge_not_an_edge",
            grid_obj("e 1 9\nel 1\n"),
            Loc::Line(19),
            "labelled edge",
        ),
        with("edge_label_without_edge", grid_obj("el 1\n"), Loc::Line(19), "'el'"),
        with(
            "no_faces",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\n".to_string(),
            Loc::FileOnly,
            "no faces",
        ),
        // Issue 5: out-of-range values.
        json(
            "aspect_min_zero",
            rect.replace("\"material\"", &format!("{REMESH},\n      \"material\"")).replace("\"aspect_min\": 0.2", "\"aspect_min\": 0"),
            Loc::Field("cloths[0].remesh.aspect_min"),
            "(0, 1]",
        ),
        json(
            "aspect_min_above_one",
            rect.replace("\"material\"", &format!("{REMESH},\n      \"material\"")).replace("\"aspect_min\": 0.2", "\"aspect_min\": 1.5"),
            Loc::Field("cloths[0].remesh.aspect_min"),
            "(0, 1]",
        ),
        json(
            "image_height_zero",
            rect.replace("\"material\"", &format!("{REMESH},\n      \"material\""))
                .replace("\"aspect_min\": 0.2", "\"aspect_min\": 0.2, \"view\": { \"min_edge_pixels\": 2, \"image_height\": 0 }"),
            Loc::Field("cloths[0].remesh.view.image_height"),
            "1..=100000",
        ),
        json(
            "occlusion_pixels_too_large",
            rect.replace("\"material\"", &format!("{REMESH},\n      \"material\""))
                .replace("\"aspect_min\": 0.2", "\"aspect_min\": 0.2, \"view\": { \"occlusion_pixels\": 100000 }"),
            Loc::Field("cloths[0].remesh.view.occlusion_pixels"),
            "0..=4096",
        ),
        json(
            "min_edge_pixels_negative",
            rect.replace("\"material\"", &format!("{REMESH},\n      \"material\""))
                .replace("\"aspect_min\": 0.2", "\"aspect_min\": 0.2, \"view\": { \"min_edge_pixels\": -1 }"),
            Loc::Field("cloths[0].remesh.view.min_edge_pixels"),
            "(0, 10000]",
        ),
        json(
            "max_jump_pixels_negative",
            rect.replace("\"material\"", &format!("{REMESH},\n      \"material\""))
                .replace("\"aspect_min\": 0.2", "\"aspect_min\": 0.2, \"view\": { \"max_jump_pixels\": -0.5 }"),
            Loc::Field("cloths[0].remesh.view.max_jump_pixels"),
            "[0, 10000]",
        ),
        json(
            "size_min_above_max",
            rect.replace("\"material\"", &format!("{REMESH},\n      \"material\"")).replace("[0.01, 0.2]", "[0.2, 0.01]"),
            Loc::Field("cloths[0].remesh.size"),
            "min ≤ max",
        ),
        json("time_step_zero", rect.replace("\"steps_per_frame\": 2", "\"time_step\": 0"), Loc::Field("time_step"), "positive"),
        json(
            "time_step_negative",
            rect.replace("\"steps_per_frame\": 2", "\"time_step\": -0.01"),
            Loc::Field("time_step"),
            "positive",
        ),
        json(
            "steps_per_frame_zero",
            rect.replace("\"steps_per_frame\": 2", "\"steps_per_frame\": 0"),
            Loc::Field("steps_per_frame"),
            "1..=100000",
        ),
        json("frame_time_zero", rect.replace("\"frame_time\": 0.04", "\"frame_time\": 0"), Loc::Field("frame_time"), "positive"),
        json(
            "zero_density",
            rect.replace("\"preset\": \"cotton\"", "\"density\": 0"),
            Loc::Field("cloths[0].material.density"),
            "positive",
        ),
        json(
            "zero_stiffness",
            rect.replace("\"preset\": \"cotton\"", "\"warp\": 0"),
            Loc::Field("cloths[0].material.warp"),
            "positive",
        ),
        json(
            "negative_yield_curvature",
            rect.replace("\"preset\": \"cotton\"", "\"yield_curv\": -200"),
            Loc::Field("cloths[0].material.yield_curv"),
            "positive curvature",
        ),
        json(
            "weakening_without_yield",
            rect.replace("\"preset\": \"cotton\"", "\"weakening\": 1"),
            Loc::Field("cloths[0].material.weakening"),
            "yield_curv",
        ),
        json(
            "negative_weakening",
            rect.replace("\"preset\": \"cotton\"", "\"yield_curv\": 200, \"weakening\": -1"),
            Loc::Field("cloths[0].material.weakening"),
            "≥ 0",
        ),
        json(
            "negative_stiffness",
            rect.replace("\"preset\": \"cotton\"", "\"youngs_modulus\": -1e6, \"thickness\": 0.001"),
            Loc::Field("cloths[0].material.youngs_modulus"),
            "positive",
        ),
        Case {
            name: "cli_checkpoint_every_zero",
            files: vec![("scene.json", rect.clone())],
            scene: "scene.json",
            args: &["--checkpoint-every", "0"],
            file: "",
            loc: Loc::FileOnly,
            mentions: "--checkpoint-every",
        },
        Case {
            name: "cli_frames_zero",
            files: vec![("scene.json", rect.clone())],
            scene: "scene.json",
            args: &["--frames", "0"],
            file: "",
            loc: Loc::FileOnly,
            mentions: "--frames",
        },
        Case {
            name: "cli_frames_negative",
            files: vec![("scene.json", rect.clone())],
            scene: "scene.json",
            args: &["--frames=-3"],
            file: "",
            loc: Loc::FileOnly,
            mentions: "--frames",
        },
    ]
}

/// Checks one failed run: exit code 2, one line of stderr in the documented form, no panic.
fn check_failure(what: &str, out: &Output, file: &Path, case: &Case) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{what}: exit status {}; stderr: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{what}: panicked: {stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{what}: expected one line on stderr, got {stderr:?}");
    let line = lines[0];
    let prefix = if case.file.is_empty() { "error: ".to_string() } else { format!("error: {}: ", file.display()) };
    assert!(line.starts_with(&prefix), "{what}: {line:?} does not start with {prefix:?}");
    let rest = &line[prefix.len()..];
    match case.loc {
        Loc::Field(path) => {
            assert!(rest.starts_with(&format!("{path}: ")), "{what}: {line:?} does not name the field {path}")
        }
        Loc::Line(n) => assert!(rest.starts_with(&format!("line {n}: ")), "{what}: {line:?} does not name line {n}"),
        Loc::FileOnly => {}
    }
    assert!(rest.contains(case.mentions), "{what}: {line:?} does not say {:?}", case.mentions);
    // The file appears once: no "<file>: <file>: …" stutter.
    if !case.file.is_empty() {
        assert_eq!(line.matches(&file.display().to_string()).count(), 1, "{what}: {line:?} repeats the file name");
    }
    line.to_string()
}

#[test]
fn bad_input_exits_2_with_one_line_naming_file_and_field() {
    let mut failures = Vec::new();
    for case in cases() {
        let dir = temp_dir(case.name);
        for (name, text) in &case.files {
            std::fs::write(dir.join(name), text).unwrap();
        }
        let scene = dir.join(case.scene);
        let out_dir = dir.join("out");
        let mut args = vec!["simulate", scene.to_str().unwrap()];
        args.extend_from_slice(case.args);
        args.extend_from_slice(&["--out", out_dir.to_str().unwrap(), "--quiet"]);
        let file = dir.join(case.file);
        let result = std::panic::catch_unwind(|| {
            let out = viewcloth(&args);
            let what = format!("{}: simulate", case.name);
            let line = check_failure(&what, &out, &file, &case);
            assert!(!out_dir.exists(), "{what}: created {out_dir:?}");
            assert!(out.stdout.is_empty(), "{what}: wrote to stdout");
            // `check` reports the same error (command-line errors are simulate's own).
            if case.args.is_empty() {
                let out = viewcloth(&["check", scene.to_str().unwrap()]);
                let checked = check_failure(&format!("{}: check", case.name), &out, &file, &case);
                assert_eq!(checked, line, "{}: check and simulate disagree", case.name);
            }
            eprintln!("{}: {line}", case.name);
        });
        if let Err(e) = result {
            let msg = e
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            failures.push(msg);
        }
        std::fs::remove_dir_all(&dir).ok();
    }
    assert!(failures.is_empty(), "{} case(s) failed:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn check_accepts_every_shipped_scene() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 3, "expected the shipped scenes in {dir:?}");
    // The film shots built on ARCSim's data (dress_dance, crowd_5) read it from ../shared/arcsim
    // beside the repository; without it they are left out, saying so.
    let arcsim = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/arcsim");
    if !arcsim.join("meshes").is_dir() {
        let needs = |p: &PathBuf| {
            let text = std::fs::read_to_string(p).unwrap();
            text.contains("shared/arcsim/") || text.contains("\"dress_dance.json\"")
        };
        let (skipped, kept): (Vec<PathBuf>, Vec<PathBuf>) = scenes.into_iter().partition(needs);
        eprintln!("SKIP checking {skipped:?}: ARCSim data not found at {}", arcsim.display());
        scenes = kept;
    }
    let mut args = vec!["check"];
    args.extend(scenes.iter().map(|p| p.to_str().unwrap()));
    let out = viewcloth(&args);
    assert_eq!(out.status.code(), Some(0), "check failed: {}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stderr.is_empty());
    for scene in &scenes {
        let out = viewcloth(&["check", scene.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{scene:?}: {}", String::from_utf8_lossy(&out.stderr));
    }
}

#[test]
fn check_rejects_a_bad_scene_among_good_ones() {
    let dir = temp_dir("check-mixed");
    let bad = dir.join("bad.json");
    std::fs::write(&bad, rect_scene().replace("\"frames\": 2", "\"frames\": 0")).unwrap();
    let good = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hanging_sheet.json");
    let out = viewcloth(&["check", good.to_str().unwrap(), bad.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "stderr: {stderr}");
    assert!(stderr.starts_with(&format!("error: {}: frames: ", bad.display())), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}
