//! Reading a scene file: JSON → `SceneSpec` (with the JSON path of any error) → range checks →
//! meshes loaded and transformed → `Scene`.

use std::path::{Path, PathBuf};

use super::material::resolve;
use super::spec::{ClothSpec, CollisionSpec, KeyframeSpec, MotSpec, SceneSpec, TransformSpec};
use super::{Cloth, Disabled, Scene};
use crate::camera::Camera;
use crate::collision::params::{CollisionParams, InitialIntersections};
use crate::collision::proximity::Law;
use crate::error::InputError;
use crate::forces::wind::Wind;
use crate::io::obj::{read_obj, ObjData};
use crate::math::motion::{KeyVelocity, Keyframe, Motion, Transform};
use crate::math::{cross2, Vec2, Vec3};
use crate::mesh::{rectangle, Face, Mesh, MeshError, Node, NodeId, Vert, VertId};

/// The built-in default shot (`viewcloth simulate` with no scene): `scenes/sheet_drape.json`,
/// seen by `cameras/sheet_drape.json` (built in too, so the shot needs no file at run time).
pub const DEFAULT_SCENE: &str = include_str!("../../../scenes/sheet_drape.json");
pub const DEFAULT_SCENE_NAME: &str = "sheet_drape";
pub const DEFAULT_CAMERA: &str = include_str!("../../../cameras/sheet_drape.json");

mod constraints;
mod frame_pattern;
mod handle;
mod instance;
mod obstacle;
mod remesh;
use constraints::{lra_params, strain_limits};
pub(super) use frame_pattern::format_frame;
use handle::load_handle;
use instance::{check_unique_names, read_instances, Placement};
use obstacle::load_obstacle;
use remesh::{remesh_params, view_sides};

type Res<T> = Result<T, InputError>;

struct Ctx<'a> {
    file: &'a Path,
    base: &'a Path,
}

impl Ctx<'_> {
    fn err(&self, path: impl Into<String>, msg: impl Into<String>) -> InputError {
        InputError { file: self.file.to_path_buf(), location: Some(path.into()), msg: msg.into() }
    }
    fn resolve(&self, rel: &str) -> PathBuf {
        self.base.join(rel)
    }
}

/// Loads and validates a scene file (and every file it references). ARCSim confs are accepted
/// too (paths from their default base, conversion warnings dropped; see `arcsim::load_path`).
pub fn load_file(path: &Path) -> Res<Scene> {
    super::arcsim::load_path(path, None).map(|loaded| loaded.scene)
}

/// Validates a scene file without keeping the result.
pub fn check_file(path: &Path) -> Res<()> {
    load_file(path).map(|_| ())
}

/// Parses scene JSON. `file` names the source in errors, `base` resolves relative paths and
/// `default_name` is used when the scene has no `name`.
pub fn load_str(text: &str, file: &Path, base: &Path, default_name: &str) -> Res<Scene> {
    let ctx = Ctx { file, base };
    let spec: SceneSpec = crate::io::json::parse(text).map_err(|(loc, msg)| ctx.err(loc, msg))?;
    build(&ctx, spec, default_name)
}

/// Like `load_str`, from an already parsed JSON value (ARCSim confs arrive converted).
pub fn load_value(value: serde_json::Value, file: &Path, base: &Path, default_name: &str) -> Res<Scene> {
    let ctx = Ctx { file, base };
    let spec: SceneSpec = serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        ctx.err(if path == "." { "JSON".to_string() } else { path }, e.inner().to_string())
    })?;
    build(&ctx, spec, default_name)
}

fn positive(ctx: &Ctx, path: &str, v: f64) -> Res<f64> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(ctx.err(path, format!("expected a positive number, got {v}")))
    }
}

fn finite3(ctx: &Ctx, path: &str, v: [f64; 3]) -> Res<Vec3> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vec3::from(v))
    } else {
        Err(ctx.err(path, "expected finite numbers"))
    }
}

fn build(ctx: &Ctx, spec: SceneSpec, default_name: &str) -> Res<Scene> {
    if spec.version != 1 {
        return Err(ctx.err("version", format!("expected 1, got {}", spec.version)));
    }
    let frame_time = match (spec.frame_time, spec.fps) {
        (Some(ft), None) => positive(ctx, "frame_time", ft)?,
        (None, Some(fps)) => 1.0 / positive(ctx, "fps", fps)?,
        (None, None) => return Err(ctx.err("frame_time", "expected frame_time (s) or fps")),
        (Some(_), Some(_)) => return Err(ctx.err("fps", "give frame_time or fps, not both")),
    };
    let steps_per_frame = match (spec.steps_per_frame, spec.time_step) {
        (Some(n), None) if (1..=100_000).contains(&n) => n as usize,
        (Some(n), None) => {
            return Err(ctx.err("steps_per_frame", format!("expected an integer in 1..=100000, got {n}")))
        }
        (None, Some(h)) => {
            let h = positive(ctx, "time_step", h)?;
            let n = frame_time / h;
            if (n - n.round()).abs() > 1e-6 * n || n.round() < 1.0 || n > 1e5 {
                return Err(
                    ctx.err("time_step", format!("expected a divisor of the frame time {frame_time} s, got {h}"))
                );
            }
            n.round() as usize
        }
        (None, None) => 1,
        (Some(_), Some(_)) => return Err(ctx.err("time_step", "give steps_per_frame or time_step, not both")),
    };
    let frames = match (spec.frames, spec.end_time) {
        (Some(n), None) if (1..=10_000_000).contains(&n) => n as usize,
        (Some(n), None) => return Err(ctx.err("frames", format!("expected an integer ≥ 1, got {n}"))),
        (None, Some(t)) => (positive(ctx, "end_time", t)? / frame_time - 1e-9).ceil().max(1.0) as usize,
        (None, None) => return Err(ctx.err("frames", "expected frames or end_time")),
        (Some(_), Some(_)) => return Err(ctx.err("end_time", "give frames or end_time, not both")),
    };
    let (start_frame, preroll_frames) = frame_range(ctx, &spec, frame_time)?;
    let gravity = finite3(ctx, "gravity", spec.gravity)?;
    let wind = match &spec.wind {
        Some(w) => Some(Wind {
            velocity: finite3(ctx, "wind.velocity", w.velocity)?,
            density: non_negative(ctx, "wind.density", w.density)?,
            drag: non_negative(ctx, "wind.drag", w.drag)?,
            implicit: w.implicit.unwrap_or(true),
        }),
        None => None,
    };
    let instances = read_instances(ctx, &spec.instances)?;
    if spec.cloths.is_empty() && instances.is_empty() {
        return Err(ctx.err("cloths", "expected at least one cloth"));
    }
    let mut scene = Scene {
        file: ctx.file.to_path_buf(),
        name: spec.name.clone().unwrap_or_else(|| default_name.to_string()),
        frame_time,
        steps_per_frame,
        frames,
        start_frame,
        preroll_frames,
        gravity,
        wind,
        cloths: Vec::new(),
        materials: Vec::new(),
        mesh: Mesh::default(),
        handles: Vec::new(),
        obstacles: Vec::new(),
        collision: collision_params(ctx, spec.collision.as_ref())?,
        camera: match &spec.camera {
            Some(rel) => Some(Camera::load(&ctx.resolve(rel))?),
            None => None,
        },
        disabled: Disabled::default(),
        initial_relax: spec.initial_relax.unwrap_or(false),
    };
    let off = disabled_stages(ctx, &spec.disable)?;
    scene.disabled = Disabled {
        proximity: off.contains(&"proximity"),
        physics: off.contains(&"physics"),
        collision: off.contains(&"collision"),
        separation: off.contains(&"separation"),
        pop_filter: off.contains(&"pop_filter"),
    };
    // Obstacles first: handles may follow one.
    for (o, os) in spec.obstacles.iter().enumerate() {
        let obstacle = load_obstacle(ctx, o, os)?;
        scene.obstacles.push(obstacle);
    }
    for instance in &instances {
        instance.add_obstacles(&mut scene)?;
    }
    for (c, cs) in spec.cloths.iter().enumerate() {
        add_cloth(ctx, &mut scene, &format!("cloths[{c}]"), cs, &Placement::IDENTITY)?;
    }
    for instance in &instances {
        instance.add_cloths(&mut scene)?;
    }
    if scene.cloths.is_empty() {
        return Err(ctx.err("instances", "expected at least one cloth (the instanced scenes have none)"));
    }
    if !instances.is_empty() {
        check_unique_names(ctx, &scene)?;
    }
    for cloth in &mut scene.cloths {
        if off.contains(&"remeshing") {
            cloth.remesh = None;
        }
        if off.contains(&"strain_limiting") {
            cloth.strain_limits = None;
        }
        if off.contains(&"lra") {
            cloth.lra = None;
        }
    }
    if off.contains(&"plasticity") {
        scene.materials.iter_mut().for_each(|m| m.plasticity = None);
    }
    scene.mesh.rebuild_topology().map_err(|e| ctx.err("cloths", e.to_string()))?;
    let density: Vec<f64> = scene.materials.iter().map(|m| m.density).collect();
    scene.mesh.compute_masses(&density);
    // Without obstacles a scene does no collision work unless it asks for self-collision.
    if spec.collision.as_ref().and_then(|c| c.self_collision).is_none() {
        scene.collision.self_collision = !scene.obstacles.is_empty();
    }
    Ok(scene)
}

/// The stages `disable` names, each one of `Disabled::NAMES`.
fn disabled_stages<'a>(ctx: &Ctx, names: &'a [String]) -> Res<Vec<&'a str>> {
    let mut out = Vec::new();
    for (i, name) in names.iter().enumerate() {
        if !Disabled::NAMES.contains(&name.as_str()) {
            let known = Disabled::NAMES.map(|n| format!("\"{n}\"")).join(", ");
            return Err(ctx.err(format!("disable[{i}]"), format!("expected one of {known}, got \"{name}\"")));
        }
        out.push(name.as_str());
    }
    Ok(out)
}

/// `start_frame` (an integer in 0..=100000000) and `preroll` (seconds ≥ 0, a whole number of
/// frames) as (start frame, preroll frames).
fn frame_range(ctx: &Ctx, spec: &SceneSpec, frame_time: f64) -> Res<(usize, usize)> {
    let start = match spec.start_frame {
        None => 0,
        Some(n) if (0..=100_000_000).contains(&n) => n as usize,
        Some(n) => return Err(ctx.err("start_frame", format!("expected an integer in 0..=100000000, got {n}"))),
    };
    let preroll = match spec.preroll {
        None => 0,
        Some(p) => {
            let p = non_negative(ctx, "preroll", p)?;
            let n = p / frame_time;
            if (n - n.round()).abs() > 1e-6 * n.max(1.0) || n > 1e6 {
                let msg = format!("expected a whole number of frames of {frame_time} s (seconds, ≥ 0), got {p}");
                return Err(ctx.err("preroll", msg));
            }
            n.round() as usize
        }
    };
    Ok((start, preroll))
}

fn collision_params(ctx: &Ctx, spec: Option<&CollisionSpec>) -> Res<CollisionParams> {
    let mut p = CollisionParams::default();
    let Some(c) = spec else { return Ok(p) };
    if let Some(t) = c.thickness {
        p.thickness = positive(ctx, "collision.thickness", t)?;
        p.push_out_tolerance = 3.0 * p.thickness;
    }
    if let Some(k) = c.stiffness {
        p.stiffness = positive(ctx, "collision.stiffness", k)?;
    }
    if let Some(law) = &c.penalty {
        p.penalty = match law.as_str() {
            "quadratic" => Law::Quadratic,
            "arcsim" => Law::Cubic,
            other => {
                return Err(
                    ctx.err("collision.penalty", format!("expected \"quadratic\" or \"arcsim\", got \"{other}\""))
                )
            }
        };
    }
    if let Some(m) = c.friction {
        p.friction = non_negative(ctx, "collision.friction", m)?;
    }
    if let Some(m) = c.self_friction {
        p.self_friction = non_negative(ctx, "collision.self_friction", m)?;
    }
    if let Some(b) = c.self_collision {
        p.self_collision = b;
    }
    if let Some(n) = c.max_iterations {
        if !(1..=100_000).contains(&n) {
            return Err(ctx.err("collision.max_iterations", format!("expected an integer in 1..=100000, got {n}")));
        }
        p.max_iterations = n as usize;
    }
    if let Some(t) = c.push_out_tolerance {
        p.push_out_tolerance = non_negative(ctx, "collision.push_out_tolerance", t)?;
    }
    if let Some(mode) = &c.initial_intersections {
        p.initial_intersections = match mode.as_str() {
            "resolve" => InitialIntersections::Resolve,
            "refuse" => InitialIntersections::Refuse,
            other => {
                let msg = format!("expected \"resolve\" or \"refuse\", got \"{other}\"");
                return Err(ctx.err("collision.initial_intersections", msg));
            }
        };
    }
    Ok(p)
}

/// A finite time (seconds, any sign).
fn finite_time(ctx: &Ctx, path: &str, t: f64) -> Res<f64> {
    if t.is_finite() {
        Ok(t)
    } else {
        Err(ctx.err(path, format!("expected a finite time in seconds, got {t}")))
    }
}

fn non_negative(ctx: &Ctx, path: &str, v: f64) -> Res<f64> {
    if v >= 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(ctx.err(path, format!("expected a number ≥ 0, got {v}")))
    }
}

fn transform(ctx: &Ctx, path: &str, t: &TransformSpec) -> Res<Transform> {
    let xf = key_transform(ctx, path, t, false)?;
    Ok(xf)
}

/// A transform whose scale may be 0 when `zero_scale` (a handle's keyframe can pull its nodes
/// onto a point, as ARCSim's can).
fn key_transform(ctx: &Ctx, path: &str, t: &TransformSpec, zero_scale: bool) -> Res<Transform> {
    finite3(ctx, &format!("{path}.translate"), t.translate)?;
    if let Some(r) = t.rotate {
        if !r.iter().all(|c| c.is_finite()) || (r[0] != 0.0 && Vec3::new(r[1], r[2], r[3]).norm() == 0.0) {
            return Err(ctx.err(format!("{path}.rotate"), "expected [degrees, axis x, y, z] with a non-zero axis"));
        }
    }
    match zero_scale {
        true => non_negative(ctx, &format!("{path}.scale"), t.scale)?,
        false => positive(ctx, &format!("{path}.scale"), t.scale)?,
    };
    Ok(Transform::new(t.translate, t.rotate, t.scale))
}

/// Keyframes at `path`; `zero_scale`: a key's scale may be 0 (handles).
fn motion(ctx: &Ctx, path: &str, keys: &[KeyframeSpec], zero_scale: bool) -> Res<Motion> {
    if keys.is_empty() {
        return Err(ctx.err(path, "expected at least one keyframe"));
    }
    let mut out = Vec::with_capacity(keys.len());
    let mut velocities = Vec::with_capacity(keys.len());
    for (i, k) in keys.iter().enumerate() {
        let p = format!("{path}[{i}]");
        if !k.time.is_finite() {
            return Err(ctx.err(format!("{p}.time"), "expected a finite time"));
        }
        if let Some(prev) = out.last().map(|k: &Keyframe| k.time) {
            if k.time <= prev {
                return Err(
                    ctx.err(format!("{p}.time"), format!("keyframe times must increase: {} after {prev}", k.time))
                );
            }
        }
        let t = TransformSpec { translate: k.translate, rotate: k.rotate, scale: k.scale };
        out.push(Keyframe { time: k.time, transform: key_transform(ctx, &p, &t, zero_scale)? });
        let velocity = match &k.velocity {
            Some(v) => {
                let translate = finite3(ctx, &format!("{p}.velocity.translate"), v.translate)?;
                if !v.scale.is_finite() {
                    return Err(ctx.err(format!("{p}.velocity.scale"), "expected a finite number"));
                }
                Some(KeyVelocity { translate, scale: v.scale })
            }
            None => None,
        };
        velocities.push(velocity);
    }
    Ok(Motion::with_velocities(out, velocities))
}

/// The motion of a handle or obstacle at `path`: keyframes (with `zero_scale`, a key may have
/// scale 0), a `.mot` body, or none.
fn motion_or_mot(
    ctx: &Ctx,
    path: &str,
    keys: Option<&[KeyframeSpec]>,
    mot: Option<&MotSpec>,
    zero_scale: bool,
) -> Res<Option<Motion>> {
    match (keys, mot) {
        (Some(_), Some(_)) => Err(ctx.err(format!("{path}.mot"), "give motion or mot, not both")),
        (Some(k), None) => motion(ctx, &format!("{path}.motion"), k, zero_scale).map(Some),
        (None, Some(m)) => {
            let mp = format!("{path}.mot");
            let fps = positive(ctx, &format!("{mp}.fps"), m.fps)?;
            if !m.start_time.is_finite() {
                return Err(ctx.err(format!("{mp}.start_time"), "expected a finite time"));
            }
            let xf = transform(ctx, &format!("{mp}.transform"), &m.transform)?;
            let file = super::mot::read_mot(&ctx.resolve(&m.file))?;
            if m.body < 0 || m.body as usize >= file.bodies.len() {
                let msg = format!("expected a body index in 0..{}, got {}", file.bodies.len(), m.body);
                return Err(ctx.err(format!("{mp}.body"), msg));
            }
            Ok(Some(file.body_motion(m.body as usize, fps, m.start_time, &xf)))
        }
        (None, None) => Ok(None),
    }
}

/// The path of a mesh file named by the scene field `field`; a missing file is that field's error.
fn mesh_file(ctx: &Ctx, field: &str, rel: &str) -> Res<PathBuf> {
    let full = ctx.resolve(rel);
    match std::fs::metadata(&full) {
        Ok(_) => Ok(full),
        Err(e) => Err(ctx.err(field, format!("cannot read mesh file {}: {e}", full.display()))),
    }
}

/// A single cloth's mesh in its own node numbering, and the material metres per unit of its
/// input's texture coordinates (`uv_scale` for an OBJ with `vt`, else 1: its material
/// coordinates are then lengths already).
fn cloth_mesh(ctx: &Ctx, path: &str, cs: &ClothSpec) -> Res<(Mesh, f64)> {
    match (&cs.mesh, &cs.rectangle) {
        (Some(file), None) => {
            let full = mesh_file(ctx, &format!("{path}.mesh"), file)?;
            let data = read_obj(&full).map_err(|msg| InputError { file: full.clone(), location: None, msg })?;
            let unit = if data.triangles.first().is_some_and(|t| t[0].vt.is_some()) { cs.uv_scale } else { 1.0 };
            Ok((mesh_from_obj(&full, &data, cs.uv_scale)?, unit))
        }
        (None, Some(r)) => {
            let w = positive(ctx, &format!("{path}.rectangle.width"), r.width)?;
            let h = positive(ctx, &format!("{path}.rectangle.height"), r.height)?;
            let [nx, ny] = r.resolution;
            if !(1..=4096).contains(&nx) || !(1..=4096).contains(&ny) {
                return Err(ctx.err(
                    format!("{path}.rectangle.resolution"),
                    format!("expected two integers in 1..=4096, got [{nx}, {ny}]"),
                ));
            }
            rectangle(w, h, nx as usize, ny as usize).map(|m| (m, 1.0)).map_err(|e| ctx.err(path, e.to_string()))
        }
        _ => Err(ctx.err(path, "expected exactly one of \"mesh\" (OBJ file) or \"rectangle\"")),
    }
}

/// Adds the cloth `cs` (at `path` in its file) to `scene`, placed by `placement`.
fn add_cloth(ctx: &Ctx, scene: &mut Scene, path: &str, cs: &ClothSpec, placement: &Placement) -> Res<()> {
    let c = scene.cloths.len();
    positive(ctx, &format!("{path}.uv_scale"), cs.uv_scale)?;
    let material = match &cs.material.arcsim {
        Some(file) => {
            let data = super::measured::read_measured(&ctx.resolve(file))?;
            super::measured::resolve_measured(&cs.material, &data)
        }
        None => resolve(&cs.material),
    }
    .map_err(|(field, msg)| ctx.err(format!("{path}.material.{field}"), format!("expected {msg}")))?;
    let flat_rest = match cs.rest_angles.as_deref() {
        None | Some("input") => false,
        Some("flat") => true,
        Some(other) => {
            let msg = format!("expected \"input\" or \"flat\", got \"{other}\"");
            return Err(ctx.err(format!("{path}.rest_angles"), msg));
        }
    };
    let xf = transform(ctx, &format!("{path}.transform"), &cs.transform)?;
    let velocity = placement.vector(&finite3(ctx, &format!("{path}.velocity"), cs.velocity)?);
    let (mut local, unit) = cloth_mesh(ctx, path, cs)?;
    // ARCSim: a cloth's scale also scales its material coordinates (an instance's too).
    let scale = xf.scale * placement.transform.scale;
    let uv_unit = unit * scale;
    for v in &mut local.verts {
        v.u *= scale;
    }
    let (node0, vert0) = (scene.mesh.nodes.len(), scene.mesh.verts.len());
    let name = cs.name.clone().unwrap_or_else(|| format!("cloth{c}"));
    for n in &local.nodes {
        scene.mesh.nodes.push(Node {
            x: placement.point(&xf.apply(&n.x)),
            v: velocity,
            a: Vec3::zeros(),
            mass: 0.0,
            cloth: c as u16,
        });
    }
    for v in &local.verts {
        scene.mesh.verts.push(Vert { u: v.u, node: NodeId(v.node.0 + node0 as u32) });
    }
    for f in &local.faces {
        scene.mesh.faces.push(Face { v: f.v.map(|v| VertId(v.0 + vert0 as u32)), material: c as u16 });
    }
    // Cloths follow each other in node order, so the creases stay sorted.
    scene.mesh.creases.extend(local.creases.iter().map(|e| e.map(|n| NodeId(n.0 + node0 as u32))));
    for (h, hs) in cs.handles.iter().enumerate() {
        let handle = load_handle(ctx, &format!("{path}.handles[{h}]"), hs, &local, node0, scene, placement)?;
        scene.handles.push(handle);
    }
    let sides = view_sides(&local, cs);
    let remesh = cs.remesh.as_ref().map(|r| remesh_params(ctx, &format!("{path}.remesh"), r, sides)).transpose()?;
    let lra = cs.lra.as_ref().map(|l| lra_params(ctx, &format!("{path}.lra"), l)).transpose()?;
    let strain_limits =
        cs.strain_limits.map(|l| strain_limits(ctx, &format!("{path}.strain_limits"), l)).transpose()?;
    scene.cloths.push(Cloth { name, material: scene.materials.len(), remesh, flat_rest, uv_unit, lra, strain_limits });
    scene.materials.push(material);
    Ok(())
}

fn mesh_from_obj(file: &Path, d: &ObjData, uv_scale: f64) -> Res<Mesh> {
    let line_err =
        |line: usize, msg: String| InputError { file: file.to_path_buf(), location: Some(format!("line {line}")), msg };
    let mut mesh = Mesh::default();
    for p in &d.positions {
        mesh.nodes.push(Node { x: *p, v: Vec3::zeros(), a: Vec3::zeros(), mass: 0.0, cloth: 0 });
    }
    let has_vt = d.triangles[0][0].vt.is_some();
    if has_vt {
        // One vert per distinct texture coordinate; a position with several is a seam.
        let mut vert_of_vt: Vec<Option<VertId>> = vec![None; d.texcoords.len()];
        for (t, tri) in d.triangles.iter().enumerate() {
            let mut face = [VertId(0); 3];
            for (k, c) in tri.iter().enumerate() {
                let vt = c.vt.unwrap_or(0);
                let id = match vert_of_vt[vt] {
                    Some(id) if mesh.verts[id.idx()].node.idx() == c.v => id,
                    Some(_) => {
                        return Err(line_err(
                            d.face_line[t],
                            format!("texture coordinate {} is used with two different vertices", vt + 1),
                        ))
                    }
                    None => {
                        mesh.verts.push(Vert { u: d.texcoords[vt] * uv_scale, node: NodeId(c.v as u32) });
                        let id = VertId(mesh.verts.len() as u32 - 1);
                        vert_of_vt[vt] = Some(id);
                        id
                    }
                };
                face[k] = id;
            }
            mesh.faces.push(Face { v: face, material: 0 });
        }
    } else {
        let uv = flatten(d).map_err(|msg| InputError { file: file.to_path_buf(), location: None, msg })?;
        for (i, u) in uv.into_iter().enumerate() {
            mesh.verts.push(Vert { u, node: NodeId(i as u32) });
        }
        for tri in &d.triangles {
            mesh.faces.push(Face { v: tri.map(|c| VertId(c.v as u32)), material: 0 });
        }
    }
    orient_faces(&mut mesh).map_err(|(t, msg)| line_err(d.face_line[t], msg))?;
    let mut used = vec![false; mesh.nodes.len()];
    for f in 0..mesh.faces.len() {
        let n = mesh.face_nodes(f);
        n.iter().for_each(|&i| used[i] = true);
        let [a, b, c] = n.map(|i| mesh.nodes[i].x);
        let scale = (b - a).norm().max((c - a).norm()).max(1e-300);
        if n[0] == n[1] || n[1] == n[2] || n[0] == n[2] || (b - a).cross(&(c - a)).norm() <= 1e-12 * scale * scale {
            return Err(line_err(d.face_line[f], "degenerate face (repeated vertex or zero area)".into()));
        }
    }
    if let Some(i) = used.iter().position(|u| !u) {
        return Err(line_err(d.position_line[i], format!("vertex {} is used by no face", i + 1)));
    }
    // Checked before the topology, where a repeated face would look like a non-manifold edge.
    let mut seen = std::collections::HashMap::new();
    for f in 0..mesh.faces.len() {
        let mut key = mesh.face_nodes(f);
        key.sort_unstable();
        if let Some(other) = seen.insert(key, f) {
            let msg = format!("duplicate face (same vertices as line {})", d.face_line[other]);
            return Err(line_err(d.face_line[f], msg));
        }
    }
    mesh.rebuild_topology().map_err(|e| match e {
        MeshError::NonManifoldEdge { a, b } => {
            // The third face (in file order) on the edge is the one to blame.
            let (a, b) = (a as usize, b as usize);
            let on_edge = |f: &usize| {
                let n = mesh.face_nodes(*f);
                n.contains(&a) && n.contains(&b)
            };
            let third = (0..mesh.faces.len()).filter(on_edge).nth(2).unwrap_or(0);
            let msg = format!("non-manifold: the edge between vertices {} and {} already has two faces", a + 1, b + 1);
            line_err(d.face_line[third], msg)
        }
        other => InputError { file: file.to_path_buf(), location: None, msg: other.to_string() },
    })?;
    mesh.creases = creases(&mesh, d).map_err(|(line, msg)| line_err(line, msg))?;
    mesh.validate().map_err(|e| match e {
        MeshError::DuplicateFace { face, other } => {
            line_err(d.face_line[face], format!("duplicate face (same vertices as line {})", d.face_line[other]))
        }
        MeshError::BadMaterialArea { face, .. } => {
            line_err(d.face_line[face], "face has zero material-space (texture) area".into())
        }
        other => InputError { file: file.to_path_buf(), location: None, msg: other.to_string() },
    })?;
    Ok(mesh)
}

/// The file's labelled edges as creases (`Mesh::creases`); each must be an edge of the faces.
fn creases(mesh: &Mesh, d: &ObjData) -> Result<Vec<[NodeId; 2]>, (usize, String)> {
    let edges: std::collections::HashSet<[NodeId; 2]> =
        mesh.edges.iter().map(|e| [e.n[0].min(e.n[1]), e.n[0].max(e.n[1])]).collect();
    let mut out = Vec::with_capacity(d.labelled_edges.len());
    for e in &d.labelled_edges {
        let [a, b] = e.n.map(|n| NodeId(n as u32));
        let key = [a.min(b), a.max(b)];
        if !edges.contains(&key) {
            let msg = format!(
                "labelled edge 'e {} {}' is not an edge of the faces (expected two vertices of one face)",
                e.n[0] + 1,
                e.n[1] + 1
            );
            return Err((e.line, msg));
        }
        out.push(key);
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// Material coordinates for a mesh without `vt`: the rest mesh must be flat; its vertices are
/// expressed in an orthonormal frame of its plane (first axis along the world x axis projected,
/// or y if x is normal to the plane).
fn flatten(d: &ObjData) -> Result<Vec<Vec2>, String> {
    let n = d.positions.len() as f64;
    let centroid = d.positions.iter().fold(Vec3::zeros(), |a, p| a + p) / n;
    let mut normal = Vec3::zeros();
    for t in &d.triangles {
        let [a, b, c] = t.map(|c| d.positions[c.v]);
        normal += (b - a).cross(&(c - a));
    }
    if normal.norm() == 0.0 {
        return Err("cannot find the plane of a mesh without texture coordinates".into());
    }
    let normal = normal.normalize();
    let extent = d.positions.iter().map(|p| (p - centroid).norm()).fold(0.0, f64::max);
    let off = d.positions.iter().map(|p| (p - centroid).dot(&normal).abs()).fold(0.0, f64::max);
    if off > 1e-6 * extent.max(1e-12) {
        return Err(format!(
            "the mesh has no texture coordinates (vt) and is not flat (off-plane by {off:.3e} m): give material coordinates as vt"
        ));
    }
    let seed = if normal.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
    let e1 = (seed - normal * normal.dot(&seed)).normalize();
    let e2 = normal.cross(&e1);
    Ok(d.positions.iter().map(|p| Vec2::new((p - centroid).dot(&e1), (p - centroid).dot(&e2))).collect())
}

/// Material-space faces must be counter-clockwise: if all are clockwise (mirrored UVs) flip
/// them; a mix is an error naming the first face that disagrees with the first.
fn orient_faces(mesh: &mut Mesh) -> Result<(), (usize, String)> {
    let sign = |m: &Mesh, f: usize| {
        let [a, b, c] = m.face_uv(f);
        cross2(&(b - a), &(c - a)).signum()
    };
    let first = sign(mesh, 0);
    for f in 0..mesh.faces.len() {
        let s = sign(mesh, f);
        if s == 0.0 {
            return Err((f, "face has zero material-space (texture) area".into()));
        }
        if s != first {
            return Err((f, "face orientation in material space differs from the first face's (flipped or mirrored texture coordinates)".into()));
        }
    }
    if first < 0.0 {
        for face in &mut mesh.faces {
            face.v.swap(1, 2);
        }
    }
    Ok(())
}
