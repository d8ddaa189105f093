//! Held-out error of fine-resolution meshes against a fine run (issue 13; `bench/upsample_garment.sh`):
//!
//!     cargo run --release --example upsample_heldout -- FINE_DIR [--frames A..B] NAME=DIR...
//!
//! For every frame of FINE_DIR (or frames A..B, both included) and every run DIR (same frame
//! numbers; one topology per run), two errors against the fine frame, averaged over the frames:
//! the two-sided mean surface distance (`metrics::geometric`, what `compare` reports) and the mean
//! distance between points of equal material coordinates (each fine node located in the run's
//! material space, the run's surface evaluated there: where a texture point ends up, which a
//! surface distance does not see). Prints a markdown table, one row per run, in mm.

use std::path::{Path, PathBuf};

use viewcloth::io::obj::{read_obj, ObjData};
use viewcloth::math::Real;
use viewcloth::metrics::{surface_distance, Surface as Measured};
use viewcloth::render::run_dir::frame_numbers;
use viewcloth::upsample::{embedding, Surface};

fn main() {
    if let Err(e) = run() {
        eprintln!("upsample_heldout: {e}");
        std::process::exit(2);
    }
}

fn run() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let fine = PathBuf::from(args.next().ok_or("usage: upsample_heldout FINE_DIR [--frames A..B] NAME=DIR...")?);
    let (mut range, mut runs) = (None, Vec::new());
    while let Some(a) = args.next() {
        if a == "--frames" {
            let v = args.next().ok_or("--frames: expected A..B")?;
            let parsed =
                v.split_once("..").and_then(|(a, b)| Some((a.parse::<usize>().ok()?, b.parse::<usize>().ok()?)));
            range = Some(parsed.filter(|(a, b)| a <= b).ok_or(format!("--frames: expected A..B, got '{v}'"))?);
        } else {
            let (name, dir) = a.split_once('=').ok_or(format!("'{a}': expected NAME=DIR"))?;
            runs.push((name.to_owned(), PathBuf::from(dir)));
        }
    }
    let all = frame_numbers(&fine).map_err(|e| e.to_string())?;
    let numbers: Vec<usize> = all.into_iter().filter(|k| range.is_none_or(|(a, b)| (a..=b).contains(k))).collect();
    if numbers.is_empty() {
        return Err(format!("{}: no frames in the range asked", fine.display()));
    }
    println!("| run | faces | mean surface distance (mm) | equal material coordinates (mm) |");
    println!("|---|---|---|---|");
    for (name, dir) in &runs {
        let (surface, material, faces) = errors(&fine, dir, &numbers)?;
        println!("| {name} | {faces} | {:.2} | {:.2} |", 1e3 * surface, 1e3 * material);
    }
    println!("({} frames, {}..={})", numbers.len(), numbers[0], numbers[numbers.len() - 1]);
    Ok(())
}

fn frame(dir: &Path, k: usize) -> Result<ObjData, String> {
    let path = dir.join(format!("frame_{k:04}.obj"));
    read_obj(&path).map_err(|e| format!("{}: {e}", path.display()))
}

fn triangles(o: &ObjData) -> Vec<[usize; 3]> {
    o.triangles.iter().map(|t| t.map(|c| c.v)).collect()
}

/// Mean surface distance and mean equal-material-coordinate distance (m) of `run` to `fine` over
/// `numbers`, and the run's face count.
fn errors(fine: &Path, run: &Path, numbers: &[usize]) -> Result<(Real, Real, usize), String> {
    let (f0, r0) = (frame(fine, numbers[0])?, frame(run, numbers[0])?);
    let named = |d: &Path, e: viewcloth::upsample::UpsampleError| format!("{}: {e}", d.display());
    let (fs, rs) =
        (Surface::from_obj(&f0).map_err(|e| named(fine, e))?, Surface::from_obj(&r0).map_err(|e| named(run, e))?);
    // The fine nodes in the run's material space (the identity for a run on the fine mesh).
    let b = embedding(&rs, &fs);
    let (tf, tr) = (triangles(&f0), triangles(&r0));
    let (mut surface, mut material) = (0.0, 0.0);
    for &k in numbers {
        let (pf, pr) = (frame(fine, k)?.positions, frame(run, k)?.positions);
        if pf.len() != f0.positions.len() || pr.len() != r0.positions.len() {
            return Err(format!("frame {k}: node count changed (one topology per run)"));
        }
        let a = Measured { positions: &pf, triangles: &tf, weight: None };
        surface += surface_distance(a, Measured { positions: &pr, triangles: &tr, weight: None }).mean;
        let at = b.apply(&pr);
        material += at.iter().zip(&pf).map(|(x, y)| (x - y).norm()).sum::<Real>() / pf.len() as Real;
    }
    let n = numbers.len() as Real;
    Ok((surface / n, material / n, tr.len()))
}
