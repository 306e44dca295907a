//! The virtual photodiode and its transimpedance front end: the optical
//! signal from the material's BRDF at the true stage angles, computed from
//! the lab-frame vectors (independently of the firmware's kinematics), plus
//! ambient light, mains pickup, amplifier bandwidth, noise, offset,
//! quantisation and saturation.

use gonio_brdf::aperture::field_average;
use gonio_brdf::{Directions, Specimen};
use gonio_firmware::config::HeadConfig;
use rand::Rng;
use rand_distr::StandardNormal;

#[derive(Debug, Clone, PartialEq)]
pub struct Photodiode {
    /// Laser power on the sample (W).
    pub laser_w: f64,
    pub responsivity_a_per_w: f64,
    /// Reflectance × transmission of the 70/30 splitter on the retro path.
    pub splitter_factor: f64,
    /// Photocurrent of room light (A), not chopped.
    pub ambient_a: f64,
    /// Mains pickup at the ADC input: amplitude (V) of the fundamental, its
    /// frequency (Hz), and the third harmonic relative to the fundamental.
    pub mains_v: f64,
    pub mains_hz: f64,
    pub mains_h3: f64,
    /// White noise at the ADC input (V rms).
    pub noise_v: f64,
    /// Amplifier output offset (V), keeps the noise off the lower rail.
    pub offset_v: f64,
    /// Slow wander of that offset (thermal drift): amplitude (V) and period (s).
    pub offset_wander_v: f64,
    pub offset_wander_s: f64,
    /// First-order time constant of the amplifier (s).
    pub tau_s: f64,
    /// Laser power drift: relative amplitude and period (s) of a slow
    /// sinusoid in the head's clock (a diode laser warming up and cycling).
    pub laser_drift: f64,
    pub laser_drift_period_s: f64,
}

impl Default for Photodiode {
    fn default() -> Self {
        Photodiode {
            laser_w: 0.01,
            responsivity_a_per_w: 0.4,
            splitter_factor: 0.7 * 0.3,
            ambient_a: 2.0e-9,
            mains_v: 0.002,
            mains_hz: 50.0,
            mains_h3: 0.3,
            noise_v: 0.001,
            offset_v: 0.05,
            offset_wander_v: 0.005,
            offset_wander_s: 600.0,
            tau_s: 80.0e-6,
            laser_drift: 0.0,
            laser_drift_period_s: 3600.0,
        }
    }
}

impl Photodiode {
    /// Signal photocurrent (A) with the laser on, at stage angles `(ω, τ, ψ)` in degrees:
    /// `P·R·f̄·cosθo·Ω` with `f̄` the BRDF the detector's field `Ω` sees
    /// ([`seen_brdf`]), times the splitter factor in the retro zone, zero in
    /// the plate's shadow or behind the sample; `defect` scales the material's
    /// reflection at a direction pair (a dust speck).
    pub fn signal_a(&self, material: &Specimen, cfg: &HeadConfig, angles: [f64; 3], defect: impl Fn(&Directions) -> f64) -> f64 {
        let psi_abs = angles[2].abs();
        let optics = &cfg.optics;
        let Some(d) = Directions::from_stage(angles) else {
            return 0.0;
        };
        if psi_abs > optics.retro_max_deg as f64 && psi_abs < optics.blind_max_deg as f64 {
            return 0.0;
        }
        let splitter = if psi_abs <= optics.retro_max_deg as f64 {
            self.splitter_factor
        } else {
            1.0
        };
        let field = optics.detector_sr as f64;
        // A dust speck marks a direction pair (within 0.05°), the nominal one.
        let f = field_average(field, &d, |d| material.eval(d)) * defect(&d);
        self.laser_w * self.responsivity_a_per_w * f * d.cos_o() * field * splitter
    }

    /// Laser power at time `t` relative to its nominal value.
    pub fn laser_factor(&self, t: f64) -> f64 {
        1.0 + self.laser_drift * (std::f64::consts::TAU * t / self.laser_drift_period_s).sin()
    }

    /// Offset, its slow drift, pickup and noise (V) at time `t`.
    pub fn interference_v(&self, t: f64, rng: &mut impl Rng) -> f64 {
        let tau = 2.0 * std::f64::consts::PI;
        let w = tau * self.mains_hz * t;
        let noise: f64 = rng.sample(StandardNormal);
        let offset = self.offset_v + self.offset_wander_v * (tau * t / self.offset_wander_s).sin();
        offset + self.mains_v * (w.sin() + self.mains_h3 * (3.0 * w + 0.4).sin()) + self.noise_v * noise
    }
}

/// The BRDF (sr⁻¹) a detector of field `detector_sr` reads at nominal
/// directions `d`: the flux `f·cosθ` it collects over its field (taken as a
/// disc of that solid angle about the view: 0.39° across for the reference
/// head's 3.6e-5 sr) over the nominal `cosθo` and the field's solid angle,
/// which is what a calibration divides by. Near a retro lobe narrower than a
/// degree it is percents off the value at the nominal view; it is what a
/// simulated scan's values are to be checked against.
pub fn seen_brdf(material: &Specimen, detector_sr: f64, d: &Directions) -> f64 {
    field_average(detector_sr, d, |d| material.eval(d))
}
