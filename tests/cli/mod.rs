//! Shared by the test crates that drive the `viewcloth` binary.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The binary run with `args`.
pub fn viewcloth(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_viewcloth")).args(args).output().expect("run viewcloth")
}

/// A fresh, empty directory under the test target's temporary directory.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
