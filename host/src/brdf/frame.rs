//! The sample frame of `models.md` §1: normal `(0,0,1)`, light and view as
//! unit vectors from polar and azimuth angles.

/// Light and view directions for one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Directions {
    pub l: [f64; 3],
    pub v: [f64; 3],
}

pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
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
}
