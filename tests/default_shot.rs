//! Issue 19, "The first run shows it": `viewcloth simulate` with no scene runs the built-in
//! `sheet_drape` shot (a sheet dropped on a sphere and a floor, remeshed in view mode under its
//! orbiting camera) without any file beside the binary — run here from an empty directory —,
//! exports its obstacles and ends with a preview of four frames from the shot camera, saying
//! where the frames and the images are.

use std::path::Path;

mod common;
use common::temp_dir;

#[test]
fn the_default_shot_runs_from_anywhere_and_writes_a_preview() {
    let cwd = temp_dir("cwd");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_viewcloth"))
        .args(["simulate", "--frames", "3", "--threads", "1", "--progress", "none"])
        .current_dir(&cwd)
        .output()
        .expect("run viewcloth");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let dir = cwd.join("out/sheet_drape");
    assert!(stdout.contains("sheet_drape: 3 frames in"), "{stdout}");
    assert!(stdout.contains("→ out/sheet_drape"), "does not say where the frames are: {stdout}");
    let preview = "preview (4 frames from the shot camera): view_0000.png, view_0001.png, view_0002.png, view_0003.png in out/sheet_drape";
    assert!(stdout.contains(preview), "{stdout}");
    for f in 0..=3 {
        let png = dir.join(format!("view_{f:04}.png"));
        let bytes = std::fs::read(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{} is not a PNG", png.display());
        for obstacle in ["sphere", "floor"] {
            assert!(dir.join(format!("obstacle_{obstacle}_{f:04}.obj")).exists(), "{obstacle} not exported");
        }
    }
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("stats.json")).unwrap()).unwrap();
    assert_eq!(stats["scene"], "sheet_drape");
    assert_eq!(stats["mode"], "view", "the default shot is remeshed by its camera");
    std::fs::remove_dir_all(&cwd).ok();
}

/// The shipped scene is the built-in one, so `viewcloth simulate scenes/sheet_drape.json` runs
/// the same shot (the camera is the scene's `camera` file).
#[test]
fn the_shipped_scene_is_the_built_in_shot() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let shipped = std::fs::read_to_string(root.join("scenes/sheet_drape.json")).unwrap();
    assert_eq!(shipped, viewcloth::scene::DEFAULT_SCENE);
    let camera = std::fs::read_to_string(root.join("cameras/sheet_drape.json")).unwrap();
    assert_eq!(camera, viewcloth::scene::DEFAULT_CAMERA);
    let scene = viewcloth::scene::load_file(&root.join("scenes/sheet_drape.json")).unwrap();
    assert!(scene.camera.is_some());
    assert_eq!(scene.obstacles.len(), 2);
}
