//! Camera files through `Camera::load` (DESIGN.md "Files", STYLE.md 7): every bad file is an
//! error of one line naming the file and the field (or line), never a panic; the example camera
//! loads and frames only part of its scene's sheet.

use std::path::Path;

mod common;

use viewcloth::camera::Camera;
use viewcloth::math::{Real, Vec3};

/// A valid camera file with `key1` as its second key and `extra` top-level fields.
fn camera(extra: &str, key1: &str) -> String {
    format!(
        r#"{{
  "version": 1,{extra}
  "keys": [
    {{ "time": 0, "position": [0, -3, 1], "target": [0, 0, 0.5], "fov": 40 }},
    {key1},
    {{ "time": 2, "position": [2, -3, 1], "target": [0, 0, 0.5], "fov": 40 }}
  ]
}}
"#
    )
}

const KEY1: &str = r#"{ "time": 1, "position": [1, -3, 1], "target": [0, 0, 0.5], "fov": 40 }"#;

#[test]
fn bad_camera_files_name_file_and_field() {
    let key1 = |edit: &str| KEY1.replace("\"fov\": 40", edit);
    // (file name, contents, the location the message must name)
    let cases: Vec<(&str, String, &str)> = vec![
        ("version.json", camera("", KEY1).replace("\"version\": 1", "\"version\": 3"), "version"),
        ("no_keys.json", r#"{ "version": 1, "keys": [] }"#.to_string(), "keys"),
        ("fov_wide.json", camera("", &key1("\"fov\": 180")), "keys[1].fov"),
        ("fov_zero.json", camera("", &key1("\"fov\": 0")), "keys[1].fov"),
        ("time_order.json", camera("", &KEY1.replace("\"time\": 1", "\"time\": 0")), "keys[1].time"),
        ("time_after.json", camera("", &KEY1.replace("\"time\": 1", "\"time\": 2")), "keys[2].time"),
        ("target_at_eye.json", camera("", &KEY1.replace("[0, 0, 0.5]", "[1, -3, 1]")), "keys[1].target"),
        ("up_zero.json", camera("", &key1("\"fov\": 40, \"up\": [0, 0, 0]")), "keys[1].up"),
        ("up_parallel.json", camera("", &KEY1.replace("[0, 0, 0.5]", "[1, -3, -4]")), "keys[1].up"),
        ("aspect.json", camera("\n  \"aspect\": -1.5,", KEY1), "aspect"),
        ("near.json", camera("\n  \"near\": 0,", KEY1), "near"),
        ("far.json", camera("\n  \"near\": 1, \"far\": 0.5,", KEY1), "far"),
        ("huge.json", camera("", &KEY1.replace("[1, -3, 1]", "[1e300, -3, 1]")), "keys[1].position"),
        ("interpolation.json", camera("\n  \"interpolation\": \"bezier\",", KEY1), "interpolation"),
        ("unknown_top.json", camera("\n  \"fps\": 24,", KEY1), "fps"),
        ("unknown_key_field.json", camera("", &key1("\"fov\": 40, \"roll\": 3")), "keys[1].roll"),
        ("missing_fov.json", camera("", &KEY1.replace(", \"fov\": 40", "")), "keys[1]"),
        ("wrong_type.json", camera("", &key1("\"fov\": \"wide\"")), "keys[1].fov"),
        ("short_vector.json", camera("", &KEY1.replace("[1, -3, 1]", "[1, -3]")), "keys[1].position"),
        ("syntax.json", camera("", KEY1).replace("\"keys\": [", "\"keys\": [,"), "line 3"),
        ("trailing.json", camera("", KEY1) + "{}\n", "line 9"),
        ("not_json.json", "camera: dolly\n".to_string(), "line 1"),
        ("empty.json", String::new(), "line 1"),
    ];
    let dir = common::temp_dir("cameras");
    for (name, contents, location) in cases {
        let path = dir.join(name);
        std::fs::write(&path, contents).unwrap();
        let e = Camera::load(&path).expect_err(name);
        let line = e.to_string();
        assert!(!line.contains('\n'), "{name}: more than one line: {line}");
        assert!(line.starts_with(&format!("{}: {location}: ", path.display())), "{name}: {line}");
        assert_eq!(e.location.as_deref(), Some(location), "{name}: {line}");
    }
    // The same text as a valid file loads (the cases differ from it only by their edit).
    let path = dir.join("valid.json");
    std::fs::write(
        &path,
        camera("\n  \"aspect\": 2, \"near\": 0.1, \"far\": 20, \"interpolation\": \"linear\",", KEY1),
    )
    .unwrap();
    let cam = Camera::load(&path).unwrap();
    assert_eq!((cam.aspect, cam.near, cam.far), (2.0, 0.1, 20.0));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_camera_file_names_the_file() {
    let path = Path::new("cameras/does_not_exist.json");
    let e = Camera::load(path).unwrap_err();
    let line = e.to_string();
    assert!(line.starts_with("cameras/does_not_exist.json: cannot read camera file"), "{line}");
    assert!(!line.contains('\n'));
    assert_eq!(e.location, None);
}

/// The example camera for `scenes/sheet_on_sphere.json`: a pan from the sheet's +x side to its
/// −x side that never frames more than two thirds of the hanging sheet (x ∈ [−0.5, 0.5],
/// z ∈ [−0.5, 0.5], y ≈ 0; 121 sample points), so view mode has something to coarsen throughout.
#[test]
fn example_camera_pans_over_part_of_the_sheet() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cameras/sheet_on_sphere_pan.json");
    let cam = Camera::load(&path).unwrap();
    let looks_at = |t: Real, target: [Real; 3]| {
        let v = cam.view_at(t);
        ((Vec3::from(target) - v.eye).normalize() - v.forward).norm() < 1e-12
    };
    assert!(looks_at(0.0, [0.45, -0.3, 0.0]));
    assert!(looks_at(5.0, [0.0, -0.3, 0.0]));
    assert!(looks_at(10.0, [-0.45, -0.3, 0.0]));
    assert!((cam.view_at(3.0).tan_half_fov - 12.5_f64.to_radians().tan()).abs() < 1e-12);
    for k in 0..=20 {
        let v = cam.view_at(0.5 * k as Real);
        let grid = (0..=10)
            .flat_map(|i| (0..=10).map(move |j| Vec3::new(-0.5 + 0.1 * i as Real, 0.0, -0.5 + 0.1 * j as Real)));
        let inside = grid.filter(|p| v.frustum_distance(p) < 0.0).count();
        assert!(inside > 0 && inside <= 80, "t = {}: {inside} of 121 points in frame", 0.5 * k as Real);
    }
}
