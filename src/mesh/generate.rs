//! Generated meshes.

use super::{Face, Mesh, MeshError, Node, NodeId, Vert, VertId};
use crate::math::{Vec2, Vec3};

/// A `width × height` rectangle with `nx × ny` quads, each split in two along alternating
/// diagonals (so no direction is favoured). Material coordinates are `(x, y)` in metres from the
/// lower-left corner; the world shape is the same rectangle in the z = 0 plane. Node
/// `j * (nx + 1) + i` sits at column `i`, row `j`.
pub fn rectangle(width: f64, height: f64, nx: usize, ny: usize) -> Result<Mesh, MeshError> {
    let mut mesh = Mesh::default();
    for j in 0..=ny {
        for i in 0..=nx {
            let u = Vec2::new(width * i as f64 / nx as f64, height * j as f64 / ny as f64);
            let id = mesh.nodes.len() as u32;
            mesh.nodes.push(Node {
                x: Vec3::new(u.x, u.y, 0.0),
                v: Vec3::zeros(),
                a: Vec3::zeros(),
                mass: 0.0,
                cloth: 0,
            });
            mesh.verts.push(Vert { u, node: NodeId(id) });
        }
    }
    let id = |i: usize, j: usize| VertId((j * (nx + 1) + i) as u32);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            let tris = if (i + j) % 2 == 0 { [[a, b, c], [a, c, d]] } else { [[a, b, d], [b, c, d]] };
            for v in tris {
                mesh.faces.push(Face { v, material: 0 });
            }
        }
    }
    mesh.rebuild_topology()?;
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    #[test]
    fn rectangle_is_valid() {
        let m = super::rectangle(1.0, 0.5, 7, 3).unwrap();
        m.validate().unwrap();
        assert_eq!(m.faces.len(), 42);
        let area: f64 = (0..m.faces.len()).map(|f| m.material_area(f)).sum();
        assert!((area - 0.5).abs() < 1e-12);
        assert_eq!(m.edges.len(), 8 * 3 + 4 * 7 + 21);
    }
}
