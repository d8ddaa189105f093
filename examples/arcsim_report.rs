//! Summarises one `viewcloth simulate` run for `bench/arcsim.sh`: wall time per frame, faces
//! over time, and the minimum cloth–obstacle clearance, measured from the written frames and the
//! obstacle meshes written with `--export-obstacles` (signed distance of every cloth vertex to
//! every obstacle, negative inside), independently of the simulator's own counters.
//!
//! Usage: `arcsim_report <run dir> <frame,frame,…> [span,span,…]`; prints one JSON object. Each
//! span N adds the mean and median wall time of the first N simulated frames, to set beside a
//! reference measured over the same frames.

use std::path::Path;

use viewcloth::collision::sdf::MeshSdf;
use viewcloth::io::obj::read_obj;

fn main() -> std::process::ExitCode {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: arcsim_report <run dir> <frame,frame,…> [span,span,…]");
        return std::process::ExitCode::from(2);
    }
    match report(&args) {
        Ok(json) => {
            println!("{json}");
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::from(2)
        }
    }
}

/// The report of the run in `args[1]` as one JSON object, or a one-line error.
fn report(args: &[String]) -> Result<String, String> {
    let dir = Path::new(&args[1]);
    let marks: Vec<usize> = args[2].split(',').filter_map(|s| s.parse().ok()).collect();
    let stats_path = dir.join("stats.json");
    let text = std::fs::read_to_string(&stats_path).map_err(|e| format!("{}: {e}", stats_path.display()))?;
    let stats: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", stats_path.display()))?;
    let frames = stats["frames"].as_array().ok_or_else(|| format!("{}: no \"frames\" array", stats_path.display()))?;
    let wall: Vec<f64> = frames.iter().skip(1).filter_map(|f| f["wall_s"].as_f64()).collect();
    let spans: Vec<String> = args
        .get(3)
        .map(|a| a.split(',').filter_map(|s| s.parse::<usize>().ok()).collect::<Vec<_>>())
        .unwrap_or_default()
        .into_iter()
        .filter(|&n| n <= wall.len())
        .map(|n| {
            let (mean, median) = mean_median(&wall[..n]);
            format!("\"{n}\": {{\"mean_s\": {mean:.4}, \"median_s\": {median:.4}}}")
        })
        .collect();
    let faces: Vec<u64> = frames.iter().filter_map(|f| f["faces"].as_u64()).collect();
    let penetrations: u64 = frames.iter().filter_map(|f| f["penetrations"].as_u64()).sum();
    let mut stages: std::collections::BTreeMap<String, f64> = Default::default();
    for f in frames.iter().skip(1) {
        if let Some(m) = f["stage_s"].as_object() {
            for (k, v) in m {
                *stages.entry(k.clone()).or_default() += v.as_f64().unwrap_or(0.0);
            }
        }
    }
    let (mean, median) = mean_median(&wall);

    // Clearance per frame: obstacle files are obstacle_<name>_<frame>.obj beside frame_<frame>.obj.
    let list = |dir: &Path| std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()));
    let mut names: Vec<String> = list(dir)?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("frame_") && n.ends_with(".obj"))
        .collect();
    names.sort();
    let mut min_clearance = f64::INFINITY;
    let mut worst_frame = 0;
    let mut have_obstacles = false;
    for name in &names {
        let digits = &name["frame_".len()..name.len() - 4];
        let read = |name: &str| read_obj(&dir.join(name)).map_err(|e| format!("{}: {e}", dir.join(name).display()));
        let cloth = read(name)?;
        let suffix = format!("_{digits}.obj");
        for entry in list(dir)?.flatten() {
            let obs = entry.file_name().into_string().unwrap_or_default();
            if !(obs.starts_with("obstacle_") && obs.ends_with(&suffix)) {
                continue;
            }
            have_obstacles = true;
            let d = read(&obs)?;
            let tris: Vec<[usize; 3]> = d.triangles.iter().map(|t| t.map(|c| c.v)).collect();
            let sdf = MeshSdf::new(&tris, &d.positions);
            let m =
                sdf.query_all(&cloth.positions).into_iter().flatten().map(|h| h.distance).fold(f64::INFINITY, f64::min);
            if m < min_clearance {
                min_clearance = m;
                worst_frame = digits.parse().unwrap_or(0);
            }
        }
    }
    let at: Vec<String> =
        marks.iter().filter(|&&f| f < faces.len()).map(|&f| format!("\"{f}\": {}", faces[f])).collect();
    let stage_json: Vec<String> = stages.iter().map(|(k, v)| format!("\"{k}\": {v:.3}")).collect();
    let clearance = if have_obstacles { format!("{min_clearance:.6}") } else { "null".to_string() };
    Ok(format!(
        "{{\"frames\": {}, \"mean_s\": {mean:.4}, \"median_s\": {median:.4}, \"faces_at\": {{{}}}, \"max_faces\": {}, \
         \"min_clearance_m\": {clearance}, \"min_clearance_frame\": {worst_frame}, \"penetrations\": {penetrations}, \
         \"total_s\": {:.2}, \"spans\": {{{}}}, \"stage_s\": {{{}}}, \"error\": {}}}",
        wall.len(),
        at.join(", "),
        faces.iter().max().copied().unwrap_or(0),
        stats["total_wall_s"].as_f64().unwrap_or(0.0),
        spans.join(", "),
        stage_json.join(", "),
        stats.get("error").map(|e| e.to_string()).unwrap_or_else(|| "null".into()),
    ))
}

/// Mean and median of per-frame wall times.
fn mean_median(wall: &[f64]) -> (f64, f64) {
    let mut sorted = wall.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mean = sorted.iter().sum::<f64>() / sorted.len().max(1) as f64;
    (mean, sorted.get(sorted.len() / 2).copied().unwrap_or(0.0))
}
