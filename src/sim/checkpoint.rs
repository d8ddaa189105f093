//! Checkpoints: the whole simulation state at a frame boundary, from which `resume` continues
//! bit-identically to an uninterrupted run.
//!
//! What is stored is the `SimState` (`state.rs`): the mesh (material coordinates, node
//! positions, velocities, accelerations, masses; the faces, from which edges are re-derived in the same
//! deterministic order; the creases), the rest dihedral angles and rest embedding, the faces' plastic state, the handles' node
//! ids and switch-ons (when, and where their nodes were), the node pairs added to the system's
//! sparsity pattern, time, step and frame counters. The `Workspace` is rebuilt from it and the scene.
//!
//! Format (little endian): `VCLOTHCK`, format version (u32), the run record, the state, the run
//! statistics so far (JSON), and an FNV-1a 64 checksum of everything before it. Reals are stored
//! as their IEEE-754 bits. Files are written atomically (temporary name, then rename).

use std::path::{Path, PathBuf};

use crate::io::stats::RunStats;
use crate::io::OutputFormat;
use crate::math::{Mat2, Vec2, Vec3};
use crate::mesh::{Face, Mesh, Node, NodeId, Vert, VertId};
use crate::scene::{RemeshMode, Scene};

use super::state::HandleOn;
use super::state::PlasticState;
use super::SimState;

const MAGIC: &[u8; 8] = b"VCLOTHCK";
const FORMAT_VERSION: u32 = 11;
/// File names: `checkpoint_<frame>.bin`.
const PREFIX: &str = "checkpoint_";
const SUFFIX: &str = ".bin";

#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("{path}: {msg}")]
    Corrupt { path: PathBuf, msg: String },
    #[error("{dir}: no checkpoint found (run `simulate` with --checkpoint-every N)")]
    None { dir: PathBuf },
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
}

/// How a run was started: what `resume` needs to rebuild the scene and continue the output.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRecord {
    /// The scene file (absolute), or `None` for the built-in default shot.
    pub scene_file: Option<PathBuf>,
    /// The `--mode` override, if any.
    pub mode: Option<RemeshMode>,
    /// The `--camera` override (absolute), if any.
    pub camera_file: Option<PathBuf>,
    /// `scene_fingerprint` of the scene as loaded (after the override).
    pub fingerprint: u64,
    /// Frames written after the first (the scene's `frames`, or `--frames`).
    pub frames: usize,
    /// Digits of the frame numbers in file names.
    pub digits: usize,
    pub export_obstacles: bool,
    /// A checkpoint every this many frames.
    pub every: usize,
    /// What is written per frame, and whether OBJ frames carry velocities (`nv`).
    pub format: OutputFormat,
    pub obj_velocities: bool,
}

pub struct Checkpoint {
    pub run: RunRecord,
    pub state: SimState,
    pub stats: RunStats,
}

/// FNV-1a, 64 bit.
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for &b in bytes {
        h = (h ^ b as u64).wrapping_mul(0x100000001b3);
    }
    h
}

/// A fingerprint of a loaded scene, its meshes and parameters included (the file name is
/// not): `resume` refuses a scene that no longer matches the run. Debug output prints every
/// real exactly (shortest round-trip form).
pub fn scene_fingerprint(scene: &Scene) -> u64 {
    let mut s = scene.clone();
    s.file = PathBuf::new();
    fnv1a(format!("{s:?}").as_bytes())
}

/// The checkpoint file of `frame` in `dir`.
pub fn checkpoint_path(dir: &Path, frame: usize, digits: usize) -> PathBuf {
    dir.join(format!("{PREFIX}{frame:0digits$}{SUFFIX}"))
}

/// Checkpoint files in `dir`, newest (highest frame) first.
pub fn list(dir: &Path) -> std::io::Result<Vec<(usize, PathBuf)>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else { continue };
        let Some(num) = name.strip_prefix(PREFIX).and_then(|n| n.strip_suffix(SUFFIX)) else { continue };
        if let Ok(frame) = num.parse::<usize>() {
            out.push((frame, path));
        }
    }
    out.sort_by(|a, b| b.cmp(a));
    Ok(out)
}

/// The newest checkpoint in `dir` that reads back intact (an older one when the newest is
/// damaged). Errors name the newest one's problem when none is usable.
pub fn latest(dir: &Path) -> Result<(PathBuf, Checkpoint), CheckpointError> {
    let files = list(dir).map_err(|source| CheckpointError::Io { path: dir.to_path_buf(), source })?;
    let mut first_err = None;
    for (_, path) in files {
        match read(&path) {
            Ok(c) => return Ok((path, c)),
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    Err(first_err.unwrap_or(CheckpointError::None { dir: dir.to_path_buf() }))
}

/// Reads and verifies one checkpoint file.
pub fn read(path: &Path) -> Result<Checkpoint, CheckpointError> {
    let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io { path: path.to_path_buf(), source })?;
    decode(&bytes).map_err(|msg| CheckpointError::Corrupt { path: path.to_path_buf(), msg })
}

/// Serialises a checkpoint.
pub fn encode(run: &RunRecord, st: &SimState, stats: &RunStats) -> Vec<u8> {
    let mut w = Writer(Vec::with_capacity(64 + st.mesh.nodes.len() * 64 + st.mesh.faces.len() * 16));
    w.0.extend_from_slice(MAGIC);
    w.u32(FORMAT_VERSION);
    w.str(env!("CARGO_PKG_VERSION"));
    // Run record.
    match &run.scene_file {
        Some(p) => {
            w.u8(1);
            w.str(&p.to_string_lossy());
        }
        None => w.u8(0),
    }
    w.u8(match run.mode {
        None => 0,
        Some(RemeshMode::Uniform) => 1,
        Some(RemeshMode::Adaptive) => 2,
        Some(RemeshMode::View) => 3,
    });
    match &run.camera_file {
        Some(p) => {
            w.u8(1);
            w.str(&p.to_string_lossy());
        }
        None => w.u8(0),
    }
    w.u64(run.fingerprint);
    w.usize(run.frames);
    w.usize(run.digits);
    w.u8(run.export_obstacles as u8);
    w.usize(run.every);
    w.u8(run.format as u8);
    w.u8(run.obj_velocities as u8);
    // State.
    w.usize(st.frame);
    w.u64(st.steps);
    w.f64(st.time);
    w.usize(st.pushed_out);
    w.u8(st.separating as u8);
    let m = &st.mesh;
    w.usize(m.verts.len());
    for v in &m.verts {
        w.f64(v.u.x);
        w.f64(v.u.y);
        w.u32(v.node.0);
    }
    w.usize(m.nodes.len());
    for n in &m.nodes {
        n.x.iter().chain(n.v.iter()).chain(n.a.iter()).for_each(|&c| w.f64(c));
        w.f64(n.mass);
        w.u32(n.cloth as u32);
    }
    w.usize(m.faces.len());
    for f in &m.faces {
        f.v.iter().for_each(|v| w.u32(v.0));
        w.u32(f.material as u32);
    }
    w.usize(m.creases.len());
    m.creases.iter().flatten().for_each(|n| w.u32(n.0));
    w.usize(st.rest_angles.len());
    st.rest_angles.iter().for_each(|&a| w.f64(a));
    w.usize(st.rest_x.len());
    st.rest_x.iter().flat_map(|p| p.iter()).for_each(|&c| w.f64(c));
    match &st.plastic {
        None => w.u8(0),
        Some(p) => {
            w.u8(1);
            w.usize(p.shapes.len());
            p.shapes.iter().flat_map(|s| s.iter()).for_each(|&c| w.f64(c));
            p.damage.iter().for_each(|&d| w.f64(d));
        }
    }
    w.usize(st.handle_nodes.len());
    for h in &st.handle_nodes {
        w.usize(h.len());
        h.iter().for_each(|&n| w.usize(n));
    }
    w.usize(st.handle_on.len());
    for on in &st.handle_on {
        match on {
            None => w.u8(0),
            Some(on) => {
                w.u8(1);
                w.f64(on.time);
                w.usize(on.x.len());
                on.x.iter().flat_map(|p| p.iter()).for_each(|&c| w.f64(c));
            }
        }
    }
    w.usize(st.extra_pairs.len());
    for &(i, j) in &st.extra_pairs {
        w.usize(i);
        w.usize(j);
    }
    w.usize(st.stuck.len());
    st.stuck.iter().flatten().for_each(|&i| w.usize(i));
    w.usize(st.pinched.len());
    st.pinched.iter().for_each(|&i| w.usize(i));
    w.usize(st.view_memory.len());
    st.view_memory.iter().for_each(|&m| w.f64(m));
    w.usize(st.buckle.len());
    st.buckle.iter().for_each(|&k| w.f64(k));
    // Statistics so far (serialising a RunStats cannot fail: strings, numbers, maps).
    w.bytes(&serde_json::to_vec(stats).unwrap_or_default());
    let sum = fnv1a(&w.0);
    w.u64(sum);
    w.0
}

fn decode(bytes: &[u8]) -> Result<Checkpoint, String> {
    if bytes.len() < MAGIC.len() + 12 || &bytes[..MAGIC.len()] != MAGIC {
        return Err("not a viewcloth checkpoint".into());
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    if fnv1a(body) != u64::from_le_bytes(sum.try_into().map_err(|_| "truncated")?) {
        return Err("checksum mismatch (damaged file)".into());
    }
    let mut r = Reader { buf: body, pos: MAGIC.len() };
    let version = r.u32()?;
    if version != FORMAT_VERSION {
        return Err(format!("format version {version}, this viewcloth reads {FORMAT_VERSION}"));
    }
    let written_by = r.str()?;
    if written_by != env!("CARGO_PKG_VERSION") {
        return Err(format!("written by viewcloth {written_by}, this is {}", env!("CARGO_PKG_VERSION")));
    }
    let scene_file = match r.u8()? {
        0 => None,
        1 => Some(PathBuf::from(r.str()?)),
        k => return Err(format!("bad scene source tag {k}")),
    };
    let mode = match r.u8()? {
        0 => None,
        1 => Some(RemeshMode::Uniform),
        2 => Some(RemeshMode::Adaptive),
        3 => Some(RemeshMode::View),
        k => return Err(format!("bad mode tag {k}")),
    };
    let camera_file = match r.u8()? {
        0 => None,
        1 => Some(PathBuf::from(r.str()?)),
        k => return Err(format!("bad camera tag {k}")),
    };
    let run = RunRecord {
        scene_file,
        mode,
        camera_file,
        fingerprint: r.u64()?,
        frames: r.usize()?,
        digits: r.usize()?,
        export_obstacles: r.u8()? != 0,
        every: r.usize()?,
        format: match r.u8()? {
            0 => OutputFormat::Obj,
            1 => OutputFormat::Usd,
            2 => OutputFormat::Both,
            k => return Err(format!("bad output format tag {k}")),
        },
        obj_velocities: r.u8()? != 0,
    };
    let (frame, steps, time, pushed_out) = (r.usize()?, r.u64()?, r.f64()?, r.usize()?);
    let separating = r.u8()? != 0;
    let mut mesh = Mesh::default();
    let nv = r.count(20)?;
    for _ in 0..nv {
        let u = Vec2::new(r.f64()?, r.f64()?);
        mesh.verts.push(Vert { u, node: NodeId(r.u32()?) });
    }
    let nn = r.count(84)?;
    for _ in 0..nn {
        let x = Vec3::new(r.f64()?, r.f64()?, r.f64()?);
        let v = Vec3::new(r.f64()?, r.f64()?, r.f64()?);
        let a = Vec3::new(r.f64()?, r.f64()?, r.f64()?);
        let mass = r.f64()?;
        let cloth = u16::try_from(r.u32()?).map_err(|_| "cloth index out of range")?;
        mesh.nodes.push(Node { x, v, a, mass, cloth });
    }
    let nf = r.count(16)?;
    for _ in 0..nf {
        let v = [VertId(r.u32()?), VertId(r.u32()?), VertId(r.u32()?)];
        let material = u16::try_from(r.u32()?).map_err(|_| "material index out of range")?;
        if v.iter().any(|v| v.idx() >= nv) {
            return Err("face references a missing vert".into());
        }
        mesh.faces.push(Face { v, material });
    }
    if mesh.verts.iter().any(|v| v.node.idx() >= nn) {
        return Err("vert references a missing node".into());
    }
    let nc = r.count(8)?;
    mesh.creases = (0..nc).map(|_| Ok([NodeId(r.u32()?), NodeId(r.u32()?)])).collect::<Result<_, String>>()?;
    let na = r.count(8)?;
    let rest_angles = (0..na).map(|_| r.f64()).collect::<Result<Vec<_>, _>>()?;
    let nr = r.count(24)?;
    let rest_x = (0..nr).map(|_| Ok(Vec3::new(r.f64()?, r.f64()?, r.f64()?))).collect::<Result<Vec<_>, String>>()?;
    let plastic = match r.u8()? {
        0 => None,
        1 => {
            let nf = r.count(40)?;
            let shapes = (0..nf)
                .map(|_| Ok(Mat2::from_column_slice(&[r.f64()?, r.f64()?, r.f64()?, r.f64()?])))
                .collect::<Result<Vec<_>, String>>()?;
            let damage = (0..nf).map(|_| r.f64()).collect::<Result<Vec<_>, _>>()?;
            Some(PlasticState { shapes, damage })
        }
        k => return Err(format!("bad plastic state tag {k}")),
    };
    let nh = r.count(8)?;
    let mut handle_nodes = Vec::with_capacity(nh);
    for _ in 0..nh {
        let k = r.count(8)?;
        handle_nodes.push((0..k).map(|_| r.usize()).collect::<Result<Vec<_>, _>>()?);
    }
    let non = r.count(1)?;
    let mut handle_on = Vec::with_capacity(non);
    for _ in 0..non {
        handle_on.push(match r.u8()? {
            0 => None,
            1 => {
                let time = r.f64()?;
                let k = r.count(24)?;
                let x = (0..k).map(|_| Ok(Vec3::new(r.f64()?, r.f64()?, r.f64()?))).collect::<Result<_, String>>()?;
                Some(HandleOn { time, x })
            }
            _ => return Err("bad handle switch-on flag".into()),
        });
    }
    let np = r.count(16)?;
    let extra_pairs = (0..np).map(|_| Ok((r.usize()?, r.usize()?))).collect::<Result<Vec<_>, String>>()?;
    let ns = r.count(32)?;
    let stuck =
        (0..ns).map(|_| Ok([r.usize()?, r.usize()?, r.usize()?, r.usize()?])).collect::<Result<Vec<_>, String>>()?;
    let nq = r.count(8)?;
    let pinched = (0..nq).map(|_| r.usize()).collect::<Result<Vec<_>, String>>()?;
    let nm = r.count(8)?;
    let view_memory = (0..nm).map(|_| r.f64()).collect::<Result<Vec<_>, String>>()?;
    let nb = r.count(8)?;
    let buckle = (0..nb).map(|_| r.f64()).collect::<Result<Vec<_>, String>>()?;
    let stats: RunStats = serde_json::from_slice(r.bytes()?).map_err(|e| format!("statistics: {e}"))?;
    if r.pos != body.len() {
        return Err("trailing bytes".into());
    }
    let state = SimState {
        frame,
        steps,
        time,
        pushed_out,
        separating,
        mesh,
        rest_angles,
        rest_x,
        plastic,
        handle_nodes,
        handle_on,
        extra_pairs,
        stuck,
        pinched,
        view_memory,
        buckle,
    };
    Ok(Checkpoint { run, state, stats })
}

struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn usize(&mut self, v: usize) {
        self.u64(v as u64);
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn bytes(&mut self, b: &[u8]) {
        self.usize(b.len());
        self.0.extend_from_slice(b);
    }
    fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
}

/// Bounds-checked reading; errors are messages (the caller adds the file).
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.buf.len()).ok_or("truncated")?;
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().map_err(|_| "truncated")?))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().map_err(|_| "truncated")?))
    }
    fn usize(&mut self) -> Result<usize, String> {
        usize::try_from(self.u64()?).map_err(|_| "count out of range".into())
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A count of items of at least `item_bytes` each, checked against what is left.
    fn count(&mut self, item_bytes: usize) -> Result<usize, String> {
        let n = self.usize()?;
        if n.saturating_mul(item_bytes) > self.buf.len() - self.pos {
            return Err("truncated (count larger than the file)".into());
        }
        Ok(n)
    }
    fn bytes(&mut self) -> Result<&'a [u8], String> {
        let n = self.count(1)?;
        self.take(n)
    }
    fn str(&mut self) -> Result<String, String> {
        String::from_utf8(self.bytes()?.to_vec()).map_err(|_| "invalid UTF-8".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn damaged_bytes_are_rejected_not_panicking() {
        let st = SimState {
            frame: 3,
            steps: 12,
            time: 0.12,
            pushed_out: 0,
            separating: true,
            mesh: {
                let mut m = crate::mesh::rectangle(1.0, 1.0, 2, 2).unwrap();
                m.creases = vec![[crate::mesh::NodeId(1), crate::mesh::NodeId(4)]];
                m
            },
            rest_angles: vec![0.0; 16],
            rest_x: (0..9).map(|i| Vec3::new(i as f64, 0.5, -1.0)).collect(),
            plastic: Some(PlasticState { shapes: vec![Mat2::new(1.0, 2.0, 2.0, 3.0); 8], damage: vec![0.5; 8] }),
            handle_nodes: vec![vec![0, 2]],
            handle_on: vec![Some(HandleOn { time: 0.5, x: vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, -1.0, 0.5)] })],
            extra_pairs: vec![(3, 1)],
            stuck: vec![[0, 1, 2, 9]],
            pinched: vec![4, 7],
            view_memory: vec![0.25; 9],
            buckle: vec![0.5; 8],
        };
        let run = RunRecord {
            scene_file: Some("/a/b.json".into()),
            mode: Some(RemeshMode::Adaptive),
            camera_file: Some("/a/cam.json".into()),
            fingerprint: 7,
            frames: 10,
            digits: 4,
            export_obstacles: false,
            every: 2,
            format: OutputFormat::Both,
            obj_velocities: true,
        };
        let bytes = encode(&run, &st, &RunStats::default());
        let back = decode(&bytes).unwrap();
        assert_eq!(back.run, run);
        assert_eq!(back.state.time.to_bits(), st.time.to_bits());
        assert_eq!(back.state.mesh.nodes.len(), st.mesh.nodes.len());
        assert_eq!(back.state.extra_pairs, st.extra_pairs);
        assert_eq!(back.state.handle_on, st.handle_on);
        assert_eq!(back.state.stuck, st.stuck);
        assert_eq!(back.state.pinched, st.pinched);
        assert_eq!(back.state.plastic, st.plastic);
        assert_eq!(back.state.rest_x, st.rest_x);
        assert_eq!(back.state.mesh.creases, st.mesh.creases);
        assert_eq!(back.state.view_memory, st.view_memory);
        assert_eq!(back.state.buckle, st.buckle);
        for cut in [0, 8, 20, bytes.len() / 2, bytes.len() - 1] {
            assert!(decode(&bytes[..cut]).is_err(), "truncated at {cut} accepted");
        }
        for k in (0..bytes.len()).step_by(37) {
            let mut b = bytes.clone();
            b[k] ^= 0x5a;
            assert!(decode(&b).is_err(), "flipped byte {k} accepted");
        }
    }
}
