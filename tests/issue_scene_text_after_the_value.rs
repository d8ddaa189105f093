//! A scene file with text after its JSON value loaded as if the text were not there, while camera
//! files refused it (fixed in 5ce1102: one strict JSON reader for both).

use std::path::Path;

mod common;

use common::{temp_dir, viewcloth};

#[test]
fn text_after_a_scene_is_refused_naming_its_line() {
    let dir = temp_dir("scene");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hanging_sheet.json");
    let valid = std::fs::read_to_string(scene).unwrap();
    let file = dir.join("trailing.json");
    std::fs::write(&file, valid.clone()).unwrap();
    let o = viewcloth(&["check", file.to_str().unwrap()]);
    assert!(o.status.success(), "the scene alone is valid: {}", String::from_utf8_lossy(&o.stderr));

    std::fs::write(&file, valid.clone() + "{}\n").unwrap();
    let o = viewcloth(&["check", file.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    let line = format!("trailing.json: line {}", valid.lines().count() + 1);
    assert!(err.contains(&line), "expected '{line}' in: {err}");
}
