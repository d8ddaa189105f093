//! Step benchmark (issue 2, "Benchmark"): a uniform 1 m × 1 m sheet pinned at its two top
//! corners, h = 1/120 s, at about 10k, 40k and 160k faces. Reports seconds per step split into
//! assembly, numeric factorisation and solve, and the peak resident memory of each size.
//!
//! `cargo bench --bench step` runs every size; `cargo bench --bench step -- 71 141` runs only the
//! given resolutions n (2n² faces). Each size runs in a child process (this binary re-invoked with
//! `--child N STEPS`) so that VmHWM is the peak of that size alone.

use std::process::Command;
use std::time::Instant;

use viewcloth::scene::load_str;
use viewcloth::sim::Simulation;

const H: f64 = 1.0 / 120.0;

/// Resolution n (2n² faces) and timed steps (after one untimed warm-up step).
const SIZES: &[(usize, usize)] = &[(71, 8), (141, 4), (283, 2)];

/// What a child reports, in seconds per step (setup once) and kB.
#[derive(Debug, Default)]
struct Row {
    n: usize,
    faces: usize,
    nodes: usize,
    steps: usize,
    setup_s: f64,
    assembly: f64,
    factorisation: f64,
    solve: f64,
    other: f64,
    step: f64,
    peak_kb: u64,
    /// FNV-1a of the final positions' bits: equal across thread counts and code changes that
    /// keep the results bit-identical.
    state_hash: u64,
}

const FIELDS: usize = 12;

impl Row {
    fn to_line(&self) -> String {
        format!(
            "ROW {} {} {} {} {:e} {:e} {:e} {:e} {:e} {:e} {} {:016x}",
            self.n,
            self.faces,
            self.nodes,
            self.steps,
            self.setup_s,
            self.assembly,
            self.factorisation,
            self.solve,
            self.other,
            self.step,
            self.peak_kb,
            self.state_hash
        )
    }

    fn from_line(line: &str) -> Option<Row> {
        let w: Vec<&str> = line.strip_prefix("ROW ")?.split_whitespace().collect();
        if w.len() != FIELDS {
            return None;
        }
        let f = |i: usize| w[i].parse::<f64>().ok();
        let u = |i: usize| w[i].parse::<usize>().ok();
        Some(Row {
            n: u(0)?,
            faces: u(1)?,
            nodes: u(2)?,
            steps: u(3)?,
            setup_s: f(4)?,
            assembly: f(5)?,
            factorisation: f(6)?,
            solve: f(7)?,
            other: f(8)?,
            step: f(9)?,
            peak_kb: w[10].parse().ok()?,
            state_hash: u64::from_str_radix(w[11], 16).ok()?,
        })
    }
}

fn scene_json(n: usize) -> String {
    let top_left = n * (n + 1);
    let top_right = top_left + n;
    format!(
        r#"{{
  "version": 1,
  "name": "bench_sheet_{n}",
  "fps": 24,
  "steps_per_frame": 5,
  "frames": 1,
  "gravity": [0, 0, -9.81],
  "cloths": [{{
    "name": "sheet",
    "rectangle": {{ "width": 1.0, "height": 1.0, "resolution": [{n}, {n}] }},
    "transform": {{ "translate": [-0.5, -0.5, 1.0] }},
    "material": {{ "preset": "cotton" }},
    "handles": [{{ "nodes": [{top_left}] }}, {{ "nodes": [{top_right}] }}]
  }}]
}}"#
    )
}

/// Peak resident set size of this process (kB), from /proc/self/status.
fn vm_hwm_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        })
        .unwrap_or(0)
}

fn state_hash(sim: &Simulation) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for node in &sim.state.mesh.nodes {
        for c in node.x.iter().chain(node.v.iter()) {
            for b in c.to_bits().to_le_bytes() {
                h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
    h
}

fn child(n: usize, steps: usize) -> Row {
    let text = scene_json(n);
    let path = std::path::Path::new("bench_sheet.json");
    let scene =
        load_str(&text, path, std::path::Path::new("."), "bench_sheet").unwrap_or_else(|e| panic!("bench scene: {e}"));
    let clock = Instant::now();
    let mut sim = Simulation::new(scene).unwrap_or_else(|e| panic!("setup: {e}"));
    let setup_s = clock.elapsed().as_secs_f64();
    // One warm-up step: first touches of the buffers, thread pool start-up.
    sim.step(H).unwrap_or_else(|e| panic!("warm-up step: {e}"));
    sim.ws.timers.take();
    let clock = Instant::now();
    for _ in 0..steps {
        sim.step(H).unwrap_or_else(|e| panic!("step: {e}"));
    }
    let wall = clock.elapsed().as_secs_f64() / steps as f64;
    let t = sim.ws.timers.take();
    let per = |k: &str| t.get(k).copied().unwrap_or(0.0) / steps as f64;
    let (assembly, factorisation, solve) = (per("assembly"), per("factorisation"), per("solve"));
    Row {
        n,
        faces: sim.state.mesh.faces.len(),
        nodes: sim.state.mesh.nodes.len(),
        steps,
        setup_s,
        assembly,
        factorisation,
        solve,
        other: wall - assembly - factorisation - solve,
        step: wall,
        peak_kb: vm_hwm_kb(),
        state_hash: state_hash(&sim),
    }
}

fn run_child(n: usize, steps: usize) -> Row {
    let exe = std::env::current_exe().expect("bench executable path");
    let out =
        Command::new(exe).args(["--child", &n.to_string(), &steps.to_string()]).output().expect("spawn bench child");
    let stdout = String::from_utf8_lossy(&out.stdout);
    match stdout.lines().find_map(Row::from_line) {
        Some(r) if out.status.success() => r,
        _ => panic!("child n = {n} failed ({}):\n{stdout}\n{}", out.status, String::from_utf8_lossy(&out.stderr)),
    }
}

fn pct(part: f64, whole: f64) -> String {
    format!("{:.0}%", 100.0 * part / whole)
}

fn print_table(rows: &[Row]) {
    println!(
        "| faces | nodes | steps | setup (s) | assembly (s) | factorisation (s) | solve (s) \
         | other (s) | **step (s)** | assembly share | peak memory (MB) |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        println!(
            "| {} | {} | {} | {:.3} | {:.4} ({}) | {:.4} ({}) | {:.4} ({}) | {:.4} | **{:.3}** | {} | {:.0} |",
            r.faces,
            r.nodes,
            r.steps,
            r.setup_s,
            r.assembly,
            pct(r.assembly, r.step),
            r.factorisation,
            pct(r.factorisation, r.step),
            r.solve,
            pct(r.solve, r.step),
            r.other,
            r.step,
            pct(r.assembly, r.step),
            r.peak_kb as f64 / 1024.0
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--child") {
        let n = args[1].parse().expect("--child N STEPS");
        let steps = args[2].parse().expect("--child N STEPS");
        println!("{}", child(n, steps).to_line());
        return;
    }
    // `cargo bench` passes `--bench`; bare numbers pick resolutions.
    let picked: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let sizes: Vec<(usize, usize)> = if picked.is_empty() {
        SIZES.to_vec()
    } else {
        picked.iter().map(|&n| *SIZES.iter().find(|s| s.0 == n).unwrap_or(&(n, 3))).collect()
    };
    let threads = rayon::current_num_threads();
    eprintln!("step benchmark: h = 1/120 s, {threads} rayon threads");
    let mut rows = Vec::new();
    for (n, steps) in sizes {
        let r = run_child(n, steps);
        eprintln!("  {} faces: {:.3} s/step, state {:016x}", r.faces, r.step, r.state_hash);
        rows.push(r);
    }
    print_table(&rows);
}
