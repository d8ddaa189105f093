//! The simulation state: everything a checkpoint holds, from which the rest of a run (the
//! `Workspace`) is rebuilt. Together with the scene it determines every later frame bit for bit.

use crate::math::{Mat2, Real, Vec3};
use crate::mesh::Mesh;
use crate::remesh::rest_shape::face_shapes;
use crate::scene::{HandleKind, Scene};

use super::SimError;

/// What a checkpoint stores (`checkpoint.rs`): the state the next frame reads.
///
/// Everything else is a function of this and the scene: rest data, masses of a restored mesh,
/// the implicit system, obstacle positions (functions of time), node areas. The broad phase's
/// trees are not stored: they only decide the order in which candidates are found, and the
/// broad phase sorts each query's results.
#[derive(Clone, Debug)]
pub struct SimState {
    /// Frames completed.
    pub frame: usize,
    /// Steps taken (retried halves count as steps).
    pub steps: u64,
    pub time: Real,
    /// Cloth nodes pushed out of obstacles at load.
    pub pushed_out: usize,
    /// Whether the separation stage (`separate.rs`) still runs: cloth started deeper inside an
    /// obstacle than the push-out tolerance and is not out yet.
    pub separating: bool,
    /// Material coordinates, node positions, velocities and masses, faces (edges re-derived).
    pub mesh: Mesh,
    /// Rest dihedral angle of each edge of `mesh`.
    pub rest_angles: Vec<Real>,
    /// Per node, where it is in the rest shape (the rest embedding; ARCSim's plastic-space
    /// position `y`), when a cloth rests in its input's shape and the input labels creases
    /// (`Scene::rest_embedded`); empty otherwise. Remeshing carries it with the nodes (a split's node at the
    /// midpoint) and takes the new edges' rest angles from it (`sim::adapt`).
    pub rest_x: Vec<Vec3>,
    /// Per face, the plastic rest shape and damage (`forces::plasticity`); present when a
    /// material has a yield curvature.
    pub plastic: Option<PlasticState>,
    /// The nodes of each of the scene's handles in `mesh` (remeshing renumbers them, and adds
    /// to a circle's ring the nodes it splits between two of its nodes; the scene's own
    /// `Handle::nodes` index its input mesh).
    pub handle_nodes: Vec<Vec<usize>>,
    /// Per handle, once it has switched on: when, and where its nodes were then (node handles;
    /// empty for circles and glue). Their targets are carried from there (`scene::handle`).
    pub handle_on: Vec<Option<HandleOn>>,
    /// Node pairs (i > j) added to the system's sparsity pattern: glue handles, and cloth–cloth
    /// pairs of self contacts (they change the fill-reducing ordering, hence the rounding of
    /// the solve).
    pub extra_pairs: Vec<(usize, usize)>,
    /// Participants of the friction contacts that stuck at the last step, sorted: the next
    /// step's first guess of their mode (`collision::friction`).
    pub stuck: Vec<[usize; 4]>,
    /// Cloth nodes the separation stage held in a pinch at the last step, sorted: queried again
    /// at the next step wherever they are (inside both obstacles once the pinch has closed past
    /// them; `sim::separate`).
    pub pinched: Vec<usize>,
    /// Per node, the largest view factor of its faces at the last view-dependent remesh
    /// (`sizing::view_memory`, smoothed coarsening); empty before it and in other modes.
    pub view_memory: Vec<Real>,
    /// Per face, the share κ of its compressive stress a face keeps under buckling
    /// compensation (`forces::buckling`), set at each view-dependent remesh; empty when off.
    pub buckle: Vec<Real>,
}

/// The plastic state of every face of the mesh (`forces::plasticity`): the rest shape operator
/// S_p the edges' rest angles are solved from, and the accumulated damage d.
#[derive(Clone, Debug, PartialEq)]
pub struct PlasticState {
    pub shapes: Vec<Mat2>,
    pub damage: Vec<Real>,
}

impl SimState {
    /// The state at load: the scene's input mesh at the start time (0, or before it the preroll), rest angles from its shape (zero on
    /// cloths that rest flat).
    pub fn initial(scene: &Scene) -> SimState {
        let mesh = scene.mesh.clone();
        let rest_angles = scene.rest_angles(&mesh);
        let rest_x = match scene.rest_embedded() {
            true => mesh.positions(),
            false => Vec::new(),
        };
        let plastic = scene
            .materials
            .iter()
            .any(|m| m.plasticity.is_some())
            .then(|| PlasticState { shapes: face_shapes(&mesh, &rest_angles), damage: vec![0.0; mesh.faces.len()] });
        SimState {
            frame: 0,
            steps: 0,
            time: scene.start_time(),
            pushed_out: 0,
            separating: false,
            handle_nodes: scene.handles.iter().map(|h| h.nodes.clone()).collect(),
            // Handles on from the run's start anchor the initial positions then.
            handle_on: scene
                .handles
                .iter()
                .map(|h| {
                    (h.start <= h.anchor_time).then(|| HandleOn {
                        time: h.anchor_time,
                        x: if h.kind == HandleKind::Nodes { h.anchors.clone() } else { Vec::new() },
                    })
                })
                .collect(),
            rest_angles,
            rest_x,
            extra_pairs: glue_pairs(scene, &scene.handles.iter().map(|h| h.nodes.clone()).collect::<Vec<_>>()),
            plastic,
            mesh,
            stuck: Vec::new(),
            pinched: Vec::new(),
            view_memory: Vec::new(),
            buckle: Vec::new(),
        }
    }

    /// Checks that a state read from a checkpoint fits `scene` and is a valid mesh (edges are
    /// re-derived here).
    pub fn fit(mut self, scene: &Scene) -> Result<SimState, SimError> {
        let bad = |msg: String| SimError::Mesh(format!("checkpoint does not fit the scene: {msg}"));
        if self.handle_nodes.len() != scene.handles.len() {
            return Err(bad(format!("{} handles, the scene has {}", self.handle_nodes.len(), scene.handles.len())));
        }
        let n = self.mesh.nodes.len();
        for (h, nodes) in scene.handles.iter().zip(&self.handle_nodes) {
            // A circle's ring grows as the remesher splits it.
            let count_ok = matches!(h.kind, HandleKind::Circle(_)) || nodes.len() == h.nodes.len();
            if !count_ok || nodes.iter().any(|&k| k >= n) {
                return Err(bad("handle nodes".into()));
            }
        }
        if self.handle_on.len() != scene.handles.len() {
            return Err(bad(format!("{} handle switch-ons, {} handles", self.handle_on.len(), scene.handles.len())));
        }
        for (h, on) in scene.handles.iter().zip(&self.handle_on) {
            let expected = if h.kind == HandleKind::Nodes { h.nodes.len() } else { 0 };
            if on.as_ref().is_some_and(|on| on.x.len() != expected) {
                return Err(bad("handle anchors".into()));
            }
        }
        if self.mesh.nodes.iter().any(|n| n.cloth as usize >= scene.cloths.len())
            || self.mesh.faces.iter().any(|f| f.material as usize >= scene.materials.len())
        {
            return Err(bad("cloth or material index out of range".into()));
        }
        self.mesh.rebuild_topology().map_err(|e| bad(e.to_string()))?;
        self.mesh.validate().map_err(|e| bad(e.to_string()))?;
        if self.rest_angles.len() != self.mesh.edges.len() {
            return Err(bad(format!("{} rest angles for {} edges", self.rest_angles.len(), self.mesh.edges.len())));
        }
        if self.rest_x.len() != if scene.rest_embedded() { n } else { 0 } {
            return Err(bad(format!("{} rest positions for {n} nodes", self.rest_x.len())));
        }
        let plastic = scene.materials.iter().any(|m| m.plasticity.is_some());
        match &self.plastic {
            None if plastic => return Err(bad("no plastic state for a plastic material".into())),
            Some(_) if !plastic => return Err(bad("plastic state for elastic materials".into())),
            Some(p) if p.shapes.len() != self.mesh.faces.len() || p.damage.len() != self.mesh.faces.len() => {
                return Err(bad(format!("plastic state of {} faces for {}", p.shapes.len(), self.mesh.faces.len())));
            }
            _ => {}
        }
        if self.extra_pairs.iter().any(|&(i, j)| i >= n || j >= i) {
            return Err(bad("contact pattern pair out of range".into()));
        }
        // Only looked up (a first guess), but looked up by binary search.
        if !self.stuck.is_sorted() {
            return Err(bad("friction contacts not sorted".into()));
        }
        if !self.pinched.is_sorted() || self.pinched.last().is_some_and(|&i| i >= n) {
            return Err(bad("pinched nodes not sorted or out of range".into()));
        }
        if !self.view_memory.is_empty() && self.view_memory.len() != n {
            return Err(bad(format!("view memory of {} nodes for {n}", self.view_memory.len())));
        }
        if !self.buckle.is_empty() && self.buckle.len() != self.mesh.faces.len() {
            return Err(bad(format!(
                "buckling compensation of {} faces for {}",
                self.buckle.len(),
                self.mesh.faces.len()
            )));
        }
        if self.buckle.iter().any(|k| !(0.0..=1.0).contains(k)) {
            return Err(bad("buckling compensation outside [0, 1]".into()));
        }
        if self.view_memory.iter().any(|m| !(0.0..=1.0).contains(m)) {
            return Err(bad("view memory outside [0, 1]".into()));
        }
        Ok(self)
    }
}

/// When a handle switched on and where its nodes were then.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleOn {
    pub time: Real,
    /// Per node of a node handle, its position at `time`.
    pub x: Vec<Vec3>,
}

/// The node pairs (larger first, sorted) of the scene's glue handles, `handle_nodes` being
/// their nodes in the current mesh: their couplings must be in the system's pattern.
pub fn glue_pairs(scene: &Scene, handle_nodes: &[Vec<usize>]) -> Vec<(usize, usize)> {
    let mut pairs: Vec<(usize, usize)> = scene
        .handles
        .iter()
        .zip(handle_nodes)
        .filter(|(h, _)| h.kind == HandleKind::Glue)
        .map(|(_, n)| (n[0].max(n[1]), n[0].min(n[1])))
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}
