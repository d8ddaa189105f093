//! Keeps remeshing from making the cloth pass through itself. Splits keep the surface (the new
//! node lies on the split edge), but a flip swaps the diagonal of a non-planar quad and a
//! collapse moves a vert's faces onto its neighbour: either can push a new face through a
//! nearby layer of cloth (a fold, two sheets in contact), and the collision stages, which
//! assume an intersection-free start, would never undo it. Each flip and collapse is tested
//! here with the exact crossing predicate (`collision::crossings::triangles_cross`) against the
//! faces near its new faces, and refused when one crosses.
//!
//! Node positions do not change while remeshing, so a uniform hash grid of face boxes, built
//! once and extended with every added face, finds the neighbours; removed faces are skipped by
//! their tombstones.

use std::collections::HashMap;

use crate::collision::crossings::triangles_cross;
use crate::math::{Real, Vec3};

use super::ops::Op;
use super::work::Work;

/// Grid cells of a face's box at most; a larger face is kept in a list tested always.
const MAX_CELLS: usize = 64;

pub struct Guard {
    cell: Real,
    grid: HashMap<[i64; 3], Vec<usize>>,
    /// Faces whose boxes span more than `MAX_CELLS` cells.
    large: Vec<usize>,
}

impl Guard {
    /// A grid over the work's alive faces, its cell the mean face box extent.
    pub fn new(w: &Work) -> Guard {
        let alive: Vec<usize> = (0..w.faces.len()).filter(|&f| w.falive[f]).collect();
        let extent: Real = alive.iter().map(|&f| box_of(w, &w.faces[f]).extent()).sum::<Real>();
        let cell = (extent / alive.len().max(1) as Real).max(1e-9);
        let mut g = Guard { cell, grid: HashMap::new(), large: Vec::new() };
        for f in alive {
            g.insert(w, f);
        }
        g
    }

    /// Records face `f` (after an op added it).
    pub fn insert(&mut self, w: &Work, f: usize) {
        let cells = self.cells(&box_of(w, &w.faces[f]));
        match cells.len() > MAX_CELLS {
            true => self.large.push(f),
            false => cells.into_iter().for_each(|c| self.grid.entry(c).or_default().push(f)),
        }
    }

    /// Whether one of `op`'s new faces would cross an alive face it does not remove. Faces
    /// sharing an edge cannot cross; faces sharing one node can (one passes through the other
    /// beyond the node), and are tested too: the frame's crossing check skips them, but a later
    /// split that separates them would reveal such a crossing, unguarded (dart.json's relaxed
    /// paper layers: 15 crossing pairs after its first remesh).
    pub fn crosses(&self, w: &Work, op: &Op) -> bool {
        op.add_faces.iter().any(|&(t, _)| {
            let b = box_of(w, &t);
            let nodes = t.map(|v| w.vnode[v]);
            let tri = nodes.map(|n| w.x[n]);
            let cells = self.cells(&b);
            let mut near: Vec<usize> = match cells.len() > MAX_CELLS {
                true => (0..w.faces.len()).collect(),
                false => cells.iter().filter_map(|c| self.grid.get(c)).flatten().copied().collect(),
            };
            near.extend(&self.large);
            near.sort_unstable();
            near.dedup();
            near.into_iter().any(|g| {
                if !w.falive[g] || op.remove_faces.contains(&g) {
                    return false;
                }
                let other = w.faces[g].map(|v| w.vnode[v]);
                if other.iter().filter(|n| nodes.contains(n)).count() > 1 || !b.overlaps(&box_of(w, &w.faces[g])) {
                    return false;
                }
                triangles_cross(&tri, &other.map(|n| w.x[n]))
            })
        })
    }

    /// The grid cells a box overlaps; more than `MAX_CELLS` entries (not the cells) when it
    /// overlaps more.
    fn cells(&self, b: &Box3) -> Vec<[i64; 3]> {
        let lo = b.lo.map(|c| (c / self.cell).floor() as i64);
        let hi = b.hi.map(|c| (c / self.cell).floor() as i64);
        let count = (0..3).map(|k| (hi[k] - lo[k] + 1).max(1) as usize).product::<usize>();
        if count > MAX_CELLS {
            return vec![[0; 3]; count.min(MAX_CELLS + 1)];
        }
        let mut out = Vec::with_capacity(count);
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                for k in lo[2]..=hi[2] {
                    out.push([i, j, k]);
                }
            }
        }
        out
    }
}

struct Box3 {
    lo: [Real; 3],
    hi: [Real; 3],
}

impl Box3 {
    fn extent(&self) -> Real {
        (0..3).map(|k| self.hi[k] - self.lo[k]).fold(0.0, Real::max)
    }

    fn overlaps(&self, o: &Box3) -> bool {
        (0..3).all(|k| self.lo[k] <= o.hi[k] && o.lo[k] <= self.hi[k])
    }
}

fn box_of(w: &Work, t: &[usize; 3]) -> Box3 {
    let p: [Vec3; 3] = t.map(|v| w.x[w.vnode[v]]);
    let lo = [0, 1, 2].map(|k| p[0][k].min(p[1][k]).min(p[2][k]));
    let hi = [0, 1, 2].map(|k| p[0][k].max(p[1][k]).max(p[2][k]));
    Box3 { lo, hi }
}
