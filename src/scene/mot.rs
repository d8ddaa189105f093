//! `.mot` motion files (ARCSim's character motions): per body, one rigid transform per frame.
//!
//! Layout: a line `NumFrames: N`, then per body i a header `body[i] position` and N lines
//! `x y z`, then a header `body[i] orientation` and N lines `w x y z` (unit quaternion, scalar
//! first). Blank lines between blocks are allowed. Frame k is at time k / fps; a body's frames
//! become keyframes of a `Motion` (central-difference Hermite tangents, as ARCSim's
//! `build_cubic_spline`), each frame's transform followed by a fixed one (ARCSim's motion
//! `transform`, applied after the body's own).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use nalgebra::{Quaternion, UnitQuaternion};

use crate::error::InputError;
use crate::math::motion::{Keyframe, Motion, Transform};
use crate::math::{Real, Vec3};

/// The frames of every body of a `.mot` file.
#[derive(Clone, Debug, PartialEq)]
pub struct MotFile {
    /// `bodies[i][k]`: body i at frame k.
    pub bodies: Vec<Vec<Transform>>,
}

impl MotFile {
    /// Body `body`'s motion: frame k at time k / fps − start_time, each frame's transform
    /// followed by `after`.
    pub fn body_motion(&self, body: usize, fps: Real, start_time: Real, after: &Transform) -> Motion {
        let keys = self.bodies[body]
            .iter()
            .enumerate()
            .map(|(k, t)| Keyframe { time: k as Real / fps - start_time, transform: after.compose(t) })
            .collect();
        Motion::new(keys)
    }
}

/// Reads and checks a `.mot` file; errors name the line. A scene names one file once per body
/// (and once more per instance of a character): a file read before with the same text is
/// parsed once per process.
pub fn read_mot(path: &Path) -> Result<Arc<MotFile>, InputError> {
    static PARSED: Mutex<Vec<(PathBuf, String, Arc<MotFile>)>> = Mutex::new(Vec::new());
    let text = std::fs::read_to_string(path).map_err(|e| InputError {
        file: path.to_path_buf(),
        location: None,
        msg: format!("cannot read motion file: {e}"),
    })?;
    let mut parsed = PARSED.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if let Some((_, _, file)) = parsed.iter().find(|(p, t, _)| p == path && *t == text) {
        return Ok(file.clone());
    }
    let file = Arc::new(parse_mot(&text).map_err(|(line, msg)| InputError {
        file: path.to_path_buf(),
        location: (line > 0).then(|| format!("line {line}")),
        msg,
    })?);
    parsed.retain(|(p, _, _)| p != path);
    parsed.push((path.to_path_buf(), text, file.clone()));
    Ok(file)
}

/// Parses `.mot` text; errors are (1-based line, message).
pub fn parse_mot(text: &str) -> Result<MotFile, (usize, String)> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty());
    let (ln, first) = lines.next().ok_or((0, "empty motion file".to_string()))?;
    let frames = first
        .strip_prefix("NumFrames:")
        .and_then(|n| n.trim().parse::<usize>().ok())
        .filter(|&n| n >= 1)
        .ok_or((ln, format!("expected \"NumFrames: N\" with N ≥ 1, found \"{first}\"")))?;
    let mut bodies = Vec::new();
    while let Some((ln, header)) = lines.next() {
        let i = bodies.len();
        let expect = |got: &str, what: &str| {
            if got == format!("body[{i}] {what}") {
                Ok(())
            } else {
                Err((ln, format!("expected \"body[{i}] {what}\", found \"{got}\"")))
            }
        };
        expect(header, "position")?;
        let positions = numbers::<3>(&mut lines, frames, ln)?;
        let (ln, header) = lines.next().ok_or((ln, format!("missing \"body[{i}] orientation\"")))?;
        if header != format!("body[{i}] orientation") {
            return Err((ln, format!("expected \"body[{i}] orientation\", found \"{header}\"")));
        }
        let quats = numbers::<4>(&mut lines, frames, ln)?;
        let mut body = Vec::with_capacity(frames);
        for (p, (qln, q)) in positions.iter().zip(&quats) {
            let quat = Quaternion::new(q[0], q[1], q[2], q[3]);
            if quat.norm() < 1e-6 {
                return Err((*qln, "orientation is not a unit quaternion (norm ≈ 0)".into()));
            }
            let rotate = UnitQuaternion::from_quaternion(quat);
            body.push(Transform { translate: Vec3::new(p.1[0], p.1[1], p.1[2]), rotate, scale: 1.0 });
        }
        bodies.push(body);
    }
    if bodies.is_empty() {
        return Err((ln, "no bodies after the NumFrames line".into()));
    }
    Ok(MotFile { bodies })
}

/// The next `count` lines of N finite numbers each, with their line numbers.
fn numbers<'a, const N: usize>(
    lines: &mut impl Iterator<Item = (usize, &'a str)>,
    count: usize,
    header_line: usize,
) -> Result<Vec<(usize, [Real; N])>, (usize, String)> {
    let mut out = Vec::with_capacity(count);
    let mut last = header_line;
    for _ in 0..count {
        let (ln, l) =
            lines.next().ok_or((last, format!("expected {count} lines of {N} numbers after line {header_line}")))?;
        last = ln;
        let words: Vec<&str> = l.split_whitespace().collect();
        if words.len() != N {
            return Err((ln, format!("expected {N} numbers, found \"{l}\"")));
        }
        let mut v = [0.0; N];
        for (x, w) in v.iter_mut().zip(&words) {
            *x = w
                .parse::<Real>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or((ln, format!("expected a number, found \"{w}\"")))?;
        }
        out.push((ln, v));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWO_BODIES: &str =
        "NumFrames: 2\nbody[0] position\n0 0 0\n1 0 0\n\nbody[0] orientation\n1 0 0 0\n1 0 0 0\n\n\
        body[1] position\n0 0 1\n0 0 2\nbody[1] orientation\n1 0 0 0\n0.7071068 0 0 0.7071068\n";

    #[test]
    fn parses_bodies_and_frames() {
        let m = parse_mot(TWO_BODIES).unwrap();
        assert_eq!(m.bodies.len(), 2);
        assert_eq!(m.bodies[0][1].translate, Vec3::new(1.0, 0.0, 0.0));
        let p = m.bodies[1][1].apply(&Vec3::x());
        assert!((p - Vec3::new(0.0, 1.0, 2.0)).norm() < 1e-6);
    }

    #[test]
    fn body_motion_composes_the_transform_after_the_body() {
        let m = parse_mot(TWO_BODIES).unwrap();
        let after = Transform::new([0.0, 0.0, -1.0], Some([90.0, 1.0, 0.0, 0.0]), 1.0);
        let motion = m.body_motion(0, 10.0, 0.0, &after);
        // Frame 1 (t = 0.1): body at x = 1, then the transform (x stays, z − 1).
        let p = motion.eval(0.1).apply(&Vec3::zeros());
        assert!((p - Vec3::new(1.0, 0.0, -1.0)).norm() < 1e-12);
    }

    #[test]
    fn errors_name_the_line() {
        let bad = "NumFrames: 2\nbody[0] position\n0 0 0\n1 x 0\n";
        assert_eq!(parse_mot(bad).unwrap_err().0, 4);
        let short = "NumFrames: 3\nbody[0] position\n0 0 0\n";
        assert!(parse_mot(short).is_err());
        assert_eq!(parse_mot("Frames 3").unwrap_err().0, 1);
    }
}
