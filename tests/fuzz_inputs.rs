//! Fuzz-style tests that run with `cargo test` (issue 5, "Bad input"): the scene parser and the
//! OBJ loader are fed deterministic random mutations of the shipped scenes and of valid OBJs and
//! must return an error or a scene, never panic. The libFuzzer targets in `fuzz/` do the same
//! open-endedly (`cargo +nightly fuzz run scene`). A few random valid scenes are also loaded
//! and stepped, and must stay finite.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

mod common;

use common::{temp_dir, Rng};
use serde_json::{json, Value};
use viewcloth::io::obj::parse_obj;
use viewcloth::scene;
use viewcloth::sim::Simulation;

const TOKENS: &[&str] = &[
    "{",
    "}",
    "[",
    "]",
    "\"",
    ",",
    ":",
    "-",
    "0",
    "-1",
    "1e309",
    "-1e-320",
    "NaN",
    "null",
    "true",
    "\"\"",
    "0.5",
    "4096",
    "[0, 0]",
    "{}",
    "[]",
    "\"mesh\"",
    "\"rectangle\"",
    "\"material\"",
    "\"handles\"",
    "\"nodes\"",
    "\"motion\"",
    "\"time\"",
    "\"remesh\"",
    "\"size\"",
    "\"aspect_min\"",
    "\"obstacles\"",
    "\"sphere\"",
    "\"sequence\"",
    "\"region\"",
    "\"collision\"",
    "\"wind\"",
    "\"preset\"",
    "\"steps_per_frame\"",
    "é",
    "\u{0}",
    "f 1 2 3\n",
    "v 0 0 0\n",
    "vt 0 0\n",
    "f 1/1 2/2 3/3\n",
    "f -1 -2 -3\n",
    "f 1 1 1\n",
    "v nan 0 0\n",
    "#",
    "\n",
    "/",
    "//",
    "99999999999999999999",
];

fn mutate(rng: &mut Rng, seed: &str) -> String {
    let mut b: Vec<u8> = seed.as_bytes().to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(b.len() + 1);
        match rng.below(6) {
            0 if !b.is_empty() => {
                let k = rng.below(b.len());
                b[k] = rng.next_u64() as u8;
            }
            1 => {
                let t = TOKENS[rng.below(TOKENS.len())].as_bytes();
                b.splice(at..at, t.iter().copied());
            }
            2 if at < b.len() => {
                let end = (at + 1 + rng.below(40)).min(b.len());
                b.drain(at..end);
            }
            3 if at < b.len() => {
                let end = (at + 1 + rng.below(60)).min(b.len());
                let chunk = b[at..end].to_vec();
                let to = rng.below(b.len() + 1);
                b.splice(to..to, chunk);
            }
            4 => {
                // Replace a number with an extreme one.
                let digits: Vec<usize> = (0..b.len()).filter(|&i| b[i].is_ascii_digit()).collect();
                if let Some(&i) = digits.get(rng.below(digits.len())) {
                    let t = ["0", "-0.0", "1e300", "-7", "3.5", "4096", "1e-300"][rng.below(7)];
                    b.splice(i..i + 1, t.bytes());
                }
            }
            _ => b.truncate(at),
        }
    }
    String::from_utf8_lossy(&b).into_owned()
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn seeds(dir: &Path, ext: &str) -> Vec<String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    files.sort();
    files.iter().map(|p| std::fs::read_to_string(p).unwrap()).collect()
}

/// A mutated input too large to be worth loading here (valid but huge: e.g. a 4096² rectangle
/// takes gigabytes); the libFuzzer target leaves these to its memory limit.
fn too_big(text: &str) -> bool {
    let Ok(v) = serde_json::from_str::<Value>(text) else { return false };
    let big = |x: &Value| x.as_f64().is_some_and(|n| n.abs() > 400.0);
    v["cloths"]
        .as_array()
        .is_some_and(|cs| cs.iter().any(|c| c["rectangle"]["resolution"].as_array().is_some_and(|r| r.iter().any(big))))
        || v["obstacles"].as_array().is_some_and(|os| os.iter().any(|o| o.get("sequence").is_some()))
}

#[test]
fn mutated_scenes_never_panic() {
    let mut all = seeds(&scenes_dir(), "json");
    all.extend(seeds(&scenes_dir().join("stress"), "json"));
    let mut rng = Rng(0x5EED_0001);
    let mut errors = 0;
    let n = 3000;
    for i in 0..n {
        let seed = &all[rng.below(all.len())];
        let text = mutate(&mut rng, seed);
        if too_big(&text) || text.contains("\"/") {
            continue;
        }
        let file = scenes_dir().join(format!("mutant_{i}.json"));
        let r = catch_unwind(AssertUnwindSafe(|| scene::load_str(&text, &file, &scenes_dir(), "mutant")));
        match r {
            Ok(Ok(_)) => {}
            Ok(Err(e)) => {
                errors += 1;
                let line = e.to_string();
                assert!(!line.contains('\n'), "mutant {i}: multi-line error {line:?}");
            }
            Err(_) => panic!("mutant {i} panicked the scene loader:\n{text}"),
        }
    }
    assert!(errors > n / 3, "mutations were mostly valid ({errors} errors of {n}): not exercising errors");
}

#[test]
fn mutated_objs_never_panic() {
    let grid = {
        let mut s = String::new();
        for j in 0..4 {
            for i in 0..4 {
                s += &format!("v {} {} 0\nvt {} {}\n", i as f64 / 3.0, j as f64 / 3.0, i as f64 / 3.0, j as f64 / 3.0);
            }
        }
        for j in 0..3 {
            for i in 0..3 {
                let a = j * 4 + i + 1;
                s += &format!(
                    "f {a}/{a} {}/{} {}/{}\nf {a}/{a} {}/{} {}/{}\n",
                    a + 1,
                    a + 1,
                    a + 5,
                    a + 5,
                    a + 5,
                    a + 5,
                    a + 4,
                    a + 4
                );
            }
        }
        s
    };
    let mut all = vec![grid];
    all.extend(seeds(&scenes_dir().join("stress/meshes"), "obj"));
    let dir = temp_dir("obj");
    let scene_text = json!({
        "version": 1, "frame_time": 0.04, "frames": 1,
        "cloths": [{ "mesh": "m.obj", "material": { "preset": "cotton" } }]
    })
    .to_string();
    let mut rng = Rng(0x5EED_0002);
    for i in 0..3000 {
        let k = rng.below(all.len());
        let text = mutate(&mut rng, &all[k]);
        let r = catch_unwind(AssertUnwindSafe(|| {
            let _ = parse_obj(&text);
            std::fs::write(dir.join("m.obj"), &text).unwrap();
            let _ = scene::load_str(&scene_text, &dir.join("s.json"), &dir, "mutant");
        }));
        assert!(r.is_ok(), "OBJ mutant {i} panicked the loader:\n{text}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Random valid scenes (sheet size, resolution, fabric, handles, an obstacle, remeshing) load
/// and run two frames without a non-finite value.
#[test]
fn random_valid_scenes_load_and_step() {
    let mut rng = Rng(0x5EED_0003);
    for i in 0..12 {
        let (w, h) = (0.2 + rng.uniform(), 0.2 + rng.uniform());
        let (nx, ny) = (2 + rng.below(10), 2 + rng.below(10));
        let presets = ["cotton", "denim", "silk", "jersey"];
        let mut cloth = json!({
            "rectangle": { "width": w, "height": h, "resolution": [nx, ny] },
            "transform": { "translate": [-0.5 * w, -0.5 * h, 0.3 + rng.uniform()], "rotate": [360.0 * rng.uniform(), rng.uniform(), rng.uniform(), 1.0] },
            "material": { "preset": presets[rng.below(4)], "stretching_mult": 0.1 + 10.0 * rng.uniform(), "density": 0.02 + rng.uniform() },
            "handles": [{ "nodes": [rng.below((nx + 1) * (ny + 1))] }]
        });
        if rng.below(2) == 0 {
            cloth["remesh"] =
                json!({ "refine_angle": 0.3, "size": [0.02 + 0.05 * rng.uniform(), 0.3], "aspect_min": 0.2 });
        }
        let mut v = json!({ "version": 1, "frame_time": 0.04, "steps_per_frame": 1 + rng.below(8), "frames": 2, "cloths": [cloth] });
        if rng.below(2) == 0 {
            v["obstacles"] = json!([{ "sphere": { "radius": 0.05 + 0.1 * rng.uniform() }, "transform": { "translate": [0, 0, -0.3] } }]);
        }
        let file = scenes_dir().join(format!("random_{i}.json"));
        let scene =
            scene::load_str(&v.to_string(), &file, &scenes_dir(), "random").unwrap_or_else(|e| panic!("{e}\n{v}"));
        let mut sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{e}\n{v}"));
        for _ in 0..2 {
            sim.advance_frame().unwrap_or_else(|e| panic!("{e}\n{v}"));
        }
        assert!(sim.state.mesh.nodes.iter().all(|n| n.x.iter().chain(n.v.iter()).all(|c| c.is_finite())), "{v}");
    }
}
