//! The two planar parametrizations of the retro domain that Belcour et al.
//! 2014 compare (§3.C): a view direction becomes `(x, y) = θ (cos φ, sin φ)`,
//! in degrees, with the retro direction at the origin in both.
//!
//! - **back**: `θ` the angle of the back vector `b` (eq. 3) from the normal,
//!   `φ` its azimuth from the light's;
//! - **light-view**: `θ` the angle between light and view, `φ` the view's
//!   azimuth about the light, from the light's plane of incidence on the
//!   normal's side.
//!
//! `+x` points to the mirror direction in both (at `x = θi` in the back
//! plane, `2θi` in the light-view one), `+y` to the sample frame's `+y` of
//! the back vector and of the view: a view at `Δφ > 0` has `y < 0` in the
//! back plane (`b` holds the view reflected), `y > 0` in the light-view one.

use gonio_brdf::frame::{angle_between, dot};
use gonio_brdf::Directions;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Parametrization {
    Back,
    LightView,
}

impl From<gonio_brdf::Param> for Parametrization {
    /// The plane a retro lobe's cosine measures its angle in: the back
    /// vector's, or the light's and the view's.
    fn from(p: gonio_brdf::Param) -> Parametrization {
        match p {
            gonio_brdf::Param::Back => Parametrization::Back,
            gonio_brdf::Param::View => Parametrization::LightView,
        }
    }
}

impl Parametrization {
    pub const BOTH: [Parametrization; 2] = [Parametrization::Back, Parametrization::LightView];

    pub fn name(self) -> &'static str {
        match self {
            Parametrization::Back => "back",
            Parametrization::LightView => "light-view",
        }
    }

    /// The view direction of `d` in this plane, degrees.
    pub fn coordinates(self, d: &Directions) -> [f64; 2] {
        let (theta, e_x, e_y, w) = match self {
            Parametrization::Back => (angle_between(d.back(), [0.0, 0.0, 1.0]), [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], d.back()),
            // About the light: x in its plane of incidence towards the
            // normal, which stays defined at normal incidence.
            Parametrization::LightView => (angle_between(d.l, d.v), [-d.l[2], 0.0, d.l[0]], [0.0, 1.0, 0.0], d.v),
        };
        let phi = dot(w, e_y).atan2(dot(w, e_x));
        let theta = theta.to_degrees();
        [theta * phi.cos(), theta * phi.sin()]
    }
}

#[cfg(test)]
mod tests {
    use super::Parametrization::{Back, LightView};
    use gonio_brdf::Directions;

    fn close(a: [f64; 2], b: [f64; 2]) -> bool {
        (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9
    }

    #[test]
    fn retro_is_the_origin_and_the_mirror_lies_on_plus_x() {
        for ti in [0.0, 15.0, 30.0, 60.0] {
            let retro = Directions::from_degrees(ti, ti, 0.0);
            assert!(close(Back.coordinates(&retro), [0.0, 0.0]));
            assert!(close(LightView.coordinates(&retro), [0.0, 0.0]));
            let mirror = Directions::from_degrees(ti, ti, 180.0);
            assert!(close(Back.coordinates(&mirror), [ti, 0.0]), "{:?}", Back.coordinates(&mirror));
            assert!(close(LightView.coordinates(&mirror), [2.0 * ti, 0.0]));
        }
    }

    #[test]
    fn a_view_out_of_the_plane_of_incidence_is_mirrored_by_minus_dphi() {
        // Δφ → −Δφ mirrors y only.
        let d = Directions::from_degrees(30.0, 30.0, 10.0);
        let m = Directions::from_degrees(30.0, 30.0, -10.0);
        assert!(Back.coordinates(&d)[1] < 0.0 && LightView.coordinates(&d)[1] > 0.0);
        for p in [Back, LightView] {
            let (a, b) = (p.coordinates(&d), p.coordinates(&m));
            assert!(close(a, [b[0], -b[1]]));
        }
    }
}
