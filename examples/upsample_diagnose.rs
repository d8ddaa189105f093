//! Where the upsampled mesh's error against a tracked fine run comes from (issue 13):
//!
//!     cargo run --release --example upsample_diagnose -- MODEL COARSE_DIR FINE_DIR [OTHER_DIR]
//!
//! For every frame pair (same numbers) it compares four fine-resolution meshes with the fine
//! frame: B p_c (the coarse surface itself, barycentrically), U p_c (the model), and the same two
//! applied to p_c* = argmin ‖B p_c − p_f‖_V, the coarse positions that best represent the fine
//! frame (so what is left is the operator's own error, not the coarse run's). Each error is split
//! into its component along the fine frame's vertex normal and the tangential rest, with the mean
//! signed normal offset (a shrink or a push shows there), over interior and boundary nodes apart,
//! and as the two-sided mean surface distance (`metrics::geometric`, what `compare` reports).
//! Everything in mm, averaged over the frames. OTHER_DIR (a run with the fine run's frame
//! numbers, e.g. `upsample loop`'s output) adds its mean surface distance to the fine frames.

use std::path::{Path, PathBuf};

use nalgebra::DMatrix;
use viewcloth::io::obj::read_obj;
use viewcloth::math::{Real, Vec3};
use viewcloth::metrics::{surface_distance, vertex_normals, Surface as Measured};
use viewcloth::render::run_dir::frame_numbers;
use viewcloth::upsample::{embedding, Laplacian, Model, Surface};

#[derive(Default, Clone, Copy)]
struct Errors {
    /// RMS node distance, RMS normal and tangential parts, mean signed normal part, RMS over
    /// interior and boundary nodes, mean surface distance.
    rms: Real,
    normal: Real,
    tangential: Real,
    signed_normal: Real,
    interior: Real,
    boundary: Real,
    surface: Real,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 4 && args.len() != 5 {
        eprintln!("usage: upsample_diagnose MODEL COARSE_DIR FINE_DIR [OTHER_DIR]");
        std::process::exit(2);
    }
    let model = Model::read(Path::new(&args[1])).unwrap_or_else(|e| panic!("{e}"));
    let (coarse, fine) = (PathBuf::from(&args[2]), PathBuf::from(&args[3]));
    let numbers = frame_numbers(&coarse).unwrap_or_else(|e| panic!("{e}"));
    let frame = |d: &Path, k: usize| read_obj(&d.join(format!("frame_{k:04}.obj"))).unwrap_or_else(|e| panic!("{e}"));
    let (c0, f0) = (frame(&coarse, numbers[0]), frame(&fine, numbers[0]));
    let (cs, fs) = (Surface::from_obj(&c0).unwrap(), Surface::from_obj(&f0).unwrap());
    let b = embedding(&cs, &fs);
    let mass = Laplacian::new(&fs).unwrap().mass;
    let triangles = model.triangles();
    let boundary = boundary_nodes(&triangles, fs.nodes);
    // Bᵀ V B, for the coarse positions that best represent a fine frame.
    let m = cs.nodes;
    let mut btvb = DMatrix::zeros(m, m);
    for (i, row) in b.rows.iter().enumerate() {
        for &(j, wj) in row {
            for &(k, wk) in row {
                btvb[(j, k)] += mass[i] * wj * wk;
            }
        }
    }
    let chol = btvb.cholesky().expect("Bᵀ V B is positive definite");
    let names = ["B p_c", "U p_c", "B p_c*", "U p_c*"];
    let mut sums = [Errors::default(); 4];
    let mut coarse_gap = 0.0;
    for &k in &numbers {
        let (pc, pf) = (frame(&coarse, k).positions, frame(&fine, k).positions);
        let mut rhs = DMatrix::zeros(m, 3);
        for (i, row) in b.rows.iter().enumerate() {
            for &(j, w) in row {
                for d in 0..3 {
                    rhs[(j, d)] += mass[i] * w * pf[i][d];
                }
            }
        }
        let best = chol.solve(&rhs);
        let pc_star: Vec<Vec3> = (0..m).map(|j| Vec3::new(best[(j, 0)], best[(j, 1)], best[(j, 2)])).collect();
        coarse_gap += pc.iter().zip(&pc_star).map(|(a, b)| (a - b).norm_squared()).sum::<Real>() / m as Real;
        let meshes = [b.apply(&pc), model.op.apply(&pc), b.apply(&pc_star), model.op.apply(&pc_star)];
        let normals = vertex_normals(&pf, &triangles);
        for (s, x) in sums.iter_mut().zip(&meshes) {
            let e = errors(x, &pf, &normals, &mass, &boundary, &triangles);
            for (acc, v) in fields(s).into_iter().zip([
                e.rms,
                e.normal,
                e.tangential,
                e.signed_normal,
                e.interior,
                e.boundary,
                e.surface,
            ]) {
                *acc += v;
            }
        }
    }
    let f = numbers.len() as Real;
    println!(
        "{} frames, {} coarse → {} fine nodes ({} on the boundary); RMS |p_c − p_c*| {:.2} mm",
        numbers.len(),
        m,
        fs.nodes,
        boundary.iter().filter(|&&x| x).count(),
        1e3 * (coarse_gap / f).sqrt()
    );
    println!("| mesh | RMS node | normal | tangential | mean signed normal | interior | boundary | surface distance |");
    println!("|---|---|---|---|---|---|---|---|");
    for (name, s) in names.iter().zip(sums.iter_mut()) {
        let v: Vec<String> = fields(s).into_iter().map(|x| format!("{:.2}", 1e3 * *x / f)).collect();
        println!("| {name} | {} |", v.join(" | "));
    }
    if let Some(other) = args.get(4) {
        println!("{other}: mean surface distance {:.2} mm", 1e3 * other_distance(Path::new(other), &fine, &numbers));
    }
}

/// Mean over the frames of the surface distance between `other`'s and `fine`'s frames.
fn other_distance(other: &Path, fine: &Path, numbers: &[usize]) -> Real {
    let tris = |o: &viewcloth::io::obj::ObjData| o.triangles.iter().map(|t| t.map(|c| c.v)).collect::<Vec<_>>();
    let mut sum = 0.0;
    for &k in numbers {
        let [a, b] =
            [other, fine].map(|d| read_obj(&d.join(format!("frame_{k:04}.obj"))).unwrap_or_else(|e| panic!("{e}")));
        let (ta, tb) = (tris(&a), tris(&b));
        let ma = Measured { positions: &a.positions, triangles: &ta, weight: None };
        sum += surface_distance(ma, Measured { positions: &b.positions, triangles: &tb, weight: None }).mean;
    }
    sum / numbers.len() as Real
}

fn fields(e: &mut Errors) -> [&mut Real; 7] {
    [
        &mut e.rms,
        &mut e.normal,
        &mut e.tangential,
        &mut e.signed_normal,
        &mut e.interior,
        &mut e.boundary,
        &mut e.surface,
    ]
}

/// Mass-weighted RMS errors of `x` against the fine frame `pf` (normals `n`).
fn errors(x: &[Vec3], pf: &[Vec3], n: &[Vec3], mass: &[Real], boundary: &[bool], tris: &[[usize; 3]]) -> Errors {
    let (mut all, mut nor, mut tan, mut signed, mut w) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut inner, mut wi, mut outer, mut wo) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..pf.len() {
        let d = x[i] - pf[i];
        let dn = d.dot(&n[i]);
        let m = mass[i];
        all += m * d.norm_squared();
        nor += m * dn * dn;
        tan += m * (d - n[i] * dn).norm_squared();
        signed += m * dn;
        w += m;
        if boundary[i] {
            outer += m * d.norm_squared();
            wo += m;
        } else {
            inner += m * d.norm_squared();
            wi += m;
        }
    }
    let ma = Measured { positions: x, triangles: tris, weight: None };
    let surface = surface_distance(ma, Measured { positions: pf, triangles: tris, weight: None }).mean;
    Errors {
        rms: (all / w).sqrt(),
        normal: (nor / w).sqrt(),
        tangential: (tan / w).sqrt(),
        signed_normal: signed / w,
        interior: (inner / wi.max(1e-300)).sqrt(),
        boundary: (outer / wo.max(1e-300)).sqrt(),
        surface,
    }
}

/// Nodes on an edge with one face.
fn boundary_nodes(tris: &[[usize; 3]], n: usize) -> Vec<bool> {
    let mut count = std::collections::HashMap::new();
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut on = vec![false; n];
    for ((a, b), c) in count {
        if c == 1 {
            on[a] = true;
            on[b] = true;
        }
    }
    on
}
