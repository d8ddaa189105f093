//! Shared by the integration tests (`mod common;`): the binary, fresh temporary directories, the
//! deterministic random generator of the unit tests, scenes given inline, finite-difference
//! checks.
#![allow(dead_code)]

pub mod fd;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

// For the generator's module, which takes them from its parent (as in `src/math`).
use viewcloth::math::{Real, Vec3};
use viewcloth::scene::{self, Scene};

/// One generator for unit and integration tests: the unit tests' file, compiled here too.
#[path = "../../src/math/test_rng.rs"]
mod test_rng;
#[allow(unused_imports)] // for the crates that draw no random numbers
pub use test_rng::Rng;

/// The binary run with `args`.
pub fn viewcloth(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_viewcloth")).args(args).output().expect("run viewcloth")
}

/// A fresh, empty directory `<crate>_<name>` under the test target's temporary directory (the
/// test crate's name keeps crates run in parallel apart).
pub fn temp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{}_{name}", env!("CARGO_CRATE_NAME")));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
    d
}

/// A scene given inline as JSON, named `name`; relative paths resolve in `base`.
pub fn inline_scene(v: &serde_json::Value, base: &Path, name: &str) -> Scene {
    scene::load_str(&v.to_string(), Path::new(name), base, name).unwrap_or_else(|e| panic!("{e}"))
}
