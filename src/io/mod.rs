//! Files in and out: OBJ meshes, atomic writes, run statistics.

pub mod json;
pub mod obj;
pub mod stats;

use std::path::{Path, PathBuf};

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
