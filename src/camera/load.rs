//! Reading a camera file: JSON → `CameraSpec` (with the JSON path of any error) → range checks →
//! `Camera`.

use std::path::Path;

use super::spec::{CameraSpec, KeySpec};
use super::{Camera, Key};
use crate::error::InputError;
use crate::math::{Real, Vec3};

type Res<T> = Result<T, InputError>;

/// Largest magnitude accepted for a time (s) or coordinate (m): far beyond any shot, and small
/// enough that differences and spline weights cannot overflow.
const MAX_MAGNITUDE: Real = 1e9;
/// Shortest accepted eye–target distance (m) and length of `up`.
const MIN_LENGTH: Real = 1e-9;
/// Smallest accepted sine of the angle between `up` and the viewing direction.
const MIN_SINE: Real = 1e-6;

fn err(file: &Path, location: impl Into<String>, msg: impl Into<String>) -> InputError {
    InputError { file: file.to_path_buf(), location: Some(location.into()), msg: msg.into() }
}

/// `[0, 0, 1]`: vectors in messages as they would be written in the file.
pub(super) fn fmt3(v: &[Real; 3]) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

pub(super) fn read(path: &Path) -> Res<Camera> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError {
        file: path.to_path_buf(),
        location: None,
        msg: format!("cannot read camera file: {e}"),
    })?;
    parse(&text, path)
}

pub(super) fn parse(text: &str, file: &Path) -> Res<Camera> {
    let spec: CameraSpec = crate::io::json::parse(text).map_err(|(loc, msg)| err(file, loc, msg))?;
    build(file, spec)
}

/// Range checks, in the order of the file's fields.
pub(super) fn build(file: &Path, spec: CameraSpec) -> Res<Camera> {
    if spec.version != 1 {
        return Err(err(file, "version", format!("expected 1, got {}", spec.version)));
    }
    let aspect = positive(file, "aspect", spec.aspect)?;
    let near = positive(file, "near", spec.near)?;
    let far = bounded(file, "far", spec.far)?;
    if far <= near {
        return Err(err(file, "far", format!("expected a distance greater than near ({near}), got {far}")));
    }
    if spec.keys.is_empty() {
        return Err(err(file, "keys", "expected at least one key, got none"));
    }
    let mut keys: Vec<Key> = Vec::with_capacity(spec.keys.len());
    for (i, k) in spec.keys.iter().enumerate() {
        let key = build_key(file, &format!("keys[{i}]"), k)?;
        if let Some(prev) = keys.last() {
            if key.time <= prev.time {
                return Err(err(
                    file,
                    format!("keys[{i}].time"),
                    format!("expected a time greater than the previous key's ({}), got {}", prev.time, key.time),
                ));
            }
        }
        keys.push(key);
    }
    Ok(Camera::new(keys, spec.interpolation, aspect, near, far))
}

fn build_key(file: &Path, at: &str, k: &KeySpec) -> Res<Key> {
    let time = bounded(file, &format!("{at}.time"), k.time)?;
    let position = bounded3(file, &format!("{at}.position"), &k.position)?;
    let target = bounded3(file, &format!("{at}.target"), &k.target)?;
    let up = bounded3(file, &format!("{at}.up"), &k.up)?;
    let fov = bounded(file, &format!("{at}.fov"), k.fov)?;
    if fov <= 0.0 || fov >= 180.0 {
        return Err(err(
            file,
            format!("{at}.fov"),
            format!("expected a vertical field of view strictly between 0 and 180 degrees, got {fov}"),
        ));
    }
    let dir = target - position;
    if dir.norm() <= MIN_LENGTH {
        return Err(err(
            file,
            format!("{at}.target"),
            format!(
                "target {} is at the position {}; expected a point at least {MIN_LENGTH} m away",
                fmt3(&k.target),
                fmt3(&k.position)
            ),
        ));
    }
    let up_len = up.norm();
    if up_len <= MIN_LENGTH {
        return Err(err(file, format!("{at}.up"), format!("expected a non-zero direction, got {}", fmt3(&k.up))));
    }
    if up.cross(&dir).norm() / (up_len * dir.norm()) <= MIN_SINE {
        return Err(err(
            file,
            format!("{at}.up"),
            format!(
                "up {} is parallel to the viewing direction {}; expected a direction that is not",
                fmt3(&k.up),
                fmt3(&dir.into())
            ),
        ));
    }
    Ok(Key { time, position, target, up: up / up_len, fov })
}

fn bounded(file: &Path, at: &str, v: Real) -> Res<Real> {
    if v.is_finite() && v.abs() <= MAX_MAGNITUDE {
        Ok(v)
    } else {
        Err(err(file, at, format!("expected a finite number of magnitude at most {MAX_MAGNITUDE:e}, got {v}")))
    }
}

fn bounded3(file: &Path, at: &str, v: &[Real; 3]) -> Res<Vec3> {
    if v.iter().all(|c| c.is_finite() && c.abs() <= MAX_MAGNITUDE) {
        Ok(Vec3::from(*v))
    } else {
        Err(err(
            file,
            at,
            format!("expected finite coordinates of magnitude at most {MAX_MAGNITUDE:e}, got {}", fmt3(v)),
        ))
    }
}

fn positive(file: &Path, at: &str, v: Real) -> Res<Real> {
    let v = bounded(file, at, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(err(file, at, format!("expected a positive number, got {v}")))
    }
}

#[cfg(test)]
mod tests {
    use super::super::spec::Interpolation;
    use super::*;

    const FILE: &str = "cameras/test.json";

    /// A valid two-key camera with `edit` applied to its JSON text.
    fn camera_json(edit: impl Fn(&mut serde_json::Value)) -> String {
        let mut v = serde_json::json!({
            "version": 1,
            "aspect": 1.5,
            "near": 0.1,
            "far": 50.0,
            "interpolation": "linear",
            "keys": [
                { "time": 0.0, "position": [0, -3, 1], "target": [0, 0, 0.5], "up": [0, 0, 1], "fov": 40 },
                { "time": 2.0, "position": [1, -3, 1], "target": [0, 0, 0.5], "fov": 30 },
                { "time": 4.0, "position": [2, -3, 1], "target": [0, 0, 0.5], "fov": 30 }
            ]
        });
        edit(&mut v);
        v.to_string()
    }

    fn load(text: &str) -> Res<Camera> {
        parse(text, Path::new(FILE))
    }

    #[test]
    fn valid_camera_and_defaults() {
        let cam = load(&camera_json(|_| {})).unwrap();
        assert_eq!((cam.aspect, cam.near, cam.far), (1.5, 0.1, 50.0));
        assert_eq!(cam.interpolation, Interpolation::Linear);
        assert_eq!(cam.keys.len(), 3);
        let minimal =
            r#"{ "version": 1, "keys": [ { "time": 0, "position": [0, -3, 1], "target": [0, 0, 0], "fov": 40 } ] }"#;
        let cam = load(minimal).unwrap();
        assert_eq!((cam.aspect, cam.near, cam.far), (16.0 / 9.0, 0.05, 100.0));
        assert_eq!(cam.interpolation, Interpolation::CatmullRom);
        assert_eq!(cam.keys[0].up, Vec3::new(0.0, 0.0, 1.0));
    }

    /// Every validation rule: (what, edit of a valid file, expected location, words in the message).
    #[test]
    fn each_error_names_its_field() {
        type Edit = Box<dyn Fn(&mut serde_json::Value)>;
        let set = |path: &'static str, value: serde_json::Value| -> Edit {
            Box::new(move |v: &mut serde_json::Value| *v.pointer_mut(path).unwrap() = value.clone())
        };
        let remove = |path: &'static str, field: &'static str| -> Edit {
            Box::new(move |v: &mut serde_json::Value| {
                v.pointer_mut(path).unwrap().as_object_mut().unwrap().remove(field);
            })
        };
        let add = |path: &'static str, field: &'static str, value: serde_json::Value| -> Edit {
            Box::new(move |v: &mut serde_json::Value| {
                v.pointer_mut(path).unwrap().as_object_mut().unwrap().insert(field.into(), value.clone());
            })
        };
        let cases: Vec<(&str, Edit, &str, &str)> = vec![
            ("version", set("/version", 2.into()), "version", "expected 1, got 2"),
            ("no keys", set("/keys", serde_json::json!([])), "keys", "at least one key"),
            ("time order", set("/keys/2/time", 2.0.into()), "keys[2].time", "greater than the previous key's (2)"),
            ("time before", set("/keys/1/time", (-1.0).into()), "keys[1].time", "got -1"),
            ("fov 180", set("/keys/2/fov", 180.into()), "keys[2].fov", "strictly between 0 and 180 degrees, got 180"),
            ("fov 0", set("/keys/0/fov", 0.into()), "keys[0].fov", "got 0"),
            ("fov negative", set("/keys/1/fov", (-10).into()), "keys[1].fov", "got -10"),
            ("target = position", set("/keys/1/target", serde_json::json!([1, -3, 1])), "keys[1].target", "at least"),
            ("up zero", set("/keys/0/up", serde_json::json!([0, 0, 0])), "keys[0].up", "non-zero direction"),
            (
                "up parallel",
                set("/keys/1/target", serde_json::json!([1, -3, 5])),
                "keys[1].up",
                "up [0, 0, 1] is parallel to the viewing direction [0, 0, 4]; expected a direction that is not",
            ),
            ("up antiparallel", set("/keys/0/up", serde_json::json!([0, -6, 1])), "keys[0].up", "parallel"),
            ("huge time", set("/keys/0/time", 1e300.into()), "keys[0].time", "magnitude at most 1e9"),
            ("huge position", set("/keys/2/position", serde_json::json!([0, 1e20, 0])), "keys[2].position", "1e9"),
            ("aspect 0", set("/aspect", 0.into()), "aspect", "expected a positive number, got 0"),
            ("near negative", set("/near", (-0.1).into()), "near", "expected a positive number, got -0.1"),
            ("far < near", set("/far", 0.05.into()), "far", "greater than near (0.1), got 0.05"),
            ("far = near", set("/far", 0.1.into()), "far", "greater than near"),
            ("interpolation", set("/interpolation", "cubic".into()), "interpolation", "unknown variant `cubic`"),
            ("unknown field", add("/keys/1", "fovy", 30.into()), "keys[1].fovy", "unknown field `fovy`"),
            ("wrong type", set("/keys/0/position", "origin".into()), "keys[0].position", "expected an array"),
            (
                "short vector",
                set("/keys/0/up", serde_json::json!([0, 1])),
                "keys[0].up",
                "expected an array of length 3",
            ),
            ("missing fov", remove("/keys/2", "fov"), "keys[2]", "fov"),
            ("missing keys", remove("", "keys"), "JSON", "keys"),
        ];
        for (what, edit, location, words) in cases {
            let e = load(&camera_json(edit)).expect_err(what);
            assert_eq!(e.location.as_deref(), Some(location), "{what}: {e}");
            assert!(e.msg.contains(words), "{what}: {e}");
            assert_eq!(e.file, Path::new(FILE), "{what}");
        }
    }

    #[test]
    fn syntax_errors_name_the_line() {
        let e = load("{\n  \"version\": 1,\n  \"keys\": [,]\n}").unwrap_err();
        assert_eq!(e.location.as_deref(), Some("line 3"), "{e}");
        let e = load(&(camera_json(|_| {}) + "\n]")).unwrap_err();
        assert_eq!(e.location.as_deref(), Some("line 2"), "{e}");
        let e = load("").unwrap_err();
        assert_eq!(e.location.as_deref(), Some("line 1"), "{e}");
    }

    /// JSON cannot spell NaN or infinity, so the finiteness check is reached through the spec.
    #[test]
    fn non_finite_numbers_are_rejected() {
        let spec: CameraSpec = serde_json::from_str(&camera_json(|_| {})).unwrap();
        let file = Path::new(FILE);
        let mut s = spec.clone();
        s.keys[1].position[2] = Real::NAN;
        assert_eq!(build(file, s).unwrap_err().location.as_deref(), Some("keys[1].position"));
        let mut s = spec.clone();
        s.keys[0].fov = Real::INFINITY;
        assert_eq!(build(file, s).unwrap_err().location.as_deref(), Some("keys[0].fov"));
        let mut s = spec.clone();
        s.far = Real::INFINITY;
        assert_eq!(build(file, s).unwrap_err().location.as_deref(), Some("far"));
        let mut s = spec;
        s.aspect = Real::NAN;
        assert_eq!(build(file, s).unwrap_err().location.as_deref(), Some("aspect"));
    }
}
