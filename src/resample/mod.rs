//! `viewcloth resample`: one fixed-topology mesh for a whole adaptive run (Brown, Samii,
//! O'Brien & Narain 2015, "Resampling adaptive cloth simulations onto fixed-topology meshes").
//!
//! Every vertex of the target mesh has a fixed material-space location (its texture
//! coordinate, in the run's output units, which are the input's: `--mesh` can be the garment
//! the scene was made from). At each frame it is placed at that location on the frame's mesh:
//! the frame face containing it in material space (`locate`), and its barycentric combination
//! of the face's world positions (and velocities, when the run wrote `nv` lines). So the
//! resampled vertices lie on the adaptive surface; between them the fixed mesh's flat faces
//! depart from it, by the error reported per frame (two-sided surface distance, `metrics`).
//!
//! `--auto` makes the target from the run itself (`auto`): the first frame's mesh refined until
//! its edges are no longer, in any frame's sizing, than that frame's own faces, so it is fine
//! wherever the run ever was.
//!
//! Output (in `--out`): `frame_NNNN.obj` per frame (numbered as the run's), `cloth.pc2` (PC2
//! point cache: every frame's positions, one topology), `cloth.usda` (the faces once, points
//! and velocities time-sampled) and `resample.json` (target face count beside the run's mean and
//! max, error per frame).

mod auto;
mod locate;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::InputError;
use crate::io::obj::{read_obj, ObjData};
use crate::io::usd::{self, StageInfo};
use crate::io::{write_atomic, write_atomic_with};
use crate::math::{Real, Vec2, Vec3};
use crate::metrics::geometric::{surface_distance, Surface};
use crate::render::run_dir::{read_stats, RunFiles};
use locate::Locator;

/// Where the fixed mesh comes from.
pub enum Target {
    /// An OBJ whose `vt` are material locations in the run's texture units.
    Mesh(PathBuf),
    /// Made from the run's own meshes (`auto`).
    Auto,
}

#[derive(Debug, thiserror::Error)]
pub enum ResampleError {
    #[error("{0}")]
    Input(InputError),
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
}

impl From<InputError> for ResampleError {
    fn from(e: InputError) -> Self {
        ResampleError::Input(e)
    }
}

/// One resampled frame's error against the run's frame (m).
#[derive(Clone, Debug, Serialize)]
pub struct FrameError {
    pub frame: usize,
    pub time: Real,
    pub mean: Real,
    pub max: Real,
}

/// `resample.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ResampleReport {
    pub run: PathBuf,
    /// `auto` or the target OBJ.
    pub target: String,
    pub vertices: usize,
    pub faces: usize,
    pub run_mean_faces: Real,
    pub run_max_faces: usize,
    /// Largest distance of a target vertex outside the material domain of some frame (the
    /// vertex was placed on the nearest point of the domain), in texture units.
    pub max_outside: Real,
    pub frames: Vec<FrameError>,
}

/// The fixed mesh: node positions of its source, and per corner the node and texture index.
pub struct FixedMesh {
    pub texcoords: Vec<Vec2>,
    /// Per node, the texture coordinate it is tracked at.
    pub node_uv: Vec<Vec2>,
    pub triangles: Vec<[(usize, usize); 3]>,
}

/// One frame of the run, as read from its OBJ.
pub struct RunFrame {
    pub number: usize,
    pub time: Real,
    pub obj: ObjData,
    /// `nv` lines, when the run wrote them (one per `v`).
    pub velocities: Option<Vec<Vec3>>,
}

fn input_error(file: &Path, msg: impl Into<String>) -> ResampleError {
    ResampleError::Input(InputError { file: file.to_path_buf(), location: None, msg: msg.into() })
}

/// Reads frame `number` of the run: positions, faces with texture coordinates, and `nv`.
fn read_frame(files: &RunFiles, number: usize, time: Real) -> Result<RunFrame, ResampleError> {
    let path = files.frame_path(number);
    let obj = read_obj(&path).map_err(|msg| input_error(&path, msg))?;
    if obj.triangles.iter().any(|t| t[0].vt.is_none()) {
        return Err(input_error(&path, "faces without texture coordinates (not a viewcloth frame?)"));
    }
    let text = std::fs::read_to_string(&path).map_err(|source| ResampleError::Io { path: path.clone(), source })?;
    if text.lines().filter(|l| l.starts_with("o ")).count() > 1 {
        return Err(input_error(
            &path,
            "the run has several cloths; resample tracks one cloth (expected one 'o' group)",
        ));
    }
    let mut velocities = Vec::new();
    for (k, l) in text.lines().enumerate().filter(|(_, l)| l.starts_with("nv ")) {
        let c: Vec<Real> = l[3..].split_whitespace().filter_map(|w| w.parse().ok()).collect();
        if c.len() != 3 {
            return Err(input_error(&path, format!("line {}: 'nv' needs 3 numbers", k + 1)));
        }
        velocities.push(Vec3::new(c[0], c[1], c[2]));
    }
    let velocities = match velocities.len() {
        0 => None,
        n if n == obj.positions.len() => Some(velocities),
        n => return Err(input_error(&path, format!("{n} 'nv' lines for {} vertices", obj.positions.len()))),
    };
    Ok(RunFrame { number, time, obj, velocities })
}

/// The fixed mesh of an OBJ with texture coordinates on every face.
fn mesh_target(path: &Path) -> Result<FixedMesh, ResampleError> {
    let obj = read_obj(path).map_err(|msg| input_error(path, msg))?;
    if obj.triangles.iter().any(|t| t[0].vt.is_none()) {
        return Err(input_error(
            path,
            "expected texture coordinates (vt) on every face: the material locations to track",
        ));
    }
    let mut node_uv: Vec<Option<Vec2>> = vec![None; obj.positions.len()];
    for t in &obj.triangles {
        for c in t {
            node_uv[c.v].get_or_insert(obj.texcoords[c.vt.unwrap_or(0)]);
        }
    }
    if let Some(i) = node_uv.iter().position(Option::is_none) {
        return Err(input_error(path, format!("vertex {} is used by no face", i + 1)));
    }
    let triangles = obj.triangles.iter().map(|t| t.map(|c| (c.v, c.vt.unwrap_or(0)))).collect();
    Ok(FixedMesh { texcoords: obj.texcoords, node_uv: node_uv.into_iter().flatten().collect(), triangles })
}

/// Resamples the run in `run_dir` onto `target`, writing into `out`.
pub fn resample(run_dir: &Path, target: &Target, out: &Path) -> Result<ResampleReport, ResampleError> {
    let stats = read_stats(run_dir)?;
    let (Some(first), Some(last)) = (stats.frames.first(), stats.frames.last()) else {
        return Err(input_error(&run_dir.join("stats.json"), "lists no frames"));
    };
    let files = RunFiles::scan(run_dir, first.frame, last.frame)?;
    let frames = stats.frames.iter().map(|f| read_frame(&files, f.frame, f.time)).collect::<Result<Vec<_>, _>>()?;
    let fixed = match target {
        Target::Mesh(path) => mesh_target(path)?,
        Target::Auto => auto::auto_target(&frames).map_err(|msg| input_error(run_dir, msg))?,
    };
    std::fs::create_dir_all(out.join(usd::SAMPLES_DIR))
        .map_err(|source| ResampleError::Io { path: out.into(), source })?;
    let digits = files.digits();
    let triangles: Vec<[usize; 3]> = fixed.triangles.iter().map(|t| t.map(|c| c.0)).collect();
    let st_indices: Vec<[usize; 3]> = fixed.triangles.iter().map(|t| t.map(|c| c.1)).collect();
    let mut report = ResampleReport {
        run: run_dir.to_path_buf(),
        target: match target {
            Target::Mesh(p) => p.display().to_string(),
            Target::Auto => "auto".into(),
        },
        vertices: fixed.node_uv.len(),
        faces: fixed.triangles.len(),
        run_mean_faces: stats.frames.iter().map(|f| f.faces as Real).sum::<Real>() / stats.frames.len() as Real,
        run_max_faces: stats.frames.iter().map(|f| f.faces).max().unwrap_or(0),
        max_outside: 0.0,
        frames: Vec::new(),
    };
    let mut cache: Vec<Vec<Vec3>> = Vec::with_capacity(frames.len());
    let mut samples = Vec::with_capacity(frames.len());
    for frame in &frames {
        let (x, v, outside) = place(&fixed, frame);
        report.max_outside = report.max_outside.max(outside);
        let run_tris: Vec<[usize; 3]> = frame.obj.triangles.iter().map(|t| t.map(|c| c.v)).collect();
        let d = surface_distance(
            Surface { positions: &x, triangles: &triangles, weight: None },
            Surface { positions: &frame.obj.positions, triangles: &run_tris, weight: None },
        );
        report.frames.push(FrameError { frame: frame.number, time: frame.time, mean: d.mean, max: d.max });
        let obj_path = out.join(format!("frame_{:0digits$}.obj", frame.number));
        write_atomic(&obj_path, fixed_obj(&fixed, &x).as_bytes()).map_err(io(&obj_path))?;
        let sample_path = out.join(usd::SAMPLES_DIR).join(format!("frame_{:0digits$}.txt", frame.number));
        let velocities = (!v.is_empty()).then_some(&v[..]);
        let text =
            usd::fixed_samples("/World/cloth/resampled", &x, velocities, &triangles, &fixed.texcoords, &st_indices);
        write_atomic(&sample_path, text.as_bytes()).map_err(io(&sample_path))?;
        samples.push((frame.number, sample_path));
        cache.push(x);
    }
    let fps = match frames.as_slice() {
        [a, b, ..] if b.time > a.time => 1.0 / ((b.time - a.time) / (b.number - a.number) as Real),
        _ => 25.0,
    };
    let pc2 = out.join("cloth.pc2");
    write_atomic(&pc2, &pc2_bytes(&cache, first.frame as f32, 1.0)).map_err(io(&pc2))?;
    let info = StageInfo { scene: stats.scene.clone(), fps, start: first.frame, end: last.frame };
    let layer = out.join("cloth.usda");
    write_atomic_with(&layer, |f| usd::assemble(f, &info, &samples)).map_err(|e| match e {
        usd::AssembleError::Write(source) => ResampleError::Io { path: layer.clone(), source },
        other => input_error(&layer, other.to_string()),
    })?;
    let json_path = out.join("resample.json");
    let json = serde_json::to_vec_pretty(&report)
        .map_err(|e| ResampleError::Io { path: json_path.clone(), source: e.into() })?;
    write_atomic(&json_path, &json).map_err(io(&json_path))?;
    Ok(report)
}

/// The fixed mesh's nodes placed on `frame`: positions, velocities (when the frame has them)
/// and how far outside the frame's material domain a node was (texture units).
fn place(fixed: &FixedMesh, frame: &RunFrame) -> (Vec<Vec3>, Vec<Vec3>, Real) {
    let locator = Locator::new(&frame.obj);
    let (mut x, mut v, mut outside) = (Vec::with_capacity(fixed.node_uv.len()), Vec::new(), 0.0);
    for uv in &fixed.node_uv {
        let hit = locator.locate(uv);
        outside = hit.outside.max(outside);
        let corners = frame.obj.triangles[hit.triangle].map(|c| c.v);
        let mix = |p: &[Vec3]| (0..3).map(|k| p[corners[k]] * hit.bary[k]).fold(Vec3::zeros(), |a, b| a + b);
        x.push(mix(&frame.obj.positions));
        if let Some(vel) = &frame.velocities {
            v.push(mix(vel));
        }
    }
    (x, v, outside)
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ResampleError + '_ {
    move |source| ResampleError::Io { path: path.to_path_buf(), source }
}

/// A resampled frame as OBJ: `v` per fixed node, the fixed `vt`, `f v/vt`.
fn fixed_obj(fixed: &FixedMesh, x: &[Vec3]) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("# viewcloth resampled frame\n");
    for p in x {
        let _ = writeln!(s, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
    }
    for u in &fixed.texcoords {
        let _ = writeln!(s, "vt {:.9} {:.9}", u.x, u.y);
    }
    for t in &fixed.triangles {
        let _ =
            writeln!(s, "f {}/{} {}/{} {}/{}", t[0].0 + 1, t[0].1 + 1, t[1].0 + 1, t[1].1 + 1, t[2].0 + 1, t[2].1 + 1);
    }
    s
}

/// A PC2 point cache (Blender's and 3ds Max's format): `POINTCACHE2\0`, version 1, point count,
/// start frame, sample rate, sample count (little endian), then every sample's points as
/// 32-bit float triples.
pub fn pc2_bytes(frames: &[Vec<Vec3>], start: f32, rate: f32) -> Vec<u8> {
    let points = frames.first().map_or(0, Vec::len);
    let mut b = Vec::with_capacity(32 + frames.len() * points * 12);
    b.extend_from_slice(b"POINTCACHE2\0");
    b.extend_from_slice(&1i32.to_le_bytes());
    b.extend_from_slice(&(points as i32).to_le_bytes());
    b.extend_from_slice(&start.to_le_bytes());
    b.extend_from_slice(&rate.to_le_bytes());
    b.extend_from_slice(&(frames.len() as i32).to_le_bytes());
    for p in frames.iter().flatten() {
        for c in [p.x, p.y, p.z] {
            b.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    b
}
