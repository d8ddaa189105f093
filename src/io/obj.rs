//! Wavefront OBJ: reading meshes (positions, texture coordinates, polygon faces) and writing
//! frames.
//!
//! The reader is our own rather than tobj's: tobj renumbers vertices by first use, and node
//! indices must stay in file order (handles name them, as ARCSim scenes do), and errors must
//! name the line. Unknown statements (`vn`, `o`, `g`, `s`, `usemtl`, ARCSim's `vv`…) are skipped.

use std::fmt::Write as _;
use std::path::Path;

use crate::math::{Vec2, Vec3};
use crate::mesh::Mesh;

/// One corner of a face: 0-based position index and optional texture-coordinate index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Corner {
    pub v: usize,
    pub vt: Option<usize>,
}

/// The contents of an OBJ file, in file order. Polygons are fan-triangulated; `face_line` gives
/// the 1-based source line of each triangle.
#[derive(Clone, Debug, Default)]
pub struct ObjData {
    pub positions: Vec<Vec3>,
    pub texcoords: Vec<Vec2>,
    pub triangles: Vec<[Corner; 3]>,
    pub face_line: Vec<usize>,
    pub position_line: Vec<usize>,
    /// ARCSim's labelled edges (`e a b` followed by `el L`, L ≠ 0): creases the remesher keeps
    /// as edges (`remesh`).
    pub labelled_edges: Vec<LabelledEdge>,
}

/// An edge the file labels (ARCSim's `e` and `el` statements): 0-based position indices, the
/// label and the 1-based line of its `e`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LabelledEdge {
    pub n: [usize; 2],
    pub label: u32,
    pub line: usize,
}

/// A parse error: line number (1-based, 0 when it concerns the whole file) and message.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjError {
    pub line: usize,
    pub msg: String,
}

fn err(line: usize, msg: impl Into<String>) -> ObjError {
    ObjError { line, msg: msg.into() }
}

fn parse_floats<const N: usize>(words: &[&str], line: usize, what: &str) -> Result<[f64; N], ObjError> {
    if words.len() < N {
        return Err(err(line, format!("'{what}' needs {N} numbers, found {}", words.len())));
    }
    let mut out = [0.0; N];
    for (o, w) in out.iter_mut().zip(words) {
        let x: f64 = w.parse().map_err(|_| err(line, format!("'{what}': expected a number, found '{w}'")))?;
        if !x.is_finite() {
            return Err(err(line, format!("'{what}': coordinate is not finite ('{w}')")));
        }
        *o = x;
    }
    Ok(out)
}

/// Resolves a 1-based (or negative, relative) OBJ index against `count` elements seen so far.
/// `stmt` names the statement (`face`, `e`) in errors.
fn resolve_index(word: &str, count: usize, line: usize, stmt: &str, what: &str) -> Result<usize, ObjError> {
    let i: i64 = word.parse().map_err(|_| err(line, format!("{stmt}: bad {what} index '{word}'")))?;
    let idx = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || idx < 0 || idx >= count as i64 {
        return Err(err(line, format!("{stmt}: {what} index {i} out of range (1..={count})")));
    }
    Ok(idx as usize)
}

pub fn parse_obj(text: &str) -> Result<ObjData, ObjError> {
    let mut d = ObjData::default();
    // The last `e` statement, which an `el` labels (ARCSim labels `mesh.edges.back()`).
    let mut last_edge: Option<LabelledEdge> = None;
    for (ln, raw) in text.lines().enumerate() {
        let line = ln + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut words = content.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let rest: Vec<&str> = words.collect();
        match tag {
            "v" => {
                let [x, y, z] = parse_floats::<3>(&rest, line, "v")?;
                d.positions.push(Vec3::new(x, y, z));
                d.position_line.push(line);
            }
            "vt" => {
                let [u, v] = parse_floats::<2>(&rest, line, "vt")?;
                d.texcoords.push(Vec2::new(u, v));
            }
            "f" => {
                if rest.len() < 3 {
                    return Err(err(line, format!("face needs at least 3 corners, found {}", rest.len())));
                }
                let mut corners = Vec::with_capacity(rest.len());
                for w in &rest {
                    let mut parts = w.split('/');
                    let v = resolve_index(parts.next().unwrap_or(""), d.positions.len(), line, "face", "vertex")?;
                    let vt = match parts.next() {
                        Some(s) if !s.is_empty() => Some(resolve_index(s, d.texcoords.len(), line, "face", "texture")?),
                        _ => None,
                    };
                    corners.push(Corner { v, vt });
                }
                if corners.iter().any(|c| c.vt.is_some()) != corners.iter().all(|c| c.vt.is_some()) {
                    return Err(err(line, "face mixes corners with and without texture coordinates"));
                }
                for k in 1..corners.len() - 1 {
                    d.triangles.push([corners[0], corners[k], corners[k + 1]]);
                    d.face_line.push(line);
                }
            }
            "e" => {
                if rest.len() != 2 {
                    return Err(err(line, format!("'e' needs 2 vertex indices, found {}", rest.len())));
                }
                let a = resolve_index(rest[0], d.positions.len(), line, "e", "vertex")?;
                let b = resolve_index(rest[1], d.positions.len(), line, "e", "vertex")?;
                if a == b {
                    return Err(err(line, format!("'e' joins vertex {} to itself", a + 1)));
                }
                last_edge = Some(LabelledEdge { n: [a, b], label: 0, line });
            }
            "el" => {
                let Some(mut e) = last_edge.take() else {
                    return Err(err(line, "'el' labels the edge of the 'e' line before it, and there is none"));
                };
                let [w] = rest[..] else {
                    return Err(err(line, format!("'el' needs 1 label, found {}", rest.len())));
                };
                e.label = w.parse().map_err(|_| err(line, format!("'el': expected a label ≥ 0, found '{w}'")))?;
                if e.label != 0 {
                    d.labelled_edges.push(e);
                }
            }
            _ => {}
        }
    }
    if d.triangles.is_empty() {
        return Err(err(0, "no faces (expected at least one 'f' line)"));
    }
    let with_vt = d.triangles.iter().filter(|t| t[0].vt.is_some()).count();
    if with_vt != 0 && with_vt != d.triangles.len() {
        let i = d.triangles.iter().position(|t| t[0].vt.is_none()).unwrap_or(0);
        return Err(err(d.face_line[i], "some faces have texture coordinates and others do not"));
    }
    Ok(d)
}

/// The OBJ text of one frame: `v` per node (world; followed by ARCSim's `nv` with its velocity
/// when `velocities`), `vt` per vert (in the input's texture units, so seams keep their
/// separate `vt`), `vn` per node, `f v/vt/vn`; one `o` group per cloth. Numbers print at fixed
/// precision (nanometres), so identical state gives identical bytes.
pub fn frame_obj(mesh: &Mesh, cloths: &[ClothOut], velocities: bool) -> String {
    let mut s = String::with_capacity(mesh.nodes.len() * if velocities { 130 } else { 80 } + mesh.faces.len() * 40);
    s.push_str("# viewcloth frame\n");
    for n in &mesh.nodes {
        let _ = writeln!(s, "v {:.9} {:.9} {:.9}", n.x.x, n.x.y, n.x.z);
        if velocities {
            let _ = writeln!(s, "nv {:.9} {:.9} {:.9}", n.v.x, n.v.y, n.v.z);
        }
    }
    for v in &mesh.verts {
        let uv = v.u / uv_unit(cloths, mesh.nodes[v.node.idx()].cloth);
        let _ = writeln!(s, "vt {:.9} {:.9}", uv.x, uv.y);
    }
    for n in mesh.node_normals() {
        let _ = writeln!(s, "vn {:.6} {:.6} {:.6}", n.x, n.y, n.z);
    }
    let mut current = None;
    for (f, face) in mesh.faces.iter().enumerate() {
        let cloth = mesh.nodes[mesh.node_of(face.v[0]).idx()].cloth as usize;
        if current != Some(cloth) {
            let name = cloths.get(cloth).map(|c| c.name.as_str()).unwrap_or("cloth");
            let _ = writeln!(s, "o {name}");
            current = Some(cloth);
        }
        let n = mesh.face_nodes(f);
        let _ = writeln!(
            s,
            "f {}/{}/{} {}/{}/{} {}/{}/{}",
            n[0] + 1,
            face.v[0].0 + 1,
            n[0] + 1,
            n[1] + 1,
            face.v[1].0 + 1,
            n[1] + 1,
            n[2] + 1,
            face.v[2].0 + 1,
            n[2] + 1
        );
    }
    s
}

/// What the output says of a cloth: its name and the material metres per texture unit.
#[derive(Clone, Debug)]
pub struct ClothOut {
    pub name: String,
    pub uv_unit: f64,
}

impl ClothOut {
    /// The scene's cloths.
    pub fn of(scene: &crate::scene::Scene) -> Vec<ClothOut> {
        scene.cloths.iter().map(|c| ClothOut { name: c.name.clone(), uv_unit: c.uv_unit }).collect()
    }
}

/// Material metres per texture unit of cloth `c` (1 when unknown).
pub fn uv_unit(cloths: &[ClothOut], c: u16) -> f64 {
    cloths.get(c as usize).map_or(1.0, |c| c.uv_unit)
}

/// The OBJ text of an obstacle's world-space triangle mesh.
pub fn obstacle_obj(x: &[Vec3], triangles: &[[usize; 3]]) -> String {
    let mut s = String::with_capacity(x.len() * 40 + triangles.len() * 24);
    s.push_str("# viewcloth obstacle\n");
    for p in x {
        let _ = writeln!(s, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
    }
    for t in triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// Reads and parses an OBJ file. The error says where in the file (`line N: …`) but not which
/// file: callers put the path in their `InputError`, so it is printed once.
pub fn read_obj(path: &Path) -> Result<ObjData, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read: {e}"))?;
    parse_obj(&text).map_err(|e| if e.line == 0 { e.msg } else { format!("line {}: {}", e.line, e.msg) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_polygons_negative_indices_and_skips_unknown() {
        let d = parse_obj("v 0 0 0\nvt 0 0 0\nvv 0 0 0\nv 1 0 0\nvt 1 0\nv 1 1 0\nvt 1 1\nv 0 1 0\nvt 0 1\nf -4/-4 -3/-3 -2/-2 -1/-1\n").unwrap();
        assert_eq!(d.positions.len(), 4);
        assert_eq!(d.triangles.len(), 2);
        assert_eq!(d.triangles[1][2], Corner { v: 3, vt: Some(3) });
        assert_eq!(d.face_line, vec![10, 10]);
    }

    #[test]
    fn reports_line_numbers() {
        assert_eq!(parse_obj("v 0 0 0\nv 1 nan 0\n").unwrap_err().line, 2);
        assert_eq!(parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 4\n").unwrap_err().line, 4);
        assert_eq!(parse_obj("v 0 0 0\n").unwrap_err().line, 0);
        assert!(parse_obj("v 0 0 inf\n").unwrap_err().msg.contains("finite"));
    }

    #[test]
    fn reads_arcsim_edge_labels() {
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
        // Labelled, unlabelled (no `el`, or `el 0`), and `ea`/`ed` skipped.
        let text = format!("{quad}e 1 3\nel 2\ne 1 2\ne 2 3\nea 0.5\nel 0\nf 1 2 3\nf 1 3 4\n");
        let d = parse_obj(&text).unwrap();
        assert_eq!(d.labelled_edges, vec![LabelledEdge { n: [0, 2], label: 2, line: 5 }]);
        let bad = |text: &str| parse_obj(&format!("{quad}{text}f 1 2 3\n")).unwrap_err();
        assert_eq!(bad("el 1\n").line, 5);
        assert!(bad("el 1\n").msg.contains("no"), "{}", bad("el 1\n").msg);
        assert!(bad("e 1 7\nel 1\n").msg.contains("out of range"));
        assert!(bad("e 1 1\n").msg.contains("itself"));
        assert!(bad("e 1 2\nel x\n").msg.contains("label"));
        assert_eq!(bad("e 1 2\nel 1\nel 1\n").line, 7);
    }
}
