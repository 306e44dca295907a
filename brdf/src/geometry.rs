//! Everything a model needs from one pair of directions that does not depend
//! on its parameters, computed once per sample. A fit evaluates each model
//! thousands of times on the same samples; only the parameter-dependent
//! arithmetic is left for those evaluations.

use super::frame::{dot, Directions, Param};

/// Parameter-independent terms of one geometry (`models.md` §1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeometryTerms {
    pub cos_i: f64,
    pub cos_o: f64,
    /// `l·v`, signed.
    pub lv: f64,
    /// `r(l)·v`, the mirror lobe's cosine, signed.
    pub mirror: f64,
    /// `n·h`.
    pub nh: f64,
    /// `v·h`.
    pub vh: f64,
    /// `cos_B = n·b`.
    pub cos_b: f64,
    /// `v'·b`.
    pub vpb: f64,
    /// `lx·vx + ly·vy`, Lafortune's tangential product.
    pub lv_xy: f64,
    /// `lz·vz`.
    pub lv_z: f64,
    /// `tan θi`, `tan θo`.
    pub tan_i: f64,
    pub tan_o: f64,
    /// Oren–Nayar's `max(0, cosΔφ)·sin(max(θi,θo))·tan(min(θi,θo))`.
    pub oren_nayar: f64,
    /// Zhang's shadowing `G` (eq. 3–4, constants of the paper) over `cosθo`.
    pub zhang_g_over_cos_o: f64,
    /// Logarithms of the lobe bases raised to a fitted power (`−∞` where the
    /// base is ≤ 0): a fit then takes one `exp` per lobe, not `ln` and `exp`.
    pub ln_mirror: f64,
    pub ln_nh: f64,
    pub ln_cos_b: f64,
    pub ln_lv: f64,
    /// `ln(1 − cosγ)`, Zhang's Fresnel substitute (γ: half the angle between l and v).
    pub ln_one_minus_cos_gamma: f64,
}

/// `ln x`, or `−∞` for `x ≤ 0`.
fn ln_pos(x: f64) -> f64 {
    if x > 0.0 {
        x.ln()
    } else {
        f64::NEG_INFINITY
    }
}

/// Smallest `cosθo` used where a model divides by it: θo < 90° is the
/// contract, this only keeps a grazing sample finite.
const MIN_COS: f64 = 1e-9;

impl GeometryTerms {
    pub fn new(d: &Directions) -> Self {
        let (cos_i, cos_o) = (d.cos_i().clamp(0.0, 1.0), d.cos_o().clamp(0.0, 1.0));
        let (sin_i, sin_o) = ((1.0 - cos_i * cos_i).sqrt(), (1.0 - cos_o * cos_o).sqrt());
        let tan = |s: f64, c: f64| s / c.max(MIN_COS);
        let h = d.half();
        let b = d.back();
        let lv = dot(d.l, d.v).clamp(-1.0, 1.0);
        let (tan_i, tan_o) = (tan(sin_i, cos_i), tan(sin_o, cos_o));
        let cos_dphi = azimuth_cos(d);
        let oren_nayar = if sin_i > sin_o {
            cos_dphi.max(0.0) * sin_i * tan_o
        } else {
            cos_dphi.max(0.0) * sin_o * tan_i
        };
        let cos_gamma = ((1.0 + lv) / 2.0).sqrt();
        let mirror = dot(d.mirror_l(), d.v);
        GeometryTerms {
            ln_mirror: ln_pos(mirror),
            ln_nh: ln_pos(h[2]),
            ln_cos_b: ln_pos(b[2]),
            ln_lv: ln_pos(lv),
            ln_one_minus_cos_gamma: ln_pos(1.0 - cos_gamma),
            cos_i,
            cos_o,
            lv,
            mirror,
            nh: h[2],
            vh: dot(d.v, h),
            cos_b: b[2],
            vpb: dot(d.reflected_v(), b),
            lv_xy: d.l[0] * d.v[0] + d.l[1] * d.v[1],
            lv_z: d.l[2] * d.v[2],
            tan_i,
            tan_o,
            oren_nayar,
            zhang_g_over_cos_o: zhang_shadowing(d, h, cos_gamma, cos_i, tan_i, tan_o) / cos_o.max(MIN_COS),
        }
    }

    /// `ln` of the retro lobe's cosine (`−∞` where it is 0).
    pub fn retro_ln(&self, p: Param) -> f64 {
        match p {
            Param::Back => self.ln_cos_b,
            Param::View => self.ln_lv,
        }
    }

    /// The retro lobe's cosine: `cos_B` or `cos_R = max(0, l·v)`.
    pub fn retro_cos(&self, p: Param) -> f64 {
        match p {
            Param::Back => self.cos_b,
            Param::View => self.lv.max(0.0),
        }
    }
}

/// `cos Δφ` between the azimuths of l and v; 1 when either is along the normal.
fn azimuth_cos(d: &Directions) -> f64 {
    let (lx, ly, vx, vy) = (d.l[0], d.l[1], d.v[0], d.v[1]);
    let norm = ((lx * lx + ly * ly) * (vx * vx + vy * vy)).sqrt();
    if norm < 1e-300 {
        1.0
    } else {
        ((lx * vx + ly * vy) / norm).clamp(-1.0, 1.0)
    }
}

/// Zhang et al. eq. 3–4 with `σ_sph = 0.0136, σ_r = 0.0141, u_sph = 9, v_sph = 1`.
///
/// The projected tangents are `tanθ·cos(azimuth of h relative to the plane of
/// that direction)` and `tanγ_sph = |cosθi − cosγ|/(2 sinα cosγ)`. At exact
/// specular (`sinα → 0`) these are 0/0; the limit taken is the one along the
/// incidence plane, where Zhang measured: the azimuth cosines → ±1 and
/// `tanγ_sph → tanθi/2`.
fn zhang_shadowing(d: &Directions, h: [f64; 3], cos_gamma: f64, cos_i: f64, tan_i: f64, tan_o: f64) -> f64 {
    const SIGMA_SPH: f64 = 0.0136;
    const SIGMA_R: f64 = 0.0141;
    const U_SPH: f64 = 9.0;
    const V_SPH: f64 = 1.0;
    let cos_alpha = h[2].clamp(0.0, 1.0);
    let sin_alpha = (h[0] * h[0] + h[1] * h[1]).sqrt();
    let (az_i, az_o, tan_gamma) = if sin_alpha < 1e-9 || cos_gamma < 1e-12 {
        (1.0, 1.0, tan_i / 2.0)
    } else {
        let (lx, ly) = planar_unit(d.l);
        let (vx, vy) = planar_unit(d.v);
        (
            (h[0] * lx + h[1] * ly) / sin_alpha,
            (h[0] * vx + h[1] * vy) / sin_alpha,
            (cos_i - cos_gamma).abs() / (2.0 * sin_alpha * cos_gamma),
        )
    };
    let w = SIGMA_SPH * (1.0 + U_SPH * sin_alpha / (sin_alpha + V_SPH * cos_alpha));
    let (ti, to) = (tan_i * az_i, tan_o * az_o);
    (1.0 + w * (ti * to).abs() / (1.0 + SIGMA_R * tan_gamma)) / ((1.0 + w * ti * ti) * (1.0 + w * to * to))
}

/// Unit azimuth direction of a vector; the light's plane (x) at the normal.
fn planar_unit(w: [f64; 3]) -> (f64, f64) {
    let r = (w[0] * w[0] + w[1] * w[1]).sqrt();
    if r < 1e-300 {
        (1.0, 0.0)
    } else {
        (w[0] / r, w[1] / r)
    }
}
