//! Tracked training runs (§4): a coarse and a fine uniform run of the same shot stepped in
//! lockstep, the fine one held to the coarse one in its T lowest harmonics,
//!   T p_f = T B p_c   (eq. 6),
//! with T = Φ_Tᵀ V the mass-weighted harmonic test functions (`Harmonics`, Φ_Tᵀ V Φ_T = I) and B
//! the barycentric embedding of the fine nodes in the coarse mesh. Only the low frequencies are
//! constrained; the rest of the fine motion is left to physics (§4, Fig. 6 right).
//!
//! The constraint is enforced as the position-based simulators the paper uses do (§4: "straight-
//! forward with a position based simulator"): after every fine step the positions are projected
//! onto eq. 6's affine set along the mass-orthogonal direction, p_f ← p_f + Φ_T Φ_Tᵀ V (B p_c − p_f)
//! (the smallest mass-weighted change that satisfies it), and the same change over the step is
//! added to the velocities, so the next step does not undo it.
//!
//! One cloth per shot (B embeds through material space, where several cloths would overlap).
//! The projection is not collision-checked: near an obstacle it can move a node inside it, and
//! cloth through cloth (the skirt of `bench/upsample_garment.sh`: crossings in 13 of 94 frames of
//! the walk; each run's stats.json counts them).

use std::path::Path;
use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DVector};

use super::run::{RunError, MAX_DENSE_NODES};
use super::{embedding, Embedding, Harmonics, Laplacian, Surface, UpsampleError};
use crate::io::obj::{frame_obj, parse_obj, ClothOut};
use crate::io::write_atomic;
use crate::math::{Real, Vec3};
use crate::scene::Scene;
use crate::sim::output::StatsLog;
use crate::sim::{SimError, Simulation};

/// Eq. 6 for one pair of meshes: B and the T lowest mass-orthonormal harmonics of the fine mesh.
pub struct Tracker {
    b: Embedding,
    /// Φ_T, N × T.
    modes: DMatrix<Real>,
    /// V, the normalised lumped mass of the fine mesh.
    mass: DVector<Real>,
}

impl Tracker {
    pub fn new(coarse: &Surface, fine: &Surface, t: usize) -> Result<Tracker, UpsampleError> {
        let h = Harmonics::new(&Laplacian::new(fine)?, t)?;
        Ok(Tracker { b: embedding(coarse, fine), modes: h.modes, mass: h.mass })
    }

    /// T (p_f − B p_c) = Φ_Tᵀ V (p_f − B p_c), T × 3 (zero when eq. 6 holds).
    pub fn residual(&self, pc: &[Vec3], pf: &[Vec3]) -> DMatrix<Real> {
        let target = self.b.apply(pc);
        let d = DMatrix::from_fn(pf.len(), 3, |i, k| self.mass[i] * (pf[i][k] - target[i][k]));
        self.modes.transpose() * d
    }

    /// The projection's change of the fine positions, Φ_T Φ_Tᵀ V (B p_c − p_f).
    pub fn correction(&self, pc: &[Vec3], pf: &[Vec3]) -> Vec<Vec3> {
        let c = -(&self.modes * self.residual(pc, pf));
        (0..pf.len()).map(|i| Vec3::new(c[(i, 0)], c[(i, 1)], c[(i, 2)])).collect()
    }
}

/// What a tracked run did.
#[derive(Debug)]
pub struct TraceReport {
    pub frames: usize,
    pub steps: usize,
    pub coarse_nodes: usize,
    pub fine_nodes: usize,
    /// Largest |T p_f − T B p_c| entry after each step's projection (m).
    pub residual_after: Vec<Real>,
    /// Largest entry before each projection: how far physics pulled the fine run away (m).
    pub residual_before: Vec<Real>,
}

/// Runs `coarse` and `fine` (uniform, same timing) in lockstep, the fine run tracked with `t`
/// harmonic test functions, writing `out/coarse/` and `out/fine/` (frame_NNNN.obj and
/// `simulate`'s stats.json, mode `uniform` and `tracked`; the fine run's frames also time the
/// projection, as stage `tracking`).
pub fn trace(coarse: Scene, fine: Scene, t: usize, out: &Path) -> Result<TraceReport, RunError> {
    check_pair(&coarse, &fine)?;
    let (cloths_c, cloths_f) = (ClothOut::of(&coarse), ClothOut::of(&fine));
    let (file_c, file_f) = (coarse.file.display().to_string(), fine.file.display().to_string());
    let bad = |file: &str| {
        let file = file.to_owned();
        move |e: SimError| RunError::Input(format!("{file}: {e}"))
    };
    // A step that fails is not bad input: exit 1, as a failed simulation.
    let failed = |file: &str| {
        let file = file.to_owned();
        move |e: SimError| RunError::Output(format!("{file}: tracked run failed: {e}"))
    };
    let mut sc = Simulation::new(coarse).map_err(bad(&file_c))?;
    let mut sf = Simulation::new(fine).map_err(bad(&file_f))?;
    let surface = |s: &Simulation, cloths: &[ClothOut]| {
        let obj = parse_obj(&frame_obj(s.mesh(), cloths, false)).map_err(|e| e.msg)?;
        Surface::from_obj(&obj).map_err(|e| e.to_string())
    };
    let named = |s: &Simulation, e: String| RunError::Input(format!("{}: {e}", s.scene.file.display()));
    let cs = surface(&sc, &cloths_c).map_err(|e| named(&sc, e))?;
    let fs = surface(&sf, &cloths_f).map_err(|e| named(&sf, e))?;
    if fs.nodes > MAX_DENSE_NODES {
        let msg = format!("{} fine nodes; the dense eigensolve is limited to {MAX_DENSE_NODES}", fs.nodes);
        return Err(named(&sf, msg));
    }
    let tracker = Tracker::new(&cs, &fs, t).map_err(|e| named(&sf, e.to_string()))?;
    let (dir_c, dir_f) = (out.join("coarse"), out.join("fine"));
    for d in [&dir_c, &dir_f] {
        std::fs::create_dir_all(d).map_err(|e| RunError::Output(format!("{}: {e}", d.display())))?;
    }
    let (preroll, frames) = (sf.scene.preroll_frames, sf.scene.frames);
    let mut report = TraceReport {
        frames,
        steps: 0,
        coarse_nodes: cs.nodes,
        fine_nodes: fs.nodes,
        residual_after: Vec::new(),
        residual_before: Vec::new(),
    };
    let (mut log_c, mut log_f) = (StatsLog::new(&dir_c, &sc, "uniform"), StatsLog::new(&dir_f, &sf, "tracked"));
    let logged = |e: crate::sim::RunError| RunError::Output(e.to_string());
    project(&tracker, &sc, &mut sf, None, &mut report);
    for k in 0..=preroll + frames {
        let mut wall = FrameWall::default();
        if k > 0 {
            if let Err((coarse_failed, e)) = lockstep_frame(&tracker, &mut sc, &mut sf, &mut report, &mut wall) {
                // The frames written so far stay; the failed run's stats.json says why it stopped.
                let at = sf.scene.frame_number(k).map_or(format!("preroll frame {k}"), |n| format!("frame {n}"));
                let (log, file) = if coarse_failed { (&mut log_c, &file_c) } else { (&mut log_f, &file_f) };
                log.fail(format!("{at}: {e}")).map_err(logged)?;
                return Err(failed(file)(e));
            }
        }
        if let Some(number) = sf.scene.frame_number(k) {
            let clock = Instant::now();
            write_frame(&dir_c, number, &frame_obj(sc.mesh(), &cloths_c, false))?;
            wall.coarse += clock.elapsed();
            let clock = Instant::now();
            write_frame(&dir_f, number, &frame_obj(sf.mesh(), &cloths_f, false))?;
            wall.fine += clock.elapsed();
        }
        log_c.frame(&mut sc, k, wall.coarse.as_secs_f64(), &[]).map_err(logged)?;
        let t = wall.tracking.as_secs_f64();
        log_f.frame(&mut sf, k, (wall.fine + wall.tracking).as_secs_f64(), &[("tracking", t)]).map_err(logged)?;
    }
    Ok(report)
}

/// Each run's own wall time in a frame, and the fine one's projections.
#[derive(Default)]
struct FrameWall {
    coarse: Duration,
    fine: Duration,
    tracking: Duration,
}

/// One frame of both runs, step by step, the fine run projected after each (`project`). A failure
/// says which run failed (true: the coarse one).
fn lockstep_frame(
    tracker: &Tracker,
    sc: &mut Simulation,
    sf: &mut Simulation,
    report: &mut TraceReport,
    wall: &mut FrameWall,
) -> Result<(), (bool, SimError)> {
    let timed = |sim: &mut Simulation, wall: &mut Duration, f: &dyn Fn(&mut Simulation) -> Result<(), SimError>| {
        let clock = Instant::now();
        let r = f(sim);
        *wall += clock.elapsed();
        r
    };
    let (h, steps) = (sf.scene.time_step(), sf.scene.steps_per_frame);
    let step = |sim: &mut Simulation| sim.step(h);
    timed(sc, &mut wall.coarse, &|s| s.begin_frame()).map_err(|e| (true, e))?;
    timed(sf, &mut wall.fine, &|s| s.begin_frame()).map_err(|e| (false, e))?;
    for _ in 0..steps {
        timed(sc, &mut wall.coarse, &step).map_err(|e| (true, e))?;
        timed(sf, &mut wall.fine, &step).map_err(|e| (false, e))?;
        let clock = Instant::now();
        project(tracker, sc, sf, Some(h), report);
        wall.tracking += clock.elapsed();
    }
    Ok(())
}

/// Eq. 6 enforced on `sf` (module doc); `h` is the step the change is spread over (None: the
/// initial state, whose velocities are left alone).
fn project(tracker: &Tracker, sc: &Simulation, sf: &mut Simulation, h: Option<Real>, report: &mut TraceReport) {
    let (pc, pf) = (sc.mesh().positions(), sf.mesh().positions());
    let before = tracker.residual(&pc, &pf).amax();
    for (node, d) in sf.state.mesh.nodes.iter_mut().zip(tracker.correction(&pc, &pf)) {
        node.x += d;
        if let Some(h) = h {
            node.v += d / h;
        }
    }
    if h.is_some() {
        report.steps += 1;
        report.residual_before.push(before);
        report.residual_after.push(tracker.residual(&pc, &sf.mesh().positions()).amax());
    }
}

/// The two shots must be one garment and motion at two resolutions: one cloth each, uniform
/// meshes (one topology each), the same frame timing.
fn check_pair(coarse: &Scene, fine: &Scene) -> Result<(), RunError> {
    for s in [coarse, fine] {
        if s.cloths.len() != 1 {
            // B embeds through material space, where separate cloths would overlap.
            let msg = format!("{} cloths; tracking pairs one cloth at two resolutions", s.cloths.len());
            return Err(RunError::Input(format!("{}: {msg}", s.file.display())));
        }
        if let Some(c) = s.cloths.iter().find(|c| c.remesh.as_ref().is_some_and(|r| r.mode.is_adaptive())) {
            return Err(RunError::Input(format!(
                "{}: cloth '{}' remeshes adaptively; tracking needs uniform runs (one topology each: \"mode\": \"uniform\" or no remesh block)",
                s.file.display(),
                c.name
            )));
        }
    }
    let timing = |s: &Scene| (s.frame_time, s.steps_per_frame, s.frames, s.preroll_frames, s.start_frame);
    if timing(coarse) != timing(fine) {
        return Err(RunError::Input(format!(
            "{}: frame_time, steps_per_frame, frames, preroll and start_frame must equal {}'s (the runs step in lockstep)",
            fine.file.display(),
            coarse.file.display()
        )));
    }
    Ok(())
}

fn write_frame(dir: &Path, number: usize, text: &str) -> Result<(), RunError> {
    let path = dir.join(format!("frame_{number:04}.obj"));
    write_atomic(&path, text.as_bytes()).map_err(|e| RunError::Output(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;

    /// After one projection eq. 6 holds to round-off, and the change is mass-orthogonal to the
    /// untracked harmonics (it only moves the T lowest).
    #[test]
    fn projection_satisfies_eq_6_and_moves_only_low_modes() {
        let (coarse, fine) = (Surface::grid(3, 3, 1.0, 1.0), Surface::grid(12, 12, 1.0, 1.0));
        let tracker = Tracker::new(&coarse, &fine, 10).unwrap();
        let bump = |p: Vec2, a: Real| Vec3::new(p.x, p.y, a * (7.0 * p.x).sin() * (5.0 * p.y).cos());
        let pc: Vec<Vec3> = coarse.node_uv().iter().map(|p| bump(p.unwrap(), 0.2)).collect();
        let mut pf: Vec<Vec3> = fine.node_uv().iter().map(|p| bump(p.unwrap(), -0.1)).collect();
        assert!(tracker.residual(&pc, &pf).amax() > 1e-3, "the pair starts apart");
        let d = tracker.correction(&pc, &pf);
        pf.iter_mut().zip(&d).for_each(|(x, d)| *x += d);
        assert!(tracker.residual(&pc, &pf).amax() < 1e-12, "{}", tracker.residual(&pc, &pf).amax());
        let all = Harmonics::new(&Laplacian::new(&fine).unwrap(), fine.nodes).unwrap();
        let dm = DMatrix::from_fn(fine.nodes, 3, |i, k| all.mass[i] * d[i][k]);
        let high = all.modes.columns(10, fine.nodes - 10).transpose() * dm;
        assert!(high.amax() < 1e-10, "correction leaks into mode > T: {}", high.amax());
    }
}
