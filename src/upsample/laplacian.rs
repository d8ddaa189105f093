//! The cotangent Laplacian of a surface in material space, with lumped mass (§3.2, after
//! Pinkall & Polthier 1993): for an edge (i, j), w_ij = (cot β_ij + cot β̃_ij)/2 over the
//! angles opposite it. We keep the positive semi-definite sign, K = −C (K_ij = −w_ij,
//! K_ii = Σ_j w_ij), so eigenvalues come out ≥ 0 and rows sum to zero: constants are harmonic.

use std::collections::BTreeMap;

use nalgebra::DMatrix;

use super::{Surface, UpsampleError};
use crate::math::{cross2, Real};

#[derive(Clone, Debug)]
pub struct Laplacian {
    /// Off-diagonal weights w_ij > 0 or < 0 (obtuse pairs), i < j, sorted.
    pub edges: Vec<(usize, usize, Real)>,
    /// Lumped mass: a third of each incident face's material area (the diagonal V of §3.2).
    pub mass: Vec<Real>,
}

/// The cotangent of the angle at corner k of a material triangle; `None` when degenerate.
pub fn corner_cot(t: &[crate::math::Vec2; 3], k: usize) -> Option<Real> {
    let (e1, e2) = (t[(k + 1) % 3] - t[k], t[(k + 2) % 3] - t[k]);
    let s = cross2(&e1, &e2).abs();
    (s > 0.0).then(|| e1.dot(&e2) / s)
}

impl Laplacian {
    /// Barycentric lumping (area/3 per corner) rather than the paper's Voronoi areas: it is
    /// what the simulator lumps masses with (`Mesh::compute_masses`) and stays positive on
    /// obtuse triangles.
    pub fn new(s: &Surface) -> Result<Laplacian, UpsampleError> {
        let mut w: BTreeMap<(usize, usize), Real> = BTreeMap::new();
        let mut mass = vec![0.0; s.nodes];
        for (f, t) in s.faces.iter().enumerate() {
            let area = s.area(f).abs();
            if area == 0.0 {
                continue;
            }
            for k in 0..3 {
                mass[t[k]] += area / 3.0;
                let (i, j) = (t[(k + 1) % 3], t[(k + 2) % 3]);
                let cot = corner_cot(&s.uv[f], k).unwrap_or(0.0);
                *w.entry((i.min(j), i.max(j))).or_insert(0.0) += 0.5 * cot;
            }
        }
        if let Some(node) = mass.iter().position(|&m| m <= 0.0) {
            return Err(UpsampleError::ZeroMass { node });
        }
        Ok(Laplacian { edges: w.into_iter().map(|((i, j), w)| (i, j, w)).collect(), mass })
    }

    /// K as a dense matrix (for the dense eigensolver; `harmonics` says why dense).
    pub fn dense_stiffness(&self) -> DMatrix<Real> {
        let n = self.mass.len();
        let mut k = DMatrix::zeros(n, n);
        for &(i, j, w) in &self.edges {
            k[(i, j)] -= w;
            k[(j, i)] -= w;
            k[(i, i)] += w;
            k[(j, j)] += w;
        }
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;

    fn two_triangles() -> Surface {
        // Nodes 0 (0,0), 1 (2,0), 2 (1,1), 3 (1,−2); faces share edge 0–1.
        let p = [Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, -2.0)];
        let faces = vec![[0, 1, 2], [0, 3, 1]];
        let uv = faces.iter().map(|t: &[usize; 3]| t.map(|n| p[n])).collect();
        Surface { nodes: 4, faces, uv }
    }

    fn weight(l: &Laplacian, i: usize, j: usize) -> Real {
        l.edges.iter().find(|e| (e.0, e.1) == (i, j)).unwrap().2
    }

    #[test]
    fn cotangent_weights_match_a_hand_computed_pair() {
        let l = Laplacian::new(&two_triangles()).unwrap();
        // Shared edge 0–1: opposite angles 90° at (1,1) (cot 0) and at (1,−2), between (−1,2)
        // and (1,2): cot = 3/4. w = (0 + 3/4)/2.
        assert!((weight(&l, 0, 1) - 0.375).abs() < 1e-15);
        // Edge 1–2 is opposite corner 0 of face 0: 45°, cot 1, one face: w = 1/2.
        assert!((weight(&l, 1, 2) - 0.5).abs() < 1e-15);
        // Edge 0–3 is opposite corner 1 (2,0) of face 1: between (−2,0) and (−1,−2): cot = 2/4.
        assert!((weight(&l, 0, 3) - 0.25).abs() < 1e-15);
        // Masses: face areas 1 and 2, a third to each corner.
        let m = [1.0, 1.0, 1.0 / 3.0, 2.0 / 3.0];
        assert!(l.mass.iter().zip(m).all(|(a, b)| (a - b).abs() < 1e-15), "{:?}", l.mass);
    }

    #[test]
    fn rows_sum_to_zero_and_matrix_is_symmetric() {
        let l = Laplacian::new(&Surface::grid(5, 4, 1.3, 0.7)).unwrap();
        let k = l.dense_stiffness();
        for i in 0..k.nrows() {
            assert!(k.row(i).sum().abs() < 1e-12);
        }
        assert!((&k - k.transpose()).amax() == 0.0);
        let area: Real = l.mass.iter().sum();
        assert!((area - 1.3 * 0.7).abs() < 1e-12);
    }

    #[test]
    fn an_isolated_node_is_refused() {
        let mut s = two_triangles();
        s.nodes = 5;
        assert_eq!(Laplacian::new(&s).unwrap_err(), UpsampleError::ZeroMass { node: 4 });
    }
}
