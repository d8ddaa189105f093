//! The model file `upsample train` writes and `upsample apply` reads: U, the fine mesh it
//! produces (faces and material coordinates, to write the fine OBJ frames) and the oscillatory
//! modes (§5), behind a versioned header. Little-endian throughout:
//!
//! ```text
//! magic "VCUPSMPL" | version u32 (2) | M u64 | N u64 | T u64 (fine texcoords) | F u64 (fine faces)
//! | K u64 (oscillatory pairs)
//! T × (u, v) f64 | F × 3 × (v, vt) u32 | U: N × M f64, column-major | K × (θ f64, N × (e₁, e₂) f64)
//! ```
//!
//! Version 1 (no K, no modes) is still read, as a model without oscillatory modes.

use std::path::Path;

use nalgebra::DMatrix;

use super::{Operator, OscillatoryMode};
use crate::io::obj::{Corner, ObjData};
use crate::math::{Real, Vec2};

const MAGIC: &[u8; 8] = b"VCUPSMPL";
pub const VERSION: u32 = 2;

/// An operator with the fine mesh it outputs.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    pub op: Operator,
    /// Fine faces (`v` and `vt` indices) and texture coordinates; positions come from U.
    pub texcoords: Vec<Vec2>,
    pub faces: Vec<[Corner; 3]>,
    /// Oscillatory mode pairs (§5), added along the upsampled normals; may be empty.
    pub modes: Vec<OscillatoryMode>,
}

#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error("{0}: not a viewcloth upsampling model (bad magic)")]
    Magic(String),
    #[error("{0}: model version {1}, this viewcloth reads versions 1 and {VERSION}")]
    Version(String, u32),
    #[error("{0}: truncated or oversized model ({1})")]
    Size(String, String),
    #[error("{0}: corrupt model ({1})")]
    Corrupt(String, String),
    #[error("{0}: {1}")]
    Io(String, std::io::Error),
}

impl Model {
    pub fn from_fine_obj(op: Operator, fine: &ObjData) -> Model {
        Model { op, texcoords: fine.texcoords.clone(), faces: fine.triangles.clone(), modes: Vec::new() }
    }

    /// The fine faces as node triangles (for normals).
    pub fn triangles(&self) -> Vec<[usize; 3]> {
        self.faces.iter().map(|f| f.map(|c| c.v)).collect()
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        let (n, m) = (self.op.fine_nodes(), self.op.coarse_nodes());
        let k = self.modes.len();
        let mut b =
            Vec::with_capacity(52 + 16 * self.texcoords.len() + 24 * self.faces.len() + 8 * n * (m + 2 * k) + 8 * k);
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        for x in [m, n, self.texcoords.len(), self.faces.len(), k] {
            b.extend_from_slice(&(x as u64).to_le_bytes());
        }
        for t in &self.texcoords {
            b.extend_from_slice(&t.x.to_le_bytes());
            b.extend_from_slice(&t.y.to_le_bytes());
        }
        for c in self.faces.iter().flatten() {
            b.extend_from_slice(&(c.v as u32).to_le_bytes());
            b.extend_from_slice(&(c.vt.unwrap_or(0) as u32).to_le_bytes());
        }
        for x in self.op.u.iter() {
            b.extend_from_slice(&x.to_le_bytes());
        }
        for mode in &self.modes {
            b.extend_from_slice(&mode.theta.to_le_bytes());
            for x in mode.e.iter().flatten() {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        b
    }

    pub fn read(path: &Path) -> Result<Model, ModelError> {
        let name = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| ModelError::Io(name.clone(), e))?;
        Model::from_bytes(&bytes, &name)
    }

    /// Parses a model, checking every count against the file length before allocating.
    pub fn from_bytes(b: &[u8], name: &str) -> Result<Model, ModelError> {
        if b.len() < 12 || &b[..8] != MAGIC {
            return Err(ModelError::Magic(name.into()));
        }
        let version = u32::from_le_bytes(b[8..12].try_into().unwrap_or_default());
        if version != 1 && version != VERSION {
            return Err(ModelError::Version(name.into(), version));
        }
        let mut r = Reader { b, at: 12 };
        let size = |what: &str| ModelError::Size(name.into(), what.into());
        let header = if version == 1 { 4 } else { 5 };
        let counts: Vec<usize> =
            (0..header).map(|_| r.u64().map(|x| x as usize)).collect::<Option<_>>().ok_or(size("header"))?;
        let (m, n, t, f, k) = (counts[0], counts[1], counts[2], counts[3], counts.get(4).copied().unwrap_or(0));
        let (n128, k128) = (n as u128, k as u128);
        let expect =
            [16 * t as u128, 24 * f as u128, 8 * n128 * m as u128, k128 * (8 + 16 * n128)].iter().sum::<u128>()
                + 12
                + 8 * header as u128;
        if expect != b.len() as u128 {
            return Err(size(&format!(
                "{} bytes for M {m}, N {n}, {t} texcoords, {f} faces, {k} oscillatory pairs; expected {expect}",
                b.len()
            )));
        }
        let texcoords: Vec<Vec2> = (0..t).map(|_| Vec2::new(r.f64(), r.f64())).collect();
        let faces: Vec<[Corner; 3]> =
            (0..f).map(|_| [0; 3].map(|_| Corner { v: r.u32(), vt: Some(r.u32()) })).collect();
        let corrupt = |what: String| ModelError::Corrupt(name.into(), what);
        if let Some(c) = faces.iter().flatten().find(|c| c.v >= n || c.vt.unwrap_or(0) >= t) {
            return Err(corrupt(format!("face corner {}/{} out of range", c.v, c.vt.unwrap_or(0))));
        }
        let u = DMatrix::from_iterator(n, m, (0..n * m).map(|_| r.f64()));
        let modes: Vec<OscillatoryMode> = (0..k)
            .map(|_| OscillatoryMode { theta: r.f64(), e: (0..n).map(|_| [r.f64(), r.f64()]).collect() })
            .collect();
        let finite = u.iter().all(|x| x.is_finite())
            && texcoords.iter().all(|p| p.iter().all(|c| c.is_finite()))
            && modes.iter().all(|md| md.theta.is_finite() && md.e.iter().flatten().all(|x| x.is_finite()));
        if !finite {
            return Err(corrupt("non-finite value".into()));
        }
        Ok(Model { op: Operator::new(u), texcoords, faces, modes })
    }
}

/// Reads little-endian values; lengths were checked up front, so reads past the end give 0.
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const K: usize>(&mut self) -> Option<[u8; K]> {
        let s = self.b.get(self.at..self.at + K)?.try_into().ok();
        self.at += K;
        s
    }
    fn u64(&mut self) -> Option<u64> {
        self.take::<8>().map(u64::from_le_bytes)
    }
    fn u32(&mut self) -> usize {
        self.take::<4>().map_or(0, u32::from_le_bytes) as usize
    }
    fn f64(&mut self) -> Real {
        self.take::<8>().map_or(0.0, f64::from_le_bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> Model {
        let u = DMatrix::from_fn(4, 3, |i, j| (i * 3 + j) as Real / 7.0);
        let texcoords = vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0)];
        let c = |v| Corner { v, vt: Some(v) };
        let modes = vec![OscillatoryMode { theta: 0.4, e: (0..4).map(|i| [0.01 * i as Real, -0.02]).collect() }];
        Model { op: Operator::new(u), texcoords, faces: vec![[c(0), c(1), c(2)], [c(1), c(3), c(2)]], modes }
    }

    #[test]
    fn round_trips_bit_for_bit() {
        let m = model();
        assert_eq!(Model::from_bytes(&m.to_bytes(), "m").unwrap(), m);
    }

    #[test]
    fn damaged_files_are_refused_with_one_line() {
        let b = model().to_bytes();
        let err = |b: &[u8]| Model::from_bytes(b, "m.bin").unwrap_err().to_string();
        assert!(err(b"hello").contains("not a viewcloth upsampling model"));
        let mut v3 = b.clone();
        v3[8] = 3;
        assert!(err(&v3).contains("version 3, this viewcloth reads versions 1 and 2"));
        assert!(err(&b[..b.len() - 1]).contains("truncated"));
        let mut huge = b.clone();
        huge[12..20].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(err(&huge).contains("truncated"));
        let mut bad_face = b.clone();
        bad_face[52 + 16 * 4..56 + 16 * 4].copy_from_slice(&99u32.to_le_bytes());
        assert!(err(&bad_face).contains("out of range"));
        assert!([err(b"hello"), err(&v3)].iter().all(|e| !e.contains('\n')));
        let mut nan = b.clone();
        let at = nan.len() - 8;
        nan[at..].copy_from_slice(&Real::NAN.to_le_bytes());
        assert!(err(&nan).contains("non-finite"));
    }

    /// A version 1 file (written as version 1 did: no pair count, no modes) reads as a model
    /// without oscillatory modes.
    #[test]
    fn version_1_files_are_still_read() {
        let m = Model { modes: Vec::new(), ..model() };
        let v2 = m.to_bytes();
        let mut v1 = v2[..8].to_vec();
        v1.extend_from_slice(&1u32.to_le_bytes());
        v1.extend_from_slice(&v2[12..44]); // M, N, T, F
        v1.extend_from_slice(&v2[52..]); // K = 0 dropped
        assert_eq!(Model::from_bytes(&v1, "m").unwrap(), m);
    }
}
