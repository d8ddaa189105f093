//! A fixed-topology triangle mesh as the upsampler sees it: node indices per face (the world
//! degrees of freedom U maps) and the material coordinates of each face corner (seams give a
//! node several), from which the embedding and the Laplacian are built.

use super::UpsampleError;
use crate::io::obj::ObjData;
use crate::math::{cross2, Real, Vec2};

#[derive(Clone, Debug)]
pub struct Surface {
    pub nodes: usize,
    pub faces: Vec<[usize; 3]>,
    /// Material coordinates of each face's corners, in face order.
    pub uv: Vec<[Vec2; 3]>,
}

impl Surface {
    /// From an OBJ frame: `v` are nodes, `vt` material coordinates (viewcloth writes both).
    pub fn from_obj(obj: &ObjData) -> Result<Surface, UpsampleError> {
        if obj.triangles.is_empty() {
            return Err(UpsampleError::Empty);
        }
        let mut uv = Vec::with_capacity(obj.triangles.len());
        for t in &obj.triangles {
            let c = t.map(|c| c.vt.and_then(|k| obj.texcoords.get(k).copied()));
            match c {
                [Some(a), Some(b), Some(c)] => uv.push([a, b, c]),
                _ => return Err(UpsampleError::NoMaterialCoords),
            }
        }
        let faces = obj.triangles.iter().map(|t| t.map(|c| c.v)).collect();
        Ok(Surface { nodes: obj.positions.len(), faces, uv })
    }

    /// Signed material-space area of face `f`.
    pub fn area(&self, f: usize) -> Real {
        let [a, b, c] = self.uv[f];
        0.5 * cross2(&(b - a), &(c - a))
    }

    /// One material coordinate per node (the first corner seen; seam nodes have several).
    pub fn node_uv(&self) -> Vec<Option<Vec2>> {
        let mut out = vec![None; self.nodes];
        for (f, t) in self.faces.iter().enumerate() {
            for k in 0..3 {
                out[t[k]].get_or_insert(self.uv[f][k]);
            }
        }
        out
    }

    /// A flat `nx × ny`-cell grid over `[0, w] × [0, h]`, two faces per cell, counter-clockwise.
    #[cfg(test)]
    pub fn grid(nx: usize, ny: usize, w: Real, h: Real) -> Surface {
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let at = |n: usize| Vec2::new((n % (nx + 1)) as Real * w / nx as Real, (n / (nx + 1)) as Real * h / ny as Real);
        let mut faces = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            }
        }
        let uv = faces.iter().map(|t: &[usize; 3]| t.map(at)).collect();
        Surface { nodes: (nx + 1) * (ny + 1), faces, uv }
    }
}
