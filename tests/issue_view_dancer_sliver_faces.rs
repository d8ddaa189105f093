//! Pins a remeshing bug: ARCSim's dress on the dancing character in view mode, under a camera
//! 20° round from the crowd shot's, stopped in its first remesh with "invalid mesh: remeshing
//! left face 1566 degenerate". Splits of short edges of thin faces along a seam line (whose own
//! edge was not split) thinned faces to collinear corners. Splits and flips now may not make a
//! face thinner than the faces they replace below a material aspect of 1e-2 (`remesh::ops`).
//! Checked from the written frames: the run completes and no face is a sliver.

use std::path::{Path, PathBuf};

mod common;

use common::{temp_dir, viewcloth};
use viewcloth::io::obj::read_obj;

fn conf() -> Option<PathBuf> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/arcsim/conf/dress-blue.json");
    if !file.exists() {
        eprintln!("SKIP: ARCSim data not found at {}", file.display());
        return None;
    }
    Some(file)
}

#[test]
fn the_dancers_dress_remeshes_in_view_mode_without_slivers() {
    let Some(conf) = conf() else { return };
    let dir = temp_dir("dancer");
    let cam = dir.join("camera.json");
    std::fs::write(
        &cam,
        r#"{"version": 1, "aspect": 1.7778, "keys": [
            {"time": 0.0, "position": [-1.7947429791000802, -2.0072114086391024, 0.0],
             "target": [2.4355993611558686, 2.306047647369222, -0.3], "fov": 40},
            {"time": 3.0, "position": [3.715586578548085, -2.9486295761443717, 0.0],
             "target": [8.99824480088224, 6.302506684121464, -0.4], "fov": 40}]}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let args = ["simulate", conf.to_str().unwrap(), "--mode", "view", "--camera", cam.to_str().unwrap()];
    let o = viewcloth(
        &[&args[..], &["--frames", "2", "--threads", "1", "--quiet", "--out", out.to_str().unwrap()]].concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in 1..=2 {
        let obj = read_obj(&out.join(format!("frame_{f:04}.obj"))).unwrap();
        for tri in &obj.triangles {
            let u: Vec<_> = tri.iter().map(|c| obj.texcoords[c.vt.unwrap()]).collect();
            let area = 0.5 * (u[1] - u[0]).perp(&(u[2] - u[0]));
            let p = (u[1] - u[0]).norm() + (u[2] - u[1]).norm() + (u[0] - u[2]).norm();
            let aspect = 12.0 * 3f64.sqrt() * area / (p * p);
            assert!(aspect > 1e-4, "frame {f}: a face of material aspect {aspect:e}: {u:?}");
        }
    }
}
