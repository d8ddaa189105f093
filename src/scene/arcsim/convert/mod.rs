//! The conversion of a parsed ARCSim conf into a viewcloth scene (see the parent module): an
//! ordered JSON value that reads top-down, built key by key with a warning for every ARCSim key
//! that has no viewcloth equivalent.

use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use super::ordered::{nums, obj, J};
use super::Res;
use crate::error::InputError;

mod cloth;
mod handle;

/// A conversion: the viewcloth scene and the warnings.
pub struct Converted {
    pub scene: J,
    pub warnings: Vec<String>,
    /// Where fields of the scene come from in the conf (`conf_location`).
    origins: Vec<(String, Origin)>,
}

/// The conf field a scene field (and what is under it) was converted from.
#[derive(Clone, Debug)]
enum Origin {
    /// The same subpath under this conf path.
    Same(String),
    /// A keyframe list from this entry of `motions`: a key's `translate`, `rotate` and `scale`
    /// are under its `transform` in the conf.
    Motion(String),
}

impl Converted {
    /// The conf location of the scene location `loc` (a JSON path the scene loader reported),
    /// when the conversion knows it.
    pub fn conf_location(&self, loc: &str) -> Option<String> {
        let under = |prefix: &str| {
            let rest = loc.strip_prefix(prefix)?;
            (rest.is_empty() || rest.starts_with(['.', '['])).then_some(rest)
        };
        let (rest, origin) = self
            .origins
            .iter()
            .filter_map(|(prefix, o)| under(prefix).map(|rest| (rest, o)))
            .min_by_key(|(rest, _)| rest.len())?;
        Some(match origin {
            Origin::Same(conf) => format!("{conf}{rest}"),
            Origin::Motion(conf) => {
                // `[k].scale` → `[k].transform.scale`
                let (key, field) =
                    rest.split_once("].").map(|(k, f)| (format!("{k}]"), f)).unwrap_or((rest.into(), ""));
                match field.split('.').next() {
                    Some("translate" | "rotate" | "scale") => format!("{conf}{key}.transform.{field}"),
                    _ if field.is_empty() => format!("{conf}{key}"),
                    _ => format!("{conf}{key}.{field}"),
                }
            }
        })
    }
}

/// Converts a parsed conf. `write_path` turns a resolved file path into the string written
/// into the scene.
pub fn convert(conf: &Value, file: &Path, base: &Path, write_path: &dyn Fn(&Path) -> String) -> Res<Converted> {
    let mut c = Conv { file, base, write_path, warnings: Vec::new(), origins: Vec::new() };
    let scene = c.scene(conf)?;
    Ok(Converted { scene, warnings: c.warnings, origins: c.origins })
}

/// A motion of the conf's `motions`, as the scene will state it.
#[derive(Clone)]
enum MotionRef {
    /// Keyframes (viewcloth form).
    Keys(J),
    /// Body `body` of a `.mot` file.
    Mot { file: String, body: usize, fps: f64, transform: J },
}

impl MotionRef {
    /// The scene field and value that attach this motion.
    fn field(&self) -> (&'static str, J) {
        match self {
            MotionRef::Keys(keys) => ("motion", keys.clone()),
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
    /// Every handle's spring stiffness (N/m; a circle's per metre of ring); ARCSim's default
    /// 1e3 when absent.
    handle_stiffness: Option<f64>,
    preserve_creases: bool,
}

/// ARCSim's `magic.handle_stiffness` default (`magic.hpp`).
const ARCSIM_HANDLE_STIFFNESS: f64 = 1e3;

/// ARCSim's `magic.collision_stiffness` default (`magic.hpp`).
const ARCSIM_COLLISION_STIFFNESS: f64 = 1e9;

/// ARCSim's repulsion energy is cubic in the depth v inside the thickness τ, K·a·v³/(6τ)
/// (`constraint.cpp`, `IneqCon::energy`, with a the smaller area of the pair): a converted conf
/// gets that law, `collision.penalty: "arcsim"`, with the conf's K as `collision.stiffness`
/// (ARCSim's default 1e9 when the conf has none). Until the cubic law was linearised with the
/// obstacle at the start of the step (`collision::speculative`), confs got viewcloth's quadratic
/// law at K/3 (equal energy at one thickness), 1.35 times weaker than ARCSim's at 90% of the
/// thickness: ARCSim's sphere.json sheet came within 0.55 mm of the sphere against ARCSim's 0.6.

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
    origins: Vec<(String, Origin)>,
}

impl Conv<'_> {
    fn err(&self, loc: &str, msg: impl Into<String>) -> InputError {
        let location = if loc.is_empty() { None } else { Some(loc.to_string()) };
        InputError { file: self.file.to_path_buf(), location, msg: msg.into() }
    }

    fn warn(&mut self, loc: &str, msg: impl AsRef<str>) {
        self.warnings.push(format!("{loc}: {}", msg.as_ref()));
    }

    /// Records that the scene field at `scene_loc` comes from the conf as `origin` says.
    fn origin(&mut self, scene_loc: &str, origin: Origin) {
        self.origins.push((scene_loc.to_string(), origin));
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
        let disable = self.disable(m.get("disable"))?;
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
            self.origin(&format!("cloths[{i}]"), Origin::Same(format!("cloths[{i}]")));
            let (fields, mesh) = self.cloth(cv, i, &magic)?;
            cloths.push(fields);
            meshes.push(mesh);
        }
        if let Some(hs) = m.get("handles") {
            for (h, hv) in self.array(hs, "handles")?.iter().enumerate() {
                self.handle(hv, h, &motions, &meshes, &magic, &mut cloths)?;
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
        let k = magic.stiffness.unwrap_or(ARCSIM_COLLISION_STIFFNESS);
        collision.insert(1, ("stiffness", J::Num(k)));
        collision.insert(2, ("penalty", J::Str("arcsim".into())));
        // ARCSim handles cloth–cloth contact in every scene (its proximity and collision
        // stages; `disable` may switch either off).
        collision.push(("self_collision", J::Bool(true)));
        let name = self.file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let mut fields = vec![
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
        ];
        if magic.preserve_creases {
            // ARCSim relaxes every run's initial state (`relax_initial_state`) and, under
            // `preserve_creases`, rests the cloth in the relaxed shape. Converted confs relax only
            // here (README, "ARCSim's initial relaxation"): the input of such a conf is a folded
            // model whose folds need not be isometric to its pattern (dart.obj starts at 13%
            // strain, 170 J of elastic energy) and is its rest shape, so it must relax first.
            fields.push(("initial_relax", J::Bool(true)));
            self.origin("initial_relax", Origin::Same("magic.preserve_creases".into()));
        }
        if !disable.is_empty() {
            fields.push(("disable", J::Arr(disable.iter().map(|d| J::Str(d.to_string())).collect())));
        }
        self.origin("collision.thickness", Origin::Same("magic.repulsion_thickness".into()));
        self.origin("collision.stiffness", Origin::Same("magic.collision_stiffness".into()));
        self.origin("collision.friction", Origin::Same("obs_friction".into()));
        self.origin("collision.self_friction", Origin::Same("friction".into()));
        for top in ["gravity", "wind", "disable"] {
            self.origin(top, Origin::Same(top.into()));
        }
        Ok(obj(fields))
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
                        "ARCSim reads it only with \"timestep\" (with frame_time it runs until stopped); used as end_time",
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

    /// ARCSim's `disable` (`conf.cpp`: module names "proximity", "physics", "strainlimiting",
    /// "collision", "remeshing", "separation", "popfilter", "plasticity"; others are ignored) as
    /// the scene's `disable`. One warning names the stages viewcloth does not have.
    fn disable(&mut self, v: Option<&Value>) -> Res<Vec<&'static str>> {
        let mut out = Vec::new();
        let mut absent = Vec::new();
        let Some(v) = v else { return Ok(out) };
        for (i, item) in self.array(v, "disable")?.iter().enumerate() {
            let loc = format!("disable[{i}]");
            let name = match self.string(item, &loc)? {
                "strainlimiting" => "strain_limiting",
                "proximity" => "proximity",
                "physics" => "physics",
                "collision" => "collision",
                "remeshing" => "remeshing",
                "separation" => "separation",
                "popfilter" => "pop_filter",
                "plasticity" => "plasticity",
                // ARCSim's stage that viewcloth does not have: nothing to switch off.
                other @ "fracture" => {
                    if !absent.contains(&other.to_string()) {
                        absent.push(other.to_string());
                    }
                    continue;
                }
                other => {
                    self.warn(&loc, format!("\"{other}\" is not an ARCSim module; ignored (as ARCSim does)"));
                    continue;
                }
            };
            if !out.contains(&name) {
                out.push(name);
            }
        }
        if !absent.is_empty() {
            let msg = format!("viewcloth has no {} stage; nothing to switch off", absent.join(", "));
            self.warn("disable", msg);
        }
        Ok(out)
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
                "handle_stiffness" => magic.handle_stiffness = Some(positive(self)?),
                "preserve_creases" => magic.preserve_creases = boolean(self)?,
                "projection_thickness"
                | "edge_flip_threshold"
                | "rib_stiffening"
                | "add_jitter"
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
        let mut out = Vec::new();
        for (i, kv) in list.iter().enumerate() {
            let kl = format!("{loc}[{i}]");
            let m = self.object(kv, &kl)?;
            self.check_keys(m, &kl, &["time", "transform", "velocity"], &[]);
            let time = self.num(m.get("time").unwrap_or(&Value::Null), &join(&kl, "time"))?;
            let mut fields: Vec<(String, J)> = vec![("time".into(), J::Num(time))];
            if let Some(t) = m.get("transform") {
                let tl = join(&kl, "transform");
                let J::Obj(tf) = self.transform(t, &tl)? else { unreachable!("transform() builds an object") };
                fields.extend(tf);
            }
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
            }
            out.push(J::Obj(fields));
        }
        Ok(MotionRef::Keys(J::Arr(out)))
    }

    /// Records that the scene's keyframes at `scene_loc` come from the conf motion that `m`'s
    /// `motion` index (at `loc`) names.
    fn motion_origin(&mut self, scene_loc: &str, m: &Map<String, Value>, loc: &str) {
        let Some(i) = m.get("motion").and_then(Value::as_i64) else { return };
        self.origin(scene_loc, Origin::Motion(format!("motions[{i}]")));
        self.origin(&scene_loc.replace(".motion", ".mot"), Origin::Same(format!("{loc}.motion")));
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
            let ignored = [("proxy", "proxies are not supported; the mesh is used")];
            let known = ["mesh", "transform", "motion", "start_time", "end_time"];
            self.check_keys(m, &loc, &known, &ignored);
            self.origin(&loc, Origin::Same(loc.clone()));
            let rel = self.string(m.get("mesh").unwrap_or(&Value::Null), &join(&loc, "mesh"))?;
            let (_, mesh) = self.path(rel);
            let mut fields = vec![("mesh", J::Str(mesh))];
            if let Some(t) = m.get("transform") {
                fields.push(("transform", self.transform(t, &join(&loc, "transform"))?));
            }
            if let Some(motion) = self.motion_index(m, &loc, motions)? {
                self.motion_origin(&join(&loc, "motion"), m, &loc);
                fields.push(motion.field());
            }
            // Present from start_time to end_time (ARCSim's `Obstacle::get_mesh`).
            for key in ["start_time", "end_time"] {
                if let Some(t) = self.opt_num(m, key, &loc)? {
                    fields.push((key, J::Num(t)));
                }
            }
            out.push(obj(fields));
        }
        Ok(out)
    }

    /// ARCSim always applies its wind force (air density 1, drag 0 by default): still air damps
    /// the cloth's normal motion. Its force is explicit (no Jacobian in the system): `implicit`
    /// false.
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
        Ok(obj(vec![
            ("velocity", nums(&velocity)),
            ("density", J::Num(density)),
            ("drag", J::Num(drag)),
            ("implicit", J::Bool(false)),
        ]))
    }
}

fn join(loc: &str, key: &str) -> String {
    if loc.is_empty() {
        key.to_string()
    } else {
        format!("{loc}.{key}")
    }
}
