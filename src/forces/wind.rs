//! Aerodynamic force on a face (the model of ARCSim's wind force):
//! f = ρ A |v_n| v_n n̂ + c_d A v_t, with v_rel = w − v̄ the wind relative to the face's mean
//! velocity, v_n = n̂·v_rel and v_t = v_rel − v_n n̂; spread equally over the three nodes.

use crate::math::{Mat3, Real, Vec3};

/// Wind parameters: velocity (m/s), air density (kg/m³), tangential drag (kg/(m²·s)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wind {
    pub velocity: Vec3,
    pub density: Real,
    pub drag: Real,
    /// The force's velocity Jacobian enters the implicit system (backward Euler in the drag);
    /// false: the force is explicit, taken at the step's start velocities, as ARCSim's
    /// (`physics.cpp`'s `add_external_forces` leaves `Jext` alone).
    pub implicit: bool,
}

/// Force on each node of a face and the (shared, negative semidefinite) velocity Jacobian block
/// ∂fᵢ/∂vⱼ, the same for every pair (i, j). `v` are node velocities, `x` positions.
pub fn wind_face(x: &[Vec3; 3], v: &[Vec3; 3], wind: &Wind) -> (Vec3, Mat3) {
    let n = (x[1] - x[0]).cross(&(x[2] - x[0]));
    let twice_area = n.norm();
    if twice_area == 0.0 {
        return (Vec3::zeros(), Mat3::zeros());
    }
    let (n, area) = (n / twice_area, 0.5 * twice_area);
    let vrel = wind.velocity - (v[0] + v[1] + v[2]) / 3.0;
    let vn = n.dot(&vrel);
    let vt = vrel - vn * n;
    let f = area * (wind.density * vn.abs() * vn * n + wind.drag * vt) / 3.0;
    let nnt = n * n.transpose();
    // ∂f/∂v̄ = −A(2ρ|v_n| n̂n̂ᵀ + c_d (I − n̂n̂ᵀ)); ∂v̄/∂vⱼ = I/3; f split in thirds.
    let dfdv = -area * (2.0 * wind.density * vn.abs() * nnt + wind.drag * (Mat3::identity() - nnt)) / 9.0;
    (f, dfdv)
}
