//! Swept samples on the host: the head tags them with stage angles only
//! (`SweptSample`); their geometry and angular extent are the kinematics'
//! functions of those, computed here in f64.

use gonio_brdf::frame::{angle_between, cross, dot};
use gonio_firmware::kinematics;
use gonio_shared::{AxisAngles, Geometry, SweptSample};

/// Where a swept sample was: the geometry halfway between its stage angles
/// at start and end.
pub fn geometry(s: &SweptSample) -> Geometry {
    kinematics::forward(&s.mid_axes())
}

/// Light and view directions at stage angles `a`, in axes fixed to the
/// sample (its normal, and the two tangents the rotation stage and the
/// cradle turn): unlike the sample frame of `gonio_brdf::Directions`, whose
/// `x` follows the light's azimuth, these do not spin when the light passes
/// the normal.
pub fn body_directions(a: &AxisAngles) -> [[f64; 3]; 2] {
    let (om, ta, ps) = (
        (a.omega_deg as f64).to_radians(),
        (a.tau_deg as f64).to_radians(),
        (a.psi_deg as f64).to_radians(),
    );
    let n = [ta.cos() * om.cos(), ta.cos() * om.sin(), ta.sin()];
    let t1 = [-om.sin(), om.cos(), 0.0];
    let t2 = cross(n, t1);
    let in_body = |w: [f64; 3]| [dot(w, t1), dot(w, t2), dot(w, n)];
    [in_body([1.0, 0.0, 0.0]), in_body([ps.cos(), ps.sin(), 0.0])]
}

/// How far (degrees) the geometry moved during a swept sample: the larger of
/// the angles the light and the view direction turned through as the sample
/// sees them ([`body_directions`]; angles on the sphere, which mean the same
/// everywhere, unlike differences of θ and Δφ near the pole).
pub fn extent_deg(s: &SweptSample) -> f64 {
    let [a, b] = [&s.axes_from, &s.axes_to].map(body_directions);
    angle_between(a[0], b[0]).max(angle_between(a[1], b[1])).to_degrees()
}
