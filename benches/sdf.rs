//! Nearest-point benchmark (issue 10, item 4): the obstacle signed distance through our tree
//! (`collision::sdf::MeshSdf` on `collision::bvh::Bvh`) and through parry3d-f64's `TriMesh`
//! (`ORIENTED`: the same pseudo-normal sign), in the same run, on the shipped scenes' obstacle
//! meshes and a fine sphere. Reports, per mesh, the cost of building the field, of bringing it to
//! moved positions (ours rebuilds its tree, parry refits), and of one query, single-threaded,
//! near the surface and over the mesh's box; and how many of parry's answers differ from ours in
//! their bits (adopting parry would change the simulation's results by that much).
//!
//! A second table prices the cache of `CollisionWorld::with_sdf` at one call site: a
//! penetration count (every cloth node against every obstacle body) as the simulation made it
//! before, with a field built from scratch per body, against the kept fields, at a time they
//! already hold and at a new time (moving bodies brought to it, static ones untouched).
//!
//! `cargo bench --bench sdf`

use std::path::Path;
use std::time::Instant;

use parry3d_f64::math::Vector;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};
use viewcloth::collision::obstacle::{sphere_mesh, ObstacleBody};
use viewcloth::collision::sdf::MeshSdf;
use viewcloth::math::{Real, Vec3};
use viewcloth::scene::load_file;
use viewcloth::sim::Simulation;

/// Query points per mesh, and repetitions of each timing (the median is reported).
const POINTS: usize = 40_000;
const REPEAT: usize = 9;

fn to_parry(v: &Vec3) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

/// Median wall time of `f` over `REPEAT` runs, in seconds.
fn time(mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..REPEAT)
        .map(|_| {
            let clock = Instant::now();
            f();
            clock.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[REPEAT / 2]
}

/// Deterministic points: half just off the surface (a random point of a random face, moved
/// along the face normal by −2 % to +5 % of the mesh size, as cloth in contact is), half
/// spread over the mesh's box grown by half.
fn points(x: &[Vec3], tris: &[[usize; 3]]) -> Vec<Vec3> {
    let mut s: u64 = 0x2545_f491_4f6c_dd1d;
    let mut u = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as Real / (1u64 << 53) as Real
    };
    let (lo, hi) = x
        .iter()
        .fold((Vec3::repeat(Real::INFINITY), Vec3::repeat(Real::NEG_INFINITY)), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    let size = (hi - lo).max();
    (0..POINTS)
        .map(|k| {
            if k % 2 == 0 {
                let t = tris[(u() * tris.len() as Real) as usize];
                let (a, b) = (u(), u());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                let p = x[t[0]] * (1.0 - a - b) + x[t[1]] * a + x[t[2]] * b;
                let n = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]])).normalize();
                p + n * (size * (0.07 * u() - 0.02))
            } else {
                let r = Vec3::new(u(), u(), u());
                lo + (hi - lo).component_mul(&(r * 2.0 - Vec3::repeat(0.5)))
            }
        })
        .collect()
}

fn bench(name: &str, tris: &[[usize; 3]], x: &[Vec3], moved: &[Vec3]) {
    let pts = points(x, tris);
    let ours = MeshSdf::new(tris, x);
    let indices: Vec<[u32; 3]> = tris.iter().map(|t| t.map(|i| i as u32)).collect();
    let verts: Vec<Vector> = x.iter().map(to_parry).collect();
    let parry = TriMesh::with_flags(verts.clone(), indices.clone(), TriMeshFlags::ORIENTED).expect("parry mesh");

    let build_ours = time(|| drop(std::hint::black_box(MeshSdf::new(tris, x))));
    let build_parry = time(|| {
        drop(std::hint::black_box(TriMesh::with_flags(verts.clone(), indices.clone(), TriMeshFlags::ORIENTED)))
    });
    let moved_parry: Vec<Vector> = moved.iter().map(to_parry).collect();
    let (mut o, mut p) = (ours.clone(), parry.clone());
    let mut flip = false;
    let update_ours = time(|| {
        flip = !flip;
        o.update(if flip { moved } else { x });
    });
    let update_parry = time(|| {
        flip = !flip;
        p.set_vertices(if flip { &moved_parry } else { &verts });
    });

    // Near the surface (cloth in contact: what the simulation asks) and over the box (deep
    // inside a round body, every face is about as near: the slow case of a nearest search).
    let (near, spread): (Vec<Vec3>, Vec<Vec3>) =
        (pts.iter().step_by(2).copied().collect(), pts.iter().skip(1).step_by(2).copied().collect());
    let per_query = |set: &[Vec3]| {
        let a = time(|| set.iter().for_each(|q| _ = std::hint::black_box(ours.query(q))));
        let b = time(|| {
            set.iter()
                .for_each(|q| _ = std::hint::black_box(parry.project_local_point_and_get_location(to_parry(q), false)))
        });
        (a / set.len() as f64, b / set.len() as f64)
    };
    let (near_ours, near_parry) = per_query(&near);
    let (spread_ours, spread_parry) = per_query(&spread);
    let (mut differ, mut sign, mut worst) = (0, 0, 0.0 as Real);
    for q in &pts {
        let a = ours.query(q).expect("mesh has faces");
        let (b, _) = parry.project_local_point_and_get_location(to_parry(q), false);
        let c = Vec3::new(b.point.x, b.point.y, b.point.z);
        differ += usize::from(a.point.map(Real::to_bits) != c.map(Real::to_bits));
        sign += usize::from(a.distance != 0.0 && (a.distance < 0.0) != b.is_inside);
        worst = worst.max((a.point - c).norm());
    }
    let ms = |s: f64| format!("{:.2}", 1e3 * s);
    let ns = |s: f64| format!("{:.0}", 1e9 * s);
    println!(
        "| {name} | {} | {} / {} | {} / {} | {} / {} ({:.2}) | {} / {} ({:.2}) | {differ} of {} ({:.1e}) | {sign} |",
        tris.len(),
        ms(build_ours),
        ms(build_parry),
        ms(update_ours),
        ms(update_parry),
        ns(near_ours),
        ns(near_parry),
        near_parry / near_ours,
        ns(spread_ours),
        ns(spread_parry),
        spread_parry / spread_ours,
        pts.len(),
        worst
    );
}

/// An obstacle's mesh at t = 0 and moved.
struct Body {
    name: String,
    tris: Vec<[usize; 3]>,
    x: Vec<Vec3>,
    moved: Vec<Vec3>,
}

/// The first obstacle of a scene file, at t = 0 and at `t`.
fn scene_body(file: &Path, t: Real) -> Option<Body> {
    let scene = load_file(file).map_err(|e| eprintln!("skipped {}: {e}", file.display())).ok()?;
    let o = scene.obstacles.first()?;
    let body = ObstacleBody::new(o);
    let name = format!("{} ({})", o.name, file.file_stem()?.to_string_lossy());
    Some(Body { name, tris: body.triangles().to_vec(), x: body.positions_at(0.0), moved: body.positions_at(t) })
}

/// One penetration count over every body of a scene (`Simulation::penetrations`), fresh
/// fields per call against kept ones, in ms per call; the scene's cloth after `frames` frames.
fn cache(file: &Path, frames: usize) {
    let Some(mut sim) = load_file(file).ok().and_then(|s| Simulation::new(s).ok()) else {
        return eprintln!("skipped {}", file.display());
    };
    for f in 1..=frames {
        sim.advance_frame().unwrap_or_else(|e| panic!("{}, frame {f}: {e}", file.display()));
    }
    let world = sim.ws.collisions.as_ref().expect("a scene with obstacles");
    let (x, depth) = (sim.state.mesh.positions(), 0.5 * world.params.thickness);
    let bodies = 0..world.bodies.len();
    let fresh = time(|| {
        for body in &world.bodies {
            std::hint::black_box(MeshSdf::new(body.triangles(), &body.positions_at(1.0)).count_deeper_than(&x, depth));
        }
    });
    let count =
        |t: Real| bodies.clone().map(|b| world.with_sdf(b, t, |sdf| sdf.count_deeper_than(&x, depth))).sum::<usize>();
    let same = time(|| _ = std::hint::black_box(count(1.0)));
    let mut t = 1.0;
    let moved = time(|| {
        t += 0.1;
        std::hint::black_box(count(t));
    });
    let statics = world.bodies.iter().filter(|b| b.is_static()).count();
    let name = file.file_stem().map_or(String::new(), |s| s.to_string_lossy().into_owned());
    println!(
        "| {name} | {} ({statics} static) | {} | {:.2} | {:.2} | {:.2} |",
        world.bodies.len(),
        x.len(),
        1e3 * fresh,
        1e3 * same,
        1e3 * moved
    );
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    eprintln!("nearest-point benchmark: {POINTS} points per mesh, median of {REPEAT}, one thread");
    println!(
        "| mesh | triangles | build ms, ours / parry | move ms, ours (rebuild) / parry (refit) \
         | query ns near the surface, ours / parry (parry ÷ ours) | query ns over the box, ours / parry (parry ÷ ours) \
         | parry's closest point differs in its bits (largest distance) | sign differs |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    for (file, t) in [
        (root.join("scenes/sheet_on_sphere.json"), 3.0),
        (root.join("scenes/skirt_mannequin.json"), 1.0),
        (root.join("../shared/arcsim/conf/sphere.json"), 3.0),
    ] {
        if let Some(b) = scene_body(&file, t) {
            bench(&b.name, &b.tris, &b.x, &b.moved);
        }
    }
    let (x, tris) = sphere_mesh(0.5, 2e-4);
    let moved: Vec<Vec3> = x.iter().map(|p| p + Vec3::new(0.01, 0.02, 0.0)).collect();
    bench("fine icosphere", &tris, &x, &moved);

    println!();
    println!("| scene | bodies | cloth nodes | fresh fields ms | kept, same time ms | kept, new time ms |");
    println!("|---|---:|---:|---:|---:|---:|");
    // ARCSim's sheet starts as four triangles and is refined over its first frames.
    for (file, frames) in [
        ("scenes/skirt_mannequin.json", 0),
        ("scenes/tablecloth_pull.json", 0),
        ("../shared/arcsim/conf/sphere.json", 5),
    ] {
        cache(&root.join(file), frames);
    }
}
