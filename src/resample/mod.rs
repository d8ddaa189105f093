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
//! Every cloth of the run is resampled onto its own fixed mesh (`--mesh` once per cloth, in
//! the order of the run's `o` groups, or `--auto` for all); the outputs hold them all, as the
//! run's frames do.
//!
//! Output (in `--out`): `frame_NNNN.obj` per frame (numbered as the run's; one `o` group per
//! cloth when there are several), `cloth.pc2` (PC2 point cache: every frame's positions, the
//! cloths' one after the other, one topology), `cloth.usda` (a prim per cloth: the faces once,
//! points and velocities time-sampled) and `resample.json` (target face count beside the run's
//! mean and max, error per frame).
//!
//! The run is streamed: `--auto` reads the frames once per refinement round, and the
//! resampling reads, places and writes one frame at a time (the PC2 cache is appended to as it
//! goes), so memory holds one frame and the fixed meshes, however long the shot.

mod auto;
mod frames;
pub(crate) mod locate;
mod write;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::InputError;
use std::io::Write as _;

use crate::io::obj::{read_obj, ObjData};
use crate::io::usd::{self, StageInfo};
use crate::io::{write_atomic, write_atomic_with};
use crate::math::{Real, Vec2, Vec3};
use crate::render::run_dir::{read_stats, RunFiles};
use locate::Locator;
pub use write::pc2_bytes;
use write::{pc2_header, pc2_points, OutFiles};

/// Where the fixed meshes come from.
pub enum Target {
    /// One OBJ per cloth, in cloth order, whose `vt` are material locations in the run's
    /// texture units.
    Meshes(Vec<PathBuf>),
    /// Made from the run's own meshes (`auto`).
    Auto,
}

#[derive(Debug, thiserror::Error)]
pub enum ResampleError {
    #[error("{0}")]
    Input(InputError),
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// `--auto` could not mesh the run.
    #[error("--auto: {0}")]
    Auto(String),
}

/// For `write_atomic_with`: an I/O error of the file it writes (the caller names it).
impl From<std::io::Error> for ResampleError {
    fn from(source: std::io::Error) -> Self {
        ResampleError::Io { path: PathBuf::new(), source }
    }
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
    /// Per cloth, when the run has several (`vertices` and `faces` above are their sums).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub cloths: Vec<ClothReport>,
    pub frames: Vec<FrameError>,
}

/// One cloth's fixed mesh.
#[derive(Clone, Debug, Serialize)]
pub struct ClothReport {
    pub name: String,
    pub target: String,
    pub vertices: usize,
    pub faces: usize,
}

/// The fixed mesh: node positions of its source, and per corner the node and texture index.
pub struct FixedMesh {
    pub texcoords: Vec<Vec2>,
    /// Per node, the texture coordinate it is tracked at.
    pub node_uv: Vec<Vec2>,
    pub triangles: Vec<[(usize, usize); 3]>,
}

/// One cloth at one frame of the run, as read from its OBJ.
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
    let names: Vec<String> = frames::read_frame(&files, first.frame, first.time)?.into_iter().map(|c| c.0).collect();
    let read = |k: usize| -> Result<Vec<RunFrame>, ResampleError> {
        let f = &stats.frames[k];
        let cloths = frames::read_frame(&files, f.frame, f.time)?;
        if cloths.len() != names.len() || cloths.iter().zip(&names).any(|(c, n)| c.0 != *n) {
            let msg = format!("its cloths ('o' groups) differ from frame {}'s: {names:?}", first.frame);
            return Err(input_error(&files.frame_path(f.frame), msg));
        }
        Ok(cloths.into_iter().map(|c| c.1).collect())
    };
    let fixed = targets(target, &names, stats.frames.len(), &read, run_dir)?;
    std::fs::create_dir_all(out.join(usd::SAMPLES_DIR)).map_err(io(out))?;
    let mut report = ResampleReport {
        run: run_dir.to_path_buf(),
        target: match target {
            Target::Meshes(p) => p.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
            Target::Auto => "auto".into(),
        },
        vertices: fixed.iter().map(|f| f.node_uv.len()).sum(),
        faces: fixed.iter().map(|f| f.triangles.len()).sum(),
        run_mean_faces: stats.frames.iter().map(|f| f.faces as Real).sum::<Real>() / stats.frames.len() as Real,
        run_max_faces: stats.frames.iter().map(|f| f.faces).max().unwrap_or(0),
        max_outside: 0.0,
        cloths: cloth_reports(&names, &fixed, target),
        frames: Vec::new(),
    };
    let out_files = OutFiles::new(&names, &fixed, files.digits());
    let pc2 = out.join("cloth.pc2");
    let mut samples = Vec::with_capacity(stats.frames.len());
    write_atomic_with(&pc2, |f| {
        let points = report.vertices;
        f.write_all(&pc2_header(points, stats.frames.len(), first.frame as f32, 1.0)).map_err(io(&pc2))?;
        for k in 0..stats.frames.len() {
            let cloths = read(k)?;
            let placed = out_files.write_frame(out, &cloths, &mut report)?;
            f.write_all(&pc2_points(&placed)).map_err(io(&pc2))?;
            samples.push((cloths[0].number, out_files.samples_path(out, cloths[0].number)));
        }
        Ok(())
    })
    .map_err(|e| match e {
        ResampleError::Io { path, source } if path.as_os_str().is_empty() => {
            ResampleError::Io { path: pc2.clone(), source }
        }
        e => e,
    })?;
    let fps = match stats.frames.as_slice() {
        [a, b, ..] if b.time > a.time => 1.0 / ((b.time - a.time) / (b.frame - a.frame) as Real),
        _ => 25.0,
    };
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

/// The fixed mesh of each cloth (`names`, in the run's order).
fn targets(
    target: &Target,
    names: &[String],
    count: usize,
    read: &dyn Fn(usize) -> Result<Vec<RunFrame>, ResampleError>,
    run_dir: &Path,
) -> Result<Vec<FixedMesh>, ResampleError> {
    match target {
        Target::Auto => auto::auto_targets(count, read).map_err(|e| match e {
            ResampleError::Auto(msg) => input_error(run_dir, msg),
            e => e,
        }),
        Target::Meshes(paths) if paths.len() != names.len() => Err(ResampleError::Input(InputError {
            file: run_dir.to_path_buf(),
            location: Some("--mesh".into()),
            msg: format!(
                "given {} time(s) for a run of {} cloth(s) ({}): give one --mesh per cloth, in this order, or --auto",
                paths.len(),
                names.len(),
                names.join(", ")
            ),
        })),
        Target::Meshes(paths) => paths.iter().map(|p| mesh_target(p)).collect(),
    }
}

fn cloth_reports(names: &[String], fixed: &[FixedMesh], target: &Target) -> Vec<ClothReport> {
    if names.len() <= 1 {
        return Vec::new();
    }
    let target = |c: usize| match target {
        Target::Meshes(p) => p[c].display().to_string(),
        Target::Auto => "auto".into(),
    };
    let each = names.iter().zip(fixed).enumerate();
    each.map(|(c, (name, f))| ClothReport {
        name: name.clone(),
        target: target(c),
        vertices: f.node_uv.len(),
        faces: f.triangles.len(),
    })
    .collect()
}

/// The fixed mesh's nodes placed on `frame`: positions, velocities (when the frame has them)
/// and how far outside the frame's material domain a node was (texture units).
pub(super) fn place(fixed: &FixedMesh, frame: &RunFrame) -> (Vec<Vec3>, Vec<Vec3>, Real) {
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

pub(super) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ResampleError + '_ {
    move |source| ResampleError::Io { path: path.to_path_buf(), source }
}
