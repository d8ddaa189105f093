//! The simulation: state, the time step as a list of named, timed stages, and frame stats.

mod run;
pub mod timers;

pub use run::{run, RunOptions};

use crate::forces::membrane::{deformation_gradient, max_principal_strain};
use crate::forces::{edge_angles, RestState};
use crate::io::stats::FrameStats;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::solver::pattern::BlockPattern;
use crate::solver::{ImplicitSystem, SolveError, StepInput};
use timers::StageTimers;

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("step {step} (t = {time:.6} s): {source}")]
    Solve {
        step: u64,
        time: Real,
        source: SolveError,
    },
    #[error("step {step} (t = {time:.6} s): the state became non-finite (NaN or infinity)")]
    NonFinite { step: u64, time: Real },
    #[error("invalid mesh: {0}")]
    Mesh(String),
}

pub struct Simulation {
    pub scene: Scene,
    pub mesh: Mesh,
    /// Rest dihedral angle of each edge (from the input shape).
    rest_angles: Vec<Real>,
    rest: RestState,
    system: ImplicitSystem,
    pub time: Real,
    pub steps: u64,
    pub timers: StageTimers,
}

impl Simulation {
    pub fn new(mut scene: Scene) -> Result<Self, SimError> {
        let mesh = std::mem::take(&mut scene.mesh);
        let rest_angles = edge_angles(&mesh);
        let rest = RestState::new(&mesh, |e| rest_angles[e])
            .map_err(|f| SimError::Mesh(format!("face {f} is degenerate in material space")))?;
        let system =
            ImplicitSystem::new(BlockPattern::new(&mesh, &rest.hinges)).map_err(|source| {
                SimError::Solve {
                    step: 0,
                    time: 0.0,
                    source,
                }
            })?;
        Ok(Simulation {
            scene,
            mesh,
            rest_angles,
            rest,
            system,
            time: 0.0,
            steps: 0,
            timers: StageTimers::default(),
        })
    }

    pub fn rest_angles(&self) -> &[Real] {
        &self.rest_angles
    }

    /// Target velocity of every node held by an active handle at the end of a step to `t1`.
    fn pinned_velocities(&self, t1: Real, h: Real) -> Vec<Option<Vec3>> {
        let mut pinned = vec![None; self.mesh.nodes.len()];
        for handle in self.scene.handles.iter().filter(|hd| hd.active(self.time)) {
            for (k, &n) in handle.nodes.iter().enumerate() {
                pinned[n] = Some((handle.target(k, t1) - self.mesh.nodes[n].x) / h);
            }
        }
        pinned
    }

    /// One implicit step of size `h`.
    pub fn step(&mut self, h: Real) -> Result<(), SimError> {
        let t1 = self.time + h;
        let clock = std::time::Instant::now();
        let pinned = self.pinned_velocities(t1, h);
        self.timers.add("handles", clock.elapsed().as_secs_f64());
        let input = StepInput {
            mesh: &self.mesh,
            rest: &self.rest,
            materials: &self.scene.materials,
            h,
            gravity: self.scene.gravity,
            wind: self.scene.wind.as_ref(),
            pinned: &pinned,
        };
        let out = self
            .system
            .solve_step(&input)
            .map_err(|source| SimError::Solve {
                step: self.steps,
                time: self.time,
                source,
            })?;
        self.timers.add("assembly", out.assemble_s);
        self.timers.add("factorisation", out.factor_s);
        self.timers.add("solve", out.solve_s);
        let (time, steps) = (self.time, self.steps);
        self.timers.time("integration", || {
            for (i, node) in self.mesh.nodes.iter_mut().enumerate() {
                node.v += out.dv[i];
                node.x += h * node.v;
                if let Some(v) = pinned[i] {
                    node.v = v;
                }
            }
            // Handles land exactly on their targets (no rounding drift).
            for handle in self.scene.handles.iter().filter(|hd| hd.active(time)) {
                for (k, &n) in handle.nodes.iter().enumerate() {
                    self.mesh.nodes[n].x = handle.target(k, t1);
                }
            }
            if self
                .mesh
                .nodes
                .iter()
                .all(|n| n.x.iter().chain(n.v.iter()).all(|c| c.is_finite()))
            {
                Ok(())
            } else {
                Err(SimError::NonFinite { step: steps, time })
            }
        })?;
        self.time = t1;
        self.steps += 1;
        Ok(())
    }

    /// Advances one frame (the scene's steps per frame).
    pub fn advance_frame(&mut self) -> Result<(), SimError> {
        let h = self.scene.time_step();
        for _ in 0..self.scene.steps_per_frame {
            self.step(h)?;
        }
        Ok(())
    }

    /// Elastic energy (membrane + bending) of the current state.
    pub fn elastic_energy(&self) -> Real {
        use crate::forces::bending::bending;
        use crate::forces::membrane::membrane;
        use crate::forces::Projection;
        let m = &self.mesh;
        let mut e = 0.0;
        for f in 0..m.faces.len() {
            let x = m.face_nodes(f).map(|n| m.nodes[n].x);
            let mat = &self.scene.materials[m.faces[f].material as usize];
            e += membrane(&x, &self.rest.membrane[f], &mat.membrane, Projection::Psd).0;
        }
        for hg in &self.rest.hinges {
            let x = hg.nodes.map(|n| m.nodes[n].x);
            e += bending(
                &x,
                &hg.rest,
                self.scene.materials[hg.material].bending,
                Projection::Psd,
            )
            .0;
        }
        e
    }

    /// Per-frame measurements (without timings).
    pub fn measure(&self, frame: usize) -> FrameStats {
        let m = &self.mesh;
        let kinetic: Real = m
            .nodes
            .iter()
            .map(|n| 0.5 * n.mass * n.v.norm_squared())
            .sum();
        let potential: Real = m
            .nodes
            .iter()
            .map(|n| -n.mass * self.scene.gravity.dot(&n.x))
            .sum();
        let (mut max_strain, mut sum, mut area) = (Real::NEG_INFINITY, 0.0, 0.0);
        for f in 0..m.faces.len() {
            let x = m.face_nodes(f).map(|n| m.nodes[n].x);
            let r = &self.rest.membrane[f];
            let s = max_principal_strain(&deformation_gradient(&x, r));
            max_strain = max_strain.max(s);
            sum += s * r.area;
            area += r.area;
        }
        FrameStats {
            frame,
            time: self.time,
            nodes: m.nodes.len(),
            faces: m.faces.len(),
            kinetic_energy: kinetic,
            total_energy: kinetic + potential + self.elastic_energy(),
            max_strain,
            mean_strain: sum / area,
            ..Default::default()
        }
    }
}
