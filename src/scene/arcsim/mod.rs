//! ARCSim scene files ("confs"), read directly or converted to viewcloth scenes.
//!
//! A conf is recognised by its keys (no `version`; ARCSim keys such as `frame_steps`,
//! `end_frame`, `timestep`, `motions`, `magic`, `disable`, or a cloth with `materials` or
//! `remeshing`). Its `//` and `/* */` comments are accepted. Paths in it are relative to a base
//! directory (ARCSim runs from its root; by default the conf's grand-parent directory, so that
//! `conf/x.json` finds `meshes/` and `materials/`).
//!
//! The conversion builds a viewcloth scene (JSON, `docs/scene-format.md`) that loads through the
//! ordinary scene loader, so a conf and its converted scene simulate identically. What has no
//! viewcloth equivalent is reported, one warning per key; ARCSim's defaults that differ from
//! viewcloth's (gravity 0, air density 1 with no wind, friction 0.6 / 0.3, repulsion thickness
//! 1 mm, rest angles flat) are written out explicitly. ARCSim's relaxation of the initial state
//! before its first frame is the scene option `initial_relax`, not set by the conversion (README).

use std::path::{Path, PathBuf};

use serde_json::Value;

use super::Scene;
use crate::error::InputError;

mod convert;
mod ordered;
pub use convert::{convert, Converted};
pub use ordered::J;

type Res<T> = Result<T, InputError>;

/// A loaded scene and the warnings its conversion produced (empty for viewcloth scenes).
pub struct Loaded {
    pub scene: Scene,
    /// One line each: `<json path>: <what was ignored or approximated>`.
    pub warnings: Vec<String>,
}

/// Loads a viewcloth scene or an ARCSim conf. `base` resolves a conf's paths (default: the
/// conf's grand-parent directory); viewcloth scenes resolve relative to their own directory.
pub fn load_path(path: &Path, base: Option<&Path>) -> Res<Loaded> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError {
        file: path.to_path_buf(),
        location: None,
        msg: format!("cannot read scene file: {e}"),
    })?;
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let value = match serde_json::from_str::<Value>(&strip_comments(&text)) {
        Ok(v) if is_arcsim(&v) => v,
        // Viewcloth scenes (and syntax errors) go through the strict loader, which reports them.
        _ => {
            let dir = path.parent().unwrap_or(Path::new("."));
            return Ok(Loaded { scene: super::load_str(&text, path, dir, &stem)?, warnings: Vec::new() });
        }
    };
    let base = base.map(Path::to_path_buf).unwrap_or_else(|| default_base(path));
    let as_is = |p: &Path| p.to_string_lossy().into_owned();
    let converted = convert(&value, path, &base, &as_is)?;
    let scene = super::load_value(
        serde_json::to_value(&converted.scene).map_err(|e| InputError {
            file: path.to_path_buf(),
            location: None,
            msg: e.to_string(),
        })?,
        path,
        Path::new(""),
        &stem,
    )
    .map_err(|e| in_conf_terms(e, path, &converted))?;
    Ok(Loaded { scene, warnings: converted.warnings })
}

/// An error the scene loader found in the converted scene of the conf at `path`, located in
/// the conf where the conversion knows where the field came from, else named as a field of
/// the converted scene (`viewcloth convert` writes it).
fn in_conf_terms(e: InputError, path: &Path, converted: &Converted) -> InputError {
    if e.file != path {
        return e; // a mesh or material file: its own location
    }
    let location = e.location.map(|loc| match converted.conf_location(&loc) {
        Some(conf) => conf,
        None => format!("{loc} (of the converted scene)"),
    });
    InputError { location, ..e }
}

/// Converts the conf at `path` into viewcloth scene JSON whose paths are relative to the
/// directory of `out` (the file it will be written to). Returns the text and the warnings.
pub fn convert_file(path: &Path, base: Option<&Path>, out: &Path) -> Res<(String, Vec<String>)> {
    let file_err = |msg: String| InputError { file: path.to_path_buf(), location: None, msg };
    let text = std::fs::read_to_string(path).map_err(|e| file_err(format!("cannot read scene file: {e}")))?;
    let value: Value = serde_json::from_str(&strip_comments(&text)).map_err(|e| InputError {
        file: path.to_path_buf(),
        location: Some(format!("line {}", e.line())),
        msg: e.to_string(),
    })?;
    if !is_arcsim(&value) {
        return Err(file_err("not an ARCSim scene file (it has \"version\" or no ARCSim keys)".into()));
    }
    let base = base.map(Path::to_path_buf).unwrap_or_else(|| default_base(path));
    let out_dir = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let relative = |p: &Path| relative_path(p, out_dir).to_string_lossy().into_owned();
    let converted = convert(&value, path, &base, &relative)?;
    let mut json = String::new();
    converted.scene.write_pretty(&mut json, 0);
    json.push('\n');
    Ok((json, converted.warnings))
}

/// ARCSim's root for a conf: the directory above the conf's directory.
pub fn default_base(conf: &Path) -> PathBuf {
    let dir = conf.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    dir.join("..")
}

/// True for a JSON object that is an ARCSim conf rather than a viewcloth scene.
pub fn is_arcsim(v: &Value) -> bool {
    let Some(m) = v.as_object() else { return false };
    if m.contains_key("version") {
        return false;
    }
    let arcsim_keys =
        ["frame_steps", "end_frame", "timestep", "save_frames", "motions", "magic", "disable", "obs_friction"];
    let cloth_keys = |c: &Value| c.get("materials").is_some() || c.get("remeshing").is_some();
    arcsim_keys.iter().any(|k| m.contains_key(*k))
        || m.get("cloths").and_then(Value::as_array).is_some_and(|cs| cs.iter().any(cloth_keys))
}

/// Removes `//` line comments and `/* */` block comments outside strings (jsoncpp accepts both).
pub fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    let mut in_string = false;
    while let Some(c) = chars.next() {
        if in_string {
            out.push(c);
            match c {
                '\\' => out.extend(chars.next()),
                '"' => in_string = false,
                _ => {}
            }
            continue;
        }
        match (c, chars.peek()) {
            ('"', _) => {
                in_string = true;
                out.push(c);
            }
            ('/', Some('/')) => {
                // Keep the newline so line numbers in errors stay right.
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            ('/', Some('*')) => {
                chars.next();
                let mut prev = ' ';
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                    }
                    if prev == '*' && c == '/' {
                        break;
                    }
                    prev = c;
                }
            }
            _ => out.push(c),
        }
    }
    out
}

/// `path` relative to `dir` when both resolve on disk (`dir` may not exist yet: its nearest
/// existing ancestor resolves), else `path` made absolute.
fn relative_path(path: &Path, dir: &Path) -> PathBuf {
    fn resolve(p: &Path) -> Option<PathBuf> {
        std::fs::canonicalize(p).ok().or_else(|| Some(resolve(p.parent()?)?.join(p.file_name()?)))
    }
    let dir = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    let (Some(p), Some(d)) = (std::fs::canonicalize(path).ok(), resolve(&dir)) else {
        return std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    };
    let (pc, dc): (Vec<_>, Vec<_>) = (p.components().collect(), d.components().collect());
    let common = pc.iter().zip(&dc).take_while(|(a, b)| a == b).count();
    let mut rel = PathBuf::new();
    for _ in common..dc.len() {
        rel.push("..");
    }
    for c in &pc[common..] {
        rel.push(c);
    }
    rel
}

#[cfg(test)]
mod tests {
    use super::ordered::{nums, obj};
    use super::*;

    #[test]
    fn comments_are_stripped_outside_strings() {
        let text = "{\n // a comment\n \"a\": \"x // not a comment\", /* block\n */ \"b\": 1 // end\n}";
        let v: Value = serde_json::from_str(&strip_comments(text)).unwrap();
        assert_eq!(v["a"], "x // not a comment");
        assert_eq!(v["b"], 1);
        assert_eq!(strip_comments(text).lines().count(), text.lines().count());
    }

    #[test]
    fn recognises_confs_by_their_keys() {
        let conf: Value = serde_json::from_str(r#"{"frame_time": 0.04, "frame_steps": 8, "cloths": []}"#).unwrap();
        assert!(is_arcsim(&conf));
        let scene: Value = serde_json::from_str(r#"{"version": 1, "frame_time": 0.04, "cloths": []}"#).unwrap();
        assert!(!is_arcsim(&scene));
        let cloth: Value = serde_json::from_str(r#"{"frame_time": 0.04, "cloths": [{"materials": []}]}"#).unwrap();
        assert!(is_arcsim(&cloth));
    }

    #[test]
    fn default_base_is_the_grand_parent() {
        assert_eq!(default_base(Path::new("a/conf/x.json")), Path::new("a/conf/.."));
        assert_eq!(default_base(Path::new("x.json")), Path::new("./.."));
    }

    #[test]
    fn ordered_json_keeps_key_order() {
        let j = obj(vec![("version", J::Int(1)), ("a", nums(&[0.5])), ("b", J::Bool(true))]);
        assert_eq!(serde_json::to_string(&j).unwrap(), r#"{"version":1,"a":[0.5],"b":true}"#);
        let mut pretty = String::new();
        j.write_pretty(&mut pretty, 0);
        assert_eq!(pretty, "{\n  \"version\": 1,\n  \"a\": [0.5],\n  \"b\": true\n}");
        let back: Value = serde_json::from_str(&pretty).unwrap();
        assert_eq!(back, serde_json::to_value(&j).unwrap());
    }
}
