//! The block sparsity pattern of the implicit system and its scalar lower-triangular CSC form.

use crate::forces::Hinge;
use crate::mesh::Mesh;

/// Lower-triangular 3×3-block pattern: for each column node `b`, the sorted row nodes `a ≥ b`
/// (the diagonal first). Block `k` stores A[a][b].
#[derive(Clone, Debug, PartialEq)]
pub struct BlockPattern {
    pub nodes: usize,
    pub col_start: Vec<usize>,
    pub rows: Vec<usize>,
    /// Per face: block index for each ordered local pair (i, j) with global row ≥ column, else
    /// `NONE`.
    pub face_slots: Vec<[usize; 9]>,
    /// Per hinge (in `RestState::hinges` order): the same for the four hinge nodes.
    pub hinge_slots: Vec<[usize; 16]>,
}

pub const NONE: usize = usize::MAX;

impl BlockPattern {
    /// The pattern of face couplings, the wing–wing couplings of `hinges` and `extra` node pairs
    /// (cloth–cloth contacts).
    pub fn new(mesh: &Mesh, hinges: &[Hinge], extra: &[(usize, usize)]) -> Self {
        let n = mesh.nodes.len();
        let mut cols: Vec<Vec<usize>> = (0..n).map(|b| vec![b]).collect();
        let mut add = |a: usize, b: usize| {
            let (hi, lo) = if a >= b { (a, b) } else { (b, a) };
            if hi != lo {
                cols[lo].push(hi);
            }
        };
        for f in 0..mesh.faces.len() {
            let [a, b, c] = mesh.face_nodes(f);
            add(a, b);
            add(b, c);
            add(a, c);
        }
        for h in hinges {
            add(h.nodes[2], h.nodes[3]);
        }
        for &(a, b) in extra {
            add(a, b);
        }
        let mut col_start = Vec::with_capacity(n + 1);
        let mut rows = Vec::new();
        for col in &mut cols {
            col[1..].sort_unstable();
            col.dedup();
            col_start.push(rows.len());
            rows.extend_from_slice(col);
        }
        col_start.push(rows.len());
        let mut p = BlockPattern { nodes: n, col_start, rows, face_slots: Vec::new(), hinge_slots: Vec::new() };
        p.face_slots = (0..mesh.faces.len()).map(|f| p.slots(&mesh.face_nodes(f))).collect();
        p.hinge_slots = hinges.iter().map(|h| p.slots(&h.nodes)).collect();
        p
    }

    /// Block index of A[a][b] for a ≥ b.
    pub fn block(&self, a: usize, b: usize) -> Option<usize> {
        let (s, e) = (self.col_start[b], self.col_start[b + 1]);
        self.rows[s..e].binary_search(&a).ok().map(|k| s + k)
    }

    fn slots<const N: usize, const M: usize>(&self, nodes: &[usize; N]) -> [usize; M] {
        let mut out = [NONE; M];
        for i in 0..N {
            for j in 0..N {
                let (a, b) = (nodes[i], nodes[j]);
                if a >= b {
                    out[i * N + j] = self.block(a, b).unwrap_or(NONE);
                }
            }
        }
        out
    }

    pub fn num_blocks(&self) -> usize {
        self.rows.len()
    }
}

/// The scalar lower triangle in CSC form, with the source (block, entry) of each value.
#[derive(Clone, Debug)]
pub struct ScalarCsc {
    pub dim: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
    /// `block * 9 + (3 i + j)` for each stored value.
    pub src: Vec<usize>,
}

impl ScalarCsc {
    pub fn new(p: &BlockPattern) -> Self {
        let mut col_ptr = vec![0];
        let (mut row_idx, mut src) = (Vec::new(), Vec::new());
        for b in 0..p.nodes {
            for j in 0..3 {
                for k in p.col_start[b]..p.col_start[b + 1] {
                    let a = p.rows[k];
                    let first = if a == b { j } else { 0 };
                    for i in first..3 {
                        row_idx.push(3 * a + i);
                        src.push(k * 9 + 3 * i + j);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        ScalarCsc { dim: 3 * p.nodes, col_ptr, row_idx, src }
    }
}
