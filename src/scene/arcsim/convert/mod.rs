//! The conversion of a parsed ARCSim conf into a viewcloth scene (see the parent module): an
//! ordered JSON value that reads top-down, built key by key with a warning for every ARCSim key
//! that has no viewcloth equivalent.

use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use super::ordered::{nums, obj, J};
use super::Res;
use crate::error::InputError;
use crate::math::motion::{KeyVelocity, Keyframe, Motion, Transform};

mod cloth;

/// A conversion: the viewcloth scene and the warnings.
pub struct Converted {
    pub scene: J,
    pub warnings: Vec<String>,
}

/// Converts a parsed conf. `write_path` turns a resolved file path into the string written
/// into the scene.
pub fn convert(conf: &Value, file: &Path, base: &Path, write_path: &dyn Fn(&Path) -> String) -> Res<Converted> {
    let mut c = Conv { file, base, write_path, warnings: Vec::new() };
    let scene = c.scene(conf)?;
    Ok(Converted { scene, warnings: c.warnings })
}

/// A motion of the conf's `motions`, as the scene will state it.
#[derive(Clone)]
enum MotionRef {
    /// Keyframes (viewcloth form) and the motion they describe.
    Keys(J, Motion),
    /// Body `body` of a `.mot` file.
    Mot { file: String, body: usize, fps: f64, transform: J },
}

impl MotionRef {
    /// The scene field and value that attach this motion.
    fn field(&self) -> (&'static str, J) {
        match self {
            MotionRef::Keys(keys, _) => ("motion", keys.clone()),
            MotionRef::Mot { file, body, fps, transform } => (
                "mot",
                obj(vec![
                    ("file", J::Str(file.clone())),
                    ("body", J::Int(*body as i64)),
                    ("fps", J::Num(*fps)),
                    ("transform", transform.clone()),
                ]),
            ),
        }
    }
}

/// ARCSim's `magic` parameters that map to viewcloth settings.
#[derive(Default)]
struct Magic {
    thickness: Option<f64>,
    stiffness: Option<f64>,
    combine_tensors: Option<bool>,
    fixed_high_res_mesh: bool,
}

/// ARCSim modules switched off by `disable`.
#[derive(Default)]
struct Disabled {
    remeshing: bool,
    strain_limiting: bool,
    collision: bool,
    plasticity: bool,
}

const TOP_KEYS: &[&str] = &[
    "frame_time",
    "frame_steps",
    "end_time",
    "end_frame",
    "timestep",
    "save_frames",
    "duration",
    "cloths",
    "motions",
    "handles",
    "obstacles",
    "gravity",
    "wind",
    "friction",
    "obs_friction",
    "disable",
    "magic",
];

/// Keys ARCSim reads that viewcloth has nothing for, with what is lost.
const TOP_IGNORED: &[(&str, &str)] = &[
    ("save_every", "output thinning is not supported; every frame is written"),
    ("passive_time", "not supported"),
    ("morphs", "morph targets are not supported"),
];

struct Conv<'a> {
    file: &'a Path,
    base: &'a Path,
    write_path: &'a dyn Fn(&Path) -> String,
    warnings: Vec<String>,
}

impl Conv<'_> {
    fn err(&self, loc: &str, msg: impl Into<String>) -> InputError {
        let location = if loc.is_empty() { None } else { Some(loc.to_string()) };
        InputError { file: self.file.to_path_buf(), location, msg: msg.into() }
    }

    fn warn(&mut self, loc: &str, msg: impl AsRef<str>) {
        self.warnings.push(format!("{loc}: {}", msg.as_ref()));
    }

    /// Warns once per key of `m` that is neither known nor among `ignored` (which get their
    /// own reason).
    fn check_keys(&mut self, m: &Map<String, Value>, loc: &str, known: &[&str], ignored: &[(&str, &str)]) {
        for k in m.keys() {
            let at = if loc.is_empty() { k.clone() } else { format!("{loc}.{k}") };
            if let Some((_, why)) = ignored.iter().find(|(name, _)| name == k) {
                self.warn(&at, format!("ignored ({why})"));
            } else if !known.contains(&k.as_str()) {
                self.warn(&at, "unknown key, ignored");
            }
        }
    }

    fn object<'v>(&self, v: &'v Value, loc: &str) -> Res<&'v Map<String, Value>> {
        v.as_object().ok_or_else(|| self.err(loc, format!("expected an object, got {v}")))
    }

    fn array<'v>(&self, v: &'v Value, loc: &str) -> Res<&'v Vec<Value>> {
        v.as_array().ok_or_else(|| self.err(loc, format!("expected an array, got {v}")))
    }

    fn num(&self, v: &Value, loc: &str) -> Res<f64> {
        v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| self.err(loc, format!("expected a number, got {v}")))
    }

    fn opt_num(&self, m: &Map<String, Value>, key: &str, loc: &str) -> Res<Option<f64>> {
        m.get(key).map(|v| self.num(v, &join(loc, key))).transpose()
    }

    fn int(&self, v: &Value, loc: &str) -> Res<i64> {
        v.as_i64().ok_or_else(|| self.err(loc, format!("expected an integer, got {v}")))
    }

    fn string<'v>(&self, v: &'v Value, loc: &str) -> Res<&'v str> {
        v.as_str().ok_or_else(|| self.err(loc, format!("expected a string, got {v}")))
    }

    fn numbers<const N: usize>(&self, v: &Value, loc: &str) -> Res<[f64; N]> {
        let a = self.array(v, loc)?;
        if a.len() != N {
            return Err(self.err(loc, format!("expected {N} numbers, got {v}")));
        }
        let mut out = [0.0; N];
        for (i, (o, x)) in out.iter_mut().zip(a).enumerate() {
            *o = self.num(x, &format!("{loc}[{i}]"))?;
        }
        Ok(out)
    }

    /// A path of the conf, resolved against the base, as written into the scene.
    fn path(&self, rel: &str) -> (PathBuf, String) {
        let full = self.base.join(rel);
        let written = (self.write_path)(&full);
        (full, written)
    }

    fn scene(&mut self, conf: &Value) -> Res<J> {
        let m = self.object(conf, "")?;
        self.check_keys(m, "", TOP_KEYS, TOP_IGNORED);
        let (frame_time, steps, frames) = self.timing(m)?;
        let disabled = self.disable(m.get("disable"))?;
        let magic = self.magic(m.get("magic"))?;
        let motions = match m.get("motions") {
            Some(v) => self.motions(v)?,
            None => Vec::new(),
        };
        let cloth_values = self.array(m.get("cloths").unwrap_or(&Value::Null), "cloths")?;
        if cloth_values.is_empty() {
            return Err(self.err("cloths", "expected at least one cloth"));
        }
        let mut cloths = Vec::new();
        let mut meshes = Vec::new();
        for (i, cv) in cloth_values.iter().enumerate() {
            let (fields, mesh) = self.cloth(cv, i, &disabled, &magic)?;
            cloths.push(fields);
            meshes.push(mesh);
        }
        if let Some(hs) = m.get("handles") {
            for (h, hv) in self.array(hs, "handles")?.iter().enumerate() {
                self.handle(hv, h, &motions, &meshes, &mut cloths)?;
            }
        }
        let obstacles = match m.get("obstacles") {
            Some(v) => self.obstacles(v, &motions)?,
            None => Vec::new(),
        };
        let gravity = match m.get("gravity") {
            Some(v) => self.numbers::<3>(v, "gravity")?,
            None => [0.0; 3],
        };
        let wind = self.wind(m.get("wind"))?;
        let friction = self.opt_num(m, "friction", "")?.unwrap_or(0.6);
        let obs_friction = self.opt_num(m, "obs_friction", "")?.unwrap_or(0.3);
        let mut collision = vec![
            ("thickness", J::Num(magic.thickness.unwrap_or(1e-3))),
            ("friction", J::Num(obs_friction)),
            ("self_friction", J::Num(friction)),
        ];
        if let Some(k) = magic.stiffness {
            collision.insert(1, ("stiffness", J::Num(k)));
        }
        // ARCSim handles cloth–cloth contact in every scene unless its collision stage is off.
        collision.push(("self_collision", J::Bool(!disabled.collision)));
        let name = self.file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        Ok(obj(vec![
            ("version", J::Int(1)),
            ("name", J::Str(name)),
            ("frame_time", J::Num(frame_time)),
            ("steps_per_frame", J::Int(steps)),
            ("frames", J::Int(frames)),
            ("gravity", nums(&gravity)),
            ("wind", wind),
            ("collision", obj(collision)),
            ("cloths", J::Arr(cloths.into_iter().map(J::Obj).collect())),
            ("obstacles", J::Arr(obstacles)),
        ]))
    }

    /// (frame time, steps per frame, frames) from ARCSim's two timing styles.
    fn timing(&mut self, m: &Map<String, Value>) -> Res<(f64, i64, i64)> {
        let positive = |c: &Self, key: &str| -> Res<Option<f64>> {
            match c.opt_num(m, key, "")? {
                Some(x) if x <= 0.0 => Err(c.err(key, format!("expected a positive number, got {x}"))),
                other => Ok(other),
            }
        };
        let int_at_least_1 = |c: &Self, key: &str| -> Res<Option<i64>> {
            match m.get(key) {
                Some(v) => match c.int(v, key)? {
                    n if n >= 1 => Ok(Some(n)),
                    n => Err(c.err(key, format!("expected an integer ≥ 1, got {n}"))),
                },
                None => Ok(None),
            }
        };
        let (frame_time, steps, end_time) = if let Some(ft) = positive(self, "frame_time")? {
            let steps = int_at_least_1(self, "frame_steps")?.unwrap_or(1);
            let mut end = positive(self, "end_time")?;
            if end.is_none() && m.get("end_frame").is_none() {
                if let Some(d) = positive(self, "duration")? {
                    self.warn(
                        "duration",
                        "ARCSim reads it only with \"timestep\" and runs forever here; used as end_time",
                    );
                    end = Some(d);
                }
            } else if m.contains_key("duration") {
                self.warn("duration", "ignored with frame_time (as in ARCSim)");
            }
            (ft, steps, end)
        } else if let Some(step) = positive(self, "timestep")? {
            let steps = int_at_least_1(self, "save_frames")?.unwrap_or(1);
            (step * steps as f64, steps, positive(self, "duration")?)
        } else {
            return Err(self.err("frame_time", "expected frame_time (s), or timestep"));
        };
        let from_time = end_time.map(|t| (t / frame_time - 1e-9).ceil().max(1.0));
        let from_frame = int_at_least_1(self, "end_frame")?.map(|n| n as f64);
        let frames = match (from_time, from_frame) {
            (Some(a), Some(b)) => a.min(b),
            (Some(a), None) | (None, Some(a)) => a,
            (None, None) => {
                return Err(self.err("end_time", "ARCSim runs until stopped: give end_time or end_frame"));
            }
        };
        if frames > 1e7 {
            return Err(self.err("end_time", format!("expected at most 10000000 frames, got {frames}")));
        }
        Ok((frame_time, steps, frames as i64))
    }

    fn disable(&mut self, v: Option<&Value>) -> Res<Disabled> {
        let mut d = Disabled::default();
        let Some(v) = v else { return Ok(d) };
        for (i, item) in self.array(v, "disable")?.iter().enumerate() {
            let loc = format!("disable[{i}]");
            match self.string(item, &loc)? {
                "remeshing" => d.remeshing = true,
                "strainlimiting" => d.strain_limiting = true,
                "collision" => d.collision = true,
                "plasticity" => d.plasticity = true,
                // Stages viewcloth does not have: nothing to switch off.
                "separation" | "popfilter" | "fracture" => {}
                "proximity" => self.warn(&loc, "repulsion cannot be switched off alone; it stays on"),
                "physics" => self.warn(&loc, "the physics stage cannot be switched off; it stays on"),
                other => self.warn(&loc, format!("unknown module \"{other}\", ignored")),
            }
        }
        Ok(d)
    }

    fn magic(&mut self, v: Option<&Value>) -> Res<Magic> {
        let mut magic = Magic::default();
        let Some(v) = v else { return Ok(magic) };
        let m = self.object(v, "magic")?;
        for (k, val) in m {
            let loc = format!("magic.{k}");
            let positive = |c: &Self| -> Res<f64> {
                match c.num(val, &loc)? {
                    x if x > 0.0 => Ok(x),
                    x => Err(c.err(&loc, format!("expected a positive number, got {x}"))),
                }
            };
            let boolean =
                |c: &Self| val.as_bool().ok_or_else(|| c.err(&loc, format!("expected true or false, got {val}")));
            match k.as_str() {
                "repulsion_thickness" => magic.thickness = Some(positive(self)?),
                "collision_stiffness" => magic.stiffness = Some(positive(self)?),
                "combine_tensors" => magic.combine_tensors = Some(boolean(self)?),
                "fixed_high_res_mesh" => magic.fixed_high_res_mesh = boolean(self)?,
                "handle_stiffness" => self.warn(&loc, "ignored (viewcloth handles are exact constraints)"),
                "projection_thickness"
                | "edge_flip_threshold"
                | "rib_stiffening"
                | "add_jitter"
                | "preserve_creases"
                | "separation_step_size"
                | "relax_method"
                | "max_cracks"
                | "enable_localopt" => self.warn(&loc, "ignored (no viewcloth equivalent)"),
                _ => self.warn(&loc, "unknown magic parameter, ignored"),
            }
        }
        Ok(magic)
    }

    fn transform(&mut self, v: &Value, loc: &str) -> Res<J> {
        let m = self.object(v, loc)?;
        self.check_keys(m, loc, &["translate", "rotate", "scale"], &[]);
        let mut fields = Vec::new();
        if let Some(t) = m.get("translate") {
            fields.push(("translate", nums(&self.numbers::<3>(t, &join(loc, "translate"))?)));
        }
        if let Some(r) = m.get("rotate") {
            fields.push(("rotate", nums(&self.numbers::<4>(r, &join(loc, "rotate"))?)));
        }
        if let Some(s) = self.opt_num(m, "scale", loc)? {
            fields.push(("scale", J::Num(s)));
        }
        Ok(obj(fields))
    }

    /// ARCSim's `motions`: a list of keyframe lists, or `{motfile, fps, transform}`.
    fn motions(&mut self, v: &Value) -> Res<Vec<MotionRef>> {
        if let Some(m) = v.as_object() {
            self.check_keys(m, "motions", &["motfile", "fps", "transform"], &[]);
            let rel = self.string(m.get("motfile").unwrap_or(&Value::Null), "motions.motfile")?;
            let fps = self.num(m.get("fps").unwrap_or(&Value::Null), "motions.fps")?;
            if fps <= 0.0 {
                return Err(self.err("motions.fps", format!("expected a positive number, got {fps}")));
            }
            let transform = match m.get("transform") {
                Some(t) => self.transform(t, "motions.transform")?,
                None => obj(vec![]),
            };
            let (full, file) = self.path(rel);
            let bodies = crate::scene::mot::read_mot(&full)?.bodies.len();
            return Ok((0..bodies)
                .map(|body| MotionRef::Mot { file: file.clone(), body, fps, transform: transform.clone() })
                .collect());
        }
        let list = self.array(v, "motions")?;
        let mut out = Vec::with_capacity(list.len());
        for (i, keys) in list.iter().enumerate() {
            out.push(self.keyframes(keys, &format!("motions[{i}]"))?);
        }
        Ok(out)
    }

    fn keyframes(&mut self, v: &Value, loc: &str) -> Res<MotionRef> {
        let list = self.array(v, loc)?;
        if list.is_empty() {
            return Err(self.err(loc, "expected at least one keyframe"));
        }
        let (mut out, mut keys, mut vels) = (Vec::new(), Vec::new(), Vec::new());
        for (i, kv) in list.iter().enumerate() {
            let kl = format!("{loc}[{i}]");
            let m = self.object(kv, &kl)?;
            self.check_keys(m, &kl, &["time", "transform", "velocity"], &[]);
            let time = self.num(m.get("time").unwrap_or(&Value::Null), &join(&kl, "time"))?;
            let mut fields: Vec<(String, J)> = vec![("time".into(), J::Num(time))];
            let (mut translate, mut rotate, mut scale) = ([0.0; 3], None, 1.0);
            if let Some(t) = m.get("transform") {
                let tl = join(&kl, "transform");
                let J::Obj(tf) = self.transform(t, &tl)? else { unreachable!("transform() builds an object") };
                for (name, value) in tf {
                    match (name.as_str(), &value) {
                        ("translate", J::Arr(a)) => translate = std::array::from_fn(|d| num_of(&a[d])),
                        ("rotate", J::Arr(a)) => rotate = Some(std::array::from_fn(|d| num_of(&a[d]))),
                        ("scale", J::Num(s)) => scale = *s,
                        _ => {}
                    }
                    fields.push((name, value));
                }
            }
            let mut velocity = None;
            if let Some(vv) = m.get("velocity") {
                let vl = join(&kl, "velocity");
                let vm = self.object(vv, &vl)?;
                self.check_keys(vm, &vl, &["translate", "rotate", "scale"], &[]);
                let t = match vm.get("translate") {
                    Some(t) => self.numbers::<3>(t, &join(&vl, "translate"))?,
                    None => [0.0; 3],
                };
                // ARCSim reads a velocity as a transform: scale 1 (its default) means no change.
                let s = match self.opt_num(vm, "scale", &vl)? {
                    Some(s) if s != 1.0 => s,
                    _ => 0.0,
                };
                if let Some(r) = vm.get("rotate") {
                    if self.numbers::<4>(r, &join(&vl, "rotate"))?[0] != 0.0 {
                        self.warn(&join(&vl, "rotate"), "rotation rates are not supported; zero used");
                    }
                }
                fields.push(("velocity".into(), obj(vec![("translate", nums(&t)), ("scale", J::Num(s))])));
                velocity = Some(KeyVelocity { translate: t.into(), scale: s });
            }
            out.push(J::Obj(fields));
            keys.push(Keyframe { time, transform: Transform::new(translate, rotate, scale) });
            vels.push(velocity);
        }
        Ok(MotionRef::Keys(J::Arr(out), Motion::with_velocities(keys, vels)))
    }

    fn motion_index(&self, m: &Map<String, Value>, loc: &str, motions: &[MotionRef]) -> Res<Option<MotionRef>> {
        let Some(v) = m.get("motion") else { return Ok(None) };
        let ml = join(loc, "motion");
        match self.int(v, &ml)? {
            -1 => Ok(None),
            i if i >= 0 && (i as usize) < motions.len() => Ok(Some(motions[i as usize].clone())),
            i => Err(self.err(&ml, format!("expected a motion index in 0..{}, got {i}", motions.len()))),
        }
    }

    fn handle(
        &mut self,
        v: &Value,
        h: usize,
        motions: &[MotionRef],
        meshes: &[PathBuf],
        cloths: &mut [Vec<(String, J)>],
    ) -> Res<()> {
        let loc = format!("handles[{h}]");
        let m = self.object(v, &loc)?;
        let kind = match m.get("type") {
            Some(t) => self.string(t, &join(&loc, "type"))?,
            None => "node",
        };
        if kind != "node" {
            let why = match kind {
                "circle" | "glue" | "soft" => format!("{kind} handles are not supported; skipped"),
                other => format!("unknown handle type \"{other}\"; skipped"),
            };
            self.warn(&join(&loc, "type"), why);
            return Ok(());
        }
        let known = ["type", "cloth", "nodes", "label", "motion", "start_time", "end_time", "fade_time"];
        self.check_keys(m, &loc, &known, &[]);
        let c = match m.get("cloth") {
            Some(v) => self.int(v, &join(&loc, "cloth"))?,
            None => 0,
        };
        if c < 0 || c as usize >= cloths.len() {
            return Err(
                self.err(&join(&loc, "cloth"), format!("expected a cloth index in 0..{}, got {c}", cloths.len()))
            );
        }
        let c = c as usize;
        let label = match m.get("label") {
            Some(l) => self.int(l, &join(&loc, "label"))?,
            None => -1,
        };
        let nodes: Vec<J> = if label != -1 {
            let labels = node_labels(&meshes[c]).map_err(|msg| self.err(&join(&loc, "label"), msg))?;
            let ns: Vec<J> = (0..labels.len()).filter(|&n| labels[n] == label).map(|n| J::Int(n as i64)).collect();
            if ns.is_empty() {
                let msg = format!("no node of {} has label {label} (OBJ \"nl\" lines)", meshes[c].display());
                return Err(self.err(&join(&loc, "label"), msg));
            }
            ns
        } else {
            let list = self.array(m.get("nodes").unwrap_or(&Value::Null), &join(&loc, "nodes"))?;
            let mut ns = Vec::with_capacity(list.len());
            for (i, n) in list.iter().enumerate() {
                ns.push(J::Int(self.int(n, &format!("{loc}.nodes[{i}]"))?));
            }
            ns
        };
        let mut fields: Vec<(&str, J)> = vec![("nodes", J::Arr(nodes))];
        let start = self.opt_num(m, "start_time", &loc)?;
        if let Some(motion) = self.motion_index(m, &loc, motions)? {
            if let MotionRef::Keys(_, mo) = &motion {
                let t = mo.eval(start.unwrap_or(0.0));
                let identity = t.translate.norm() < 1e-12 && (t.scale - 1.0).abs() < 1e-12 && t.rotate.angle() < 1e-12;
                if !identity {
                    let msg =
                        "the motion is not the identity when the handle starts: ARCSim moves the nodes relative to \
                               their position then, viewcloth applies it to their initial positions";
                    self.warn(&join(&loc, "motion"), msg);
                }
            }
            fields.push(motion.field());
        }
        if let Some(s) = start {
            fields.push(("start_time", J::Num(s)));
        }
        if let Some(e) = self.opt_num(m, "end_time", &loc)? {
            fields.push(("end_time", J::Num(e)));
        }
        if self.opt_num(m, "fade_time", &loc)?.is_some_and(|f| f > 0.0) {
            self.warn(&join(&loc, "fade_time"), "handles release at end_time without fading");
        }
        let handle = obj(fields);
        let cloth = &mut cloths[c];
        match cloth.iter_mut().find(|(k, _)| k == "handles") {
            Some((_, J::Arr(list))) => list.push(handle),
            _ => cloth.push(("handles".into(), J::Arr(vec![handle]))),
        }
        Ok(())
    }

    fn obstacles(&mut self, v: &Value, motions: &[MotionRef]) -> Res<Vec<J>> {
        if let Some(pattern) = v.as_str() {
            // One obstacle per existing file pattern(0), pattern(1), …, obstacle i moved by motion i.
            let mut out = Vec::new();
            for i in 0.. {
                let rel = crate::scene::load::format_frame(pattern, i).map_err(|msg| self.err("obstacles", msg))?;
                let (full, mesh) = self.path(&rel);
                if !full.is_file() {
                    break;
                }
                let name = full.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                let mut fields = vec![("name", J::Str(name)), ("mesh", J::Str(mesh))];
                if let Some(m) = motions.get(i as usize) {
                    fields.push(m.field());
                }
                out.push(obj(fields));
            }
            if out.is_empty() {
                let first = self.base.join(crate::scene::load::format_frame(pattern, 0).unwrap_or_default());
                return Err(self.err("obstacles", format!("no obstacle file: {} does not exist", first.display())));
            }
            return Ok(out);
        }
        let mut out = Vec::new();
        for (o, ov) in self.array(v, "obstacles")?.iter().enumerate() {
            let loc = format!("obstacles[{o}]");
            let m = self.object(ov, &loc)?;
            let ignored = [
                ("start_time", "obstacles are present for the whole shot"),
                ("end_time", "obstacles are present for the whole shot"),
                ("proxy", "proxies are not supported; the mesh is used"),
            ];
            self.check_keys(m, &loc, &["mesh", "transform", "motion"], &ignored);
            let rel = self.string(m.get("mesh").unwrap_or(&Value::Null), &join(&loc, "mesh"))?;
            let (_, mesh) = self.path(rel);
            let mut fields = vec![("mesh", J::Str(mesh))];
            if let Some(t) = m.get("transform") {
                fields.push(("transform", self.transform(t, &join(&loc, "transform"))?));
            }
            if let Some(motion) = self.motion_index(m, &loc, motions)? {
                fields.push(motion.field());
            }
            out.push(obj(fields));
        }
        Ok(out)
    }

    /// ARCSim always applies its wind force (air density 1, drag 0 by default): still air damps
    /// the cloth's normal motion.
    fn wind(&mut self, v: Option<&Value>) -> Res<J> {
        let (mut velocity, mut density, mut drag) = ([0.0; 3], 1.0, 0.0);
        if let Some(v) = v {
            let m = self.object(v, "wind")?;
            self.check_keys(m, "wind", &["velocity", "density", "drag"], &[]);
            if let Some(w) = m.get("velocity") {
                velocity = self.numbers::<3>(w, "wind.velocity")?;
            }
            density = self.opt_num(m, "density", "wind")?.unwrap_or(density);
            drag = self.opt_num(m, "drag", "wind")?.unwrap_or(drag);
        }
        Ok(obj(vec![("velocity", nums(&velocity)), ("density", J::Num(density)), ("drag", J::Num(drag))]))
    }
}

fn join(loc: &str, key: &str) -> String {
    if loc.is_empty() {
        key.to_string()
    } else {
        format!("{loc}.{key}")
    }
}

fn num_of(j: &J) -> f64 {
    match j {
        J::Num(x) => *x,
        J::Int(i) => *i as f64,
        _ => 0.0,
    }
}

/// Node labels of an ARCSim OBJ (`nl <label>` after a `v` line; 0 when absent), per node.
fn node_labels(path: &Path) -> Result<Vec<i64>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read mesh file {}: {e}", path.display()))?;
    let mut labels: Vec<i64> = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => labels.push(0),
            Some("nl") => {
                let label = words.next().and_then(|w| w.parse().ok());
                match (labels.last_mut(), label) {
                    (Some(l), Some(x)) => *l = x,
                    _ => return Err(format!("{}: line {}: bad \"nl\" line", path.display(), ln + 1)),
                }
            }
            _ => {}
        }
    }
    Ok(labels)
}
