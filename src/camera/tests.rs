use super::*;

const FILE: &str = "cameras/test.json";

fn camera(interpolation: &str, keys: &str) -> Camera {
    let text = format!(
        r#"{{ "version": 1, "aspect": 2.0, "near": 0.1, "far": 10.0, "interpolation": "{interpolation}", "keys": [{keys}] }}"#
    );
    Camera::from_json(&text, Path::new(FILE)).unwrap()
}

/// Three keys, unevenly spaced, moving along x and changing target, up and fov.
const KEYS: &str = r#"
    { "time": 0.0, "position": [0, -3, 1], "target": [0, 0, 0.5], "up": [0, 0, 1], "fov": 40 },
    { "time": 1.0, "position": [1, -3, 2], "target": [0.5, 0, 0], "up": [0.2, 0, 1], "fov": 30 },
    { "time": 3.0, "position": [3, -2, 1], "target": [1, 0, 0], "up": [0, 0.1, 2], "fov": 60 }"#;

fn close(a: &Vec3, b: &Vec3, tol: Real) -> bool {
    (a - b).norm() <= tol
}

/// Checks `v` against a key written out by hand.
fn assert_view_is_key(v: &View, position: [Real; 3], target: [Real; 3], up: [Real; 3], fov: Real) {
    let (position, target, up) = (Vec3::from(position), Vec3::from(target), Vec3::from(up));
    let forward = (target - position).normalize();
    let up = (up - forward * up.dot(&forward)).normalize();
    assert_eq!(v.eye, position);
    assert!(close(&v.forward, &forward, 1e-14), "{v:?}");
    assert!(close(&v.up, &up, 1e-14), "{v:?}");
    assert!(close(&v.right, &forward.cross(&up), 1e-14), "{v:?}");
    assert!((v.tan_half_fov - (0.5 * fov.to_radians()).tan()).abs() < 1e-14, "{v:?}");
    assert_eq!((v.aspect, v.near, v.far), (2.0, 0.1, 10.0));
}

fn assert_orthonormal(v: &View) {
    for (a, b) in [(&v.forward, &v.up), (&v.forward, &v.right), (&v.up, &v.right)] {
        assert!(a.dot(b).abs() < 1e-12, "{v:?}");
    }
    for a in [&v.forward, &v.up, &v.right] {
        assert!((a.norm() - 1.0).abs() < 1e-12, "{v:?}");
    }
    assert!(close(&v.forward.cross(&v.up), &v.right, 1e-12), "{v:?}");
}

#[test]
fn view_at_key_times_is_the_key() {
    for interpolation in ["linear", "catmull-rom"] {
        let cam = camera(interpolation, KEYS);
        assert_view_is_key(&cam.view_at(0.0), [0.0, -3.0, 1.0], [0.0, 0.0, 0.5], [0.0, 0.0, 1.0], 40.0);
        assert_view_is_key(&cam.view_at(1.0), [1.0, -3.0, 2.0], [0.5, 0.0, 0.0], [0.2, 0.0, 1.0], 30.0);
        assert_view_is_key(&cam.view_at(3.0), [3.0, -2.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.1, 2.0], 60.0);
    }
}

#[test]
fn linear_midpoint() {
    let cam = camera("linear", KEYS);
    // Halfway between keys 1 and 2.
    let v = cam.view_at(2.0);
    assert!(close(&v.eye, &Vec3::new(2.0, -2.5, 1.5), 1e-14));
    let target = Vec3::new(0.75, 0.0, 0.0);
    assert!(close(&v.forward, &(target - v.eye).normalize(), 1e-14));
    assert!((v.tan_half_fov - (45.0_f64 / 2.0).to_radians().tan()).abs() < 1e-14);
    assert_orthonormal(&v);
}

#[test]
fn catmull_rom_passes_through_keys_and_holds_outside() {
    let cam = camera("catmull-rom", KEYS);
    assert_eq!(cam.view_at(-5.0), cam.view_at(0.0));
    assert_eq!(cam.view_at(Real::NEG_INFINITY), cam.view_at(0.0));
    assert_eq!(cam.view_at(Real::NAN), cam.view_at(0.0));
    assert_eq!(cam.view_at(3.5), cam.view_at(3.0));
    assert_eq!(cam.view_at(Real::INFINITY), cam.view_at(3.0));
    // Continuous through the middle key, and differs from linear between keys.
    let (a, b) = (cam.view_at(1.0 - 1e-7), cam.view_at(1.0 + 1e-7));
    assert!(close(&a.eye, &b.eye, 1e-6) && close(&a.forward, &b.forward, 1e-6));
    let linear = camera("linear", KEYS);
    assert!(!close(&cam.view_at(2.0).eye, &linear.view_at(2.0).eye, 1e-3));
    for k in 0..=40 {
        assert_orthonormal(&cam.view_at(-0.5 + 0.1 * k as Real));
    }
}

#[test]
fn one_key_is_a_static_camera() {
    let cam = camera("catmull-rom", r#"{ "time": 2, "position": [0, -3, 1], "target": [0, 0, 1], "fov": 40 }"#);
    let v = cam.view_at(0.0);
    assert_eq!(v, cam.view_at(2.0));
    assert_eq!(v, cam.view_at(100.0));
    assert_eq!((v.forward, v.up, v.right), (Vec3::y(), Vec3::z(), Vec3::x()));
}

#[test]
fn catmull_rom_fov_stays_within_the_keys() {
    // A spline through 10°, 170°, 170° overshoots past 170° on the second segment.
    let keys = r#"
        { "time": 0, "position": [0, -3, 0], "target": [0, 0, 0], "fov": 10 },
        { "time": 1, "position": [0, -3, 0], "target": [0, 0, 0], "fov": 170 },
        { "time": 2, "position": [0, -3, 0], "target": [0, 0, 0], "fov": 170 }"#;
    let cam = camera("catmull-rom", keys);
    let max = (85.0_f64).to_radians().tan();
    for k in 0..=100 {
        let v = cam.view_at(0.02 * k as Real);
        assert!(v.tan_half_fov > 0.0 && v.tan_half_fov <= max * (1.0 + 1e-12), "{v:?}");
    }
}

/// Up turns from +x to −x while the camera looks along y: halfway the interpolated up is zero.
#[test]
fn degenerate_interpolated_up_falls_back_to_the_nearest_key() {
    let keys = r#"
        { "time": 0, "position": [0, 0, 0], "target": [0, 1, 0], "up": [1, 0, 0], "fov": 40 },
        { "time": 1, "position": [0, 0, 0], "target": [0, 1, 0], "up": [-1, 0, 0], "fov": 40 }"#;
    for interpolation in ["linear", "catmull-rom"] {
        let cam = camera(interpolation, keys);
        assert_eq!(cam.view_at(0.5 - 1e-12).up, Vec3::x());
        assert_eq!(cam.view_at(0.5).up, -Vec3::x());
        for k in 0..=100 {
            assert_orthonormal(&cam.view_at(0.01 * k as Real));
        }
    }
    // Forward passes through +z halfway, where the interpolated up [0, 0, 1] and both keys' ups
    // are parallel to it: some direction orthogonal to forward is chosen.
    let keys = r#"
        { "time": 0, "position": [0, 0, 0], "target": [-1, 0, 1], "up": [0, 0, 1], "fov": 40 },
        { "time": 1, "position": [0, 0, 0], "target": [1, 0, 1], "up": [0, 0, 1], "fov": 40 }"#;
    let v = camera("linear", keys).view_at(0.5);
    assert_eq!(v.forward, Vec3::z());
    assert_orthonormal(&v);
}

/// Eye and target cross between keys: the nearest key's direction is kept.
#[test]
fn degenerate_interpolated_forward_falls_back_to_the_nearest_key() {
    let keys = r#"
        { "time": 0, "position": [0, -1, 0], "target": [0, 1, 0], "fov": 40 },
        { "time": 1, "position": [0, 1, 0], "target": [0, -1, 0], "fov": 40 }"#;
    let cam = camera("linear", keys);
    let v = cam.view_at(0.5);
    assert_eq!(v.eye, Vec3::zeros());
    assert_eq!(v.forward, -Vec3::y());
    assert_orthonormal(&v);
}

/// A camera at the origin looking along +y with up +z (so right is +x), vertical fov 90°.
fn axis_view() -> View {
    let cam = camera("linear", r#"{ "time": 0, "position": [0, 0, 0], "target": [0, 1, 0], "fov": 90 }"#);
    cam.view_at(0.0)
}

#[test]
fn frustum_distance_inside_and_behind() {
    let v = axis_view();
    // On the axis between near (0.1) and far (10): just past near, the near plane is the closest.
    assert!((v.frustum_distance(&Vec3::new(0.0, 0.2, 0.0)) + 0.1).abs() < 1e-12);
    assert!(v.frustum_distance(&Vec3::new(0.0, 5.0, 0.0)) < 0.0);
    // Behind the eye: outside, by at least the distance to the near plane.
    assert!((v.frustum_distance(&Vec3::new(0.0, -1.0, 0.0)) - 1.1).abs() < 1e-12);
    // Beyond far.
    assert!((v.frustum_distance(&Vec3::new(0.0, 12.0, 0.0)) - 2.0).abs() < 1e-12);
}

#[test]
fn frustum_distance_beyond_each_side_plane() {
    let v = axis_view();
    let (tan_v, tan_h) = (v.tan_half_fov, v.aspect * v.tan_half_fov);
    let depth = 4.0;
    // (a point on the side plane at `depth`, that plane's unit outward normal)
    let planes = [
        (
            v.eye + v.forward * depth + v.right * (tan_h * depth),
            (v.right - v.forward * tan_h) / (1.0 + tan_h * tan_h).sqrt(),
        ),
        (
            v.eye + v.forward * depth - v.right * (tan_h * depth),
            (-v.right - v.forward * tan_h) / (1.0 + tan_h * tan_h).sqrt(),
        ),
        (v.eye + v.forward * depth + v.up * (tan_v * depth), (v.up - v.forward * tan_v) / (1.0 + tan_v * tan_v).sqrt()),
        (
            v.eye + v.forward * depth - v.up * (tan_v * depth),
            (-v.up - v.forward * tan_v) / (1.0 + tan_v * tan_v).sqrt(),
        ),
    ];
    for (on_plane, normal) in planes {
        assert!(v.frustum_distance(&on_plane).abs() < 1e-12);
        for d in [0.05, 0.3, -0.2] {
            let got = v.frustum_distance(&(on_plane + normal * d));
            assert!((got - d).abs() < 1e-12, "d = {d}: {got}");
        }
    }
}

#[test]
fn frustum_distance_of_a_rotated_camera() {
    // Same frustum, turned: a point expressed in the camera's axes gives the same distance.
    let cam = camera("linear", KEYS);
    let v = cam.view_at(2.0);
    let (tan_v, tan_h) = (v.tan_half_fov, v.aspect * v.tan_half_fov);
    for (x, y, z) in [(0.0, 0.0, 3.0), (1.0, 0.5, 2.0), (-4.0, 0.0, 1.0), (0.0, 0.0, -2.0), (0.3, -0.2, 11.0)] {
        let p = v.eye + v.right * x + v.up * y + v.forward * z;
        let expected = [
            v.near - z,
            z - v.far,
            (x.abs() - tan_h * z) / (1.0 + tan_h * tan_h).sqrt(),
            (y.abs() - tan_v * z) / (1.0 + tan_v * tan_v).sqrt(),
        ]
        .into_iter()
        .fold(Real::NEG_INFINITY, Real::max);
        assert!((v.frustum_distance(&p) - expected).abs() < 1e-12);
    }
}

#[test]
fn eye_distance() {
    let cam = camera("linear", KEYS);
    let v = cam.view_at(0.0);
    assert_eq!(v.eye_distance(&Vec3::new(0.0, -3.0, 1.0)), 0.0);
    assert!((v.eye_distance(&Vec3::new(3.0, 1.0, 1.0)) - 5.0).abs() < 1e-14);
}

#[test]
fn describe_is_stable_and_sees_every_value() {
    let base = camera("catmull-rom", KEYS);
    assert_eq!(base.describe(), camera("catmull-rom", KEYS).describe());
    // Defaults and formatting do not matter, values do.
    let spaced = format!(r#"{{"keys":[{KEYS}],"far":1e1,"near":0.1,"version":1,"aspect":2}}"#);
    assert_eq!(Camera::from_json(&spaced, Path::new(FILE)).unwrap().describe(), base.describe());
    for (from, to) in
        [("\"fov\": 60", "\"fov\": 61"), ("[0, 0.1, 2]", "[0, 0.1, 2.1]"), ("\"time\": 3.0", "\"time\": 3.5")]
    {
        assert_ne!(camera("catmull-rom", &KEYS.replace(from, to)).describe(), base.describe(), "{from}");
    }
    assert_ne!(camera("linear", KEYS).describe(), base.describe());
    assert!(base.describe().contains("interpolation=CatmullRom"));
}
