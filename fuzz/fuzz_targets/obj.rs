//! The OBJ loader: the parser, then the cloth mesh checks (degenerate, duplicate and non-manifold
//! faces, flattening, orientation) through a scene that references the file. Any bytes give a
//! mesh or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

const SCENE: &str = r#"{ "version": 1, "frame_time": 0.04, "frames": 1,
  "cloths": [{ "mesh": "m.obj", "material": { "preset": "cotton" } }] }"#;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = viewcloth::io::obj::parse_obj(text);
    let dir = std::env::temp_dir().join(format!("viewcloth-fuzz-obj-{}", std::process::id()));
    if std::fs::create_dir_all(&dir).is_ok() && std::fs::write(dir.join("m.obj"), text).is_ok() {
        let _ = viewcloth::scene::load_str(SCENE, &dir.join("s.json"), &dir, "fuzz");
    }
});
