//! Reading one frame's USD samples file back (`usd_samples/frame_NNNN.txt`, written by
//! `usd::frame_samples`): the meshes of a run written with `--format usd`, for `render`,
//! `compare` and `crossings`.
//!
//! The samples file, not the assembled `cloth.usda`, is read: it holds one frame, in a
//! line format of our own (`usd` module docs), and it is on disk as soon as its frame is, also
//! while a run is still going. Positions come back as the layer holds them (32-bit floats).

use std::path::Path;

use crate::math::Vec3;

/// One prim's mesh at the frame.
#[derive(Clone, Debug, Default)]
pub struct PrimMesh {
    pub prim: String,
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[usize; 3]>,
    /// Time-sampled `visibility` "invisible": an obstacle outside its time window.
    pub hidden: bool,
}

/// A frame's meshes: the cloths (`/World/cloth/…`), then the obstacles (`/World/obstacles/…`),
/// each in file order.
#[derive(Clone, Debug, Default)]
pub struct SampledFrame {
    pub cloths: Vec<PrimMesh>,
    pub obstacles: Vec<PrimMesh>,
}

/// Reads the samples file at `path`; the error names the line and what was wrong.
pub fn read_samples(path: &Path) -> Result<SampledFrame, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read: {e}"))?;
    let mut prims: Vec<PrimMesh> = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let bad = |msg: &str| format!("line {}: {msg}", k + 1);
        let mut parts = line.splitn(4, '\t');
        let (Some(prim), Some(_kind), Some(decl), Some(value)) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(bad("not a samples line (prim, kind, declaration, value)"));
        };
        if prims.last().is_none_or(|p| p.prim != prim) {
            prims.push(PrimMesh { prim: prim.to_string(), ..Default::default() });
        }
        let last = prims.len() - 1;
        let mesh = &mut prims[last];
        match decl {
            "point3f[] points" => {
                let c = numbers(value).map_err(|e| bad(&e))?;
                if c.len() % 3 != 0 {
                    return Err(bad("points: not a list of 3-vectors"));
                }
                mesh.positions = c.chunks(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
            }
            "int[] faceVertexIndices" => {
                let c = numbers(value).map_err(|e| bad(&e))?;
                if c.len() % 3 != 0 || c.iter().any(|&i| i < 0.0 || i.fract() != 0.0) {
                    return Err(bad("faceVertexIndices: not triangles of vertex indices"));
                }
                mesh.triangles = c.chunks(3).map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
            }
            "token visibility" => mesh.hidden = value.contains("invisible"),
            _ => {}
        }
    }
    let mut frame = SampledFrame::default();
    for mesh in prims.into_iter().filter(|m| !m.hidden) {
        if let Some(i) = mesh.triangles.iter().flatten().find(|&&i| i >= mesh.positions.len()) {
            return Err(format!("{}: vertex index {i} of {} points", mesh.prim, mesh.positions.len()));
        }
        if mesh.prim.starts_with("/World/cloth/") {
            frame.cloths.push(mesh);
        } else if mesh.prim.starts_with("/World/obstacles/") {
            frame.obstacles.push(mesh);
        }
    }
    if frame.cloths.is_empty() {
        return Err("no cloth prim (/World/cloth/…): not a viewcloth USD samples file".into());
    }
    Ok(frame)
}

/// The numbers of a USD array value such as `[(1, 2, 3), (4, 5, 6)]` or `[0, 1, 2]`.
fn numbers(value: &str) -> Result<Vec<f64>, String> {
    let inner =
        value.trim().strip_prefix('[').and_then(|v| v.strip_suffix(']')).ok_or_else(|| {
            format!("expected an array '[…]', found '{}'", value.chars().take(40).collect::<String>())
        })?;
    inner
        .split(|c: char| c == ',' || c == '(' || c == ')' || c.is_whitespace())
        .filter(|w| !w.is_empty())
        .map(|w| w.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| format!("'{w}' is not a finite number")))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::obj::ClothOut;
    use crate::io::usd::{frame_samples, ObstacleFrame};

    #[test]
    fn a_frames_samples_read_back_as_its_meshes() {
        let dir = std::env::temp_dir().join(format!("viewcloth_usd_samples_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut mesh = crate::mesh::rectangle(1.0, 1.0, 2, 1).unwrap();
        mesh.nodes[1].x.z = 0.125;
        let cloths = [ClothOut { name: "sheet".into(), uv_unit: 1.0 }];
        let tri = [[0, 1, 2]];
        let positions = vec![Vec3::zeros(), Vec3::x(), Vec3::y()];
        let o = ObstacleFrame {
            name: "ball",
            positions: positions.clone(),
            velocities: None,
            triangles: &tri,
            visible: None,
        };
        let path = dir.join("frame_0000.txt");
        std::fs::write(&path, frame_samples(&mesh, &cloths, &[o])).unwrap();
        let frame = read_samples(&path).unwrap();
        assert_eq!(frame.cloths.len(), 1);
        let c = &frame.cloths[0];
        assert_eq!(c.positions.len(), mesh.nodes.len());
        assert_eq!(c.positions[1], mesh.nodes[1].x);
        let faces: Vec<[usize; 3]> = (0..mesh.faces.len()).map(|f| mesh.face_nodes(f)).collect();
        assert_eq!(c.triangles, faces);
        assert_eq!(frame.obstacles[0].positions, positions);
        assert_eq!(frame.obstacles[0].triangles, tri);
        std::fs::write(&path, "/World/cloth/a\tt\tpoint3f[] points\t[(1, 2)]\n").unwrap();
        assert!(read_samples(&path).unwrap_err().contains("line 1"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
