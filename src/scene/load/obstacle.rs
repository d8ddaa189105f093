//! Obstacles of a scene: analytic shapes, OBJ meshes and per-frame OBJ sequences, with their
//! transform and motion.

use std::path::{Path, PathBuf};

use super::{format_frame, mesh_file, motion_or_mot, non_negative, positive, transform, Ctx, Res};
use crate::collision::shape::{MeshSequence, Obstacle, ObstacleShape, Window};
use crate::error::InputError;
use crate::io::obj::{read_obj, ObjData};
use crate::scene::spec::{ObstacleSpec, SequenceSpec};

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
        motion: motion_or_mot(ctx, &path, os.motion.as_deref(), os.mot.as_ref(), false)?,
        window: window(ctx, &path, os)?,
    })
}

/// `start_time` and `end_time`: finite when given, end after start.
fn window(ctx: &Ctx, path: &str, os: &ObstacleSpec) -> Res<Window> {
    let mut w = Window::default();
    for (field, value, slot) in [("start_time", os.start_time, &mut w.start), ("end_time", os.end_time, &mut w.end)] {
        if let Some(t) = value {
            if !t.is_finite() {
                return Err(ctx.err(format!("{path}.{field}"), format!("expected a time in seconds, got {t}")));
            }
            *slot = t;
        }
    }
    if w.end < w.start {
        let msg = format!("expected end_time ≥ start_time, got {} .. {}", w.start, w.end);
        return Err(ctx.err(format!("{path}.end_time"), msg));
    }
    Ok(w)
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

#[cfg(test)]
mod tests {
    use crate::collision::obstacle::{signed_volume, ObstacleBody};
    use crate::math::{Real, Vec3};

    /// Writes `frames` as `dir/body_000k.obj` (a tetrahedron scaled per frame; frame `bad` gets
    /// an extra vertex) and a scene naming them as a sequence.
    fn write_sequence(dir: &std::path::Path, frames: usize, bad: Option<usize>) -> String {
        std::fs::create_dir_all(dir.join("meshes")).unwrap();
        for k in 0..frames {
            let s = 1.0 + k as Real;
            let mut obj = format!("v 0 0 0\nv {s} 0 0\nv 0 {s} 0\nv 0 0 {s}\n");
            if bad == Some(k) {
                obj.push_str("v 9 9 9\n");
            }
            obj.push_str("f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
            std::fs::write(dir.join(format!("meshes/body_{:04}.obj", 3 + k)), obj).unwrap();
        }
        format!(
            r#"{{"version": 1, "frame_time": 0.04, "frames": 1,
                "cloths": [{{"rectangle": {{"width": 1, "height": 1, "resolution": [2, 2]}},
                             "material": {{"preset": "cotton"}}}}],
                "obstacles": [{{"name": "body", "sequence":
                    {{"pattern": "meshes/body_%04d.obj", "first": 3, "count": {frames},
                      "fps": 25}}}}]}}"#
        )
    }

    #[test]
    fn sequence_scene_loads_and_rejects_a_mismatched_frame() {
        let dir = std::env::temp_dir().join(format!("viewcloth_seq_{}", std::process::id()));
        let text = write_sequence(&dir, 2, None);
        let file = dir.join("scene.json");
        let scene = crate::scene::load_str(&text, &file, &dir, "seq").unwrap();
        let body = ObstacleBody::new(&scene.obstacles[0]);
        let half = body.positions_at(0.02);
        assert!((half[1] - Vec3::new(1.5, 0.0, 0.0)).norm() < 1e-12);
        assert!(signed_volume(body.triangles(), &half) > 0.0);

        let text = write_sequence(&dir, 3, Some(2));
        let err = crate::scene::load_str(&text, &file, &dir, "seq").unwrap_err();
        assert!(err.file.ends_with("meshes/body_0005.obj"), "{err}");
        assert!(err.msg.contains("5 vertices, expected 4"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
