//! The vectors of `models.md` §1 in fixed point: light and view in the sample
//! frame, half vector, reflected view and back vector.

use super::fixed::Fx;
use gonio_shared::Geometry;

type V3 = [Fx; 3];

/// π/180 in Q32.
const DEG: Fx = Fx(74_961_321);

fn dot(a: V3, b: V3) -> Fx {
    a[0].times(b[0]).plus(a[1].times(b[1])).plus(a[2].times(b[2]))
}

/// `(a + b)/‖a + b‖`, or the normal when the sum vanishes.
fn unit_sum(a: V3, b: V3) -> V3 {
    let s = [a[0].plus(b[0]), a[1].plus(b[1]), a[2].plus(b[2])];
    let n = dot(s, s).sqrt();
    if n.0 < 16 {
        return [Fx::ZERO, Fx::ZERO, Fx::ONE];
    }
    [s[0].over(n), s[1].over(n), s[2].over(n)]
}

/// Light and view for one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixedGeometry {
    pub l: V3,
    pub v: V3,
}

impl FixedGeometry {
    /// From `(θi, θo, Δφ)` in radians.
    pub fn new(theta_i: Fx, theta_o: Fx, dphi: Fx) -> Self {
        let (si, ci) = theta_i.sin_cos();
        let (so, co) = theta_o.sin_cos();
        let (sp, cp) = dphi.sin_cos();
        FixedGeometry {
            l: [si, Fx::ZERO, ci],
            v: [so.times(cp), so.times(sp), co],
        }
    }

    /// The edge from the message type (degrees, f32); `None` for non-finite angles.
    pub fn from_degrees(g: &Geometry) -> Option<Self> {
        let rad = |d: f32| Fx::from_f32(d).map(|x| x.times(DEG));
        Some(Self::new(rad(g.theta_i_deg)?, rad(g.theta_o_deg)?, rad(g.dphi_deg)?))
    }

    pub fn cos_i(&self) -> Fx {
        self.l[2]
    }

    pub fn cos_o(&self) -> Fx {
        self.v[2]
    }

    pub fn l_dot_v(&self) -> Fx {
        dot(self.l, self.v)
    }

    /// `r(l)·v` with `r(l) = 2(n·l)n − l`.
    pub fn mirror_dot_v(&self) -> Fx {
        dot([self.l[0].negated(), self.l[1].negated(), self.l[2]], self.v)
    }

    pub fn reflected_v(&self) -> V3 {
        [self.v[0].negated(), self.v[1].negated(), self.v[2]]
    }

    pub fn half(&self) -> V3 {
        unit_sum(self.l, self.v)
    }

    pub fn back(&self) -> V3 {
        unit_sum(self.reflected_v(), self.l)
    }

    /// `v·h`.
    pub fn v_dot_half(&self) -> Fx {
        dot(self.v, self.half())
    }

    /// `v'·b`.
    pub fn reflected_dot_back(&self) -> Fx {
        dot(self.reflected_v(), self.back())
    }

    /// Retro-lobe cosine: `cos_B = n·b` (back) or `cos_R = max(0, l·v)` (view).
    pub fn retro_cos(&self, back: bool) -> Fx {
        if back {
            self.back()[2]
        } else {
            self.l_dot_v().max(Fx::ZERO)
        }
    }
}
