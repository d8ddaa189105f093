//! The user-input error shared by every reader of user files (scenes, cameras, batch files, run
//! directories).

use std::path::PathBuf;

/// A user-input error: the file, where in it (JSON path or line), and what was expected.
/// Displayed as one line.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError {
    pub file: PathBuf,
    pub location: Option<String>,
    pub msg: String,
}

impl std::fmt::Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let msg = self.msg.replace('\n', " ");
        match &self.location {
            Some(loc) => write!(f, "{}: {}: {}", self.file.display(), loc, msg),
            None => write!(f, "{}: {}", self.file.display(), msg),
        }
    }
}

impl std::error::Error for InputError {}
