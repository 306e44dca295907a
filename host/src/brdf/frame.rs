//! The sample frame of `models.md` §1: normal `(0,0,1)`, light and view as
//! unit vectors from polar and azimuth angles, and the derived vectors and
//! cosines every model uses.

/// Light and view directions for one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Directions {
    pub l: [f64; 3],
    pub v: [f64; 3],
}

pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `(a + b)/‖a + b‖`, or the normal when the sum vanishes.
fn unit_sum(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let s = [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
    let n = dot(s, s).sqrt();
    if n < 1e-300 {
        [0.0, 0.0, 1.0]
    } else {
        [s[0] / n, s[1] / n, s[2] / n]
    }
}

/// Which cosine a retro lobe takes (`models.md` §1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Param {
    /// `cos_B = n·b`, the back vector (Belcour eq. 3–4).
    Back,
    /// `cos_R = max(0, l·v)`.
    View,
}

impl Directions {
    /// From `(θi, θo, Δφ)` in radians, light at azimuth 0.
    pub fn from_angles(theta_i: f64, theta_o: f64, dphi: f64) -> Self {
        Directions {
            l: [theta_i.sin(), 0.0, theta_i.cos()],
            v: [theta_o.sin() * dphi.cos(), theta_o.sin() * dphi.sin(), theta_o.cos()],
        }
    }

    pub fn from_degrees(theta_i: f64, theta_o: f64, dphi: f64) -> Self {
        Self::from_angles(theta_i.to_radians(), theta_o.to_radians(), dphi.to_radians())
    }

    /// `cos θi`.
    pub fn cos_i(&self) -> f64 {
        self.l[2]
    }

    /// `cos θo`.
    pub fn cos_o(&self) -> f64 {
        self.v[2]
    }

    /// Mirror of the light about the normal, `r(l) = 2(n·l)n − l`.
    pub fn mirror_l(&self) -> [f64; 3] {
        [-self.l[0], -self.l[1], self.l[2]]
    }

    /// Reflected view `v' = 2(n·v)n − v`.
    pub fn reflected_v(&self) -> [f64; 3] {
        [-self.v[0], -self.v[1], self.v[2]]
    }

    /// Half vector `h = (l + v)/‖l + v‖`.
    pub fn half(&self) -> [f64; 3] {
        unit_sum(self.l, self.v)
    }

    /// Back vector `b = (v' + l)/‖v' + l‖`.
    pub fn back(&self) -> [f64; 3] {
        unit_sum(self.reflected_v(), self.l)
    }
}
