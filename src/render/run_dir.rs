//! Reading a run's output directory (for `render` and `compare`): the frames and times listed
//! in `stats.json`, the frame meshes `frame_NNNN.obj` and the exported obstacles
//! `obstacle_<name>_NNNN.obj` — or, for a run written with `--format usd` (no OBJ frames), each
//! frame's USD samples `usd_samples/frame_NNNN.txt`, which hold the cloths and the exported
//! obstacles together (`io::usd_samples`).
//!
//! A run numbers its files with at least four digits, more when its frame count needs them
//! (`sim::run`); the width is found from the files themselves.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::error::InputError;
use crate::io::obj::read_obj;
use crate::io::stats::RunStats;
use crate::io::usd::SAMPLES_DIR;
use crate::io::usd_samples::read_samples;
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

/// Where a run's files are: its directory, the digits of its frame numbers, which files hold
/// its frames, and the names of the obstacles it exported as OBJ.
#[derive(Clone, Debug)]
pub struct RunFiles {
    dir: PathBuf,
    digits: usize,
    source: Source,
    obstacles: Vec<String>,
}

/// Which files hold a run's frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Source {
    Obj,
    /// `usd_samples/frame_NNNN.txt` (a `--format usd` run; obstacles are in the same file).
    /// `true` when the probed frame's file holds obstacles.
    Usd(bool),
}

impl RunFiles {
    /// The digits of the frame numbers from the name of frame `probe`'s OBJ, or else of its
    /// USD samples file, which then hold the frames (when neither exists, the run's default for
    /// a last frame `last` and OBJ frames; `load` reports the missing file), and the exported
    /// obstacles from the directory listing.
    pub fn scan(dir: &Path, probe: usize, last: usize) -> Result<RunFiles, InputError> {
        let obj = (4..=20).find(|&w| dir.join(frame_name(probe, w)).is_file());
        let usd = (4..=20).find(|&w| samples_path(dir, probe, w).is_file()).filter(|_| obj.is_none());
        if let Some(digits) = usd {
            let path = samples_path(dir, probe, digits);
            let frame = read_samples(&path).map_err(|msg| input_error(&path, msg))?;
            let source = Source::Usd(!frame.obstacles.is_empty());
            return Ok(RunFiles { dir: dir.to_path_buf(), digits, source, obstacles: Vec::new() });
        }
        let digits = obj.unwrap_or_else(|| last.to_string().len().max(4));
        let entries = std::fs::read_dir(dir).map_err(|e| input_error(dir, format!("cannot list: {e}")))?;
        let obstacles: BTreeSet<String> =
            entries.filter_map(|e| obstacle_name(&e.ok()?.file_name().to_string_lossy(), digits)).collect();
        Ok(RunFiles { dir: dir.to_path_buf(), digits, source: Source::Obj, obstacles: obstacles.into_iter().collect() })
    }

    /// The digits of the run's frame numbers in its file names.
    pub fn digits(&self) -> usize {
        self.digits
    }

    /// The frame's OBJ (also for a USD run: where strips and errors are named).
    pub fn frame_path(&self, frame: usize) -> PathBuf {
        self.dir.join(frame_name(frame, self.digits))
    }

    /// Whether frame `frame`'s file (OBJ or USD samples) is there.
    pub fn has_frame(&self, frame: usize) -> bool {
        match self.source {
            Source::Obj => self.frame_path(frame).is_file(),
            Source::Usd(_) => samples_path(&self.dir, frame, self.digits).is_file(),
        }
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
        !self.obstacles.is_empty() || self.source == Source::Usd(true)
    }

    /// The cloth of `frame` and the obstacles exported for it.
    pub fn load(&self, frame: usize) -> Result<FrameMeshes, InputError> {
        let mut meshes = self.cloth(frame)?;
        if let Some(o) = self.obstacles(frame)? {
            meshes.append(o.positions, o.triangles);
        }
        Ok(meshes)
    }

    /// The cloth of `frame` (every cloth of the run, as one mesh).
    pub fn cloth(&self, frame: usize) -> Result<FrameMeshes, InputError> {
        let mut meshes = FrameMeshes::default();
        match self.source {
            Source::Obj => {
                let path = self.frame_path(frame);
                if !path.is_file() && !samples_path(&self.dir, frame, self.digits).is_file() {
                    let msg = format!("missing (no OBJ frame, nor {SAMPLES_DIR}/ of a --format usd run)");
                    return Err(input_error(&path, msg));
                }
                let (x, t) = read_mesh(&path)?;
                meshes.append(x, t);
            }
            Source::Usd(_) => {
                for c in self.samples(frame)?.cloths {
                    meshes.append(c.positions, c.triangles);
                }
            }
        }
        meshes.cloth_triangles = meshes.triangles.len();
        Ok(meshes)
    }

    /// The obstacles the run exported for `frame` (none exported: None).
    pub fn obstacles(&self, frame: usize) -> Result<Option<FrameMeshes>, InputError> {
        if !self.has_obstacles() {
            return Ok(None);
        }
        let mut meshes = FrameMeshes::default();
        if let Source::Usd(_) = self.source {
            for o in self.samples(frame)?.obstacles {
                meshes.append(o.positions, o.triangles);
            }
            return Ok(Some(meshes));
        }
        for name in &self.obstacles {
            let path = self.obstacle_path(name, frame);
            if path.is_file() {
                let (x, t) = read_mesh(&path)?;
                meshes.append(x, t);
            }
        }
        Ok(Some(meshes))
    }

    fn samples(&self, frame: usize) -> Result<crate::io::usd_samples::SampledFrame, InputError> {
        let path = samples_path(&self.dir, frame, self.digits);
        if !path.is_file() {
            return Err(input_error(&path, "missing (the run has USD samples, not OBJ frames)"));
        }
        read_samples(&path).map_err(|msg| input_error(&path, msg))
    }
}

fn samples_path(dir: &Path, frame: usize, digits: usize) -> PathBuf {
    dir.join(SAMPLES_DIR).join(format!("frame_{frame:0digits$}.txt"))
}

/// The frame numbers of the `frame_NNNN.obj` files in `dir`, ascending, or else of its USD
/// samples files (none: an error naming the directory).
pub fn frame_numbers(dir: &Path) -> Result<Vec<usize>, InputError> {
    let mut frames = numbered(dir, ".obj")?;
    if frames.is_empty() && dir.join(SAMPLES_DIR).is_dir() {
        frames = numbered(&dir.join(SAMPLES_DIR), ".txt")?;
    }
    if frames.is_empty() {
        let msg = format!("no frame_NNNN.obj files nor {SAMPLES_DIR}/ (expected the output directory of a run)");
        return Err(input_error(dir, msg));
    }
    Ok(frames)
}

/// The numbers of the `frame_NNNN<ext>` files in `dir`, ascending.
fn numbered(dir: &Path, ext: &str) -> Result<Vec<usize>, InputError> {
    let entries = std::fs::read_dir(dir).map_err(|e| input_error(dir, format!("cannot list: {e}")))?;
    let mut frames: Vec<usize> = entries
        .filter_map(|e| {
            let name = e.ok()?.file_name().to_string_lossy().into_owned();
            let number = name.strip_prefix("frame_")?.strip_suffix(ext)?;
            number.bytes().all(|b| b.is_ascii_digit()).then(|| number.parse().ok())?
        })
        .collect();
    frames.sort_unstable();
    frames.dedup();
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
