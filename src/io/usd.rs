//! USD output: one text layer (`.usda`) per run, with every frame as time samples.
//!
//! A run writes each frame's samples to a file of its own (`frame_samples`), beside its OBJ
//! frames, and assembles the layer from those files (`assemble`) when it stops (finished,
//! failed or interrupted). A resumed run rewrites the frames after its checkpoint and assembles
//! again, so its layer is byte-identical to an uninterrupted run's, and a layer is never
//! half-written (`write_atomic_with`).
//!
//! Samples file: one line per attribute, `<prim path> TAB <kind> TAB <declaration> TAB <value>`,
//! in the order the layer lists them. Kind `t` is time-sampled (the value at this frame), `u`
//! a value that holds for the whole run (taken from the first frame), `m` an attribute
//! declared with metadata only (the value is the metadata). Every frame of a run has the same
//! lines in the same order, only the `t` values differ.
//!
//! The layer (USD's `UsdGeom` schema):
//! ```text
//! #usda 1.0
//! ( defaultPrim = "World", startTimeCode, endTimeCode, timeCodesPerSecond = framesPerSecond
//!   = the frame rate, metersPerUnit = 1, upAxis = "Z" )
//! def Xform "World" {
//!     def Scope "cloth" { def Mesh "<cloth>" { points, velocities (m/s), extent,
//!         faceVertexCounts, faceVertexIndices, primvars:st (face-varying, indexed by
//!         primvars:st:indices, in the input's texture units): all time-sampled } }
//!     def Scope "obstacles" { def Mesh "<obstacle>" { points, extent, velocities (m/s)
//!         time-sampled (velocities once, zero, for an obstacle that never moves); the faces
//!         once; visibility time-sampled for an obstacle present only in a time window } }
//! }
//! ```
//! Reals are written as the shortest decimal of their 32-bit float (USD's `float`), so the
//! text is a function of the state's bits.

use std::fmt::Write as _;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::obj::{uv_unit, ClothOut};
use crate::math::Vec3;
use crate::mesh::Mesh;

/// The folder of a layer's per-frame samples files, beside the layer.
pub const SAMPLES_DIR: &str = "usd_samples";

/// The stage's time range and rate.
#[derive(Clone, Debug)]
pub struct StageInfo {
    /// Scene name, for the layer's `doc`.
    pub scene: String,
    /// Frames per second (time codes per second).
    pub fps: f64,
    /// First and last time code (frame numbers).
    pub start: usize,
    pub end: usize,
}

/// An obstacle's world-space mesh at one frame.
pub struct ObstacleFrame<'a> {
    pub name: &'a str,
    pub positions: Vec<Vec3>,
    /// Per vertex (m/s); `None` for an obstacle that never moves (written once, as zeros).
    pub velocities: Option<Vec<Vec3>>,
    pub triangles: &'a [[usize; 3]],
    /// Whether it is present at this frame; `None` for an obstacle that is always present.
    pub visible: Option<bool>,
}

/// The samples file of one frame: each cloth of `mesh` as a Mesh prim under `/World/cloth`, each
/// obstacle under `/World/obstacles`.
pub fn frame_samples(mesh: &Mesh, cloths: &[ClothOut], obstacles: &[ObstacleFrame]) -> String {
    let mut s = String::new();
    let names = prim_names(cloths.iter().map(|c| c.name.as_str()));
    for (c, name) in names.iter().enumerate() {
        cloth_samples(&mut s, &format!("/World/cloth/{name}"), mesh, c as u16, cloths);
    }
    let names = prim_names(obstacles.iter().map(|o| o.name));
    for (o, name) in obstacles.iter().zip(&names) {
        obstacle_samples(&mut s, &format!("/World/obstacles/{name}"), o);
    }
    s
}

/// Prim names: identifiers (letters, digits, `_`; not starting with a digit), made distinct by
/// an `_<index>` suffix where two would be equal.
pub fn prim_names<'a>(names: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for (i, name) in names.enumerate() {
        let mut id: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
        if id.is_empty() || id.starts_with(|c: char| c.is_ascii_digit()) {
            id.insert(0, '_');
        }
        if out.contains(&id) {
            id = format!("{id}_{i}");
        }
        out.push(id);
    }
    out
}

/// A real as the shortest decimal of its 32-bit float (USD `float`).
struct F(f64);

impl std::fmt::Display for F {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0 as f32)
    }
}

/// `[a, b, …]` of the items written by `item`.
fn array<T>(s: &mut String, items: impl Iterator<Item = T>, mut item: impl FnMut(&mut String, T)) {
    s.push('[');
    for (k, x) in items.enumerate() {
        if k > 0 {
            s.push_str(", ");
        }
        item(s, x);
    }
    s.push(']');
}

fn vec3s<'a>(s: &mut String, v: impl Iterator<Item = &'a Vec3>) {
    array(s, v, |s, p| {
        let _ = write!(s, "({}, {}, {})", F(p.x), F(p.y), F(p.z));
    });
}

fn ints(s: &mut String, v: impl Iterator<Item = usize>) {
    array(s, v, |s, i| {
        let _ = write!(s, "{i}");
    });
}

fn line(s: &mut String, prim: &str, kind: char, decl: &str, value: impl FnOnce(&mut String)) {
    let _ = write!(s, "{prim}\t{kind}\t{decl}\t");
    value(s);
    s.push('\n');
}

/// The bounding box of `x` as `[(min), (max)]`.
fn extent<'a>(s: &mut String, x: impl Iterator<Item = &'a Vec3>) {
    let (mut lo, mut hi) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
    for p in x {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    if lo.x > hi.x {
        (lo, hi) = (Vec3::zeros(), Vec3::zeros());
    }
    vec3s(s, [lo, hi].iter());
}

fn mesh_header(s: &mut String, prim: &str) {
    line(s, prim, 'u', "uniform bool doubleSided", |s| s.push('1'));
    line(s, prim, 'u', "uniform token orientation", |s| s.push_str("\"rightHanded\""));
    line(s, prim, 'u', "uniform token subdivisionScheme", |s| s.push_str("\"none\""));
}

/// Cloth `c` of `mesh`, its nodes and verts renumbered in their order in the mesh.
fn cloth_samples(s: &mut String, prim: &str, mesh: &Mesh, c: u16, cloths: &[ClothOut]) {
    let mut node_index = vec![usize::MAX; mesh.nodes.len()];
    let nodes: Vec<usize> = (0..mesh.nodes.len()).filter(|&n| mesh.nodes[n].cloth == c).collect();
    for (k, &n) in nodes.iter().enumerate() {
        node_index[n] = k;
    }
    let mut vert_index = vec![usize::MAX; mesh.verts.len()];
    let verts: Vec<usize> =
        (0..mesh.verts.len()).filter(|&v| mesh.nodes[mesh.verts[v].node.idx()].cloth == c).collect();
    for (k, &v) in verts.iter().enumerate() {
        vert_index[v] = k;
    }
    let faces: Vec<usize> = (0..mesh.faces.len()).filter(|&f| mesh.nodes[mesh.face_nodes(f)[0]].cloth == c).collect();
    let unit = uv_unit(cloths, c);
    mesh_header(s, prim);
    line(s, prim, 't', "int[] faceVertexCounts", |s| ints(s, faces.iter().map(|_| 3)));
    line(s, prim, 't', "int[] faceVertexIndices", |s| {
        ints(s, faces.iter().flat_map(|&f| mesh.face_nodes(f)).map(|n| node_index[n]))
    });
    line(s, prim, 't', "point3f[] points", |s| vec3s(s, nodes.iter().map(|&n| &mesh.nodes[n].x)));
    line(s, prim, 't', "float3[] extent", |s| extent(s, nodes.iter().map(|&n| &mesh.nodes[n].x)));
    line(s, prim, 't', "vector3f[] velocities", |s| vec3s(s, nodes.iter().map(|&n| &mesh.nodes[n].v)));
    line(s, prim, 'm', "texCoord2f[] primvars:st", |s| s.push_str("interpolation = \"faceVarying\""));
    line(s, prim, 't', "texCoord2f[] primvars:st", |s| {
        array(s, verts.iter().map(|&v| mesh.verts[v].u / unit), |s, u| {
            let _ = write!(s, "({}, {})", F(u.x), F(u.y));
        })
    });
    line(s, prim, 't', "int[] primvars:st:indices", |s| {
        ints(s, faces.iter().flat_map(|&f| mesh.faces[f].v).map(|v| vert_index[v.idx()]))
    });
}

/// The samples file of one frame of a fixed-topology mesh (a resampled run): the faces and the
/// face-varying st once, points, extent and (when given) velocities time-sampled.
pub fn fixed_samples(
    prim: &str,
    points: &[Vec3],
    velocities: Option<&[Vec3]>,
    faces: &[[usize; 3]],
    st: &[crate::math::Vec2],
    st_indices: &[[usize; 3]],
) -> String {
    let mut s = String::new();
    mesh_header(&mut s, prim);
    line(&mut s, prim, 'u', "int[] faceVertexCounts", |s| ints(s, faces.iter().map(|_| 3)));
    line(&mut s, prim, 'u', "int[] faceVertexIndices", |s| ints(s, faces.iter().flatten().copied()));
    line(&mut s, prim, 't', "point3f[] points", |s| vec3s(s, points.iter()));
    line(&mut s, prim, 't', "float3[] extent", |s| extent(s, points.iter()));
    if let Some(v) = velocities {
        line(&mut s, prim, 't', "vector3f[] velocities", |s| vec3s(s, v.iter()));
    }
    line(&mut s, prim, 'm', "texCoord2f[] primvars:st", |s| s.push_str("interpolation = \"faceVarying\""));
    line(&mut s, prim, 'u', "texCoord2f[] primvars:st", |s| {
        array(s, st.iter(), |s, u| {
            let _ = write!(s, "({}, {})", F(u.x), F(u.y));
        })
    });
    line(&mut s, prim, 'u', "int[] primvars:st:indices", |s| ints(s, st_indices.iter().flatten().copied()));
    s
}

fn obstacle_samples(s: &mut String, prim: &str, o: &ObstacleFrame) {
    mesh_header(s, prim);
    line(s, prim, 'u', "int[] faceVertexCounts", |s| ints(s, o.triangles.iter().map(|_| 3)));
    line(s, prim, 'u', "int[] faceVertexIndices", |s| ints(s, o.triangles.iter().flatten().copied()));
    line(s, prim, 't', "point3f[] points", |s| vec3s(s, o.positions.iter()));
    line(s, prim, 't', "float3[] extent", |s| extent(s, o.positions.iter()));
    match &o.velocities {
        Some(v) => line(s, prim, 't', "vector3f[] velocities", |s| vec3s(s, v.iter())),
        None => line(s, prim, 'u', "vector3f[] velocities", |s| vec3s(s, o.positions.iter().map(|_| &ZERO))),
    }
    if let Some(visible) = o.visible {
        let token = if visible { "\"inherited\"" } else { "\"invisible\"" };
        line(s, prim, 't', "token visibility", |s| s.push_str(token));
    }
}

const ZERO: Vec3 = Vec3::new(0.0, 0.0, 0.0);

/// Why a layer could not be assembled.
#[derive(Debug, thiserror::Error)]
pub enum AssembleError {
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: {msg}")]
    Bad { path: PathBuf, msg: String },
    /// Writing the layer failed (the caller knows where it was going).
    #[error("{0}")]
    Write(std::io::Error),
}

impl From<std::io::Error> for AssembleError {
    fn from(e: std::io::Error) -> Self {
        AssembleError::Write(e)
    }
}

/// Where each line's parts are in one samples file.
struct Index {
    path: PathBuf,
    /// Per line: (prim, kind, declaration) and the byte range of the value.
    lines: Vec<(String, char, String, u64, usize)>,
}

fn index(path: &Path) -> Result<Index, AssembleError> {
    let text = std::fs::read_to_string(path).map_err(|source| AssembleError::Io { path: path.into(), source })?;
    let bad = |k: usize| AssembleError::Bad { path: path.into(), msg: format!("line {}: not a samples line", k + 1) };
    let mut lines = Vec::new();
    let mut offset = 0u64;
    for (k, l) in text.split_inclusive('\n').enumerate() {
        let body = l.strip_suffix('\n').ok_or_else(|| bad(k))?;
        let mut parts = body.splitn(4, '\t');
        let (Some(prim), Some(kind), Some(decl), Some(value)) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(bad(k));
        };
        let kind = match kind {
            "t" => 't',
            "u" => 'u',
            "m" => 'm',
            _ => return Err(bad(k)),
        };
        let start = offset + (body.len() - value.len()) as u64;
        lines.push((prim.to_string(), kind, decl.to_string(), start, value.len()));
        offset += l.len() as u64;
    }
    Ok(Index { path: path.to_path_buf(), lines })
}

/// Writes the layer of `frames` (time code, samples file), in time order, to `out`.
pub fn assemble(out: &mut dyn Write, info: &StageInfo, frames: &[(usize, PathBuf)]) -> Result<(), AssembleError> {
    let indices = frames.iter().map(|(_, p)| index(p)).collect::<Result<Vec<_>, _>>()?;
    let Some(first) = indices.first() else {
        return Err(AssembleError::Bad { path: PathBuf::new(), msg: "no frames to assemble".into() });
    };
    for ix in &indices[1..] {
        let same = ix.lines.len() == first.lines.len()
            && ix.lines.iter().zip(&first.lines).all(|(a, b)| (&a.0, a.1, &a.2) == (&b.0, b.1, &b.2));
        if !same {
            let msg = format!("its prims or attributes differ from {}'s", first.path.display());
            return Err(AssembleError::Bad { path: ix.path.clone(), msg });
        }
    }
    let mut w = std::io::BufWriter::new(out);
    write_layer(&mut w, info, frames, &indices).map_err(|e| match e {
        LayerError::Read(e) => e,
        LayerError::Write(e) => AssembleError::Write(e),
    })?;
    w.flush().map_err(AssembleError::Write)
}

enum LayerError {
    Read(AssembleError),
    Write(std::io::Error),
}

impl From<std::io::Error> for LayerError {
    fn from(e: std::io::Error) -> Self {
        LayerError::Write(e)
    }
}

fn write_layer(
    w: &mut dyn Write,
    info: &StageInfo,
    frames: &[(usize, PathBuf)],
    indices: &[Index],
) -> Result<(), LayerError> {
    let first = &indices[0];
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| LayerError::Read(AssembleError::Io { path, source })
    };
    w.write_all(header(info).as_bytes())?;
    let mut open: Vec<&str> = Vec::new();
    let mut buf = Vec::new();
    for (l, (prim, kind, decl, _, _)) in first.lines.iter().enumerate() {
        let parts: Vec<&str> = prim.trim_start_matches('/').split('/').collect();
        let common = open.iter().zip(&parts).take_while(|(a, b)| a == b).count();
        while open.len() > common {
            open.pop();
            writeln!(w, "{}}}", indent(open.len()))?;
        }
        while open.len() < parts.len() {
            let depth = open.len();
            let ty = match depth {
                0 => "Xform",
                d if d + 1 == parts.len() => "Mesh",
                _ => "Scope",
            };
            writeln!(w, "{}def {ty} \"{}\"\n{}{{", indent(depth), parts[depth], indent(depth))?;
            open.push(parts[depth]);
        }
        let pad = indent(open.len());
        let value = |k: usize, buf: &mut Vec<u8>| -> Result<(), LayerError> {
            let (_, _, _, start, len) = indices[k].lines[l];
            let path = &indices[k].path;
            let mut f = std::fs::File::open(path).map_err(io(path))?;
            f.seek(SeekFrom::Start(start)).map_err(io(path))?;
            buf.resize(len, 0);
            f.read_exact(buf).map_err(io(path))
        };
        match kind {
            'm' => {
                value(0, &mut buf)?;
                let meta = String::from_utf8_lossy(&buf);
                writeln!(w, "{pad}{decl} (\n{pad}    {meta}\n{pad})")?;
            }
            'u' => {
                value(0, &mut buf)?;
                write!(w, "{pad}{decl} = ")?;
                w.write_all(&buf)?;
                writeln!(w)?;
            }
            _ => {
                writeln!(w, "{pad}{decl}.timeSamples = {{")?;
                for (k, (code, _)) in frames.iter().enumerate() {
                    value(k, &mut buf)?;
                    write!(w, "{pad}    {code}: ")?;
                    w.write_all(&buf)?;
                    writeln!(w, ",")?;
                }
                writeln!(w, "{pad}}}")?;
            }
        }
    }
    while !open.is_empty() {
        open.pop();
        writeln!(w, "{}}}", indent(open.len()))?;
    }
    Ok(())
}

fn indent(depth: usize) -> String {
    "    ".repeat(depth)
}

/// The layer's header: format line and stage metadata (keys in USD's own sorted order).
fn header(info: &StageInfo) -> String {
    let fps = if (info.fps - info.fps.round()).abs() < 1e-9 * info.fps {
        format!("{}", info.fps.round())
    } else {
        format!("{}", info.fps)
    };
    let doc: String =
        info.scene.chars().map(|c| if c == '"' || c == '\\' || c.is_control() { '_' } else { c }).collect();
    format!(
        "#usda 1.0\n(\n    defaultPrim = \"World\"\n    doc = \"viewcloth run of scene '{doc}'\"\n    endTimeCode = {}\n    \
         framesPerSecond = {fps}\n    metersPerUnit = 1\n    startTimeCode = {}\n    timeCodesPerSecond = {fps}\n    \
         upAxis = \"Z\"\n)\n\n",
        info.end, info.start
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prim_names_are_distinct_identifiers() {
        let names = prim_names(["sheet", "my cloth", "sheet", "2nd", ""].into_iter());
        assert_eq!(names, ["sheet", "my_cloth", "sheet_2", "_2nd", "_"]);
    }

    #[test]
    fn two_frames_assemble_into_one_layer() {
        let dir = std::env::temp_dir().join(format!("viewcloth_usd_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut mesh = crate::mesh::rectangle(1.0, 1.0, 1, 1).unwrap();
        let cloths = [ClothOut { name: "sheet".into(), uv_unit: 0.5 }];
        let tri = [[0, 1, 2]];
        let frame = |mesh: &Mesh| {
            let positions = vec![Vec3::zeros(), Vec3::x(), Vec3::y()];
            let o = ObstacleFrame { name: "ball", positions, velocities: None, triangles: &tri, visible: None };
            frame_samples(mesh, &cloths, &[o])
        };
        std::fs::write(dir.join("a"), frame(&mesh)).unwrap();
        mesh.nodes[0].x.z = 0.25;
        mesh.nodes[0].v.z = -1.5;
        std::fs::write(dir.join("b"), frame(&mesh)).unwrap();
        let info = StageInfo { scene: "t\"q".into(), fps: 25.0, start: 1001, end: 1002 };
        let mut out = Vec::new();
        assemble(&mut out, &info, &[(1001, dir.join("a")), (1002, dir.join("b"))]).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.starts_with("#usda 1.0\n"));
        assert!(text.contains("startTimeCode = 1001\n") && text.contains("timeCodesPerSecond = 25\n"));
        assert!(text.contains("doc = \"viewcloth run of scene 't_q'\""));
        assert!(text.contains("def Mesh \"sheet\"") && text.contains("def Mesh \"ball\""));
        assert!(text.contains("1002: [(0, 0, 0.25), "), "{text}");
        assert!(text.contains("1002: [(0, 0, -1.5), "), "{text}");
        // UVs in the input's units: material metres / 0.5.
        assert!(text.contains("(2, 2)"), "{text}");
        assert!(text.contains("int[] faceVertexIndices = [0, 1, 2]\n"), "{text}");
        assert!(text.contains("vector3f[] velocities = [(0, 0, 0), (0, 0, 0), (0, 0, 0)]\n"), "{text}");
        assert_eq!(text.matches('{').count(), text.matches('}').count());
        std::fs::write(dir.join("c"), "junk\n").unwrap();
        assert!(assemble(&mut Vec::new(), &info, &[(1, dir.join("a")), (2, dir.join("c"))]).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
