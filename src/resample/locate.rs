//! Point location in material space: which face of a frame's mesh holds a texture coordinate,
//! and where in it (barycentric coordinates), through a uniform grid of the faces' boxes.

use crate::io::obj::ObjData;
use crate::math::{cross2, Real, Vec2};

/// A located point: the face, its barycentric coordinates there, and how far outside every
/// face the point was (0 inside; else it is moved to the nearest point of the nearest face).
pub struct Hit {
    pub triangle: usize,
    pub bary: [Real; 3],
    pub outside: Real,
}

/// One locator per group of triangles (the cloths of a mesh, whose material spaces overlap):
/// `items` gives each triangle's id, material corners and group. Per group, the ids of its
/// triangles in the order given (`Hit::triangle` of its locator indexes that list) and the
/// locator; `None` for a group without triangles.
pub fn by_group(items: impl Iterator<Item = (usize, [Vec2; 3], usize)>) -> Vec<Option<(Vec<usize>, Locator)>> {
    let mut groups: Vec<(Vec<usize>, Vec<[Vec2; 3]>)> = Vec::new();
    for (id, uv, g) in items {
        if groups.len() <= g {
            groups.resize_with(g + 1, Default::default);
        }
        groups[g].0.push(id);
        groups[g].1.push(uv);
    }
    groups.into_iter().map(|(ids, uv)| (!ids.is_empty()).then(|| (ids, Locator::from_triangles(uv)))).collect()
}

#[derive(Clone, Debug)]
pub struct Locator {
    uv: Vec<[Vec2; 3]>,
    lo: Vec2,
    cell: Real,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<usize>>,
}

/// Barycentric coordinates of `p` in triangle `t` (any signs).
fn bary(t: &[Vec2; 3], p: &Vec2) -> [Real; 3] {
    let d = cross2(&(t[1] - t[0]), &(t[2] - t[0]));
    let l1 = cross2(&(t[2] - t[1]), &(p - t[1])) / d;
    let l2 = cross2(&(t[0] - t[2]), &(p - t[2])) / d;
    [l1, l2, 1.0 - l1 - l2]
}

/// The nearest point of triangle `t` to `p` (outside it), as barycentric coordinates and distance.
fn nearest(t: &[Vec2; 3], p: &Vec2) -> ([Real; 3], Real) {
    let mut best = ([1.0, 0.0, 0.0], Real::INFINITY);
    for k in 0..3 {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        let e = b - a;
        let s = ((p - a).dot(&e) / e.norm_squared().max(Real::MIN_POSITIVE)).clamp(0.0, 1.0);
        let d = (a + e * s - p).norm();
        if d < best.1 {
            let mut w = [0.0; 3];
            w[k] = 1.0 - s;
            w[(k + 1) % 3] = s;
            best = (w, d);
        }
    }
    best
}

impl Locator {
    pub fn new(obj: &ObjData) -> Locator {
        Locator::from_triangles(obj.triangles.iter().map(|t| t.map(|c| obj.texcoords[c.vt.unwrap_or(0)])).collect())
    }

    /// A locator over material-space triangles (`Hit::triangle` indexes `uv`); at least one.
    pub fn from_triangles(uv: Vec<[Vec2; 3]>) -> Locator {
        let (mut lo, mut hi) = (Vec2::repeat(Real::INFINITY), Vec2::repeat(Real::NEG_INFINITY));
        for p in uv.iter().flatten() {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let span = (hi - lo).max().max(Real::MIN_POSITIVE);
        let cells_per_side = ((uv.len() as Real).sqrt().ceil() as usize).clamp(1, 1024);
        let cell = span / cells_per_side as Real * (1.0 + 1e-9);
        let nx = (((hi.x - lo.x) / cell) as usize + 1).min(1024);
        let ny = (((hi.y - lo.y) / cell) as usize + 1).min(1024);
        let mut cells = vec![Vec::new(); nx * ny];
        let index = |v: Real, lo: Real, n: usize| (((v - lo) / cell).max(0.0) as usize).min(n - 1);
        for (f, t) in uv.iter().enumerate() {
            let (a, b) = (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2]));
            for j in index(a.y, lo.y, ny)..=index(b.y, lo.y, ny) {
                for i in index(a.x, lo.x, nx)..=index(b.x, lo.x, nx) {
                    cells[j * nx + i].push(f);
                }
            }
        }
        Locator { uv, lo, cell, nx, ny, cells }
    }

    /// The triangles whose boxes may overlap the box `lo`–`hi` (those in the grid cells it
    /// covers), each once, in increasing order.
    pub fn near_box(&self, lo: &Vec2, hi: &Vec2) -> Vec<usize> {
        let index = |v: Real, lo: Real, n: usize| (((v - lo) / self.cell).max(0.0) as usize).min(n - 1);
        let mut out = Vec::new();
        for j in index(lo.y, self.lo.y, self.ny)..=index(hi.y, self.lo.y, self.ny) {
            for i in index(lo.x, self.lo.x, self.nx)..=index(hi.x, self.lo.x, self.nx) {
                out.extend_from_slice(&self.cells[j * self.nx + i]);
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The face holding `p` (the lowest-numbered one on a shared edge), else the nearest face.
    pub fn locate(&self, p: &Vec2) -> Hit {
        let i = (((p.x - self.lo.x) / self.cell).max(0.0) as usize).min(self.nx - 1);
        let j = (((p.y - self.lo.y) / self.cell).max(0.0) as usize).min(self.ny - 1);
        const SLACK: Real = 1e-10;
        for &f in &self.cells[j * self.nx + i] {
            let w = bary(&self.uv[f], p);
            if w.iter().all(|&c| c >= -SLACK) {
                return Hit {
                    triangle: f,
                    bary: w.map(|c| c.max(0.0)).map(|c| c / (w.map(|c| c.max(0.0)).iter().sum::<Real>())),
                    outside: 0.0,
                };
            }
        }
        // Outside every face (beyond the domain's boundary): the nearest point of the nearest.
        let mut best = Hit { triangle: 0, bary: [1.0, 0.0, 0.0], outside: Real::INFINITY };
        for (f, t) in self.uv.iter().enumerate() {
            let (w, d) = nearest(t, p);
            if d < best.outside {
                best = Hit { triangle: f, bary: w, outside: d };
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::obj::parse_obj;

    #[test]
    fn points_are_found_inside_and_clamped_outside() {
        let obj = parse_obj(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 2 0\nvt 2 2\nvt 0 2\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
        )
        .unwrap();
        let l = Locator::new(&obj);
        let h = l.locate(&Vec2::new(1.5, 0.5));
        assert_eq!((h.triangle, h.outside), (0, 0.0));
        let w = [0.25, 0.5, 0.25];
        assert!(h.bary.iter().zip(w).all(|(a, b)| (a - b).abs() < 1e-12), "{:?}", h.bary);
        let h = l.locate(&Vec2::new(0.5, 1.5));
        assert_eq!(h.triangle, 1);
        let h = l.locate(&Vec2::new(3.0, 1.0));
        assert!((h.outside - 1.0).abs() < 1e-12 && h.triangle == 0);
    }
}
