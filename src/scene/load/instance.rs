//! `instances`: copies of another scene file's cloths and obstacles, each placed by a transform
//! and shifted in time, loaded as cloths and obstacles of their own (names suffixed with the
//! instance's name), so that nothing downstream knows about instancing.
//!
//! An instance with placement P and time offset τ is, at time t, the original at t + τ carried
//! by P: an obstacle follows P ∘ motion(t + τ) ∘ transform (a sequence's files and its time
//! window shift by τ too), a handle's motion becomes P ∘ M(t + τ) (anchors then move by
//! P ∘ D(t + τ) ∘ P⁻¹), its `start_time` and `end_time` come τ earlier, and a cloth starts at P
//! applied to its own initial positions (its material coordinates scaled with P's scale, as a
//! cloth's own `transform` scales them). The cloth itself is not advanced: it starts from its
//! initial state at the run's start, whatever τ.

use std::path::{Path, PathBuf};

use super::{add_cloth, finite_time, load_obstacle, transform, Ctx, Res};
use crate::collision::shape::{Obstacle, ObstacleShape};
use crate::error::InputError;
use crate::math::motion::{Keyframe, Motion, Transform};
use crate::math::{Real, Vec3};
use crate::scene::spec::{InstanceSpec, SceneSpec};
use crate::scene::{Handle, HandleKind, Scene};

/// Where an instance is put and how far ahead in time it runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Placement {
    pub transform: Transform,
    pub time_offset: Real,
}

impl Placement {
    /// The original itself: nothing is moved (so the scene's own cloths and obstacles keep
    /// their bits).
    pub const IDENTITY: Placement = Placement {
        transform: Transform {
            translate: Vec3::new(0.0, 0.0, 0.0),
            rotate: nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(1.0, 0.0, 0.0, 0.0)),
            scale: 1.0,
        },
        time_offset: 0.0,
    };

    fn is_identity(&self) -> bool {
        *self == Placement::IDENTITY
    }

    /// A point of the original, placed.
    pub fn point(&self, p: &Vec3) -> Vec3 {
        if self.is_identity() {
            *p
        } else {
            self.transform.apply(p)
        }
    }

    /// A velocity (or any direction with a length) of the original, placed.
    pub fn vector(&self, v: &Vec3) -> Vec3 {
        if self.is_identity() {
            *v
        } else {
            self.transform.rotate * (self.transform.scale * v)
        }
    }

    /// A time of the original as a time of the instance: τ earlier (infinities stay).
    pub fn time(&self, t: Real) -> Real {
        t - self.time_offset
    }

    fn motion(&self, m: &Motion) -> Motion {
        m.placed(&self.transform, self.time_offset)
    }

    /// The obstacle `o` of the original scene as this instance's.
    pub fn obstacle(&self, mut o: Obstacle) -> Obstacle {
        if self.is_identity() {
            return o;
        }
        match &o.motion {
            Some(m) => o.motion = Some(self.motion(m)),
            None => o.transform = self.transform.compose(&o.transform),
        }
        if let ObstacleShape::Sequence(s) = &mut o.shape {
            s.start_time = self.time(s.start_time);
        }
        o.window.start = self.time(o.window.start);
        o.window.end = self.time(o.window.end);
        o
    }

    /// A handle of the original as this instance's (its anchors, taken from the placed nodes,
    /// and an obstacle it follows, already placed, are left as they are).
    pub fn handle(&self, mut h: Handle) -> Handle {
        if self.is_identity() {
            return h;
        }
        h.motion = match (&h.motion, &h.kind) {
            (Some(m), _) => Some(self.motion(m)),
            // A circle without motion sits where its fields put it: there, placed.
            (None, HandleKind::Circle(_)) => Some(Motion::new(vec![Keyframe { time: 0.0, transform: self.transform }])),
            (None, _) => None,
        };
        h.start = self.time(h.start);
        h.end = self.time(h.end);
        h
    }
}

/// An instance read and checked: its placement, name suffix and the scene it copies.
pub(super) struct Instance {
    placement: Placement,
    suffix: String,
    file: PathBuf,
    spec: SceneSpec,
}

/// Reads every instance's scene file and checks the instance's own fields.
pub(super) fn read_instances(ctx: &Ctx, specs: &[InstanceSpec]) -> Res<Vec<Instance>> {
    let mut out: Vec<Instance> = Vec::with_capacity(specs.len());
    for (k, is) in specs.iter().enumerate() {
        let path = format!("instances[{k}]");
        let suffix = is.name.clone().unwrap_or_else(|| format!("i{k}"));
        if suffix.is_empty() || !suffix.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
            let msg = format!("expected a name of letters, digits, '_' or '-' (it ends file names), got \"{suffix}\"");
            return Err(ctx.err(format!("{path}.name"), msg));
        }
        if let Some(j) = out.iter().position(|o| o.suffix == suffix) {
            let msg = format!("\"{suffix}\" is also instances[{j}]'s name: name the instances apart");
            return Err(ctx.err(format!("{path}.name"), msg));
        }
        let time_offset = finite_time(ctx, &format!("{path}.time_offset"), is.time_offset)?;
        let placement =
            Placement { transform: transform(ctx, &format!("{path}.transform"), &is.transform)?, time_offset };
        let file = ctx.resolve(&is.scene);
        let text = std::fs::read_to_string(&file)
            .map_err(|e| ctx.err(format!("{path}.scene"), format!("cannot read scene file {}: {e}", file.display())))?;
        let spec: SceneSpec = crate::io::json::parse(&text).map_err(|(loc, msg)| InputError {
            file: file.clone(),
            location: Some(loc),
            msg,
        })?;
        if spec.version != 1 {
            let msg = format!("expected a scene file of version 1 (an ARCSim conf must be converted first: viewcloth convert), got version {}", spec.version);
            return Err(ctx.err(format!("{path}.scene"), msg));
        }
        if !spec.instances.is_empty() {
            let msg = format!("\"{}\" has instances of its own; instances do not nest", is.scene);
            return Err(ctx.err(format!("{path}.scene"), msg));
        }
        if spec.cloths.is_empty() && spec.obstacles.is_empty() {
            return Err(ctx.err(format!("{path}.scene"), format!("\"{}\" has no cloth and no obstacle", is.scene)));
        }
        out.push(Instance { placement, suffix, file, spec });
    }
    Ok(out)
}

impl Instance {
    fn ctx(&self) -> Ctx<'_> {
        Ctx { file: &self.file, base: self.file.parent().unwrap_or(Path::new(".")) }
    }

    fn named(&self, name: &str) -> String {
        format!("{name}_{}", self.suffix)
    }

    /// Adds the instance's obstacles to `scene`, placed and named `<name>_<suffix>`.
    pub fn add_obstacles(&self, scene: &mut Scene) -> Res<()> {
        for (o, os) in self.spec.obstacles.iter().enumerate() {
            let mut os = os.clone();
            os.name = Some(self.named(os.name.as_deref().unwrap_or(&format!("obstacle{o}"))));
            let obstacle = load_obstacle(&self.ctx(), o, &os)?;
            scene.obstacles.push(self.placement.obstacle(obstacle));
        }
        Ok(())
    }

    /// Adds the instance's cloths to `scene` (after every obstacle: handles may ride on one of
    /// the instance's obstacles, whose name is suffixed likewise).
    pub fn add_cloths(&self, scene: &mut Scene) -> Res<()> {
        for (c, cs) in self.spec.cloths.iter().enumerate() {
            let mut cs = cs.clone();
            cs.name = Some(self.named(cs.name.as_deref().unwrap_or(&format!("cloth{c}"))));
            for h in &mut cs.handles {
                h.obstacle = h.obstacle.as_deref().map(|n| self.named(n));
            }
            add_cloth(&self.ctx(), scene, &format!("cloths[{c}]"), &cs, &self.placement)?;
        }
        Ok(())
    }
}

/// Names of cloths and of obstacles must be unique once instances are in: a name is an output
/// file name (`obstacle_<name>_NNNN.obj`) and what handles find obstacles by.
pub(super) fn check_unique_names(ctx: &Ctx, scene: &Scene) -> Res<()> {
    let clash = |names: Vec<&str>| -> Option<String> {
        let mut seen = std::collections::HashSet::new();
        names.into_iter().find(|n| !seen.insert(*n)).map(str::to_string)
    };
    if let Some(n) = clash(scene.cloths.iter().map(|c| c.name.as_str()).collect()) {
        return Err(ctx.err("instances", format!("two cloths are named \"{n}\": name the instances or cloths apart")));
    }
    if let Some(n) = clash(scene.obstacles.iter().map(|o| o.name.as_str()).collect()) {
        let msg = format!("two obstacles are named \"{n}\": name the instances or obstacles apart");
        return Err(ctx.err("instances", msg));
    }
    Ok(())
}
