//! The one place a shot is set up from what a user asked for, for every command that runs one
//! (`simulate`, `resume`, `batch`, `compare`): the scene (a viewcloth scene, an ARCSim conf, or
//! the built-in default), the camera laid over it, the remeshing-mode override, and the refusal
//! of view-dependent remeshing without a camera — all before anything is written.

use std::path::{Path, PathBuf};

use crate::camera::Camera;
use crate::error::InputError;
use crate::render::{render_run, Colouring, RenderError, RenderOptions, RunFiles};
use crate::scene::{self, RemeshMode, Scene};
use crate::sim::progress::ProgressMode;

/// What the user asked for.
#[derive(Clone, Debug, Default)]
pub struct ShotRequest {
    /// The scene file or ARCSim conf; `None` for the built-in default shot.
    pub scene: Option<PathBuf>,
    /// Base directory of an ARCSim conf's paths (default: the conf's grand-parent).
    pub base: Option<PathBuf>,
    /// A camera file laid over the scene's own.
    pub camera: Option<PathBuf>,
    /// Remeshing mode of every cloth with a remesh block.
    pub mode: Option<RemeshMode>,
    /// A camera given with no mode sets `View` (simulate, batch); compare, which runs the
    /// modes it is given, leaves the scene's.
    pub camera_implies_view: bool,
}

/// A shot ready to run.
#[derive(Clone, Debug)]
pub struct Shot {
    pub scene: Scene,
    /// Names the default output directory: the scene file's stem, or the built-in shot's name.
    pub stem: String,
    /// The scene file, absolute (`None` for the built-in shot): what a checkpoint records.
    pub scene_file: Option<PathBuf>,
    /// The camera file given, absolute.
    pub camera_file: Option<PathBuf>,
    /// The mode override applied.
    pub mode: Option<RemeshMode>,
    /// The ARCSim conversion's warnings, one line each.
    pub warnings: Vec<String>,
}

/// The part of the request an error is about, for callers that name their own fields
/// (`shots[3].camera`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShotField {
    Scene,
    Camera,
    Mode,
}

impl ShotField {
    pub fn name(self) -> &'static str {
        match self {
            ShotField::Scene => "scene",
            ShotField::Camera => "camera",
            ShotField::Mode => "mode",
        }
    }
}

#[derive(Debug, thiserror::Error)]
#[error("{error}")]
pub struct ShotError {
    pub field: ShotField,
    pub error: InputError,
}

fn absolute(path: &Path, field: ShotField) -> Result<PathBuf, ShotError> {
    std::path::absolute(path).map_err(|e| ShotError {
        field,
        error: InputError { file: path.to_path_buf(), location: None, msg: e.to_string() },
    })
}

/// Loads and checks the shot `req` describes.
pub fn resolve(req: &ShotRequest) -> Result<Shot, ShotError> {
    let (mut scene, stem, warnings, scene_file) = match &req.scene {
        Some(path) => {
            let scene_file = absolute(path, ShotField::Scene)?;
            let loaded = scene::load_path(path, req.base.as_deref())
                .map_err(|error| ShotError { field: ShotField::Scene, error })?;
            let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
            (loaded.scene, stem, loaded.warnings, Some(scene_file))
        }
        None => {
            let name = scene::DEFAULT_SCENE_NAME;
            let file = PathBuf::from(format!("<built-in {name}>"));
            let scene = default_scene(&file).map_err(|error| ShotError { field: ShotField::Scene, error })?;
            (scene, name.to_string(), Vec::new(), None)
        }
    };
    let camera_file = req.camera.as_deref().map(|c| absolute(c, ShotField::Camera)).transpose()?;
    if let Some(file) = &camera_file {
        let camera = Camera::load(file).map_err(|error| ShotError { field: ShotField::Camera, error })?;
        scene.camera = Some(camera);
    }
    let implied = camera_file.as_ref().filter(|_| req.camera_implies_view).map(|_| RemeshMode::View);
    let mode = req.mode.or(implied);
    if let Some(mode) = mode {
        if scene.set_remesh_mode(mode) == 0 {
            let msg = format!("scene '{}' has no cloth with a remesh block to run in {} mode", scene.name, mode.name());
            return Err(ShotError {
                field: ShotField::Mode,
                error: InputError { file: scene.file, location: None, msg },
            });
        }
    }
    scene.require_camera_for_view().map_err(|error| ShotError { field: ShotField::Mode, error })?;
    Ok(Shot { scene, stem, scene_file, camera_file, mode, warnings })
}

/// The built-in shot with its built-in camera: the scene file's `camera` names
/// `cameras/sheet_drape.json` relative to `scenes/`, which need not exist where the binary runs.
fn default_scene(file: &Path) -> Result<Scene, InputError> {
    let name = scene::DEFAULT_SCENE_NAME;
    let mut value: serde_json::Value = serde_json::from_str(scene::DEFAULT_SCENE).map_err(|e| InputError {
        file: file.to_path_buf(),
        location: None,
        msg: e.to_string(),
    })?;
    if let Some(fields) = value.as_object_mut() {
        fields.remove("camera");
    }
    let mut scene = scene::load_value(value, file, Path::new("."), name)?;
    let camera_file = PathBuf::from(format!("<built-in {name} camera>"));
    scene.camera = Some(Camera::from_json(scene::DEFAULT_CAMERA, &camera_file)?);
    Ok(scene)
}

/// Images of the built-in shot's preview: this many frames, evenly spaced, first and last
/// included.
pub const PREVIEW_FRAMES: usize = 4;

/// Renders the preview of a finished run of the built-in shot: `PREVIEW_FRAMES` frames evenly
/// spaced from `first` to `last` (both included), seen from its camera, as `dir/view_NNNN.png`
/// (480 × 270); returns the image paths.
pub fn write_preview(dir: &Path, camera: &Camera, first: usize, last: usize) -> Result<Vec<PathBuf>, RenderError> {
    let mut picks: Vec<usize> =
        (0..PREVIEW_FRAMES).map(|k| first + (last - first) * k / (PREVIEW_FRAMES - 1)).collect();
    picks.dedup();
    let run = RunFiles::scan(dir, first, last)?;
    let mut images = Vec::with_capacity(picks.len());
    for f in picks {
        let opts = RenderOptions {
            width: 480,
            height: 270,
            frames: Some((f, f)),
            every: 1,
            colouring: Colouring::Shade,
            progress: ProgressMode::None,
        };
        render_run(dir, camera, &opts)?;
        images.push(run.image_path(f));
    }
    Ok(images)
}
