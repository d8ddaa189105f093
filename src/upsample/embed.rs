//! The barycentric embedding B ∈ R^{N×M} of §4: each fine node located in a coarse triangle in
//! material space, its row holding that triangle's barycentric weights. The rows sum to one, so
//! B·p_c follows rigid and affine motions of the coarse mesh exactly.

use super::Surface;
use crate::io::obj::{Corner, ObjData};
use crate::math::{Real, Vec3};
use crate::resample::locate::Locator;

/// B, one row per fine node: three (coarse node, weight) pairs, weights summing to one.
#[derive(Clone, Debug)]
pub struct Embedding {
    pub rows: Vec<[(usize, Real); 3]>,
    /// The farthest any fine node lay outside every coarse face (material metres; 0 when the
    /// fine domain is inside the coarse one). Such nodes take the nearest coarse point.
    pub outside: Real,
}

/// Embeds every node of `fine` in `coarse`, through material space (§4: "projecting the fine
/// vertices onto the coarse triangles" — in the rest pattern, where both meshes coincide).
pub fn embedding(coarse: &Surface, fine: &Surface) -> Embedding {
    let locator = Locator::new(&as_obj(coarse));
    let mut outside: Real = 0.0;
    let rows = fine
        .node_uv()
        .iter()
        .map(|uv| {
            // A node in no face has no material coordinate; it gets coarse node 0 (weight 1).
            let Some(uv) = uv else { return [(0, 1.0), (0, 0.0), (0, 0.0)] };
            let hit = locator.locate(uv);
            outside = outside.max(hit.outside);
            let t = coarse.faces[hit.triangle];
            [0, 1, 2].map(|k| (t[k], hit.bary[k]))
        })
        .collect();
    Embedding { rows, outside }
}

/// The coarse surface as an OBJ whose texture coordinates are its corners (what `Locator` reads).
fn as_obj(s: &Surface) -> ObjData {
    let texcoords = s.uv.iter().flatten().copied().collect();
    let triangles =
        s.faces.iter().enumerate().map(|(f, t)| [0, 1, 2].map(|k| Corner { v: t[k], vt: Some(3 * f + k) })).collect();
    ObjData { texcoords, triangles, ..ObjData::default() }
}

impl Embedding {
    /// B·p_c.
    pub fn apply(&self, coarse: &[Vec3]) -> Vec<Vec3> {
        self.rows.iter().map(|r| r.iter().map(|&(j, w)| coarse[j] * w).sum()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;

    #[test]
    fn rows_sum_to_one_and_reproduce_affine_maps() {
        let (coarse, fine) = (Surface::grid(3, 2, 1.0, 0.5), Surface::grid(9, 7, 1.0, 0.5));
        let b = embedding(&coarse, &fine);
        assert!(b.outside < 1e-12);
        for r in &b.rows {
            assert!((r.iter().map(|e| e.1).sum::<Real>() - 1.0).abs() < 1e-12);
        }
        // A linear field of material space, sampled at coarse nodes, is interpolated exactly.
        let f = |p: Vec2| Vec3::new(2.0 * p.x - p.y + 0.3, 0.5 * p.y, p.x + p.y);
        let pc: Vec<Vec3> = coarse.node_uv().iter().map(|p| f(p.unwrap())).collect();
        for (x, p) in b.apply(&pc).iter().zip(fine.node_uv()) {
            assert!((x - f(p.unwrap())).norm() < 1e-12);
        }
    }
}
