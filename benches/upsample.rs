//! Upsampling benchmark (issue 13): apply time per frame of a dense U for M = 196 coarse and
//! N = 7056 fine nodes (the paper's skirt is 196 × 7016: 0.8 ms on one 2.9 GHz core; target here
//! under 0.5 ms), single-threaded, with U in f64 (`Operator`) and in f32 (`Compact`); and the training cost (harmonics, fit) at a size the dense
//! eigensolver handles in seconds.
//!
//! The apply timing does not depend on U's values, so it uses a synthetic dense U whose rows sum
//! to one (training at N = 7056 would need a 7056² dense eigensolve, minutes here).
//!
//! Memory: U's bytes in f64 (the model file's bulk) and f32 (`Compact`, what `apply` holds), and
//! the size of the model file `upsample train` would write for that U and a fine grid mesh.
//!
//! `cargo bench --bench upsample`

use std::time::Instant;

use nalgebra::DMatrix;
use viewcloth::io::obj::{Corner, ObjData};
use viewcloth::math::{Real, Vec2, Vec3};
use viewcloth::upsample::oscillatory::add_modes;
use viewcloth::upsample::validate::{cross_validate, grid as profile_grid};
use viewcloth::upsample::{
    embedding, fit, Compact, Harmonics, Laplacian, Model, Operator, OscillatoryMode, Prior, Profile, Surface,
    TrainingSet,
};

const REPEAT: usize = 200;

fn main() {
    apply_timing(196, 7056);
    training_timing(9, 30, 50);
}

fn apply_timing(m: usize, n: usize) {
    let u = DMatrix::from_fn(n, m, |i, j| ((i * 31 + j * 17) % 97) as Real + 1.0);
    let u = DMatrix::from_fn(n, m, |i, j| u[(i, j)] / u.row(i).sum());
    let op = Operator::new(u);
    memory(&op);
    let pc = DMatrix::from_fn(m, 3, |i, d| (i * 3 + d) as Real * 1e-3);
    let mut pf = DMatrix::zeros(n, 3);
    op.apply_into(&pc, &mut pf); // warm up
    let mut times: Vec<f64> = (0..REPEAT)
        .map(|_| {
            let t = Instant::now();
            op.apply_into(&pc, &mut pf);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(|a, b| a.total_cmp(b));
    let mb = (n * m * 8) as f64 / 1e6;
    println!(
        "apply: M {m}, N {n}, U {mb:.1} MB (f64): median {:.3} ms, min {:.3} ms per frame ({REPEAT} runs; check {:.3})",
        times[REPEAT / 2],
        times[0],
        pf.sum()
    );
    // `Compact`: U in f32 about the coarse centroid (what `upsample apply` uses), the whole
    // call timed (centring, product, conversion back to f64 points): `apply` allocating the
    // result, `apply_into` writing into the caller's buffer (what `upsample apply` does).
    let mut compact = Compact::new(&op);
    let points: Vec<Vec3> = (0..m).map(|i| Vec3::new(pc[(i, 0)], pc[(i, 1)], pc[(i, 2)])).collect();
    let times = timed(|| {
        std::hint::black_box(compact.apply(&points));
    });
    println!(
        "apply, Compact (U in f32, {:.1} MB): median {:.3} ms, min {:.3} ms per frame",
        mb / 2.0,
        times[REPEAT / 2],
        times[0]
    );
    let mut fine = vec![Vec3::zeros(); n];
    let times = timed(|| compact.apply_into(&points, std::hint::black_box(&mut fine)));
    println!(
        "apply_into, Compact (no allocation): median {:.3} ms, min {:.3} ms per frame",
        times[REPEAT / 2],
        times[0]
    );
    // Oscillatory modes (§5) on top: the fine grid's vertex normals and 2 pairs along them,
    // as `upsample apply` adds them when the model has modes (not in the times above).
    let side = (n as f64).sqrt().round() as usize;
    let triangles: Vec<[usize; 3]> = grid_obj(side - 1).triangles.iter().map(|t| t.map(|c| c.v)).collect();
    let modes: Vec<OscillatoryMode> = (0..2)
        .map(|k| OscillatoryMode {
            theta: 0.3 + 0.2 * k as Real,
            e: (0..n).map(|i| [1e-3, 1e-4 * (i % 7) as Real]).collect(),
        })
        .collect();
    let mut frame = 0;
    let times = timed(|| {
        compact.apply_into(&points, &mut fine);
        add_modes(&modes, &mut fine, &triangles, frame);
        frame += 1;
    });
    println!(
        "apply_into + 2 oscillatory pairs (normals of {} faces): median {:.3} ms, min {:.3} ms per frame",
        triangles.len(),
        times[REPEAT / 2],
        times[0]
    );
}

/// `REPEAT` wall times of `f` in ms, sorted, after one warm-up call.
fn timed(mut f: impl FnMut()) -> Vec<f64> {
    f();
    let mut times: Vec<f64> = (0..REPEAT)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(|a, b| a.total_cmp(b));
    times
}

/// U's bytes and the model file's size for an `n`-node fine grid (84 × 84 cells for N = 7056).
fn memory(op: &Operator) {
    let (n, m) = (op.fine_nodes(), op.coarse_nodes());
    let side = (n as f64).sqrt().round() as usize;
    let fine = grid_obj(side - 1);
    let model = Model::from_fine_obj(op.clone(), &fine);
    println!(
        "memory: M {m}, N {n}: U {:.2} MB in f64, {:.2} MB in f32 (Compact, held by apply); model file {:.2} MB",
        (n * m * 8) as f64 / 1e6,
        (n * m * 4) as f64 / 1e6,
        model.to_bytes().len() as f64 / 1e6
    );
}

/// Grids `c × c` cells (coarse) and `f × f` (fine) over the unit square, `frames` wavy frames.
fn training_timing(c: usize, f: usize, frames: usize) {
    let (coarse, fine) = (grid(c), grid(f));
    let t = Instant::now();
    let lap = Laplacian::new(&fine).unwrap();
    let h = Harmonics::new(&lap, fine.nodes).unwrap();
    let th = t.elapsed().as_secs_f64();
    let wave = |s: &Surface, k: usize| -> Vec<Vec3> {
        let p = |n: usize| Vec2::new((n % (s_side(s))) as Real, (n / s_side(s)) as Real) / (s_side(s) - 1) as Real;
        (0..s.nodes).map(|n| Vec3::new(p(n).x, p(n).y, 0.1 * (4.0 * p(n).x + 0.2 * k as Real).sin())).collect()
    };
    let data = TrainingSet {
        coarse: (0..frames).map(|k| wave(&coarse, k)).collect(),
        fine: (0..frames).map(|k| wave(&fine, k)).collect(),
    };
    let t = Instant::now();
    let op = fit(&h, &Profile::from_bounds(1.0, 1e5, 4.0, fine.nodes).unwrap(), &data).unwrap();
    let tf = t.elapsed().as_secs_f64();
    // The default `--cross-validate` grid: 2 priors × 24 (γ_1, γ_N) × 4 c = 192 profiles, 5 folds.
    let g = profile_grid(
        &[Prior::Zero, Prior::Barycentric],
        &[1e-3, 1e-2, 0.1, 1.0, 10.0],
        &[1.0, 10.0, 100.0, 1e3, 1e5],
        &[1.0, 2.0, 4.0, 8.0],
    );
    let t = Instant::now();
    let scores = cross_validate(&h, &embedding(&coarse, &fine), &data, 5, &g).unwrap();
    println!(
        "train: M {}, N {}, F {frames}, all N modes: harmonics {th:.2} s, fit {tf:.2} s (U {}×{}); \
         cross-validation of {} profiles × 5 folds {:.2} s",
        coarse.nodes,
        fine.nodes,
        op.fine_nodes(),
        op.coarse_nodes(),
        scores.len(),
        t.elapsed().as_secs_f64()
    );
}

fn s_side(s: &Surface) -> usize {
    (s.nodes as f64).sqrt().round() as usize
}

/// An `n × n`-cell grid over the unit square, as an OBJ frame would give it.
fn grid(n: usize) -> Surface {
    Surface::from_obj(&grid_obj(n)).unwrap()
}

fn grid_obj(n: usize) -> ObjData {
    let side = n + 1;
    let texcoords: Vec<Vec2> =
        (0..side * side).map(|k| Vec2::new((k % side) as Real, (k / side) as Real) / n as Real).collect();
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let id = |a: usize, b: usize| Corner { v: b * side + a, vt: Some(b * side + a) };
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let positions = texcoords.iter().map(|p| Vec3::new(p.x, p.y, 0.0)).collect();
    ObjData { positions, texcoords, triangles, ..ObjData::default() }
}
