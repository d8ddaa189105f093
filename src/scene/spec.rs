//! The scene file format (JSON, version 1), exactly as written by users. Unknown fields are
//! rejected. Range checks and file references are checked in `scene::load`; every field is
//! documented in `docs/scene-format.md`.

use serde::Deserialize;

fn one() -> f64 {
    1.0
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub version: u32,
    #[serde(default)]
    pub name: Option<String>,
    /// Seconds per output frame (or give `fps`).
    #[serde(default)]
    pub frame_time: Option<f64>,
    #[serde(default)]
    pub fps: Option<f64>,
    /// Integration steps per frame (or give `time_step`).
    #[serde(default)]
    pub steps_per_frame: Option<i64>,
    #[serde(default)]
    pub time_step: Option<f64>,
    /// Number of frames to simulate after frame 0 (or give `end_time`).
    #[serde(default)]
    pub frames: Option<i64>,
    #[serde(default)]
    pub end_time: Option<f64>,
    /// The number of the first written frame (file names, USD time codes), e.g. 1001.
    #[serde(default)]
    pub start_frame: Option<i64>,
    /// Seconds simulated before the first written frame (a whole number of frames).
    #[serde(default)]
    pub preroll: Option<f64>,
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    #[serde(default)]
    pub wind: Option<WindSpec>,
    /// May be empty when `instances` bring cloths.
    #[serde(default)]
    pub cloths: Vec<ClothSpec>,
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// Copies of another scene file's cloths and obstacles, each placed by a transform and
    /// shifted in time (`scene::load::instance`).
    #[serde(default)]
    pub instances: Vec<InstanceSpec>,
    /// Collision handling; defaults apply when absent.
    #[serde(default)]
    pub collision: Option<CollisionSpec>,
    /// Camera file (relative to the scene) for view-dependent remeshing (`mode: "view"`).
    #[serde(default)]
    pub camera: Option<String>,
    /// Stages switched off: `proximity`, `physics`, `strain_limiting`, `lra`, `collision`,
    /// `remeshing`, `separation`, `pop_filter`, `plasticity` (ARCSim's `disable`).
    #[serde(default)]
    pub disable: Vec<String>,
    /// Relax the initial state towards its elastic equilibrium before frame 0, remeshing between
    /// two relaxations, as ARCSim does before every run (`sim::pop`, `equilibrate`); default false.
    #[serde(default)]
    pub initial_relax: Option<bool>,
}

/// One instance: the cloths and obstacles of the scene file `scene` (nothing else of it), named
/// `<their name>_<name>`, placed by `transform` after their own transforms and motions, and
/// `time_offset` seconds ahead in their motions: the instance at time t is the original at
/// t + time_offset.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct InstanceSpec {
    /// Suffix of the instance's cloth and obstacle names (default `i<index>`).
    #[serde(default)]
    pub name: Option<String>,
    /// A scene file (this format, not an ARCSim conf), relative to this scene.
    pub scene: String,
    #[serde(default)]
    pub transform: TransformSpec,
    /// Seconds (any sign): positive runs the motions ahead, negative holds their start longer.
    #[serde(default)]
    pub time_offset: f64,
}

#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct CollisionSpec {
    /// Repulsion thickness (m): contacts closer than this are pushed apart.
    #[serde(default)]
    pub thickness: Option<f64>,
    /// Repulsion stiffness per unit area (N/m³); a contact's stiffness is this × its area.
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// `"quadratic"` (default: ½ k a d², a the largest cloth node area of the pair) or
    /// `"arcsim"` (ARCSim 0.2.1's k a d³/(6 τ), a the smaller of the two elements' areas).
    #[serde(default)]
    pub penalty: Option<String>,
    /// Coulomb friction coefficient cloth–obstacle.
    #[serde(default)]
    pub friction: Option<f64>,
    /// Coulomb friction coefficient cloth–cloth.
    #[serde(default)]
    pub self_friction: Option<f64>,
    /// Cloth–cloth collisions on/off (default on).
    #[serde(default)]
    pub self_collision: Option<bool>,
    /// Cap on impact-zone iterations per step (default 100).
    #[serde(default)]
    pub max_iterations: Option<i64>,
    /// Cloth nodes up to this deep inside an obstacle at load are pushed out (m, default 3 ×
    /// thickness); deeper nodes are separated over the first steps (`"resolve"`, default) or
    /// are an error (`"refuse"`).
    #[serde(default)]
    pub push_out_tolerance: Option<f64>,
    /// `"resolve"` or `"refuse"`: cloth deeper than `push_out_tolerance` inside an obstacle.
    #[serde(default)]
    pub initial_intersections: Option<String>,
}

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct WindSpec {
    pub velocity: [f64; 3],
    /// Air density (kg/m³).
    #[serde(default = "default_air_density")]
    pub density: f64,
    /// Tangential drag coefficient (kg/(m²·s)).
    #[serde(default)]
    pub drag: f64,
    /// Whether the force's velocity Jacobian is in the implicit solve (default true).
    #[serde(default)]
    pub implicit: Option<bool>,
}

fn default_air_density() -> f64 {
    1.225
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct ClothSpec {
    #[serde(default)]
    pub name: Option<String>,
    /// OBJ file, relative to the scene file.
    #[serde(default)]
    pub mesh: Option<String>,
    #[serde(default)]
    pub rectangle: Option<RectangleSpec>,
    /// Multiplies OBJ `vt` to get material coordinates in metres (before `transform.scale`).
    #[serde(default = "one")]
    pub uv_scale: f64,
    #[serde(default)]
    pub transform: TransformSpec,
    /// Initial velocity (m/s).
    #[serde(default)]
    pub velocity: [f64; 3],
    pub material: MaterialSpec,
    #[serde(default)]
    pub handles: Vec<HandleSpec>,
    /// Adaptive remeshing; absent = the input mesh is kept.
    #[serde(default)]
    pub remesh: Option<RemeshSpec>,
    /// Rest dihedral angles: `input` (default, the input mesh's shape) or `flat` (ARCSim).
    #[serde(default)]
    pub rest_angles: Option<String>,
    /// Long range attachments (Kim et al. 2012); absent = none.
    #[serde(default)]
    pub lra: Option<LraSpec>,
    /// [min, max] principal stretch of every face (strain limiting); absent = none.
    #[serde(default)]
    pub strain_limits: Option<[f64; 2]>,
}

/// Long range attachments of one cloth to its handles' nodes.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct LraSpec {
    /// Attachment islands each node is tied to (default 4).
    #[serde(default)]
    pub max_attachments: Option<i64>,
    /// Radius inflation (0 = inextensible, 0.1 = 10%; default 0).
    #[serde(default)]
    pub stretch: Option<f64>,
    /// `geodesic` (default) or `euclidean`.
    #[serde(default)]
    pub distance: Option<String>,
}

/// Remeshing of one cloth (Narain et al. 2012). A missing criterion is off.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RemeshSpec {
    /// `adaptive` (default) or `uniform` (refined once to `size[0]`, never remeshed).
    #[serde(default)]
    pub mode: Option<String>,
    /// Radians a face may bend through.
    #[serde(default)]
    pub refine_angle: Option<f64>,
    /// Compression a face may buckle through.
    #[serde(default)]
    pub refine_compression: Option<f64>,
    /// Velocity difference (m/s) allowed across a face.
    #[serde(default)]
    pub refine_velocity: Option<f64>,
    /// Refine near obstacles (default off).
    #[serde(default)]
    pub refine_obstacle: Option<bool>,
    /// [min, max] edge length (m).
    pub size: [f64; 2],
    /// Smallest aspect ratio, in (0, 1] (default 0.2).
    #[serde(default)]
    pub aspect_min: Option<f64>,
    /// How criteria combine: `max` (default, tensor max) or `sum`.
    #[serde(default)]
    pub combine: Option<String>,
    /// Where a split puts its new node: `midpoint` (default) or `relaxed` (ARCSim's).
    #[serde(default)]
    pub split_position: Option<String>,
    /// Remesh every N frames (default 1).
    #[serde(default)]
    pub every: Option<i64>,
    /// View-dependent sizing parameters (mode `view`; Koh et al. 2014), defaults when absent.
    #[serde(default)]
    pub view: Option<ViewSpec>,
}

/// View factor parameters (Koh et al. 2014, eqs. 1–10); each defaults to the paper's value.
#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct ViewSpec {
    #[serde(default)]
    pub k_cos: Option<f64>,
    #[serde(default)]
    pub mu_back: Option<f64>,
    #[serde(default)]
    pub mu_out: Option<f64>,
    #[serde(default)]
    pub margin: Option<f64>,
    #[serde(default)]
    pub k_dist: Option<f64>,
    #[serde(default)]
    pub min_edge_pixels: Option<f64>,
    #[serde(default)]
    pub image_height: Option<i64>,
    #[serde(default)]
    pub window: Option<f64>,
    #[serde(default)]
    pub hold: Option<f64>,
    #[serde(default)]
    pub two_sided: Option<bool>,
    #[serde(default)]
    pub coarsen_time: Option<f64>,
    #[serde(default)]
    pub buckling_compensation: Option<bool>,
    #[serde(default)]
    pub occlusion_pixels: Option<i64>,
    #[serde(default)]
    pub max_jump_pixels: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RectangleSpec {
    pub width: f64,
    pub height: f64,
    /// Quads along width and height.
    pub resolution: [i64; 2],
}

/// Scale, then rotate (`[degrees, axis x, y, z]`), then translate (ARCSim's order).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    #[serde(default)]
    pub translate: [f64; 3],
    #[serde(default)]
    pub rotate: Option<[f64; 4]>,
    #[serde(default = "one")]
    pub scale: f64,
}

impl Default for TransformSpec {
    fn default() -> Self {
        TransformSpec { translate: [0.0; 3], rotate: None, scale: 1.0 }
    }
}

#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// A named fabric (`cotton`, `denim`, `silk`, `jersey`); other fields override it.
    #[serde(default)]
    pub preset: Option<String>,
    /// kg/m².
    #[serde(default)]
    pub density: Option<f64>,
    /// Isotropic membrane: Young's modulus (Pa), Poisson ratio, thickness (m).
    #[serde(default)]
    pub youngs_modulus: Option<f64>,
    #[serde(default)]
    pub poisson_ratio: Option<f64>,
    #[serde(default)]
    pub thickness: Option<f64>,
    /// Orthotropic membrane (N/m): warp, weft, shear and the warp–weft coupling.
    #[serde(default)]
    pub warp: Option<f64>,
    #[serde(default)]
    pub weft: Option<f64>,
    #[serde(default)]
    pub shear: Option<f64>,
    #[serde(default)]
    pub coupling: Option<f64>,
    /// Bending stiffness (N·m).
    #[serde(default)]
    pub bending: Option<f64>,
    /// Stiffness-proportional (Rayleigh) damping coefficient (s).
    #[serde(default)]
    pub damping: Option<f64>,
    /// Multiplies the membrane stiffness.
    #[serde(default)]
    pub stretching_mult: Option<f64>,
    /// Multiplies the bending stiffness.
    #[serde(default)]
    pub bending_mult: Option<f64>,
    /// A measured fabric file (Wang et al. 2011 / ARCSim `materials/*.json`), relative to the
    /// scene file; exclusive with the preset and stiffness fields.
    #[serde(default)]
    pub arcsim: Option<String>,
    /// With `arcsim`: multiplies the file's density.
    #[serde(default)]
    pub density_mult: Option<f64>,
    /// With `arcsim`: multiplies density, stretching and bending together (ARCSim).
    #[serde(default)]
    pub thicken: Option<f64>,
    /// With `arcsim`: `"absolute"` (default: folds towards either side alike) or `"signed"`
    /// (ARCSim 0.2.1's lookup of the bending table by signed curvature).
    #[serde(default)]
    pub bending_curvature: Option<String>,
    /// With `arcsim`: `"stress"` (default) or `"arcsim"`, the membrane Jacobian's geometric term
    /// (`forces::data_driven::Geometric`).
    #[serde(default)]
    pub geometric_stiffness: Option<String>,
    /// Bending plasticity: the yield curvature (1/m); absent = elastic.
    #[serde(default)]
    pub yield_curv: Option<f64>,
    /// With `yield_curv`: stiffnesses are divided by 1 + weakening·damage.
    #[serde(default)]
    pub weakening: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct HandleSpec {
    /// Node indices (OBJ vertex order, 0-based; for a rectangle, row-major from the
    /// lower-left corner).
    #[serde(default)]
    pub nodes: Option<Vec<i64>>,
    /// Every node with a material coordinate inside this box.
    #[serde(default)]
    pub region: Option<RegionSpec>,
    /// Keyframed rigid motion applied to the handle's initial positions.
    #[serde(default)]
    pub motion: Option<Vec<KeyframeSpec>>,
    /// Motion of one body of a `.mot` file; exclusive with `motion` and `obstacle`.
    #[serde(default)]
    pub mot: Option<MotSpec>,
    /// Name of a (rigid) obstacle the handle rides on; exclusive with `motion`.
    #[serde(default)]
    pub obstacle: Option<String>,
    /// The handle holds from `start_time` until `end_time` (seconds), then releases.
    #[serde(default)]
    pub start_time: Option<f64>,
    #[serde(default)]
    pub end_time: Option<f64>,
    /// Seconds over which a soft handle's strength fades out after `end_time`.
    #[serde(default)]
    pub fade_time: Option<f64>,
    /// Spring stiffness (N/m; a circle's per metre of ring): a soft handle. Absent = exact.
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Holds the nodes (`nodes` or `region`) on a circle by their material coordinates.
    #[serde(default)]
    pub circle: Option<CircleSpec>,
    /// Two node indices tied together by a spring (needs `stiffness`); instead of `nodes`.
    #[serde(default)]
    pub glue: Option<Vec<i64>>,
}

/// A circle handle's circle (ARCSim's `"type": "circle"`): a node at material coordinate u goes
/// to center + (axis0 cos θ + axis1 sin θ) · circumference / 2π, θ = 2π (u · u_dir) /
/// circumference.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct CircleSpec {
    pub circumference: f64,
    /// Material direction along the ring.
    pub u: [f64; 2],
    pub center: [f64; 3],
    pub axis0: [f64; 3],
    pub axis1: [f64; 3],
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// Material-space box corners (metres).
    pub min: [f64; 2],
    pub max: [f64; 2],
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct KeyframeSpec {
    pub time: f64,
    #[serde(default)]
    pub translate: [f64; 3],
    #[serde(default)]
    pub rotate: Option<[f64; 4]>,
    #[serde(default = "one")]
    pub scale: f64,
    /// Explicit tangent at this key (ARCSim's keyframe `velocity`); absent = central difference.
    #[serde(default)]
    pub velocity: Option<KeyVelocitySpec>,
}

/// Rates of change at a keyframe: translation (m/s) and scale (1/s); the rotation's rate is zero.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct KeyVelocitySpec {
    #[serde(default)]
    pub translate: [f64; 3],
    #[serde(default)]
    pub scale: f64,
}

/// One body of a `.mot` motion file (ARCSim's character motions): its per-frame rigid transforms,
/// frame k at time k / fps − start_time, each followed by `transform`, splined like keyframes.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct MotSpec {
    /// The `.mot` file, relative to the scene file.
    pub file: String,
    /// Body index (0-based).
    pub body: i64,
    pub fps: f64,
    #[serde(default)]
    pub start_time: f64,
    #[serde(default)]
    pub transform: TransformSpec,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    #[serde(default)]
    pub name: Option<String>,
    /// Exactly one shape: an OBJ mesh, or an analytic sphere, plane, box or capsule.
    #[serde(default)]
    pub mesh: Option<String>,
    #[serde(default)]
    pub sphere: Option<SphereSpec>,
    #[serde(default)]
    pub plane: Option<PlaneSpec>,
    #[serde(rename = "box", default)]
    pub cuboid: Option<BoxSpec>,
    #[serde(default)]
    pub capsule: Option<CapsuleSpec>,
    /// A deforming obstacle: one OBJ per frame, all of one topology.
    #[serde(default)]
    pub sequence: Option<SequenceSpec>,
    #[serde(default)]
    pub transform: TransformSpec,
    #[serde(default)]
    pub motion: Option<Vec<KeyframeSpec>>,
    /// Motion from a `.mot` file instead of keyframes.
    #[serde(default)]
    pub mot: Option<MotSpec>,
    /// The obstacle is present from `start_time` to `end_time` (seconds; default always).
    #[serde(default)]
    pub start_time: Option<f64>,
    #[serde(default)]
    pub end_time: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    pub radius: f64,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct PlaneSpec {
    /// Extent of the (square) plane patch in its local xy plane, normal +z.
    pub size: [f64; 2],
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub size: [f64; 3],
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct CapsuleSpec {
    pub radius: f64,
    /// Distance between the two hemisphere centres, along local z.
    pub length: f64,
}

/// A per-frame OBJ sequence: files `pattern` formatted with `first`, `first + 1`, …,
/// `first + count − 1` (printf style `%d` or zero-padded `%04d`, Houdini's `$F` / `$F4`, or a
/// run of `#`, one per digit: `####`), relative to the scene file.
/// File k is the obstacle's local shape at time `start_time + k / fps`; positions are linearly
/// interpolated between files and held before the first and after the last. Every file must have
/// the vertex count and faces of the first.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct SequenceSpec {
    pub pattern: String,
    #[serde(default)]
    pub first: i64,
    pub count: i64,
    pub fps: f64,
    #[serde(default)]
    pub start_time: f64,
}
