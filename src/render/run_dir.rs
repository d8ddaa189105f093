//! Reading a run's output directory (for `render` and `compare`): the frames and times listed
//! in `stats.json`, the frame meshes `frame_NNNN.obj` and the exported obstacles
//! `obstacle_<name>_NNNN.obj`.
//!
//! A run numbers its files with at least four digits, more when its frame count needs them
//! (`sim::run`); the width is found from the files themselves.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::error::InputError;
use crate::io::obj::read_obj;
use crate::io::stats::RunStats;
use crate::math::{Real, Vec3};

/// One frame's surfaces, rasterised together: the cloth's triangles first, then the obstacles'.
#[derive(Clone, Debug, Default)]
pub struct FrameMeshes {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[usize; 3]>,
    /// Triangles `0..cloth_triangles` are cloth, the rest obstacles.
    pub cloth_triangles: usize,
}

impl FrameMeshes {
    /// Appends a mesh, renumbering its triangles after the positions already held.
    pub fn append(&mut self, positions: Vec<Vec3>, triangles: Vec<[usize; 3]>) {
        let base = self.positions.len();
        self.positions.extend(positions);
        self.triangles.extend(triangles.into_iter().map(|t| t.map(|i| i + base)));
    }
}

fn input_error(file: &Path, msg: impl Into<String>) -> InputError {
    InputError { file: file.to_path_buf(), location: None, msg: msg.into() }
}

/// The run's `stats.json`.
pub fn read_stats(dir: &Path) -> Result<RunStats, InputError> {
    let path = dir.join("stats.json");
    let text = std::fs::read_to_string(&path).map_err(|e| input_error(&path, format!("cannot read: {e}")))?;
    serde_json::from_str(&text).map_err(|e| input_error(&path, format!("not a viewcloth stats.json: {e}")))
}

/// The frames to render, as (frame number, time): those listed in `stats` within `range`
/// (inclusive; all of them by default), every `every`-th counted from the range's first frame.
/// A range reaching outside the listed frames is an error (`stats_path` names the file).
pub fn select_frames(
    stats: &RunStats,
    range: Option<(usize, usize)>,
    every: usize,
    stats_path: &Path,
) -> Result<Vec<(usize, Real)>, InputError> {
    let numbers = stats.frames.iter().map(|f| f.frame);
    let (Some(first), Some(last)) = (numbers.clone().min(), numbers.max()) else {
        return Err(input_error(stats_path, "lists no frames"));
    };
    let (a, b) = range.unwrap_or((first, last));
    if a > b || a < first || b > last {
        return Err(input_error(
            stats_path,
            format!("frames {a}..{b} are not in the run (it has frames {first}..{last})"),
        ));
    }
    let every = every.max(1);
    Ok(stats
        .frames
        .iter()
        .filter(|f| (a..=b).contains(&f.frame) && (f.frame - a) % every == 0)
        .map(|f| (f.frame, f.time))
        .collect())
}

/// Where a run's files are: its directory, the digits of its frame numbers, and the names of
/// the obstacles it exported.
#[derive(Clone, Debug)]
pub struct RunFiles {
    dir: PathBuf,
    digits: usize,
    obstacles: Vec<String>,
}

impl RunFiles {
    /// The digits of the frame numbers from the name of frame `probe`'s OBJ (when it is
    /// missing, the run's default for a last frame `last`, and `load` reports the file), and
    /// the exported obstacles from the directory listing.
    pub fn scan(dir: &Path, probe: usize, last: usize) -> Result<RunFiles, InputError> {
        let digits = (4..=20)
            .find(|&w| dir.join(frame_name(probe, w)).is_file())
            .unwrap_or_else(|| last.to_string().len().max(4));
        let entries = std::fs::read_dir(dir).map_err(|e| input_error(dir, format!("cannot list: {e}")))?;
        let obstacles: BTreeSet<String> =
            entries.filter_map(|e| obstacle_name(&e.ok()?.file_name().to_string_lossy(), digits)).collect();
        Ok(RunFiles { dir: dir.to_path_buf(), digits, obstacles: obstacles.into_iter().collect() })
    }

    /// The digits of the run's frame numbers in its file names.
    pub fn digits(&self) -> usize {
        self.digits
    }

    pub fn frame_path(&self, frame: usize) -> PathBuf {
        self.dir.join(frame_name(frame, self.digits))
    }

    fn obstacle_path(&self, name: &str, frame: usize) -> PathBuf {
        self.dir.join(format!("obstacle_{name}_{frame:0w$}.obj", w = self.digits))
    }

    /// `view_NNNN.png`, numbered as the frames.
    pub fn image_path(&self, frame: usize) -> PathBuf {
        self.dir.join(format!("view_{frame:0w$}.png", w = self.digits))
    }

    /// Whether the run exported obstacle meshes (`--export-obstacles`).
    pub fn has_obstacles(&self) -> bool {
        !self.obstacles.is_empty()
    }

    /// The cloth of `frame` and the obstacles exported for it.
    pub fn load(&self, frame: usize) -> Result<FrameMeshes, InputError> {
        let mut meshes = FrameMeshes::default();
        let (x, t) = read_mesh(&self.frame_path(frame))?;
        meshes.append(x, t);
        meshes.cloth_triangles = meshes.triangles.len();
        for name in &self.obstacles {
            let path = self.obstacle_path(name, frame);
            if path.is_file() {
                let (x, t) = read_mesh(&path)?;
                meshes.append(x, t);
            }
        }
        Ok(meshes)
    }
}

impl RunFiles {
    /// The obstacles the run exported for `frame` (none exported: None).
    pub fn obstacles(&self, frame: usize) -> Result<Option<FrameMeshes>, InputError> {
        if self.obstacles.is_empty() {
            return Ok(None);
        }
        let mut meshes = FrameMeshes::default();
        for name in &self.obstacles {
            let path = self.obstacle_path(name, frame);
            if path.is_file() {
                let (x, t) = read_mesh(&path)?;
                meshes.append(x, t);
            }
        }
        Ok(Some(meshes))
    }
}

/// The frame numbers of the `frame_NNNN.obj` files in `dir`, ascending (none: an error naming
/// the directory).
pub fn frame_numbers(dir: &Path) -> Result<Vec<usize>, InputError> {
    let entries = std::fs::read_dir(dir).map_err(|e| input_error(dir, format!("cannot list: {e}")))?;
    let mut frames: Vec<usize> = entries
        .filter_map(|e| {
            let name = e.ok()?.file_name().to_string_lossy().into_owned();
            let number = name.strip_prefix("frame_")?.strip_suffix(".obj")?;
            number.bytes().all(|b| b.is_ascii_digit()).then(|| number.parse().ok())?
        })
        .collect();
    frames.sort_unstable();
    frames.dedup();
    if frames.is_empty() {
        return Err(input_error(dir, "no frame_NNNN.obj files (expected the output directory of a run)"));
    }
    Ok(frames)
}

fn frame_name(frame: usize, digits: usize) -> String {
    format!("frame_{frame:0digits$}.obj")
}

/// The obstacle's name when `file` is `obstacle_<name>_<frame>.obj` with the frame number
/// written in `digits` digits (the name may itself contain underscores and digits).
fn obstacle_name(file: &str, digits: usize) -> Option<String> {
    let (name, number) = file.strip_prefix("obstacle_")?.strip_suffix(".obj")?.rsplit_once('_')?;
    let n: usize = number.parse().ok().filter(|_| number.bytes().all(|b| b.is_ascii_digit()))?;
    (!name.is_empty() && format!("{n:0digits$}") == number).then(|| name.to_string())
}

/// Positions and triangles of an OBJ file.
fn read_mesh(path: &Path) -> Result<(Vec<Vec3>, Vec<[usize; 3]>), InputError> {
    let obj = read_obj(path).map_err(|msg| input_error(path, msg))?;
    let triangles = obj.triangles.iter().map(|t| t.map(|c| c.v)).collect();
    Ok((obj.positions, triangles))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::stats::FrameStats;

    fn stats(frames: usize) -> RunStats {
        let frames = (0..=frames).map(|f| FrameStats { frame: f, time: 0.04 * f as Real, ..Default::default() });
        RunStats { frames: frames.collect(), ..Default::default() }
    }

    #[test]
    fn frames_are_selected_by_range_and_every_nth_from_its_start() {
        let s = stats(30);
        let p = Path::new("stats.json");
        let numbers = |range, every| -> Vec<usize> {
            select_frames(&s, range, every, p).unwrap().into_iter().map(|(f, _)| f).collect()
        };
        assert_eq!(numbers(None, 1).len(), 31);
        assert_eq!(numbers(None, 10), [0, 10, 20, 30]);
        assert_eq!(numbers(Some((5, 17)), 5), [5, 10, 15]);
        assert_eq!(numbers(Some((30, 30)), 1), [30]);
        let (_, t) = select_frames(&s, Some((25, 25)), 1, p).unwrap()[0];
        assert!((t - 1.0).abs() < 1e-12);
        for bad in [(20, 10), (25, 31)] {
            let e = select_frames(&s, Some(bad), 1, p).unwrap_err();
            assert!(e.msg.contains("frames 0..30"), "{e}");
        }
        assert!(select_frames(&RunStats::default(), None, 1, p).is_err());
    }

    #[test]
    fn obstacle_files_are_told_apart_by_their_frame_digits() {
        assert_eq!(obstacle_name("obstacle_sphere_0012.obj", 4).as_deref(), Some("sphere"));
        assert_eq!(obstacle_name("obstacle_ball_2_0000.obj", 4).as_deref(), Some("ball_2"));
        assert_eq!(obstacle_name("obstacle_sphere_12345.obj", 4).as_deref(), Some("sphere"));
        assert_eq!(obstacle_name("obstacle_sphere_00012.obj", 4), None);
        assert_eq!(obstacle_name("obstacle_sphere_00012.obj", 5).as_deref(), Some("sphere"));
        assert_eq!(obstacle_name(".obstacle_sphere_0012.obj.tmp99", 4), None);
        assert_eq!(obstacle_name("obstacle__0012.obj", 4), None);
        assert_eq!(obstacle_name("frame_0012.obj", 4), None);
        assert_eq!(obstacle_name("obstacle_sphere_+012.obj", 4), None);
    }
}
