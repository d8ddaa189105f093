//! Where cloth has passed through itself, which parts are on the wrong side (Baraff, Witkin &
//! Kass 2003, "Untangling Cloth", ACM TOG 22(3), §3 "Global intersection analysis").
//!
//! Collision handling keeps cloth from *passing* through cloth; it cannot take back a crossing
//! that is already there. Cloth held in a pinch between two body parts goes through the body and
//! can go through itself there (an armpit: the side of a dress between the arm and the torso), a
//! remesh can leave a crossing, and a crossing once made is kept by the very contacts and
//! impacts that should have prevented it: they push the pierced cloth back to the side it is
//! on. BWK03's analysis: the curve along which two parts of the cloth cross cuts the mesh edges
//! that pass through the other part. Cut along those edges, a closed curve encloses a region of
//! the mesh: the part that went through. Of each connected cloth the largest piece left after
//! the cuts is taken to be on the right side (BWK03 take the smaller of the two sides of a
//! curve as the one in error); every other piece a cut touches is a *region* in error.
//!
//! The analysis gives each region the faces it passes through and, for each of its nodes at a
//! cut edge, the way back: along the pierced face's normal to the side the edge's other end (in
//! the right-side piece) is on, far enough to pass the face's plane by `margin`. Nodes inside a
//! region, with no cut edge, take the mean of the region's moves. The response is the caller's
//! (`sim::untangle`): it moves the nodes and, for the step, exempts each region from collisions
//! with the faces it passes through, so that they can come back through (BWK03 reverse the
//! repulsion between such pairs instead; a bounded move does the same without storing energy).
//!
//! A curve that cuts off nothing is not closed on the cloth: it ends on the cloth's boundary or
//! at a node where the cloth folds onto itself (a node both layers share: the faces around it
//! are skipped by the crossing test, adjacent faces always touch). BWK03 call these boundary
//! intersections and resolve them from history. Here, where such crossings are few (at most
//! `LOCAL_CUTS` edge–face piercings in a cluster), they are taken back locally
//! (`local_moves`): the cluster's crossing faces fall into two layers, and one layer's piercing
//! edges each move their end nearer the pierced face's plane to the other end's side, the
//! smaller move that ends the piercing (Volino & Magnenat-Thalmann 2006 shorten the
//! intersection contour on the same principle). The layer that moves is the one with a
//! boundary node among those ends (a hem poked through the fold beside it: `dress_dance`'s
//! armpit), else the one with the smaller moves. More piercings: a sheet through a sheet along
//! a line, where moving the nodes at the line only moves the line; nothing is done, nor where a
//! cut piece holds more than a quarter of its cloth (size does not tell which side is wrong).
//! Everything is a function of the positions and the sorted crossing list: the same on any
//! thread count.

use std::collections::BTreeMap;

use super::crossings::orient;
use crate::math::{Real, Vec3};
use crate::mesh::Mesh;

/// What the analysis found: the regions in error and how each of their nodes gets back.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tangle {
    /// The nodes of each region, sorted; regions in order of their first node.
    pub regions: Vec<Vec<usize>>,
    /// Per region, the nodes of the faces it passes through (sorted): its collisions with these
    /// are off while it comes back.
    pub pierced: Vec<Vec<usize>>,
    /// (node, displacement) that takes each region node back through, in node order.
    pub moves: Vec<(usize, Vec3)>,
}

impl Tangle {
    pub fn is_empty(&self) -> bool {
        self.regions.is_empty()
    }

    /// Per node: the bit of every region it belongs to, and of every region whose pierced
    /// faces it is a node of (region k has bit k mod 64; more regions share bits, which exempts
    /// more pairs, never fewer).
    pub fn masks(&self, nodes: usize) -> Vec<(u64, u64)> {
        let mut out = vec![(0u64, 0u64); nodes];
        for (k, (region, pierced)) in self.regions.iter().zip(&self.pierced).enumerate() {
            let bit = 1u64 << (k % 64);
            region.iter().for_each(|&i| out[i].0 |= bit);
            pierced.iter().for_each(|&i| out[i].1 |= bit);
        }
        out
    }
}

/// Whether a cloth–cloth pair (`VF` = `[p, a, b, c]` when `vertex_face`, else `[a0, a1, b0, b1]`)
/// joins a region to a face it passes through (`Tangle::masks`; empty: none).
pub fn exempt_pair(masks: &[(u64, u64)], vertex_face: bool, nodes: &[usize; 4]) -> bool {
    if masks.is_empty() || nodes.iter().any(|&i| i >= masks.len()) {
        return false;
    }
    let split = if vertex_face { 1 } else { 2 };
    let side = |ids: &[usize]| ids.iter().fold((0u64, 0u64), |(r, p), &i| (r | masks[i].0, p | masks[i].1));
    let (a, b) = (side(&nodes[..split]), side(&nodes[split..]));
    (a.0 & b.1) | (b.0 & a.1) != 0
}

/// Whether the open segment pq passes through the open triangle t (exact; a segment touching
/// the triangle's plane or boundary does not).
pub fn edge_through(p: &Vec3, q: &Vec3, t: &[Vec3; 3]) -> bool {
    let (sp, sq) = (orient(&t[0], &t[1], &t[2], p), orient(&t[0], &t[1], &t[2], q));
    if sp * sq >= 0 {
        return false;
    }
    let s = [0, 1, 2].map(|k| orient(p, q, &t[k], &t[(k + 1) % 3]));
    s.iter().all(|&v| v > 0) || s.iter().all(|&v| v < 0)
}

/// The most edge–face piercings a cluster of crossings that cuts off no region may have to be
/// taken back by `local_moves`: beyond it, a sheet through a sheet along a line, where moving the
/// nodes at the line would only move the line.
pub const LOCAL_CUTS: usize = 12;

/// Union–find over the nodes.
struct Sets(Vec<usize>);

impl Sets {
    fn new(n: usize) -> Self {
        Sets((0..n).collect())
    }
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    /// Joins the sets of a and b under the smaller root (so roots do not depend on order).
    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            self.0[hi] = lo;
        }
    }
}

/// The global intersection analysis of `mesh` at positions `x` for its crossing triangle pairs
/// `crossing` (`crossings::find_crossings`' cloth list): see the module doc. `margin` is how far
/// past a pierced face's plane a node is taken.
pub fn analyse(mesh: &Mesh, x: &[Vec3], crossing: &[(usize, usize)], margin: Real) -> Tangle {
    let n = mesh.nodes.len();
    if crossing.is_empty() || n == 0 {
        return Tangle::default();
    }
    let corners = |f: usize| mesh.face_nodes(f).map(|i| x[i]);
    // Cut edges (sorted node pairs), each with the faces it passes through.
    let mut cut: BTreeMap<[usize; 2], Vec<usize>> = BTreeMap::new();
    for &(f, g) in crossing {
        for (a, b) in [(f, g), (g, f)] {
            let (ids, tri) = (mesh.face_nodes(a), corners(b));
            for k in 0..3 {
                let (p, q) = (ids[k], ids[(k + 1) % 3]);
                if edge_through(&x[p], &x[q], &tri) {
                    let faces = cut.entry([p.min(q), p.max(q)]).or_default();
                    if !faces.contains(&b) {
                        faces.push(b);
                    }
                }
            }
        }
    }
    if cut.is_empty() {
        return Tangle::default();
    }
    let (mut whole, mut pieces) = (Sets::new(n), Sets::new(n));
    for e in &mesh.edges {
        let (a, b) = (e.n[0].idx(), e.n[1].idx());
        whole.join(a, b);
        if !cut.contains_key(&[a.min(b), a.max(b)]) {
            pieces.join(a, b);
        }
    }
    let piece: Vec<usize> = (0..n).map(|i| pieces.find(i)).collect();
    let cloth: Vec<usize> = (0..n).map(|i| whole.find(i)).collect();
    let mut size = vec![0usize; n];
    piece.iter().for_each(|&r| size[r] += 1);
    // The right-side piece of each cloth: the largest (ties: the one with the lowest node).
    let mut main: BTreeMap<usize, usize> = BTreeMap::new();
    for i in 0..n {
        let r = piece[i];
        let best = main.entry(cloth[i]).or_insert(r);
        if size[r] > size[*best] {
            *best = r;
        }
    }
    let right = |i: usize| main[&cloth[i]] == piece[i];
    // Each cut edge with one end on the right side and the other in a region: the region end's
    // way back through each face the edge passes through.
    let mut way: BTreeMap<usize, (Vec3, Real)> = BTreeMap::new();
    let mut region_faces: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (&[a, b], faces) in &cut {
        let (u, v) = match (right(a), right(b)) {
            (false, true) => (a, b),
            (true, false) => (b, a),
            _ => continue,
        };
        for &g in faces {
            let t = corners(g);
            let Some(normal) = (t[1] - t[0]).cross(&(t[2] - t[0])).try_normalize(0.0) else { continue };
            let side = Real::from(orient(&t[0], &t[1], &t[2], &x[v]));
            let dir = normal * side;
            let need = margin - dir.dot(&(x[u] - t[0]));
            if need <= 0.0 {
                continue;
            }
            let w = way.entry(u).or_insert((Vec3::zeros(), 0.0));
            w.0 += dir;
            w.1 = w.1.max(need);
            region_faces.entry(piece[u]).or_default().push(g);
        }
    }
    let mut tangle = Tangle::default();
    let mut moves: Vec<Option<Vec3>> = vec![None; n];
    let mut cloth_size = vec![0usize; n];
    cloth.iter().for_each(|&r| cloth_size[r] += 1);
    for (&root, faces) in &region_faces {
        let region: Vec<usize> = (0..n).filter(|&i| piece[i] == root).collect();
        // More than a quarter of its cloth: a sheet through a sheet, not a part poked through;
        // which side is in error is not told by size (BWK03's boundary curves).
        if 4 * region.len() > cloth_size[cloth[region[0]]] {
            continue;
        }
        let edge_moves: Vec<Vec3> = region
            .iter()
            .filter_map(|i| way.get(i))
            .filter_map(|(dir, need)| dir.try_normalize(0.0).map(|d| d * *need))
            .collect();
        if edge_moves.is_empty() {
            continue;
        }
        let mean = edge_moves.iter().sum::<Vec3>() / edge_moves.len() as Real;
        for &i in &region {
            moves[i] = Some(match way.get(&i).and_then(|(dir, need)| dir.try_normalize(0.0).map(|d| d * *need)) {
                Some(d) => d,
                None => mean,
            });
        }
        let mut pierced: Vec<usize> = faces.iter().flat_map(|&g| mesh.face_nodes(g)).collect();
        pierced.sort_unstable();
        pierced.dedup();
        tangle.regions.push(region);
        tangle.pierced.push(pierced);
    }
    local_moves(mesh, x, crossing, margin, &mut tangle, &mut moves);
    tangle.moves = moves.into_iter().enumerate().filter_map(|(i, d)| d.map(|d| (i, d))).collect();
    tangle
}

/// The crossings that cut off no region (the curve ends on the cloth's boundary, or at a node
/// where the cloth folds onto itself: a hem's tip through the fold beside it), in clusters of
/// at most `LOCAL_CUTS` edge–face piercings: the crossing faces of a cluster fall into two
/// layers (each pair one of each; a cluster that does not is left), and one layer goes back:
/// for each of its edges through a face of the other, the end nearer that face's plane goes to
/// the other end's side (the smaller move that ends the piercing). The layer that goes back is
/// the one whose moved nodes include a boundary node (a hem poked through), else the one with
/// the smaller moves (a layer none of whose edges pierces the other stays). Each cluster is one
/// region: its moved nodes, exempt from the other layer's faces.
fn local_moves(
    mesh: &Mesh,
    x: &[Vec3],
    crossing: &[(usize, usize)],
    margin: Real,
    tangle: &mut Tangle,
    moves: &mut [Option<Vec3>],
) {
    let corners = |f: usize| mesh.face_nodes(f).map(|i| x[i]);
    let mut boundary = vec![false; x.len()];
    for e in &mesh.edges {
        if e.adj.0.iter().filter(|f| f.is_some()).count() < 2 {
            e.n.iter().for_each(|i| boundary[i.idx()] = true);
        }
    }
    let mut partners: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for &(f, g) in crossing {
        partners.entry(f).or_default().push(g);
        partners.entry(g).or_default().push(f);
    }
    let mut layer: BTreeMap<usize, u8> = BTreeMap::new();
    for &start in partners.keys() {
        if layer.contains_key(&start) {
            continue;
        }
        layer.insert(start, 0);
        let (mut cluster, mut two_layers, mut k) = (vec![start], true, 0);
        while k < cluster.len() {
            let f = cluster[k];
            k += 1;
            for &g in &partners[&f] {
                match layer.get(&g) {
                    None => {
                        layer.insert(g, 1 - layer[&f]);
                        cluster.push(g);
                    }
                    Some(&c) => two_layers &= c != layer[&f],
                }
            }
        }
        if !two_layers {
            continue;
        }
        // Per layer: (node, direction sum, largest need) of its edges' nearer ends, whether a
        // boundary node is among them, and the sum of the needs.
        let mut plans: [(BTreeMap<usize, (Vec3, Real)>, bool, Real, usize); 2] = Default::default();
        for &f in &cluster {
            let plan = &mut plans[layer[&f] as usize];
            let ids = mesh.face_nodes(f);
            for &g in &partners[&f] {
                let t = corners(g);
                let Some(normal) = (t[1] - t[0]).cross(&(t[2] - t[0])).try_normalize(0.0) else { continue };
                for k in 0..3 {
                    let (a, b) = (ids[k], ids[(k + 1) % 3]);
                    if !edge_through(&x[a], &x[b], &t) {
                        continue;
                    }
                    plan.3 += 1;
                    let depth = |i: usize| normal.dot(&(x[i] - t[0])).abs();
                    let (u, v) = if depth(b) < depth(a) { (b, a) } else { (a, b) };
                    let dir = normal * Real::from(orient(&t[0], &t[1], &t[2], &x[v]));
                    let need = margin - dir.dot(&(x[u] - t[0]));
                    let w = plan.0.entry(u).or_insert((Vec3::zeros(), 0.0));
                    w.0 += dir;
                    w.1 = w.1.max(need);
                    plan.1 |= boundary[u];
                }
            }
            plan.2 = plan.0.values().map(|w| w.1).sum();
        }
        let piercings = plans[0].3 + plans[1].3;
        let taken = plans.iter().flat_map(|p| p.0.keys()).any(|&i| moves[i].is_some());
        if piercings == 0 || piercings > LOCAL_CUTS || taken {
            continue;
        }
        let pick = match (plans[0].1, plans[1].1) {
            _ if plans[0].0.is_empty() => 1,
            _ if plans[1].0.is_empty() => 0,
            (true, false) => 0,
            (false, true) => 1,
            _ => usize::from(plans[1].2 < plans[0].2),
        };
        let mut region = Vec::new();
        for (&u, (dir, need)) in &plans[pick].0 {
            if let Some(d) = dir.try_normalize(0.0).filter(|_| *need > 0.0) {
                moves[u] = Some(d * *need);
                region.push(u);
            }
        }
        if region.is_empty() {
            continue;
        }
        let mut pierced: Vec<usize> =
            cluster.iter().filter(|f| layer[f] as usize != pick).flat_map(|&g| mesh.face_nodes(g)).collect();
        pierced.sort_unstable();
        pierced.dedup();
        tangle.regions.push(region);
        tangle.pierced.push(pierced);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::crossings::{find_self_crossings, Soup};
    use crate::mesh::{rectangle, NodeId, VertId};

    /// Two flat sheets, one 1 cm above the other, with one interior node of the upper one
    /// pushed 5 mm below the lower one: its fan of faces crosses the lower sheet.
    fn poked() -> (Mesh, Vec<Vec3>, usize) {
        let mut mesh = rectangle(1.0, 1.0, 6, 6).unwrap();
        let (nv, nn, nf) = (mesh.verts.len(), mesh.nodes.len(), mesh.faces.len());
        // The upper sheet offset so that no node lies over a lower node or edge.
        for k in 0..nn {
            let mut node = mesh.nodes[k].clone();
            node.x += Vec3::new(0.031, 0.017, 0.01);
            mesh.nodes.push(node);
        }
        for k in 0..nv {
            let mut v = mesh.verts[k].clone();
            v.node = NodeId((v.node.idx() + nn) as u32);
            mesh.verts.push(v);
        }
        for k in 0..nf {
            let mut f = mesh.faces[k].clone();
            f.v = f.v.map(|v| VertId((v.idx() + nv) as u32));
            mesh.faces.push(f);
        }
        mesh.rebuild_topology().unwrap();
        let centre = nn + 3 * 7 + 3;
        let mut x = mesh.positions();
        x[centre].z = -0.005;
        (mesh, x, centre)
    }

    fn crossings(mesh: &Mesh, x: &[Vec3]) -> Vec<(usize, usize)> {
        let tris: Vec<[usize; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).collect();
        find_self_crossings(Soup { x, tris: &tris })
    }

    #[test]
    fn a_node_through_another_sheet_and_the_node_it_encloses_are_regions() {
        let (mesh, x, centre) = poked();
        let crossing = crossings(&mesh, &x);
        assert!(!crossing.is_empty());
        let t = analyse(&mesh, &x, &crossing, 0.001);
        // The poked node, below the lower sheet; and the lower sheet's node (3, 3), 3.6 cm from
        // it, which the poked fan's curve on the lower sheet encloses: it is above the fan.
        let below = 3 * 7 + 3;
        assert_eq!(t.regions, vec![vec![below], vec![centre]]);
        let moved: BTreeMap<usize, Vec3> = t.moves.iter().copied().collect();
        assert_eq!(moved.len(), 2);
        // Up through the lower sheet (z = 0), 1 mm past it; the other down through the fan.
        assert!((moved[&centre] - Vec3::new(0.0, 0.0, 0.006)).norm() < 1e-12, "{}", moved[&centre]);
        assert!(moved[&below].z < -0.001, "{}", moved[&below]);
        // The poked node's move alone, or both, leave the sheets uncrossed.
        let mut y = x.clone();
        y[centre] += moved[&centre];
        assert!(crossings(&mesh, &y).is_empty());
        y[below] += moved[&below];
        assert!(crossings(&mesh, &y).is_empty());
        // The poked node is exempt from the faces it passed through, nothing else.
        let masks = t.masks(mesh.nodes.len());
        let k = t.regions.iter().position(|r| r.contains(&centre)).unwrap();
        let pierced = &t.pierced[k];
        let face =
            (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).find(|f| f.iter().all(|i| pierced.contains(i))).unwrap();
        assert!(exempt_pair(&masks, true, &[centre, face[0], face[1], face[2]]));
        let far = mesh.face_nodes(0);
        assert!(!exempt_pair(&masks, true, &[centre, far[0], far[1], far[2]]));
        assert!(!exempt_pair(&[], true, &[centre, face[0], face[1], face[2]]));
    }

    #[test]
    fn a_sheet_through_a_sheet_to_its_edge_cuts_off_nothing() {
        // The upper sheet tilted so that one edge row dips through the lower sheet: the curve
        // runs from boundary to boundary of both, no region.
        let (mesh, mut x, _) = poked();
        let base = 49; // the upper sheet's first node
        for p in &mut x[base..] {
            p.z = 0.01 - 0.03 * p.x.max(0.0) + 0.001;
        }
        let crossing = crossings(&mesh, &x);
        assert!(!crossing.is_empty());
        let t = analyse(&mesh, &x, &crossing, 0.001);
        assert!(t.is_empty(), "{:?}", t.regions);
    }

    /// A strip folded back over itself about its middle column (x = 0.2), the upper layer 6 mm
    /// above the lower, shifted 2.5 cm along y, and the upper node beside the fold at the middle
    /// row pushed 1 mm through the lower layer. Its edges to the fold column end on the lower
    /// layer and pierce nothing, so the crossing curve cuts off no region: the fold case.
    fn folded() -> (Mesh, Vec<Vec3>, usize) {
        let mesh = rectangle(0.4, 0.2, 8, 4).unwrap();
        let x: Vec<Vec3> = mesh
            .positions()
            .iter()
            .map(|p| match p.x <= 0.2 + 1e-9 {
                true => *p,
                false => Vec3::new(0.2 - 0.8 * (p.x - 0.2), p.y + 0.025, 0.006),
            })
            .collect();
        let poked = 2 * 9 + 5;
        let mut x = x;
        x[poked].z = -0.001;
        (mesh, x, poked)
    }

    #[test]
    fn a_node_beside_a_fold_through_the_layer_below_goes_back_alone() {
        let (mesh, x, poked) = folded();
        let crossing = crossings(&mesh, &x);
        assert!(!crossing.is_empty());
        let t = analyse(&mesh, &x, &crossing, 0.001);
        let moved: BTreeMap<usize, Vec3> = t.moves.iter().copied().collect();
        assert_eq!(moved.keys().copied().collect::<Vec<_>>(), vec![poked], "{:?}", t.regions);
        // Up through the lower layer (z = 0), 1 mm past it.
        assert!((moved[&poked] - Vec3::new(0.0, 0.0, 0.002)).norm() < 1e-12, "{}", moved[&poked]);
        let mut y = x.clone();
        y[poked] += moved[&poked];
        assert!(crossings(&mesh, &y).is_empty());
    }

    #[test]
    fn no_crossing_no_tangle() {
        let (mesh, mut x, centre) = poked();
        x[centre].z = 0.01;
        assert!(analyse(&mesh, &x, &crossings(&mesh, &x), 0.001).is_empty());
    }
}
