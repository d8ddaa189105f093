//! `viewcloth render` on 30 frames of `sheet_on_sphere` (obstacles exported), simulated once:
//! every tenth frame gives a valid 320×180 PNG (read back by the `png` crate's decoder), the same bytes
//! when rendered again, with cloth in frame 30; `--color view` colours the cloth by its view
//! factor; the sphere is drawn from a camera that sees it; the run's USD samples alone (a
//! `--format usd` run) render as its OBJ frames do; bad input is refused in one line with
//! exit code 2 and writes nothing.

use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::OnceLock;

mod common;
use common::{temp_dir, viewcloth};

const CAMERA: &str = "cameras/sheet_on_sphere_pan.json";

/// The simulated run, shared by the tests (each renders into its own copy).
fn simulated() -> &'static Path {
    static RUN: OnceLock<PathBuf> = OnceLock::new();
    RUN.get_or_init(|| {
        let dir = temp_dir("run");
        let out = viewcloth(&[
            "simulate",
            "scenes/sheet_on_sphere.json",
            "--frames",
            "30",
            "--export-obstacles",
            "--format",
            "both",
            "--quiet",
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "simulate: {}", String::from_utf8_lossy(&out.stderr));
        dir
    })
}

/// A copy of the simulated run's files in a directory of its own.
fn run_copy(name: &str) -> PathBuf {
    let from = simulated();
    let dir = temp_dir(name);
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), dir.join(e.file_name())).unwrap();
        }
    }
    dir
}

/// The simulated run as a `--format usd` run holds it: stats.json, the layer and the samples.
fn usd_copy(name: &str) -> PathBuf {
    let from = simulated();
    let dir = temp_dir(name);
    std::fs::create_dir_all(dir.join("usd_samples")).unwrap();
    for f in ["stats.json", "cloth.usda"] {
        std::fs::copy(from.join(f), dir.join(f)).unwrap();
    }
    for e in std::fs::read_dir(from.join("usd_samples")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), dir.join("usd_samples").join(e.file_name())).unwrap();
    }
    dir
}

fn render(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["render", dir.to_str().unwrap(), "--camera", CAMERA, "--size", "320x180"];
    args.extend_from_slice(extra);
    viewcloth(&args)
}

fn previews(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("view_"))
        .collect();
    names.sort();
    names
}

/// The RGB pixels of a 320×180 preview (as i32, to compare channels without overflow), read by
/// the `png` crate's decoder (which checks every chunk's CRC and the zlib stream's Adler-32).
fn pixels(path: &Path) -> Vec<[i32; 3]> {
    let file = std::fs::File::open(path).unwrap();
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut rgb).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!((info.width, info.height), (320, 180), "{}", path.display());
    assert_eq!((info.color_type, info.bit_depth), (png::ColorType::Rgb, png::BitDepth::Eight));
    rgb[..info.buffer_size()].chunks(3).map(|p| [p[0], p[1], p[2]].map(i32::from)).collect()
}

fn count(pixels: &[[i32; 3]], f: impl Fn(&[i32; 3]) -> bool) -> usize {
    pixels.iter().filter(|p| f(p)).count()
}

fn assert_refused(out: &Output, mentions: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(stderr.starts_with("error: ") && stderr.contains(mentions), "expected '{mentions}' in: {stderr}");
}

#[test]
fn every_tenth_frame_gives_a_valid_deterministic_preview() {
    let dir = run_copy("shade");
    let out = render(&dir, &["--every", "10"]);
    assert!(out.status.success(), "render: {}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("4 images"));
    let names = ["view_0000.png", "view_0010.png", "view_0020.png", "view_0030.png"];
    assert_eq!(previews(&dir), names);
    let first: Vec<Vec<u8>> = names.iter().map(|n| std::fs::read(dir.join(n)).unwrap()).collect();
    for n in names {
        pixels(&dir.join(n));
    }
    // The sheet has fallen into the camera's view by frame 30: a good share of the image is
    // cloth, light blue shaded (blue above red), and the rest white.
    let last = pixels(&dir.join("view_0030.png"));
    let cloth = count(&last, |p| p[2] > p[0] + 20);
    assert!(cloth > last.len() / 20, "{cloth} cloth pixels of {}", last.len());
    assert!(count(&last, |p| *p == [255; 3]) > last.len() / 4);
    // Rendering again gives the same bytes.
    let out = render(&dir, &["--every", "10"]);
    assert!(out.status.success());
    for (n, bytes) in names.iter().zip(&first) {
        assert!(std::fs::read(dir.join(n)).unwrap() == *bytes, "{n} changed on a second render");
    }
}

#[test]
fn view_colouring_shows_where_the_mesh_will_be_fine() {
    let dir = run_copy("view");
    let out = render(&dir, &["--frames", "20..30", "--every", "10", "--color", "view"]);
    assert!(out.status.success(), "render: {}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(previews(&dir), ["view_0020.png", "view_0030.png"]);
    let view = pixels(&dir.join("view_0030.png"));
    // Cloth facing the camera in frame has μ near 1: red dominates.
    let red = count(&view, |p| p[0] > p[2] + 60);
    assert!(red > view.len() / 50, "{red} red pixels");
    // The same frame shaded covers the same pixels with other colours.
    let out = render(&dir, &["--frames", "30..30"]);
    assert!(out.status.success(), "render: {}", String::from_utf8_lossy(&out.stderr));
    let shade = pixels(&dir.join("view_0030.png"));
    let covered = |img: &[[i32; 3]]| count(img, |p| *p != [255; 3]);
    assert_eq!(covered(&view), covered(&shade));
    assert_eq!(count(&shade, |p| p[0] > p[2] + 60), 0);
}

#[test]
fn exported_obstacles_are_drawn_and_hide_what_is_behind_them() {
    let dir = run_copy("obstacle");
    // From behind the sheet, looking at the sphere that pushes into it.
    let camera = dir.join("behind.json");
    std::fs::write(
        &camera,
        r#"{ "version": 1, "keys": [{ "time": 0, "position": [0.9, 1.2, 0.6], "target": [0, 0, 0], "fov": 50 }] }"#,
    )
    .unwrap();
    let args = ["render", dir.to_str().unwrap(), "--camera", camera.to_str().unwrap(), "--size", "320x180"];
    let out = viewcloth(&[&args[..], &["--frames", "30..30"]].concat());
    assert!(out.status.success(), "render: {}", String::from_utf8_lossy(&out.stderr));
    let img = pixels(&dir.join("view_0030.png"));
    // Light salmon, shaded: red well above blue, green between.
    let salmon = |p: &[i32; 3]| p[0] > p[2] + 60 && p[1] > p[2];
    let sphere = count(&img, salmon);
    assert!(sphere > 200, "{sphere} sphere pixels");
    // Without the obstacle files the same pixels show cloth.
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        if path.file_name().unwrap().to_string_lossy().starts_with("obstacle_") {
            std::fs::remove_file(path).unwrap();
        }
    }
    let out = viewcloth(&[&args[..], &["--frames", "30..30"]].concat());
    assert!(out.status.success());
    let bare = pixels(&dir.join("view_0030.png"));
    assert_eq!(count(&bare, salmon), 0);
    assert!(img.iter().zip(&bare).filter(|(a, _)| salmon(a)).all(|(_, b)| b[2] > b[0]), "cloth behind the sphere");
}

#[test]
fn bad_input_is_refused_in_one_line_and_writes_nothing() {
    let missing = temp_dir("missing").join("no_such_run");
    assert_refused(&render(&missing, &[]), "stats.json");
    let dir = run_copy("bad");
    assert_refused(&render(&dir, &["--size", "320by180"]), "--size");
    assert_refused(&render(&dir, &["--size", "8x8"]), "--size");
    assert_refused(&render(&dir, &["--frames", "20..10"]), "--frames");
    assert_refused(&render(&dir, &["--frames", "ten..20"]), "--frames");
    assert_refused(&render(&dir, &["--frames", "25..31"]), "frames 0..30");
    let no_camera = viewcloth(&["render", dir.to_str().unwrap(), "--camera", "cameras/none.json"]);
    assert_refused(&no_camera, "none.json");
    // A frame missing or malformed halfway through the selection: nothing is written.
    std::fs::remove_file(dir.join("frame_0020.obj")).unwrap();
    assert_refused(&render(&dir, &["--every", "10"]), "frame_0020.obj");
    std::fs::write(dir.join("frame_0020.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    assert_refused(&render(&dir, &["--every", "10"]), "frame_0020.obj: line 3");
    std::fs::write(dir.join("obstacle_sphere_0010.obj"), "v 0 0 0\n").unwrap();
    assert_refused(&render(&dir, &["--frames", "0..10"]), "obstacle_sphere_0010.obj");
    assert_eq!(previews(&dir), Vec::<String>::new());
}

/// A run written with `--format usd` (no OBJ) renders from its USD samples: the same pictures as
/// from its OBJ frames but for the rounding of positions to 32-bit floats (a few edge pixels);
/// a missing samples file is named, and a run with neither OBJ frames nor samples is refused.
#[test]
fn a_usd_run_renders_from_its_samples() {
    let (obj, usd) = (run_copy("from_obj"), usd_copy("from_usd"));
    for dir in [&obj, &usd] {
        let out = render(dir, &["--every", "10"]);
        assert!(out.status.success(), "render {}: {}", dir.display(), String::from_utf8_lossy(&out.stderr));
    }
    assert_eq!(previews(&usd), previews(&obj));
    for n in previews(&obj) {
        let (a, b) = (pixels(&obj.join(&n)), pixels(&usd.join(&n)));
        let differ = a.iter().zip(&b).filter(|(p, q)| p != q).count();
        assert!(differ * 1000 <= a.len(), "{n}: {differ} of {} pixels differ", a.len());
        // The sphere (salmon) is there too: the obstacles come from the samples.
        let salmon = |p: &[i32; 3]| p[0] > p[2] + 40;
        assert_eq!(count(&a, salmon) > 0, count(&b, salmon) > 0, "{n}: obstacle");
    }
    std::fs::remove_file(usd.join("usd_samples/frame_0020.txt")).unwrap();
    assert_refused(&render(&usd, &["--every", "10"]), "usd_samples/frame_0020.txt");
    std::fs::remove_dir_all(usd.join("usd_samples")).unwrap();
    assert_refused(&render(&usd, &["--every", "10"]), "frame_0000.obj: missing (no OBJ frame, nor usd_samples/");
}
