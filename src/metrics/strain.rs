//! Membrane strain of a mesh, as `stats.json` reports it: per face the largest principal stretch
//! of F = D_s D_m⁻¹ minus one (`forces::membrane::max_principal_strain`), its maximum over the
//! faces and its mean weighted by material area. `simulate` measures it on the simulated mesh;
//! runs derived from another's frames (`compare`'s `upsampled` and `loop`) on their OBJ frames,
//! from the positions and the texture coordinates scaled to material metres.

use crate::forces::membrane::{deformation_gradient, max_principal_strain, MembraneRest};
use crate::io::obj::ObjData;
use crate::math::{Real, Vec3};

/// Largest and area-weighted mean principal strain over a mesh's faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strain {
    pub max: Real,
    pub mean: Real,
}

/// The strain of faces given as world corners and rest data (no faces: max −∞, mean NaN).
pub fn principal_strain(faces: impl Iterator<Item = ([Vec3; 3], MembraneRest)>) -> Strain {
    let (mut max, mut sum, mut area) = (Real::NEG_INFINITY, 0.0, 0.0);
    for (x, rest) in faces {
        let s = max_principal_strain(&deformation_gradient(&x, &rest));
        max = max.max(s);
        sum += s * rest.area;
        area += rest.area;
    }
    Strain { max, mean: sum / area }
}

/// The strain of an OBJ frame whose `vt` are material coordinates in units of `uv_unit` metres.
/// Refused, naming the face (1-based, in file order), when a face has no texture coordinates or
/// a degenerate or inverted material triangle.
pub fn obj_strain(obj: &ObjData, uv_unit: Real) -> Result<Strain, String> {
    if obj.triangles.is_empty() {
        return Err("no faces".into());
    }
    let mut faces = Vec::with_capacity(obj.triangles.len());
    for (f, t) in obj.triangles.iter().enumerate() {
        let uv = t.map(|c| c.vt.and_then(|k| obj.texcoords.get(k)).map(|u| u * uv_unit));
        let [Some(a), Some(b), Some(c)] = uv else {
            return Err(format!("face {}: no texture coordinates (material space is needed for strain)", f + 1));
        };
        let rest = MembraneRest::new([a, b, c])
            .ok_or_else(|| format!("face {}: degenerate or inverted in material space", f + 1))?;
        faces.push((t.map(|c| obj.positions[c.v]), rest));
    }
    Ok(principal_strain(faces.into_iter()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::obj::parse_obj;

    /// A unit square (two faces) stretched by 10 % along x and 4 % along y: every face's largest
    /// principal strain is 0.1, whatever the texture unit, once the positions scale with it.
    #[test]
    fn stretched_square_has_its_stretch_as_strain() {
        let text = "v 0 0 0\nv 1.1 0 0\nv 1.1 1.04 0\nv 0 1.04 0\nvt 0 0\nvt 10 0\nvt 10 10\nvt 0 10\n\
                    f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
        let obj = parse_obj(text).unwrap();
        let s = obj_strain(&obj, 0.1).unwrap();
        assert!((s.max - 0.1).abs() < 1e-12 && (s.mean - 0.1).abs() < 1e-12, "{s:?}");
        // In the wrong unit the same frame reads as compressed to a tenth.
        assert!((obj_strain(&obj, 1.0).unwrap().max - (0.11 - 1.0)).abs() < 1e-12);
        let flat = parse_obj("v 0 0 0\nv 1 0 0\nv 2 0 0\nvt 0 0\nvt 1 0\nvt 2 0\nf 1/1 2/2 3/3\n").unwrap();
        assert_eq!(obj_strain(&flat, 1.0).unwrap_err(), "face 1: degenerate or inverted in material space");
        let bare = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert!(obj_strain(&bare, 1.0).unwrap_err().starts_with("face 1: no texture coordinates"));
    }
}
