//! Issue 19 item 1: which sides of a cloth the camera sees by default. A garment (seams, or a
//! handle riding on a body) is one-sided with its outside found from its own centroid; a flat
//! sheet is two-sided; an explicit `view.two_sided` always wins.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};
use viewcloth::scene::{self, Scene};
use viewcloth::sizing::ViewParams;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn load(v: Value) -> Scene {
    let dir = scenes_dir();
    scene::load_value(v, &dir.join("t.json"), &dir, "t").expect("scene loads")
}

fn view(s: &Scene) -> ViewParams {
    s.cloths[0].remesh.as_ref().expect("remesh block").view
}

/// The skirt of scenes/skirt_mannequin.json with a view remesh block whose `view` is `view`.
fn skirt(view: Value, handle_on_hips: bool) -> Value {
    let mut handles = vec![];
    if handle_on_hips {
        handles.push(json!({ "nodes": [0, 1, 2], "obstacle": "hips" }));
    }
    json!({
        "version": 1, "frame_time": 0.04, "steps_per_frame": 2, "end_time": 0.04,
        "cloths": [{ "mesh": "meshes/skirt.obj", "material": { "preset": "denim" }, "handles": handles,
                     "remesh": { "mode": "view", "size": [0.01, 0.2], "view": view } }],
        "obstacles": [{ "name": "hips", "capsule": { "radius": 0.16, "length": 0.45 },
                        "transform": { "translate": [0, 0, 1.2] } }]
    })
}

fn sheet(view: Value, transform: Value) -> Value {
    json!({
        "version": 1, "frame_time": 0.04, "steps_per_frame": 2, "end_time": 0.04,
        "cloths": [{ "rectangle": { "width": 1.0, "height": 1.0, "resolution": [4, 4] },
                     "material": { "preset": "denim" }, "transform": transform,
                     "remesh": { "mode": "view", "size": [0.01, 0.2], "view": view } }]
    })
}

#[test]
fn a_seamed_skirt_is_one_sided_with_its_outside_away_from_its_centroid() {
    // skirt.obj's UVs are mirrored, so the loader flips its faces (material space must be
    // counter-clockwise), and the winding normals end up pointing away from the hips.
    let p = view(&load(skirt(json!({}), false)));
    assert!(!p.two_sided);
    assert_eq!(p.front, 1.0);
    assert!(!view(&load(skirt(json!({}), true))).two_sided);
    // Mirror its UVs back: the faces keep the file's winding, inward, and the outside is the
    // reversed normal.
    let dir = std::env::temp_dir().join(format!("vc_issue19_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = std::fs::read_to_string(scenes_dir().join("meshes/skirt.obj")).unwrap();
    let mirrored: String = obj
        .lines()
        .map(|l| match l.strip_prefix("vt ") {
            Some(rest) => {
                let uv: Vec<f64> = rest.split_whitespace().map(|x| x.parse().unwrap()).collect();
                format!("vt {} {}\n", -uv[0], uv[1])
            }
            None => format!("{l}\n"),
        })
        .collect();
    let file = dir.join("skirt_mirrored.obj");
    std::fs::write(&file, mirrored).unwrap();
    let mut s = skirt(json!({}), false);
    s["cloths"][0]["mesh"] = json!(file.to_str().unwrap());
    assert_eq!(view(&load(s)).front, -1.0);
}

#[test]
fn a_flat_sheet_stays_two_sided_and_an_explicit_field_wins() {
    assert!(view(&load(sheet(json!({}), json!({})))).two_sided);
    assert!(!view(&load(sheet(json!({ "two_sided": false }), json!({})))).two_sided);
    assert!(view(&load(skirt(json!({ "two_sided": true }), true))).two_sided);
}

#[test]
fn a_sheet_riding_on_an_obstacle_is_one_sided() {
    let mut s = sheet(json!({}), json!({}));
    s["cloths"][0]["handles"] = json!([{ "nodes": [0], "obstacle": "box" }]);
    s["obstacles"] = json!([{ "name": "box", "box": { "size": [0.1, 0.1, 0.1] },
                              "transform": { "translate": [0, 0, -1] } }]);
    assert!(!view(&load(s)).two_sided);
}

#[test]
fn the_outside_of_a_tube_does_not_depend_on_its_transform() {
    // A rotated, scaled copy of the skirt keeps its orientation sign.
    let mut s = skirt(json!({}), false);
    s["cloths"][0]["transform"] = json!({ "scale": 2.0, "rotate": [90, 1, 0, 0], "translate": [3, 0, 0] });
    assert_eq!(view(&load(s)).front, 1.0);
}
