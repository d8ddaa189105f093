//! Writes the `skirt_mannequin` shot: `scenes/meshes/skirt.obj` (an A-line skirt, a cone frustum
//! sewn from one flat pattern piece) and `scenes/skirt_mannequin.json` (the skirt pinned at the
//! waist on a walking mannequin of capsules).
//!
//!     cargo run --release --example make_skirt [-- OUT_DIR [--around N] [--down N]]
//!
//! (default: `scenes`, 64 columns around and 22 rows down, the shipped files). Other counts give
//! the same skirt and walk on another mesh: `bench/upsample_garment.sh` takes a 32 × 11 one as the
//! coarse mesh of a learned upsampling (issue 13).
//!
//! The pattern is the frustum unrolled: an annular sector with inner radius ρ₁ = r₁ s / (r₂ − r₁)
//! (s the slant length) and angle Φ = 2π r₁ / ρ₁, so the sewn skirt is at rest in its initial
//! shape. The seam runs down the back: its vertices are shared by both edges of the sector, so
//! each has one `v` and two `vt`.
//!
//! The mannequin walks along +x (z up): "hips" (pelvis and torso, one capsule) bobs, twists and
//! moves forward; each leg is a capsule swinging about its hip joint, in antiphase, and carried
//! by the hips. The waist ring of the skirt follows the hips obstacle.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::PathBuf;

use nalgebra::{UnitQuaternion, Vector3};

/// Skirt: waist and hem radius and height (m), columns around, rows down.
const WAIST_R: f64 = 0.175;
const HEM_R: f64 = 0.4;
const WAIST_Z: f64 = 1.02;
const HEM_Z: f64 = 0.55;
const AROUND: usize = 64;
const DOWN: usize = 22;

/// The skirt's mesh: columns around and rows down.
#[derive(Clone, Copy)]
struct Grid {
    around: usize,
    down: usize,
}

/// Mannequin: hips capsule (radius, length, centre height), legs (radius, length, hip joint).
const HIPS_R: f64 = 0.16;
const HIPS_LEN: f64 = 0.45;
const HIPS_Z: f64 = 1.2;
const LEG_R: f64 = 0.07;
const LEG_LEN: f64 = 0.72;
const JOINT_Y: f64 = 0.08;
const JOINT_Z: f64 = 0.86;

/// Gait: stand still, then ramp into a walk of this period, swing amplitude and speed.
const STAND: f64 = 0.4;
const RAMP: f64 = 0.6;
const PERIOD: f64 = 1.1;
const SWING_DEG: f64 = 22.0;
const TWIST_DEG: f64 = 5.0;
const BOB: f64 = 0.012;
const SPEED: f64 = 0.5;
const END: f64 = STAND + 3.0 * PERIOD;
const KEYS_PER_PERIOD: usize = 16;

fn main() -> std::io::Result<()> {
    let (dir, grid) = args().unwrap_or_else(|e| {
        eprintln!("make_skirt: {e}");
        std::process::exit(2)
    });
    std::fs::create_dir_all(dir.join("meshes"))?;
    std::fs::write(dir.join("meshes/skirt.obj"), skirt_obj(grid))?;
    std::fs::write(dir.join("skirt_mannequin.json"), scene_json(grid))?;
    println!("wrote {} and {}", dir.join("meshes/skirt.obj").display(), dir.join("skirt_mannequin.json").display());
    Ok(())
}

/// `[OUT_DIR] [--around N] [--down N]`.
fn args() -> Result<(PathBuf, Grid), String> {
    let (mut dir, mut grid) = (PathBuf::from("scenes"), Grid { around: AROUND, down: DOWN });
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let count = |it: &mut dyn Iterator<Item = String>, min: usize| {
            let v = it.next().ok_or(format!("{a}: expected a count"))?;
            v.parse::<usize>().ok().filter(|&n| n >= min).ok_or(format!("{a}: expected a count ≥ {min}, got '{v}'"))
        };
        match a.as_str() {
            "--around" => grid.around = count(&mut it, 3)?,
            "--down" => grid.down = count(&mut it, 1)?,
            _ if a.starts_with("--") => return Err(format!("unknown option {a}")),
            _ => dir = PathBuf::from(a),
        }
    }
    Ok((dir, grid))
}

/// Ring j (0 = waist) radius and height, of `down` rows.
fn ring(j: usize, down: usize) -> (f64, f64) {
    let s = j as f64 / down as f64;
    (WAIST_R + s * (HEM_R - WAIST_R), WAIST_Z + s * (HEM_Z - WAIST_Z))
}

fn skirt_obj(Grid { around: n, down: m }: Grid) -> String {
    let slant = ((HEM_R - WAIST_R).powi(2) + (WAIST_Z - HEM_Z).powi(2)).sqrt();
    let rho1 = WAIST_R * slant / (HEM_R - WAIST_R);
    let sector = TAU * WAIST_R / rho1;
    let mut out = format!("# A-line skirt (examples/make_skirt.rs): vertex j*{n}+i is ring j (0 = waist), column i\n");
    for j in 0..=m {
        let (r, z) = ring(j, m);
        for i in 0..n {
            // Column 0 is the seam, at the back (−x).
            let theta = PI + TAU * i as f64 / n as f64;
            let _ = writeln!(out, "v {:.6} {:.6} {:.6}", r * theta.cos(), r * theta.sin(), z);
        }
    }
    // Material coordinates: column i of ring j at radius ρ₁ + j·s/m, angle i·Φ/n (n + 1
    // columns: the last is the seam's second side).
    for j in 0..=m {
        let rho = rho1 + slant * j as f64 / m as f64;
        for i in 0..=n {
            let phi = sector * i as f64 / n as f64;
            let _ = writeln!(out, "vt {:.6} {:.6}", rho * phi.cos(), rho * phi.sin());
        }
    }
    let v = |i: usize, j: usize| j * n + i % n + 1;
    let vt = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..m {
        for i in 0..n {
            let c = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            // Alternate diagonals, as the generated rectangles do.
            let tris = if (i + j) % 2 == 0 { [[0, 1, 2], [0, 2, 3]] } else { [[0, 1, 3], [1, 2, 3]] };
            for t in tris {
                out.push('f');
                for k in t {
                    let (a, b) = c[k];
                    let _ = write!(out, " {}/{}", v(a, b), vt(a, b));
                }
                out.push('\n');
            }
        }
    }
    out
}

/// Smooth 0 → 1 over [STAND, STAND + RAMP].
fn ramp(t: f64) -> f64 {
    let s = ((t - STAND) / RAMP).clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// Walking phase (radians), zero when the walk starts.
fn phase(t: f64) -> f64 {
    TAU * (t - STAND).max(0.0) / PERIOD
}

/// Forward distance: the integral of SPEED · ramp.
fn forward(t: f64) -> f64 {
    let n = 200;
    let dt = t / n as f64;
    (0..n).map(|k| SPEED * ramp((k as f64 + 0.5) * dt) * dt).sum()
}

/// The hips' motion at `t`: a twist about the vertical axis, then the bob and forward walk.
fn hips(t: f64) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let a = ramp(t);
    let twist = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), (a * TWIST_DEG).to_radians() * phase(t).sin());
    let bob = a * BOB * (1.0 - (2.0 * phase(t)).cos()) * 0.5;
    (Vector3::new(forward(t), 0.0, bob), twist)
}

/// A leg's motion at `t`: swing about its hip joint, carried by the hips.
fn leg(t: f64, side: f64) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let swing = side * ramp(t) * SWING_DEG.to_radians() * phase(t).sin();
    let r = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), swing);
    let joint = Vector3::new(0.0, side * JOINT_Y, JOINT_Z);
    let (ht, hq) = hips(t);
    (ht + hq * (joint - r * joint), hq * r)
}

fn keys(motion: impl Fn(f64) -> (Vector3<f64>, UnitQuaternion<f64>)) -> String {
    let dt = PERIOD / KEYS_PER_PERIOD as f64;
    let mut times = vec![0.0];
    let mut t = STAND;
    while t < END + 0.5 * dt {
        times.push(t);
        t += dt;
    }
    let lines: Vec<String> = times
        .iter()
        .map(|&t| {
            let (tr, q) = motion(t);
            let (axis, angle) = q.axis_angle().map(|(a, g)| (a.into_inner(), g)).unwrap_or((Vector3::z(), 0.0));
            format!(
                "        {{ \"time\": {:.4}, \"translate\": [{:.5}, {:.5}, {:.5}], \"rotate\": [{:.4}, {:.6}, {:.6}, {:.6}] }}",
                t,
                tr.x,
                tr.y,
                tr.z,
                angle.to_degrees(),
                axis.x,
                axis.y,
                axis.z
            )
        })
        .collect();
    lines.join(",\n")
}

fn scene_json(grid: Grid) -> String {
    let waist: Vec<String> = (0..grid.around).map(|i| i.to_string()).collect();
    let leg_obstacle = |name: &str, side: f64| {
        format!(
            "    {{\n      \"name\": \"{name}\",\n      \"capsule\": {{ \"radius\": {LEG_R}, \"length\": {LEG_LEN} }},\n      \"transform\": {{ \"translate\": [0, {:.3}, {:.3}] }},\n      \"motion\": [\n{}\n      ]\n    }}",
            side * JOINT_Y,
            JOINT_Z - 0.5 * LEG_LEN,
            keys(|t| leg(t, side))
        )
    };
    format!(
        r#"{{
  "version": 1,
  "name": "skirt_mannequin",
  "frame_time": 0.04,
  "steps_per_frame": 20,
  "end_time": {END:.2},
  "gravity": [0, 0, -9.81],
  "cloths": [
    {{
      "name": "skirt",
      "mesh": "meshes/skirt.obj",
      "material": {{ "preset": "denim" }},
      "handles": [
        {{ "nodes": [{waist}], "obstacle": "hips" }}
      ]
    }}
  ],
  "obstacles": [
    {{
      "name": "hips",
      "capsule": {{ "radius": {HIPS_R}, "length": {HIPS_LEN} }},
      "transform": {{ "translate": [0, 0, {HIPS_Z}] }},
      "motion": [
{hips_keys}
      ]
    }},
{left},
{right}
  ],
  "collision": {{ "thickness": 0.004, "friction": 0.3, "self_friction": 0.3 }}
}}
"#,
        waist = waist.join(", "),
        hips_keys = keys(hips),
        left = leg_obstacle("leg_left", 1.0),
        right = leg_obstacle("leg_right", -1.0),
    )
}
