//! Conversion of a conf's `handles` as ARCSim 0.2.1 reads them (`conf.cpp`: `parse_handle`,
//! `parse_node_handle`, `parse_circle_handle`, `parse_glue_handle`; `handle.cpp`).
//!
//! Every ARCSim handle is a penalty spring of stiffness `magic.handle_stiffness` (default 1e3
//! N/m), so each becomes a soft handle (`stiffness`). `start_time` (default 0), `end_time` and
//! `fade_time` carry over; ARCSim anchors a node handle's nodes where they are when it switches
//! on, as viewcloth does. Node handles take their nodes from `label` (OBJ `nl` lines; `nodes`
//! is then not read) or from `nodes`; a handle with neither holds nothing in ARCSim (jsoncpp
//! 0.5 reads a missing array as empty) and is skipped with a warning. A circle handle's ring is
//! the nodes of its label; a glue handle ties exactly two nodes.

use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use super::{join, nums, obj, Conv, Magic, MotionRef, Origin, Res, ARCSIM_HANDLE_STIFFNESS, J};

const COMMON: [&str; 6] = ["type", "cloth", "motion", "start_time", "end_time", "fade_time"];

impl Conv<'_> {
    /// Conf handle `h` into its cloth's `handles` (or skipped with a warning).
    pub(super) fn handle(
        &mut self,
        v: &Value,
        h: usize,
        motions: &[MotionRef],
        meshes: &[PathBuf],
        magic: &Magic,
        cloths: &mut [Vec<(String, J)>],
    ) -> Res<()> {
        let loc = format!("handles[{h}]");
        let m = self.object(v, &loc)?;
        let kind = match m.get("type") {
            Some(t) => self.string(t, &join(&loc, "type"))?,
            None => "node",
        };
        let c = match m.get("cloth") {
            Some(v) => self.int(v, &join(&loc, "cloth"))?,
            None => 0,
        };
        if c < 0 || c as usize >= cloths.len() {
            let msg = format!("expected a cloth index in 0..{}, got {c}", cloths.len());
            return Err(self.err(&join(&loc, "cloth"), msg));
        }
        let c = c as usize;
        let mut fields: Vec<(&str, J)> = match kind {
            "node" => match self.node_selection(m, &loc, &meshes[c])? {
                Some(nodes) => vec![("nodes", nodes)],
                None => return Ok(()),
            },
            "circle" => self.circle(m, &loc, &meshes[c])?,
            "glue" => self.glue(m, &loc)?,
            other => {
                let msg =
                    format!("expected \"node\", \"circle\" or \"glue\" (ARCSim stops on any other), got \"{other}\"");
                return Err(self.err(&join(&loc, "type"), msg));
            }
        };
        let index = cloths[c].iter().find(|(k, _)| k == "handles").map_or(0, |(_, l)| match l {
            J::Arr(l) => l.len(),
            _ => 0,
        });
        let scene_loc = format!("cloths[{c}].handles[{index}]");
        self.origin(&scene_loc, Origin::Same(loc.clone()));
        self.origin(&join(&scene_loc, "stiffness"), Origin::Same("magic.handle_stiffness".into()));
        if kind != "glue" {
            if let Some(motion) = self.motion_index(m, &loc, motions)? {
                self.motion_origin(&join(&scene_loc, "motion"), m, &loc);
                fields.push(motion.field());
            }
        } else if m.contains_key("motion") {
            self.warn(&join(&loc, "motion"), "ignored: a glue handle does not move (as in ARCSim)");
        }
        fields.push(("stiffness", J::Num(magic.handle_stiffness.unwrap_or(ARCSIM_HANDLE_STIFFNESS))));
        let start = self.opt_num(m, "start_time", &loc)?;
        let end = self.opt_num(m, "end_time", &loc)?;
        if let Some(s) = start {
            fields.push(("start_time", J::Num(s)));
        }
        if let Some(e) = end {
            fields.push(("end_time", J::Num(e)));
        }
        // Without an end the handle never fades (ARCSim's strength is 1 until end_time).
        match (self.opt_num(m, "fade_time", &loc)?, end) {
            (Some(f), Some(_)) if f > 0.0 => fields.push(("fade_time", J::Num(f))),
            (Some(f), _) if f < 0.0 => {
                return Err(self.err(&join(&loc, "fade_time"), format!("expected a number ≥ 0, got {f}")));
            }
            _ => {}
        }
        let handle = obj(fields);
        let cloth = &mut cloths[c];
        match cloth.iter_mut().find(|(k, _)| k == "handles") {
            Some((_, J::Arr(list))) => list.push(handle),
            _ => cloth.push(("handles".into(), J::Arr(vec![handle]))),
        }
        Ok(())
    }

    /// A node handle's nodes: those labelled `label`, or `nodes`; `None` (with a warning) when
    /// the handle gives neither, as ARCSim then makes no handle.
    fn node_selection(&mut self, m: &Map<String, Value>, loc: &str, mesh: &Path) -> Res<Option<J>> {
        let mut known = COMMON.to_vec();
        known.extend(["nodes", "label", "vertices"]);
        self.check_keys(m, loc, &known, &[]);
        if let Some(label) = m.get("label").map(|l| self.int(l, &join(loc, "label"))).transpose()? {
            if label != -1 {
                if m.contains_key("nodes") {
                    self.warn(&join(loc, "nodes"), "ignored: the handle has a label (as in ARCSim)");
                }
                return self.labelled(mesh, label, &join(loc, "label")).map(Some);
            }
        }
        let Some(list) = m.get("nodes") else {
            // jsoncpp 0.5 reads the missing "nodes" as an empty list: ARCSim makes no handle.
            let (at, msg) = match m.contains_key("vertices") {
                true => (join(loc, "vertices"), "ignored: ARCSim 0.2.1 reads a handle's nodes from \"nodes\" (or \"label\"), so this handle holds nothing there; skipped"),
                false => (loc.to_string(), "no \"nodes\" or \"label\": ARCSim makes no handle of it; skipped"),
            };
            self.warn(&at, msg);
            return Ok(None);
        };
        if m.contains_key("vertices") {
            self.warn(&join(loc, "vertices"), "ignored: ARCSim 0.2.1 reads a handle's nodes from \"nodes\"");
        }
        let list = self.array(list, &join(loc, "nodes"))?;
        if list.is_empty() {
            self.warn(&join(loc, "nodes"), "empty: ARCSim makes no handle of it; skipped");
            return Ok(None);
        }
        let mut ns = Vec::with_capacity(list.len());
        for (i, n) in list.iter().enumerate() {
            ns.push(J::Int(self.int(n, &format!("{loc}.nodes[{i}]"))?));
        }
        Ok(Some(J::Arr(ns)))
    }

    /// The nodes of `mesh` labelled `label`, as a JSON list.
    fn labelled(&self, mesh: &Path, label: i64, loc: &str) -> Res<J> {
        let labels = node_labels(mesh).map_err(|msg| self.err(loc, msg))?;
        let ns: Vec<J> = (0..labels.len()).filter(|&n| labels[n] == label).map(|n| J::Int(n as i64)).collect();
        if ns.is_empty() {
            return Err(self.err(loc, format!("no node of {} has label {label} (OBJ \"nl\" lines)", mesh.display())));
        }
        Ok(J::Arr(ns))
    }

    /// A circle handle: the ring of `label`'s nodes and the circle (all fields required, as
    /// ARCSim's `parse_circle_handle` stops without them).
    fn circle(&mut self, m: &Map<String, Value>, loc: &str, mesh: &Path) -> Res<Vec<(&'static str, J)>> {
        let mut known = COMMON.to_vec();
        known.extend(["label", "circumference", "u", "center", "axis0", "axis1"]);
        self.check_keys(m, loc, &known, &[]);
        let need = |key: &str| m.get(key).ok_or_else(|| self.err(&join(loc, key), "required for a circle handle"));
        let label = self.int(need("label")?, &join(loc, "label"))?;
        let nodes = self.labelled(mesh, label, &join(loc, "label"))?;
        let circumference = self.num(need("circumference")?, &join(loc, "circumference"))?;
        let u = self.numbers::<2>(need("u")?, &join(loc, "u"))?;
        let center = self.numbers::<3>(need("center")?, &join(loc, "center"))?;
        let axis0 = self.numbers::<3>(need("axis0")?, &join(loc, "axis0"))?;
        let axis1 = self.numbers::<3>(need("axis1")?, &join(loc, "axis1"))?;
        let circle = obj(vec![
            ("circumference", J::Num(circumference)),
            ("u", nums(&u)),
            ("center", nums(&center)),
            ("axis0", nums(&axis0)),
            ("axis1", nums(&axis1)),
        ]);
        Ok(vec![("nodes", nodes), ("circle", circle)])
    }

    /// A glue handle: exactly two nodes (ARCSim stops otherwise).
    fn glue(&mut self, m: &Map<String, Value>, loc: &str) -> Res<Vec<(&'static str, J)>> {
        let mut known = COMMON.to_vec();
        known.push("nodes");
        self.check_keys(m, loc, &known, &[]);
        let nl = join(loc, "nodes");
        let list = self.array(m.get("nodes").unwrap_or(&Value::Null), &nl)?;
        if list.len() != 2 {
            return Err(self.err(&nl, format!("expected exactly two nodes to glue, got {}", list.len())));
        }
        let a = self.int(&list[0], &format!("{nl}[0]"))?;
        let b = self.int(&list[1], &format!("{nl}[1]"))?;
        Ok(vec![("glue", J::Arr(vec![J::Int(a), J::Int(b)]))])
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
