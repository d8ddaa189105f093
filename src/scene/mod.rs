//! Scenes: the file format (`spec`), its validation and assembly into a runnable `Scene`
//! (`load`), fabric presets and material blocks (`material`), measured fabric files (`measured`),
//! `.mot` motion files (`mot`) and ARCSim configurations (`arcsim`).
//!
//! A `Scene` is assembled out of the stages' own types: fabrics (`forces::material`), obstacles
//! and collision parameters (`collision::shape`, `collision::params`), motions (`math::motion`)
//! and the camera. None of those modules imports `scene`.

pub mod arcsim;
pub mod handle;
mod load;
pub mod material;
mod measured;
pub mod mot;
pub mod spec;

pub use arcsim::{load_path, Loaded};
pub use handle::{Circle, FollowObstacle, Handle, HandleKind};
pub use load::{check_file, load_file, load_str, load_value, DEFAULT_CAMERA, DEFAULT_SCENE, DEFAULT_SCENE_NAME};
pub use measured::read_measured;

use std::path::PathBuf;

use crate::camera::Camera;
use crate::collision::params::CollisionParams;
use crate::collision::shape::Obstacle;
use crate::constraints::LraParams;
use crate::error::InputError;
use crate::forces::material::Material;
use crate::forces::wind::Wind;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;
use crate::sizing::{SizingParams, ViewParams};

/// A cloth of the scene: its name and the range of nodes it owns in the combined mesh.
#[derive(Clone, Debug)]
pub struct Cloth {
    pub name: String,
    pub material: usize,
    /// Remeshing of this cloth; `None` keeps its input mesh.
    pub remesh: Option<Remesh>,
    /// Rest dihedral angles are zero (ARCSim) instead of the input mesh's.
    pub flat_rest: bool,
    /// Material metres per unit of the input's texture coordinates (`uv_scale` × the cloth's
    /// `transform.scale`; for a mesh without `vt` or a rectangle, the scale alone): output UVs
    /// are material coordinates divided by it, so they are in the input's units.
    pub uv_unit: Real,
    /// Long range attachments to the handles' nodes (Kim et al. 2012).
    pub lra: Option<LraParams>,
    /// [min, max] principal stretch of every face.
    pub strain_limits: Option<[Real; 2]>,
}

/// Whether a cloth's mesh adapts every few frames or is refined once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RemeshMode {
    Adaptive,
    Uniform,
    /// Adaptive, with the curvature and compression criteria scaled by the camera's view
    /// factors (Koh et al. 2014).
    View,
}

impl RemeshMode {
    /// The modes' names in scene files and on the command line.
    pub const NAMES: [&'static str; 3] = ["uniform", "adaptive", "view"];

    pub fn parse(name: &str) -> Option<RemeshMode> {
        match name {
            "uniform" => Some(RemeshMode::Uniform),
            "adaptive" => Some(RemeshMode::Adaptive),
            "view" => Some(RemeshMode::View),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            RemeshMode::Uniform => "uniform",
            RemeshMode::Adaptive => "adaptive",
            RemeshMode::View => "view",
        }
    }

    /// Remeshed every frame from its sizing field (adaptive, with or without view factors).
    pub fn is_adaptive(self) -> bool {
        matches!(self, RemeshMode::Adaptive | RemeshMode::View)
    }
}

/// A cloth's resolved remeshing parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Remesh {
    pub mode: RemeshMode,
    pub sizing: SizingParams,
    /// Remesh every this many frames.
    pub every: usize,
    /// View factor parameters, used in `RemeshMode::View`.
    pub view: ViewParams,
    /// A split's new node is relaxed off the edge's midpoint as ARCSim does
    /// (`remesh::split_place`; `split_position: "relaxed"`).
    pub relax_splits: bool,
}

/// A validated, runnable scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// The scene file (or a description of the source), for error messages.
    pub file: PathBuf,
    pub frame_time: Real,
    pub steps_per_frame: usize,
    /// Frames written after the first (the first is the state at time 0).
    pub frames: usize,
    /// The number of the first written frame, in file names and USD time codes.
    pub start_frame: usize,
    /// Frames simulated before the first written one: the run starts at time
    /// −`preroll_frames` × `frame_time`, so that written frame k is at time k × `frame_time`.
    pub preroll_frames: usize,
    pub gravity: Vec3,
    pub wind: Option<Wind>,
    pub cloths: Vec<Cloth>,
    pub materials: Vec<Material>,
    /// All cloths in one mesh; `Node::cloth` and `Face::material` say which.
    pub mesh: Mesh,
    pub handles: Vec<Handle>,
    pub obstacles: Vec<Obstacle>,
    pub collision: CollisionParams,
    /// The shot camera, for view-dependent remeshing.
    pub camera: Option<Camera>,
    /// Stages the scene switches off (`disable`).
    pub disabled: Disabled,
    /// Relax the initial state before frame 0 (`initial_relax`; `Simulation::new`).
    pub initial_relax: bool,
}

/// Stages a scene switches off (its `disable` list, ARCSim's names). Remeshing, strain limiting,
/// long range attachments and plasticity are switched off at load, by dropping the cloths'
/// `remesh`, `strain_limits` and `lra` and the materials' plasticity; these are the stages the
/// step itself skips.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Disabled {
    /// No repulsion contacts (and so no friction) in the implicit solve.
    pub proximity: bool,
    /// No implicit solve: the cloth moves only where exact handles, constraints and collisions
    /// move it.
    pub physics: bool,
    /// No continuous collision detection and impact zones.
    pub collision: bool,
    /// No pushing cloth back out of obstacles after a remesh.
    pub separation: bool,
    /// No pop filter after a remesh (`sim::pop`).
    pub pop_filter: bool,
}

impl Disabled {
    /// The names `disable` accepts, in the order of a step (ARCSim's module names, with
    /// `strain_limiting` for its `strainlimiting`).
    pub const NAMES: [&'static str; 9] = [
        "proximity",
        "physics",
        "strain_limiting",
        "lra",
        "collision",
        "remeshing",
        "separation",
        "pop_filter",
        "plasticity",
    ];
}

impl Scene {
    /// Sets the remeshing mode of every cloth that has a remesh block; returns how many.
    pub fn set_remesh_mode(&mut self, mode: RemeshMode) -> usize {
        let mut n = 0;
        for r in self.cloths.iter_mut().filter_map(|c| c.remesh.as_mut()) {
            r.mode = mode;
            n += 1;
        }
        n
    }

    /// Moves every initial cloth node by `amplitude` (m) in a direction fixed by its index and
    /// `seed` (SplitMix64 finaliser of both: deterministic, independent across nodes and
    /// seeds). No node is exempt, handles included: the size is meant to be far below any
    /// tolerance (1 µm for `compare`'s chaos floor and `simulate --jitter-seed`).
    pub fn jitter_positions(&mut self, seed: u64, amplitude: Real) {
        for (i, node) in self.mesh.nodes.iter_mut().enumerate() {
            let h = |k: u64| {
                let mut z = (i as u64)
                    .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    .wrapping_add(seed.wrapping_mul(0xD1B5_4A32_D192_ED03))
                    .wrapping_add(k);
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                ((z ^ (z >> 31)) as Real / u64::MAX as Real) * 2.0 - 1.0
            };
            let d = Vec3::new(h(1), h(2), h(3));
            node.x += d.try_normalize(0.0).unwrap_or_else(Vec3::x) * amplitude;
        }
    }

    /// Refuses a cloth remeshed in view mode when the scene has no camera to give its view
    /// factors (an error naming that cloth's `remesh.mode`).
    pub fn require_camera_for_view(&self) -> Result<(), InputError> {
        if self.camera.is_some() {
            return Ok(());
        }
        match self.cloths.iter().position(|c| c.remesh.as_ref().is_some_and(|r| r.mode == RemeshMode::View)) {
            Some(c) => Err(InputError {
                file: self.file.clone(),
                location: Some(format!("cloths[{c}].remesh.mode")),
                msg: "\"view\" needs a camera: give the scene a \"camera\" file or pass --camera".into(),
            }),
            None => Ok(()),
        }
    }

    /// The number (file names, USD time codes) of the frame `k` frames after the run's start,
    /// preroll included; `None` for a preroll frame, which is not written.
    pub fn frame_number(&self, k: usize) -> Option<usize> {
        k.checked_sub(self.preroll_frames).map(|w| self.start_frame + w)
    }

    /// The time at which the run starts (negative with a preroll).
    pub fn start_time(&self) -> Real {
        -(self.preroll_frames as Real) * self.frame_time
    }

    pub fn time_step(&self) -> Real {
        self.frame_time / self.steps_per_frame as Real
    }

    /// Rest dihedral angle of every edge of `mesh`: its current angle, or zero on cloths that
    /// rest flat.
    pub fn rest_angles(&self, mesh: &Mesh) -> Vec<Real> {
        self.flat_where_resting_flat(mesh, crate::forces::edge_angles(mesh))
    }

    /// Whether the rest shape is carried through remeshing as a rest embedding
    /// (`SimState::rest_x`): when a cloth rests in its input's shape and the input labels
    /// creases. An embedding keeps every input edge as the sharp fold it is (a split's node at the
    /// midpoint), right for a folded model (dart.json's paper, ARCSim's `preserve_creases`, which
    /// also keeps its midpoints linear); a smooth curved input is carried by the faces' shape
    /// operators instead (`remesh::rest_shape`), which spread its curvature over the refined
    /// faces rather than kinking them along the input's edges.
    pub fn rest_embedded(&self) -> bool {
        !self.mesh.creases.is_empty() && !self.cloths.iter().all(|c| c.flat_rest)
    }

    /// `rest_angles` of the mesh with its nodes at the rest embedding `x` (`SimState::rest_x`).
    pub fn rest_angles_at(&self, mesh: &Mesh, x: &[crate::math::Vec3]) -> Vec<Real> {
        self.flat_where_resting_flat(mesh, crate::forces::edge_angles_at(mesh, x))
    }

    fn flat_where_resting_flat(&self, mesh: &Mesh, mut angles: Vec<Real>) -> Vec<Real> {
        for (a, e) in angles.iter_mut().zip(&mesh.edges) {
            if self.cloths.get(mesh.nodes[e.n[0].idx()].cloth as usize).is_some_and(|c| c.flat_rest) {
                *a = 0.0;
            }
        }
        angles
    }
}
