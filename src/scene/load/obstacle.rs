//! Obstacles of a scene: analytic shapes, OBJ meshes and per-frame OBJ sequences, with their
//! transform and motion.

use std::path::{Path, PathBuf};

use super::{format_frame, mesh_file, motion_or_mot, non_negative, positive, transform, Ctx, Res};
use crate::error::InputError;
use crate::io::obj::{read_obj, ObjData};
use crate::scene::spec::{ObstacleSpec, SequenceSpec};
use crate::scene::{MeshSequence, Obstacle, ObstacleShape};

const ONE_SHAPE: &str = "expected exactly one shape: mesh, sphere, plane, box, capsule or sequence";

pub(super) fn load_obstacle(ctx: &Ctx, o: usize, os: &ObstacleSpec) -> Res<Obstacle> {
    let path = format!("obstacles[{o}]");
    let count = [
        os.mesh.is_some(),
        os.sphere.is_some(),
        os.plane.is_some(),
        os.cuboid.is_some(),
        os.capsule.is_some(),
        os.sequence.is_some(),
    ]
    .iter()
    .filter(|b| **b)
    .count();
    if count != 1 {
        return Err(ctx.err(&path, ONE_SHAPE));
    }
    let shape = if let Some(file) = &os.mesh {
        let full = mesh_file(ctx, &format!("{path}.mesh"), file)?;
        let data = read_obj(&full).map_err(|msg| InputError { file: full.clone(), location: None, msg })?;
        ObstacleShape::Mesh(data)
    } else if let Some(s) = &os.sphere {
        ObstacleShape::Sphere { radius: positive(ctx, &format!("{path}.sphere.radius"), s.radius)? }
    } else if let Some(p) = &os.plane {
        ObstacleShape::Plane {
            size: [
                positive(ctx, &format!("{path}.plane.size[0]"), p.size[0])?,
                positive(ctx, &format!("{path}.plane.size[1]"), p.size[1])?,
            ],
        }
    } else if let Some(b) = &os.cuboid {
        let mut size = [0.0; 3];
        for (i, s) in size.iter_mut().enumerate() {
            *s = positive(ctx, &format!("{path}.box.size[{i}]"), b.size[i])?;
        }
        ObstacleShape::Box { size }
    } else if let Some(c) = &os.capsule {
        ObstacleShape::Capsule {
            radius: positive(ctx, &format!("{path}.capsule.radius"), c.radius)?,
            length: non_negative(ctx, &format!("{path}.capsule.length"), c.length)?,
        }
    } else if let Some(seq) = &os.sequence {
        ObstacleShape::Sequence(load_sequence(ctx, &format!("{path}.sequence"), seq)?)
    } else {
        return Err(ctx.err(&path, ONE_SHAPE));
    };
    Ok(Obstacle {
        name: os.name.clone().unwrap_or_else(|| format!("obstacle{o}")),
        shape,
        transform: transform(ctx, &format!("{path}.transform"), &os.transform)?,
        motion: motion_or_mot(ctx, &path, os.motion.as_deref(), os.mot.as_ref())?,
    })
}

/// Reads every file of a per-frame OBJ sequence; all must share the first file's vertex count
/// and faces.
fn load_sequence(ctx: &Ctx, path: &str, seq: &SequenceSpec) -> Res<MeshSequence> {
    let fps = positive(ctx, &format!("{path}.fps"), seq.fps)?;
    if !seq.start_time.is_finite() {
        return Err(ctx.err(format!("{path}.start_time"), "expected a finite time"));
    }
    if !(1..=1_000_000).contains(&seq.count) {
        let msg = format!("expected an integer in 1..=1000000, got {}", seq.count);
        return Err(ctx.err(format!("{path}.count"), msg));
    }
    if seq.first < 0 {
        let msg = format!("expected an integer ≥ 0, got {}", seq.first);
        return Err(ctx.err(format!("{path}.first"), msg));
    }
    let read = |k: i64| -> Res<(PathBuf, ObjData)> {
        let name = format_frame(&seq.pattern, seq.first + k).map_err(|msg| ctx.err(format!("{path}.pattern"), msg))?;
        let full = ctx.resolve(&name);
        let data = read_obj(&full).map_err(|msg| InputError { file: full.clone(), location: None, msg })?;
        Ok((full, data))
    };
    let file_err = |full: &Path, msg: String| InputError { file: full.to_path_buf(), location: None, msg };
    let (full, mesh) = read(0)?;
    if mesh.triangles.is_empty() {
        return Err(file_err(&full, "the mesh has no faces".into()));
    }
    let mut frames = Vec::with_capacity(seq.count as usize);
    frames.push(mesh.positions.clone());
    for k in 1..seq.count {
        let (full, data) = read(k)?;
        if data.positions.len() != mesh.positions.len() {
            let msg = format!(
                "sequence frame has {} vertices, expected {} as in the first frame",
                data.positions.len(),
                mesh.positions.len()
            );
            return Err(file_err(&full, msg));
        }
        let same_faces = data.triangles.len() == mesh.triangles.len()
            && data.triangles.iter().zip(&mesh.triangles).all(|(a, b)| a.map(|c| c.v) == b.map(|c| c.v));
        if !same_faces {
            return Err(file_err(&full, "sequence frame has different faces from the first frame".into()));
        }
        frames.push(data.positions);
    }
    Ok(MeshSequence { mesh, frames, start_time: seq.start_time, fps })
}
