//! Files in and out: OBJ meshes, USD layers, atomic writes, run statistics.

pub mod json;
pub mod obj;
pub mod stats;
pub mod usd;
pub mod usd_samples;

use std::path::{Path, PathBuf};

/// What a run writes per frame: OBJ files, the USD layer, or both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OutputFormat {
    #[default]
    Obj,
    Usd,
    Both,
}

impl OutputFormat {
    /// The formats' names on the command line and in shots files.
    pub const NAMES: [&'static str; 3] = ["obj", "usd", "both"];

    pub fn parse(name: &str) -> Option<OutputFormat> {
        match name {
            "obj" => Some(OutputFormat::Obj),
            "usd" => Some(OutputFormat::Usd),
            "both" => Some(OutputFormat::Both),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        OutputFormat::NAMES[self as usize]
    }

    pub fn obj(self) -> bool {
        self != OutputFormat::Usd
    }

    pub fn usd(self) -> bool {
        self != OutputFormat::Obj
    }
}

/// Writes `bytes` to `path` atomically: a temporary file in the same directory, flushed, then
/// renamed into place, so a reader (or a run killed midway) never sees a partial file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let tmp = temp_name(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_data()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `write_atomic` for a file written as a stream by `write` (a large one need not be held in
/// memory).
pub fn write_atomic_with<E: From<std::io::Error>>(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> Result<(), E>,
) -> Result<(), E> {
    let tmp = temp_name(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        write(&mut f)?;
        f.sync_data()?;
        drop(f);
        std::fs::rename(&tmp, path).map_err(E::from)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Whether a file name is a temporary of `write_atomic` (`.<name>.tmp<pid>`), left behind
/// only by a process killed mid-write.
pub fn is_temp_name(name: &str) -> bool {
    name.starts_with('.')
        && name.rfind(".tmp").is_some_and(|k| {
            let pid = &name[k + 4..];
            !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())
        })
}

fn temp_name(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp{}", std::process::id()))
}
