//! Writing the resampled run: per frame the OBJ (every cloth, `o` groups as the run's frames)
//! and the USD samples (a prim per cloth), and the PC2 point cache's header and samples.

use std::path::{Path, PathBuf};

use super::{io, place, FixedMesh, FrameError, ResampleError, ResampleReport, RunFrame};
use crate::io::usd;
use crate::io::write_atomic;
use crate::math::Vec3;
use crate::metrics::geometric::{surface_distance, Surface};
use crate::render::run_dir::FrameMeshes;

/// One cloth's USD prim: its path, faces as node triples and as st index triples.
struct Prim {
    path: String,
    tris: Vec<[usize; 3]>,
    st: Vec<[usize; 3]>,
}

/// What the resampled frames are written as: the OBJ frames, the USD samples per cloth prim.
pub(super) struct OutFiles<'a> {
    names: &'a [String],
    fixed: &'a [FixedMesh],
    prims: Vec<Prim>,
    digits: usize,
}

impl<'a> OutFiles<'a> {
    pub(super) fn new(names: &'a [String], fixed: &'a [FixedMesh], digits: usize) -> OutFiles<'a> {
        // One cloth keeps the prim name it always had.
        let prim_names = match names.len() {
            1 => vec!["resampled".to_string()],
            _ => usd::prim_names(names.iter().map(String::as_str)),
        };
        let prims = fixed
            .iter()
            .zip(prim_names)
            .map(|(f, name)| {
                let tris = f.triangles.iter().map(|t| t.map(|c| c.0)).collect();
                let st = f.triangles.iter().map(|t| t.map(|c| c.1)).collect();
                Prim { path: format!("/World/cloth/{name}"), tris, st }
            })
            .collect();
        OutFiles { names, fixed, prims, digits }
    }

    pub(super) fn samples_path(&self, out: &Path, number: usize) -> PathBuf {
        out.join(usd::SAMPLES_DIR).join(format!("frame_{number:0w$}.txt", w = self.digits))
    }

    /// Places every cloth's fixed mesh on its frame, records the error in `report` and writes
    /// the frame's OBJ and USD samples; returns the placed positions, cloth after cloth.
    pub(super) fn write_frame(
        &self,
        out: &Path,
        cloths: &[RunFrame],
        report: &mut ResampleReport,
    ) -> Result<Vec<Vec3>, ResampleError> {
        let (mut all, mut run) = (FrameMeshes::default(), FrameMeshes::default());
        let mut text = String::new();
        let mut placed = Vec::with_capacity(self.fixed.len());
        for ((fixed, frame), prim) in self.fixed.iter().zip(cloths).zip(&self.prims) {
            let (tris, st) = (&prim.tris, &prim.st);
            let (x, v, outside) = place(fixed, frame);
            report.max_outside = report.max_outside.max(outside);
            run.append(frame.obj.positions.clone(), frame.obj.triangles.iter().map(|t| t.map(|c| c.v)).collect());
            all.append(x.clone(), tris.clone());
            let velocities = (!v.is_empty()).then_some(&v[..]);
            text.push_str(&usd::fixed_samples(&prim.path, &x, velocities, tris, &fixed.texcoords, st));
            placed.push(x);
        }
        let d = surface_distance(
            Surface { positions: &all.positions, triangles: &all.triangles, weight: None },
            Surface { positions: &run.positions, triangles: &run.triangles, weight: None },
        );
        let (number, time) = (cloths[0].number, cloths[0].time);
        report.frames.push(FrameError { frame: number, time, mean: d.mean, max: d.max });
        let obj_path = out.join(format!("frame_{number:0w$}.obj", w = self.digits));
        write_atomic(&obj_path, fixed_obj(self.names, self.fixed, &placed).as_bytes()).map_err(io(&obj_path))?;
        let sample_path = self.samples_path(out, number);
        write_atomic(&sample_path, text.as_bytes()).map_err(io(&sample_path))?;
        Ok(placed.into_iter().flatten().collect())
    }
}

/// A resampled frame as OBJ: `v` per fixed node, the fixed `vt`, `f v/vt`; with several
/// cloths, every cloth's `v` then every cloth's `vt`, and its faces under `o <cloth>` (as the
/// run's frames).
fn fixed_obj(names: &[String], fixed: &[FixedMesh], x: &[Vec<Vec3>]) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("# viewcloth resampled frame\n");
    for p in x.iter().flatten() {
        let _ = writeln!(s, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
    }
    for u in fixed.iter().flat_map(|f| &f.texcoords) {
        let _ = writeln!(s, "vt {:.9} {:.9}", u.x, u.y);
    }
    let (mut v0, mut vt0) = (1, 1);
    for (f, name) in fixed.iter().zip(names) {
        if fixed.len() > 1 {
            let _ = writeln!(s, "o {name}");
        }
        for t in &f.triangles {
            let c = t.map(|(v, vt)| (v + v0, vt + vt0));
            let _ = writeln!(s, "f {}/{} {}/{} {}/{}", c[0].0, c[0].1, c[1].0, c[1].1, c[2].0, c[2].1);
        }
        (v0, vt0) = (v0 + f.node_uv.len(), vt0 + f.texcoords.len());
    }
    s
}

/// A PC2 point cache (Blender's and 3ds Max's format): `POINTCACHE2\0`, version 1, point count,
/// start frame, sample rate, sample count (little endian), then every sample's points as
/// 32-bit float triples.
pub fn pc2_bytes(frames: &[Vec<Vec3>], start: f32, rate: f32) -> Vec<u8> {
    let points = frames.first().map_or(0, Vec::len);
    let mut b = pc2_header(points, frames.len(), start, rate);
    for f in frames {
        b.extend(pc2_points(f));
    }
    b
}

/// The 32-byte header of a PC2 cache.
pub(super) fn pc2_header(points: usize, samples: usize, start: f32, rate: f32) -> Vec<u8> {
    let mut b = Vec::with_capacity(32);
    b.extend_from_slice(b"POINTCACHE2\0");
    b.extend_from_slice(&1i32.to_le_bytes());
    b.extend_from_slice(&(points as i32).to_le_bytes());
    b.extend_from_slice(&start.to_le_bytes());
    b.extend_from_slice(&rate.to_le_bytes());
    b.extend_from_slice(&(samples as i32).to_le_bytes());
    b
}

/// One sample of a PC2 cache.
pub(super) fn pc2_points(x: &[Vec3]) -> Vec<u8> {
    x.iter().flat_map(|p| [p.x, p.y, p.z]).flat_map(|c| (c as f32).to_le_bytes()).collect()
}
