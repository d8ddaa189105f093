//! Loop subdivision (Loop 1987, "Smooth subdivision surfaces based on triangles"): the classical
//! linear baseline the paper compares its operator against (§1, §2, Fig. 1b, Fig. 3a).
//!
//! Each level splits every triangle in four at its edge midpoints and moves the nodes:
//! - new (odd) node on an interior edge (a, b) with opposite nodes c, d: 3/8 (a + b) + 1/8 (c + d);
//! - new node on a boundary edge: (a + b)/2;
//! - old (even) interior node of valence n: (1 − nβ) v + β Σ neighbours, Loop's
//!   β = (1/n) (5/8 − (3/8 + 1/4 cos 2π/n)²);
//! - old boundary node: 3/4 v + 1/8 (b₀ + b₁), b₀ and b₁ its neighbours along the boundary (the
//!   cubic B-spline rule for open edges, Hoppe et al. 1994, "Piecewise smooth surface
//!   reconstruction");
//! - corners stay put (Hoppe et al. 1994's corner rule): a boundary node whose boundary turns by
//!   more than `CORNER_TURN` in material space (a rectangle's corners), or that meets more than
//!   two boundary edges (non-manifold).
//!
//! Edges with more than two faces are treated as boundary (creases). Subdivision is linear in the
//! coarse positions for a fixed topology, so all levels are composed into one sparse operator S,
//! p_loop = S p_c, built once and applied per frame like U (and at about its cost). Material
//! coordinates are split linearly (midpoints), so textures stay put.

use std::collections::HashMap;

use super::{Surface, UpsampleError};
use crate::math::{cross2, Real, Vec2, Vec3};

/// A boundary node whose two boundary edges turn by more than this (radians) in material space is
/// a corner and is interpolated: a rectangle's corners turn by π/2, a 12-gon's by π/6.
pub const CORNER_TURN: Real = std::f64::consts::FRAC_PI_4;
/// At most this many levels (4^L faces per coarse face).
pub const MAX_LEVELS: usize = 6;

/// The composed Loop operator S and the subdivided mesh.
#[derive(Clone, Debug)]
pub struct Subdivision {
    /// One sparse row per subdivided node: (coarse node, weight), ascending nodes, weights
    /// summing to one.
    pub rows: Vec<Vec<(usize, Real)>>,
    /// The subdivided surface (faces and per-corner material coordinates).
    pub surface: Surface,
    pub levels: usize,
}

impl Subdivision {
    /// `levels` levels of Loop subdivision of `coarse`.
    pub fn new(coarse: &Surface, levels: usize) -> Result<Subdivision, UpsampleError> {
        if coarse.faces.is_empty() {
            return Err(UpsampleError::Empty);
        }
        if levels > MAX_LEVELS {
            return Err(UpsampleError::TooManyLevels { levels, max: MAX_LEVELS });
        }
        let mut rows: Vec<Vec<(usize, Real)>> = (0..coarse.nodes).map(|i| vec![(i, 1.0)]).collect();
        let mut surface = coarse.clone();
        for _ in 0..levels {
            let (stencils, finer) = one_level(&surface);
            rows = stencils.iter().map(|s| compose(s, &rows)).collect();
            surface = finer;
        }
        Ok(Subdivision { rows, surface, levels })
    }

    /// S p_c.
    pub fn apply(&self, coarse: &[Vec3]) -> Vec<Vec3> {
        self.rows.iter().map(|r| r.iter().map(|&(j, w)| coarse[j] * w).sum()).collect()
    }
}

/// The level count L ≥ 1 whose face count 4^L · `coarse_faces` is nearest `fine_faces` in ratio.
pub fn levels_to_match(coarse_faces: usize, fine_faces: usize) -> usize {
    let gap = |l: usize| ((coarse_faces as Real * (4.0 as Real).powi(l as i32)) / fine_faces.max(1) as Real).ln().abs();
    (1..=MAX_LEVELS).min_by(|&a, &b| gap(a).total_cmp(&gap(b))).unwrap_or(1)
}

/// An edge of the current level: its faces and, per face, the node opposite it.
struct Edge {
    ends: (usize, usize),
    faces: Vec<(usize, usize)>,
}

/// One level: the stencil of every new node over the current nodes, and the finer surface.
/// Old nodes keep their ids; the node on edge e is `nodes + e` (edges in order of first use).
fn one_level(s: &Surface) -> (Vec<Vec<(usize, Real)>>, Surface) {
    let mut index: HashMap<(usize, usize), usize> = HashMap::new();
    let mut edges: Vec<Edge> = Vec::new();
    let mut face_edges = Vec::with_capacity(s.faces.len());
    for (f, t) in s.faces.iter().enumerate() {
        // Edge k of a face is opposite its corner k: (t[k+1], t[k+2]).
        face_edges.push([0, 1, 2].map(|k| {
            let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            let e = *index.entry((a.min(b), a.max(b))).or_insert_with(|| {
                edges.push(Edge { ends: (a.min(b), a.max(b)), faces: Vec::new() });
                edges.len() - 1
            });
            edges[e].faces.push((f, t[k]));
            e
        }));
    }
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); s.nodes];
    let mut boundary: Vec<Vec<(usize, usize)>> = vec![Vec::new(); s.nodes]; // (other end, face)
    for e in &edges {
        let (a, b) = e.ends;
        neighbours[a].push(b);
        neighbours[b].push(a);
        if e.faces.len() != 2 {
            boundary[a].push((b, e.faces[0].0));
            boundary[b].push((a, e.faces[0].0));
        }
    }
    let mut stencils: Vec<Vec<(usize, Real)>> =
        (0..s.nodes).map(|v| even(s, v, &neighbours[v], &boundary[v])).collect();
    for e in &edges {
        let (a, b) = e.ends;
        stencils.push(match e.faces[..] {
            [(_, c), (_, d)] => vec![(a, 0.375), (b, 0.375), (c, 0.125), (d, 0.125)],
            _ => vec![(a, 0.5), (b, 0.5)],
        });
    }
    let mut faces = Vec::with_capacity(4 * s.faces.len());
    let mut uv = Vec::with_capacity(4 * s.faces.len());
    for (f, t) in s.faces.iter().enumerate() {
        let w = s.uv[f];
        // Midpoint of edge k (opposite corner k), node and material coordinate.
        let m = [0, 1, 2].map(|k| s.nodes + face_edges[f][k]);
        let mu = [0, 1, 2].map(|k| (w[(k + 1) % 3] + w[(k + 2) % 3]) * 0.5);
        faces.extend([[t[0], m[2], m[1]], [m[2], t[1], m[0]], [m[1], m[0], t[2]], [m[0], m[1], m[2]]]);
        uv.extend([[w[0], mu[2], mu[1]], [mu[2], w[1], mu[0]], [mu[1], mu[0], w[2]], [mu[0], mu[1], mu[2]]]);
    }
    (stencils, Surface { nodes: s.nodes + edges.len(), faces, uv })
}

/// The stencil of old node `v` (module doc: interior, boundary or corner rule).
fn even(s: &Surface, v: usize, neighbours: &[usize], boundary: &[(usize, usize)]) -> Vec<(usize, Real)> {
    if neighbours.is_empty() {
        return vec![(v, 1.0)];
    }
    match boundary {
        [] => {
            let n = neighbours.len() as Real;
            let c = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / n).cos();
            let beta = (0.625 - c * c) / n;
            let mut st = vec![(v, 1.0 - n * beta)];
            st.extend(neighbours.iter().map(|&u| (u, beta)));
            st
        }
        [(b0, f0), (b1, f1)] if turn(s, v, (*b0, *f0), (*b1, *f1)) <= CORNER_TURN => {
            vec![(v, 0.75), (*b0, 0.125), (*b1, 0.125)]
        }
        _ => vec![(v, 1.0)],
    }
}

/// The angle (radians, 0 for a straight boundary) between boundary edges (b₀, v) and (v, b₁),
/// each measured in material space in the face it bounds.
fn turn(s: &Surface, v: usize, (b0, f0): (usize, usize), (b1, f1): (usize, usize)) -> Real {
    let at = |f: usize, node: usize| -> Option<Vec2> { (0..3).find(|&k| s.faces[f][k] == node).map(|k| s.uv[f][k]) };
    let (Some(p0), Some(v0), Some(v1), Some(p1)) = (at(f0, b0), at(f0, v), at(f1, v), at(f1, b1)) else {
        return Real::INFINITY;
    };
    let (d0, d1) = (v0 - p0, p1 - v1);
    cross2(&d0, &d1).atan2(d0.dot(&d1)).abs()
}

/// Σ_k w_k · rows[k], as one sorted sparse row (merging equal coarse nodes).
fn compose(stencil: &[(usize, Real)], rows: &[Vec<(usize, Real)>]) -> Vec<(usize, Real)> {
    let mut out: Vec<(usize, Real)> =
        stencil.iter().flat_map(|&(k, w)| rows[k].iter().map(move |&(j, x)| (j, w * x))).collect();
    out.sort_by_key(|e| e.0);
    let mut merged: Vec<(usize, Real)> = Vec::with_capacity(out.len());
    for (j, x) in out {
        match merged.last_mut() {
            Some(last) if last.0 == j => last.1 += x,
            _ => merged.push((j, x)),
        }
    }
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_sum_to_one_and_faces_quadruple() {
        let s = Surface::grid(3, 2, 1.5, 1.0);
        let sub = Subdivision::new(&s, 2).unwrap();
        assert_eq!(sub.surface.faces.len(), 16 * s.faces.len());
        // (3·4 + 1) × (2·4 + 1) nodes: each level splits every cell's edges once.
        assert_eq!(sub.rows.len(), 13 * 9);
        for r in &sub.rows {
            assert!((r.iter().map(|e| e.1).sum::<Real>() - 1.0).abs() < 1e-12);
        }
        assert!(sub.surface.faces.iter().enumerate().all(|(f, _)| sub.surface.area(f) > 0.0), "orientation kept");
        let area: Real = (0..sub.surface.faces.len()).map(|f| sub.surface.area(f)).sum();
        assert!((area - 1.5).abs() < 1e-12, "material area {area}");
    }

    /// On a flat grid Loop reproduces the plane and its linear functions (affine invariance), and
    /// keeps the corners where they are.
    #[test]
    fn a_linear_field_is_reproduced_and_corners_stay() {
        let s = Surface::grid(4, 4, 1.0, 1.0);
        let sub = Subdivision::new(&s, 2).unwrap();
        let f = |p: Vec2| Vec3::new(p.x, p.y, 0.3 * p.x - 0.7 * p.y + 0.1);
        let pc: Vec<Vec3> = s.node_uv().iter().map(|p| f(p.unwrap())).collect();
        let out = sub.apply(&pc);
        for (x, p) in out.iter().zip(sub.surface.node_uv()) {
            assert!((x - f(p.unwrap())).norm() < 1e-12, "{x} vs {}", f(p.unwrap()));
        }
        for corner in [0, 4, 20, 24] {
            assert_eq!(sub.rows[corner], vec![(corner, 1.0)]);
        }
    }

    /// A hand-checked level: the interior node of valence 6 of a 2×2 grid and an edge node.
    #[test]
    fn stencils_match_loop_1987() {
        let s = Surface::grid(2, 2, 1.0, 1.0);
        let sub = Subdivision::new(&s, 1).unwrap();
        // Node 4 is the centre, valence 6: β = (5/8 − (3/8 + 1/4 cos 60°)²)/6 = 1/16.
        let centre = &sub.rows[4];
        assert_eq!(centre.len(), 7);
        assert!(centre.iter().all(|&(j, w)| (w - if j == 4 { 0.625 } else { 0.0625 }).abs() < 1e-15), "{centre:?}");
        // Node 1, bottom edge midpoint (not a corner): 3/4 v + 1/8 (0 + 2).
        assert_eq!(sub.rows[1], vec![(0, 0.125), (1, 0.75), (2, 0.125)]);
        // An interior edge node has four weights, 3/8, 3/8, 1/8, 1/8.
        let mut w: Vec<Real> = sub.rows.iter().find(|r| r.len() == 4).unwrap().iter().map(|e| e.1).collect();
        w.sort_by(Real::total_cmp);
        assert_eq!(w, [0.125, 0.125, 0.375, 0.375]);
    }

    /// A bumped sheet shrinks under Loop (it approximates, it does not interpolate): the peak of
    /// a single raised interior node drops to 5/8 after one level.
    #[test]
    fn loop_approximates_rather_than_interpolates() {
        let s = Surface::grid(2, 2, 1.0, 1.0);
        let mut pc: Vec<Vec3> = s.node_uv().iter().map(|p| Vec3::new(p.unwrap().x, p.unwrap().y, 0.0)).collect();
        pc[4].z = 1.0;
        let out = Subdivision::new(&s, 1).unwrap().apply(&pc);
        assert!((out[4].z - 0.625).abs() < 1e-15);
    }

    #[test]
    fn levels_match_face_counts() {
        assert_eq!(levels_to_match(72, 1152), 2);
        assert_eq!(levels_to_match(72, 1000), 2);
        assert_eq!(levels_to_match(72, 5000), 3);
        assert_eq!(levels_to_match(72, 10), 1);
        assert!(matches!(
            Subdivision::new(&Surface::grid(1, 1, 1.0, 1.0), 7),
            Err(UpsampleError::TooManyLevels { levels: 7, max: 6 })
        ));
    }
}
