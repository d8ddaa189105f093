//! Reading a run's OBJ frame for resampling, split into its cloths: a frame holds every cloth's
//! nodes in one `v` list and their faces under one `o <cloth name>` group per cloth (as
//! `io::obj::frame_obj` writes it); each cloth is resampled on its own, in the order its group
//! first appears in the frame.

use std::path::Path;

use super::{input_error, ResampleError, RunFrame};
use crate::io::obj::{read_obj, Corner, ObjData};
use crate::math::{Real, Vec3};
use crate::render::run_dir::RunFiles;

/// Frame `number` of the run, one `RunFrame` per cloth with its name.
pub fn read_frame(files: &RunFiles, number: usize, time: Real) -> Result<Vec<(String, RunFrame)>, ResampleError> {
    let path = files.frame_path(number);
    let obj = read_obj(&path).map_err(|msg| input_error(&path, msg))?;
    if obj.triangles.iter().any(|t| t[0].vt.is_none()) {
        return Err(input_error(&path, "faces without texture coordinates (not a viewcloth frame?)"));
    }
    let text = std::fs::read_to_string(&path).map_err(|source| ResampleError::Io { path: path.clone(), source })?;
    let velocities = velocities(&text, obj.positions.len(), &path)?;
    let (names, group) = groups(&text, &obj);
    if names.len() <= 1 {
        let name = names.into_iter().next().unwrap_or_default();
        return Ok(vec![(name, RunFrame { number, time, obj, velocities })]);
    }
    Ok(names
        .into_iter()
        .enumerate()
        .map(|(g, name)| {
            let (sub, nodes) = subset(&obj, |t| group[t] == g);
            let velocities = velocities.as_ref().map(|v| nodes.iter().map(|&n| v[n]).collect());
            (name, RunFrame { number, time, obj: sub, velocities })
        })
        .collect())
}

/// The `nv` lines, when the run wrote them (one per `v`).
fn velocities(text: &str, count: usize, path: &Path) -> Result<Option<Vec<Vec3>>, ResampleError> {
    let mut v = Vec::new();
    for (k, l) in text.lines().enumerate().filter(|(_, l)| l.starts_with("nv ")) {
        let c: Vec<Real> = l[3..].split_whitespace().filter_map(|w| w.parse().ok()).collect();
        if c.len() != 3 {
            return Err(input_error(path, format!("line {}: 'nv' needs 3 numbers", k + 1)));
        }
        v.push(Vec3::new(c[0], c[1], c[2]));
    }
    match v.len() {
        0 => Ok(None),
        n if n == count => Ok(Some(v)),
        n => Err(input_error(path, format!("{n} 'nv' lines for {count} vertices"))),
    }
}

/// The distinct `o` names in order of first appearance, and per triangle the index of the
/// group its face line is in (faces before any `o` line: group 0).
fn groups(text: &str, obj: &ObjData) -> (Vec<String>, Vec<usize>) {
    let mut names: Vec<String> = Vec::new();
    // (1-based line of the `o`, group index), in line order.
    let mut starts: Vec<(usize, usize)> = Vec::new();
    for (k, l) in text.lines().enumerate() {
        if let Some(name) = l.strip_prefix("o ") {
            let name = name.trim().to_string();
            let g = names.iter().position(|n| *n == name).unwrap_or_else(|| {
                names.push(name);
                names.len() - 1
            });
            starts.push((k + 1, g));
        }
    }
    let group = obj
        .face_line
        .iter()
        .map(|&line| match starts.partition_point(|&(l, _)| l < line) {
            0 => 0,
            i => starts[i - 1].1,
        })
        .collect();
    (names, group)
}

/// The triangles `keep` selects, with the positions and texture coordinates they use
/// renumbered in their file order; and the original index of each kept position.
fn subset(obj: &ObjData, keep: impl Fn(usize) -> bool) -> (ObjData, Vec<usize>) {
    let tris: Vec<usize> = (0..obj.triangles.len()).filter(|&t| keep(t)).collect();
    let renumber = |count: usize, index: &dyn Fn(&Corner) -> usize| {
        let mut new = vec![usize::MAX; count];
        for c in tris.iter().flat_map(|&t| &obj.triangles[t]) {
            new[index(c)] = 0;
        }
        let mut kept = Vec::new();
        for (i, n) in new.iter_mut().enumerate().filter(|(_, n)| **n == 0) {
            *n = kept.len();
            kept.push(i);
        }
        (new, kept)
    };
    let (v_new, v_kept) = renumber(obj.positions.len(), &|c| c.v);
    let (vt_new, vt_kept) = renumber(obj.texcoords.len(), &|c| c.vt.unwrap_or(0));
    let sub = ObjData {
        positions: v_kept.iter().map(|&i| obj.positions[i]).collect(),
        texcoords: vt_kept.iter().map(|&i| obj.texcoords[i]).collect(),
        triangles: tris
            .iter()
            .map(|&t| obj.triangles[t].map(|c| Corner { v: v_new[c.v], vt: Some(vt_new[c.vt.unwrap_or(0)]) }))
            .collect(),
        face_line: tris.iter().map(|&t| obj.face_line[t]).collect(),
        position_line: v_kept.iter().map(|&i| obj.position_line[i]).collect(),
        labelled_edges: Vec::new(),
    };
    (sub, v_kept)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::obj::parse_obj;

    #[test]
    fn a_frame_splits_into_its_cloths_groups() {
        let text =
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 5 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0 0\nvt 1 0\nvt 0 1\n\
                    o a\nf 1/1 2/2 3/3\no b\nf 4/4 5/5 6/6\n";
        let obj = parse_obj(text).unwrap();
        let (names, group) = groups(text, &obj);
        assert_eq!(names, ["a", "b"]);
        assert_eq!(group, [0, 1]);
        let (b, nodes) = subset(&obj, |t| group[t] == 1);
        assert_eq!(nodes, [3, 4, 5]);
        assert_eq!(b.positions[0], Vec3::new(5.0, 0.0, 0.0));
        assert_eq!(b.triangles[0].map(|c| (c.v, c.vt)), [(0, Some(0)), (1, Some(1)), (2, Some(2))]);
    }
}
