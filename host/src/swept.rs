//! Swept samples on the host: the head tags them with stage angles only
//! (`SweptSample`); their geometry and angular extent are the kinematics'
//! functions of those, computed here in f64.

use crate::calibration::CalibratedRow;
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

/// Extents of neighbours within this ratio of each other count as one
/// steady speed (not the ramps at a row's ends).
const STEADY: f32 = 1.25;

/// Takes out what their extent adds to swept samples' calibrated values. A
/// swept sample averages `f` over its path (the demodulation weighs its
/// periods alike, and the arm moves steadily), which exceeds `f` at its
/// middle by `h²·f''/24` (`h` its extent); the samples of a row abut (each
/// begins where the previous ended), so `(B₋ − 2B + B₊)/24` from its two
/// neighbours estimates that term, leaving an error of order `h⁴`. On the
/// flank of a narrow lobe the term is what bends a fit: the tape's
/// retro-phong exponent (n = 500) came out 494 ± 2.3 from samples 1° long,
/// 2.6 standard errors short (`scan-bench`, `fit_agreement`). The noise
/// grows by 0.5 % (`√(1 + 6/24²)`); the uncertainty budget is kept as it
/// was (the correction moves a value by a few per cent at most). Samples at rest, at a row's ends, in a
/// ramp or beside an unusable one are left as they are.
pub fn unblur(rows: &mut [CalibratedRow]) {
    let steady = |a: f32, b: f32| a.max(b) <= STEADY * a.min(b);
    let same_row = |a: &CalibratedRow, b: &CalibratedRow| {
        a.raw.order.is_some() && a.raw.order == b.raw.order && a.raw.seq.wrapping_add(1) == b.raw.seq && a.usable && b.usable
    };
    let values: Vec<f64> = rows.iter().map(|r| r.brdf_sr).collect();
    for k in 1..rows.len().saturating_sub(1) {
        let (p, r, n) = (&rows[k - 1], &rows[k], &rows[k + 1]);
        let (Some(hp), Some(h), Some(hn)) = (p.raw.extent_deg, r.raw.extent_deg, n.raw.extent_deg) else {
            continue;
        };
        if !(same_row(p, r) && same_row(r, n) && steady(hp, h) && steady(h, hn)) {
            continue;
        }
        let corrected = values[k] - (values[k - 1] - 2.0 * values[k] + values[k + 1]) / 24.0;
        let r = &mut rows[k];
        if r.brdf_sr != 0.0 {
            let ratio = corrected / r.brdf_sr;
            r.brdf_cos_sr *= ratio;
            r.shifts = r.shifts.map(|s| s * ratio);
        }
        r.brdf_sr = corrected;
    }
}
