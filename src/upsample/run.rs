//! Training, applying and subdividing over run directories (`upsample train`, `upsample apply`,
//! `upsample loop`): OBJ frames in, a model or OBJ frames out. All need one topology for the
//! whole shot (uniform runs): a frame whose node or face count differs from the first is refused,
//! naming it.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, DVector};

use super::oscillatory::{add_modes, fit_modes, normal_residual, OscillatoryMode};
use super::validate::{barycentric_rms, best, cross_validate, Candidate, Scored};
use super::{
    embedding, fit_towards, Compact, Harmonics, Laplacian, Model, Prior, Profile, Subdivision, Surface, TrainingSet,
};
use crate::io::obj::{read_obj, Corner, ObjData};
use crate::io::write_atomic;
use crate::math::{Real, Vec3};
use crate::render::run_dir::frame_numbers;

/// Above this many fine nodes the dense eigensolve (`harmonics`) takes too long and too much
/// memory (N² doubles, several copies) to start unasked.
pub const MAX_DENSE_NODES: usize = 6000;

/// A failure: `Input` for bad input (exit 2), `Output` for a write that failed (exit 1).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("{0}")]
    Input(String),
    #[error("{0}")]
    Output(String),
}

fn input(path: &Path, msg: impl std::fmt::Display) -> RunError {
    RunError::Input(format!("{}: {msg}", path.display()))
}

pub struct TrainOptions {
    /// Harmonics kept (None: all N, the paper's choice; `fit` says why).
    pub modes: Option<usize>,
    /// The damping profiles to train with: one is used as given; from several, the one of least
    /// error under `folds`-fold cross-validation on the training frames (`validate`).
    pub profiles: Vec<Candidate>,
    pub folds: usize,
    /// Oscillatory mode pairs to fit to the residual (§5; 0: none).
    pub oscillatory: usize,
}

/// What training saw, for the closing line.
#[derive(Debug)]
pub struct TrainReport {
    pub frames: usize,
    pub coarse_nodes: usize,
    pub fine_nodes: usize,
    pub modes: usize,
    /// The profile U was fitted with.
    pub profile: Candidate,
    /// Every candidate's cross-validation score, in the order given (empty: one candidate).
    pub validation: Vec<Scored>,
    /// RMS node distance (m) of B p_c to p_f over the training frames (`barycentric_rms`).
    pub barycentric_rms: Real,
    /// The oscillatory pairs fitted: θ (radians per frame) of each.
    pub oscillatory: Vec<Real>,
}

/// Learns a model from the paired frames of a coarse and a fine run (same frame numbers).
pub fn train(coarse: &Path, fine: &Path, opts: &TrainOptions) -> Result<(Model, TrainReport), RunError> {
    let numbers = frame_numbers(coarse).map_err(|e| RunError::Input(e.to_string()))?;
    if frame_numbers(fine).map_err(|e| RunError::Input(e.to_string()))? != numbers {
        return Err(input(
            fine,
            format!("its frames differ from {}'s: training pairs frames by number", coarse.display()),
        ));
    }
    let (c0, f0) = (read_frame(coarse, numbers[0])?, read_frame(fine, numbers[0])?);
    let n = f0.positions.len();
    if n > MAX_DENSE_NODES {
        return Err(input(fine, format!("{n} fine nodes; the dense eigensolve is limited to {MAX_DENSE_NODES}")));
    }
    let surface = Surface::from_obj(&f0).map_err(|e| input(&frame_path(fine, numbers[0]), e))?;
    let lap = Laplacian::new(&surface).map_err(|e| input(&frame_path(fine, numbers[0]), e))?;
    let modes = opts.modes.unwrap_or(n);
    let h = Harmonics::new(&lap, modes).map_err(|e| RunError::Input(e.to_string()))?;
    let bad = |e: super::UpsampleError| RunError::Input(e.to_string());
    let coarse_surface = Surface::from_obj(&c0).map_err(|e| input(&frame_path(coarse, numbers[0]), e))?;
    let b = embedding(&coarse_surface, &surface);
    let mut data = TrainingSet::default();
    for &k in &numbers {
        data.coarse.push(positions_like(coarse, k, &c0)?);
        data.fine.push(positions_like(fine, k, &f0)?);
    }
    let (chosen, validation) = match opts.profiles.as_slice() {
        [] => return Err(RunError::Input("no damping profile to train with".into())),
        [one] => (*one, Vec::new()),
        grid => {
            let scores = cross_validate(&h, &b, &data, opts.folds, grid).map_err(bad)?;
            let best = best(&scores).map(|s| s.candidate).unwrap_or(grid[0]);
            (best, scores)
        }
    };
    let profile = Profile::from_bounds(chosen.gamma1, chosen.gamma_n, chosen.c, n).map_err(bad)?;
    let prior = (chosen.prior == Prior::Barycentric).then_some(&b);
    let op = fit_towards(&h, &profile, &data, prior).map_err(bad)?;
    let mut model = Model::from_fine_obj(op, &f0);
    if opts.oscillatory > 0 {
        if numbers.windows(2).any(|w| w[1] != w[0] + 1) {
            return Err(input(coarse, "oscillatory modes need consecutive frame numbers (one frame rate)"));
        }
        model.modes = oscillatory_modes(&model, &data, opts.oscillatory, numbers[0]);
    }
    let report = TrainReport {
        frames: numbers.len(),
        coarse_nodes: c0.positions.len(),
        fine_nodes: n,
        modes,
        profile: chosen,
        validation,
        barycentric_rms: barycentric_rms(&b, h.mass.as_slice(), &data),
        oscillatory: model.modes.iter().map(|m| m.theta).collect(),
    };
    Ok((model, report))
}

/// §5: D's column j is frame j's residual normal displacement after U; the pairs are fitted with
/// frame `first` as j = 0 and then phased to the frame numbers, which `apply` uses.
fn oscillatory_modes(model: &Model, data: &TrainingSet, pairs: usize, first: usize) -> Vec<OscillatoryMode> {
    let triangles = model.triangles();
    let mut d = DMatrix::zeros(model.op.fine_nodes(), data.fine.len());
    for (j, (pc, pf)) in data.coarse.iter().zip(&data.fine).enumerate() {
        let r = normal_residual(&model.op.apply(pc), pf, &triangles);
        d.set_column(j, &DVector::from_vec(r));
    }
    fit_modes(&d, pairs).into_iter().map(|m| m.shifted(first)).collect()
}

/// Upsamples every frame of `coarse` into `out` (frame_NNNN.obj, same numbers); returns the count.
pub fn apply(model: &Model, coarse: &Path, out: &Path) -> Result<usize, RunError> {
    let numbers = frame_numbers(coarse).map_err(|e| RunError::Input(e.to_string()))?;
    // The first frame is checked before the output folder is made: a refused run leaves nothing.
    if let Some(&first) = numbers.first() {
        coarse_positions(model, coarse, first)?;
    }
    std::fs::create_dir_all(out).map_err(|e| RunError::Output(format!("{}: {e}", out.display())))?;
    let mut compact = Compact::new(&model.op);
    let triangles = model.triangles();
    let mut fine = vec![Vec3::zeros(); model.op.fine_nodes()];
    for &k in &numbers {
        compact.apply_into(&coarse_positions(model, coarse, k)?, &mut fine);
        add_modes(&model.modes, &mut fine, &triangles, k);
        let path = frame_path(out, k);
        write_atomic(&path, obj_text("upsampled", &fine, &model.texcoords, &model.faces).as_bytes())
            .map_err(|e| RunError::Output(format!("{}: {e}", path.display())))?;
    }
    Ok(numbers.len())
}

/// Loop-subdivides (`levels` levels) every frame of the uniform run `coarse` into `out`
/// (frame_NNNN.obj, same numbers); returns the frame and node counts. The baseline U is
/// measured against.
pub fn subdivide(coarse: &Path, levels: usize, out: &Path) -> Result<(usize, usize), RunError> {
    let numbers = frame_numbers(coarse).map_err(|e| RunError::Input(e.to_string()))?;
    let first = read_frame(coarse, numbers[0])?;
    let surface = Surface::from_obj(&first).map_err(|e| input(&frame_path(coarse, numbers[0]), e))?;
    let sub = Subdivision::new(&surface, levels).map_err(|e| RunError::Input(e.to_string()))?;
    let (texcoords, faces) = corners(&sub.surface);
    std::fs::create_dir_all(out).map_err(|e| RunError::Output(format!("{}: {e}", out.display())))?;
    for &k in &numbers {
        let x = sub.apply(&positions_like(coarse, k, &first)?);
        let path = frame_path(out, k);
        write_atomic(&path, obj_text("Loop-subdivided", &x, &texcoords, &faces).as_bytes())
            .map_err(|e| RunError::Output(format!("{}: {e}", path.display())))?;
    }
    Ok((numbers.len(), sub.rows.len()))
}

/// The face count of the first frame of the run in `dir`.
pub fn coarse_faces(dir: &Path) -> Result<usize, RunError> {
    let numbers = frame_numbers(dir).map_err(|e| RunError::Input(e.to_string()))?;
    Ok(read_frame(dir, numbers[0])?.triangles.len())
}

/// A surface's material coordinates as OBJ texture coordinates (equal ones shared) and faces.
fn corners(s: &Surface) -> (Vec<crate::math::Vec2>, Vec<[Corner; 3]>) {
    let mut index: HashMap<(u64, u64), usize> = HashMap::new();
    let mut texcoords = Vec::new();
    let faces = s
        .faces
        .iter()
        .zip(&s.uv)
        .map(|(t, uv)| {
            [0, 1, 2].map(|k| {
                let vt = *index.entry((uv[k].x.to_bits(), uv[k].y.to_bits())).or_insert_with(|| {
                    texcoords.push(uv[k]);
                    texcoords.len() - 1
                });
                Corner { v: t[k], vt: Some(vt) }
            })
        })
        .collect();
    (texcoords, faces)
}

/// Coarse frame `k`'s positions, refused unless it has the model's coarse node count.
fn coarse_positions(model: &Model, coarse: &Path, k: usize) -> Result<Vec<Vec3>, RunError> {
    let obj = read_frame(coarse, k)?;
    let m = model.op.coarse_nodes();
    if obj.positions.len() != m {
        let msg = format!(
            "{} nodes, the model was trained on {m} (a different coarse mesh, or an adaptive run?)",
            obj.positions.len()
        );
        return Err(input(&frame_path(coarse, k), msg));
    }
    Ok(obj.positions)
}

fn frame_path(dir: &Path, number: usize) -> PathBuf {
    dir.join(format!("frame_{number:04}.obj"))
}

fn read_frame(dir: &Path, number: usize) -> Result<ObjData, RunError> {
    let path = frame_path(dir, number);
    read_obj(&path).map_err(|e| input(&path, e))
}

/// Frame `number`'s positions, refused unless its mesh has the first frame's size.
fn positions_like(dir: &Path, number: usize, first: &ObjData) -> Result<Vec<Vec3>, RunError> {
    let obj = read_frame(dir, number)?;
    if obj.positions.len() != first.positions.len() || obj.triangles.len() != first.triangles.len() {
        let msg = format!(
            "{} nodes and {} faces, the first frame {} and {}: training needs a uniform run (one topology)",
            obj.positions.len(),
            obj.triangles.len(),
            first.positions.len(),
            first.triangles.len()
        );
        return Err(input(&frame_path(dir, number), msg));
    }
    Ok(obj.positions)
}

/// A fine frame as OBJ: positions, texture coordinates and faces.
fn obj_text(what: &str, x: &[Vec3], texcoords: &[crate::math::Vec2], faces: &[[Corner; 3]]) -> String {
    let mut s = String::with_capacity(x.len() * 40 + texcoords.len() * 28 + faces.len() * 24);
    let _ = writeln!(s, "# viewcloth {what} frame");
    for p in x {
        let _ = writeln!(s, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
    }
    for t in texcoords {
        let _ = writeln!(s, "vt {:.9} {:.9}", t.x, t.y);
    }
    for f in faces {
        let c = f.map(|c| (c.v + 1, c.vt.unwrap_or(0) + 1));
        let _ = writeln!(s, "f {}/{} {}/{} {}/{}", c[0].0, c[0].1, c[1].0, c[1].1, c[2].0, c[2].1);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;

    /// Writes frames of an `n × n` grid over the unit square, bent by frame, into `dir`.
    fn write_run(dir: &Path, n: usize, frames: usize) {
        std::fs::create_dir_all(dir).unwrap();
        let side = n + 1;
        let uv: Vec<Vec2> =
            (0..side * side).map(|k| Vec2::new((k % side) as Real, (k / side) as Real) / n as Real).collect();
        for f in 0..frames {
            let mut s = String::new();
            for p in &uv {
                let z = 0.1 * (3.0 * p.x + 0.4 * f as Real).sin();
                let _ = writeln!(s, "v {} {} {z}", p.x, p.y);
            }
            for p in &uv {
                let _ = writeln!(s, "vt {} {}", p.x, p.y);
            }
            for j in 0..n {
                for i in 0..n {
                    let [a, b, c, d] = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|(x, y)| y * side + x + 1);
                    let _ = writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}\nf {a}/{a} {c}/{c} {d}/{d}");
                }
            }
            std::fs::write(frame_path(dir, f), s).unwrap();
        }
    }

    #[test]
    fn trains_applies_and_refuses_a_mismatched_run() {
        let root = std::env::temp_dir().join(format!("viewcloth-upsample-{}", std::process::id()));
        let (coarse, fine, out) = (root.join("coarse"), root.join("fine"), root.join("out"));
        write_run(&coarse, 3, 6);
        write_run(&fine, 9, 6);
        // γ competes with the spectrum of P_c P_cᵀ, which grows with the frame count: for 6
        // frames it must be far below §6's (with γ_N = 10 U is worse than barycentric here).
        let profiles = vec![Candidate { gamma1: 1e-3, gamma_n: 0.1, c: 4.0, prior: Prior::Zero }];
        let opts = TrainOptions { modes: None, profiles, folds: 5, oscillatory: 0 };
        let (model, r) = train(&coarse, &fine, &opts).unwrap();
        assert_eq!((r.frames, r.coarse_nodes, r.fine_nodes, r.modes), (6, 16, 100, 100));
        let model = Model::from_bytes(&model.to_bytes(), "m").unwrap();
        assert_eq!(apply(&model, &coarse, &out).unwrap(), 6);
        let got = read_obj(&frame_path(&out, 5)).unwrap();
        let want = read_obj(&frame_path(&fine, 5)).unwrap();
        assert_eq!((got.triangles.len(), got.texcoords.len()), (want.triangles.len(), want.texcoords.len()));
        let err = got.positions.iter().zip(&want.positions).map(|(a, b)| (a - b).norm()).fold(0.0, Real::max);
        // Closer than barycentric interpolation of the coarse frame (what U would be untrained).
        let (c5, f0) = (read_obj(&frame_path(&coarse, 5)).unwrap(), read_obj(&frame_path(&fine, 0)).unwrap());
        let (cs, fs) = (Surface::from_obj(&c5).unwrap(), Surface::from_obj(&f0).unwrap());
        let b = super::super::embedding(&cs, &fs).apply(&c5.positions);
        let err_b = b.iter().zip(&want.positions).map(|(a, b)| (a - b).norm()).fold(0.0, Real::max);
        assert!(err < 0.5 * err_b, "training frame: upsampled {err}, barycentric {err_b}");
        // The fine run applied as if coarse: wrong node count, one line naming the frame.
        let e = apply(&model, &fine, &root.join("bad")).unwrap_err().to_string();
        assert!(e.contains("frame_0000.obj") && e.contains("100 nodes") && !e.contains('\n'), "{e}");
        assert!(!root.join("bad").exists(), "a refused apply left its output folder");
        // Frames that do not pair up.
        std::fs::remove_file(frame_path(&fine, 5)).unwrap();
        assert!(train(&coarse, &fine, &opts).unwrap_err().to_string().contains("frames differ"));
        let _ = std::fs::remove_dir_all(&root);
    }
}
