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

pub fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Angle (rad) between two directions, accurate near 0 and π (not `acos`).
pub fn angle_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let c = cross(a, b);
    dot(c, c).sqrt().atan2(dot(a, b))
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
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
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

    /// The light and view of the head at stage angles `(ω, τ, ψ)` in degrees
    /// (the lab frame of `gonio_firmware::kinematics`), in the sample frame (`z = n`, `x` along the
    /// light's projection), computed from the lab-frame vectors: independent
    /// of the firmware's inverse kinematics. `None` when the light or the
    /// detector is behind the sample.
    pub fn from_stage(angles_deg: [f64; 3]) -> Option<Self> {
        let [om, ta, ps] = angles_deg.map(f64::to_radians);
        let n = [ta.cos() * om.cos(), ta.cos() * om.sin(), ta.sin()];
        let l_lab = [1.0, 0.0, 0.0];
        let d_lab = [ps.cos(), ps.sin(), 0.0];
        if dot(n, l_lab) <= 0.0 || dot(n, d_lab) <= 0.0 {
            return None;
        }
        Some(Self::in_frame(n, l_lab, d_lab, cross(n, [0.0, 0.0, 1.0])))
    }

    /// Light `l` and view `v` (unit vectors of any frame) in the frame of the
    /// unit normal `n`: `z = n`, `x` along the light's projection on the
    /// surface, or along `tangent`'s where the light is on the normal.
    pub fn in_frame(n: [f64; 3], l: [f64; 3], v: [f64; 3], tangent: [f64; 3]) -> Self {
        let on_surface = |w: [f64; 3]| {
            let c = dot(n, w);
            [w[0] - c * n[0], w[1] - c * n[1], w[2] - c * n[2]]
        };
        let proj = on_surface(l);
        let x = normalize(if dot(proj, proj) > 1e-24 { proj } else { on_surface(tangent) });
        let y = cross(n, x);
        let to = |w: [f64; 3]| [dot(w, x), dot(w, y), dot(w, n)];
        Directions { l: to(l), v: to(v) }
    }

    /// `(θi, θo, Δφ)` in radians, `Δφ = φv − φl` in (−π, π] (0 where a
    /// direction is the normal's and has no azimuth).
    pub fn angles(&self) -> (f64, f64, f64) {
        let polar = |w: [f64; 3]| w[0].hypot(w[1]).atan2(w[2]);
        let dphi = self.v[1].atan2(self.v[0]) - self.l[1].atan2(self.l[0]);
        (polar(self.l), polar(self.v), dphi.sin().atan2(dphi.cos()))
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
